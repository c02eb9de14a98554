// Dual-horizon PD (Ren, Zhuang & Rabczuk 2017) on a graded particle arrangement:
// balance of forces and wave transmission through a 2:1 resolution change.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "breccia/solver/exec_openmp.hpp"
#include "helpers.hpp"
#include "measures.hpp"

using namespace breccia;
using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

// 2D strip [0, L] x [0, W]: spacing h for x < L/2, 2h beyond (thickness h).
std::string graded_strip(const std::string& name, double L, double W, double h) {
  return breccia::atlas::write_graded_strip(breccia::solver::testing::process_temp_dir() + "/" + name + ".h5", L, W, h, 2.0);
}

std::string graded_case(const std::string& particles) {
  return "specimen: {particles: " + particles + "}\n"
         "model: {type: pmb, planar: plane_strain, variable_horizon: true, horizon_factor: 3.015}\n"
         "materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
         "time: {steps: 1}\n";
}

// Emulate a naive variable horizon: each particle uses only its own horizon with the full
// micro-modulus c(delta_i), and no reaction from neighbours' horizons.
void make_naive(PdSystem& s) {
  for (size_t k = 0; k < s.k_own.size(); ++k) {
    s.k_own[k] *= 2.0;
    s.k_dual[k] = 0.0;
  }
}

double net_force_norm(const PdSystem& s, double* per_particle_max) {
  double f[3] = {0, 0, 0}, fmax = 0;
  for (size_t i = 0; i < s.n; ++i)
    for (int d = 0; d < 3; ++d) {
      f[d] += s.volume[i] * s.force[3 * i + d];
      fmax = std::max(fmax, std::fabs(s.volume[i] * s.force[3 * i + d]));
    }
  if (per_particle_max) *per_particle_max = fmax;
  return std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
}

}  // namespace

TEST(DualHorizon, ForcesBalanceToRoundOffUnderAffineStrainOnAGradedArrangement) {
  const std::string file = graded_strip("graded_affine", 0.04, 0.01, 0.5e-3);
  const double eps[9] = {1e-4, 2e-5, 0, 2e-5, -3e-5, 0, 0, 0, 0};
  PdSystem dh = setup_system(parse_case_file(write_case("graded_affine", graded_case(file))));
  impose_affine(dh, eps);
  cpu_compute_forces(dh);
  double dh_max = 0, naive_max = 0;
  const double dh_net = net_force_norm(dh, &dh_max);
  PdSystem naive = setup_system(parse_case_file(write_case("graded_affine_naive", graded_case(file))));
  make_naive(naive);
  impose_affine(naive, eps);
  cpu_compute_forces(naive);
  const double naive_net = net_force_norm(naive, &naive_max);
  std::printf("graded strip under affine strain: max particle force DH %.3e N, naive %.3e N; net DH %.3e, naive %.3e\n",
              dh_max, naive_max, dh_net, naive_net);
  // Round-off: sum of ~1e5 terms of size dh_max with relative precision 1e-16.
  EXPECT_LT(dh_net, 1e-10 * dh_max * dh.n) << "dual horizon: net force " << dh_net;
  // The naive scheme's ghost forces do not cancel: the body would accelerate by itself.
  EXPECT_GT(naive_net, 1e-3 * naive_max) << "naive variable horizon: net force " << naive_net;
}

