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
