// Verification of the MPS operators (Koshizuka & Oka 1996; [MPS harmonics] eqs 1-3, docs/references.md)
// on regular lattices. References are the exact derivatives of polynomial fields.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "breccia/mps/kernels.hpp"
#include "breccia/mps/neighbours.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;
using breccia::mps::test::lattice;

namespace {

constexpr double kRe = 2.1;  // re / spacing, the solver default

// Particles whose full stencil of radius `layers * re` lies inside the lattice.
bool interior(const std::vector<double>& p, long long i, int dimension, const std::array<int, 3>& n, double h,
              double depth) {
  for (int a = 0; a < dimension; ++a) {
    const double x = p[3 * i + a];
    if (x < depth || x > n[a] * h - depth) return false;
  }
  return true;
}

struct LatticeFixture {
  int dimension;
  std::array<int, 3> n;
  double h;
  std::vector<double> p;
  BondList bonds;
  OperatorScales scales;
  LatticeFixture(int d, int nx, int ny, int nz, double spacing) : dimension(d), n{nx, ny, nz}, h(spacing) {
    p = lattice(d, nx, ny, nz, h);
    bonds = build_bonds(d, p, kRe * h);
    scales = reference_normalisation(bonds).scales(d);
  }
  size_t size() const { return p.size() / 3; }
};

}  // namespace

TEST(MpsNeighbours, CellListFindsExactlyTheBruteForcePairs) {
  // Irregular cloud: jittered lattice, so cell boundaries cut through stencils.
  auto p = lattice(2, 23, 17, 1, 1.0);
  for (size_t i = 0; i < p.size(); ++i)
    if (i % 3 != 2) p[i] += 0.3 * std::sin(12.9898 * i);
  const double re = 2.1;
  const BondList b = build_bonds(2, p, re);
  size_t brute = 0;
  const size_t n = p.size() / 3;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j)
      if (i != j && std::hypot(p[3 * i] - p[3 * j], p[3 * i + 1] - p[3 * j + 1]) < re) ++brute;
  EXPECT_EQ(b.size(), brute);
}

TEST(MpsNeighbours, PeriodicLatticeGivesEveryParticleTheFullStencil) {
  const auto p = lattice(2, 8, 6, 1, 1.0);
  Periodicity per;
  per.period_m = {8.0, 6.0, 0.0};
  const BondList b = build_bonds(2, p, 2.1, per);
  // 2D square lattice, re = 2.1 h: 4 neighbours at h, 4 at sqrt(2) h, 4 at 2 h.
  for (size_t i = 0; i + 1 < b.offset.size(); ++i) EXPECT_EQ(b.offset[i + 1] - b.offset[i], 12);
}

TEST(MpsOperators, GradientAndDivergenceAreExactForLinearFieldsAtInteriorParticles2D) {
  LatticeFixture s(2, 20, 18, 1, 1e-3);
  const size_t n = s.size();
  std::vector<double> phi(n), ux(n), uy(n), uz(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const double x = s.p[3 * i], y = s.p[3 * i + 1];
    phi[i] = 3.0 + 2.0 * x - 5.0 * y;
    ux[i] = 0.7 * x + 0.2 * y;
    uy[i] = -0.4 * x + 1.3 * y;
  }
  const BondsView b = s.bonds.view();
  int checked = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!interior(s.p, i, 2, s.n, s.h, kRe * s.h)) continue;
    double g[3];
    gradient_at(i, b, phi.data(), s.scales.gradient, g);
    // Exact up to round-off: the second moment sum_j w r (x) r / r^2 of a square lattice is
    // isotropic, (n0 / d) I; 1e-12 relative to the slope covers summation round-off.
    EXPECT_NEAR(g[0], 2.0, 1e-12 * 5);
    EXPECT_NEAR(g[1], -5.0, 1e-12 * 5);
    EXPECT_NEAR(divergence_at(i, b, {ux.data(), uy.data(), uz.data()}, s.scales.gradient), 0.7 + 1.3, 1e-12 * 5);
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(MpsOperators, LaplacianIsExactForQuadraticFieldsAtInteriorParticles2DAnd3D) {
  // Why exact: phi_j - phi_i = r.grad + (1/2) r.H.r + (cubic terms). The first and third
  // moments vanish by the lattice's point symmetry; the second moment sum_j w r (x) r is
  // (lambda n0 / d) I by the cubic symmetry, which is exactly what 2d/(lambda n0) undoes.
  for (int d : {2, 3}) {
    LatticeFixture s(d, 14, 13, 12, 0.5e-3);
    const size_t n = s.size();
    std::vector<double> phi(n);
    double exact = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double x = s.p[3 * i], y = s.p[3 * i + 1], z = s.p[3 * i + 2];
      phi[i] = 1.0 + x + 4e3 * x * x - 3e3 * y * y + 2e3 * x * y + (d == 3 ? 5e3 * z * z - 1e3 * y * z : 0.0);
    }
    exact = 2 * 4e3 - 2 * 3e3 + (d == 3 ? 2 * 5e3 : 0.0);
    int checked = 0;
    for (size_t i = 0; i < n; ++i) {
      if (!interior(s.p, i, d, s.n, s.h, kRe * s.h)) continue;
      // 1e-9 relative: phi ~ 1 is differenced over h^2 ~ 1e-7 m^2, losing ~7 digits.
      EXPECT_NEAR(laplacian_scalar_at(i, s.bonds.view(), phi.data(), s.scales.laplacian), exact, 1e-9 * std::abs(exact) * 1e3)
          << "dimension " << d;
      ++checked;
    }
    EXPECT_GT(checked, 50);
  }
}