TEST(DualHorizon, InteriorForcesVanishAwayFromSurfacesUnderAffineStrain) {
  // Particles more than two (coarse) horizons from the outer surface and from the
  // resolution change see a complete, point-symmetric family: zero force to round-off.
  const std::string file = graded_strip("graded_interior", 0.06, 0.03, 0.5e-3);
  PdSystem s = setup_system(parse_case_file(write_case("graded_interior", graded_case(file))));
  const double eps[9] = {1e-4, 2e-5, 0, 2e-5, -3e-5, 0, 0, 0, 0};
  impose_affine(s, eps);
  cpu_compute_forces(s);
  double interior_max = 0, scale = 0;
  const double reach = 2 * 3.015 * 1e-3;
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], y = s.x0[3 * i + 1];
    const double f = std::hypot(s.force[3 * i], s.force[3 * i + 1]);
    scale = std::max(scale, f);
    const bool interior = x > reach && x < 0.06 - reach && y > reach && y < 0.03 - reach && std::fabs(x - 0.03) > reach;
    if (interior) interior_max = std::max(interior_max, f);
  }
  EXPECT_LT(interior_max, 1e-9 * scale);

  // At the resolution change itself: ghost forces of the naive variable horizon against the
  // dual horizon's residual (which is the discretisation's, not zero: see docs/theory.md).
  PdSystem naive = setup_system(parse_case_file(write_case("graded_interior_naive", graded_case(file))));
  make_naive(naive);
  impose_affine(naive, eps);
  cpu_compute_forces(naive);
  double dh_interface = 0, naive_interface = 0;
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], y = s.x0[3 * i + 1];
    if (!(y > reach && y < 0.03 - reach && std::fabs(x - 0.03) <= reach)) continue;
    dh_interface = std::max(dh_interface, std::hypot(s.force[3 * i], s.force[3 * i + 1]));
  }
  for (size_t i = 0; i < naive.n; ++i) {
    const double x = naive.x0[3 * i], y = naive.x0[3 * i + 1];
    if (!(y > reach && y < 0.03 - reach && std::fabs(x - 0.03) <= reach)) continue;
    naive_interface = std::max(naive_interface, std::hypot(naive.force[3 * i], naive.force[3 * i + 1]));
  }
  std::printf("force density at the 2:1 interface: dual horizon %.3e, naive %.3e N/m3 (bulk surface scale %.3e)\n",
              dh_interface, naive_interface, scale);
  // What docs/theory.md ("Known limits") states from these figures: at the change itself the
  // dual horizon's residual is not smaller than the naive scheme's (1.54e9 against 3.91e8
  // N/m3 measured); both are real residuals, below the free surface's scale. A change that
  // made it smaller would fail here, and the docs would have to say so.
  EXPECT_GT(naive_interface, 0.0);
  EXPECT_GT(dh_interface, naive_interface);
  EXPECT_LT(dh_interface, scale);
}

// 5% (issue 3, test 6): a smooth pulse (width ~ 10 coarse horizons) crossing a 2:1
// spacing change reflects little energy with dual horizon.
TEST(DualHorizon, WaveCrossesATwoToOneResolutionChangeWithLittleReflection) {
  const double L = 0.3, W = 0.004, h = 0.5e-3;
  const std::string file = graded_strip("graded_wave", L, W, h);
  PdSystem s = setup_system(parse_case_file(write_case("graded_wave", graded_case(file))));
  for (auto& f : s.fixed_dof) f |= 2u;  // uniaxial strain: a 1D-like P wave
  const double E = 50e9, nu = 0.25, rho = 2600;
  const double cp = std::sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho);
  // Until the pulse centre is 4 widths past the interface; energy left of it, less one
  // coarse horizon: NaN (failing) if the pulse carried no energy.
  const double reflected = breccia::atlas::reflected_pulse_energy(s, L / 2, 0.07, 0.012, cp);
  EXPECT_LT(reflected, 0.05) << "reflected energy fraction " << reflected;
}

namespace {
// `strength`: e.g. " tensile_strength: 3 MPa," for quasi-brittle (softening) bonds.
std::string graded_weibull_case(const std::string& particles, const std::string& model, const std::string& strength = "") {
  return "specimen: {particles: " + particles + "}\n"
         "model: {type: " + model + ", planar: plane_strain, variable_horizon: true, horizon_factor: 3.015}\n"
         "materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25, fracture_energy: 20," +
         strength + " weibull: {modulus: 3, seed: 5}}]\n"
         "time: {steps: 1}\n";
}
}  // namespace

