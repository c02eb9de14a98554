#pragma once
// Brittle fracture of the stress-based MPS solid ([Inagaki 2009]: "a separation
// tensor - the stress with its inertial part removed - decides failure; crack faces of any
// orientation; surface particles do not scatter").
//
// Separation tensor (O'Brien & Hodgins 1999, "Graphical modeling and animation of brittle
// fracture", SIGGRAPH; the graphics source of the term, which the thesis' visualisation
// chapter builds on). Split the particle stress into its tensile and compressive parts
// sigma = sigma+ + sigma- (positive / negative principal values). Each intact bond k of
// particle i carries the pair force of each part (the bond term of solid_force_at),
//   f+_k = V_j c_k (S+_i + S+_j) r_k,   S+ = J sigma+ F^-T L^-1    (likewise f-_k),
// and with m(a) = a a^T / |a| (0 for a = 0)
//   varsigma_i = 1/2 [ -m(sum_k f+_k) + m(sum_k f-_k) + sum_k m(f+_k) - sum_k m(f-_k) ].
// The sums of m(f_k) measure how hard the bonds pull (push) the particle apart in each
// direction; the unbalanced resultant sum_k f_k is what accelerates the particle (the
// inertial part), and subtracting m of it removes exactly that: bonds that all pull a
// particle to one side (a free-surface particle being decelerated, a fragment's edge)
// give varsigma = 0 however large the particle's stress, so surface particles do not
// scatter. In a balanced interior state under uniaxial stress s n n^T every f_k is parallel
// to n and varsigma = s D(n) n n^T with
//   D(n) = 1/2 sum_k V_j c_k |n . (G_i + G_j) r_k|,   G = J F^-T L^-1,
// so the separation stress S_i = lambda_max(varsigma_i) / D(n_max) equals the principal
// tensile stress there (n_max the eigenvector of the largest eigenvalue). That calibration
// lets the criterion use the material's tensile strength: particle i fails when
// S_i >= tensile_strength, with the crack plane through i normal to n_max, whatever the
// lattice's bond directions.
//
// Crack plane: the bonds of i's neighbourhood (i and its reference neighbours) whose
// current segment crosses the plane {x : (x - x_i) . n = 0} within cut_radius (half a
// spacing: each particle owns one spacing of crack length) of x_i are cut (i itself counts
// as on the - side). A cut bond has weight 0, so it carries no stress force, no hourglass
// force and drops out of the gradient (Solid then recomputes the moment matrices).
//
// Per step at most one particle per neighbourhood fails (the most loaded first): a new
// crack face needs a wave transit to unload its neighbours, and without the rule a smooth
// stress peak would open several parallel cracks one spacing apart in the same step.
#include <array>
#include <cmath>
#include <vector>

#include "breccia/mps/neighbours.hpp"
#include "breccia/mps/solid_kernels.hpp"

