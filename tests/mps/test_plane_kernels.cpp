// The plane-strain forms of the stress solid's kernels (solid_kernels.hpp, "Plane strain"):
// in 2D they skip the products with an exactly zero factor (the z row and column of every
// matrix) and read the bond coefficients from an array instead of dividing per bond. The
// claim is that every value equals the full 3x3 form's to the last bit (only the sign of a
// value that is zero anyway may differ), so a 2D run gives the same numbers as before the
// plane forms existed. Checked here against the full forms themselves on random states,
// with EXPECT_EQ on doubles (exact equality; -0 == +0).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/mps/neighbours.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/solid_phases.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;

namespace {

// A block-diagonal matrix (in-plane 2x2 block and zz entry) of entries in [-1, 1] around `diag` on the diagonal.
Mat3 random_plane_matrix(std::mt19937& rng, double diag) {
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  Mat3 m;
  m(0, 0) = diag + d(rng);
  m(0, 1) = d(rng);
  m(1, 0) = d(rng);
  m(1, 1) = diag + d(rng);
  m(2, 2) = diag + d(rng);
  return m;
}

void expect_same_matrix(const Mat3& plane, const Mat3& full, const char* what) {
  for (int k = 0; k < 9; ++k) EXPECT_EQ(plane.a[k], full.a[k]) << what << " entry " << k;
}

}  // namespace

TEST(MpsPlaneKernels, ProductDeterminantAndInverseEqualTheFullFormsOnBlockDiagonalMatrices) {
  std::mt19937 rng(1995);
  for (int trial = 0; trial < 1000; ++trial) {
    const Mat3 x = random_plane_matrix(rng, 2.0), y = random_plane_matrix(rng, 2.0);
    expect_same_matrix(mul(x, y, 2), mul(x, y), "x y");
    EXPECT_EQ(det(x, 2), det(x));
    expect_same_matrix(inverse(x, 2), inverse(x), "x^-1");
    expect_same_matrix(mul(x, y, 3), mul(x, y), "x y, dimension 3");
  }
}