// Passes without diagnostics (between output steps, the stable step's probe) skip the energy
// density, damage and max stretch; the forces, breaks and released energy must be the
// diagnostic pass's bit for bit (the stable step and the run depend on it). On the graded
// strip (variable horizons: the general loop) and a lattice (one horizon: the PMB and LPS
// symmetric loops), from one random displacement that breaks some bonds.
TEST(DiagnosticsOff, ForcesBreaksAndReleasedEnergyEqualTheDiagnosticPassBitForBit) {
  const std::string strip = graded_strip("graded_diagnostics", 0.02, 0.01, 0.5e-3);
  for (const std::string model : {"pmb", "lps"})
    for (const bool graded : {true, false}) {
      const std::string deck =
          graded ? graded_weibull_case(strip, model)
                 : "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.004, 0.004], spacing: 0.5 mm}}\n"
                   "model: {type: " + model + ", horizon_factor: 3.015}\n"
                   "materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 2}]\n"
                   "time: {steps: 1}\n";
      PdSystem s = setup_system(parse_case_file(write_case("diagnostics_" + model + (graded ? "_graded" : "_lattice"), deck)));
      ASSERT_EQ(s.symmetric_halves, !graded) << model;
      SplitMixUniform uniform{99};
      for (size_t k = 0; k < 3 * s.n; ++k) s.u[k] = (s.dimension == 2 && k % 3 == 2) ? 0.0 : 2e-6 * uniform();
      const std::vector<uint8_t> state0 = s.state;
      s.diagnostics = false;
      cpu_compute_forces(s);
      const std::vector<double> force_off = s.force, released_off = s.dissipated;
      const std::vector<uint8_t> state_off = s.state;
      s.state = state0;
      s.diagnostics = true;
      cpu_compute_forces(s);
      long long broken = 0;
      for (size_t k = 0; k < s.state.size(); ++k) broken += s.state[k] != state0[k];
      EXPECT_GT(broken, 0) << model << ": the field should break some bonds";
      EXPECT_TRUE(state_off == s.state) << model << (graded ? " graded" : " lattice");
      ASSERT_EQ(force_off.size(), s.force.size());
      EXPECT_EQ(0, std::memcmp(force_off.data(), s.force.data(), s.force.size() * sizeof(double)))
          << model << (graded ? " graded" : " lattice");
      EXPECT_EQ(0, std::memcmp(released_off.data(), s.dissipated.data(), s.n * sizeof(double)))
          << model << (graded ? " graded" : " lattice");
    }
}

// The set-up's linear passes (the stable-step probe, the energy-scatter check: fracture off)
// hide a softening system's bond damage while every bond's is 0 (DamageHiddenWhileUndamaged),
// so that the kernels take the unbroken loops. With fracture off soften() returns the stored
// damage, so each entry keeps 1.0 of its force and dilatation weight: the forces and the
// dilatation must be the same bits either way. On the graded strip (the general loop, dual
// horizons) with quasi-brittle bonds, PMB and LPS, at a small random displacement; and a
// damaged bond must keep the damage where the kernels read it.
TEST(DamageHidden, LinearPassesGiveTheSameForcesAndDilatationBitForBit) {
  const std::string strip = graded_strip("graded_damage_hidden", 0.02, 0.01, 0.5e-3);
  for (const std::string model : {"pmb", "lps"}) {
    const std::string deck = graded_weibull_case(strip, model, " tensile_strength: 3 MPa,");
    PdSystem s = setup_system(parse_case_file(write_case("damage_hidden_" + model, deck)));
    ASSERT_FALSE(s.bond_damage.empty()) << model << ": quasi-brittle bonds hold a damage per entry";
    ASSERT_FALSE(s.symmetric_halves) << model << ": the general loop";
    SplitMixUniform uniform{7};
    for (size_t k = 0; k < 3 * s.n; ++k) s.u[k] = (k % 3 == 2) ? 0.0 : 1e-9 * uniform();
    s.config.fracture = false;
    s.diagnostics = false;
    cpu_compute_forces(s);
    const std::vector<double> force_with = s.force, dilatation_with = s.dilatation;
    {
      const DamageHiddenWhileUndamaged hidden(s);
      EXPECT_TRUE(s.bond_damage.empty()) << model;
      std::fill(s.force.begin(), s.force.end(), 0.0);
      std::fill(s.dilatation.begin(), s.dilatation.end(), 0.0);
      cpu_compute_forces(s);
    }
    ASSERT_EQ(s.bond_damage.size(), s.state.size()) << model << ": the damage is back";
    EXPECT_TRUE(std::all_of(s.bond_damage.begin(), s.bond_damage.end(), [](float d) { return d == 0.0f; }));
    EXPECT_EQ(0, std::memcmp(force_with.data(), s.force.data(), s.force.size() * sizeof(double))) << model;
    EXPECT_EQ(0, std::memcmp(dilatation_with.data(), s.dilatation.data(), s.n * sizeof(double))) << model;
    s.bond_damage[s.bond_damage.size() / 2] = 0.5f;  // one damaged bond: its force is half, so nothing is hidden
    const DamageHiddenWhileUndamaged kept(s);
    EXPECT_FALSE(s.bond_damage.empty()) << model;
  }
}

