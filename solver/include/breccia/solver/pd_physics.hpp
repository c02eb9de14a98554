#pragma once
// Peridynamic physics written once, as plain functions on plain data, callable from the
// OpenMP loops and from CUDA kernels (BRECCIA_HD). Derivations: docs/theory.md.
#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "breccia/solver/hd.hpp"

namespace breccia::solver {

// The bond physics is templated over the real type (double, or float for model.precision:
// float32, docs/theory.md "Precision"). The first argument fixes Real; `SameReal` keeps the
// others from taking part in the deduction, so a call mixing a double modulus with a float
// critical stretch still resolves to the double version, as before.
template <class Real>
using SameReal = typename std::type_identity<Real>::type;

enum class Influence : int { Constant = 0, Inverse = 1, Gaussian = 2 };
enum class PdModel : int { PMB = 0, LPS = 1, Correspondence = 2 };  // correspondence: CPU only
enum class Planar : int { None = 0, PlaneStress = 1, PlaneStrain = 2 };

// Influence function in terms of q = |xi| / delta (dimensionless so that micro-moduli keep
// their textbook units): constant 1; inverse delta/|xi| (= 1/q); Gaussian exp(-q^2) ([Fukuda PD], eq. 8).
BRECCIA_HD double influence(Influence kind, double q) {
  switch (kind) {
    case Influence::Inverse: return 1.0 / q;
    case Influence::Gaussian: return std::exp(-q * q);
    default: return 1.0;
  }
}

// Fraction of neighbour j's cell inside the horizon: a linear ramp over j's cell width,
// which needs no lattice (tet-centroid particles have cells of any shape; docs/theory.md).
BRECCIA_HD double partial_volume_fraction(double xi_len, double horizon, double half_cell_j) {
  if (half_cell_j <= 0.0) return xi_len <= horizon ? 1.0 : 0.0;
  const double f = (horizon + half_cell_j - xi_len) / (2.0 * half_cell_j);
  return f < 0.0 ? 0.0 : (f > 1.0 ? 1.0 : f);
}

// The same fraction by quadrature: j's cell taken as an axis-aligned cube (square) of
// j's own volume, sampled at n^d midpoints. Far more accurate than the ramp near the
// horizon edge (it sees the cell's orientation to the bond), still lattice-free.
// partial_volume_samples_inside counts the sample points inside the horizon, out of
// partial_volume_sample_total(dimension); the fraction is their ratio.
inline constexpr int kPartialVolumeSamples = 6;  // per axis
inline constexpr int partial_volume_sample_total(int dimension) {
  return dimension == 3 ? kPartialVolumeSamples * kPartialVolumeSamples * kPartialVolumeSamples
                        : kPartialVolumeSamples * kPartialVolumeSamples;
}
// The half diagonal of a neighbour's cell (half edge half_cell): the early accept and reject
// of the partial-volume quadrature, and the family search's pad below, measure from it.
inline double partial_volume_half_diagonal(double half_cell, int dimension) {
  return half_cell * (dimension == 3 ? 1.7320508075688772 : 1.4142135623730951);
}
// How far beyond a horizon a neighbour's centre may lie and still have a sample point of its
// cell inside (the family search's pad): the outermost sample's distance from the cell's
// centre, (n - 1) / n of the half diagonal (the samples are the n midpoints per axis; 2D's
// samples lie in the plane), times 1 + 1e-6, far above the quadrature's rounding (a few ulp
// of |xi|). A farther candidate has no sample inside from either end, so the kept entries are
// those of the cell-corner pad it replaced (half diagonal: 18 % more candidates on a cubic
// lattice at m = 3, all of them dropped by the keep test); the Lammps rule needs no pad.
inline double partial_volume_reach(double half_cell, int dimension) {
  return partial_volume_half_diagonal(half_cell, dimension) * (static_cast<double>(kPartialVolumeSamples - 1) / kPartialVolumeSamples) * (1.0 + 1e-6);
}
// count / total for every count 0 .. total (the sampled partial volume's fractions), built
// once per dimension: the same division as the set-up's own table, so the same bits. A table
// read, not a division per entry, where the loops form the own halves' volumes (below).
inline const double* partial_volume_sample_fractions(int dimension) {
  static const std::array<std::array<double, partial_volume_sample_total(3) + 1>, 2> table = [] {
    std::array<std::array<double, partial_volume_sample_total(3) + 1>, 2> t{};
    for (int d : {2, 3}) {
      const double total = partial_volume_sample_total(d);
      for (int q = 0; q <= partial_volume_sample_total(d); ++q) t[d == 3][q] = static_cast<double>(q) / total;
    }
    return t;
  }();
  return table[dimension == 3].data();
}
// The own half's volume beta V_j of an entry whose partial volume was counted (model.
// partial_volume: sampled): fraction[count] times the partner's volume, the set-up's
// expression (`fraction`: partial_volume_sample_fractions, or a device copy of it), so that
// every place that forms it from the count (PdSystem::own_volume, pd_kernels.hpp own_volume)
// has the bits the 8 B array of these volumes held.
BRECCIA_HD double counted_own_volume(uint8_t count, const double* fraction, double volume_j) {
  return fraction[count] * volume_j;
}
// Host only (solver/src/partial_volume.cpp): the set-up runs it once per candidate entry.
int partial_volume_samples_inside(const double xi[3], double horizon, double half_cell_j, int dimension);
// A pair's two counts at once: entry (i -> j)'s own, xi = x_j - x_i (j's cell in i's horizon),
// and its reverse's, -xi (i's cell in j's horizon); each the count partial_volume_samples_inside
// gives, bit for bit, the offset's length (a square root) formed once for both.
// The set-up's count pass on a graded mesh (71 million candidates on the full concrete case).
void partial_volume_pair_samples_inside(const double xi[3], double horizon_i, double half_cell_j, double horizon_j,
                                        double half_cell_i, int dimension, int& own, int& reverse);
inline double partial_volume_sampled(const double xi[3], double horizon, double half_cell_j, int dimension) {
  return static_cast<double>(partial_volume_samples_inside(xi, horizon, half_cell_j, dimension)) /
         partial_volume_sample_total(dimension);
}

// partial_volume_sampled(...) > 0 without the quadrature: some sample point lies inside iff
// the one nearest the centre does, and on the sample grid that point takes the coordinate
// nearest zero on each axis; its squared distance is summed in the quadrature's own order,
// so the answer is the quadrature's exactly (floating-point sums are monotonic).
inline bool partial_volume_sampled_positive(const double xi[3], double horizon, double half_cell_j, int dimension) {
  const double reach = partial_volume_half_diagonal(half_cell_j, dimension);
  const double len = std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
  if (len + reach <= horizon) return true;
  if (len - reach >= horizon) return false;
  constexpr int n = 6;
  const double h = 2.0 * half_cell_j / n;
  double nearest[3];
  for (int axis = 0; axis < 3; ++axis) {
    if (axis == 2 && dimension != 3) {
      nearest[axis] = xi[2];
      continue;
    }
    double best = 0.0, best2 = 1e300;
    for (int a = 0; a < n; ++a) {
      const double p = xi[axis] - half_cell_j + (a + 0.5) * h;
      if (p * p < best2) {
        best2 = p * p;
        best = p;
      }
    }
    nearest[axis] = best;
  }
  return nearest[0] * nearest[0] + nearest[1] * nearest[1] + nearest[2] * nearest[2] <= horizon * horizon;
}

// How much of neighbour j's cell a family counts. Sampled: the quadrature above, families
// reaching to the horizon plus a cell's half diagonal (Breccia's default). Lammps: LAMMPS
// PERI's rule (FixPeriNeigh, PairPeriPMB; Parks et al. 2008): neighbours with |xi| <= delta
// only, the ones in the last half cell (|xi| > delta - h) weighted by the same linear ramp
// as partial_volume_fraction, which is 1/2 at |xi| = delta.
enum class PartialVolume : int { Sampled = 0, Lammps = 1 };
inline bool partial_volume_positive(PartialVolume kind, const double xi[3], double horizon, double half_cell_j,
                                    int dimension) {
  if (kind == PartialVolume::Sampled) return partial_volume_sampled_positive(xi, horizon, half_cell_j, dimension);
  const double len = std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
  return len <= horizon && partial_volume_fraction(len, horizon, half_cell_j) > 0.0;
}

inline double partial_volume(PartialVolume kind, const double xi[3], double horizon, double half_cell_j,
                             int dimension) {
  if (kind == PartialVolume::Sampled) return partial_volume_sampled(xi, horizon, half_cell_j, dimension);
  const double len = std::sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]);
  return len <= horizon ? partial_volume_fraction(len, horizon, half_cell_j) : 0.0;
}

