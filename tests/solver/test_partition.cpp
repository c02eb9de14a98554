// Domain decomposition (partition.hpp): ownership by weighted Morton ranges, and halos that
// are exactly the off-rank bond partners of the serial CSR. Checked against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <barrier>
#include <cmath>
#include <functional>
#include <random>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include "breccia/common/families.hpp"
#include "breccia/solver/distributed_setup.hpp"
#include "breccia/solver/family.hpp"
#include "breccia/solver/partition.hpp"
#include "breccia/solver/rank_system.hpp"
#include "helpers.hpp"

using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

PdSystem lattice(const std::string& name, const std::string& model_extra = "") {
  return system_from_yaml(name, "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.012, 0.012, 0.012], spacing: 1 mm}}\n"
                                "model: {type: pmb, horizon_factor: 3.015" + model_extra + "}\n"
                                "materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
                                "time: {steps: 1}\n");
}

// The rank-system tests' block: a 6 x 5 x 4 mm lattice at 1 mm with one material, model
// `type` at horizon factor 3.015, 5 steps; `extra`: the case's other lines (loads, initial state).
std::string rank_block(const std::string& type, const std::string& extra = "") {
  return "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.006, 0.005, 0.004], spacing: 1 mm}}\n"
         "model: {type: " + type + ", horizon_factor: 3.015}\n"
         "materials: [{name: m, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: 0.25, fracture_energy: 10}]\n" +
         extra + "time: {steps: 5}\n";
}

// Whether rank 0 gathers the loop's state into its global system (serial HDF5: it writes every
// file from it); with parallel HDF5 no rank gathers it, so none names an array as held.
#ifdef BRECCIA_PARALLEL_HDF5
constexpr bool kRootStages = false;
#else
constexpr bool kRootStages = true;
#endif

// Whether release_global_for_loop named array `a` as held (rank 0 gathers into it: every
// rank takes part).
bool named_as_held(const std::vector<const void*>& held, const void* a) {
  return std::find(held.begin(), held.end(), a) != held.end();
}

// A distributed set-up's global system as rank `rank` holds it before the stable step's cut
// (distributed_setup.hpp), from a whole one: the per-particle arrays whole, the other ranks'
// rows empty (their offsets flat), the per-entry arrays the rank's rows only, the partition
// in distributed_rows.
PdSystem rank_rows_only(const PdSystem& whole, const Partition& part, int rank) {
  PdSystem g = whole;
  const int64_t eb = whole.offsets[part.begin[rank]], ee = whole.offsets[part.begin[rank + 1]];
  for (int64_t& o : g.offsets) o = std::clamp(o, eb, ee) - eb;
  const size_t entries = whole.bond_count();
  auto rows = [&](auto& a) {
    if (a.size() == entries) a = std::remove_reference_t<decltype(a)>(a.begin() + eb, a.begin() + ee);
  };
  rows(g.neighbor);
  rows(g.xi_len);
  rows(g.k_own);
  rows(g.k_dual);
  rows(g.vol_own);
  rows(g.s0_own);
  rows(g.s0_dual);
  rows(g.s_onset);
  rows(g.state);
  g.distributed_rows = part.begin;
  return g;
}

// The halo of rank r by brute force: every off-rank partner of an owned particle's row.
std::set<int32_t> brute_ghosts(const PdSystem& s, const Partition& p, int r) {
  std::set<int32_t> g;
  for (int64_t i = p.begin[r]; i < p.begin[r + 1]; ++i)
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k)
      if (p.owner(s.neighbor[k]) != r) g.insert(s.neighbor[k]);
  return g;
}

}  // namespace

TEST(Partition, GhostsAreTheOffRankPartnersAndSendsMatchTheReceivers) {
  const PdSystem s = lattice("partition_lattice");  // 1,728 particles, families cut by the faces
  for (int ranks : {1, 2, 3, 4, 7}) {
    const Partition p = MortonRangePartitioner().partition(s.offsets, ranks);
    ASSERT_EQ(p.ranks(), ranks);
    std::vector<Halo> halos;
    for (int r = 0; r < ranks; ++r) halos.push_back(build_halo(p, r, s.offsets, s.neighbor));
    for (int r = 0; r < ranks; ++r) {
      const std::set<int32_t> expected = brute_ghosts(s, p, r);
      EXPECT_EQ(std::vector<int32_t>(expected.begin(), expected.end()), halos[r].ghosts) << ranks << " ranks, rank " << r;
      // What r receives from q is exactly what q sends to r.
      for (size_t a = 0; a < halos[r].recv_ranks.size(); ++a) {
        const int q = halos[r].recv_ranks[a];
        const std::vector<int32_t> received(halos[r].ghosts.begin() + halos[r].recv_begin[a],
                                            halos[r].ghosts.begin() + halos[r].recv_begin[a + 1]);
        const auto& sq = halos[q].send_ranks;
        const auto at = std::find(sq.begin(), sq.end(), r);
        ASSERT_NE(at, sq.end()) << "rank " << q << " must send to " << r;
        EXPECT_EQ(halos[q].send_lists[at - sq.begin()], received);
        for (int32_t g : received) EXPECT_EQ(p.owner(g), q);
      }
    }
    if (ranks == 1) EXPECT_TRUE(halos[0].ghosts.empty());
  }
}

TEST(Partition, WeightedRangesBalanceTheBondLoop) {
  // Equal work (entries + 4 per particle) per range; on 1,728 particles the granularity of
  // one particle (~100 entries of ~25,000 per rank at 8 ranks) bounds the imbalance near 1.
  const PdSystem s = lattice("partition_balance");
  for (int ranks : {2, 4, 8}) {
    const DecompositionStats st = decomposition_stats(MortonRangePartitioner().partition(s.offsets, ranks), s.offsets,
                                                      s.neighbor, 24.0);
    EXPECT_LE(st.max_over_mean_bonds, 1.05) << ranks;
    EXPECT_GT(st.mean_ghost_ratio, 0.0);
  }
}

// The cut without the whole offsets (cut_partition: each rank its slice's cuts, merged)
// equals partition's on the whole offsets, exactly: row lengths with long equal runs (targets
// on exact ties between two rows), zero-length rows, a few heavy rows (the clamp), cut into
// 1 to 7 ranks from 1 to 5 slices of unequal lengths.
TEST(Partition, CutsFromSlicesAreTheWholeOffsetsCuts) {
  std::mt19937 gen(7);
  for (int pattern = 0; pattern < 4; ++pattern) {
    const int64_t n = 40 + 17 * pattern;
    std::vector<int64_t> sizes(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i)
      sizes[i] = pattern == 0 ? 4 : pattern == 1 ? static_cast<int64_t>(gen() % 3) * 2 : pattern == 2 ? (i % 9 == 0 ? 400 : 0)
                                                                                             : static_cast<int64_t>(gen() % 50);
    std::vector<int64_t> offsets(static_cast<size_t>(n) + 1, 0);
    for (int64_t i = 0; i < n; ++i) offsets[i + 1] = offsets[i] + sizes[i];
    for (int ranks = 1; ranks <= 7; ++ranks) {
      const Partition whole = MortonRangePartitioner().partition(offsets, ranks);
      for (int slices = 1; slices <= 5; ++slices) {
        std::vector<int64_t> cut(static_cast<size_t>(ranks), -1);
        for (int q = 0; q < slices; ++q) {
          const int64_t b = n * q * q / (slices * slices), e = n * (q + 1) * (q + 1) / (slices * slices);
          const std::vector<int64_t> mine(sizes.begin() + b, sizes.begin() + e);
          const std::vector<int64_t> found = MortonRangePartitioner().slice_cuts(mine, b, offsets[b], n, offsets[n], ranks);
          for (int r = 1; r < ranks; ++r)
            if (found[r] >= 0) {
              EXPECT_EQ(cut[r], -1) << "two slices hold target " << r;
              cut[r] = found[r];
            }
        }
        EXPECT_EQ(MortonRangePartitioner::from_slice_cuts(cut, n, ranks).begin, whole.begin)
            << "pattern " << pattern << ", " << ranks << " ranks, " << slices << " slices";
      }
    }
  }
}

TEST(Partition, AnEmptyRankHasNothingToExchange) {
  const PdSystem s = lattice("partition_empty");
  const int64_t n = static_cast<int64_t>(s.n);
  Partition p;
  p.begin = {0, 0, n / 2, n};  // rank 0 owns nothing
  EXPECT_EQ(p.owner(0), 1);
  EXPECT_EQ(p.owner(n - 1), 2);
  const Halo empty = build_halo(p, 0, s.offsets, s.neighbor);
  EXPECT_TRUE(empty.ghosts.empty());
  EXPECT_TRUE(empty.send_ranks.empty());
  for (int r : {1, 2}) {
    const Halo h = build_halo(p, r, s.offsets, s.neighbor);
    EXPECT_EQ(std::count(h.recv_ranks.begin(), h.recv_ranks.end(), 0), 0);
    EXPECT_EQ(std::count(h.send_ranks.begin(), h.send_ranks.end(), 0), 0);
  }
}

TEST(Partition, AFamilySpanningThreeRanksIsFedByAllOfThem) {
  const PdSystem s = lattice("partition_span");
  const int ranks = 8;
  const Partition p = MortonRangePartitioner().partition(s.offsets, ranks);
  int64_t found = -1;
  std::set<int> owners;
  for (size_t i = 0; i < s.n && found < 0; ++i) {
    std::set<int> o;
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) o.insert(p.owner(s.neighbor[k]));
    o.erase(p.owner(static_cast<int64_t>(i)));
    if (o.size() >= 2) {  // its own rank and two or more others
      found = static_cast<int64_t>(i);
      owners = o;
    }
  }
  ASSERT_GE(found, 0) << "8 ranks of a 12^3 lattice must have a family over three ranks";
  const int r = p.owner(found);
  const Halo h = build_halo(p, r, s.offsets, s.neighbor);
  for (int q : owners) {
    EXPECT_NE(std::find(h.recv_ranks.begin(), h.recv_ranks.end(), q), h.recv_ranks.end()) << q;
    EXPECT_NE(std::find(h.send_ranks.begin(), h.send_ranks.end(), q), h.send_ranks.end()) << q;
  }
  for (int64_t k = s.offsets[found]; k < s.offsets[found + 1]; ++k) {
    const int32_t j = s.neighbor[k];
    if (p.owner(j) != r) EXPECT_TRUE(std::binary_search(h.ghosts.begin(), h.ghosts.end(), j)) << j;
  }
}

TEST(Partition, MoreRanksThanParticlesIsRefusedNamingBoth) {
  const std::vector<int64_t> offsets{0, 1, 2};  // two particles
  try {
    MortonRangePartitioner().partition(offsets, 3);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("3 ranks for 2 particles"), std::string::npos) << e.what();
  }
}

