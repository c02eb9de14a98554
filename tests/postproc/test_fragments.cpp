// Fragments over the intact bond graph, their measures and the split deformed mesh.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <omp.h>

#include "breccia/postproc/bond_graph.hpp"
#include "breccia/postproc/fragments.hpp"
#include "breccia/postproc/meshes.hpp"
#include "synthetic_run.hpp"

using namespace breccia;
using namespace breccia::postproc;
namespace bt = breccia::postproc::testing;

namespace {

constexpr double kH = 1e-3;
constexpr double kDensity = 2500.0;

FragmentResult fragments_of(const ParticleModel& m, double horizon, const std::vector<int64_t>& broken,
                            int64_t min_particles = 1, const std::vector<double>& displacement = {}) {
  const auto fam = build_families(m.position_m, std::vector<double>(m.size(), horizon));
  int32_t count = 0;
  const auto comp = intact_components(fam, RemovedBonds(broken, m.size()), RemovedBonds({}, m.size()), &count);
  const std::vector<double> density(m.size(), kDensity);
  FragmentInputs in{m.dimension, m.thickness_m, m.position_m, displacement, {}, m.volume_m3, density};
  return measure_fragments(in, comp, count, min_particles);
}

}  // namespace

TEST(Fragments, PlanarCutSplitsBlockIntoTwoHalvesOfExactVolume) {
  // 4 x 4 x 4 mm block cut on z = 1 mm: fragments of 4 x 4 x 3 and 4 x 4 x 1 mm^3.
  const auto m = bt::structured_mesh(3, {4, 4, 4}, kH);
  const double horizon = 1.6 * kH;
  const auto cut = bt::bonds_where(m, horizon, [](const double* a, const double* b) {
    return (a[2] - kH) * (b[2] - kH) < 0;
  });
  const FragmentResult r = fragments_of(m, horizon, cut);
  ASSERT_EQ(r.fragments.size(), 2u);
  // Volumes are sums of h^3/6: equal to the boxes up to rounding.
  EXPECT_NEAR(r.fragments[0].volume_m3, 48e-9, 1e-20);
  EXPECT_NEAR(r.fragments[1].volume_m3, 16e-9, 1e-20);
  EXPECT_NEAR(r.fragments[0].mass_kg, 48e-9 * kDensity, 1e-16);
  EXPECT_NEAR(r.fragments[0].centroid_reference_m[2], 2.5 * kH, 1e-12);  // uniform density: box centre
  EXPECT_NEAR(r.fragments[1].centroid_reference_m[2], 0.5 * kH, 1e-12);
  // The slab's box is 4 x 4 x 1 mm; particle centres span (edge - h/2), plus the mean
  // spacing (h / 6^(1/3) = 0.55 h): each edge within 0.1 h of the true one.
  EXPECT_NEAR(r.fragments[1].box_m[0], 4 * kH, 0.1 * kH);
  EXPECT_NEAR(r.fragments[1].box_m[2], 1 * kH, 0.1 * kH);
  EXPECT_NEAR(r.fragments[1].sieve_size_m, 4 * kH, 0.1 * kH);
}

TEST(Fragments, SeparatedCubesGiveOneFragmentEachWithExactVolume) {
  // Cubes of 1, 2, 3 and 4 cells, 3 h apart (beyond the horizon): no bond between them.
  std::vector<ParticleModel> parts;
  double x0 = 0;
  for (int n = 1; n <= 4; ++n) {
    parts.push_back(bt::structured_mesh(3, {n, n, n}, kH, {x0, 0, 0}));
    x0 += (n + 3) * kH;
  }
  const auto m = bt::merge(parts);
  const FragmentResult r = fragments_of(m, 1.6 * kH, {});
  ASSERT_EQ(r.fragments.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    const int n = 4 - k;  // sorted by decreasing mass
    const double volume = std::pow(n * kH, 3);
    EXPECT_NEAR(r.fragments[k].volume_m3, volume, 1e-12 * volume);
    EXPECT_EQ(r.fragments[k].particle_count, 6 * n * n * n);
    EXPECT_NEAR(r.fragments[k].equivalent_diameter_m, std::cbrt(6 * volume / std::numbers::pi), 1e-12);
    // Cube: the coordinate box wins over the (arbitrary) principal axes; see the slab test
    // for why 0.1 h.
    EXPECT_NEAR(r.fragments[k].sieve_size_m, n * kH, 0.1 * kH);
  }
}