// The Weibull draw (and the critical stretches from it) is computed once per bond and copied
// to the reverse entry, own and dual swapped. Check every entry against its reverse on the
// graded strip, where own and dual horizons differ (so the swap matters), and that the draw
// scatters the strengths at all.
TEST(WeibullPerBond, ReverseEntriesHoldTheSameDrawWithOwnAndDualSwapped) {
  const std::string strip = graded_strip("graded_weibull", 0.02, 0.01, 0.5e-3);
  for (const std::string model : {"pmb", "lps"}) {
    PdSystem s = setup_system(parse_case_file(write_case("weibull_per_bond_" + model, graded_weibull_case(strip, model))));
    long long differ = 0, checked = 0;
    std::vector<float> values;
    for (size_t i = 0; i < s.n; ++i)
      for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
        const int32_t j = s.neighbor[k];
        const auto row_end = s.neighbor.begin() + s.offsets[j + 1];
        const auto it = std::lower_bound(s.neighbor.begin() + s.offsets[j], row_end, static_cast<int32_t>(i));
        ASSERT_TRUE(it != row_end && *it == static_cast<int32_t>(i)) << "entry " << i << " -> " << j << " has no reverse";
        const int64_t r = it - s.neighbor.begin();
        ASSERT_EQ(s.s0_own[k], s.s0_dual[r]) << model << " entry " << k;
        ASSERT_EQ(s.s0_dual[k], s.s0_own[r]) << model << " entry " << k;
        differ += s.s0_own[k] != s.s0_dual[k];
        ++checked;
        values.push_back(s.s0_own[k]);
      }
    EXPECT_GT(differ, 0) << model << ": own and dual horizons differ somewhere on the graded strip";
    std::sort(values.begin(), values.end());
    const long long distinct = std::unique(values.begin(), values.end()) - values.begin();
    EXPECT_GT(distinct, checked / 20) << model << ": the Weibull draw should scatter the critical stretches";
  }
}

// A small 3D LPS lattice in float32: the uniform deck of the own-volume and family-volume tests.
static std::string small_float32_lps_lattice() {
  return "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.004, 0.003, 0.003], spacing: 0.5 mm}}\n"
         "model: {type: lps, horizon_factor: 3.015, precision: float32}\n"
         "materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, "
         "fracture_energy: 10}]\n"
         "time: {steps: 1}\n";
}