// The lattice figures without families (lattice_decomposition_stats, used for 10^8
// particles) equal decomposition_stats on the families built here explicitly, in the same
// Morton order of the lattice indices, when every particle is counted (sample 1).
TEST(Partition, LatticeFiguresWithoutFamiliesEqualThoseOfTheBuiltFamilies) {
  const std::array<int64_t, 3> n{13, 9, 6};
  std::vector<std::array<int, 3>> stencil;
  for (int a = -2; a <= 2; ++a)
    for (int b = -2; b <= 2; ++b)
      for (int c = -2; c <= 2; ++c)
        if ((a || b || c) && a * a + b * b + c * c <= 5) stencil.push_back({a, b, c});
  // Lattice points in Morton order of their indices (keys of a brute-force interleave).
  auto key = [](int64_t x, int64_t y, int64_t z) {
    uint64_t k = 0;
    for (int bit = 0; bit < 21; ++bit)
      k |= ((uint64_t(x) >> bit & 1) << (3 * bit)) | ((uint64_t(y) >> bit & 1) << (3 * bit + 1)) |
           ((uint64_t(z) >> bit & 1) << (3 * bit + 2));
    return k;
  };
  std::vector<std::array<int64_t, 3>> points;
  for (int64_t z = 0; z < n[2]; ++z)
    for (int64_t y = 0; y < n[1]; ++y)
      for (int64_t x = 0; x < n[0]; ++x) points.push_back({x, y, z});
  std::sort(points.begin(), points.end(),
            [&](const auto& p, const auto& q) { return key(p[0], p[1], p[2]) < key(q[0], q[1], q[2]); });
  std::map<std::array<int64_t, 3>, int32_t> index;
  for (size_t i = 0; i < points.size(); ++i) index[points[i]] = static_cast<int32_t>(i);
  std::vector<int64_t> offsets{0};
  std::vector<int32_t> neighbor;
  for (const auto& p : points) {
    for (const auto& o : stencil) {
      const auto it = index.find({p[0] + o[0], p[1] + o[1], p[2] + o[2]});
      if (it != index.end()) neighbor.push_back(it->second);
    }
    offsets.push_back(static_cast<int64_t>(neighbor.size()));
  }
  const std::vector<int> ranks{1, 2, 3, 5, 8, 13};
  const auto lattice_stats = lattice_decomposition_stats(n, stencil, ranks, 24.0, 1);
  for (size_t q = 0; q < ranks.size(); ++q) {
    const auto ref = decomposition_stats(MortonRangePartitioner().partition(offsets, ranks[q]), offsets, neighbor, 24.0);
    const auto& got = lattice_stats[q];
    EXPECT_EQ(got.min_owned, ref.min_owned) << ranks[q];
    EXPECT_EQ(got.max_owned, ref.max_owned) << ranks[q];
    EXPECT_DOUBLE_EQ(got.max_over_mean_bonds, ref.max_over_mean_bonds) << ranks[q];
    EXPECT_DOUBLE_EQ(got.mean_ghost_ratio, ref.mean_ghost_ratio) << ranks[q];
    EXPECT_DOUBLE_EQ(got.max_ghost_ratio, ref.max_ghost_ratio) << ranks[q];
    EXPECT_DOUBLE_EQ(got.max_halo_bytes, ref.max_halo_bytes) << ranks[q];
    EXPECT_EQ(got.max_neighbour_ranks, ref.max_neighbour_ranks) << ranks[q];
  }
}

// The rank's system (no MPI needed): each owned row reads the same partners, through local
// indices, with the same bond data, as the global row; ghosts hold the partners' values.
TEST(RankSystem, OwnedRowsReadTheGlobalPartnersThroughLocalIndices) {
  PdSystem g = system_from_yaml("rank_rows", rank_block("lps", "boundary: [{type: velocity, set: xmin, value: [-1, 0, 0], components: [x]}]\n"));
  for (int ranks : {1, 3, 5}) {
    for (int r = 0; r < ranks; ++r) {
      const RankLayout L = rank_layout(g, ranks, r);
      const PdSystem s = restrict_to_rank(g, L);
      ASSERT_EQ(static_cast<int64_t>(s.n), L.owned());
      ASSERT_EQ(s.x0.size(), 3 * static_cast<size_t>(L.owned() + L.ghosts()));
      for (int64_t i = 0; i < L.owned(); ++i) {
        const int64_t gi = L.begin() + i;
        ASSERT_EQ(s.offsets[i + 1] - s.offsets[i], g.offsets[gi + 1] - g.offsets[gi]);
        for (int64_t k = 0; k < s.offsets[i + 1] - s.offsets[i]; ++k) {
          const int64_t lj = s.neighbor[s.offsets[i] + k], gj = g.neighbor[g.offsets[gi] + k];
          ASSERT_GE(lj, 0);
          EXPECT_EQ(s.original_index[lj], g.original_index[gj]);
          EXPECT_EQ(s.x0[3 * lj], g.x0[3 * gj]);
          EXPECT_EQ(s.k_own[s.offsets[i] + k], g.k_own[g.offsets[gi] + k]);
        }
      }
      // The constraint keeps exactly the owned members, in order.
      size_t owned_members = 0;
      for (const int32_t p : g.constraints[0].particles) owned_members += p >= L.begin() && p < L.begin() + L.owned();
      EXPECT_EQ(s.constraints[0].particles.size(), owned_members);
    }
  }
}

// What the global system of a distributed run keeps for the time loop
// (release_global_for_loop): on rank 0 the state its writers gather and read, on the other
// ranks only the counts and offsets every rank's collectives and checkpoint sizes read; the
// arrays a gather targets are named as held on every rank (else the other ranks would skip
// a collective rank 0 enters).
TEST(RankSystem, GlobalSystemKeepsWhatTheLoopReadsAfterTheRanksTookTheirShare) {
  const std::string yaml = rank_block("lps", "boundary: [{type: velocity, set: xmin, value: [-1, 0, 0], components: [x]}]\n");
  const PdSystem whole = system_from_yaml("release_whole", yaml);
  for (const bool root : {true, false}) {
    PdSystem g = system_from_yaml("release_global", yaml);
    const std::vector<const void*> held = release_global_for_loop(g, root);
    const auto named = [&](const void* a) { return named_as_held(held, a); };
    // Every rank: the counts, offsets and content id (the checkpoint's sizes and identity).
    EXPECT_EQ(g.n, whole.n);
    EXPECT_EQ(g.bond_count(), whole.bond_count());
    EXPECT_EQ(g.offsets, whole.offsets);
    EXPECT_EQ(g.particles.content_id, whole.particles.content_id);
    // Set-up only, on every rank: released.
    for (const std::vector<double>* a : {&g.density, &g.horizon, &g.weighted_volume, &g.particles.position_m})
      EXPECT_TRUE(a->empty());
    EXPECT_TRUE(g.material.empty());
    EXPECT_TRUE(g.constraints[0].particles.empty());
    EXPECT_TRUE(named(&g.density));
    // The bond states: with parallel HDF5 no rank gathers them (each writes its rows, the
    // broken bits come from every rank's rows): released on every rank, named as held on
    // none. Without it rank 0 holds them whole for its writers, the others take part in its
    // gathers.
#ifdef BRECCIA_PARALLEL_HDF5
    EXPECT_TRUE(g.state.empty());
    EXPECT_FALSE(named(&g.state));
    const bool states_gathered = false;
#else
    const bool states_gathered = true;
#endif
#ifdef BRECCIA_PARALLEL_HDF5
    // With parallel HDF5 rank 0 gathers nothing either (every rank writes its rows, the
    // history's particles and the instability message come from their owners): the state,
    // fields and reference arrays go on every rank, named as held on none.
    for (const std::vector<double>* a : {&g.u, &g.v, &g.a, &g.force, &g.damage, &g.dilatation, &g.x0, &g.volume})
      EXPECT_TRUE(a->empty()) << (root ? "rank 0" : "another rank");
    EXPECT_TRUE(g.original_index.empty());
    EXPECT_TRUE(g.neighbor.empty());
    for (const void* a : {static_cast<const void*>(&g.u), static_cast<const void*>(&g.dilatation),
                          static_cast<const void*>(&g.x0)})
      EXPECT_FALSE(named(a));
    EXPECT_EQ(loop_state_bytes(g), 0u);
    (void)states_gathered;
#else
    if (root) {  // the gathers' targets and what the writers read stay whole
      EXPECT_EQ(g.u.size(), 3 * whole.n);
      if (states_gathered) EXPECT_EQ(g.state, whole.state);
      EXPECT_EQ(g.x0, whole.x0);
      EXPECT_EQ(g.original_index, whole.original_index);
      EXPECT_EQ(g.neighbor, whole.neighbor);
      EXPECT_FALSE(named(&g.u));
      EXPECT_GT(loop_state_bytes(g), 3 * whole.n * sizeof(double));
    } else {  // released, and named as held: the gather into rank 0's still runs
      for (const std::vector<double>* a : {&g.u, &g.v, &g.force, &g.damage, &g.dilatation, &g.x0, &g.volume})
        EXPECT_TRUE(a->empty());
      EXPECT_TRUE(g.state.empty());
      EXPECT_TRUE(g.original_index.empty());
      for (const void* a : {static_cast<const void*>(&g.u), static_cast<const void*>(&g.dilatation)})
        EXPECT_TRUE(named(a));
      EXPECT_EQ(named(&g.state), states_gathered);
      EXPECT_FALSE(named(&g.min_stretch)) << "not held (no compressive enhancement): no gather";
    }
#endif
  }
}