TEST(Fragments, TheCurrentCentroidIsTheCentreOfMassOfATwoDensityBlockTurnedHalfATurn) {
  // A 12 x 8 x 4 mm block, density 1000 for x < 6 mm and 3000 above, turned half a turn about
  // the z axis through its centre (u = -2 (X - c) in x and y). Centre of mass in the reference:
  // x = (1000 x 3 + 3000 x 9) / 4000 = 7.5 mm; turned: 12 - 7.5 = 4.5 mm. Its velocity is
  // mass-weighted, so the centroid that moves with it is this one; the reference centroid
  // stays the shape's centre, 6 mm.
  const auto m = bt::structured_mesh(3, {12, 8, 4}, kH);
  const double horizon = 1.6 * kH;
  const auto fam = build_families(m.position_m, std::vector<double>(m.size(), horizon));
  int32_t count = 0;
  const auto comp = intact_components(fam, RemovedBonds({}, m.size()), RemovedBonds({}, m.size()), &count);
  std::vector<double> density(m.size()), u(3 * m.size(), 0.0);
  const double c[2] = {6 * kH, 4 * kH};
  for (size_t i = 0; i < m.size(); ++i) {
    density[i] = m.position_m[3 * i] < 6 * kH ? 1000.0 : 3000.0;
    for (int d = 0; d < 2; ++d) u[3 * i + d] = -2.0 * (m.position_m[3 * i + d] - c[d]);
  }
  FragmentInputs in{m.dimension, m.thickness_m, m.position_m, u, {}, m.volume_m3, density};
  const FragmentResult r = measure_fragments(in, comp, count, 1);
  ASSERT_EQ(r.fragments.size(), 1u);
  EXPECT_NEAR(r.fragments[0].centroid_reference_m[0], 6 * kH, 1e-12);
  EXPECT_NEAR(r.fragments[0].centroid_m[0], 4.5 * kH, 1e-12);  // rounding only
  EXPECT_NEAR(r.fragments[0].centroid_m[1], 4 * kH, 1e-12);
}

TEST(Fragments, MinimumSizeFilterDropsSmallFragmentsAndCountsTheirMass) {
  std::vector<ParticleModel> parts{bt::structured_mesh(3, {1, 1, 1}, kH), bt::structured_mesh(3, {3, 3, 3}, kH, {5 * kH, 0, 0})};
  const auto m = bt::merge(parts);
  const FragmentResult r = fragments_of(m, 1.6 * kH, {}, 7);  // the 1-cell cube has 6 particles
  ASSERT_EQ(r.fragments.size(), 1u);
  EXPECT_EQ(r.filtered_count, 1);
  EXPECT_NEAR(r.filtered_mass_kg, 1e-9 * kDensity, 1e-18);
  EXPECT_EQ(r.fragment_id[0], -1);
  EXPECT_EQ(r.fragment_id[m.size() - 1], 0);
}

