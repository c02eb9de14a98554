// Dissipated energy against G0 x crack area on a real breccia-solve fracture run whose crack
// grows stably: the quick variant of cases/dcb-energy (a glass double cantilever beam, 2D
// PMB plane stress, lattice spacing 0.1 mm, arms 2 mm high, 8 mm long, pre-crack to 2.037 mm,
// arms pinned one spacing from the load line and pulled apart at 0.025 m/s each). At a fixed
// opening a DCB's energy release rate falls as the crack grows, so the crack advances only as
// the opening grows: it runs slowly (about 25 m/s) along the mid-plane, one lattice column at
// a time, with no branching and no chips. docs/postproc.md "Energy check" has the numbers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "breccia/common/particle_file.hpp"
#include "real_run.hpp"

namespace fs = std::filesystem;
using breccia::postproc::testing::json_number;
using breccia::postproc::testing::solve_and_post;

namespace {


constexpr double kSpacing_m = 1e-4, kThickness_m = 1e-3, kG0 = 3.8;
constexpr int kColumns = 80, kArmRows = 20;  // 8 mm long, arms 2 mm high
constexpr double kPrecrackTip_m = 2.037e-3;

// The particles of cases/dcb-energy/specimen.py (same order, sets and pins): cell centres of
// the dx-square lattice on 0 <= x <= 8 mm, -2 <= y <= 2 mm, rows from the bottom.
breccia::ParticleModel dcb_particles() {
  breccia::ParticleModel m;
  m.dimension = 2;
  m.thickness_m = kThickness_m;
  breccia::ParticleSet load_top{"load_top", {}}, load_bottom{"load_bottom", {}}, grips{"grips", {}};
  const int pin_row = kArmRows + (kArmRows - 1) / 2;  // nearest the top arm's mid-height
  for (int row = 0; row < 2 * kArmRows; ++row)
    for (int col = 0; col < kColumns; ++col) {
      const int64_t id = static_cast<int64_t>(m.volume_m3.size());
      const double x = (col + 0.5) * kSpacing_m, y = (row - kArmRows + 0.5) * kSpacing_m;
      m.position_m.insert(m.position_m.end(), {x, y, 0.0});
      m.volume_m3.push_back(kSpacing_m * kSpacing_m * kThickness_m);
      m.spacing_m.push_back(kSpacing_m);
      m.material_id.push_back(0);
      if (col == 0 && row == pin_row) load_top.indices.push_back(id);
      if (col == 0 && row == 2 * kArmRows - 1 - pin_row) load_bottom.indices.push_back(id);
      if (x < 0.5e-3) grips.indices.push_back(id);
    }
  m.sets = {load_top, load_bottom, grips};
  m.source = "double cantilever beam 8 x 2 x 2 mm, lattice dx 0.1 mm (test_energy_real_run)";
  return m;
}

// Runs the solver and breccia-post on the quick DCB: glass with the critical-stretch law
// (strength empty) or with tensile_strength (softening bonds), PMB, LPS or correspondence, at
// the step's safety factor `safety` (the default 0.8 when empty).
std::string run_dcb(const char* name, const std::string& strength, const std::string& model = "pmb",
                    const std::string& safety = "") {
  return breccia::postproc::testing::solve_and_post(name, [&](const fs::path& dir) {
    breccia::write_particle_file((dir / "particles.h5").string(), dcb_particles());
    // The pre-crack tip is off every bond's line (a lattice bond crosses y = 0 at multiples of
    // dx/12): see cases/dcb-energy/README.md. End: 170 us, while the crack is still growing
    // stably (it leaves that range near 5 mm, about 1.5 arm heights from the far end).
    std::ofstream(dir / "case.yaml") << R"(name: dcb-energy-quick
specimen: {particles: particles.h5}
model: {type: )" << model << R"(, planar: plane_stress, horizon_factor: 3.015, no_fail: [grips]}
materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.3333333333333333, fracture_energy: 3.8)"
                                     << strength << R"(}]
precracks:
  - {type: segment, from: [-0.001, 0], to: [0.002037, 0]}
boundary:
  - {type: velocity, set: load_top, value: [0, 0.025, 0], components: [x, y], ramp_time: 20 us}
  - {type: velocity, set: load_bottom, value: [0, -0.025, 0], components: [x, y], ramp_time: 20 us}
time: {end: 170 us)" << (safety.empty() ? "" : ", safety: " + safety) << R"(}
output: {every: 1000000, history_every: 100}
)";
  });
}