// A distributed set-up's ranks other than 0 never allocate the global system's accelerations
// and body forces (zero at set-up) and let its displacements and velocities go once the
// stable-step estimate cut the rank's system (setup_system, mpi_stable_step_forces): the
// rank's system starts from zeros where the set-up's values are zeros and otherwise keeps its
// own (copy_rank_state), and the four are named as held all the same (rank 0 holds them for
// every particle: a rank that skipped the gather would leave rank 0 waiting in it).
TEST(RankSystem, StateArraysARankNeverHeldAreZeroOrKeptAndStillNamedAsHeld) {
  const std::string yaml = rank_block("pmb", "initial: [{type: velocity, value: [1, 2, 3]}]\n");
  PdSystem g = system_from_yaml("never_held", yaml);
  const RankLayout L = rank_layout(g, 2, 1);
  const size_t local3 = 3 * static_cast<size_t>(L.owned() + L.ghosts());
  std::vector<double>().swap(g.a);
  std::vector<double>().swap(g.body);
  PdSystem s = restrict_to_rank(g, L);  // cut afresh: zeros for a and body, the velocities taken
  EXPECT_EQ(s.a, std::vector<double>(local3, 0.0));
  EXPECT_EQ(s.body, std::vector<double>(local3, 0.0));
  ASSERT_EQ(s.v.size(), local3);
  EXPECT_EQ(s.v[0], 1.0);
  EXPECT_EQ(s.v[local3 - 1], 3.0);
  // The velocities let go: the rank's system keeps its own when brought up to date.
  std::vector<double>().swap(g.v);
  s.v[0] = 7.0;
  copy_rank_state(s, g, L);
  ASSERT_EQ(s.v.size(), local3);
  EXPECT_EQ(s.v[0], 7.0);
  EXPECT_EQ(s.a.size(), local3);
  // A system cut afresh from a global one that holds no velocities has none to start from.
  EXPECT_THROW(restrict_to_rank(g, L), std::logic_error);
  std::vector<double>().swap(g.u);
  const std::vector<const void*> held = release_global_for_loop(g, false);
  const auto named = [&](const void* a) { return named_as_held(held, a); };
  for (const std::vector<double>* a : {&g.u, &g.v, &g.a, &g.body}) EXPECT_EQ(named(a), kRootStages);
  EXPECT_EQ(named(&g.force), kRootStages);  // held here, as before
  EXPECT_FALSE(named(&g.min_stretch)) << "not held on rank 0 either (no compressive enhancement): no gather";
}

// A distributed set-up's ranks other than 0 also let go of the forces and of the fields the
// stable-step estimate's last pass fills (release_global_at_stable_step, called by
// mpi_stable_step_forces once the rank's system is cut): none of them is left in the global
// system, not even as capacity; the rank's system keeps its own values when brought up to date
// (copy_rank_state), and each array is named as held for rank 0's gathers, the model's own
// fields (here LPS's two factors) only where the rank's system holds them.
TEST(RankSystem, ForcesAndFieldsLetGoAtTheStableStepAreKeptByTheRankAndStillNamedAsHeld) {
  const std::string yaml = rank_block("lps", "initial: [{type: velocity, value: [1, 2, 3]}]\n");
  PdSystem g = system_from_yaml("fields_let_go", yaml);
  ASSERT_FALSE(g.lps_a.empty()) << "a uniform LPS lattice takes the fast path (its factors are what this checks)";
  ASSERT_TRUE(g.corr_deformation.empty());
  ASSERT_EQ(g.fixed_dof.size(), g.n);
  ASSERT_EQ(g.lps.size(), g.n);
  g.calibration_factor.assign(g.n, 1.0);  // the PMB surface correction's; filled here to see it let go
  const RankLayout L = rank_layout(g, 2, 1);
  const size_t local = static_cast<size_t>(L.owned() + L.ghosts());
  PdSystem s = restrict_to_rank(g, L);
  // The rank's own values, as the estimate's last pass and the ghosts' exchange leave them.
  s.force.assign(3 * local, 0.25);
  for (std::vector<double>* a : {&s.energy_density, &s.dissipated, &s.damage, &s.max_stretch, &s.dilatation,
                                 &s.lps_a, &s.lps_b})
    a->assign(local, 0.5);
  release_global_at_stable_step(g);
  for (const std::vector<double>* a : {&g.u, &g.v, &g.force, &g.energy_density, &g.dissipated, &g.damage,
                                       &g.max_stretch, &g.dilatation, &g.lps_a, &g.lps_b, &g.weighted_volume})
    EXPECT_EQ(a->capacity(), 0u) << "an array the rank's system holds is still held whole";
  for (const std::vector<double>* a : {&g.calibration_factor})
    EXPECT_EQ(a->capacity(), 0u) << "a set-up value the estimate does not read is still held whole";
  EXPECT_EQ(g.fixed_dof.capacity(), 0u);
  EXPECT_EQ(g.lps.capacity(), 0u);
  for (const std::vector<double>* a : {&g.x0, &g.volume, &g.density, &g.horizon, &g.half_cell})
    EXPECT_EQ(a->capacity(), 0u) << "a reference array the estimate reads from the rank's system";
  EXPECT_EQ(g.material.capacity(), 0u);
  copy_rank_state(s, g, L);
  EXPECT_EQ(s.force, std::vector<double>(3 * local, 0.25));
  for (const std::vector<double>* a : {&s.energy_density, &s.dissipated, &s.damage, &s.max_stretch, &s.dilatation,
                                       &s.lps_a, &s.lps_b})
    EXPECT_EQ(*a, std::vector<double>(local, 0.5)) << "the rank's own field lost";
  EXPECT_TRUE(s.corr_deformation.empty()) << "a field neither system holds stays empty";
  // Held by neither: a system cut afresh has no forces to start from.
  EXPECT_THROW(restrict_to_rank(g, L), std::logic_error);
  const std::vector<const void*> held = release_global_for_loop(g, false, &s);
  const auto named = [&](const void* a) { return named_as_held(held, a); };
  for (const std::vector<double>* a : {&g.force, &g.energy_density, &g.dissipated, &g.damage, &g.max_stretch,
                                       &g.dilatation, &g.lps_a, &g.lps_b})
    EXPECT_EQ(named(a), kRootStages) << "rank 0 gathers into it (serial HDF5): this rank must take part";
  for (const std::vector<double>* a : {&g.corr_deformation, &g.corr_force_tensor, &g.corr_nonaffine})
    EXPECT_FALSE(named(a)) << "LPS has no correspondence tensors: no rank gathers them";
}

// The reference arrays (positions, volumes, densities, horizons, cells, materials: 60 B per
// particle) at the stable step's cut of a distributed set-up (restrict_to_rank_taking_bonds,
// then release_global_at_stable_step, as mpi_stable_step_forces calls them): on a rank other
// than 0 they hold no memory in the global system afterwards, the rank's system holding its
// particles' rows (the same values as a cut of the whole system, kept when its state is
// brought up to date); a staged rank 0 (root_stages_whole_body: serial HDF5) keeps them
// whole (its writers read them), with parallel HDF5 it lets go as the others; the file order
// stays on every rank.
TEST(RankSystem, ReferenceArraysHoldNoMemoryOnANonZeroRankAfterTheStableStepCut) {
  const PdSystem whole = system_from_yaml("reference_let_go", rank_block("pmb"));
  const Partition part = MortonRangePartitioner().partition(whole.offsets, 2);
  for (const int rank : {0, 1}) {
    PdSystem g = rank_rows_only(whole, part, rank);
    const RankLayout L = rank_layout(g, 2, rank);
    ASSERT_EQ(L.part.begin, part.begin);
    const PdSystem expected = restrict_to_rank(whole, rank_layout(whole, 2, rank));
    PdSystem s = restrict_to_rank_taking_bonds(g, L);
    ASSERT_EQ(s.neighbor, expected.neighbor) << "rank " << rank << ": the cut's rows";
    const bool staged = rank == 0 && root_stages_whole_body();
    if (!staged) release_global_at_stable_step(g);
    for (const auto field : {&PdSystem::x0, &PdSystem::volume, &PdSystem::density, &PdSystem::horizon,
                             &PdSystem::half_cell}) {
      EXPECT_EQ(s.*field, expected.*field) << "rank " << rank;
      if (staged) EXPECT_EQ(g.*field, whole.*field) << "a staged rank 0's writers read them whole";
      else EXPECT_EQ((g.*field).capacity(), 0u) << "a reference array still held whole on rank " << rank;
    }
    EXPECT_EQ(s.material, expected.material);
    EXPECT_EQ(g.material.capacity(), staged ? whole.material.capacity() : 0u);
    EXPECT_EQ(g.original_index, whole.original_index) << "the file order stays (rank 0's gathers, the files)";
    copy_rank_state(s, g, L);  // as the loop's backend brings the rank's system up to date
    EXPECT_EQ(s.x0, expected.x0);
    EXPECT_EQ(s.half_cell, expected.half_cell);
    EXPECT_EQ(s.material, expected.material);
  }
}

// The stable-step estimate of a distributed run (StableStepRanks) reads its particles'
// reference arrays from the rank's system, and takes the largest cell (the probe's amplitude)
// and the stiff region's scale and count over the ranks: with the global system's reference
// arrays let go it gives one process's frequency, bit for bit, on a body whose stiff third
// (a quarter of the density: four times the frequency scale) is the region it moves. One
// rank owning every particle (the chain is its own sum; more ranks: the distributed set-up
// tests, test_distributed.cpp, which compare the whole run with one process's).
TEST(RankSystem, StableStepEstimateOverTheRanksReadsNoReferenceArrayOfTheGlobalSystem) {
  PdSystem one = system_from_yaml("estimate_reference", rank_block("pmb"));
  for (size_t i = 0; i < one.n / 3; ++i) one.density[i] /= 4.0;
  PdSystem g = one;
  const StableStepStartWave wave = stable_step_start_wave(one);
  ASSERT_TRUE(wave.found);
  const double omega_one = estimate_max_frequency_lanczos(one, 60, {}, kStableStepRegionRatio, &wave);
  ASSERT_GT(one.stable_step_particles, 0u);
  ASSERT_LT(2 * one.stable_step_particles, one.n) << "the estimate must work on a region";
  const RankLayout L = rank_layout(g, 1, 0);
  PdSystem local = restrict_to_rank(g, L);
  for (std::vector<double>* a : {&g.x0, &g.volume, &g.density, &g.horizon, &g.half_cell}) std::vector<double>().swap(*a);
  std::vector<int32_t>().swap(g.material);
  g.distributed_rows = {0, static_cast<int64_t>(g.n)};  // the probe's closing pass runs on the rank's system
  const ForcePass pass = [&](PdSystem& global) {  // as mpi_stable_step_forces's rank_force_pass
    local.config.fracture = global.config.fracture;
    local.diagnostics = global.diagnostics;
    cpu_compute_forces(local);
  };
  StableStepRanks ranks;
  ranks.begin = 0;
  ranks.end = static_cast<int64_t>(g.n);
  ranks.u = local.u.data();
  ranks.force = local.force.data();
  ranks.system = &local;
  ranks.pass = pass;
  ranks.chain = [](const std::function<double(double)>& f) { return f(0.0); };
  const double omega_ranks = estimate_max_frequency_lanczos(g, 60, pass, kStableStepRegionRatio, &wave, &ranks);
  EXPECT_EQ(omega_ranks, omega_one);
  EXPECT_EQ(g.stable_step_particles, one.stable_step_particles);
  EXPECT_EQ(g.stable_step_passes, one.stable_step_passes);
}