TEST(Fragments, InclinedRodPrincipalBoxFindsTheSieveSizeOfTheCrossSection) {
  // A 20 x 3 x 2 lattice rod rotated by 30 degrees about z: the coordinate box is wide, the
  // principal box is 20 x 3 x 2 spacings, so the sieve size is 3 spacings (exact for a
  // lattice: centre spread (n-1) s plus one spacing).
  auto m = bt::lattice(3, {20, 3, 2}, kH);
  const double c = std::cos(std::numbers::pi / 6), s = std::sin(std::numbers::pi / 6);
  for (size_t i = 0; i < m.size(); ++i) {
    const double x = m.position_m[3 * i], y = m.position_m[3 * i + 1];
    m.position_m[3 * i] = c * x - s * y;
    m.position_m[3 * i + 1] = s * x + c * y;
  }
  const FragmentResult r = fragments_of(m, 1.6 * kH, {});
  ASSERT_EQ(r.fragments.size(), 1u);
  EXPECT_NEAR(r.fragments[0].box_m[0], 20 * kH, 1e-9);
  EXPECT_NEAR(r.fragments[0].sieve_size_m, 3 * kH, 1e-9);
  EXPECT_NEAR(r.fragments[0].box_m[2], 2 * kH, 1e-9);
}

namespace {

// Rotate every position by the rotation of `angle` about the unit `axis` (Rodrigues).
void rotate(ParticleModel& m, std::array<double, 3> axis, double angle) {
  const double len = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  for (double& a : axis) a /= len;
  const double c = std::cos(angle), s = std::sin(angle);
  for (size_t i = 0; i < m.size(); ++i) {
    double* x = &m.position_m[3 * i];
    const double d = axis[0] * x[0] + axis[1] * x[1] + axis[2] * x[2];
    const double cr[3] = {axis[1] * x[2] - axis[2] * x[1], axis[2] * x[0] - axis[0] * x[2], axis[0] * x[1] - axis[1] * x[0]};
    for (int k = 0; k < 3; ++k) x[k] = x[k] * c + cr[k] * s + axis[k] * d * (1 - c);
  }
}

}  // namespace

// Shapes whose principal axes are not unique: a cube (three equal moments) and square
// plates (two; one of a single layer, whose points are coplanar: its rectangle is found in
// its plane), turned about an oblique axis; and a box with distinct edges as a control. The principal frame is then whatever the eigen
// solver returns and the coordinate frame is oblique; CGAL's minimal box finds the edges.
// The known answer is the lattice's box, n spacings per edge (centre spread (n-1) h plus
// one spacing). Tolerance 0.02 h: the minimal-volume search is a heuristic (convex hull,
// then an evolutionary search over rotations), not exact by construction; on these hulls it
// lands within 1e-14 h (printed). The former two-frame rule (principal or coordinate axes)
// gave, on the same turned shapes, middle edges 2 to 3 spacings too wide for the cube and
// the plates (the 12 x 5 x 2 box, distinct moments, it got right).
TEST(Fragments, TurnedCubeAndSquarePlateGetTheirOwnBoxFromTheOrientedBoundingBox) {
  struct Shape {
    std::array<int, 3> cells;
    std::array<double, 3> box;  // in spacings, largest first
  };
  for (const Shape& shape : {Shape{{6, 6, 6}, {6, 6, 6}}, Shape{{10, 10, 2}, {10, 10, 2}}, Shape{{9, 9, 1}, {9, 9, 1}},
                            Shape{{12, 5, 2}, {12, 5, 2}}}) {
    auto m = bt::lattice(3, shape.cells, kH);
    rotate(m, {1.0, 2.0, 3.0}, 0.7);
    const FragmentResult r = fragments_of(m, 1.6 * kH, {});
    ASSERT_EQ(r.fragments.size(), 1u);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(r.fragments[0].box_m[k], shape.box[k] * kH, 0.02 * kH) << shape.cells[0] << "x" << shape.cells[1]
                                                                          << "x" << shape.cells[2] << " edge " << k;
    EXPECT_NEAR(r.fragments[0].sieve_size_m, shape.box[1] * kH, 0.02 * kH);
    double worst = 0;
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::fabs(r.fragments[0].box_m[k] - shape.box[k] * kH));
    std::printf("turned %dx%dx%d: largest box edge error %.2e spacings\n", shape.cells[0], shape.cells[1], shape.cells[2],
                worst / kH);
  }
}