namespace breccia::mps {

struct FractureLaw {
  double tensile_strength_pa = 0.0;  // > 0
};

// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations (converges to
// rounding in a few sweeps for 3x3). vector[k] is the unit eigenvector of value[k].
struct SymEigen {
  double value[3];
  double vector[3][3];
};

BRECCIA_HD inline SymEigen symmetric_eigen(const Mat3& m) {
  double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a[r][c] = 0.5 * (m(r, c) + m(c, r));
  for (int sweep = 0; sweep < 12; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-30 * diag || off == 0.0) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        const double theta = 0.5 * (a[q][q] - a[p][p]) / a[p][q];
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < 3; ++k) {  // A <- A J
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {  // A <- J^T A
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {  // V <- V J
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  SymEigen e;
  for (int k = 0; k < 3; ++k) {
    e.value[k] = a[k][k];
    for (int r = 0; r < 3; ++r) e.vector[k][r] = v[r][k];
  }
  return e;
}

// The same for a matrix without z couplings (2D: the in-plane block), in closed form; the
// third pair is (m_zz, e_z). Several times cheaper than the Jacobi sweeps, and the
// separation tensor needs two decompositions per particle and step.
BRECCIA_HD inline SymEigen symmetric_eigen_xy(const Mat3& m) {
  const double a = m(0, 0), d = m(1, 1), b = 0.5 * (m(0, 1) + m(1, 0));
  const double mean = 0.5 * (a + d), half = 0.5 * (a - d);
  const double radius = std::sqrt(half * half + b * b);
  const double angle = 0.5 * std::atan2(b, half);  // direction of the larger value
  const double c = std::cos(angle), s = std::sin(angle);
  SymEigen e;
  e.value[0] = mean + radius;
  e.value[1] = mean - radius;
  e.value[2] = m(2, 2);
  const double v[3][3] = {{c, s, 0.0}, {-s, c, 0.0}, {0.0, 0.0, 1.0}};
  for (int k = 0; k < 3; ++k)
    for (int r = 0; r < 3; ++r) e.vector[k][r] = v[k][r];
  return e;
}

// Conditioning of particle i's stencil: smallest over largest eigenvalue of its moment
// matrix L = sum_k V_j c_k r_k (x) r_k over the intact bonds (in-plane in 2D); 1 for a full or
// a half (flat-surface) stencil, 0 for one whose bonds all lie on a line.
BRECCIA_HD inline double stencil_conditioning(long long i, BondsView b, const double* volume_m3, int dimension) {
  Mat3 moment;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    if (b.weight[k] == 0.0) continue;
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double c = volume_m3[b.neighbour[k]] * b.weight[k] / (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) moment(p, q) += c * r[p] * r[q];
  }
  const SymEigen e = dimension == 2 ? symmetric_eigen_xy(moment) : symmetric_eigen(moment);
  const int d = dimension == 2 ? 2 : 3;
  double lo = e.value[0], hi = e.value[0];
  for (int k = 1; k < d; ++k) {
    lo = e.value[k] < lo ? e.value[k] : lo;
    hi = e.value[k] > hi ? e.value[k] : hi;
  }
  return hi > 0.0 ? lo / hi : 0.0;
}

// A damaged particle whose remaining stencil's conditioning lies in
// [kCollinearStencil, kRemnantConditioning) is a remnant (a few bonds left on one side where
// cracks meet) and is detached as debris: L^-1 scales the gradient across its weak direction
// by 1/lambda_min, so its stress can run away before the stencil folds (ring at 0.25 mm:
// +31% energy). 0.1 is the conditioning of bonds spread evenly over a wedge of +-31 deg
// ((t - sin t cos t)/(t + sin t cos t), t the half-angle); the stencils a damaged particle
// keeps in ordinary fracture lie well above it: a crack face (half stencil) 0.59 on a
// square lattice (1 for evenly spread bonds), a crack meeting a free surface at right angles
// (quarter stencil) 0.70 on a square lattice, 0.22 for evenly spread bonds (the lattice
// values are tested). Two bonds at 45 deg to each other on a square lattice
// ((2,0) and (1,1) spacings) give 0.046 and are detached. Stencils with every bond on one
// line (a one-particle-thick sliver between two cracks on a lattice) are below
// kCollinearStencil: they have no gradient across the line to amplify, use the plain MPS
// scale (inverse_moment_matrix_at) and are kept, as before.
constexpr double kRemnantConditioning = 0.1;
constexpr double kCollinearStencil = 1e-6;

// sigma+ = sum over positive principal values s_k e_k e_k^T; sigma- = sigma - sigma+.
// In 2D (plane strain) only the in-plane part matters: the bond forces have no z
// component and sigma_zz does not enter them.
BRECCIA_HD inline void split_tensile(const SymTensor& stress, int dimension, Mat3& tensile, Mat3& compressive) {
  Mat3 s = to_matrix(stress);
  if (dimension == 2) s(2, 2) = 0.0;
  const SymEigen e = dimension == 2 ? symmetric_eigen_xy(s) : symmetric_eigen(s);
  tensile = Mat3{};
  for (int k = 0; k < 3; ++k) {
    if (!(e.value[k] > 0.0)) continue;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) tensile(r, c) += e.value[k] * e.vector[k][r] * e.vector[k][c];
  }
  for (int k = 0; k < 9; ++k) compressive.a[k] = s.a[k] - tensile.a[k];
}

// acc += sign * a a^T / |a|, upper triangle only (the caller mirrors it once at the end).
BRECCIA_HD inline void add_norm_outer(Mat3& acc, const double a[3], double sign) {
  const double len2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
  if (!(len2 > 0.0)) return;
  const double f = sign / std::sqrt(len2);
  acc(0, 0) += f * a[0] * a[0];
  acc(0, 1) += f * a[0] * a[1];
  acc(0, 2) += f * a[0] * a[2];
  acc(1, 1) += f * a[1] * a[1];
  acc(1, 2) += f * a[1] * a[2];
  acc(2, 2) += f * a[2] * a[2];
}

// Per-particle inputs of the separation tensor: the bond-force matrices of the tensile and
// compressive stress parts, S+- = sigma+- G (G = J F^-T L^-1, ForceMatrices::pressure).
struct SeparationInputs {
  BondsView bonds;
  const double* volume_m3 = nullptr;
  const Mat3* tensile = nullptr;
  const Mat3* compressive = nullptr;
  const ForceMatrices* matrices = nullptr;  // for G
  // Per particle: 1 if its stress has a positive principal value. A particle with no
  // tension in its neighbourhood is not evaluated (S = 0): separation is driven by
  // tension, and m(sum f-) - sum m(f-) alone can be slightly positive where opposed
  // compressive bond forces nearly cancel, which must not break material in compression.
  const char* tensile_nonzero = nullptr;
  int dimension = 2;
};

// First pass of the separation, per particle (separation_at then reads the neighbours'):
// the bond-force matrices of sigma+ and sigma- and whether sigma+ is non-zero.
BRECCIA_HD inline void separation_parts_at(long long i, const SymTensor* stress, const ForceMatrices* matrices,
                                           int dimension, Mat3* tensile, Mat3* compressive, char* tensile_nonzero) {
  Mat3 plus, minus;
  split_tensile(stress[i], dimension, plus, minus);
  tensile[i] = mul(plus, matrices[i].pressure);
  compressive[i] = mul(minus, matrices[i].pressure);
  tensile_nonzero[i] = plus(0, 0) + plus(1, 1) + plus(2, 2) > 0.0;  // trace of a PSD part
}

struct Separation {
  double stress_pa = 0.0;          // S_i = lambda_max / D(n_max); 0 when no bond pulls
  double normal[3] = {0, 0, 0};    // n_max (unit; zero when stress_pa is 0)
};

// The separation tensor of particle i and its calibrated largest principal value (header).
// The common factor V_i of every bond force of i cancels between varsigma and D.
// Body of separation_at for D = 2 or 3 (in 2D every bond force and the z row of the stress
// parts vanish, so the loops run over the in-plane components only).
template <int D>
BRECCIA_HD inline Separation separation_in(long long i, const SeparationInputs& in) {
  const BondsView& b = in.bonds;
  if (in.tensile_nonzero) {
    bool tension = in.tensile_nonzero[i];
    for (long long k = b.offset[i]; k < b.offset[i + 1] && !tension; ++k)
      tension = b.weight[k] != 0.0 && in.tensile_nonzero[b.neighbour[k]];
    if (!tension) return Separation{};
  }
  Mat3 varsigma;
  double sum_plus[3] = {0, 0, 0}, sum_minus[3] = {0, 0, 0};
  const Mat3& ti = in.tensile[i];
  const Mat3& ci = in.compressive[i];
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    if (b.weight[k] == 0.0) continue;  // cut
    const long long j = b.neighbour[k];
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double c = in.volume_m3[j] * b.weight[k] / (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    const Mat3& tj = in.tensile[j];
    const Mat3& cj = in.compressive[j];
    double fp[3] = {0, 0, 0}, fm[3] = {0, 0, 0};
    for (int p = 0; p < D; ++p) {
      for (int q = 0; q < D; ++q) {
        fp[p] += (ti(p, q) + tj(p, q)) * r[q];
        fm[p] += (ci(p, q) + cj(p, q)) * r[q];
      }
      fp[p] *= c;
      fm[p] *= c;
      sum_plus[p] += fp[p];
      sum_minus[p] += fm[p];
    }
    add_norm_outer(varsigma, fp, 0.5);
    add_norm_outer(varsigma, fm, -0.5);
  }
  add_norm_outer(varsigma, sum_plus, -0.5);
  add_norm_outer(varsigma, sum_minus, 0.5);
  varsigma(1, 0) = varsigma(0, 1);
  varsigma(2, 0) = varsigma(0, 2);
  varsigma(2, 1) = varsigma(1, 2);
  const SymEigen e = D == 2 ? symmetric_eigen_xy(varsigma) : symmetric_eigen(varsigma);
  // In 2D the third pair is (0, e_z); the largest is taken among the in-plane vectors.
  int top = 0;
  for (int k = 1; k < D; ++k)
    if (e.value[k] > e.value[top]) top = k;
  Separation out;
  if (!(e.value[top] > 0.0)) return out;
  const double* n = e.vector[top];
  const Mat3& gi = in.matrices[i].pressure;
  double gi_n[3] = {0, 0, 0};  // G_i^T n
  for (int q = 0; q < D; ++q)
    for (int p = 0; p < D; ++p) gi_n[q] += n[p] * gi(p, q);
  double d = 0.0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    if (b.weight[k] == 0.0) continue;
    const long long j = b.neighbour[k];
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double c = in.volume_m3[j] * b.weight[k] / (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    const Mat3& gj = in.matrices[j].pressure;
    double proj = 0.0;
    for (int q = 0; q < D; ++q) {
      double g = gi_n[q];
      for (int p = 0; p < D; ++p) g += n[p] * gj(p, q);
      proj += g * r[q];
    }
    d += 0.5 * c * std::fabs(proj);
  }
  if (!(d > 0.0)) return out;
  out.stress_pa = e.value[top] / d;
  for (int p = 0; p < 3; ++p) out.normal[p] = n[p];
  return out;
}

BRECCIA_HD inline Separation separation_at(long long i, const SeparationInputs& in) {
  return in.dimension == 2 ? separation_in<2>(i, in) : separation_in<3>(i, in);
}

// Owns the fracture state of a Solid: which bonds are cut, per-particle separation stress,
// failure count, normal and time of the first failure. Host code (the cutting is rare and
// irregular); the per-particle separation is the BRECCIA_HD kernel above.
class FractureModel {
public:
  FractureModel(const FractureLaw& law, const BondList& bonds, double spacing_m);