// The same for a gas load's per-particle arrays (its front, the crack pass's positions and
// marks, the crack faces' factors, the vent areas: about 90 B per particle): let go at the
// stable step on the ranks other than 0, kept by the rank's system, the front named as held
// (rank 0 gathers it for its checkpoint). The gas state is filled by hand on a lattice (a gas
// case needs a meshed cavity); the facet lists stay empty.
TEST(RankSystem, GasArraysLetGoAtTheStableStepAreKeptByTheRankAndTheFrontStillNamedAsHeld) {
  const std::string yaml = rank_block("pmb");
  PdSystem g = system_from_yaml("gas_let_go", yaml);
  GasState& G = g.gas;
  G.active = true;
  G.crack_entry = true;
  G.crack_pass_every = 4;
  const size_t n = g.n;
  G.arrival.assign(n, 1.0);
  G.arrival_next = G.arrival;
  G.push.assign(3 * n, 2.0);
  G.kappa_volume.assign(2 * n, 3.0);
  G.vent_facet_area.assign(n, 4.0);
  G.position.assign(3 * n, 5.0);
  G.front_done.assign(n, 1);
  G.attached.assign(n, 1);
  G.in_crack.assign(g.bond_count(), 0);
  G.halves.assign(g.bond_count(), 3);
  const RankLayout L = rank_layout(g, 2, 1);
  const size_t local = static_cast<size_t>(L.owned() + L.ghosts());
  PdSystem s = restrict_to_rank(g, L);
  ASSERT_EQ(s.gas.arrival, std::vector<double>(local, 1.0));
  ASSERT_EQ(s.gas.position, std::vector<double>(3 * local, 5.0));
  s.gas.arrival.assign(local, 0.5);  // the rank's own values, to tell them from the global ones
  s.gas.push.assign(3 * local, 0.25);
  release_global_at_stable_step(g);
  for (const std::vector<double>* a : {&G.arrival, &G.arrival_next, &G.push, &G.kappa_volume, &G.vent_facet_area,
                                       &G.position})
    EXPECT_EQ(a->capacity(), 0u) << "a gas array the rank's system holds is still held whole";
  EXPECT_EQ(G.front_done.capacity(), 0u);
  EXPECT_EQ(G.attached.capacity(), 0u);
  copy_rank_state(s, g, L);
  EXPECT_EQ(s.gas.arrival, std::vector<double>(local, 0.5)) << "the rank's front lost";
  EXPECT_EQ(s.gas.arrival_next, std::vector<double>(local, 0.5));
  EXPECT_EQ(s.gas.push, std::vector<double>(3 * local, 0.25));
  EXPECT_EQ(s.gas.kappa_volume, std::vector<double>(2 * local, 3.0));
  EXPECT_EQ(s.gas.vent_facet_area, std::vector<double>(local, 4.0));
  EXPECT_EQ(s.gas.position, std::vector<double>(3 * local, 5.0));
  EXPECT_EQ(s.gas.front_done, std::vector<uint8_t>(local, 1));
  EXPECT_EQ(s.gas.attached, std::vector<uint8_t>(local, 1));
  const std::vector<const void*> held = release_global_for_loop(g, false, &s);
  const auto named = [&](const void* a) { return named_as_held(held, a); };
  EXPECT_EQ(named(&G.arrival), kRootStages) << "rank 0 gathers the front (serial HDF5): this rank must take part";
  EXPECT_EQ(named(&G.push), kRootStages) << "and, between crack passes, the pushes";
}

// The lattice stencil the figures without families use (lattice_family_stencil) is the
// family the set-up builds for a lattice point whose reach stays inside the box: same
// offsets, none missing, none extra.
TEST(Partition, LatticeStencilIsTheFamilyTheSetUpBuilds) {
  const PdSystem s = lattice("partition_stencil");  // 12^3 points at 1 mm, m = 3.015
  const double spacing = 1e-3;
  // The point at cell (5, 5, 5): centre (5.5, 5.5, 5.5) mm, 5 cells from the low faces and
  // 6 from the high ones, beyond the family's reach of m + a half diagonal < 4 cells.
  size_t centre = s.n;
  for (size_t i = 0; i < s.n; ++i)
    if (std::abs(s.x0[3 * i] - 5.5e-3) < 1e-9 && std::abs(s.x0[3 * i + 1] - 5.5e-3) < 1e-9 &&
        std::abs(s.x0[3 * i + 2] - 5.5e-3) < 1e-9)
      centre = i;
  ASSERT_LT(centre, s.n);
  std::set<std::array<int, 3>> built;
  for (int64_t k = s.offsets[centre]; k < s.offsets[centre + 1]; ++k) {
    std::array<int, 3> o{};
    for (int d = 0; d < 3; ++d)
      o[d] = static_cast<int>(std::lround((s.x0[3 * s.neighbor[k] + d] - s.x0[3 * centre + d]) / spacing));
    built.insert(o);
  }
  const auto stencil = lattice_family_stencil(3.015, PartialVolume::Sampled);
  const std::set<std::array<int, 3>> expected(stencil.begin(), stencil.end());
  EXPECT_EQ(expected.size(), stencil.size());  // no offset twice
  EXPECT_EQ(built, expected);
}

// The family sizes counted without families (family_sizes) are the set-up's row lengths,
// so the partition can be cut before any family is built: a 3D lattice under the sampled
// partial volumes (rows cut by the faces) and the pre-cracked 2D plate under LAMMPS's rule
// (pre-cracks keep their entries, broken: the rows do not change).
TEST(Partition, FamilySizesWithoutFamiliesAreTheSetUpsRowLengths) {
  const PdSystem cube = lattice("partition_sizes_cube");
  const PdSystem plate =
      system_from_yaml("partition_sizes_plate", std::string(kPrecrackedGlassPlateDeck).replace(
                                                    kPrecrackedGlassPlateDeck.find("horizon_factor: 3.015"), 21,
                                                    "horizon_factor: 3.015, partial_volume: lammps") +
                                                    "time: {steps: 1}\n");
  for (const PdSystem* s : {&cube, &plate}) {
    const std::vector<int64_t> sizes =
        family_sizes(s->x0, s->horizon, s->half_cell, s->dimension, s->config.partial_volume);
    ASSERT_EQ(sizes.size(), s->n);
    for (size_t i = 0; i < s->n; ++i) ASSERT_EQ(sizes[i], s->offsets[i + 1] - s->offsets[i]) << "particle " << i;
    std::vector<int64_t> offsets{0};
    for (const int64_t c : sizes) offsets.push_back(offsets.back() + c);
    for (int ranks : {2, 3, 5})
      EXPECT_EQ(MortonRangePartitioner().partition(offsets, ranks).begin,
                MortonRangePartitioner().partition(s->offsets, ranks).begin);
  }
}

// Graded, irregular points with per-particle horizons varying threefold (the dual horizon's
// case, where a pair is found from one end only): the counts equal build_families' pairs
// kept by the set-up's test, counted by brute force over the built families.
namespace {
// 1500 particles in a 10 mm cube, spacing graded 0.4-1.2 mm along x, horizon 3 spacings.
struct GradedCloud {
  static constexpr int n = 1500;
  std::vector<double> x = std::vector<double>(3 * n), horizon = std::vector<double>(n), half_cell = std::vector<double>(n);
  GradedCloud() {
    uint64_t state = 12345;
    auto uniform = [&] {  // a fixed LCG: the same cloud on every machine
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<double>(state >> 11) / 9007199254740992.0;
    };
    for (int i = 0; i < n; ++i) {
      for (int d = 0; d < 3; ++d) x[3 * i + d] = 0.01 * uniform();
      const double spacing = 0.4e-3 + 0.8e-3 * x[3 * i] / 0.01;  // finer towards x = 0
      half_cell[i] = 0.5 * spacing;
      horizon[i] = 3.0 * spacing;
    }
  }
  // Each row's entries with a partial volume from either end (the set-up's keep test).
  std::vector<std::vector<int32_t>> kept(const breccia::Families& fam, PartialVolume kind) const {
    std::vector<std::vector<int32_t>> rows(n);
    for (int i = 0; i < n; ++i)
      for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k) {
        const int j = fam.neighbors[k];
        const double xv[3] = {x[3 * j] - x[3 * i], x[3 * j + 1] - x[3 * i + 1], x[3 * j + 2] - x[3 * i + 2]};
        const double xm[3] = {-xv[0], -xv[1], -xv[2]};
        if (partial_volume_positive(kind, xv, horizon[i], half_cell[j], 3) ||
            partial_volume_positive(kind, xm, horizon[j], half_cell[i], 3))
          rows[i].push_back(j);
      }
    return rows;
  }
};
}  // namespace

TEST(Partition, FamilySizesOfAGradedCloudMatchBuiltFamiliesFiltered) {
  const GradedCloud cloud;
  const int n = cloud.n;
  const std::vector<double>&x = cloud.x, &horizon = cloud.horizon, &half_cell = cloud.half_cell;
  std::vector<double> pad(n);
  for (int i = 0; i < n; ++i) pad[i] = half_cell[i] * std::sqrt(3.0);
  const breccia::Families fam = breccia::build_families(x, horizon, pad);
  for (const PartialVolume kind : {PartialVolume::Sampled, PartialVolume::Lammps}) {
    const std::vector<int64_t> sizes = family_sizes(x, horizon, half_cell, 3, kind);
    const std::vector<std::vector<int32_t>> kept = cloud.kept(fam, kind);
    int64_t total = 0;
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(sizes[i], static_cast<int64_t>(kept[i].size())) << "particle " << i;
      total += sizes[i];
    }
    EXPECT_GT(total, 20 * n);  // the families are not trivially empty
  }
}