// The oriented boxes are searched in parallel, one fragment per OpenMP iteration; each search
// seeds its own random generator, so the boxes must not depend on the thread count. Twelve
// turned cubes and square plates (each with undetermined principal axes, so each goes to the
// search), far apart: the boxes with 1 and 4 threads equal bit for bit, and each is its
// lattice box within the 0.02 spacings of the test above.
TEST(Fragments, OrientedBoxesAreTheSameWithOneOrSeveralThreads) {
  std::vector<ParticleModel> parts;
  for (int p = 0; p < 12; ++p) {
    auto part = bt::lattice(3, p % 2 ? std::array<int, 3>{6, 6, 6} : std::array<int, 3>{8, 8, 2}, kH);
    rotate(part, {1.0 + p, 2.0, 3.0 - 0.2 * p}, 0.3 + 0.1 * p);
    for (size_t i = 0; i < part.size(); ++i) part.position_m[3 * i] += 30 * kH * p;  // beyond every horizon
    parts.push_back(part);
  }
  const auto m = bt::merge(parts);
  omp_set_num_threads(1);
  const FragmentResult one = fragments_of(m, 1.6 * kH, {});
  omp_set_num_threads(4);
  const FragmentResult four = fragments_of(m, 1.6 * kH, {});
  omp_set_num_threads(1);
  ASSERT_EQ(one.fragments.size(), 12u);
  ASSERT_EQ(four.fragments.size(), 12u);
  for (size_t f = 0; f < 12; ++f) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(one.fragments[f].box_m[k], four.fragments[f].box_m[k]) << "fragment " << f;
    const double middle = one.fragments[f].particle_count == 216 ? 6 : 8;  // cube 6, plate 8 spacings
    EXPECT_NEAR(one.fragments[f].sieve_size_m, middle * kH, 0.02 * kH) << "fragment " << f;
  }
}

TEST(Fragments, TurnedSquareIn2DGetsItsOwnRectangle) {
  // 2D: the minimal-area rectangle of the hull (exact), here of an 8 x 8 lattice square
  // turned by 0.3 rad in the plane: 8 x 8 spacings (round-off of the rotation only).
  auto m = bt::lattice(2, {8, 8, 1}, kH);
  rotate(m, {0.0, 0.0, 1.0}, 0.3);
  const FragmentResult r = fragments_of(m, 1.6 * kH, {});
  ASSERT_EQ(r.fragments.size(), 1u);
  EXPECT_NEAR(r.fragments[0].box_m[0], 8 * kH, 1e-9);
  EXPECT_NEAR(r.fragments[0].box_m[1], 8 * kH, 1e-9);
  EXPECT_NEAR(r.fragments[0].sieve_size_m, 8 * kH, 1e-9);
}

TEST(DeformedMesh, AffineDisplacementIsReproducedAtEveryNode) {
  // Least squares with an affine basis is exact for affine fields, interior or boundary.
  const auto m = bt::structured_mesh(3, {3, 3, 3}, kH);
  auto u_of = [](const double* x) {
    return std::array<double, 3>{0.01 * x[0] + 0.002 * x[1] + 1e-5, -0.02 * x[1], 0.005 * x[2] + 0.003 * x[0]};
  };
  std::vector<double> u;
  for (size_t i = 0; i < m.size(); ++i) {
    const auto v = u_of(&m.position_m[3 * i]);
    u.insert(u.end(), v.begin(), v.end());
  }
  const std::vector<int32_t> one(m.size(), 0);
  const Mesh d = deformed_mesh(m, u, one);
  ASSERT_EQ(d.points_m.size(), m.mesh_nodes_m.size());  // one piece: no node duplicated
  for (size_t v = 0; v < d.points_m.size() / 3; ++v) {
    const auto uv = u_of(&m.mesh_nodes_m[3 * v]);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(d.points_m[3 * v + k], m.mesh_nodes_m[3 * v + k] + uv[k], 1e-15);
  }
}