// A 2D lattice with a random in-plane displacement over two steps (so the second has an old
// gradient, a rotation and a stress to rotate), plastic (the radial return active) and with
// material damping: the plane forms (dimension 2, bond coefficients from an array) against
// the full forms (dimension 3, coefficients computed per bond) in every phase of a step.
TEST(MpsPlaneKernels, StressPhaseForceAndHourglassEnergyEqualTheFullFormsOnA2DLattice) {
  const double h = 1e-3;
  const auto pos = test::lattice(2, 9, 8, 1, h);
  const long long n = static_cast<long long>(pos.size() / 3);
  const BondList bonds = build_bonds(2, pos, 2.1 * h);
  const BondsView b = bonds.view();
  const std::vector<double> volume(n, h * h);
  const double mps_scale = 2.0 / reference_normalisation(bonds).number_density_n0;
  std::vector<Mat3> moment_inverse(n);
  for (long long i = 0; i < n; ++i) moment_inverse[i] = inverse_moment_matrix_at(i, b, volume.data(), 2, mps_scale);
  std::vector<double> coefficient(bonds.size());
  for (size_t k = 0; k < bonds.size(); ++k) coefficient[k] = bond_coefficient(b, static_cast<long long>(k), volume.data(), nullptr);

  SolidLaw law;
  law.lame_lambda_pa = 1.15e11;
  law.shear_modulus_pa = 7.7e10;
  law.plastic = true;
  law.hardening = {law.shear_modulus_pa, 2e8, 1e9};  // yields at a strain of ~1e-3
  law.viscous_time_s = 1e-7;

  // Per-particle state of each form.
  struct State {
    std::vector<Mat3> gradient, f_inverse;
    std::vector<SymTensor> stress, viscous;
    std::vector<double> eq_plastic, work, pressure, viscous_work;
    std::vector<ForceMatrices> matrices;
    explicit State(long long n)
        : gradient(n), f_inverse(n, identity3()), stress(n), viscous(n), eq_plastic(n), work(n), pressure(n),
          viscous_work(n), matrices(n) {}
    SolidStressState view() {
      return {gradient.data(), f_inverse.data(), stress.data(), eq_plastic.data(), work.data(), pressure.data(),
              matrices.data(),  viscous.data(),  viscous_work.data()};
    }
  };
  State plane(n), full(n);
  std::vector<double> ux(n), uy(n), uz(n, 0.0);
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  const VectorField u{ux.data(), uy.data(), uz.data()};
  long long yielded = 0;
  for (int step = 0; step < 2; ++step) {
    // A rotation of 0.01 rad per step, a stretch and a random part of 1e-3 spacings.
    const double angle = 0.01 * (step + 1), c = std::cos(angle), s = std::sin(angle);
    for (long long i = 0; i < n; ++i) {
      const double x = pos[3 * i], y = pos[3 * i + 1];
      ux[i] = (c - 1.0) * x - s * y + 2e-3 * x + 1e-3 * h * noise(rng);
      uy[i] = s * x + (c - 1.0) * y + 1e-6 * h * noise(rng);
    }
    SolidStressInputs in;
    in.bonds = b;
    in.u = u;
    in.volume_m3 = volume.data();
    in.moment_inverse = moment_inverse.data();
    in.law = law;
    in.hourglass_stiffness = 1e15;
    in.dt_s = 1e-7;
    SolidStressInputs in_plane = in, in_full = in;
    in_plane.dimension = 2;
    in_plane.bond_coefficient = coefficient.data();
    in_full.dimension = 3;  // the full forms (the state is planar: no z bond, no z displacement)
    for (long long i = 0; i < n; ++i) {
      EXPECT_EQ(stress_phase_at(i, in_plane, plane.view()), stress_phase_at(i, in_full, full.view()));
      expect_same_matrix(plane.gradient[i], full.gradient[i], "H");
      expect_same_matrix(plane.f_inverse[i], full.f_inverse[i], "F^-1");
      const SymTensor& p = plane.stress[i];
      const SymTensor& f = full.stress[i];
      EXPECT_EQ(p.xx, f.xx);
      EXPECT_EQ(p.yy, f.yy);
      EXPECT_EQ(p.zz, f.zz);
      EXPECT_EQ(p.xy, f.xy);
      EXPECT_EQ(p.yz, f.yz);
      EXPECT_EQ(p.zx, f.zx);
      EXPECT_EQ(plane.eq_plastic[i], full.eq_plastic[i]);
      EXPECT_EQ(plane.work[i], full.work[i]);
      EXPECT_EQ(plane.viscous_work[i], full.viscous_work[i]);
      expect_same_matrix(plane.matrices[i].combined, full.matrices[i].combined, "P L^-1 - K H");
      expect_same_matrix(plane.matrices[i].pressure, full.matrices[i].pressure, "J F^-T L^-1");
      EXPECT_EQ(plane.matrices[i].hourglass_stiffness, full.matrices[i].hourglass_stiffness);
      yielded += step == 1 && full.eq_plastic[i] > 0.0;
    }
  }
  EXPECT_GT(yielded, 0) << "the radial return was not exercised";
  SolidForceInputs forces;
  forces.bonds = b;
  forces.u = u;
  forces.volume_m3 = volume.data();
  SolidForceInputs plane_forces = forces, full_forces = forces;
  plane_forces.matrices = plane.matrices.data();
  plane_forces.bond_coefficient = coefficient.data();
  plane_forces.dimension = 2;
  full_forces.matrices = full.matrices.data();
  for (long long i = 0; i < n; ++i) {
    double fp[3], ff[3];
    solid_force_at(i, plane_forces, fp);
    solid_force_at(i, full_forces, ff);
    EXPECT_EQ(fp[0], ff[0]);
    EXPECT_EQ(fp[1], ff[1]);
    EXPECT_EQ(fp[2], 0.0);
    EXPECT_EQ(hourglass_energy_at(i, b, u, volume.data(), plane.gradient[i], 1e15, 2, coefficient.data()),
              hourglass_energy_at(i, b, u, volume.data(), full.gradient[i], 1e15));
  }
}

// The plane forms assume no bond has a z component: a 2D solid with particles off one plane
// is refused rather than run with matrices that are not block-diagonal.
TEST(MpsPlaneKernels, TwoDimensionalSolidRefusesParticlesOutOfOnePlane) {
  const double h = 1e-3;
  auto pos = test::lattice(2, 4, 4, 1, h);
  pos[3 * 5 + 2] = 0.1 * h;
  SolidOptions opt;
  opt.dimension = 2;
  opt.spacing_m = h;
  SolidLaw law;
  law.lame_lambda_pa = 1e9;
  law.shear_modulus_pa = 1e9;
  try {
    Solid solid(pos, std::vector<double>(pos.size() / 3, h * h), 1000, law, opt);
    FAIL() << "a 2D solid with a particle off the plane was accepted";
  } catch (const breccia::RunError& e) {
    EXPECT_NE(std::string(e.what()).find("same z"), std::string::npos) << e.what();
  }
}