// A distributed set-up's ranks each count the family sizes of their family_slice only and
// concatenate them (plan_distributed_rows): on the graded cloud (horizons varying threefold:
// pairs found from one end only, near a slice's edge too) the concatenated slices must be
// the whole count, integer for integer, at every rank count, so the partition cut from them
// is the same. The slices must tile [0, n) in rank order, equal to within one particle.
TEST(Partition, FamilySizesCountedBySlicesAreTheWholeCount) {
  const GradedCloud cloud;
  const int64_t n = cloud.n;
  for (const PartialVolume kind : {PartialVolume::Sampled, PartialVolume::Lammps}) {
    const std::vector<int64_t> whole = family_sizes(cloud.x, cloud.horizon, cloud.half_cell, 3, kind);
    ASSERT_EQ(static_cast<int64_t>(whole.size()), n);
    std::vector<int64_t> offsets{0};
    for (const int64_t c : whole) offsets.push_back(offsets.back() + c);
    for (const int ranks : {1, 2, 3, 4, 7, 16}) {
      std::vector<int64_t> joined;
      int64_t next = 0;
      for (int r = 0; r < ranks; ++r) {
        const FamilySlice sl = family_slice(n, r, ranks);
        ASSERT_EQ(sl.begin, next) << ranks << " ranks, rank " << r;  // contiguous, in rank order
        ASSERT_LE(sl.end - sl.begin, n / ranks + 1);
        ASSERT_GE(sl.end - sl.begin, n / ranks);
        next = sl.end;
        const std::vector<int64_t> part =
            family_sizes(cloud.x, cloud.horizon, cloud.half_cell, 3, kind, sl.begin, sl.end);
        ASSERT_EQ(static_cast<int64_t>(part.size()), sl.end - sl.begin);
        joined.insert(joined.end(), part.begin(), part.end());
      }
      EXPECT_EQ(next, n);
      ASSERT_EQ(joined, whole) << ranks << " ranks";
      std::vector<int64_t> joined_offsets{0};
      for (const int64_t c : joined) joined_offsets.push_back(joined_offsets.back() + c);
      EXPECT_EQ(MortonRangePartitioner().partition(joined_offsets, ranks).begin,
                MortonRangePartitioner().partition(offsets, ranks).begin);
    }
    // A slice is the whole count's rows, not a renumbered count: a slice shifted by one
    // particle differs (the graded cloud's neighbouring rows differ in size).
    const std::vector<int64_t> shifted = family_sizes(cloud.x, cloud.horizon, cloud.half_cell, 3, kind, 501, 1001);
    EXPECT_NE(shifted, std::vector<int64_t>(whole.begin() + 500, whole.begin() + 1000));
    EXPECT_EQ(shifted, std::vector<int64_t>(whole.begin() + 501, whole.begin() + 1001));
  }
  EXPECT_TRUE(family_sizes(cloud.x, cloud.horizon, cloud.half_cell, 3, PartialVolume::Sampled, 7, 7).empty());
  EXPECT_THROW(family_sizes(cloud.x, cloud.horizon, cloud.half_cell, 3, PartialVolume::Sampled, 10, 5),
               std::invalid_argument);
  EXPECT_THROW(family_sizes(cloud.x, cloud.horizon, cloud.half_cell, 3, PartialVolume::Sampled, 0, n + 1),
               std::invalid_argument);
  EXPECT_THROW(family_slice(n, 4, 4), std::invalid_argument);
}

// The set-up's family search pads each horizon by the reach of a cell's outermost sample
// (partial_volume_reach), not its corner: the entries kept (a partial volume from either end)
// must be the corner pad's, entry for entry, on a graded cloud (horizons and cells differing
// 3x between neighbours), and the tighter pad must leave candidates out.
TEST(Partition, SamplePadKeepsTheCornerPadsEntries) {
  const GradedCloud cloud;
  std::vector<double> corner(cloud.n), sample(cloud.n);
  for (int i = 0; i < cloud.n; ++i) {
    corner[i] = cloud.half_cell[i] * std::sqrt(3.0);
    sample[i] = partial_volume_reach(cloud.half_cell[i], 3);
    ASSERT_LT(sample[i], corner[i]);
  }
  const breccia::Families by_corner = breccia::build_families(cloud.x, cloud.horizon, corner);
  const breccia::Families by_sample = breccia::build_families(cloud.x, cloud.horizon, sample);
  EXPECT_LT(by_sample.neighbors.size(), by_corner.neighbors.size());
  for (const PartialVolume kind : {PartialVolume::Sampled, PartialVolume::Lammps}) {
    const auto a = cloud.kept(by_corner, kind), b = cloud.kept(by_sample, kind);
    for (int i = 0; i < cloud.n; ++i) ASSERT_EQ(a[i], b[i]) << "particle " << i;
  }
}

// The geometric halo (geometric_window, partition.hpp; docs/parallel.md, Memory, What to
// take next, item 2 b): the particles near a rank's owned positions by the body's largest
// reach (in their box grown by it and in the cells around theirs) must hold every family
// ghost of the rank, known before any family exists. On a
// graded tet mesh with the dual horizon (horizons differing threefold between bonded
// particles: a coarse particle's partner reaches the rank with its own horizon, so the
// reach must be the whole body's largest) at 2 to 8 ranks, an empty rank, and a family over
// three ranks; the window's rows built alone (build_own_families, what a distributed set-up
// runs) are the whole build's rows, partner for partner.
#if defined(BRECCIA_MESH_EXE) && defined(BRECCIA_PLACE_EXE)
namespace {
// test_distributed.cpp's graded, notched block: 0.4 mm tets at the notch grading to 1 mm.
std::string graded_notch_particles() {
  static const std::string path = mesh_and_place(
      "halo_graded_notch",
      "dimension: 3\n"
      "body: {shape: box, name: block, size: [12 mm, 6 mm, 3 mm]}\n"
      "notches: [{name: notch, corner: [6 mm, 0, 0], edge_a: [0, 2 mm, 0], edge_b: [0, 0, 3 mm]}]\n"
      "mesh: {size: 1 mm, refine: [{near: notch, size: 0.4 mm, distance_min: 0.5 mm, distance_max: 4 mm}]}\n");
  return path;
}

// How many off-rank partners of rows [b, e) of the families (offsets, neighbor) the window
// does not hold.
int64_t ghosts_outside(const GeometricWindow& w, int64_t b, int64_t e, const std::vector<int64_t>& offsets,
                       const std::vector<int32_t>& neighbor) {
  int64_t missing = 0;
  for (int64_t i = b; i < e; ++i)
    for (int64_t k = offsets[i]; k < offsets[i + 1]; ++k) {
      const int32_t j = neighbor[k];
      if (j >= b && j < e) continue;
      if (!std::binary_search(w.index.begin(), w.index.end(), j)) ++missing;
    }
  return missing;
}

// PMB with the dual horizon on a meshed particle file (the graded tests below).
PdSystem dual_horizon_system(const std::string& name, const std::string& particles) {
  return system_from_yaml(name, "specimen: {particles: " + particles + "}\n"
                          "model: {type: pmb, horizon_factor: 3.015, variable_horizon: true}\n"
                          "materials: [{name: block, density: 2400, youngs_modulus: 30 GPa, poisson_ratio: 0.25}]\n"
                          "time: {steps: 1, check_stability: false}\n");
}

// Rank r's window w under the partition p: ascending, distinct, its rows r's range in
// order; it holds every ghost of the kept bonds (returned) and of the candidate families
// `whole`.
std::set<int32_t> expect_window_holds_rank_ghosts(const PdSystem& s, const Partition& p, int r, const GeometricWindow& w,
                                                  const breccia::Families& whole) {
  const int64_t b = p.begin[r], e = p.begin[r + 1];
  const std::string at = std::to_string(p.ranks()) + " ranks, rank " + std::to_string(r);
  EXPECT_EQ(w.row_end - w.row_begin, e - b) << at;
  EXPECT_TRUE(std::is_sorted(w.index.begin(), w.index.end())) << at;
  EXPECT_EQ(std::adjacent_find(w.index.begin(), w.index.end()), w.index.end()) << at;
  for (int64_t k = w.row_begin; k < w.row_end && k < static_cast<int64_t>(w.index.size()); ++k)
    EXPECT_EQ(w.index[k], b + (k - w.row_begin)) << at;
  const std::set<int32_t> ghosts = brute_ghosts(s, p, r);
  for (const int32_t g : ghosts) EXPECT_TRUE(std::binary_search(w.index.begin(), w.index.end(), g)) << at << ": " << g;
  EXPECT_EQ(ghosts_outside(w, b, e, whole.offsets, whole.neighbors), 0) << at;
  return ghosts;
}
}  // namespace

TEST(RankSystem, GeometricHaloHoldsEveryFamilyGhostOfAGradedDualHorizonMesh) {
  const std::string particles = graded_notch_particles();
  ASSERT_FALSE(particles.empty()) << "could not mesh the graded block";
  const PdSystem s = dual_horizon_system("halo_graded", particles);
  const int64_t n = static_cast<int64_t>(s.n);
  ASSERT_GT(n, 3000);
  const auto [hmin, hmax] = std::minmax_element(s.horizon.begin(), s.horizon.end());
  ASSERT_GT(*hmax / *hmin, 2.0) << "a graded arrangement: horizons differing at least twofold";
  // The candidate families the set-up searches (a superset of the kept bonds, s.neighbor).
  std::vector<double> pad(s.n);
  for (size_t i = 0; i < s.n; ++i) pad[i] = partial_volume_reach(s.half_cell[i], 3);
  const breccia::Families whole = breccia::build_families(s.x0, s.horizon, pad);
  int64_t local_reach_misses = 0;  // ghosts beyond the rank's own largest reach (the dual horizon's)
  for (const int ranks : {2, 3, 4, 8}) {
    const Partition p = MortonRangePartitioner().partition(s.offsets, ranks);
    for (int r = 0; r < ranks; ++r) {
      const int64_t b = p.begin[r], e = p.begin[r + 1];
      const GeometricWindow w = geometric_window(s.x0, s.horizon, s.half_cell, 3, b, e);
      // Every ghost: of the kept bonds (the rank system's, brute_ghosts) and of the candidates.
      const std::set<int32_t> ghosts = expect_window_holds_rank_ghosts(s, p, r, w, whole);
      EXPECT_FALSE(ghosts.empty()) << ranks << " ranks, rank " << r;
      // The rows built on the window alone: the whole build's rows, the others empty.
      DistributedRows rows;
      rows.active = true;
      rows.begin = b;
      rows.end = e;
      const breccia::Families own = build_own_families(s, rows, pad);
      ASSERT_EQ(own.offsets.size(), s.n + 1);
      ASSERT_EQ(own.offsets[b], 0);
      ASSERT_EQ(own.offsets[n], whole.offsets[e] - whole.offsets[b]);
      for (int64_t i = 0; i <= n; ++i)
        ASSERT_EQ(own.offsets[i], std::clamp(whole.offsets[i], whole.offsets[b], whole.offsets[e]) - whole.offsets[b]) << i;
      ASSERT_TRUE(std::equal(own.neighbors.begin(), own.neighbors.end(), whole.neighbors.begin() + whole.offsets[b]));
      // The same box grown by the rank's own largest reach instead of the body's.
      double own_h = 0.0, own_pad = 0.0, lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
      for (int64_t i = b; i < e; ++i) {
        own_h = std::max(own_h, s.horizon[i]);
        own_pad = std::max(own_pad, pad[i]);
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], s.x0[3 * i + d]), hi[d] = std::max(hi[d], s.x0[3 * i + d]);
      }
      for (const int32_t g : ghosts)
        for (int d = 0; d < 3; ++d)
          if (lo[d] - s.x0[3 * g + d] > own_h + own_pad || s.x0[3 * g + d] - hi[d] > own_h + own_pad) {
            ++local_reach_misses;
            break;
          }
    }
  }
  EXPECT_GT(local_reach_misses, 0) << "the dual horizon's ghosts reach beyond a rank's own largest reach";
  // An empty rank: no rows, an empty window; its neighbours' windows still hold their ghosts.
  Partition p;
  p.begin = {0, 0, n / 2, n};
  EXPECT_TRUE(geometric_window(s.x0, s.horizon, s.half_cell, 3, 0, 0).index.empty());
  for (const int r : {1, 2}) {
    const GeometricWindow w = geometric_window(s.x0, s.horizon, s.half_cell, 3, p.begin[r], p.begin[r + 1]);
    EXPECT_EQ(ghosts_outside(w, p.begin[r], p.begin[r + 1], whole.offsets, whole.neighbors), 0) << r;
  }
  // A family spanning three ranks or more (8 ranks): its partners on every other rank are in
  // its rank's window.
  const Partition p8 = MortonRangePartitioner().partition(s.offsets, 8);
  int64_t found = -1;
  for (int64_t i = 0; i < n && found < 0; ++i) {
    std::set<int> o;
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) o.insert(p8.owner(s.neighbor[k]));
    o.erase(p8.owner(i));
    if (o.size() >= 2) found = i;
  }
  ASSERT_GE(found, 0) << "8 ranks of the graded block must have a family over three ranks";
  const int r = p8.owner(found);
  const GeometricWindow w = geometric_window(s.x0, s.horizon, s.half_cell, 3, p8.begin[r], p8.begin[r + 1]);
  for (int64_t k = s.offsets[found]; k < s.offsets[found + 1]; ++k)
    EXPECT_TRUE(std::binary_search(w.index.begin(), w.index.end(), s.neighbor[k])) << s.neighbor[k];
  EXPECT_THROW(geometric_window(s.x0, s.horizon, s.half_cell, 3, 5, 4), std::invalid_argument);
}

