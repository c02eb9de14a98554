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

TEST(SpecimenSpec, RefinementCoarserThanTheGlobalSizeIsRejected) {
  const auto path = write_temp_file("coarse.yaml",
      "body: {shape: box, size: [1, 1, 1]}\n"
      "mesh: {size: 0.1, refine: [{near: top, size: 0.2, distance_max: 0.3}]}\n");
  EXPECT_THROW(load_specimen(path), InputError);
}

}  // namespace
}  // namespace breccia::mesher
