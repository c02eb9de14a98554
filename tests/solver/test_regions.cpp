// Particle sets defined in the case (sets:): regions of the reference configuration and set
// algebra, each against a brute-force selection written here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include "breccia/common/error.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using breccia::ParticleModel;
using breccia::ParticleSet;
using namespace breccia::solver::testing;

namespace {

const std::string kCube =
    "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.01, 0.01, 0.01], spacing: 1 mm}}\n"
    "model: {type: pmb, horizon_factor: 3.015}\n"
    "materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
    "time: {steps: 1}\n";

std::vector<int64_t> select(const ParticleModel& pm, auto&& keep) {
  std::vector<int64_t> out;
  for (size_t i = 0; i < pm.size(); ++i)
    if (keep(&pm.position_m[3 * i])) out.push_back(static_cast<int64_t>(i));
  return out;
}

const std::vector<int64_t>& set_of(const PdSystem& s, const std::string& name) {
  const ParticleSet* set = s.particles.find_set(name);
  EXPECT_NE(set, nullptr) << name;
  static const std::vector<int64_t> none;
  return set ? set->indices : none;
}

}  // namespace

TEST(CaseSets, RegionsAndTheirAlgebraSelectWhatBruteForceSelects) {
  const PdSystem s = system_from_yaml("regions", kCube +
      "sets:\n"
      "  - {name: slab, box: [0, 0, 0.004, 0.01, 0.01, 0.007]}\n"
      "  - {name: ball, sphere: {center: [0.005, 0.005, 0.005], radius: 3 mm}}\n"
      "  - {name: rod, cylinder: {center: [0.005, 0.005, 0.005], axis: [1, 1, 0], radius: 2 mm, length: 6 mm}}\n"
      "  - {name: upper, half_space: {point: [0, 0.006, 0], normal: [0, 1, 0.5]}}\n"
      "  - {name: both, union: [slab, ball]}\n"
      "  - {name: core, intersection: [slab, ball, upper]}\n"
      "  - {name: rest, difference: [ball, slab, xmin]}\n");
  const ParticleModel& pm = s.particles;
  auto box = [](const double* p) { return p[2] >= 0.004 && p[2] <= 0.007; };
  auto ball = [](const double* p) {
    return std::pow(p[0] - 0.005, 2) + std::pow(p[1] - 0.005, 2) + std::pow(p[2] - 0.005, 2) <= 9e-6;
  };
  auto rod = [](const double* p) {
    const double a = 1.0 / std::sqrt(2.0), rx = p[0] - 0.005, ry = p[1] - 0.005, rz = p[2] - 0.005;
    const double t = (rx + ry) * a;
    const double d2 = std::pow(rx - t * a, 2) + std::pow(ry - t * a, 2) + rz * rz;
    return d2 <= 4e-6 && std::fabs(t) <= 0.003;
  };
  auto upper = [](const double* p) { return (p[1] - 0.006) * 1.0 + p[2] * 0.5 >= 0.0; };
  EXPECT_EQ(set_of(s, "slab"), select(pm, box));
  EXPECT_EQ(set_of(s, "ball"), select(pm, ball));
  EXPECT_EQ(set_of(s, "rod"), select(pm, rod));
  EXPECT_EQ(set_of(s, "upper"), select(pm, upper));
  EXPECT_EQ(set_of(s, "both"), select(pm, [&](const double* p) { return box(p) || ball(p); }));
  EXPECT_EQ(set_of(s, "core"), select(pm, [&](const double* p) { return box(p) && ball(p) && upper(p); }));
  const std::vector<int64_t>& xmin = set_of(s, "xmin");  // a set of the (lattice) particle model
  std::vector<int64_t> rest;
  for (int64_t i : select(pm, [&](const double* p) { return ball(p) && !box(p); }))
    if (!std::binary_search(xmin.begin(), xmin.end(), i)) rest.push_back(i);
  EXPECT_EQ(set_of(s, "rest"), rest);
  for (const char* name : {"slab", "ball", "rod", "upper", "both", "core", "rest"}) EXPECT_FALSE(set_of(s, name).empty()) << name;
}

TEST(CaseSets, ARegionServesWhereverASetNameIs) {
  // A fixed region and a body force on another: the constraint holds exactly that region.
  PdSystem s = system_from_yaml("regions_used", kCube +
      "sets:\n"
      "  - {name: base, box: [0, 0, 0, 0.01, 0.01, 0.0021]}\n"
      "  - {name: top, half_space: {point: [0, 0, 0.008], normal: [0, 0, 1]}}\n"
      "boundary: [{type: fixed, set: base}]\n"
      "loads: [{type: body_force, set: top, value: [0, 0, 1e5]}]\n");
  ASSERT_EQ(s.constraints.size(), 1u);
  EXPECT_EQ(s.constraints[0].particles.size(), 200u);  // 2 layers of 10 x 10
  for (int k = 0; k < 20; ++k) cpu_step(s);
  for (auto i : s.constraints[0].particles) EXPECT_EQ(s.u[3 * i + 2], 0.0);
}

TEST(CaseSets, BadDefinitionsAreNamed) {
  auto error_of = [](const std::string& sets) {
    try {
      system_from_yaml("regions_bad", kCube + sets);
    } catch (const breccia::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("sets: [{name: a, union: [xmin, nowhere]}]\n").find("no set named 'nowhere'"), std::string::npos);
  EXPECT_NE(error_of("sets: [{name: xmin, sphere: {center: [0, 0, 0], radius: 1 mm}}]\n").find("sets[0].name"),
            std::string::npos);
  EXPECT_NE(error_of("sets: [{name: a, box: [0, 0, 1, 1], sphere: {center: [0, 0, 0], radius: 1 mm}}]\n")
                .find("exactly one of"),
            std::string::npos);
  EXPECT_NE(error_of("sets: [{name: a, box: [0, 0, 1]}]\n").find("sets[0].box"), std::string::npos);
  EXPECT_NE(error_of("sets: [{name: a, cylinder: {center: [0, 0, 0], axis: [0, 0, 0], radius: 1 mm}}]\n")
                .find("sets[0].cylinder.axis"),
            std::string::npos);
}
