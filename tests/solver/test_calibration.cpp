// Verification of the calibration: strain energy under homogeneous strain and fracture
// energy, against classical elasticity and G0 (docs/theory.md derives both).
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <numbers>

#include "breccia/solver/calibration.hpp"
#include "helpers.hpp"
#include "measures.hpp"  // tools/atlas: the energy to break the bonds crossing a plane

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

struct EnergyCase {
  const char* model;   // pmb | lps
  int dimension;
  const char* planar;  // none | plane_stress | plane_strain
  double nu;
  double m;            // horizon / spacing
};

// Printed in CTest's test names: must not show the struct's bytes (pointers differ per run).
void PrintTo(const EnergyCase& c, std::ostream* os) {
  *os << c.model << " " << c.dimension << "D " << c.planar << " nu " << c.nu << " m " << c.m;
}

std::string energy_case_yaml(const EnergyCase& c, bool surface_correction) {
  // Box large enough that the centre particle's family lies 2 horizons from any surface.
  const double dx = 1e-3;
  const double half = (std::ceil(c.m) + 1) * dx + 0.5 * dx;  // the centre family is complete
  std::string box = c.dimension == 3
      ? "[" + std::to_string(-half) + ", " + std::to_string(-half) + ", " + std::to_string(-half) + ", " +
            std::to_string(half) + ", " + std::to_string(half) + ", " + std::to_string(half) + "]"
      : "[" + std::to_string(-half) + ", " + std::to_string(-half) + ", " + std::to_string(half) + ", " +
            std::to_string(half) + "]";
  std::string y = "specimen:\n  lattice: {dimension: " + std::to_string(c.dimension) + ", box: " + box +
                  ", spacing: 0.001, thickness: 0.001}\n";
  y += "model: {type: " + std::string(c.model) + ", horizon_factor: " + std::to_string(c.m) +
       ", surface_correction: " + (surface_correction ? "energy" : "none");
  if (c.dimension == 2) y += ", planar: " + std::string(c.planar);
  y += "}\nmaterials:\n  - {name: m, density: 1000, youngs_modulus: 10 GPa, poisson_ratio: " + std::to_string(c.nu) +
       "}\ntime: {steps: 1}\n";
  return y;
}

ElasticInput elastic_of(const EnergyCase& c) {
  ElasticInput in;
  in.dimension = c.dimension;
  in.planar = std::string(c.planar) == "plane_stress" ? Planar::PlaneStress
              : std::string(c.planar) == "plane_strain" ? Planar::PlaneStrain : Planar::None;
  in.youngs_modulus = 10e9;
  in.poisson_ratio = c.nu;
  in.thickness = 1e-3;
  return in;
}

// Relative error of the centre particle's PD strain-energy density under strain eps.
double energy_error(const EnergyCase& c, const double eps[9]) {
  PdSystem s = system_from_yaml(std::string("energy_") + c.model + std::to_string(c.dimension) + c.planar,
                                energy_case_yaml(c, false));
  impose_affine(s, eps);
  cpu_compute_forces(s);
  const int64_t centre = nearest(s, 0, 0, 0);
  const double w_classical = classical_energy_density(elastic_of(c), eps);
  return (s.energy_density[centre] - w_classical) / w_classical;
}

const double kUniaxial[9] = {1e-4, 0, 0, 0, 0, 0, 0, 0, 0};
const double kShear[9] = {0, 1e-4, 0, 1e-4, 0, 0, 0, 0, 0};
const double kMixed[9] = {1e-4, 0.3e-4, 0, 0.3e-4, -0.5e-4, 0, 0, 0, 0.2e-4};

}  // namespace

// 1% (issue 3, test 1): the lattice sum over a horizon of m = 3..4 spacings reproduces the
// continuum integral the micro-modulus was calibrated on to about a percent.
constexpr double kLatticeEnergyTolerance = 0.01;

class StrainEnergyOnLattice : public ::testing::TestWithParam<EnergyCase> {};