// The halo follows each particle's own reach (geometric_window's reach classes): on a
// strongly graded bar (2 mm tets grading to 0.4 mm at a notch, the dual horizon: horizons
// differing over fourfold) each rank's window at 2, 3, 4 and 8 ranks holds every family
// ghost (kept bonds and candidates), yet fewer particles than the window of the body's
// largest reach (the same function given every particle the largest horizon and half cell:
// what the window was before the classes); and no particle of a window lies farther from
// every row than 2.5 times the pair's reach max(h_i, h_j) + max(pad_i, pad_j): a shell about
// as thick as the local reach (the slack: a marked cell's diagonal, sqrt(3) / 3 of the
// class's reach, and the class's bin, at most 2^(1/4) wide here; 1.8 measured).
namespace {
std::string strongly_graded_notch_particles() {
  static const std::string path = mesh_and_place(
      "halo_strongly_graded_notch",
      "dimension: 3\n"
      "body: {shape: box, name: block, size: [60 mm, 12 mm, 6 mm]}\n"
      "notches: [{name: notch, corner: [12 mm, 0, 0], edge_a: [0, 3 mm, 0], edge_b: [0, 0, 6 mm]}]\n"
      "mesh: {size: 2 mm, refine: [{near: notch, size: 0.4 mm, distance_min: 0.5 mm, distance_max: 5 mm}]}\n");
  return path;
}
}  // namespace

TEST(RankSystem, GeometricHaloFollowsEachParticlesReachOnAStronglyGradedMesh) {
  const std::string particles = strongly_graded_notch_particles();
  ASSERT_FALSE(particles.empty()) << "could not mesh the graded block";
  const PdSystem s = dual_horizon_system("halo_strongly_graded", particles);
  const int64_t n = static_cast<int64_t>(s.n);
  const auto [hmin, hmax] = std::minmax_element(s.horizon.begin(), s.horizon.end());
  ASSERT_GE(*hmax / *hmin, 4.0) << "strongly graded: horizons differing at least fourfold";
  std::vector<double> pad(s.n);
  for (size_t i = 0; i < s.n; ++i) pad[i] = partial_volume_reach(s.half_cell[i], 3);
  const std::vector<double> largest_h(s.n, *hmax),
      largest_cell(s.n, *std::max_element(s.half_cell.begin(), s.half_cell.end()));
  const breccia::Families whole = breccia::build_families(s.x0, s.horizon, pad);
  auto dist2 = [&](int64_t i, int64_t j) {
    double r2 = 0.0;
    for (int d = 0; d < 3; ++d) r2 += (s.x0[3 * j + d] - s.x0[3 * i + d]) * (s.x0[3 * j + d] - s.x0[3 * i + d]);
    return r2;
  };
  double worst = 0.0;  // the largest (distance to the nearest row in pair reaches) of a halo particle
  for (const int ranks : {2, 3, 4, 8}) {
    const Partition p = MortonRangePartitioner().partition(s.offsets, ranks);
    int64_t held = 0, body_reach_held = 0;
    for (int r = 0; r < ranks; ++r) {
      const int64_t b = p.begin[r], e = p.begin[r + 1];
      const GeometricWindow w = geometric_window(s.x0, s.horizon, s.half_cell, 3, b, e);
      expect_window_holds_rank_ghosts(s, p, r, w, whole);
      const int64_t body_wide =
          static_cast<int64_t>(geometric_window(s.x0, largest_h, largest_cell, 3, b, e).index.size());
      EXPECT_LT(static_cast<int64_t>(w.index.size()), body_wide) << ranks << " ranks, rank " << r;
      held += static_cast<int64_t>(w.index.size());
      body_reach_held += body_wide;
      for (size_t k = 0; k < w.index.size(); ++k) {
        if (static_cast<int64_t>(k) >= w.row_begin && static_cast<int64_t>(k) < w.row_end) continue;
        const int32_t j = w.index[k];
        double nearest = 1e300;
        for (int64_t i = b; i < e; ++i) {
          const double reach = std::max(s.horizon[i], s.horizon[j]) + std::max(pad[i], pad[j]);
          nearest = std::min(nearest, std::sqrt(dist2(i, j)) / reach);
        }
        worst = std::max(worst, nearest);
      }
    }
    std::printf("%d ranks: the windows hold %lld particles in all, %lld with the body's largest reach (%lld particles)\n",
                ranks, static_cast<long long>(held), static_cast<long long>(body_reach_held), static_cast<long long>(n));
  }
  std::printf("farthest halo particle: %.3f pair reaches from its nearest row\n", worst);
  EXPECT_LE(worst, 2.5);
}

// The rows mark their cells in groups (geometric_window's group_cells), each cell about a group
// decided from the group's box and only the doubtful ones row by row; the marks must be each
// row's alone. So the windows by groups equal, index for index, the windows with every row its
// own group (group_cells 0), on the strongly graded bar (reach classes over fourfold horizons)
// at 2, 3, 4 and 8 ranks, and with larger groups (8 cells) too.
TEST(RankSystem, GeometricWindowByGroupsOfRowsIsTheWindowRowByRow) {
  const std::string particles = strongly_graded_notch_particles();
  ASSERT_FALSE(particles.empty()) << "could not mesh the graded block";
  const PdSystem s = dual_horizon_system("halo_groups", particles);
  for (const int ranks : {2, 3, 4, 8}) {
    const Partition p = MortonRangePartitioner().partition(s.offsets, ranks);
    for (int r = 0; r < ranks; ++r) {
      const int64_t b = p.begin[r], e = p.begin[r + 1];
      const GeometricWindow alone = geometric_window(s.x0, s.horizon, s.half_cell, 3, b, e, 0.0);
      for (const double cells : {kWindowGroupCells, 8.0}) {
        const GeometricWindow grouped = geometric_window(s.x0, s.horizon, s.half_cell, 3, b, e, cells);
        EXPECT_EQ(grouped.index, alone.index) << ranks << " ranks, rank " << r << ", groups of " << cells << " cells";
        EXPECT_EQ(grouped.row_begin, alone.row_begin);
        EXPECT_EQ(grouped.row_end, alone.row_end);
      }
    }
  }
  EXPECT_THROW(geometric_window(s.x0, s.horizon, s.half_cell, 3, 0, 10, -1.0), std::invalid_argument);
}
#endif

// plan_distributed_rows counts each slice's family sizes on the slice's geometric window:
// on the graded cloud (horizons varying threefold, both partial-volume rules) the window's
// counts are the whole count's, integer for integer, at 1 to 16 slices.
TEST(Partition, FamilySizesCountedOnASlicesGeometricWindowAreTheWholeCount) {
  const GradedCloud cloud;
  const int64_t n = cloud.n;
  for (const PartialVolume kind : {PartialVolume::Sampled, PartialVolume::Lammps}) {
    const std::vector<int64_t> whole = family_sizes(cloud.x, cloud.horizon, cloud.half_cell, 3, kind);
    for (const int ranks : {1, 2, 3, 7, 16}) {
      for (int r = 0; r < ranks; ++r) {
        const FamilySlice sl = family_slice(n, r, ranks);
        const GeometricWindow w = geometric_window(cloud.x, cloud.horizon, cloud.half_cell, 3, sl.begin, sl.end);
        std::vector<double> x, h, c;
        for (const int32_t i : w.index) {
          x.insert(x.end(), &cloud.x[3 * i], &cloud.x[3 * i] + 3);
          h.push_back(cloud.horizon[i]);
          c.push_back(cloud.half_cell[i]);
        }
        ASSERT_EQ(family_sizes(x, h, c, 3, kind, w.row_begin, w.row_end),
                  std::vector<int64_t>(whole.begin() + sl.begin, whole.begin() + sl.end))
            << ranks << " slices, slice " << r;
      }
    }
  }
}