// The own halves' volumes beta_own V_j (damage weights, family volumes; pd_system.hpp
// own_count): with the sampled partial volume set-up keeps each entry's own sample count (a
// byte) and forms the volume where it is read; it must be the set-up's former value, the
// quadrature's fraction times the partner's volume, bit for bit: on the graded strip (counts
// made per pair, from both ends) and on a 3D lattice (counts looked up by offset), in double
// and rounded once to float in the float32 view; with the analytic partial volume (lammps)
// the volumes themselves are kept. Reference: partial_volume (pd_physics.hpp), evaluated here
// per entry from the positions, not read from the system.
TEST(DualHorizon, OwnVolumesFormedFromSampleCountsAreTheQuadratureTimesTheVolume) {
  const std::string strip = graded_strip("graded_own_counts", 0.02, 0.01, 0.5e-3);
  struct Deck {
    std::string name, yaml;
    bool counted;
  };
  const std::string lattice = small_float32_lps_lattice();
  std::string lammps = graded_case(strip);
  lammps.replace(lammps.find("variable_horizon"), 0, "partial_volume: lammps, ");
  const std::vector<Deck> decks = {{"graded", graded_case(strip), true}, {"lattice_float32", lattice, true},
                                   {"graded_lammps", lammps, false}};
  size_t counted_bytes = 0, stored_bytes = 0;
  for (const Deck& d : decks) {
    SCOPED_TRACE(d.name);
    const CaseConfig config = parse_case_file(write_case("own_counts_" + d.name, d.yaml));
    PdSystem s = setup_system(config);
    ASSERT_GT(s.bond_count(), 0u);
    EXPECT_EQ(s.own_count.size(), d.counted ? s.bond_count() : 0u);
    EXPECT_EQ(s.vol_own.size(), d.counted ? 0u : s.bond_count());
    if (!s.symmetric_halves) (d.counted ? counted_bytes : stored_bytes) = s.bytes_per_bond_entry();
    if (config.precision == CaseConfig::Precision::Float32 && !s.f32.active) float32_enable(s);
    const PdView p = s.view();
    const PdViewT<float> q = s.f32.active ? float32_view(s) : PdViewT<float>{};
    long long partial = 0;
    for (size_t i = 0; i < s.n; ++i)
      for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
        const int32_t j = s.neighbor[k];
        const double xv[3] = {s.x0[3 * j] - s.x0[3 * i], s.x0[3 * j + 1] - s.x0[3 * i + 1], s.x0[3 * j + 2] - s.x0[3 * i + 2]};
        const double beta = partial_volume(config.partial_volume, xv, s.horizon[i], s.half_cell[j], s.dimension);
        const double expected = beta * s.volume[j];
        partial += beta > 0 && beta < 1;
        const double held = s.own_volume(k), viewed = own_volume(p, k);
        ASSERT_EQ(std::memcmp(&expected, &held, sizeof(double)), 0) << "entry " << k << ": " << expected << " " << held;
        ASSERT_EQ(std::memcmp(&expected, &viewed, sizeof(double)), 0) << "entry " << k;
        ASSERT_EQ(s.own_half_exists(k), expected > 0) << "entry " << k;
        ASSERT_EQ(own_half_exists(p, k), expected > 0) << "entry " << k;
        if (q.n) {
          const float expected_f = static_cast<float>(expected), viewed_f = own_volume(q, k);
          ASSERT_EQ(std::memcmp(&expected_f, &viewed_f, sizeof(float)), 0) << "entry " << k;
        }
      }
    EXPECT_GT(partial, 0) << "some entries should hold a partial volume (0 < beta < 1)";
  }
  // A double per entry replaced by a byte (both graded decks store their dual halves).
  EXPECT_EQ(counted_bytes + sizeof(double) - sizeof(uint8_t), stored_bytes);
}