// Bond stretch s = (|xi + eta| - |xi|) / |xi| and the deformed unit direction.
template <class Real>
struct BondGeometryT {
  Real dx, dy, dz;   // deformed bond vector (j - i)
  Real length;       // |xi + eta|
  Real extension;    // |xi + eta| - |xi|
  Real stretch;      // s
};
using BondGeometry = BondGeometryT<double>;

// Double: (x0_j + u_j) - (x0_i + u_i), as always. Float: xi + eta = (x0_j - x0_i) + (u_j - u_i),
// because x0 + u rounded to float would lose a displacement of 1e-6 of the coordinate.
template <class Real>
BRECCIA_HD BondGeometryT<Real> bond_geometry(const Real* x0, const Real* u, int64_t i, int64_t j,
                                             SameReal<Real> xi_len) {
  BondGeometryT<Real> g;
  if constexpr (std::is_same_v<Real, double>) {
    g.dx = (x0[3 * j] + u[3 * j]) - (x0[3 * i] + u[3 * i]);
    g.dy = (x0[3 * j + 1] + u[3 * j + 1]) - (x0[3 * i + 1] + u[3 * i + 1]);
    g.dz = (x0[3 * j + 2] + u[3 * j + 2]) - (x0[3 * i + 2] + u[3 * i + 2]);
    g.length = std::sqrt(g.dx * g.dx + g.dy * g.dy + g.dz * g.dz);
    g.extension = g.length - xi_len;
  } else {
    // Without cancellation: e = (2 xi.eta + eta.eta) / (|xi + eta| + |xi|) (pd_kernels.hpp, BondOriginT).
    const Real ax = x0[3 * j] - x0[3 * i], ay = x0[3 * j + 1] - x0[3 * i + 1], az = x0[3 * j + 2] - x0[3 * i + 2];
    const Real bx = u[3 * j] - u[3 * i], by = u[3 * j + 1] - u[3 * i + 1], bz = u[3 * j + 2] - u[3 * i + 2];
    g.dx = ax + bx;
    g.dy = ay + by;
    g.dz = az + bz;
    g.length = std::sqrt(g.dx * g.dx + g.dy * g.dy + g.dz * g.dz);
    g.extension = (Real(2) * (ax * bx + ay * by + az * bz) + (bx * bx + by * by + bz * bz)) / (g.length + xi_len);
  }
  g.stretch = g.extension / xi_len;
  return g;
}