TEST(DeformedMesh, LatticeBlocksMoveWithTheirParticlesAndCarryItsDisplacement) {
  // One block per particle (no mesh): each of its 8 corners is the particle's centre +- h/2
  // per axis, moved by the particle's displacement, which is also the corner's point data.
  const auto m = bt::lattice(3, {3, 2, 2}, kH);
  std::vector<double> u;
  for (size_t i = 0; i < m.size(); ++i) u.insert(u.end(), {1e-5 * i, -2e-6, 3e-6 * (i % 2)});
  const Mesh d = deformed_mesh(m, u, std::vector<int32_t>(m.size(), 0));
  ASSERT_EQ(d.nodes_per_cell, 8);
  ASSERT_EQ(d.points_m.size(), 3 * 8 * m.size());
  ASSERT_EQ(d.point_data.size(), 1u);
  EXPECT_EQ(d.point_data[0].name, "displacement");
  for (size_t i = 0; i < m.size(); ++i)
    for (int c = 0; c < 8; ++c)
      for (int k = 0; k < 3; ++k) {
        const size_t p = 3 * (8 * i + c) + k;
        EXPECT_EQ(d.point_data[0].values[p], u[3 * i + k]);
        EXPECT_NEAR(std::fabs(d.points_m[p] - u[3 * i + k] - m.position_m[3 * i + k]), 0.5 * kH, 1e-15);
      }
}

TEST(DeformedMesh, AffineDisplacementIsReproducedOnTriangleMeshes) {
  const auto m = bt::structured_mesh(2, {4, 3, 0}, kH);
  auto u_of = [](const double* x) { return std::array<double, 3>{0.01 * x[0] - 0.004 * x[1] + 2e-6, 0.02 * x[1], 0.0}; };
  std::vector<double> u;
  for (size_t i = 0; i < m.size(); ++i) {
    const auto v = u_of(&m.position_m[3 * i]);
    u.insert(u.end(), v.begin(), v.end());
  }
  const Mesh d = deformed_mesh(m, u, std::vector<int32_t>(m.size(), 0));
  ASSERT_EQ(d.points_m.size(), m.mesh_nodes_m.size());
  for (size_t v = 0; v < d.points_m.size() / 3; ++v) {
    const auto uv = u_of(&m.mesh_nodes_m[3 * v]);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(d.points_m[3 * v + k], m.mesh_nodes_m[3 * v + k] + uv[k], 1e-15);
  }
}

TEST(DeformedMesh, NodesOnTheCrackAreDuplicatedPerFragmentAndMoveWithIt) {
  const auto m = bt::structured_mesh(3, {4, 4, 4}, kH);
  std::vector<int32_t> comp(m.size());
  std::vector<double> u(3 * m.size(), 0.0);
  for (size_t i = 0; i < m.size(); ++i) {
    comp[i] = m.position_m[3 * i + 2] > 2 * kH ? 1 : 0;
    u[3 * i + 2] = comp[i] ? 1e-4 : 0.0;  // upper half lifted rigidly by 0.1 mm
  }
  const Mesh d = deformed_mesh(m, u, comp);
  EXPECT_EQ(d.points_m.size() / 3, m.mesh_nodes_m.size() / 3 + 25);  // the 5 x 5 nodes on z = 2 mm
  for (size_t c = 0; c < m.size(); ++c)
    for (int k = 0; k < 4; ++k) {
      const int64_t p = d.cells[4 * c + k], v = m.mesh_cells[4 * c + k];
      EXPECT_NEAR(d.points_m[3 * p + 2] - m.mesh_nodes_m[3 * v + 2], comp[c] ? 1e-4 : 0.0, 1e-15);
    }
}