// Once for all tests of this file.
const std::string& dcb_post_json() {
  static const std::string json = run_dcb("breccia_energy_real_run", "");
  return json;
}

}  // namespace

TEST(EnergyRealRun, StableDcbCrackDissipatesG0TimesItsAreaWithinTenPercent) {
  const std::string& json = dcb_post_json();
  ASSERT_FALSE(json.empty()) << "breccia-solve or breccia-post failed";
  // One piece: the crack has not run through and tore out no chips.
  EXPECT_EQ(json_number(json, "fragment_count", "\"fragments\""), 1);
  // The crack grew well past the pre-crack: 2.9 mm measured (29 lattice columns). At least
  // 2 mm, so that the crack front (a fan of partly broken bonds about one horizon, 0.3 mm,
  // long) and stray faces (below) are a small part of what is compared.
  const double area = json_number(json, "smoothed_fracture_area_m2", "\"cracks\"");
  EXPECT_GT(area, 2e-3 * kThickness_m);
  EXPECT_LT(area, 5.5e-3 * kThickness_m);  // not past the far end's unstable range
  // The smoothed area is the projected crack area: a broken bond between two particles of the
  // same row (a face normal to the crack) adds face area but no crack area; 4 such faces of
  // 33 here. The separating area is 0 by design (the beam is one piece), so `ratio` is the
  // like-for-like measure on this run.
  EXPECT_NEAR(json_number(json, "G0_times_crack_area_J", "\"energy\""), kG0 * area, 1e-6 * kG0 * area);
  // The claim of issue 5. Measured 1.006 (0.975-1.006 from 0.9 mm of growth on). Tolerance
  // 10 %: the lattice quadrature of the bonds crossing a straight crack gives 1.015-1.025 G0
  // per area; the crack front, whose bonds are partly broken over about one horizon (0.3 mm,
  // 10 % of the 2.9 mm grown), adds or withholds part of that share depending on where in the
  // column-by-column advance the run stops; and a face parallel to the crack one row off it,
  // broken in the initiation jump, counts dx of area for one bond's energy (the 12 mm beam of
  // cases/dcb-energy has two such: 0.2 mm, 7 % at this growth; this run has none).
  const double ratio = json_number(json, "ratio", "\"energy\"");
  EXPECT_GT(ratio, 0.9);
  EXPECT_LT(ratio, 1.1);
}

// Issue "Quasi-brittle bonds": the stable DCB with softening bonds, dissipated energy against
// G0 x crack area within 5%. sigma_t 20 MPa: s_u / s_t about 3.5 at this horizon (0.3 mm), a
// cohesive length E G0 / sigma_t^2 of 0.68 mm against 2 mm arms. The dissipation is booked as
// bonds soften, the area only when they have broken, so the process zone ahead of the tip
// counts energy without area: measured 1.008 at the end (0.963-1.015 from 1 mm of growth on);
// at 15 MPa (cohesive length 1.2 mm) 1.046, at 30 MPa 0.961 (cases/dcb-energy/README.md).
TEST(EnergyRealRun, StableDcbCrackWithSofteningBondsDissipatesG0TimesItsAreaWithinFivePercent) {
  const std::string json = run_dcb("breccia_energy_real_run_softening", ", tensile_strength: 20 MPa");
  ASSERT_FALSE(json.empty()) << "breccia-solve or breccia-post failed";
  EXPECT_EQ(json_number(json, "fragment_count", "\"fragments\""), 1);
  const double area = json_number(json, "smoothed_fracture_area_m2", "\"cracks\"");
  EXPECT_GT(area, 2e-3 * kThickness_m);
  EXPECT_LT(area, 5.5e-3 * kThickness_m);
  EXPECT_NEAR(json_number(json, "ratio", "\"energy\""), 1.0, 0.05);
}

