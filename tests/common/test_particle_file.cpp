#include <gtest/gtest.h>

#include <filesystem>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"

using namespace breccia;

TEST(ParticleFile, RoundTripKeepsEverything) {
  ParticleModel m;
  m.dimension = 3;
  m.position_m = {0, 0, 0, 1, 0, 0};
  m.volume_m3 = {0.5, 0.25};
  m.material_id = {0, 0};
  m.sets.push_back({"left", {0}});
  SurfaceFacets s;
  s.name = "top";
  s.area_m2 = {0.1};
  s.normal = {0, 0, 1};
  s.centroid_m = {0, 0, 1};
  s.particle = {1};
  m.surfaces.push_back(s);
  m.source = "unit test";
  const std::string path = ::testing::TempDir() + "/rt/particles.h5";
  write_particle_file(path, m);
  EXPECT_TRUE(std::filesystem::exists(::testing::TempDir() + "/rt/particles.xdmf"));
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  const ParticleModel r = read_particle_file(path);
  EXPECT_EQ(r.size(), 2u);
  EXPECT_EQ(r.position_m, m.position_m);
  EXPECT_EQ(r.volume_m3, m.volume_m3);
  ASSERT_NE(r.find_set("left"), nullptr);
  ASSERT_NE(r.find_surface("top"), nullptr);
  EXPECT_EQ(r.find_surface("top")->particle[0], 1);
  EXPECT_EQ(r.content_id, compute_content_id(m));
}

TEST(ParticleFile, FacetVerticesRoundTripAndAFileWithoutThemStaysReadable) {
  ParticleModel m;
  m.dimension = 3;
  m.position_m = {0, 0, 0, 1, 0, 0};
  m.volume_m3 = {0.5, 0.25};
  m.material_id = {0, 0};
  SurfaceFacets with;  // one triangle with its vertices
  with.name = "notch";
  with.area_m2 = {0.5};
  with.normal = {0, 0, 1};
  with.centroid_m = {1.0 / 3, 1.0 / 3, 0};
  with.particle = {0};
  with.vertices_m = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  SurfaceFacets without = with;  // as a format-version-1 file has it
  without.name = "old";
  without.vertices_m.clear();
  m.surfaces = {with, without};
  const std::string path = ::testing::TempDir() + "/vertices/particles.h5";
  write_particle_file(path, m);
  const ParticleModel r = read_particle_file(path);
  ASSERT_NE(r.find_surface("notch"), nullptr);
  EXPECT_EQ(r.find_surface("notch")->vertices_m, with.vertices_m);
  ASSERT_NE(r.find_surface("old"), nullptr);
  EXPECT_FALSE(r.find_surface("old")->has_vertices());

  m.surfaces[0].vertices_m.pop_back();  // not F x 3 x 3
  try {
    write_particle_file(::testing::TempDir() + "/vertices_bad/particles.h5", m);
    FAIL() << "a wrong vertex count was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/surfaces/notch/vertices"), std::string::npos) << e.what();
  }
}

TEST(ParticleFile, NonHdf5FileIsRejectedByName) {
  const std::string path = ::testing::TempDir() + "/not_h5.h5";
  { FILE* f = std::fopen(path.c_str(), "w"); std::fputs("hello", f); std::fclose(f); }
  try {
    read_particle_file(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
}

// A distributed run's process reads its own rows (hyperslabs): each range equals that slice
// of the whole file, the ranges of several processes tile it, and rows past the end are an
// input error naming the file and the dataset.
TEST(ParticleFile, RowsAreTheSlicesOfTheWholeFile) {
  ParticleModel m;
  m.dimension = 3;
  const int n = 11;
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) m.position_m.push_back(0.1 * i + 0.01 * d);
    m.volume_m3.push_back(1e-9 * (i + 1));
    m.spacing_m.push_back(1e-3 * (1 + i % 3));
    m.material_id.push_back(i % 2);
  }
  m.material_names = {"a", "b"};
  const std::string path = ::testing::TempDir() + "/rows/particles.h5";
  write_particle_file(path, m);
  const ParticleModel whole = read_particle_file(path);
  std::vector<double> tiled;
  for (const auto& [first, count] : std::vector<std::pair<int64_t, int64_t>>{{0, 4}, {4, 0}, {4, 7}}) {
    const ParticleRows r = read_particle_rows(path, first, count);
    EXPECT_EQ(r.total, n);
    EXPECT_EQ(r.first, first);
    EXPECT_EQ(r.content_id, whole.content_id);
    ASSERT_EQ(r.size(), static_cast<size_t>(count));
    EXPECT_EQ(r.position_m, std::vector<double>(whole.position_m.begin() + 3 * first,
                                                whole.position_m.begin() + 3 * (first + count)));
    EXPECT_EQ(r.volume_m3, std::vector<double>(whole.volume_m3.begin() + first, whole.volume_m3.begin() + first + count));
    EXPECT_EQ(r.spacing_m, std::vector<double>(whole.spacing_m.begin() + first, whole.spacing_m.begin() + first + count));
    EXPECT_EQ(r.material_id,
              std::vector<int32_t>(whole.material_id.begin() + first, whole.material_id.begin() + first + count));
    tiled.insert(tiled.end(), r.volume_m3.begin(), r.volume_m3.end());
  }
  EXPECT_EQ(tiled, whole.volume_m3);
  try {
    read_particle_rows(path, 8, 4);
    FAIL() << "rows past the end must be refused";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("/particles/volume"), std::string::npos) << what;
    EXPECT_NE(what.find("11 rows"), std::string::npos) << what;
  }
}