// Each particle's family volume (pd_system.hpp family_volume), the damage's denominator in
// every diagnostic pass, summed once at set-up: it must be the sum the passes formed per entry
// before, the own halves' volumes beta_own V_j of the row added in row order from 0, bit for
// bit: in double, and in the float32 view as the volumes rounded to float and added in double.
// Reference: partial_volume (pd_physics.hpp) per entry from the positions, summed here. The
// damage of a diagnostic pass must then be the same bits whether the view holds the stored
// volumes or sums them per entry (the view without them), with a third of the bonds broken.
TEST(FamilyVolume, StoredPerParticleIsTheRowSumOfTheOwnVolumesBitForBit) {
  const std::string strip = graded_strip("graded_family_volume", 0.02, 0.01, 0.5e-3);
  const std::string lattice = small_float32_lps_lattice();
  std::string lammps = graded_case(strip);
  lammps.replace(lammps.find("variable_horizon"), 0, "partial_volume: lammps, ");
  std::string graded_lps = graded_case(strip);
  graded_lps.replace(graded_lps.find("type: pmb"), 9, "type: lps");
  std::string lattice_pmb = lattice;
  lattice_pmb.replace(lattice_pmb.find("type: lps"), 9, "type: pmb");
  lattice_pmb.replace(lattice_pmb.find(", precision: float32"), 20, "");
  const std::vector<std::pair<std::string, std::string>> decks = {{"graded", graded_case(strip)},
                                                                  {"graded_lps", graded_lps},
                                                                  {"lattice_float32", lattice},
                                                                  {"lattice_pmb", lattice_pmb},
                                                                  {"graded_lammps", lammps}};
  for (const auto& [name, yaml] : decks) {
    SCOPED_TRACE(name);
    const CaseConfig config = parse_case_file(write_case("family_volume_" + name, yaml));
    PdSystem s = setup_system(config);
    ASSERT_GT(s.bond_count(), 0u);
    ASSERT_EQ(s.family_volume.size(), s.n);
    const bool f32 = config.precision == CaseConfig::Precision::Float32;
    if (f32 && !s.f32.active) float32_enable(s);
    if (f32) ASSERT_EQ(s.f32.family_volume.size(), s.n);
    size_t differ_from_reversed = 0;
    for (size_t i = 0; i < s.n; ++i) {
      double expected = 0.0, expected_f = 0.0, reversed = 0.0;
      std::vector<double> parts;
      for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
        const int32_t j = s.neighbor[k];
        const double xv[3] = {s.x0[3 * j] - s.x0[3 * i], s.x0[3 * j + 1] - s.x0[3 * i + 1], s.x0[3 * j + 2] - s.x0[3 * i + 2]};
        const double v = partial_volume(config.partial_volume, xv, s.horizon[i], s.half_cell[j], s.dimension) * s.volume[j];
        expected += v;
        expected_f += static_cast<float>(v);
        parts.push_back(v);
      }
      for (auto it = parts.rbegin(); it != parts.rend(); ++it) reversed += *it;
      differ_from_reversed += reversed != expected;
      ASSERT_EQ(std::memcmp(&expected, &s.family_volume[i], sizeof(double)), 0)
          << "particle " << i << ": " << expected << " " << s.family_volume[i];
      if (f32) ASSERT_EQ(std::memcmp(&expected_f, &s.f32.family_volume[i], sizeof(double)), 0) << "particle " << i;
    }
    // The order matters on these families (another order gives other bits somewhere), so the
    // comparison above checks the order too.
    EXPECT_GT(differ_from_reversed, 0u);

    // The diagnostic pass's damage with the stored volumes and with the per-entry sums.
    for (size_t k = 0; k < s.bond_count(); k += 3) s.state[k] = 0;
    s.diagnostics = true;
    auto damage_of_a_pass = [&](bool stored) {
      std::vector<double> kept = s.family_volume, kept_f = s.f32.family_volume;
      if (!stored) s.family_volume.clear(), s.f32.family_volume.clear();
      if (f32) float32_compute_forces(s);
      else cpu_compute_forces(s);
      s.family_volume = kept;
      s.f32.family_volume = kept_f;
      return s.damage;
    };
    const std::vector<double> with = damage_of_a_pass(true), without = damage_of_a_pass(false);
    ASSERT_EQ(with.size(), s.n);
    EXPECT_EQ(std::memcmp(with.data(), without.data(), s.n * sizeof(double)), 0);
    EXPECT_GT(*std::max_element(with.begin(), with.end()), 0.2) << "a third of the bonds broken should show";
  }
}
