// Spec parsing: units converted to SI, defaults applied, features validated against the body.
#include <gtest/gtest.h>

#include "breccia/common/error.hpp"
#include "breccia/mesher/specimen.hpp"
#include "mesh_probe.hpp"

namespace breccia::mesher {
namespace {

using testing::write_temp_file;

TEST(SpecimenSpec, ConcreteSpecimenLengthsAreConvertedFromMillimetresToMetres) {
  const Specimen s = load_specimen(BRECCIA_CASES_DIR "/concrete-blast/specimen.yaml");
  EXPECT_EQ(s.dimension, 3);
  EXPECT_EQ(s.body.shape, BodyShape::Box);
  EXPECT_EQ(s.body.name, "concrete");
  for (double edge : s.body.size) EXPECT_DOUBLE_EQ(edge, 0.3);
  ASSERT_EQ(s.holes.size(), 1u);
  EXPECT_EQ(s.holes[0].name, "charge_hole");
  EXPECT_DOUBLE_EQ(s.holes[0].radius_m, 0.010);
  EXPECT_DOUBLE_EQ(*s.holes[0].depth_m, 0.150);
  EXPECT_DOUBLE_EQ(s.holes[0].axis[2], -1.0);
  ASSERT_EQ(s.mesh.refine.size(), 1u);
  EXPECT_EQ(s.mesh.refine[0].near, "charge_hole");
}

TEST(SpecimenSpec, OmittedOptionalKeysTakeTheDocumentedDefaults) {
  const auto path = write_temp_file("defaults.yaml",
      "body: {shape: box, size: [1, 2, 3]}\n"
      "holes: [{centre: [0.5, 1, 3], radius: 0.1}]\n"
      "mesh: {size: 0.5}\n");
  const Specimen s = load_specimen(path);
  EXPECT_EQ(s.dimension, 3);                 // docs: dimension defaults to 3
  EXPECT_EQ(s.body.name, "body");
  EXPECT_EQ(s.body.origin, (Vec3{0, 0, 0}));
  EXPECT_EQ(s.holes[0].name, "hole");
  EXPECT_EQ(s.holes[0].axis, (Vec3{0, 0, -1}));
  EXPECT_FALSE(s.holes[0].depth_m.has_value());  // no depth: through hole
  EXPECT_TRUE(s.mesh.optimize);
  EXPECT_EQ(s.mesh.algorithm_3d, Algorithm3D::Delaunay);
}

TEST(SpecimenSpec, BlindHoleEndingOutsideTheBodyIsRejectedNamingTheDepth) {
  const auto path = write_temp_file("deep.yaml",
      "body: {shape: box, size: [1, 1, 1]}\n"
      "holes: [{centre: [0.5, 0.5, 1], radius: 0.1, depth: 1.2}]\n"
      "mesh: {size: 0.5}\n");
  try {
    load_specimen(path);
    FAIL() << "a hole deeper than the block was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "holes[0].depth");
  }
}

TEST(SpecimenSpec, InclusionOverlappingAHoleIsRejected) {
  const auto path = write_temp_file("overlap.yaml",
      "body: {shape: box, size: [1, 1, 1]}\n"
      "holes: [{centre: [0.5, 0.5, 1], radius: 0.1, depth: 0.5}]\n"
      "inclusions: [{name: stone, centre: [0.5, 0.55, 0.7], radius: 0.1}]\n"
      "mesh: {size: 0.5}\n");
  EXPECT_THROW(load_specimen(path), InputError);
}

// Loads `yaml` and expects an InputError naming `field` whose message holds `part`.
void expect_refused(const std::string& name, const std::string& yaml, const std::string& field, const std::string& part) {
  try {
    load_specimen(write_temp_file(name, yaml));
    ADD_FAILURE() << name << ": accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << "missing '" << part << "' in: " << e.what();
  }
}

// A slot is cut out of the body, so an inclusion in it would fill the void again (it was
// meshed as stone where the slot should be empty); refused as an inclusion in a hole is.
TEST(SpecimenSpec, InclusionOverlappingASlotIsRejectedNamingTheSlot) {
  const std::string block3 =
      "body: {shape: box, name: rock, size: [100 mm, 60 mm, 40 mm]}\n"
      "notches: [{name: cut, type: slot, width: 4 mm, corner: [50 mm, 0, 0], edge_a: [0, 30 mm, 0], edge_b: [0, 0, 40 mm]}]\n"
      "mesh: {size: 6 mm}\n";
  expect_refused("incl_slot.yaml", block3 + "inclusions: [{name: stone, centre: [50 mm, 30 mm, 20 mm], radius: 8 mm}]\n",
                 "inclusions[0]", "slot 'cut'");
  // The slot is the box x in [48, 52], y in [0, 30] mm. From (60, 38) its nearest point is
  // the edge at (52, 30): distance sqrt(8^2 + 8^2) = 11.31 mm, although the centre is only
  // 8 mm from the slot's planes in x and in y. So radius 11 mm is clear, 11.5 mm overlaps.
  EXPECT_NO_THROW(load_specimen(write_temp_file(
      "incl_slot_clear.yaml", block3 + "inclusions: [{name: stone, centre: [60 mm, 38 mm, 20 mm], radius: 11 mm}]\n")));
  expect_refused("incl_slot_edge.yaml", block3 + "inclusions: [{name: stone, centre: [60 mm, 38 mm, 20 mm], radius: 11.5 mm}]\n",
                 "inclusions[0]", "slot 'cut'");
  // 2D: the slot is the rectangle x in [48, 52], y in [0, 20] mm; a grain at its end.
  expect_refused("incl_slot_2d.yaml",
                 "dimension: 2\n"
                 "body: {shape: rectangle, name: glass, size: [100 mm, 40 mm]}\n"
                 "notches: [{name: cut, type: slot, width: 4 mm, start: [50 mm, 0], end: [50 mm, 20 mm]}]\n"
                 "inclusions: [{name: grain, centre: [50 mm, 20 mm], radius: 6 mm}]\n"
                 "mesh: {size: 2 mm}\n",
                 "inclusions[0]", "slot 'cut'");
}

// The body's cells would be put in the group of its faces (or the faces in that of the
// cells): its volume group must not share a name with one of its boundary groups.
TEST(SpecimenSpec, BodyNamedLikeOneOfItsBoundaryGroupsIsRejected) {
  expect_refused("name_top.yaml", "body: {shape: box, name: top, size: [10 mm, 10 mm, 10 mm]}\nmesh: {size: 5 mm}\n",
                 "body.name", "'top' is a boundary group of the body");
  expect_refused("name_outer.yaml", "dimension: 2\nbody: {shape: disc, name: outer, radius: 10 mm}\nmesh: {size: 5 mm}\n",
                 "body.name", "'outer' is a boundary group of the body");
}

// A through hole runs along its whole axis; if its wall leaves the body sideways it cuts
// a groove or splits the body instead of making a bore, as a blind hole's wall may not.
TEST(SpecimenSpec, ThroughHoleWhoseWallLeavesTheBodyIsRejectedNamingTheRadius) {
  const std::string block =
      "body: {shape: box, name: rock, size: [100 mm, 60 mm, 40 mm]}\n"
      "mesh: {size: 6 mm}\n";
  // Axis at y = 30 mm in a block 60 mm deep: a radius over 30 mm reaches y < 0 or y > 60.
  expect_refused("wide_hole.yaml", block + "holes: [{name: bore, centre: [50 mm, 30 mm, 40 mm], radius: 31 mm}]\n",
                 "holes[0].radius", "hole wall (radius 31 mm) reaches outside the body");
  expect_refused("big_hole.yaml", block + "holes: [{name: bore, centre: [50 mm, 30 mm, 40 mm], radius: 200 mm}]\n",
                 "holes[0].radius", "hole wall (radius 200 mm) reaches outside the body");
  EXPECT_NO_THROW(load_specimen(write_temp_file(
      "fit_hole.yaml", block + "holes: [{name: bore, centre: [50 mm, 30 mm, 40 mm], radius: 29 mm}]\n")));
  // A bore at 45 degrees from the top face to the bottom one stays a bore: its wall is
  // cut by both faces obliquely but never leaves through a side.
  EXPECT_NO_THROW(load_specimen(write_temp_file(
      "oblique_hole.yaml", block + "holes: [{name: bore, centre: [50 mm, 30 mm, 40 mm], axis: [1, 0, -1], radius: 5 mm}]\n")));
  // The blind hole's wall check names the radius too.
  expect_refused("wide_blind.yaml", block + "holes: [{name: bore, centre: [50 mm, 30 mm, 40 mm], radius: 31 mm, depth: 10 mm}]\n",
                 "holes[0].radius", "hole wall (radius 31 mm) reaches outside the body");
}

TEST(SpecimenSpec, RefinementCoarserThanTheGlobalSizeIsRejected) {
  const auto path = write_temp_file("coarse.yaml",
      "body: {shape: box, size: [1, 1, 1]}\n"
      "mesh: {size: 0.1, refine: [{near: top, size: 0.2, distance_max: 0.3}]}\n");
  EXPECT_THROW(load_specimen(path), InputError);
}

}  // namespace
}  // namespace breccia::mesher