  // Current state of the solid that the separation and the cutting need (arrays of N).
  struct State {
    VectorField displacement;
    const double* volume_m3 = nullptr;
    const SymTensor* stress = nullptr;
    const ForceMatrices* matrices = nullptr;
    int dimension = 2;
    double time_s = 0.0;
  };

  // Evaluate the separation stress of every particle, fail those at or above the strength
  // (at most one per neighbourhood, most loaded first), cut their bonds in `bonds` (weight
  // set to 0 in both directions). Returns the particles whose stencil lost a bond (sorted).
  std::vector<long long> fail_and_cut(BondList& bonds, const State& state);
  // The evaluation alone (separation_pa(), normal_of(); nothing is cut). fail_and_cut starts
  // with it; Solid calls it on its own to bring the values up to date after steps taken on a
  // device (the device only compares them with the strength, solid.hpp SolidStepDevice).
  void evaluate(const BondList& bonds, const State& state);
  // Whether absorb_inversion or absorb_remnant flagged particles that detach_flagged has not
  // yet cut.
  bool has_flagged() const { return flagged_ > 0; }

  // A particle that already lost bonds and whose remaining stencil folds (det F <= 0) is
  // debris at a crack face, not a failed run: it is flagged here (thread-safe per particle)
  // and detach_flagged() cuts its remaining bonds. Returns false for an undamaged particle.
  bool absorb_inversion(long long i, const BondList& bonds);
  // A damaged particle whose remaining stencil is a remnant (conditioning in
  // [kCollinearStencil, kRemnantConditioning)) is flagged the same way; returns whether it was.
  bool absorb_remnant(long long i, const BondList& bonds, const double* volume_m3, int dimension);
  long long remnant_particles() const { return remnants_; }
  // Cut every bond of the flagged particles; returns the particles that lost bonds (sorted).
  std::vector<long long> detach_flagged(BondList& bonds);
  long long detached_particles() const { return detached_; }