// The same DCB with LPS bonds: a brittle LPS bond books, as it breaks, the deviatoric pair
// energy at its critical extension with the dilatation left out (lps_break_energy, the
// calibration's quantity); the energy the run really spends on the crack, the work less the
// kinetic and strain energy, is that within the time step's share, so the balance closes.
// Measured (2026-12-07): 0.8 % of the work (0.4 % at a quarter of the step); booked at the
// particle's current dilatation, as before, it was 30 % off. Tolerance 2 %: the PMB run's
// own imbalance at this step is 2.2 %, its time step's (cases/dcb-energy/README.md). (The
// crack area of breccia-post is no measure here: LPS also breaks a few dozen bonds next to the
// crack plane near the tip, which count as faces; on the crack plane the crack grows 3.5 mm
// against PMB's 3.2 mm, and the booked dissipation is 0.98 G0 per unit of that area.)
TEST(EnergyRealRun, StableDcbCrackWithLpsBondsBooksTheEnergyItSpends) {
  const std::string json = run_dcb("breccia_energy_real_run_lps", "", "lps");
  ASSERT_FALSE(json.empty()) << "breccia-solve or breccia-post failed";
  EXPECT_EQ(json_number(json, "fragment_count", "\"fragments\""), 1);
  EXPECT_GT(json_number(json, "dissipated_J", "\"energy\""), 0.0);
  EXPECT_LT(std::abs(json_number(json, "relative_imbalance")), 0.02) << json;
}

// The same DCB with correspondence bonds: a break books the drop of the particle's energy
// density (St Venant-Kirchhoff and penalty) at the current positions, its family with the
// broken bonds against without them (correspondence_kernels.hpp), so the balance closes up to
// velocity Verlet's error at a sudden break, which is first order in the step: measured
// (2026-12-07) 4.8 %, 1.7 % and 0.88 % of the work at safety 0.8, 0.4 and 0.2. Run at 0.4;
// tolerance 2.5 %. The PMB-equivalent half-bond energy booked before left the balance 9.7 %
// of the work off at 0.8 (the crack spends 1.13 G0 per unit area, that booking counted 0.94)
// and 11.2 % at 0.4 (this test on that code, measured).
TEST(EnergyRealRun, StableDcbCrackWithCorrespondenceBooksTheEnergyItSpends) {
  const std::string json = run_dcb("breccia_energy_real_run_correspondence", "", "correspondence", "0.4");
  ASSERT_FALSE(json.empty()) << "breccia-solve or breccia-post failed";
  EXPECT_EQ(json_number(json, "fragment_count", "\"fragments\""), 1);
  EXPECT_GT(json_number(json, "dissipated_J", "\"energy\""), 0.0);
  EXPECT_LT(std::abs(json_number(json, "relative_imbalance")), 0.025) << json;
}

// A plate given an initial velocity field and nothing else: no work is done, so the balance
// is K + U = K0 (the energy of the first history row). Velocity Verlet keeps it to a small
// fraction of a percent at the default safety factor; leaving K0 out (as post.json once did)
// gives an imbalance of -100%.
TEST(EnergyRealRun, InitialVelocityFieldIsPartOfTheBalance) {
  const std::string json = solve_and_post("post_initial_energy", [](const std::filesystem::path& dir) {
    std::ofstream(dir / "case.yaml") << R"yaml(specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_strain}
materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25}]
initial: [{type: velocity, expression: ["5 * (x / 0.01 - 1)", "0"]}]
time: {steps: 300}
output: {every: 300, history_every: 10}
)yaml";
  });
  ASSERT_FALSE(json.empty());
  const double imbalance = json_number(json, "relative_imbalance");
  EXPECT_LT(std::abs(imbalance), 5e-3) << json;
}