// The window is the rows' neighbourhood, not the body: on a 40 mm bar at 1 mm (m = 3.015,
// reach 3.015 mm + the pad, 0.77 mm) cut into 4 ranks along its length, each window holds the
// rank's rows, every particle within the reach of one of them (Euclidean), and only particles
// within the reach of the rows' box on every axis: under half the bar. On the 41^3 lattice
// of 4 Morton ranges the box alone held 80 % of the body for one rank (docs/parallel.md): an
// L-shaped range's, here a range of 7 of a 20 x 10 x 10 block.
TEST(Partition, GeometricWindowOfABarIsTheRanksNeighbourhood) {
  const PdSystem s = system_from_yaml("halo_bar", "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.04, 0.004, 0.004], spacing: 1 mm}}\n"
                                      "model: {type: pmb, horizon_factor: 3.015}\n"
                                      "materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
                                      "time: {steps: 1}\n");
  ASSERT_EQ(s.n, 640u);
  const double reach = s.horizon[0] + partial_volume_reach(s.half_cell[0], 3);
  const Partition p = MortonRangePartitioner().partition(s.offsets, 4);
  for (int r = 0; r < 4; ++r) {
    const int64_t b = p.begin[r], e = p.begin[r + 1];
    const GeometricWindow w = geometric_window(s.x0, s.horizon, s.half_cell, 3, b, e);
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (int64_t i = b; i < e; ++i)
      for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], s.x0[3 * i + d]), hi[d] = std::max(hi[d], s.x0[3 * i + d]);
    for (size_t j = 0; j < s.n; ++j) {
      const bool held = std::binary_search(w.index.begin(), w.index.end(), static_cast<int32_t>(j));
      const bool own = static_cast<int64_t>(j) >= b && static_cast<int64_t>(j) < e;
      bool in_box = true, within = false;
      for (int d = 0; d < 3; ++d) in_box = in_box && lo[d] - s.x0[3 * j + d] <= reach && s.x0[3 * j + d] - hi[d] <= reach;
      for (int64_t i = b; i < e && !within; ++i) {
        double r2 = 0.0;
        for (int d = 0; d < 3; ++d) r2 += (s.x0[3 * j + d] - s.x0[3 * i + d]) * (s.x0[3 * j + d] - s.x0[3 * i + d]);
        within = r2 <= reach * reach;
      }
      if (own || within) EXPECT_TRUE(held) << r << ": " << j;
      if (held) EXPECT_TRUE(own || in_box) << r << ": " << j;
    }
    EXPECT_LT(w.index.size(), s.n / 2) << "rank " << r;
    EXPECT_GT(w.halo(), 0u) << "rank " << r;
  }
  // Ranges whose box holds far more than their neighbourhood (a Morton range across an
  // octant's boundary is L-shaped): a 20 x 10 x 10 mm block at 1 mm cut into 3, 5, 6 and 7
  // ranks; the cells drop the box's far corners for some rank.
  const PdSystem t = system_from_yaml("halo_block", "specimen: {lattice: {dimension: 3, box: [0, 0, 0, 0.02, 0.01, 0.01], spacing: 1 mm}}\n"
                                      "model: {type: pmb, horizon_factor: 3.015}\n"
                                      "materials: [{name: m, density: 1000, youngs_modulus: 1 GPa, poisson_ratio: 0.25}]\n"
                                      "time: {steps: 1}\n");
  size_t fewer = 0, most = 0;
  for (const int ranks : {3, 5, 6, 7}) {
    const Partition q = MortonRangePartitioner().partition(t.offsets, ranks);
    for (int r = 0; r < ranks; ++r) {
      const int64_t b = q.begin[r], e = q.begin[r + 1];
      const GeometricWindow w = geometric_window(t.x0, t.horizon, t.half_cell, 3, b, e);
      double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
      for (int64_t i = b; i < e; ++i)
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], t.x0[3 * i + d]), hi[d] = std::max(hi[d], t.x0[3 * i + d]);
      size_t in_box = 0;
      for (size_t j = 0; j < t.n; ++j) {
        bool in = true;
        for (int d = 0; d < 3; ++d) in = in && lo[d] - t.x0[3 * j + d] <= reach && t.x0[3 * j + d] - hi[d] <= reach;
        in_box += in;
      }
      EXPECT_LE(w.index.size(), in_box);
      fewer += w.index.size() < in_box;
      most = std::max(most, in_box - w.index.size());
    }
  }
  std::printf("ranges whose window is smaller than their grown box: %zu, by up to %zu of %zu particles\n", fewer, most, t.n);
  EXPECT_GT(fewer, 0u) << "the cells must drop some box's corners";
}

// The owners' values to the windows that hold them (exchange_owned, distributed_setup.hpp;
// docs/parallel.md, Memory, What to take next, item 2 c): every rank's geometric window
// (partition.hpp) asks each owner for its particles once (window_exchange), and each
// exchange then fills every particle of the window outside the rank's rows with its owner's
// value, and no other. The ranks run as threads here, their all-to-all through a barrier
// (MPI's is the same contract: counts[r] elements to rank r, what arrives in rank order).
namespace {
struct ThreadRanks {
  explicit ThreadRanks(int ranks) : ranks(ranks), box(static_cast<size_t>(ranks * ranks)), sync(ranks) {}
  DistributedSetup setup(int rank) {
    DistributedSetup d;
    d.rank = rank;
    d.ranks = ranks;
    d.exchange = [this, rank](const void* data, const std::vector<int64_t>& counts, size_t bytes,
                              std::vector<int64_t>& received) {
      const char* p = static_cast<const char*>(data);
      for (int r = 0; r < ranks; ++r) {
        box[rank * ranks + r].assign(p, p + counts[r] * bytes);
        p += counts[r] * bytes;
      }
      sync.arrive_and_wait();
      std::vector<char> out;
      received.assign(ranks, 0);
      for (int from = 0; from < ranks; ++from) {
        const std::vector<char>& b = box[from * ranks + rank];
        out.insert(out.end(), b.begin(), b.end());
        received[from] = static_cast<int64_t>(b.size() / bytes);
      }
      sync.arrive_and_wait();  // every rank has read its boxes before any writes again
      return out;
    };
    d.concat = [this, rank](const void* data, size_t count, size_t bytes, bool everyone) {
      const char* p = static_cast<const char*>(data);
      box[rank * ranks].assign(p, p + count * bytes);
      sync.arrive_and_wait();
      std::vector<char> out;
      if (everyone || rank == 0)
        for (int from = 0; from < ranks; ++from) out.insert(out.end(), box[from * ranks].begin(), box[from * ranks].end());
      sync.arrive_and_wait();
      return out;
    };
    return d;
  }
  int ranks;
  std::vector<std::vector<char>> box;  // [from * ranks + to]
  std::barrier<> sync;
};
}  // namespace

TEST(RankSystem, OwnersValuesReachEveryWindowThatHoldsThemAndNoOtherParticle) {
  const PdSystem s = lattice("window_exchange");
  const int64_t n = static_cast<int64_t>(s.n);
  for (const int ranks : {2, 3, 5}) {
    const Partition p = MortonRangePartitioner().partition(s.offsets, ranks);
    ThreadRanks world(ranks);
    std::vector<int64_t> wrong(ranks, 0), filled(ranks, 0), window(ranks, 0);
    std::vector<std::string> error(ranks);
    std::vector<std::thread> threads;
    for (int r = 0; r < ranks; ++r)
      threads.emplace_back([&, r] {
        try {
          const DistributedSetup d = world.setup(r);
          DistributedRows rows;
          rows.active = true;
          rows.begin = p.begin[r];
          rows.end = p.begin[r + 1];
          rows.window = geometric_window(s.x0, s.horizon, s.half_cell, 3, rows.begin, rows.end);
          rows.exchange = window_exchange(d, p.begin, rows.window);
          require_partners_in_window(rows, s.offsets, s.neighbor);  // the whole build's partners: all held
          window[r] = static_cast<int64_t>(rows.window.index.size());
          // Each rank knows its own particles' values only (3 each); -1 elsewhere.
          std::vector<double> a(3 * s.n, -1.0);
          for (int64_t i = rows.begin; i < rows.end; ++i)
            for (int c = 0; c < 3; ++c) a[3 * i + c] = 10.0 * i + c;
          exchange_owned(d, rows, a, 3);
          for (int64_t j = 0; j < n; ++j) {
            const bool held = std::binary_search(rows.window.index.begin(), rows.window.index.end(), static_cast<int32_t>(j));
            for (int c = 0; c < 3; ++c) wrong[r] += a[3 * j + c] != (held ? 10.0 * j + c : -1.0);
            filled[r] += held && (j < rows.begin || j >= rows.end);
          }
        } catch (const std::exception& e) {
          error[r] = e.what();
        }
      });
    for (auto& t : threads) t.join();
    for (int r = 0; r < ranks; ++r) {
      EXPECT_EQ(error[r], "") << ranks << " ranks, rank " << r;
      EXPECT_EQ(wrong[r], 0) << ranks << " ranks, rank " << r;
      EXPECT_GT(filled[r], 0) << ranks << " ranks, rank " << r << ": a halo to fill";
      EXPECT_LT(window[r], n) << ranks << " ranks, rank " << r << ": the window, not the body";
    }
  }
  // count_by_owner: a halo over an empty rank, and one outside the partition refused.
  EXPECT_EQ(count_by_owner({0, 4, 4, 9}, {1, 3, 4, 8}), (std::vector<int64_t>{2, 0, 2}));
  EXPECT_THROW(count_by_owner({0, 4, 9}, {3, 9}), std::invalid_argument);
  EXPECT_THROW(count_by_owner({0, 4, 9}, {5, 3}), std::invalid_argument);
}

// A window that misses a partner of one of the rank's rows fails loudly, naming the row and
// the partner, before any pass reads that partner's value (which the exchange would never
// fill: the pass would read another value, not the owner's).
TEST(RankSystem, AWindowMissingAPartnerFailsNamingTheRowAndThePartner) {
  const PdSystem s = lattice("window_missing_partner");
  const Partition p = MortonRangePartitioner().partition(s.offsets, 3);
  const int r = 1;
  DistributedRows rows;
  rows.active = true;
  rows.begin = p.begin[r];
  rows.end = p.begin[r + 1];
  rows.window = geometric_window(s.x0, s.horizon, s.half_cell, 3, rows.begin, rows.end);
  EXPECT_NO_THROW(require_partners_in_window(rows, s.offsets, s.neighbor));
  // Drop the last ghost of the rank's last row from the window (one above the rows).
  int32_t ghost = -1;
  int64_t row = -1;
  for (int64_t i = rows.begin; i < rows.end; ++i)
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k)
      if (s.neighbor[k] >= rows.end) ghost = s.neighbor[k];
  ASSERT_GE(ghost, 0) << "a partner above the rank's rows";
  for (int64_t i = rows.begin; i < rows.end && row == -1; ++i)  // the first row that reads it
    if (std::binary_search(s.neighbor.begin() + s.offsets[i], s.neighbor.begin() + s.offsets[i + 1], ghost)) row = i;
  auto& index = rows.window.index;
  index.erase(std::find(index.begin(), index.end(), ghost));
  try {
    require_partners_in_window(rows, s.offsets, s.neighbor);
    ADD_FAILURE() << "a window without partner " << ghost << " passed";
  } catch (const std::logic_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("particle " + std::to_string(ghost)), std::string::npos) << what;
    EXPECT_NE(what.find("row " + std::to_string(row) + ","), std::string::npos) << what;
  }
  // Inactive rows (one process): nothing to check.
  EXPECT_NO_THROW(require_partners_in_window(DistributedRows{}, s.offsets, s.neighbor));
}