  const FractureLaw& law() const { return law_; }
  const std::vector<double>& separation_pa() const { return separation_pa_; }
  // Normal of the largest separation value at the last evaluation (zero where S = 0).
  const std::array<double, 3>& normal_of(size_t i) const { return normal_[i]; }
  const std::vector<int>& failures() const { return failures_; }  // failure events per particle
  // Crack-plane normal of the particle's first failure (zero if it never failed).
  const std::vector<std::array<double, 3>>& first_normal() const { return first_normal_; }
  // Time of the particle's first failure (s); negative if it never failed.
  const std::vector<double>& first_failure_time_s() const { return first_failure_time_s_; }
  // Fraction of the particle's initial bonds that are cut (0 ... 1).
  std::vector<double> damage(const BondList& bonds) const;
  // Connected pieces over the intact bonds: a label per particle (0 ... pieces - 1, the
  // largest piece first, equal sizes in the order of their first particle) and the number
  // of pieces with at least min_particles particles.
  static std::vector<int> fragment_labels(const BondList& bonds);
  static int fragment_count(const std::vector<int>& labels, int min_particles);
  long long cut_bonds() const { return cut_bonds_; }
  long long failed_particles() const;
  double max_separation_pa() const;

private:
  void cut_plane(BondList& bonds, const State& s, long long i, const double n[3], std::vector<long long>& touched);

  FractureLaw law_;
  double cut_radius_m_ = 0.0;
  std::vector<int> initial_bonds_;
  std::vector<Mat3> tensile_, compressive_;
  std::vector<char> tensile_nonzero_, inverted_;
  long long detached_ = 0, remnants_ = 0, flagged_ = 0;
  std::vector<double> separation_pa_, first_failure_time_s_;
  std::vector<std::array<double, 3>> normal_, first_normal_;
  std::vector<int> failures_;
  long long cut_bonds_ = 0;
};

}  // namespace breccia::mps