// Half-bond state bits of one family entry (i -> j): the bond as seen from i's horizon
// ("own", uses delta_i) and from j's horizon ("dual", uses delta_j). With one constant
// horizon both halves are identical and break together (dual-horizon PD, Ren et al. 2017).
inline constexpr uint8_t kOwnIntact = 1;
inline constexpr uint8_t kDualIntact = 2;

// PMB (eq. 3 of [Fukuda PD]): force density on i from bond (i, j) is
// (k_own [own intact] + k_dual [dual intact]) * s * e_ij, where k = c_half * omega * beta * V_j.
// Returns the scalar multiplying the unit vector; also the bond's contribution to
// i's strain-energy density: W_i += 1/4 * k * s^2 * |xi| (docs/theory.md, PMB energy).
template <class Real>
BRECCIA_HD Real pmb_force_scalar(Real k_own, SameReal<Real> k_dual, uint8_t state, SameReal<Real> stretch) {
  const Real k = ((state & kOwnIntact) ? k_own : Real(0)) + ((state & kDualIntact) ? k_dual : Real(0));
  return k * stretch;
}

template <class Real>
BRECCIA_HD Real pmb_energy_density(Real k_own, SameReal<Real> k_dual, uint8_t state, SameReal<Real> stretch,
                                   SameReal<Real> xi_len) {
  const Real k = ((state & kOwnIntact) ? k_own : Real(0)) + ((state & kDualIntact) ? k_dual : Real(0));
  return Real(0.25) * k * stretch * stretch * xi_len;
}