// results.h5 stores the bonds once (half list) and one bit per bond and output; the
// components over it must be the pair-list components exactly (same labels, same count).
TEST(Fragments, BrokenBitsOverTheHalfBondListGiveThePairListComponents) {
  const auto m = bt::structured_mesh(3, {5, 4, 4}, kH);
  const double horizon = 1.6 * kH;
  const auto fam = build_families(m.position_m, std::vector<double>(m.size(), horizon));
  Families half;
  half.offsets.assign(m.size() + 1, 0);
  for (size_t i = 0; i < m.size(); ++i) {
    for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k)
      if (fam.neighbors[k] > static_cast<int32_t>(i)) half.neighbors.push_back(fam.neighbors[k]);
    half.offsets[i + 1] = static_cast<int64_t>(half.neighbors.size());
  }
  // A full cut on x = 2 mm, 60 % of the bonds on z = 2 mm (not separating), a pre-crack
  // on y = 2 mm below z = 1 mm, and a pseudo-random 30 % elsewhere.
  std::vector<int64_t> broken_pairs, precrack_pairs;
  std::vector<uint8_t> bits((half.bond_count() + 7) / 8, 0);
  uint32_t rng = 12345;
  for (size_t i = 0; i < m.size(); ++i)
    for (int64_t b = half.offsets[i]; b < half.offsets[i + 1]; ++b) {
      const int32_t j = half.neighbors[b];
      const double* a = &m.position_m[3 * i];
      const double* c = &m.position_m[3 * j];
      rng = rng * 1664525u + 1013904223u;
      const double u = (rng >> 8) / 16777216.0;
      if ((a[1] - 2 * kH) * (c[1] - 2 * kH) < 0 && a[2] < kH && c[2] < kH) {
        precrack_pairs.insert(precrack_pairs.end(), {static_cast<int64_t>(i), j});
        continue;
      }
      const bool cut = (a[0] - 2 * kH) * (c[0] - 2 * kH) < 0 || ((a[2] - 2 * kH) * (c[2] - 2 * kH) < 0 && u < 0.6) ||
                       u < 0.3;
      if (!cut) continue;
      broken_pairs.insert(broken_pairs.end(), {static_cast<int64_t>(i), j});
      bits[b / 8] |= static_cast<uint8_t>(1u << (b % 8));
    }
  const RemovedBonds broken(broken_pairs, m.size()), precracks(precrack_pairs, m.size());
  int32_t count_pairs = 0, count_bits = 0;
  const auto by_pairs = intact_components(fam, broken, precracks, &count_pairs);
  const auto by_bits = intact_components(half, {}, bits, precracks, &count_bits);
  EXPECT_GE(count_pairs, 2);  // the x cut separates at least two pieces
  EXPECT_EQ(count_bits, count_pairs);
  EXPECT_EQ(by_bits, by_pairs);
  // Bond lookups agree for every family pair, and pairs that are not bonds are not broken.
  const BondBits lookup(half, bits);
  for (size_t i = 0; i < m.size(); ++i)
    for (int64_t k = fam.offsets[i]; k < fam.offsets[i + 1]; ++k)
      ASSERT_EQ(lookup.contains(static_cast<int64_t>(i), fam.neighbors[k]),
                broken.contains(static_cast<int64_t>(i), fam.neighbors[k]));
  EXPECT_EQ(bond_index(half, 0, static_cast<int64_t>(m.size()) - 1), -1);  // opposite corners: no bond
  EXPECT_EQ(postproc::count_bits(bits), broken_pairs.size() / 2);
  // A bond outside the fragment graph (within_horizon bit clear) connects nothing.
  const std::vector<uint8_t> none(bits.size(), 0);
  int32_t isolated = 0;
  intact_components(half, none, none, RemovedBonds{}, &isolated);
  EXPECT_EQ(static_cast<size_t>(isolated), m.size());
}
