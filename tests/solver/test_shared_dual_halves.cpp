// Shared dual halves (pd_system.hpp k_dual_halves): with one horizon and equal partial volumes
// both ways, set-up keeps no k_dual / s0_dual and every reader takes the own halves. The same
// case set up with the dual halves stored (SetupHooks::store_dual_halves: the layout every run
// had before) must hold them equal to the own halves bit for bit, and give the same set-up and
// the same forces, breaks and released energy bit for bit, through the symmetric loops and the
// general loop (which reads the dual halves; symmetric_halves cleared to take it).
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "helpers.hpp"
#include "measures.hpp"

using namespace breccia;
using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

template <class T, class A>
bool same_bits(const std::vector<T, A>& a, const std::vector<T, A>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

std::string lattice_deck(const std::string& model, const std::string& extra_model, const std::string& extra_material,
                         int dimension) {
  const std::string box = dimension == 3 ? "[0, 0, 0, 0.004, 0.004, 0.004]" : "[0, 0, 0.006, 0.006]";
  return "specimen: {lattice: {dimension: " + std::to_string(dimension) + ", box: " + box + ", spacing: 0.5 mm}}\n" +
         "model: {type: " + model + ", horizon_factor: 3.015" + (dimension == 2 ? ", planar: plane_strain" : "") +
         extra_model + "}\n" +
         "materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 2" +
         extra_material + "}]\ntime: {steps: 1}\n";
}

// One force pass from a random displacement that breaks some bonds; what it changed.
struct PassResult {
  std::vector<double> force, dissipated, damage;
  std::vector<uint8_t> state;
  decltype(PdSystem::bond_damage) bond_damage;
};
PassResult random_pass(PdSystem& s, uint64_t seed) {
  SplitMixUniform uniform{seed};
  for (size_t k = 0; k < 3 * s.n; ++k) s.u[k] = (s.dimension == 2 && k % 3 == 2) ? 0.0 : 2e-6 * uniform();
  s.diagnostics = true;
  cpu_compute_forces(s);
  return {s.force, s.dissipated, s.damage, s.state, s.bond_damage};
}

}  // namespace

TEST(SharedDualHalves, OneHorizonHoldsNoDualHalvesAndGivesTheStoredLayoutsForcesBitForBit) {
  struct Deck {
    std::string name, yaml;
  };
  const std::string weibull = ", weibull: {modulus: 3, seed: 5}";
  const std::vector<Deck> decks = {
      {"pmb_weibull_surface", lattice_deck("pmb", ", surface_correction: energy", weibull, 3)},
      {"lps_gaussian_weibull", lattice_deck("lps", ", influence: gaussian", weibull, 3)},
      {"pmb_softening_rate", lattice_deck("pmb", "", ", tensile_strength: 2 MPa, strength_rate: fib_mc2010", 3)},
      {"pmb_float32", lattice_deck("pmb", ", precision: float32", "", 3)},
      {"pmb_2d", lattice_deck("pmb", "", weibull, 2)},
  };
  for (const Deck& d : decks) {
    SCOPED_TRACE(d.name);
    const CaseConfig config = parse_case_file(write_case("shared_dual_" + d.name, d.yaml));
    PdSystem shared = setup_system(config);
    SetupHooks store;
    store.store_dual_halves = true;
    PdSystem stored = setup_system(config, store);
    // The shared layout holds no dual halves; the stored one holds copies of the own ones.
    ASSERT_TRUE(shared.dual_halves_shared);
    EXPECT_TRUE(shared.k_dual.empty());
    EXPECT_TRUE(shared.s0_dual.empty());
    ASSERT_FALSE(stored.dual_halves_shared);
    ASSERT_GT(stored.bond_count(), 0u);
    EXPECT_TRUE(same_bits(stored.k_dual, stored.k_own)) << "a one-horizon entry's dual modulus is its own";
    EXPECT_TRUE(same_bits(stored.s0_dual, stored.s0_own)) << "a one-horizon entry's dual stretch is its own";
    EXPECT_EQ(shared.bytes_per_bond_entry() + sizeof(double) + sizeof(float), stored.bytes_per_bond_entry());
    // The rest of the set-up, bit for bit.
    EXPECT_TRUE(same_bits(shared.k_own, stored.k_own));
    EXPECT_TRUE(same_bits(shared.s0_own, stored.s0_own));
    EXPECT_TRUE(same_bits(shared.vol_own, stored.vol_own));
    EXPECT_TRUE(same_bits(shared.own_count, stored.own_count));
    EXPECT_TRUE(same_bits(shared.state, stored.state));
    EXPECT_TRUE(same_bits(shared.s_onset, stored.s_onset));
    EXPECT_TRUE(same_bits(shared.calibration_factor, stored.calibration_factor));
    EXPECT_EQ(shared.symmetric_halves, stored.symmetric_halves);
    EXPECT_EQ(shared.stable_dt, stored.stable_dt);
    EXPECT_EQ(shared.dt, stored.dt);
    // The forces: the set-up's own loop, then the general loop (it reads the dual halves).
    for (const bool general : {false, true}) {
      SCOPED_TRACE(general ? "general loop" : "set-up's loop");
      if (general) shared.symmetric_halves = stored.symmetric_halves = false;
      const uint64_t seed = general ? 7 : 3;
      const std::vector<uint8_t> state0 = shared.state;
      const PassResult a = random_pass(shared, seed), b = random_pass(stored, seed);
      long long broken = 0;
      for (size_t k = 0; k < a.state.size(); ++k) broken += a.state[k] != state0[k];
      if (d.name != "pmb_softening_rate") EXPECT_GT(broken, 0) << "the field should break some bonds";
      EXPECT_TRUE(same_bits(a.force, b.force));
      EXPECT_TRUE(same_bits(a.dissipated, b.dissipated));
      EXPECT_TRUE(same_bits(a.damage, b.damage));
      EXPECT_TRUE(same_bits(a.state, b.state));
      EXPECT_TRUE(same_bits(a.bond_damage, b.bond_damage));
    }
  }
}

// Where the halves differ the set-up stores them: variable horizons on a graded strip (the
// dual horizon's own case), and the 2D LPS critical stretch, scaled per end of the entry.
TEST(SharedDualHalves, HalvesThatDifferAreStored) {
  const std::string lps_2d = lattice_deck("lps", "", "", 2);
  PdSystem s = system_from_yaml("shared_dual_lps_2d", lps_2d);
  EXPECT_FALSE(s.dual_halves_shared);
  EXPECT_EQ(s.k_dual.size(), s.bond_count());
  EXPECT_EQ(s.s0_dual.size(), s.bond_count());
  // A graded arrangement with one horizon: j's cell in i's horizon and i's cell in j's differ.
  const std::string graded = breccia::atlas::write_graded_strip(process_temp_dir() + "/shared_dual_graded.h5", 0.02,
                                                                0.01, 0.5e-3, 2.0);
  for (const bool variable : {true, false}) {
    PdSystem g = system_from_yaml(
        "shared_dual_graded",
        "specimen: {particles: " + graded + "}\n"
        "model: {type: pmb, planar: plane_strain, variable_horizon: " + (variable ? "true" : "false") +
            ", horizon_factor: 3.015}\n"
            "materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]\n"
            "time: {steps: 1, check_stability: false}\n");
    EXPECT_FALSE(g.dual_halves_shared) << (variable ? "variable" : "one") << " horizon on a graded strip";
    EXPECT_EQ(g.k_dual.size(), g.bond_count());
  }
}