// LPS (Silling et al. 2007; [Fukuda PD] eqs. 6-8 with the 3/m factor restored).
// Per-particle coefficients: 3D dilatation_factor = 3, bulk term 3K, shear term 15 mu;
// 2D (Le, Silling & Bobaru 2014): dilatation_factor = 2, bulk term 2 K2, shear term 8 mu.
struct LpsCoefficients {
  double dilatation_factor;  // d: theta = d/m * sum(w |xi| e V)
  double bulk_term;          // 3K (3D) or 2K2 (2D)
  double shear_term;         // 15 mu (3D) or 8 mu (2D)
};

// lps_force_state's per-particle factors, bulk theta / m and shear / m with theta and d: the
// general force loop forms its own particle's once per pass and reads each neighbour's from
// the dilatation pass (PdViewT::lps_factors) instead of three divisions per bond and end.
// The same operations in the same order, so the same bits as forming them per bond.
template <class Real>
struct LpsForceFactors {
  Real bulk_theta_m = Real(0), shear_m = Real(0), theta = Real(0), d = Real(1);
};

template <class Real>
BRECCIA_HD LpsForceFactors<Real> lps_force_factors(const LpsCoefficients& c, Real m, SameReal<Real> theta) {
  const Real d = static_cast<Real>(c.dilatation_factor);
  const Real bulk = static_cast<Real>(c.bulk_term), shear = static_cast<Real>(c.shear_term);
  return LpsForceFactors<Real>{bulk * theta / m, shear / m, theta, d};
}

// Scalar force state t<xi> of one bond seen from a particle with weighted volume m and
// dilatation theta; w = omega * beta * V_neighbour is carried separately by the caller.
// (The coefficients stay double per particle; they enter in the working precision.)
template <class Real>
BRECCIA_HD Real lps_force_state(const LpsForceFactors<Real>& f, SameReal<Real> omega, SameReal<Real> xi_len,
                                SameReal<Real> extension) {
  const Real deviatoric_extension = extension - f.theta * xi_len / f.d;
  return f.bulk_theta_m * omega * xi_len + f.shear_m * omega * deviatoric_extension;
}

template <class Real>
BRECCIA_HD Real lps_force_state(const LpsCoefficients& c, Real m, SameReal<Real> theta, SameReal<Real> omega,
                                SameReal<Real> xi_len, SameReal<Real> extension) {
  return lps_force_state(lps_force_factors(c, m, theta), omega, xi_len, extension);
}

// Strain energy density of an LPS particle: K_d theta^2 / 2 + (shear/(2m)) sum w e_d^2 V.
// bulk_term / dilatation_factor = K (3D) or K2 (2D).
BRECCIA_HD double lps_bulk_energy(const LpsCoefficients& c, double theta) {
  return 0.5 * (c.bulk_term / c.dilatation_factor) * theta * theta;
}

// Velocity Verlet half kick + drift for one particle component.
BRECCIA_HD void verlet_kick(double* v, const double* a, double half_dt, int64_t k) { v[k] += half_dt * a[k]; }

// Bilinear softening bond (materials[].tensile_strength; docs/theory.md "Quasi-brittle
// bonds"): the bond force is linear in the stretch up to the onset s_t = sigma_t / E, then
// falls linearly to zero at the ultimate stretch s_u, where the bond breaks. In damage form
// f = (1 - d) c s with d = 1 - (s_t / s) (s_u - s) / (s_u - s_t) on the loading path; d
// never decreases, and a bond unloads along its secant (to the origin). The area under the
// law is c s_t s_u / 2, against c s0^2 / 2 of a brittle bond: s_u = s0^2 / s_t gives the same
// fracture energy G0 whatever the horizon, while s_t alone sets the strength.
template <class Real>
BRECCIA_HD Real softening_damage(Real s, SameReal<Real> onset, SameReal<Real> ultimate) {
  if (s <= onset) return Real(0);
  if (s >= ultimate) return Real(1);
  return Real(1) - (onset / s) * (ultimate - s) / (ultimate - onset);
}