// The distributed Morton order (distributed_setup.hpp distributed_morton_sort; docs/parallel.md,
// Memory, item 2): every rank's block of file rows, keyed in the whole body's box
// (body_bounding_box), sorted across 1 to 4 ranks (threads here), is morton_order's stable
// order exactly: the blocks concatenated in rank order name the same file rows, ties by file
// row. Random positions, then many tied keys (coincident points and points closer than a
// key's resolution), with equal blocks and with uneven ones (an empty rank among them).
namespace {
template <class F>
void on_thread_ranks(int ranks, F f) {
  ThreadRanks world(ranks);
  std::vector<std::string> error(static_cast<size_t>(ranks));
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r)
    threads.emplace_back([&, r] {
      try {
        f(world.setup(r));
      } catch (const std::exception& e) {
        error[static_cast<size_t>(r)] = e.what();
      }
    });
  for (auto& t : threads) t.join();
  for (int r = 0; r < ranks; ++r) EXPECT_EQ(error[static_cast<size_t>(r)], "") << ranks << " ranks, rank " << r;
}
}  // namespace

TEST(DistributedSort, MortonSortOverTheRanksIsMortonOrderWithItsTies) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 1.7);
  std::vector<std::vector<double>> clouds;
  {
    std::vector<double> x(3 * 2000);
    for (double& v : x) v = u(rng);
    clouds.push_back(std::move(x));
  }
  {
    // Ties: 1500 points on 40 sites (coincident), and 500 within 1e-9 of the extent of one
    // site (below 1 / 2^21 of it: the same key, distinct positions).
    std::vector<double> site(3 * 40);
    for (double& v : site) v = u(rng);
    std::vector<double> x;
    for (int i = 0; i < 1500; ++i) {
      const size_t k = static_cast<size_t>(rng() % 40);
      x.insert(x.end(), &site[3 * k], &site[3 * k] + 3);
    }
    for (int i = 0; i < 500; ++i)
      for (int d = 0; d < 3; ++d) x.push_back(site[static_cast<size_t>(d)] + 1e-9 * static_cast<double>(i % 7));
    clouds.push_back(std::move(x));
  }
  for (size_t cl = 0; cl < clouds.size(); ++cl) {
    const std::vector<double>& x = clouds[cl];
    const int64_t n = static_cast<int64_t>(x.size() / 3);
    const std::vector<int32_t> expected = morton_order(x);
    for (const int ranks : {1, 2, 3, 4})
      for (const bool uneven : {false, true}) {
        // Each rank's first file row: file_block's, or uneven (rank 1 empty above one rank).
        std::vector<int64_t> begin;
        for (int r = 0; r <= ranks; ++r) begin.push_back(r == ranks ? n : file_block(n, r, ranks).begin);
        if (uneven && ranks > 1) {
          begin[1] = n / 5;
          if (ranks > 2) begin[2] = begin[1];
        }
        std::vector<std::vector<int32_t>> got(static_cast<size_t>(ranks));
        std::vector<int64_t> first(static_cast<size_t>(ranks)), whole(static_cast<size_t>(ranks));
        on_thread_ranks(ranks, [&](const DistributedSetup& d) {
          const int64_t b = begin[static_cast<size_t>(d.rank)], e = begin[static_cast<size_t>(d.rank) + 1];
          const breccia::BoundingBox box = body_bounding_box(d, std::span<const double>(x.data() + 3 * b, 3 * static_cast<size_t>(e - b)));
          const double extent = morton_extent(box);
          std::vector<MortonItem> items;
          for (int64_t f = b; f < e; ++f) {
            MortonItem it;
            it.file = f;
            std::copy_n(&x[3 * static_cast<size_t>(f)], 3, it.x);
            it.spacing = static_cast<double>(f);
            it.key = morton_key(it.x, box, extent);
            items.push_back(it);
          }
          const MortonBlock sorted = distributed_morton_sort(d, std::move(items));
          for (const MortonItem& it : sorted.items) {
            got[static_cast<size_t>(d.rank)].push_back(static_cast<int32_t>(it.file));
            if (it.spacing != static_cast<double>(it.file) || !std::equal(it.x, it.x + 3, &x[3 * static_cast<size_t>(it.file)]))
              throw std::runtime_error("an item's position or value did not travel with its row");
          }
          first[static_cast<size_t>(d.rank)] = sorted.first;
          whole[static_cast<size_t>(d.rank)] = sorted.n;
        });
        std::vector<int32_t> order;
        for (int r = 0; r < ranks; ++r) {
          EXPECT_EQ(first[static_cast<size_t>(r)], static_cast<int64_t>(order.size())) << cl << ", " << ranks << " ranks";
          EXPECT_EQ(whole[static_cast<size_t>(r)], n);
          order.insert(order.end(), got[static_cast<size_t>(r)].begin(), got[static_cast<size_t>(r)].end());
        }
        EXPECT_EQ(order, expected) << "cloud " << cl << ", " << ranks << " ranks, uneven " << uneven;
      }
  }
  // The tied cloud has ties to break (else the test would not test them).
  const std::vector<double>& tied = clouds[1];
  const breccia::BoundingBox box = breccia::bounding_box(tied);
  std::vector<uint64_t> key;
  for (size_t i = 0; i < tied.size() / 3; ++i) key.push_back(morton_key(&tied[3 * i], box, morton_extent(box)));
  std::sort(key.begin(), key.end());
  EXPECT_LT(std::unique(key.begin(), key.end()) - key.begin(), 100);
}

// distributed_order_statistic: the k-th smallest of the ranks' values together is the value
// std::nth_element places at k in one array (the set-up's median: k = n / 2), duplicates,
// negative values and zero among them, at 1 to 4 ranks with uneven shares.
TEST(DistributedSort, OrderStatisticOverTheRanksIsNthElementsValue) {
  std::mt19937_64 rng(11);
  std::vector<double> v;
  for (int i = 0; i < 777; ++i) v.push_back(i % 5 == 0 ? 0.25 * static_cast<double>(rng() % 4) : std::ldexp(static_cast<double>(rng() % 1000) - 300.0, -7));
  v.push_back(0.0);
  const int64_t n = static_cast<int64_t>(v.size());
  for (const int ranks : {1, 2, 3, 4})
    for (const int64_t k : {int64_t{0}, n / 3, n / 2, n - 1}) {
      std::vector<double> sorted = v;
      std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
      const double expected = sorted[static_cast<size_t>(k)];
      std::vector<double> got(static_cast<size_t>(ranks));
      on_thread_ranks(ranks, [&](const DistributedSetup& d) {
        const int64_t b = n * d.rank * d.rank / (ranks * ranks), e = n * (d.rank + 1) * (d.rank + 1) / (ranks * ranks);
        got[static_cast<size_t>(d.rank)] = distributed_order_statistic(d, std::vector<double>(v.begin() + b, v.begin() + e), k);
      });
      for (int r = 0; r < ranks; ++r) EXPECT_EQ(got[static_cast<size_t>(r)], expected) << ranks << " ranks, k " << k;
    }
}

// Each rank's geometric window formed from the ranks' runs of the order (form_window,
// distributed_setup.hpp: the ranks' grid boxes to every rank, the particles inside them to
// that rank, filtered by geometric_window's own test) is geometric_window's over the whole
// body, particle for particle, with each particle's values: on the graded cloud (horizons
// varying threefold, so several reach classes) at 1 to 4 ranks, equal runs and uneven ones
// (an empty rank among them).
TEST(DistributedSort, WindowsFormedFromTheRanksRunsAreTheWholeBodysGeometricWindows) {
  const GradedCloud graded;
  const int64_t n = graded.n;
  struct {
    std::vector<double> x, horizon, half_cell;
  } cloud;  // in Morton order, as the set-up holds it
  for (const int32_t f : morton_order(graded.x)) {
    cloud.x.insert(cloud.x.end(), &graded.x[3 * static_cast<size_t>(f)], &graded.x[3 * static_cast<size_t>(f)] + 3);
    cloud.horizon.push_back(graded.horizon[static_cast<size_t>(f)]);
    cloud.half_cell.push_back(graded.half_cell[static_cast<size_t>(f)]);
  }
  for (const int ranks : {1, 2, 3, 4})
    for (const bool uneven : {false, true}) {
      std::vector<int64_t> begin;
      for (int r = 0; r <= ranks; ++r) begin.push_back(r == ranks ? n : family_slice(n, r, ranks).begin);
      if (uneven && ranks > 2) begin[2] = begin[1];
      if (uneven && ranks == 2) begin[1] = n / 7;
      std::vector<GeometricWindow> got(static_cast<size_t>(ranks));
      std::vector<int64_t> wrong(static_cast<size_t>(ranks), 0);
      on_thread_ranks(ranks, [&](const DistributedSetup& d) {
        RankRun run;
        run.first = begin[static_cast<size_t>(d.rank)];
        for (int64_t i = run.first; i < begin[static_cast<size_t>(d.rank) + 1]; ++i) {
          PlanParticle q;
          q.file = 1000000 + i;
          std::copy_n(&cloud.x[3 * static_cast<size_t>(i)], 3, q.x);
          q.horizon = cloud.horizon[static_cast<size_t>(i)];
          q.half_cell = cloud.half_cell[static_cast<size_t>(i)];
          run.p.push_back(q);
        }
        const ReachFigures body = body_reach_figures(d, run, 3);
        const FormedWindow f = form_window(d, run, 3, body, n);
        for (size_t k = 0; k < f.p.size(); ++k) {
          const size_t i = static_cast<size_t>(f.window.index[k]);
          wrong[static_cast<size_t>(d.rank)] += f.p[k].file != 1000000 + static_cast<int64_t>(i) ||
                                                f.p[k].horizon != cloud.horizon[i] || f.p[k].x[1] != cloud.x[3 * i + 1];
        }
        got[static_cast<size_t>(d.rank)] = f.window;
      });
      for (int r = 0; r < ranks; ++r) {
        const GeometricWindow w = geometric_window(cloud.x, cloud.horizon, cloud.half_cell, 3, begin[static_cast<size_t>(r)],
                                                   begin[static_cast<size_t>(r) + 1]);
        const GeometricWindow& g = got[static_cast<size_t>(r)];
        EXPECT_EQ(g.index, w.index) << ranks << " ranks, rank " << r << ", uneven " << uneven;
        EXPECT_EQ(g.row_begin, w.row_begin) << ranks << " ranks, rank " << r;
        EXPECT_EQ(g.row_end, w.row_end) << ranks << " ranks, rank " << r;
        EXPECT_EQ(wrong[static_cast<size_t>(r)], 0) << ranks << " ranks, rank " << r;
        if (ranks == 4 && !uneven) EXPECT_LT(w.index.size(), static_cast<size_t>(n)) << "a window, not the body";
      }
    }
}