TEST(MpsOperators, GradOfDivIsExactForQuadraticDisplacementTwoStencilsFromTheSurface) {
  // Composition used by the elastic force: <grad <div u>> with the adjoint gradient. Each
  // operator is exact one degree down (div of quadratic is exact-linear in the interior,
  // grad of linear is exact), so the composite is exact where both stencils are full.
  LatticeFixture s(2, 24, 22, 1, 1e-3);
  const size_t n = s.size();
  std::vector<double> ux(n), uy(n), uz(n, 0.0), div(n);
  for (size_t i = 0; i < n; ++i) {
    const double x = s.p[3 * i], y = s.p[3 * i + 1];
    ux[i] = 30 * x * x + 10 * x * y - 20 * y * y;
    uy[i] = -15 * x * x + 40 * x * y + 5 * y * y;
  }
  // div u = 60x + 10y + 40x + 10y = 100x + 20y: grad(div u) = (100, 20).
  const BondsView b = s.bonds.view();
  for (size_t i = 0; i < n; ++i) div[i] = divergence_at(i, b, {ux.data(), uy.data(), uz.data()}, s.scales.gradient);
  int checked = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!interior(s.p, i, 2, s.n, s.h, 2 * kRe * s.h)) continue;
    double g[3];
    gradient_adjoint_at(i, b, div.data(), s.scales.gradient, g);
    EXPECT_NEAR(g[0], 100.0, 1e-8);  // differences of O(0.1) values over h = 1e-3: ~1e-10 round-off
    EXPECT_NEAR(g[1], 20.0, 1e-8);
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

TEST(MpsOperators, LaplacianConvergesAtSecondOrderForASmoothField) {
  // phi = sin(k x) cos(k y); lap phi = -2 k^2 phi. With re/h fixed the truncation error is
  // the fourth-moment term, O(h^2): halving h should divide the error by 4 (order 2).
  const double length = 1.0, k = 2.0 * std::numbers::pi / length;
  auto max_error = [&](int cells) {
    LatticeFixture s(2, cells, cells, 1, length / cells);
    const size_t n = s.size();
    std::vector<double> phi(n);
    for (size_t i = 0; i < n; ++i) phi[i] = std::sin(k * s.p[3 * i]) * std::cos(k * s.p[3 * i + 1]);
    double err = 0.0;
    for (size_t i = 0; i < n; ++i) {
      if (!interior(s.p, i, 2, s.n, s.h, kRe * s.h)) continue;
      err = std::max(err, std::abs(laplacian_scalar_at(i, s.bonds.view(), phi.data(), s.scales.laplacian) +
                                   2 * k * k * phi[i]));
    }
    return err;
  };
  const double coarse = max_error(40), fine = max_error(80);
  const double order = std::log2(coarse / fine);
  // 1.8..2.2: the leading h^2 term dominates at these resolutions (10-20 stencils per
  // wavelength); higher-order terms shift the measured order by a few percent.
  EXPECT_GT(order, 1.8) << "coarse " << coarse << " fine " << fine;
  EXPECT_LT(order, 2.2) << "coarse " << coarse << " fine " << fine;
}

TEST(MpsOperators, GradientIsExactForLinearFieldsIn3D) {
  LatticeFixture s(3, 10, 9, 8, 1e-3);
  const size_t n = s.size();
  std::vector<double> phi(n);
  for (size_t i = 0; i < n; ++i) phi[i] = 2.0 * s.p[3 * i] - 1.0 * s.p[3 * i + 1] + 4.0 * s.p[3 * i + 2];
  int checked = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!interior(s.p, i, 3, s.n, s.h, kRe * s.h)) continue;
    double g[3];
    gradient_at(i, s.bonds.view(), phi.data(), s.scales.gradient, g);
    EXPECT_NEAR(g[0], 2.0, 1e-11);  // round-off on sums of ~30 bonds
    EXPECT_NEAR(g[1], -1.0, 1e-11);
    EXPECT_NEAR(g[2], 4.0, 1e-11);
    ++checked;
  }
  EXPECT_GT(checked, 10);
}