TEST_P(StrainEnergyOnLattice, InteriorEnergyDensityMatchesClassicalElasticity) {
  const EnergyCase c = GetParam();
  for (const double* eps : {kUniaxial, kShear, kMixed}) {
    const double err = energy_error(c, eps);
    // Every case, LPS in 2D at m = 3 included: the square lattice's cos(4 theta) anisotropy
    // (uniaxial -2.3%, shear +1.5% before) is removed by reweighting each 2D family
    // (docs/theory.md).
    const double tolerance = kLatticeEnergyTolerance;
    EXPECT_LT(std::fabs(err), tolerance)
        << c.model << " " << c.dimension << "D " << c.planar << " nu=" << c.nu << " m=" << c.m
        << " relative error " << err;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, StrainEnergyOnLattice,
    ::testing::Values(EnergyCase{"pmb", 3, "none", 0.25, 3.015}, EnergyCase{"pmb", 3, "none", 0.25, 4.015},
                      EnergyCase{"pmb", 2, "plane_stress", 1.0 / 3.0, 3.015},
                      EnergyCase{"pmb", 2, "plane_stress", 1.0 / 3.0, 4.015},
                      EnergyCase{"pmb", 2, "plane_strain", 0.25, 3.015},
                      EnergyCase{"pmb", 2, "plane_strain", 0.25, 4.015},
                      EnergyCase{"lps", 3, "none", 0.2, 3.015}, EnergyCase{"lps", 3, "none", 0.33, 3.015},
                      EnergyCase{"lps", 3, "none", 0.2, 4.015}, EnergyCase{"lps", 3, "none", 0.33, 4.015},
                      EnergyCase{"lps", 2, "plane_stress", 0.2, 3.015},
                      EnergyCase{"lps", 2, "plane_stress", 0.33, 3.015},
                      EnergyCase{"lps", 2, "plane_stress", 0.2, 4.015},
                      EnergyCase{"lps", 2, "plane_stress", 0.33, 4.015},
                      EnergyCase{"lps", 2, "plane_strain", 0.2, 3.015},
                      EnergyCase{"lps", 2, "plane_strain", 0.33, 3.015},
                      EnergyCase{"lps", 2, "plane_strain", 0.2, 4.015},
                      EnergyCase{"lps", 2, "plane_strain", 0.33, 4.015}),
    // Stable, readable names (the default prints the struct's bytes, pointers included,
    // which differ between CTest's discovery and the run).
    [](const ::testing::TestParamInfo<EnergyCase>& info) {
      const EnergyCase& c = info.param;
      return std::string(c.model) + "_" + std::to_string(c.dimension) + "D_" + c.planar + "_nu" +
             std::to_string(static_cast<int>(std::lround(c.nu * 100))) + "_m" +
             std::to_string(static_cast<int>(std::lround(c.m * 1000)));
    });

TEST(Calibration, TextbookMicroModuliAndCriticalStretchAreRecovered) {
  // Silling & Askari 2005; Ha & Bobaru 2010 (constant influence function): exact formulas.
  using std::numbers::pi;
  ElasticInput in3{3, Planar::None, 72e9, 0.25, 1.0};
  const double K = 72e9 / (3 * (1 - 0.5)), delta = 1e-3, G0 = 3.8;
  EXPECT_NEAR(pmb_micromodulus(in3, Influence::Constant, delta) / (18 * K / (pi * std::pow(delta, 4))), 1.0, 1e-12);
  EXPECT_NEAR(pmb_critical_stretch(in3, Influence::Constant, delta, G0) / std::sqrt(5 * G0 / (9 * K * delta)), 1.0, 1e-12);
  ElasticInput ps{2, Planar::PlaneStress, 72e9, 1.0 / 3.0, 0.002};
  EXPECT_NEAR(pmb_micromodulus(ps, Influence::Constant, delta) / (9 * 72e9 / (pi * 0.002 * std::pow(delta, 3))), 1.0, 1e-12);
  EXPECT_NEAR(pmb_critical_stretch(ps, Influence::Constant, delta, G0) / std::sqrt(4 * pi * G0 / (9 * 72e9 * delta)), 1.0, 1e-12);
  ElasticInput pe{2, Planar::PlaneStrain, 72e9, 0.25, 0.002};
  EXPECT_NEAR(pmb_micromodulus(pe, Influence::Constant, delta) / (48 * 72e9 / (5 * pi * 0.002 * std::pow(delta, 3))), 1.0, 1e-12);
  EXPECT_NEAR(pmb_critical_stretch(pe, Influence::Constant, delta, G0) / std::sqrt(5 * pi * G0 / (12 * 72e9 * delta)), 1.0, 1e-12);
}

namespace {

// Work to break every bond crossing the mid-plane x = 0, per unit area, measured over a
// window in the middle of the plane (away from the lateral surfaces).
// strength (optional, e.g. ", tensile_strength: 3 MPa"): softening bonds, whose work to break
// is U s_t s_u along the law (SofteningLaw.* checks that integral) where a brittle bond's is U s0^2.
double fracture_energy_ratio(int dimension, const char* planar, const char* model, double m, const char* influence,
                             const std::string& strength = "") {
  const double dx = 1e-3, G0 = 100.0;
  const double half = (std::ceil(m) + 4) * dx;
  std::string box = dimension == 3 ? "[" + std::to_string(-half) + ", " + std::to_string(-half) + ", " +
                                         std::to_string(-half) + ", " + std::to_string(half) + ", " +
                                         std::to_string(half) + ", " + std::to_string(half) + "]"
                                   : "[" + std::to_string(-half) + ", " + std::to_string(-half) + ", " +
                                         std::to_string(half) + ", " + std::to_string(half) + "]";
  const double nu = std::string(planar) == "plane_stress" ? 1.0 / 3.0 : 0.25;
  std::string y = "specimen:\n  lattice: {dimension: " + std::to_string(dimension) + ", box: " + box +
                  ", spacing: 0.001, thickness: 0.001}\nmodel: {type: " + model + ", horizon_factor: " +
                  std::to_string(m) + ", influence: " + influence;
  if (dimension == 2) y += ", planar: " + std::string(planar);
  y += "}\nmaterials:\n  - {name: m, density: 1000, youngs_modulus: 10 GPa, poisson_ratio: " + std::to_string(nu) +
       ", fracture_energy: " + std::to_string(G0) + strength + "}\ntime: {steps: 1}\n";
  PdSystem s = system_from_yaml(std::string("gc_") + model + std::to_string(dimension) + planar + influence, y);
  if (!strength.empty() && s.bond_damage.empty()) return 0.0;  // not softening: fail the caller's check
  // Two lattice periods: crossing points repeat with the lattice period, so the window counts
  // each kind of crossing exactly twice.
  const double ratio = breccia::atlas::crossing_fracture_energy_ratio(s, 2 * dx, 0.0, G0);
  std::printf("fracture energy / G0, %s %dD %s m = %g%s: %.4f\n", model, dimension, planar, m, strength.c_str(),
              ratio);
  return ratio;
}

}  // namespace

// 2% (issue 3, test 2): the critical-stretch formula integrates the bond energy over the
// continuum; a lattice with partial volumes reproduces that integral to about 1-2%.
constexpr double kFractureEnergyTolerance = 0.02;

TEST(FractureEnergy, BreakingAllBondsAcrossAPlaneReleasesG0In3D) {
  EXPECT_NEAR(fracture_energy_ratio(3, "none", "pmb", 3.015, "constant"), 1.0, kFractureEnergyTolerance);
}

TEST(FractureEnergy, BreakingAllBondsAcrossAPlaneReleasesG0InPlaneStress) {
  EXPECT_NEAR(fracture_energy_ratio(2, "plane_stress", "pmb", 3.015, "constant"), 1.0, kFractureEnergyTolerance);
}

TEST(FractureEnergy, BreakingAllBondsAcrossAPlaneReleasesG0InPlaneStrain) {
  EXPECT_NEAR(fracture_energy_ratio(2, "plane_strain", "pmb", 3.015, "constant"), 1.0, kFractureEnergyTolerance);
}

// Issue "Quasi-brittle bonds": softening bonds release G0 per unit of crack area within the same
// 2%, at two strengths (PMB 3D: s_u / s_t of order 900 and 40 at this horizon, 3 mm, E 10 GPa).
TEST(FractureEnergy, SofteningBondsReleaseG0AtAnyStrength) {
  for (const char* strength : {", tensile_strength: 1 MPa", ", tensile_strength: 4 MPa"}) {
    EXPECT_NEAR(fracture_energy_ratio(3, "none", "pmb", 3.015, "constant", strength), 1.0, kFractureEnergyTolerance);
    EXPECT_NEAR(fracture_energy_ratio(3, "none", "lps", 3.015, "constant", strength), 1.0, kFractureEnergyTolerance);
    EXPECT_NEAR(fracture_energy_ratio(2, "plane_stress", "pmb", 3.015, "constant", strength), 1.0,
                kFractureEnergyTolerance);
    EXPECT_NEAR(fracture_energy_ratio(2, "plane_strain", "lps", 3.015, "constant", strength), 1.0,
                kFractureEnergyTolerance);
  }
}

TEST(FractureEnergy, GaussianInfluenceAndLpsAlsoReleaseG0) {
  EXPECT_NEAR(fracture_energy_ratio(3, "none", "pmb", 3.015, "gaussian"), 1.0, kFractureEnergyTolerance);
  EXPECT_NEAR(fracture_energy_ratio(3, "none", "lps", 3.015, "constant"), 1.0, kFractureEnergyTolerance);
  EXPECT_NEAR(fracture_energy_ratio(2, "plane_stress", "lps", 3.015, "constant"), 1.0, kFractureEnergyTolerance);
  EXPECT_NEAR(fracture_energy_ratio(2, "plane_strain", "lps", 3.015, "constant"), 1.0, kFractureEnergyTolerance);
  EXPECT_NEAR(fracture_energy_ratio(2, "plane_stress", "lps", 4.015, "constant"), 1.0, kFractureEnergyTolerance);
}