// Energy a softening bond has dissipated on reaching damage d along its loading path, in
// units of its energy factor U (a PMB half-bond's energy is U s^2 at stretch s, intact): the
// work done on it up to the stretch s(d) where the law reaches d, less the energy it still
// stores, (1 - d) s(d)^2. 0 at d = 0, s_t s_u at d = 1 (the triangle). Used as
// released = U (D(d_new) - D(d_old)), exact for any step size along the law.
BRECCIA_HD double softening_dissipation(double d, double onset, double ultimate) {
  if (d <= 0.0) return 0.0;
  if (d >= 1.0 || ultimate <= onset) return onset * ultimate;
  const double s = onset * ultimate / ((1.0 - d) * (ultimate - onset) + onset);
  const double work = onset * onset + 2.0 * onset / (ultimate - onset) * (ultimate * (s - onset) - 0.5 * (s * s - onset * onset));
  return work - (1.0 - d) * s * s;
}

// Rate-dependent tensile strength of softening bonds (materials[].strength_rate; docs/theory.md
// "Rate-dependent strength"): the dynamic increase factor DIF = f_ct,imp / f_ct that multiplies
// a bond's onset stretch at the stretch rate it has when it first reaches it.
enum class StrengthRateLaw : int { None = 0, FibMC2010 = 1 };

// fib Model Code 2010 (fib 2013), section 5.1.11 "concrete under impact", tensile strength
// (docs/references.md [fib 2013]; the equation numbers are not checked: we do not hold the text):
//   f_ct,imp / f_ct = (rate / rate0)^0.018            for rate <= 10 s^-1
//                   = 0.0062 (rate / rate0)^(1/3)      for rate >  10 s^-1,   rate0 = 1e-6 s^-1.
// (The two branches meet at 10 s^-1 to 0.07%.) Below rate0, and for a bond that shortens, 1:
// the static strength is the floor.
BRECCIA_HD double strength_dif(int law, double rate) {
  if (law != static_cast<int>(StrengthRateLaw::FibMC2010)) return 1.0;
  constexpr double rate0 = 1e-6;
  if (!(rate > rate0)) return 1.0;
  return rate <= 10.0 ? std::pow(rate / rate0, 0.018) : 0.0062 * std::cbrt(rate / rate0);
}

// Borehole pressure ([Fukuda PD], eq. 12): P0 (e^-at - e^-bt) / (e^-a t0 - e^-b t0), with a and b
// from the rise time t0 and the ratio r = b/a: t0 = ln(r) / (b - a).
BRECCIA_HD double double_exponential_pressure(double peak, double rise_time, double ratio, double t) {
  const double a = std::log(ratio) / ((ratio - 1.0) * rise_time);
  const double b = ratio * a;
  const double norm = std::exp(-a * rise_time) - std::exp(-b * rise_time);
  return t < 0.0 ? 0.0 : peak * (std::exp(-a * t) - std::exp(-b * t)) / norm;
}

// Deterministic per-bond uniform random number in (0,1): the same for (i,j) and (j,i),
// independent of thread count and particle order (hash of the particles' ids and the seed).
BRECCIA_HD double bond_uniform(uint64_t id_a, uint64_t id_b, uint64_t seed) {
  uint64_t lo = id_a < id_b ? id_a : id_b, hi = id_a < id_b ? id_b : id_a;
  uint64_t z = seed ^ (lo * 0x9E3779B97F4A7C15ull) ^ (hi + 0x632BE59BD9B4E019ull + (lo << 6) + (lo >> 2));
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z = z ^ (z >> 31);
  return (static_cast<double>(z >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

}  // namespace breccia::solver
