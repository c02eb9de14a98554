#pragma once
// Per-particle kernels over raw views: the loop bodies both backends run. A backend only
// decides how `for i in [0, n)` is launched (OpenMP here, CUDA in solver/cuda/).
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "breccia/solver/host_pack.hpp"
#include "breccia/solver/pd_physics.hpp"

#if defined(BRECCIA_HOST_PACK)
// The packed rows' helpers return 32-byte packs (PackedBond<PackD4>): always inlined into AVX
// functions (host_pack.hpp, on_avx_pack), so GCC's ABI note (-Wpsabi) does not apply.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace breccia::solver {

// Everything a kernel reads or writes, as raw pointers (structure of arrays). Real is the
// working precision of the bond loop and of the state it streams (double; float for
// model.precision: float32). The per-particle diagnostics (energy density, damage, dissipated
// energy, max stretch) stay double: they are written once per particle on output steps and
// summed over the body, where float would lose the small terms.
template <class Real>
struct PdViewT {
  int64_t n = 0;
  int model = 0;  // PdModel
  bool fracture = true;
  // Damage, energy density and max stretch are only needed on output/history steps.
  bool diagnostics = true;
  // One constant horizon: both halves of every entry are equal (k_own == k_dual,
  // s0_own == s0_dual, both bits set together), so the kernel reads one of each.
  bool symmetric_halves = false;
  const Real* x0 = nullptr;   // 3N reference positions (float: relative to the body's centre)
  const Real* x = nullptr;    // 3N current positions x0 + u (optional, double only: fast paths)
  Real* u = nullptr;          // 3N displacement
  Real* v = nullptr;          // 3N velocity
  Real* a = nullptr;          // 3N acceleration
  Real* force = nullptr;      // 3N internal force density [N/m3]
  const Real* body = nullptr; // 3N external force density [N/m3]
  const Real* volume = nullptr;
  const Real* density = nullptr;
  const uint8_t* fixed_dof = nullptr;  // N, bit d set: component d is prescribed
  // bonds, CSR over full families
  const int64_t* offsets = nullptr;
  const int32_t* neighbor = nullptr;
  const Real* xi_len = nullptr;
  const Real* k_own = nullptr;   // PMB: c_half*omega*beta*V_j; LPS: omega*beta (own horizon)
  const Real* k_dual = nullptr;  // same for the neighbour's horizon
  // The own halves' volumes beta*V_j in the own horizon (damage weights): read through
  // own_volume / own_half_exists below, never directly. With the analytic partial volume
  // (model.partial_volume: lammps) vol_own holds them; where set-up counted samples (sampled,
  // the default) vol_own is null and own_count holds each entry's own sample count, the
  // volume formed from it (counted_own_volume, pd_physics.hpp) from the partner's volume in
  // double (volume_exact: `volume` in the double view, the double copy in the float one) and
  // the count's fraction (sample_fraction: partial_volume_sample_fractions, pd_physics.hpp, or
  // its device copy): the bits the array held, 1 B per entry instead of 8 (4 in float).
  const Real* vol_own = nullptr;
  const uint8_t* own_count = nullptr;
  const double* volume_exact = nullptr;
  const double* sample_fraction = nullptr;
  // Per particle, the damage's denominator: the own halves' volumes of its row (own_volume,
  // as Real) summed in double in row order from 0, whatever the entries' states, a constant of
  // the run (family_volume below; PdSystem::family_volume, Float32State::family_volume). Null:
  // the diagnostic passes sum it over the row themselves (views built by hand).
  const double* family_volume = nullptr;
  const float* s0_own = nullptr;   // critical stretch of each half-bond
  const float* s0_dual = nullptr;
  uint8_t* state = nullptr;        // kOwnIntact | kDualIntact
  // Silling & Askari's compressive enhancement (model.compressive_enhancement): a bond breaks
  // at s0 - alpha max(s_min_i, s_min_j), s_min the smallest stretch over a particle's intact
  // bonds at the previous step's force pass (min_stretch, read) and at this one
  // (min_stretch_next, written by the owner; each step begins by swapping the two,
  // commit_min_stretch). Null: fixed s0.
  float alpha = 0.0f;
  const float* min_stretch = nullptr;
  float* min_stretch_next = nullptr;
  // Softening bonds (pd_physics.hpp softening_damage): per entry the onset stretch (s0_own is
  // then the ultimate one) and the damage, written by the entry's owner. Null: brittle.
  // With a strength rate law (StrengthRateLaw, materials[].strength_rate) the onset of an entry
  // that has not begun to soften is the static one times strength_dif at its stretch rate, and
  // the owner writes that dynamic onset into s_onset when it begins to soften (soften()).
  // The rate law raises the ultimate stretch with the onset (self-similar law): it writes the
  // entry's raised ultimate through s_ultimate, the storage s0_own reads (one float per entry).
  float* s_onset = nullptr;
  float* s_ultimate = nullptr;
  float* bond_damage = nullptr;
  int strength_rate = 0;  // StrengthRateLaw; None: the onset is s_onset as set up
  // Crushing (materials[].compressive_strength): a softening entry shortened past
  // crush_ratio x its onset follows the same bilinear law in compression, onset and ultimate
  // both scaled by crush_ratio = f_c / sigma_t (one per case); 0: elastic in compression.
  float crush_ratio = 0.0f;
  // model.break_check: after_force (LAMMPS PERI's order) lets a bond that breaks in this pass
  // carry its force once more; before_force (default) drops it from this pass on.
  bool break_after_force = false;
  // Short-range forces (model.short_range_forces; short_range_kernel): per particle
  // 15 c / delta [N/m^7] and the particle spacing. Null: none.
  const Real* short_range_k = nullptr;
  const Real* spacing = nullptr;
  // LPS per particle
  const LpsCoefficients* lps = nullptr;
  const Real* weighted_volume = nullptr;  // m_i
  Real* dilatation = nullptr;             // theta_i
  // Optional per-particle LPS factors for the fast path: t_i = omega (A_i |xi| + B_i e),
  // A_i = theta_i (c_b - c_s/d) / m_i, B_i = c_s / m_i (filled by the dilatation pass).
  Real* lps_a = nullptr;
  Real* lps_b = nullptr;
  // Optional per-particle lps_force_factors (pd_physics.hpp), written by the dilatation pass
  // with theta_i: the general force loop reads a neighbour's instead of dividing per bond.
  LpsForceFactors<Real>* lps_factors = nullptr;
  // per-particle outputs
  double* energy_density = nullptr;   // W_i [J/m3]
  double* dissipated = nullptr;       // energy released by bonds broken this step, per particle [J]
  double* damage = nullptr;
  double* max_stretch = nullptr;      // optional
};
using PdView = PdViewT<double>;

// Entry k's own half's volume beta*V_j (vol_own's note above): the stored value, or the one
// formed from its sample count, rounded to Real as the float copy of the array was.
template <class Real>
BRECCIA_HD Real own_volume(const PdViewT<Real>& p, int64_t k) {
  if (p.own_count) return static_cast<Real>(counted_own_volume(p.own_count[k], p.sample_fraction, p.volume_exact[p.neighbor[k]]));
  return p.vol_own[k];
}
// Particle i's family volume summed over its `count` entries, the q-th at index `at(q)`, in
// row order: the own halves' volumes as Real (own_volume), added in double from 0. The damage
// weights' total (1 - intact / total) in every diagnostic pass; the one loop that forms
// PdSystem::family_volume (family_volumes, setup.cpp), so the stored values are its bits.
template <class Real, class At>
BRECCIA_HD double summed_family_volume(const PdViewT<Real>& p, int64_t count, const At& at) {
  double v = 0.0;
  for (int64_t q = 0; q < count; ++q) v += own_volume(p, at(q));
  return v;
}
template <class Real>
BRECCIA_HD double summed_family_volume(const PdViewT<Real>& p, int64_t i) {  // i's CSR row
  double v = 0.0;
  for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) v += own_volume(p, k);
  return v;
}
// The diagnostic passes' family volume of particle i: the view's stored one where it holds
// them (summed once by the loop above), else summed over the row here.
template <class Real, class At>
BRECCIA_HD double family_volume(const PdViewT<Real>& p, int64_t i, int64_t count, const At& at) {
  return p.family_volume ? p.family_volume[i] : summed_family_volume(p, count, at);
}
template <class Real>
BRECCIA_HD double family_volume(const PdViewT<Real>& p, int64_t i) {
  return p.family_volume ? p.family_volume[i] : summed_family_volume(p, i);
}
// Does entry k's own half exist (j in i's horizon: beta*V_j > 0)? A count > 0 exactly when
// the volume formed from it is (volumes are positive: particle_file.cpp).
template <class Real>
BRECCIA_HD bool own_half_exists(const PdViewT<Real>& p, int64_t k) {
  return p.own_count ? p.own_count[k] != 0 : p.vol_own[k] > Real(0);
}

// The deformed bond vector j - i and its extension |xi + eta| - |xi|, computed the way each
// precision keeps them. Double gathers the current positions x (one array) and subtracts
// the lengths, as it always has. Float forms xi + eta from the reference and displacement
// differences (x0 + u in float would round a small u away against the coordinate), and
// the extension without cancellation, e = (2 xi.eta + eta.eta) / (|xi + eta| + |xi|):
// |xi + eta| - |xi| in float has an absolute error of u |xi| (a stretch error of 6e-8 at any
// strain), the quotient a relative one of a few u (docs/theory.md, Precision).
// `BondOriginT` holds what particle i contributes, read once per particle.
template <class Real>
struct BondOriginT {
  static constexpr bool kRelative = !std::is_same_v<Real, double>;
  Real px = Real(0), py = Real(0), pz = Real(0), ux = Real(0), uy = Real(0), uz = Real(0);
  BondOriginT() = default;
  BRECCIA_HD BondOriginT(const PdViewT<Real>& p, int64_t i) {
    const Real* pos = kRelative ? p.x0 : p.x;
    px = pos[3 * i]; py = pos[3 * i + 1]; pz = pos[3 * i + 2];
    if (kRelative) { ux = p.u[3 * i]; uy = p.u[3 * i + 1]; uz = p.u[3 * i + 2]; }
    else { ux = uy = uz = Real(0); }
  }
  // The SIMD path's form (kRelative only): returns num = eta.(xi + (xi + eta)), the extension
  // times (len + |xi|), with no division; dx, dy, dz and len as to(). Both of that path's
  // passes call it, so the bond it breaks is the bond it masked.
  BRECCIA_HD Real extension_numerator(const Real* x0, const Real* u, int64_t j, Real& dx, Real& dy, Real& dz,
                                      Real& len) const {
    const Real ax = x0[3 * j] - px, ay = x0[3 * j + 1] - py, az = x0[3 * j + 2] - pz;
    const Real bx = u[3 * j] - ux, by = u[3 * j + 1] - uy, bz = u[3 * j + 2] - uz;
    dx = ax + bx; dy = ay + by; dz = az + bz;
    len = std::sqrt(dx * dx + dy * dy + dz * dz);
    return bx * (ax + dx) + by * (ay + dy) + bz * (az + dz);
  }
  // Returns the extension; dx, dy, dz and len receive the deformed vector and its length.
  BRECCIA_HD Real to(const PdViewT<Real>& p, int64_t j, Real xi_len, Real& dx, Real& dy, Real& dz,
                     Real& len) const {
    if constexpr (kRelative) {
      const Real ax = p.x0[3 * j] - px, ay = p.x0[3 * j + 1] - py, az = p.x0[3 * j + 2] - pz;  // xi (exact)
      const Real bx = p.u[3 * j] - ux, by = p.u[3 * j + 1] - uy, bz = p.u[3 * j + 2] - uz;      // eta
      dx = ax + bx; dy = ay + by; dz = az + bz;
      len = std::sqrt(dx * dx + dy * dy + dz * dz);
      return (Real(2) * (ax * bx + ay * by + az * bz) + (bx * bx + by * by + bz * bz)) / (len + xi_len);
    } else {
      return extension_from(bond_vector(p.x, j, dx, dy, dz), xi_len, len);
    }
  }
  // Double's two halves of to(): the deformed vector to j from the current positions and its
  // squared length, then the length and the extension. The host's PMB loop gathers every
  // entry's vector of a chunk first and runs the rest over the gathered buffers
  // (two_stage_force_loop), with the same operations as to().
  BRECCIA_HD Real bond_vector(const Real* x, int64_t j, Real& dx, Real& dy, Real& dz) const {
    dx = x[3 * j] - px; dy = x[3 * j + 1] - py; dz = x[3 * j + 2] - pz;
    return dx * dx + dy * dy + dz * dz;
  }
  BRECCIA_HD static Real extension_from(Real squared_len, Real xi_len, Real& len) {
    len = std::sqrt(squared_len);
    return len - xi_len;
  }
};

// Can the fast paths gather bond vectors? Double needs the current positions x; float
// always can (reference positions and displacements).
template <class Real>
BRECCIA_HD bool has_bond_vectors(const PdViewT<Real>& p) {
  return !std::is_same_v<Real, double> || p.x != nullptr;
}

// alpha max(s_min_i, s_min_j): what the compressive enhancement takes off the critical
// stretch of bond (i, j) at this pass (Silling & Askari 2005, eq. 23; LAMMPS PairPeriPMB).
// With alpha > 0 a compressed neighbourhood (s_min < 0) raises it; a wholly stretched one
// lowers it.
template <class Real>
BRECCIA_HD Real stretch_shift(const PdViewT<Real>& p, int64_t i, int64_t j) {
  if (!p.min_stretch) return Real(0);
  const float a = p.min_stretch[i], b = p.min_stretch[j];
  return static_cast<Real>(p.alpha * (a > b ? a : b));
}

// Record particle i's smallest stretch of this pass over the bonds intact when it began
// (those that break in it included, as LAMMPS does); 0 for a particle without bonds.
template <class Real>
BRECCIA_HD void store_min_stretch(const PdViewT<Real>& p, int64_t i, double smin, bool any) {
  if (p.min_stretch_next) p.min_stretch_next[i] = any ? static_cast<float>(smin) : 0.0f;
}

// Does entry k follow the softening law? Only in a softening case, and not a pair of a brittle
// material or an unbreakable one (their onset is FLT_MAX, set-up's convert_to_softening).
template <class Real>
BRECCIA_HD bool softens(const PdViewT<Real>& p, int64_t k) {
  return p.bond_damage && p.s_onset[k] < FLT_MAX;
}

// What a softening entry's stretch rate needs: its ends and its deformed vector j - i (length
// len, reference length xi), as the force loops have them.
template <class Real>
struct BondMotionT {
  int64_t i, j;
  Real dx, dy, dz, len, xi;
};

// The bond's stretch rate ds/dt = (v_j - v_i) . n / |xi|, n the deformed direction. The force
// pass runs after the drift, so v is the half-step velocity (x^{n+1} - x^n) / dt: this is the
// stretch change since the previous step over dt (to first order in the step), without storing
// a stretch per entry. (A distributed run's ghosts receive their owners' velocities with their
// displacements under a rate law: solver/mpi/, MpiExec::exchange.)
template <class Real>
BRECCIA_HD double bond_stretch_rate(const PdViewT<Real>& p, const BondMotionT<Real>& b) {
  const Real* v = p.v;
  const double dvx = double(v[3 * b.j]) - double(v[3 * b.i]), dvy = double(v[3 * b.j + 1]) - double(v[3 * b.i + 1]),
               dvz = double(v[3 * b.j + 2]) - double(v[3 * b.i + 2]);
  return (dvx * double(b.dx) + dvy * double(b.dy) + dvz * double(b.dz)) / (double(b.len) * double(b.xi));
}

// The uniaxial strain rate a softening bond's stretch rate stands for, the rate fib's law
// (strength_dif) is stated for. In uniaxial tension at the strain rate R a bond at angle a to
// the load stretches at R (cos^2 a - nu sin^2 a): the bonds that carry the material past its
// first onsets are oblique and see less than R, so the DIF at the bond's own rate gives the
// material less than DIF(R) sigma_t (0.83-0.93 of it on the cube-root branch, depending on
// s_u/s_t). The factor c that corrects it is calibrated, as the static onset is, on the
// homogeneous uniaxial response of the bond mixture with the rate law (3D, nu = 1/4:
// docs/theory.md "Rate-dependent strength"): on the cube-root branch it depends on r = s_u/s_t
// alone, and equals that mixture's static peak per unit onset Phi(r) (the Calibration table)
// within 1% from r = 3 to 100, so c = Phi(r), interpolated in ln r from the values below
// (180 directions, steps of s_t/100; 1 at r = 1, where the law is brittle; held above 1000).
// The table's point q (0 to 13): r and Phi(r). A switch, not an array: an array indexed at run
// time lives in local memory on the device (ptxas gave every force kernel with a softening path
// a 224-byte stack frame for these two tables).
BRECCIA_HD void bond_rate_point(int q, double& r, double& phi) {
  switch (q) {
    case 0: r = 1.0, phi = 1.0; return;
    case 1: r = 1.5, phi = 1.0842; return;
    case 2: r = 2.0, phi = 1.1434; return;
    case 3: r = 3.0, phi = 1.2248; return;
    case 4: r = 5.0, phi = 1.3228; return;
    case 5: r = 7.0, phi = 1.3838; return;
    case 6: r = 10.0, phi = 1.4449; return;
    case 7: r = 20.0, phi = 1.5521; return;
    case 8: r = 30.0, phi = 1.6073; return;
    case 9: r = 50.0, phi = 1.6692; return;
    case 10: r = 100.0, phi = 1.7402; return;
    case 11: r = 200.0, phi = 1.7976; return;
    case 12: r = 500.0, phi = 1.8558; return;
    default: r = 1000.0, phi = 1.8891; return;
  }
}
BRECCIA_HD double bond_rate_factor(double ultimate_over_onset) {
  constexpr int kPoints = 14;
  double r0, phi0;
  bond_rate_point(0, r0, phi0);
  if (!(ultimate_over_onset > r0)) return phi0;
  for (int q = 1; q < kPoints; ++q) {
    double r1, phi1;
    bond_rate_point(q, r1, phi1);
    if (ultimate_over_onset <= r1) {
      const double t = std::log(ultimate_over_onset / r0) / std::log(r1 / r0);
      return phi0 + t * (phi1 - phi0);
    }
    r0 = r1;
    phi0 = phi1;
  }
  return phi0;
}

// The ultimate stretch of an entry whose onset the rate law raised from `onset` to `raised`:
// `ultimate` scaled by the same factor (self-similar law). One expression in floats, so that a
// restart rebuilds the checkpointed ultimate bit for bit from the set-up's onset and ultimate
// and the checkpointed onset (read_checkpoint).
BRECCIA_HD float raised_ultimate(float onset, float raised, float ultimate) {
  return static_cast<float>(double(ultimate) * (double(raised) / double(onset)));
}

// A system takes `count` onsets a rate law may have raised (a checkpoint's, or the global
// system's rows for a rank): each entry whose onset differs gets the raised onset and, where
// the system holds its ultimates (`ultimate` not null), the ultimate raised with it from the
// system's own (the set-up's) by raised_ultimate. Host only.
inline void adopt_raised_onsets(float* onset, float* ultimate, const float* raised, size_t count) {
  for (size_t k = 0; k < count; ++k) {
    if (raised[k] == onset[k]) continue;
    if (ultimate) ultimate[k] = raised_ultimate(onset[k], raised[k], ultimate[k]);
    onset[k] = raised[k];
  }
}

// The rule for taking raised onsets `raised` (a checkpoint's, or a rank's rows of the global
// system's) into arrays `onset` and `ultimate`: arrays of another size (a system that holds
// none of them yet: a distributed run's global system, whose rows are in the ranks' systems)
// take the raised onsets as they are; arrays of the same size adopt them (adopt_raised_onsets),
// the ultimates with them where held for the same entries. Host only.
inline void take_raised_onsets(std::vector<float>& onset, std::vector<float>& ultimate, const std::vector<float>& raised) {
  if (onset.size() != raised.size()) {
    onset = raised;
    return;
  }
  adopt_raised_onsets(onset.data(), ultimate.size() == raised.size() ? ultimate.data() : nullptr, raised.data(),
                      raised.size());
}

// One softening bond entry at stretch s this pass (softens(p, k)): the damage it reaches
// (never below what it had), stored unless fracture is off, and the energy that dissipated,
// `unit` x (D(d) - D(d_old)) with unit the entry's energy per unit stretch squared (a PMB
// half-bond: V_i k2 |xi| / 4). Returns d; d = 1 means broken (the caller clears the state).
// Rate law (p.strength_rate): while the entry is undamaged its law is the static one scaled by
// F = strength_dif at the material strain rate its stretch rate stands for
// (bond_rate_factor): onset and ultimate stretch both times F, so a material point whose
// bonds share F peaks at F times its static strength whatever s_u/s_t (the homogeneous peak
// Phi depends on s_u/s_t alone); the rate is only formed once s passes the static onset
// (F >= 1, so below it nothing can soften). The law the entry has when it begins to soften is
// written into s_onset and s_ultimate and kept: the law of a softening bond is then fixed, so
// D(d) stays the energy it dissipates (F^2 times the static triangle; docs/theory.md
// "Rate-dependent strength").
template <class Real>
BRECCIA_HD double soften(const PdViewT<Real>& p, int64_t k, double s, double unit, double& released,
                         const BondMotionT<Real>& motion) {
  const double d_old = p.bond_damage[k];
  if (!p.fracture) return d_old;
  double onset = p.s_onset[k];
  double ultimate = p.s0_own[k];
  if (s < 0.0) {  // crushing: one damage for both signs, so D(d) of the law in force stays exact
    if (!(p.crush_ratio > 0.0f)) return d_old;
    const double c_onset = double(p.crush_ratio) * onset, c_ultimate = double(p.crush_ratio) * ultimate;
    const double d = softening_damage<double>(-s, c_onset, c_ultimate);
    if (d <= d_old) return d_old;
    released += unit * (softening_dissipation(d, c_onset, c_ultimate) - softening_dissipation(d_old, c_onset, c_ultimate));
    p.bond_damage[k] = static_cast<float>(d);
    return d;
  }
  const bool dynamic_onset = p.strength_rate && d_old <= 0.0 && s > onset;
  if (dynamic_onset) {
    const double stretch_rate = bond_stretch_rate(p, motion);
    // Damage grows only while the bond is loaded (the loading condition of damage mechanics):
    // an entry past its static onset whose stretch is falling (a particle's vibration) does
    // not begin to soften at this step; it does at the next step that stretches it, at the DIF
    // of that step's rate. Taken here instead, a falling stretch gave DIF 1, and the smallest
    // DIF along the way set the bond's law (docs/theory.md "Rate-dependent strength").
    if (stretch_rate < 0.0) return d_old;
    const double uniaxial_rate = bond_rate_factor(ultimate / onset) * stretch_rate;
    const float raised = static_cast<float>(onset * strength_dif(p.strength_rate, uniaxial_rate));
    ultimate = raised_ultimate(p.s_onset[k], raised, p.s0_own[k]);
    onset = raised;
  }
  const double d = softening_damage<double>(s, onset, ultimate);
  if (d <= d_old) return d_old;
  released += unit * (softening_dissipation(d, onset, ultimate) - softening_dissipation(d_old, onset, ultimate));
  const float stored = static_cast<float>(d);
  p.bond_damage[k] = stored;
  if (dynamic_onset && stored > 0.0f) {  // fixed while d > 0 is stored
    p.s_onset[k] = static_cast<float>(onset);
    p.s_ultimate[k] = static_cast<float>(ultimate);
  }
  return d;
}

// Is softening entry k quiet at stretch s: undamaged, stretched no further than its onset, and
// not compressed where bonds crush? Then soften(p, k, s, ...) would return its damage 0 and
// change nothing (no damage stored, nothing released, no onset raised: the rate law acts only
// past the onset), so a loop may keep the entry's whole force without forming its energy unit
// or calling it. The contract is tested against soften itself (Softening.QuietEntriesAreTheOnesSoftenLeavesAlone).
// Host only: on the device the test added 8 B to the CSR force kernel's spills in double
// (scripts/cuda_registers.sh, docs/cuda.md "Registers"), a cost no GPU run has weighed against
// the call it saves, so the device sends every softening entry through soften as before.
template <class Real>
BRECCIA_HD bool softening_entry_quiet(const PdViewT<Real>& p, int64_t k, double s) {
#if defined(__CUDA_ARCH__)
  (void)p;
  (void)k;
  (void)s;
  return false;
#else
  return p.bond_damage[k] == 0.0f && s <= double(p.s_onset[k]) && (s >= 0.0 || !(p.crush_ratio > 0.0f));
#endif
}

// Particle i's force sums over its row. PMB with one constant horizon (every path: the packed
// rows, the two-stage and one-entry loops, the device's, the SELL lanes', the diagnostic loop)
// keeps four partial sums per component, entry q of the row added to sum q mod 4 in row order,
// and combines them as (s0 + s1) + (s2 + s3) (kFour). One sum per component, every entry added
// in row order, would be a chain of dependent additions, one per entry: on the host that chain
// bounded the packed PMB loop once its square roots and divisions ran 4 wide (docs/performance-log.md,
// "The packed rows 4 wide, four partial sums"); four sums run four chains side by side. LPS and
// the general loops keep one sum (kFour false: every add goes to s0). A sum starts at +0 and
// never becomes -0, so adding a masked entry's +0 leaves it unchanged whichever sum it goes to.
template <class Real, bool kFour>
struct RowForceSums {
  Real x[4] = {Real(0), Real(0), Real(0), Real(0)}, y[4] = {Real(0), Real(0), Real(0), Real(0)},
       z[4] = {Real(0), Real(0), Real(0), Real(0)};
  // Entry q's force, r = q mod 4 (a constant where the caller's loop is unrolled by 4).
  BRECCIA_HD void add(int r, Real cx, Real cy, Real cz) {
#if defined(__CUDA_ARCH__)
    // On the device a run-time index into the sums puts all twelve in local memory (ptxas
    // reported a 320-byte stack frame for the CSR force kernel): the switch keeps them in
    // registers, and folds away where r is a constant. The same additions, the same bits.
    if constexpr (kFour) {
      switch (r) {
        case 0: add_to<0>(cx, cy, cz); return;
        case 1: add_to<1>(cx, cy, cz); return;
        case 2: add_to<2>(cx, cy, cz); return;
        default: add_to<3>(cx, cy, cz); return;
      }
    }
    add_to<0>(cx, cy, cz);
#else
    const int s = kFour ? r : 0;
    x[s] += cx;
    y[s] += cy;
    z[s] += cz;
#endif
  }
  template <int kS>
  BRECCIA_HD void add_to(Real cx, Real cy, Real cz) {
    x[kS] += cx;
    y[kS] += cy;
    z[kS] += cz;
  }
  BRECCIA_HD static Real total(const Real (&v)[4]) { return kFour ? (v[0] + v[1]) + (v[2] + v[3]) : v[0]; }
  BRECCIA_HD void store(Real* force) const {
    force[0] = total(x);
    force[1] = total(y);
    force[2] = total(z);
  }
};

// The fast bond loops between output steps (one constant horizon, brittle bonds, no
// compressive enhancement) run in two stages over chunks of kBondChunk entries: a
// branch-free stage that computes every entry's force contribution and whether it breaks
// (broken and breaking entries masked to +0), which the compiler runs several entries at
// once (SIMD: sqrt and division dominate the scalar loop), then a scalar stage that adds the
// contributions in the entry order and marks the bonds that broke. The sums therefore keep
// each particle's order, so the result is the scalar loop's bit for bit on any instruction
// set, and the CUDA build (one entry per iteration, no buffer) agrees with it. Adding the +0
// of a masked entry changes nothing: a sum that starts at +0 never becomes -0.
inline constexpr int kBondChunk = 64;
static_assert(kBondChunk % 4 == 0, "a chunk starts at a multiple of 4 entries from its row's start (RowForceSums)");

// Are the own halves of all m entries of a chunk from `base` intact? Then the host's two
// stages run a copy of the entry without its state test (kCheckState false): in a run most
// chunks have no broken entry, and the test (a byte widened to a lane mask and a select per
// entry) measured 11 % of LPS's loop (docs/performance-log.md, "Bond state in bits"). The own bit
// of the AND of the state bytes is set only if every byte has it. The unchecked entries test
// the own half (lps_dilatation_entry) or, with one constant horizon, where both bits go
// together, any bit (pmb_fast_entry, lps_fast_entry), so the results are the checked copy's bit
// for bit. (Testing for any shared bit would be wrong with variable horizons: a chunk whose
// entries all keep their dual half would add own halves that broke to LPS's dilatation.)
// A bit per entry would make this test one word per chunk, but the byte test is a few vector
// ANDs per 64 entries, and every other reader of the state (checkpoints, outputs, the general
// loops) keeps its bytes.
template <class Real>
BRECCIA_HD bool chunk_intact(const PdViewT<Real>& p, int64_t base, int m) {
  uint8_t all = 0xff;
  for (int q = 0; q < m; ++q) all &= p.state[base + q];
  return (all & kOwnIntact) != 0;
}

// Is particle i's PMB or LPS pass free of per-entry state beyond the intact flag (the fast
// loops' condition)? Diagnostics are compiled out by the callers.
template <class Real>
BRECCIA_HD bool fast_bond_loop(const PdViewT<Real>& p) {
  return !p.min_stretch && !p.min_stretch_next && !p.bond_damage;
}

// LPS's brittle terms, for one entry (V = Real) or a pack of entries (the host's PackD2/PackD4,
// lps_packed_dilatation_row and lps_packed_row): the first pass's omega beta |xi| e V_j, and
// the force pass's force density over length t V_j / |xi + eta| with t = omega ((A_i + A_j)
// |xi| + (B_i + B_j) e) (lps_symmetric_force_kernel).
template <class V>
BRECCIA_HD V lps_dilatation_term(V omega, V xi, V extension, V volume_j) {
  return omega * xi * extension * volume_j;
}
template <class V>
BRECCIA_HD V lps_fast_density(V omega, V a_sum, V b_sum, V xi, V e, V volume_j, V len) {
  const V t = omega * (a_sum * xi + b_sum * e);
  return t * volume_j / len;
}

// One entry's term of the LPS first pass through gathered bond vectors, brittle bonds:
// omega beta |xi| e V_j for an intact own half, else +0 (formed for every entry, then selected).
template <bool kCheckState = true, class Real>
BRECCIA_HD Real lps_dilatation_entry(const PdViewT<Real>& p, const BondOriginT<Real>& origin, int64_t k) {
  const int64_t j = p.neighbor[k];
  Real dx, dy, dz, len;
  const Real extension = origin.to(p, j, p.xi_len[k], dx, dy, dz, len);
  const Real term = lps_dilatation_term(p.k_own[k], p.xi_len[k], extension, p.volume[j]);
  if constexpr (!kCheckState) return term;  // chunk_intact
  return (p.state[k] & kOwnIntact) ? term : Real(0);
}

// The end of LPS's first pass, from the sum over particle i's intact own bonds (the CSR loop
// below and the SELL lanes of sell_kernels.hpp): theta_i and the fast path's factors.
template <class Real>
BRECCIA_HD void lps_store_dilatation(const PdViewT<Real>& p, int64_t i, Real sum) {
  const Real theta = static_cast<Real>(p.lps[i].dilatation_factor) * sum / p.weighted_volume[i];
  p.dilatation[i] = theta;
  if (p.lps_factors) p.lps_factors[i] = lps_force_factors(p.lps[i], p.weighted_volume[i], theta);
  if (p.lps_a) {
    const LpsCoefficients& c = p.lps[i];
    p.lps_a[i] = theta * static_cast<Real>(c.bulk_term - c.shear_term / c.dilatation_factor) / p.weighted_volume[i];
    p.lps_b[i] = static_cast<Real>(c.shear_term) / p.weighted_volume[i];
  }
}

#if defined(BRECCIA_HOST_PACK)
// The host's bond vectors of entries k .. k + lanes - 1 from particle i (origin) in double, P
// a host pack (host_pack.hpp): x_j - x_i per component (BondOriginT::bond_vector, lane by lane).
template <class P>
struct PackedBond {
  P dx, dy, dz;
  BRECCIA_PACK_INLINE P squared_length() const { return dx * dx + dy * dy + dz * dz; }
};
template <class P>
BRECCIA_PACK_INLINE PackedBond<P> packed_bond(const PdViewT<double>& p, const BondOriginT<double>& origin, int64_t k) {
  const int32_t* j = p.neighbor + k;
  return {gather_pack<P>(p.x, j, 3, 0) - origin.px, gather_pack<P>(p.x, j, 3, 1) - origin.py,
          gather_pack<P>(p.x, j, 3, 2) - origin.pz};
}

// LPS's first pass in double on the host for a row whose own halves are all intact: the terms
// a pack P at a time and their sum in the entry order in the same loop (pmb_packed_row), so
// the sum is the two-stage loop's bit for bit, at either width. False, with `sum` untouched,
// for a row with an own half broken (the two-stage loop selects).
template <class P>
inline bool lps_packed_dilatation_row(const PdViewT<double>& p, int64_t i, const BondOriginT<double>& origin,
                                      double& sum) {
  constexpr int kLanes = kPackLanes<P>;
  const int64_t begin = p.offsets[i], end = p.offsets[i + 1];
  if (end > begin && !chunk_intact(p, begin, static_cast<int>(end - begin))) return false;
  double total = 0.0;
  int64_t k = begin;
  for (; k + kLanes <= end; k += kLanes) {
    const P xi = load_pack<P>(p.xi_len + k);
    const P extension = sqrt_of(packed_bond<P>(p, origin, k).squared_length()) - xi;  // BondOriginT::extension_from
    const P term = lps_dilatation_term(load_pack<P>(p.k_own + k), xi, extension, gather_pack<P>(p.volume, p.neighbor + k, 1, 0));
    for (int l = 0; l < kLanes; ++l) total += term[l];
  }
  for (; k < end; ++k) total += lps_dilatation_entry<false>(p, origin, k);
  sum = total;
  return true;
}
#endif

// A CSR row: its q-th entry is at begin + q (general_force_row, ordered_fast_loop).
struct CsrRow {
  int64_t begin;
  BRECCIA_HD int64_t operator()(int64_t q) const { return begin + q; }
};

// After a broken entry at row position q (state byte 0), the last position of the run of
// zero state bytes that follows it, taken 8 bytes at a time on the host, so that a row of a
// broken-up body (a pulverised block's grains: most rows have no bond left) costs a load per
// 8 entries instead of a branch per entry. Only whole zero words are skipped: every entry
// skipped is one the loop would have passed over (`if (!st) continue`), so the sums are the
// same bits. The device and a SELL lane (strided entries) keep the one-entry step: q itself.
template <class At>
BRECCIA_HD int64_t last_of_zero_run(const uint8_t* state, const At& at, int64_t q, int64_t count) {
#if !defined(__CUDA_ARCH__)
  if constexpr (std::is_same_v<At, CsrRow>) {
    const uint8_t* row = state + at(0);
    int64_t next = q + 1;
    while (next + 8 <= count) {
      uint64_t word;
      std::memcpy(&word, row + next, sizeof word);
      if (word != 0) break;
      next += 8;
    }
    return next - 1;
  }
#endif
  (void)state;
  (void)at;
  (void)count;
  return q;
}

// LPS first pass: theta_i = d/m_i * sum_j omega beta |xi| e V_j over intact own bonds.
template <class Real>
BRECCIA_HD void lps_dilatation_kernel(const PdViewT<Real>& p, int64_t i) {
  Real sum = Real(0);
  const bool gather = has_bond_vectors(p);
  const BondOriginT<Real> origin = gather ? BondOriginT<Real>(p, i) : BondOriginT<Real>();
#if !defined(__CUDA_ARCH__)
#if defined(BRECCIA_HOST_PACK)
  if constexpr (!BondOriginT<Real>::kRelative)
    if (gather && !p.bond_damage && on_host_pack([&](auto pack) {
          return lps_packed_dilatation_row<typename decltype(pack)::type>(p, i, origin, sum);
        })) {
      lps_store_dilatation(p, i, sum);
      return;
    }
#endif
  if (gather && !p.bond_damage) {  // the fast loops' two stages (kBondChunk): every term, then the sum in order
    Real term[kBondChunk];
    for (int64_t base = p.offsets[i]; base < p.offsets[i + 1]; base += kBondChunk) {
      const int m = static_cast<int>(p.offsets[i + 1] - base < kBondChunk ? p.offsets[i + 1] - base : kBondChunk);
      const auto stage = [&](auto check_state) {  // with or without the state test (chunk_intact)
BRECCIA_SIMD
        for (int q = 0; q < m; ++q) term[q] = lps_dilatation_entry<decltype(check_state)::value>(p, origin, base + q);
      };
      if (chunk_intact(p, base, m)) stage(std::false_type{});
      else stage(std::true_type{});
      for (int q = 0; q < m; ++q) sum += term[q];
    }
  } else
#endif
  {
    const int64_t row_begin = p.offsets[i], row_count = p.offsets[i + 1] - row_begin;
    for (int64_t q = 0; q < row_count; ++q) {
      const int64_t k = row_begin + q;
      if (!(p.state[k] & kOwnIntact)) {
        if (!p.state[k]) q = last_of_zero_run(p.state, CsrRow{row_begin}, q, row_count);
        continue;
      }
      const int64_t j = p.neighbor[k];
      Real extension;
      if (gather) {
        Real dx, dy, dz, len;
        extension = origin.to(p, j, p.xi_len[k], dx, dy, dz, len);
      } else {
        extension = bond_geometry(p.x0, p.u, i, j, p.xi_len[k]).extension;
      }
      const Real weight = p.bond_damage ? Real(1) - static_cast<Real>(p.bond_damage[k]) : Real(1);
      sum += weight * p.k_own[k] * p.xi_len[k] * extension * p.volume[j];
    }
  }
  lps_store_dilatation(p, i, sum);
}

// One LPS entry of the fast loop (lps_symmetric_force_kernel between output steps): the force
// contribution on i (+0 when broken, or breaking with break_check before_force) and whether it
// breaks now.
template <bool kCheckState = true, class Real>
BRECCIA_HD bool lps_fast_entry(const PdViewT<Real>& p, const BondOriginT<Real>& origin, int64_t k, Real a_i, Real b_i,
                               Real& cx, Real& cy, Real& cz) {
  const int64_t j = p.neighbor[k];
  const Real xi = p.xi_len[k];
  Real dx, dy, dz, len;
  const Real e = origin.to(p, j, xi, dx, dy, dz, len);
  const Real omega = p.k_own[k];
  const Real s0 = p.s0_own[k];
  const bool intact = !kCheckState || p.state[k] != 0;  // chunk_intact
  const bool breaks = p.fracture & intact & (e > s0 * xi);  // bitwise: no branch (pmb_fast_entry)
  const bool pushes = intact & (!breaks | p.break_after_force);
  const Real f = lps_fast_density(omega, a_i + p.lps_a[j], b_i + p.lps_b[j], xi, e, p.volume[j], len);
  const Real fdx = f * dx, fdy = f * dy, fdz = f * dz;  // formed for every entry (pmb_fast_entry)
  cx = pushes ? fdx : Real(0);
  cy = pushes ? fdy : Real(0);
  cz = pushes ? fdz : Real(0);
  return breaks;
}

// The energy a brittle LPS half-bond takes with it when it breaks (the released energy, booked
// as dissipated): its deviatoric pair energy `b omega e^2 V_j V_i / 2` (b = c_s / m_i) at the
// critical extension e = s0 |xi| in an undilated neighbourhood (theta = 0): the quantity the
// critical stretch is calibrated on (docs/theory.md, "Critical stretch"; FractureEnergy.*), and
// the one a softening LPS bond books along its law (its U). What the model releases when a bond
// goes also changes its particle's dilatation terms, which are no pair energy; over a growing
// crack the two agree: on cases/dcb-energy run with LPS the work less the kinetic and strain
// energy is 0.97-0.99 G0 per unit of crack area. The pair part at the particle's current
// dilatation, booked before 2026-12-07, came to 0.47 of it there (the energy balance 30 % off).
BRECCIA_HD double lps_break_energy(double b_i, double omega, double critical_extension, double volume_j,
                                   double volume_i) {
  return 0.5 * b_i * omega * critical_extension * critical_extension * volume_j * volume_i;
}

// Entry k of particle i broke in the fast LPS loop: clear it and return the energy it takes
// (lps_break_energy).
template <class Real>
BRECCIA_HD double lps_fast_break(const PdViewT<Real>& p, int64_t i, int64_t k) {
  p.state[k] = 0;
  const Real xi = p.xi_len[k], omega = p.k_own[k], s0 = p.s0_own[k];
  return lps_break_energy(double(p.lps_b[i]), double(omega), double(s0) * xi, double(p.volume[p.neighbor[k]]),
                          double(p.volume[i]));
}

// The fast loops' two stages, written once for PMB and LPS. `path.entry(view, k, cx, cy, cz)`
// gives entry k's force contribution (+0 when it does not push) and whether it breaks now;
// `path.release(view, i, k)` breaks it and returns the energy it held; the released energy is
// summed in `Released`. On the host each chunk of kBondChunk entries is computed branch-free
// first (the stage the compiler vectorises), then summed in the entry order, so the sums are
// the scalar loop's and the CUDA build's (one entry per iteration) bit for bit.
//
// ordered_fast_loop is the one-entry-at-a-time form (the device's): particle i's `count`
// entries in row order, the q-th at index `at(q)`; `broke(k)` is told of each break after
// `path.release`. The CSR row (CsrRow) and a SELL lane (sell_kernels.hpp) both run it.
struct NoBreakHook {
  BRECCIA_HD void operator()(int64_t) const {}
};

// Does a path's particle keep four force sums (`Path::kFourSums` true: PMB, RowForceSums)?
template <class Path>
inline constexpr bool kPathFourSums = requires { requires Path::kFourSums; };

template <class Released, class Real, class Path, class At, class Broke>
BRECCIA_HD void ordered_fast_loop(const PdViewT<Real>& p, int64_t i, int64_t count, const Path& path, const At& at,
                                  const Broke& broke) {
  RowForceSums<Real, kPathFourSums<Path>> sums;
  Released released = Released(0);
  for (int64_t q0 = 0; q0 < count; q0 += 4) {
BRECCIA_UNROLL4
    for (int r = 0; r < 4; ++r) {
      if (q0 + r >= count) break;
      const int64_t k = at(q0 + r);
      Real cx, cy, cz;
      if (path.entry(p, k, cx, cy, cz)) {
        released += static_cast<Released>(path.release(p, i, k));
        broke(k);
      }
      sums.add(r, cx, cy, cz);
    }
  }
  sums.store(p.force + 3 * i);
  p.dissipated[i] = released;
}

// Does a path gather its bond vectors in stages of their own (`Path::kGathers` true, with
// `gather`, `density` and `select`)? Paths without the member do it all in entry().
template <class Path>
inline constexpr bool kPathGathers = requires { requires Path::kGathers; };

template <class Released, class Real, class Path>
BRECCIA_HD void two_stage_force_loop(const PdViewT<Real>& p, int64_t i, const Path& path) {
  const int64_t begin = p.offsets[i], end = p.offsets[i + 1];
#if defined(__CUDA_ARCH__)
  ordered_fast_loop<Released>(p, i, end - begin, path, CsrRow{begin}, NoBreakHook{});
#else
  RowForceSums<Real, kPathFourSums<Path>> sums;
  Released released = Released(0);
  // A local copy of the view: its pointers are then loop invariants GCC keeps in registers
  // (read through `p` they are loads it will not vectorise).
  const PdViewT<Real> v = p;
  Real cx[kBondChunk], cy[kBondChunk], cz[kBondChunk];
  bool breaks[kBondChunk];
  // kPathGathers: the chunk's bond vectors and squared lengths.
  [[maybe_unused]] Real gx[kBondChunk], gy[kBondChunk], gz[kBondChunk], gr2[kBondChunk];
  for (int64_t base = begin; base < end; base += kBondChunk) {
    const int m = static_cast<int>(end - base < kBondChunk ? end - base : kBondChunk);
    int breaking = 0;
    if constexpr (kPathGathers<Path>) {
      // PMB in double. The neighbours' positions are gathered first, one entry at a time,
      // into unit-stride buffers, so the next stage reads nothing indirectly and runs packed
      // even on SSE2 (sqrtpd, divpd: the scalar instructions' results lane by lane); with the
      // gathers inside it SSE2 emulated them lane by lane and it gained nothing. That stage
      // forms every entry's unmasked force (no selection: it is instruction-bound, and GCC 12
      // sank the division of a selecting loop into a branch and left it scalar) and counts the
      // entries that may break; only a chunk with a broken entry or a candidate runs the
      // selection (path.select, the same as in entry()) over the buffers. Otherwise every
      // entry pushes and none breaks, which is what the selection would find.
      for (int q = 0; q < m; ++q) gr2[q] = path.gather(v, base + q, gx[q], gy[q], gz[q]);
      // Counted in Real (exact up to 2^53 in any order): GCC 12 would not vectorise the
      // conversion of the lanes' comparison masks to an integer count here.
      Real candidates = Real(0);
BRECCIA_SIMD_COUNT(candidates)
      for (int q = 0; q < m; ++q) {
        bool over;
        const Real f = path.density(v, base + q, gr2[q], over);
        cx[q] = f * gx[q];
        cy[q] = f * gy[q];
        cz[q] = f * gz[q];
        candidates += (v.fracture & over) ? Real(1) : Real(0);
      }
      if (candidates != Real(0) || !chunk_intact(v, base, m)) {
        for (int q = 0; q < m; ++q) {
          bool over;  // (a bool array stored from the vector stage kept GCC 12 from vectorising it)
          path.density(v, base + q, gr2[q], over);
          breaks[q] = path.select(v, base + q, over, cx[q], cy[q], cz[q]);
          breaking += breaks[q] ? 1 : 0;
        }
      }
    } else {
      // The branch-free stage, with or without the state test (chunk_intact).
      const auto stage = [&](auto check_state) {
        int count = 0;
BRECCIA_SIMD_COUNT(count)
        for (int q = 0; q < m; ++q) {
          breaks[q] = path.template entry<decltype(check_state)::value>(v, base + q, cx[q], cy[q], cz[q]);
          count += breaks[q] ? 1 : 0;
        }
        return count;
      };
      breaking = chunk_intact(v, base, m) ? stage(std::false_type{}) : stage(std::true_type{});
    }
    // In entry order; a chunk starts at a multiple of 4 from the row's start (kBondChunk).
    for (int q0 = 0; q0 < m; q0 += 4) {
BRECCIA_UNROLL4
      for (int r = 0; r < 4; ++r)
        if (q0 + r < m) sums.add(r, cx[q0 + r], cy[q0 + r], cz[q0 + r]);
    }
    if (breaking)  // rare: in entry order, as the scalar loop sums the released energy
      for (int q = 0; q < m; ++q)
        if (breaks[q]) released += static_cast<Released>(path.release(p, i, base + q));
  }
  sums.store(p.force + 3 * i);
  p.dissipated[i] = released;
#endif
}

// The fast LPS loop's entries (two_stage_force_loop).
template <class Real>
struct LpsFastPath {
  BondOriginT<Real> origin;
  Real a_i, b_i;
  template <bool kCheckState = true>
  BRECCIA_HD bool entry(const PdViewT<Real>& v, int64_t k, Real& cx, Real& cy, Real& cz) const {
    return lps_fast_entry<kCheckState>(v, origin, k, a_i, b_i, cx, cy, cz);
  }
  BRECCIA_HD double release(const PdViewT<Real>& p, int64_t i, int64_t k) const { return lps_fast_break(p, i, k); }
};

#if defined(BRECCIA_HOST_PACK)
// The packed force rows' loop (pmb_packed_row, lps_packed_row), written once: a pack P of entries
// at a time through `pack_term` (their force components and a mask of entries past their
// critical extension), the rest one at a time through `entry_term`, every term added to the
// sums in entry order (the one-entry loop's order, so the bits are its). False, having written
// nothing, for a row with a broken entry, or one past its critical extension with fracture on:
// the two-stage loop then runs it (the selection, the breaks and their released energy).
template <class P, bool kFour, class PackTerm, class EntryTerm>
inline bool packed_row_force(const PdViewT<double>& p, int64_t i, PackTerm&& pack_term, EntryTerm&& entry_term) {
  constexpr int kLanes = kPackLanes<P>;
  const int64_t begin = p.offsets[i], end = p.offsets[i + 1];
  if (end > begin && !chunk_intact(p, begin, static_cast<int>(end - begin))) return false;
  RowForceSums<double, kFour> sums;
  PackMaskOf<P> over_any = {};
  bool over_tail = false;
  int64_t k = begin;
  if constexpr (kFour) {
    // The four sums as packs: entry q's lane of pack g (q mod 4 = g kLanes + lane, the packs of
    // each 4 entries in turn), so each lane adds the entries of its sum in row order.
    constexpr int kGroups = 4 / kLanes;
    static_assert(kGroups * kLanes == 4, "a pack holds 2 or 4 of the four sums");
    P sx[kGroups] = {}, sy[kGroups] = {}, sz[kGroups] = {};
    for (; k + 4 <= end; k += 4)
      for (int g = 0; g < kGroups; ++g) {
        P cx, cy, cz;
        over_any |= pack_term(k + g * kLanes, cx, cy, cz);
        sx[g] += cx;
        sy[g] += cy;
        sz[g] += cz;
      }
    for (int g = 0; g < kGroups; ++g)
      for (int l = 0; l < kLanes; ++l) {
        sums.x[g * kLanes + l] = sx[g][l];
        sums.y[g * kLanes + l] = sy[g][l];
        sums.z[g * kLanes + l] = sz[g][l];
      }
    // The row's last 0-3 entries, k - begin a multiple of 4: entry k + r goes to sum r.
    for (int r = 0; k + r < end; ++r) {
      double cx, cy, cz;
      over_tail |= entry_term(k + r, cx, cy, cz);
      sums.add(r, cx, cy, cz);
    }
  } else {
    for (; k + kLanes <= end; k += kLanes) {
      P cx, cy, cz;
      over_any |= pack_term(k, cx, cy, cz);
      for (int l = 0; l < kLanes; ++l) sums.add(0, cx[l], cy[l], cz[l]);
    }
    for (; k < end; ++k) {
      double cx, cy, cz;
      over_tail |= entry_term(k, cx, cy, cz);
      sums.add(0, cx, cy, cz);
    }
  }
  if (p.fracture && (over_tail || any_lane(over_any))) return false;
  sums.store(p.force + 3 * i);
  p.dissipated[i] = 0.0;
  return true;
}
#endif

#if defined(BRECCIA_HOST_PACK)
// The fast LPS force pass in double on the host for a row whose entries are all intact (one
// constant horizon): as pmb_packed_row, a pack P of entries at a time and the ordered sums in
// one loop. False, having written nothing, for a row with a broken entry or one past its
// critical extension with fracture on (the two-stage loop selects and breaks).
template <class P>
inline bool lps_packed_row(const PdViewT<double>& p, int64_t i, const BondOriginT<double>& origin, double a_i,
                           double b_i) {
  return packed_row_force<P, false>(
      p, i,
      [&](int64_t k, P& cx, P& cy, P& cz) {
        const int32_t* j = p.neighbor + k;
        const PackedBond<P> b = packed_bond<P>(p, origin, k);
        const P xi = load_pack<P>(p.xi_len + k);
        const P len = sqrt_of(b.squared_length());
        const P e = len - xi;  // BondOriginT::extension_from
        const PackMaskOf<P> over = e > widen_floats(p.s0_own + k, P{}) * xi;
        const P f = lps_fast_density(load_pack<P>(p.k_own + k), a_i + gather_pack<P>(p.lps_a, j, 1, 0),
                                     b_i + gather_pack<P>(p.lps_b, j, 1, 0), xi, e, gather_pack<P>(p.volume, j, 1, 0), len);
        cx = f * b.dx;
        cy = f * b.dy;
        cz = f * b.dz;
        return over;
      },
      [&](int64_t k, double& cx, double& cy, double& cz) {
        return lps_fast_entry<false>(p, origin, k, a_i, b_i, cx, cy, cz);  // a break: with fracture on only
      });
}
#endif

template <class Real>
BRECCIA_HD void lps_fast_force_loop(const PdViewT<Real>& p, int64_t i, const BondOriginT<Real>& origin) {
#if defined(BRECCIA_HOST_PACK) && !defined(__CUDA_ARCH__)
  if constexpr (!BondOriginT<Real>::kRelative)
    if (on_host_pack([&](auto pack) {
          return lps_packed_row<typename decltype(pack)::type>(p, i, origin, p.lps_a[i], p.lps_b[i]);
        }))
      return;
#endif
  two_stage_force_loop<double>(p, i, LpsFastPath<Real>{origin, p.lps_a[i], p.lps_b[i]});
}

// LPS with one constant horizon: the pair's force state is omega ((A_i + A_j)|xi| +
// (B_i + B_j) e), the same algebra as lps_force_state summed over both ends.
// Forces accumulate in Real; the diagnostics (energy, damage, released energy) in double.
template <class Real>
BRECCIA_HD void lps_symmetric_force_kernel(const PdViewT<Real>& p, int64_t i) {
  const BondOriginT<Real> origin(p, i);
  if (!p.diagnostics && fast_bond_loop(p)) {
    lps_fast_force_loop(p, i, origin);
    return;
  }
  const Real a_i = p.lps_a[i], b_i = p.lps_b[i];
  const Real theta_i = p.dilatation[i], d = static_cast<Real>(p.lps[i].dilatation_factor);
  Real fx = Real(0), fy = Real(0), fz = Real(0);
  double released = 0.0, dev_sum = 0.0, smax = 0.0, smin = 1e300;
  double intact_vol = 0.0;
  const double total_vol = p.diagnostics ? family_volume(p, i) : 0.0;
  bool any = false;
  const int64_t end = p.offsets[i + 1];
  for (int64_t k = p.offsets[i]; k < end; ++k) {
    if (!p.state[k]) continue;
    const int64_t j = p.neighbor[k];
    const Real xi = p.xi_len[k];
    Real dx, dy, dz, len;
    const Real e = origin.to(p, j, xi, dx, dy, dz, len);
    const Real omega = p.k_own[k];
    if (p.min_stretch_next) {
      any = true;
      if (double(e) / xi < smin) smin = double(e) / xi;
    }
    // keep: the share of the bond's force left (softening: 1 - d; brittle: 1 while intact).
    Real keep = Real(1);
    bool breaking = false;
    if (softens(p, k)) {
      if (!softening_entry_quiet(p, k, double(e) / xi)) {
        const double dmg = soften(p, k, double(e) / xi, 0.5 * double(b_i) * omega * double(p.volume[j]) * p.volume[i] * double(xi) * xi,
                                  released, BondMotionT<Real>{i, j, dx, dy, dz, len, xi});
        if (dmg >= 1.0) {
          p.state[k] = 0;
          continue;
        }
        keep = static_cast<Real>(1.0 - dmg);
      }
    } else {
      const Real s0 = p.s0_own[k] - stretch_shift(p, i, j);
      if (p.fracture && e > s0 * xi) {
        released += lps_break_energy(double(b_i), double(omega), double(s0) * xi, double(p.volume[j]),
                                     double(p.volume[i]));
        p.state[k] = 0;
        if (!p.break_after_force) continue;
        breaking = true;
      }
    }
    const Real t = keep * omega * ((a_i + p.lps_a[j]) * xi + (b_i + p.lps_b[j]) * e);
    const Real f = t * p.volume[j] / len;
    fx += f * dx;
    fy += f * dy;
    fz += f * dz;
    if (p.diagnostics && !breaking) {
      const double dev = double(e) - double(theta_i) * xi / d;
      dev_sum += double(keep) * omega * dev * dev * p.volume[j];
      intact_vol += double(keep) * own_volume(p, k);
      if (double(e) / xi > smax) smax = double(e) / xi;
    }
  }
  p.force[3 * i] = fx;
  p.force[3 * i + 1] = fy;
  p.force[3 * i + 2] = fz;
  p.dissipated[i] = released;
  store_min_stretch(p, i, smin, any);
  if (p.diagnostics) {
    p.energy_density[i] = lps_bulk_energy(p.lps[i], double(theta_i)) + 0.5 * b_i * dev_sum;
    p.damage[i] = total_vol > 0.0 ? 1.0 - intact_vol / total_vol : 0.0;
    if (p.max_stretch) p.max_stretch[i] = smax;
  }
}

// Has entry k lost a half-bond that existed? (With variable horizons a half may never
// have existed: j outside i's horizon, or i outside j's.)
template <class Real>
BRECCIA_HD bool entry_broken(const PdViewT<Real>& p, int64_t k) {
  const uint8_t st = p.state[k];
  const bool own_lost = own_half_exists(p, k) && !(st & kOwnIntact);
  const bool dual_lost = p.k_dual[k] > Real(0) && !(st & kDualIntact);
  return own_lost || dual_lost;
}

// Break the half-bonds of entry k whose stretch passed their critical value. Each entry is
// written only by its owner i; (i,j) and (j,i) see the same stretch, so they agree.
template <class Real>
BRECCIA_HD uint8_t break_bonds(const PdViewT<Real>& p, int64_t k, SameReal<Real> stretch, SameReal<Real> shift) {
  uint8_t st = p.state[k];
  if ((st & kOwnIntact) && stretch > p.s0_own[k] - shift) st &= static_cast<uint8_t>(~kOwnIntact);
  if ((st & kDualIntact) && stretch > p.s0_dual[k] - shift) st &= static_cast<uint8_t>(~kDualIntact);
  return st;
}

// What a PMB entry of the fast loop contributes, given whether its extension passed the
// critical one (`over`) and its unmasked force f (xi + eta) (fdx, fdy, fdz, formed by the
// caller for every entry): the force on i (+0 when the entry is broken, or breaks in this
// pass with break_check before_force) and whether it breaks now.
template <bool kCheckState = true, class Real>
BRECCIA_HD bool pmb_fast_select(const PdViewT<Real>& p, int64_t k, bool over, Real fdx, Real fdy, Real fdz, Real& cx,
                                Real& cy, Real& cz) {
  // Bitwise & and | (no short circuit): the loop stays free of branches the vectoriser refuses.
  const bool intact = !kCheckState || p.state[k] != 0;  // chunk_intact
  const bool breaks = p.fracture & intact & over;
  const bool pushes = intact & (!breaks | p.break_after_force);
  // The products are formed for every entry and then selected: a product inside the
  // condition is one GCC will not run for all lanes (it could trap), and it would not vectorise.
  cx = pushes ? fdx : Real(0);
  cy = pushes ? fdy : Real(0);
  cz = pushes ? fdz : Real(0);
  return breaks;
}

// Double's PMB entry from its squared deformed length r2 (BondOriginT::bond_vector), its
// reference length xi, own modulus and critical stretch (widened from float): its force
// density over length f = c s / |xi + eta|, and whether its extension |xi + eta| - |xi| passed
// the critical one (`over`). V is double (one entry) or a host pack (2 or 4 entries,
// pmb_packed_row), whose lanes round as the scalar operations do: one expression for both.
BRECCIA_HD double sqrt_of(double v) { return std::sqrt(v); }
template <class V>
BRECCIA_HD V pmb_density_from(V r2, V xi, V k_own, V s0, decltype(V{} > V{})& over) {
  const V k2 = k_own + k_own;  // own + dual halves (2 k, exact)
  const V len = sqrt_of(r2);   // BondOriginT::extension_from
  const V extension = len - xi;
  over = extension > s0 * xi;
  return k2 * extension / (xi * len);
}
template <class Real>
BRECCIA_HD Real pmb_fast_density(const PdViewT<Real>& p, int64_t k, Real r2, bool& over) {
  static_assert(!BondOriginT<Real>::kRelative, "float forms its extension from x0 and u (pmb_fast_entry)");
  return pmb_density_from<Real>(r2, p.xi_len[k], p.k_own[k], static_cast<Real>(p.s0_own[k]), over);
}

// One PMB entry of the fast loop (pmb_fast_select). Double takes the extension as
// |xi + eta| - |xi| (pmb_fast_density); float as num / den, num = eta.(xi + (xi + eta)),
// den = |xi + eta| + |xi|, with one division per entry.
template <bool kCheckState = true, class Real>
BRECCIA_HD bool pmb_fast_entry(const PdViewT<Real>& p, const BondOriginT<Real>& origin, int64_t k, Real& cx,
                               Real& cy, Real& cz) {
  Real dx, dy, dz, f;
  bool over;
  if constexpr (BondOriginT<Real>::kRelative) {
    const Real xi = p.xi_len[k];
    const Real k2 = Real(2) * p.k_own[k];  // own + dual halves
    const Real s0 = p.s0_own[k];
    Real len;
    const Real num = origin.extension_numerator(p.x0, p.u, p.neighbor[k], dx, dy, dz, len);
    const Real den = len + xi;
    over = num > s0 * xi * den;
    f = k2 * num / (xi * len * den);
  } else {
    f = pmb_fast_density(p, k, origin.bond_vector(p.x, p.neighbor[k], dx, dy, dz), over);
  }
  return pmb_fast_select<kCheckState>(p, k, over, f * dx, f * dy, f * dz, cx, cy, cz);
}

// Entry k of particle i broke in the fast PMB loop: clear it and return the energy it held at
// its critical stretch (it broke somewhere inside this step, so its force never worked
// against the stretch beyond s0).
template <class Real>
BRECCIA_HD double pmb_fast_break(const PdViewT<Real>& p, int64_t i, int64_t k) {
  p.state[k] = 0;
  const Real k2 = Real(2) * p.k_own[k];
  if constexpr (BondOriginT<Real>::kRelative) {
    const Real s0 = p.s0_own[k], xi = p.xi_len[k];
    return p.volume[i] * Real(0.25) * k2 * s0 * s0 * xi;  // float, as the float loop sums it
  } else {
    const double s0 = p.s0_own[k];
    return double(p.volume[i]) * 0.25 * k2 * s0 * s0 * p.xi_len[k];
  }
}

// The fast PMB loop's entries (two_stage_force_loop).
template <class Real>
struct PmbFastPath {
  BondOriginT<Real> origin;
  template <bool kCheckState = true>
  BRECCIA_HD bool entry(const PdViewT<Real>& v, int64_t k, Real& cx, Real& cy, Real& cz) const {
    return pmb_fast_entry<kCheckState>(v, origin, k, cx, cy, cz);
  }
  // Double gathers its bond vectors in a stage of their own on the host (two_stage_force_loop).
  static constexpr bool kGathers = !BondOriginT<Real>::kRelative;
  static constexpr bool kFourSums = true;  // RowForceSums
  BRECCIA_HD Real gather(const PdViewT<Real>& v, int64_t k, Real& dx, Real& dy, Real& dz) const {
    return origin.bond_vector(v.x, v.neighbor[k], dx, dy, dz);
  }
  BRECCIA_HD Real density(const PdViewT<Real>& v, int64_t k, Real r2, bool& over) const {
    return pmb_fast_density(v, k, r2, over);
  }
  BRECCIA_HD bool select(const PdViewT<Real>& v, int64_t k, bool over, Real& cx, Real& cy, Real& cz) const {
    return pmb_fast_select(v, k, over, cx, cy, cz, cx, cy, cz);
  }
  BRECCIA_HD double release(const PdViewT<Real>& p, int64_t i, int64_t k) const { return pmb_fast_break(p, i, k); }
};

// The fast PMB loop sums the released energy in double, and float in float (as the float
// loop always has).
template <class Real>
using PmbReleased = std::conditional_t<BondOriginT<Real>::kRelative, Real, double>;

#if defined(BRECCIA_HOST_PACK)
// PMB in double on the host, a row whose entries are all intact (between output steps nearly
// every row): one loop forms a pack P of entries at a time (gathers, squared length, square
// root, division, force: pmb_density_from on packs) and adds their forces to the sums in the
// entry order, so the sums and every value are two_stage_force_loop's bit for bit. In one loop
// the gathers, products and the ordered sum run while the divider works on the square roots
// and divisions, which the two-stage loop's separate stages serialised (docs/performance-log.md,
// "PMB and LPS rows in one packed loop"). Returns false, having written nothing, for a row
// with an entry broken, or past its critical extension with fracture on: the two-stage loop
// then runs it (the selection, the breaks and their released energy). P is PackD2 or PackD4
// (the same bits); pmb_fast_force_loop runs the widest the CPU has (on_host_pack).
template <class P>
inline bool pmb_packed_row(const PdViewT<double>& p, int64_t i, const BondOriginT<double>& origin) {
  return packed_row_force<P, true>(
      p, i,
      [&](int64_t k, P& cx, P& cy, P& cz) {
        const PackedBond<P> b = packed_bond<P>(p, origin, k);
        PackMaskOf<P> over;
        const P f = pmb_density_from<P>(b.squared_length(), load_pack<P>(p.xi_len + k), load_pack<P>(p.k_own + k),
                                        widen_floats(p.s0_own + k, P{}), over);
        cx = f * b.dx;
        cy = f * b.dy;
        cz = f * b.dz;
        return over;
      },
      [&](int64_t k, double& cx, double& cy, double& cz) {
        double dx, dy, dz;
        bool over;
        const double f = pmb_fast_density(p, k, origin.bond_vector(p.x, p.neighbor[k], dx, dy, dz), over);
        cx = f * dx;
        cy = f * dy;
        cz = f * dz;
        return over;
      });
}
#endif

template <class Real>
BRECCIA_HD void pmb_fast_force_loop(const PdViewT<Real>& p, int64_t i, const BondOriginT<Real>& origin) {
#if defined(BRECCIA_HOST_PACK) && !defined(__CUDA_ARCH__)
  if constexpr (!BondOriginT<Real>::kRelative)
    if (on_host_pack([&](auto pack) { return pmb_packed_row<typename decltype(pack)::type>(p, i, origin); })) return;
#endif
  two_stage_force_loop<PmbReleased<Real>>(p, i, PmbFastPath<Real>{origin});
}

// PMB with one constant horizon, the common production case: reads one modulus and one
// critical stretch per entry; the diagnostics (energy, damage) are compiled out of the
// loop between output steps.
template <bool kDiagnostics, class Real>
BRECCIA_HD void pmb_symmetric_force_loop(const PdViewT<Real>& p, int64_t i) {
  const BondOriginT<Real> origin(p, i);
  // (The compressive enhancement and softening bonds take the scalar loop below: they read and
  // write per-bond and per-particle state the fast loop does not carry.)
  if constexpr (!kDiagnostics) {
    if (fast_bond_loop(p)) {
      pmb_fast_force_loop(p, i, origin);
      return;
    }
  }
  RowForceSums<Real, true> sums;  // the fast loops' four sums: the same bits
  double w = 0.0, released = 0.0, smax = 0.0, smin = 1e300;
  double intact_vol = 0.0;
  const double total_vol = kDiagnostics ? family_volume(p, i) : 0.0;
  bool any = false;
  const int64_t begin = p.offsets[i], end = p.offsets[i + 1];
  for (int64_t k = begin; k < end; ++k) {
    if (!p.state[k]) continue;
    const int64_t j = p.neighbor[k];
    const Real xi = p.xi_len[k];
    Real dx, dy, dz, len;
    const Real extension = origin.to(p, j, xi, dx, dy, dz, len);
    const Real k2 = Real(2) * p.k_own[k];  // own + dual halves
    if (p.min_stretch_next) {
      any = true;
      if (double(extension) / xi < smin) smin = double(extension) / xi;
    }
    // share: the part of the bond's force left (softening: 1 - d; brittle: 1 while intact).
    double share = 1.0;
    bool breaking = false;
    if (softens(p, k)) {
      if (!softening_entry_quiet(p, k, double(extension) / xi)) {
        const double dmg = soften(p, k, double(extension) / xi, 0.25 * double(p.volume[i]) * double(k2) * xi, released,
                                  BondMotionT<Real>{i, j, dx, dy, dz, len, xi});
        if (dmg >= 1.0) {
          p.state[k] = 0;
          continue;
        }
        share = 1.0 - dmg;
      }
    } else {
      const Real s0_bond = p.s0_own[k] - stretch_shift(p, i, j);
      if (p.fracture && extension > s0_bond * xi) {
        // Dissipated: what the bond holds at its critical stretch. It broke somewhere inside
        // this step, so its force never worked against the stretch beyond s0.
        const double s0 = s0_bond;
        released += double(p.volume[i]) * 0.25 * k2 * s0 * s0 * xi;
        p.state[k] = 0;
        if (!p.break_after_force) continue;
        breaking = true;
      }
    }
    const Real f = static_cast<Real>(share) * k2 * extension / (xi * len);  // (1 - d) c s / |xi + eta|
    sums.add(static_cast<int>((k - begin) & 3), f * dx, f * dy, f * dz);
    if (kDiagnostics && !breaking) {
      const double stretch = double(extension) / xi;
      w += share * 0.25 * k2 * stretch * stretch * xi;
      intact_vol += share * own_volume(p, k);
      if (stretch > smax) smax = stretch;
    }
  }
  sums.store(p.force + 3 * i);
  p.dissipated[i] = released;
  store_min_stretch(p, i, smin, any);
  if (kDiagnostics) {
    p.energy_density[i] = w;
    p.damage[i] = total_vol > 0.0 ? 1.0 - intact_vol / total_vol : 0.0;
    if (p.max_stretch) p.max_stretch[i] = smax;
  }
}

template <class Real>
BRECCIA_HD void pmb_symmetric_force_kernel(const PdViewT<Real>& p, int64_t i) {
  if (p.diagnostics) pmb_symmetric_force_loop<true>(p, i);
  else pmb_symmetric_force_loop<false>(p, i);
}

// The general loop (variable horizons: own and dual halves differ). Without kDiagnostics the
// energy density, damage and max stretch are neither summed nor written (passes between
// output steps, the stable step's probe): the force arithmetic is the same code in the same
// order, so the forces, breaks and released energy are the diagnostic pass's bit for bit.
// The general loop's entries where no bond can break or soften and nothing but the force is
// asked for (fracture off, no diagnostics, no per-entry state beyond the intact bits: the
// stable-step estimate's passes): each entry's term of the scalar loop below, the same
// expressions in the same order (a half not intact adds nothing, an entry with none +0), for
// two_stage_force_loop, whose first stage runs several entries at once. The bond vector comes
// from the current positions x = x0 + u (BondOriginT), which gives bond_geometry's bits.
// Particle j's lps_force_factors: stored by the dilatation pass where the system holds them,
// else formed here (the same operations, so the same bits).
template <class Real>
BRECCIA_HD LpsForceFactors<Real> neighbour_lps_factors(const PdViewT<Real>& p, int64_t j) {
  return p.lps_factors ? p.lps_factors[j] : lps_force_factors(p.lps[j], p.weighted_volume[j], p.dilatation[j]);
}

template <class Real>
struct GeneralUnbrokenPath {
  BondOriginT<Real> origin;
  LpsForceFactors<Real> own;  // particle i's (LPS)
  bool lps;
  // kCheckState is two_stage_force_loop's permission to skip the state test in an intact
  // chunk; this path reads the state anyway, since its bits choose the halves that count.
  template <bool kCheckState = true>
  BRECCIA_HD bool entry(const PdViewT<Real>& v, int64_t k, Real& cx, Real& cy, Real& cz) const {
    const int64_t j = v.neighbor[k];
    const Real xi = v.xi_len[k];
    const uint8_t st = v.state[k];
    Real dx, dy, dz, len;
    const Real e = origin.to(v, j, xi, dx, dy, dz, len);
    Real scalar;
    if (lps) {
      const Real own_t = lps_force_state(own, v.k_own[k], xi, e);
      const Real dual_t = lps_force_state(neighbour_lps_factors(v, j), v.k_dual[k], xi, e);
      Real t = Real(0);
      t += (st & kOwnIntact) ? own_t : Real(0);
      t += (st & kDualIntact) ? dual_t : Real(0);
      scalar = t * v.volume[j];
    } else {
      scalar = pmb_force_scalar(v.k_own[k], v.k_dual[k], st, e / xi);
    }
    const Real inv_len = Real(1) / len;
    const Real fdx = scalar * dx * inv_len, fdy = scalar * dy * inv_len, fdz = scalar * dz * inv_len;
    cx = st ? fdx : Real(0);
    cy = st ? fdy : Real(0);
    cz = st ? fdz : Real(0);
    return false;
  }
  BRECCIA_HD double release(const PdViewT<Real>&, int64_t, int64_t) const { return 0.0; }
};

// The general loop over particle i's `count` entries in row order, the q-th at index `at(q)`;
// `broke(k)` is told of every change of entry k's state (a half broken, or a softened bond
// gone). The CSR row (general_force_loop) and a SELL lane (sell_kernels.hpp) both run it, so a
// lane's sums are the CSR loop's bit for bit.
template <bool kDiagnostics, class Real, class At, class Broke>
BRECCIA_HD void general_force_row(const PdViewT<Real>& p, int64_t i, int64_t count, const At& at, const Broke& broke) {
  Real fx = Real(0), fy = Real(0), fz = Real(0);
  double w = 0.0, released = 0.0, smax = 0.0, smin = 1e300;
  double intact_vol = 0.0;
  const double total_vol = kDiagnostics ? family_volume(p, i, count, at) : 0.0;
  bool any = false;
  const bool lps = p.model == static_cast<int>(PdModel::LPS);
  Real m_i = Real(0), theta_i = Real(0);
  LpsForceFactors<Real> own_factors;
  double dev_sum = 0.0;
  if (lps) {
    m_i = p.weighted_volume[i];
    theta_i = p.dilatation[i];
    own_factors = lps_force_factors(p.lps[i], m_i, theta_i);
  }
  for (int64_t q = 0; q < count; ++q) {
    const int64_t k = at(q);
    uint8_t st = p.state[k];
    if (!st) {
      q = last_of_zero_run(p.state, at, q, count);
      continue;
    }
    const uint8_t state_before = st;
    const int64_t j = p.neighbor[k];
    const Real xi = p.xi_len[k];
    const BondGeometryT<Real> g = bond_geometry(p.x0, p.u, i, j, xi);
    if (kDiagnostics && g.stretch > smax) smax = g.stretch;
    if (p.min_stretch_next) {
      any = true;
      if (double(g.stretch) < smin) smin = g.stretch;
    }
    double keep = 1.0;  // softening: the share of the bond's force left, 1 - d
    if (softens(p, k)) {
      if (!softening_entry_quiet(p, k, double(g.stretch))) {  // most entries of an intact block are quiet
        const double unit = lps ? 0.5 * (p.lps[i].shear_term / m_i) * p.k_own[k] * double(p.volume[j]) * p.volume[i] * double(xi) * xi
                                : 0.25 * double(p.volume[i]) * (double(p.k_own[k]) + double(p.k_dual[k])) * xi;
        keep = 1.0 - soften(p, k, double(g.stretch), unit, released, BondMotionT<Real>{i, j, g.dx, g.dy, g.dz, g.length, xi});
        if (keep <= 0.0) {
          p.state[k] = 0;
          broke(k);
          continue;
        }
      }
    } else if (p.fracture) {
      const Real shift = stretch_shift(p, i, j);
      const uint8_t after = break_bonds(p, k, g.stretch, shift);
      if (after != st) {
        // What the broken halves take at their critical stretch (PMB: the pair potential; LPS:
        // lps_break_energy).
        const uint8_t lost = static_cast<uint8_t>(st & ~after);
        if (lps) {
          const double e = (double(p.s0_own[k]) - double(shift)) * xi;
          if (lost & kOwnIntact)
            released += lps_break_energy(p.lps[i].shear_term / m_i, double(p.k_own[k]), e, double(p.volume[j]),
                                         double(p.volume[i]));
        } else {
          if (lost & kOwnIntact)
            released += p.volume[i] * pmb_energy_density<double>(p.k_own[k], 0.0, kOwnIntact,
                                                                 double(p.s0_own[k]) - double(shift), xi);
          if (lost & kDualIntact)
            released += p.volume[i] * pmb_energy_density<double>(0.0, p.k_dual[k], kDualIntact,
                                                                 double(p.s0_dual[k]) - double(shift), xi);
        }
        st = after;
        p.state[k] = st;
        broke(k);
      }
    }
    if (kDiagnostics && (st & kOwnIntact)) intact_vol += keep * own_volume(p, k);
    // The halves that push this pass: those intact now, or with break_after_force those
    // intact when it began (the energy of the ones that broke is in `released`).
    const uint8_t active = p.break_after_force ? state_before : st;
    if (!active) continue;
    Real scalar;  // force density along the deformed bond direction
    if (lps) {
      const Real e = g.extension;
      const int64_t jj = j;
      Real t = Real(0);
      if (active & kOwnIntact) {
        t += lps_force_state(own_factors, p.k_own[k], xi, e);
        if (kDiagnostics && (st & kOwnIntact)) {
          const double dev = double(e) - double(theta_i) * xi / p.lps[i].dilatation_factor;
          dev_sum += keep * p.k_own[k] * dev * dev * p.volume[j];
        }
      }
      if (active & kDualIntact)
        t += lps_force_state(neighbour_lps_factors(p, jj), p.k_dual[k], xi, e);
      scalar = static_cast<Real>(keep) * t * p.volume[j];
    } else {
      scalar = static_cast<Real>(keep) * pmb_force_scalar(p.k_own[k], p.k_dual[k], active, g.stretch);
      if (kDiagnostics) w += keep * pmb_energy_density<double>(p.k_own[k], p.k_dual[k], st, g.stretch, xi);
    }
    const Real inv_len = Real(1) / g.length;
    fx += scalar * g.dx * inv_len;
    fy += scalar * g.dy * inv_len;
    fz += scalar * g.dz * inv_len;
  }
  store_min_stretch(p, i, smin, any);
  p.force[3 * i] = fx;
  p.force[3 * i + 1] = fy;
  p.force[3 * i + 2] = fz;
  p.dissipated[i] = released;
  if (kDiagnostics) {
    if (lps) w = lps_bulk_energy(p.lps[i], double(theta_i)) + 0.5 * (p.lps[i].shear_term / m_i) * dev_sum;
    p.energy_density[i] = w;
    p.damage[i] = total_vol > 0.0 ? 1.0 - intact_vol / total_vol : 0.0;
    if (p.max_stretch) p.max_stretch[i] = smax;
  }
}

// Particle i's strain-energy density alone, as the general loop's diagnostic pass writes it
// (general_force_row<true>: the same expressions on the same inputs in the same row order, so
// the same bits), where that pass can break, soften or reshape nothing: fracture off, no bond
// damage array, no compressive-enhancement stretches (energy_only_row_applies). No forces,
// damage or largest stretch are written; LPS reads i's own dilatation, computed before.
template <class Real>
BRECCIA_HD bool energy_only_row_applies(const PdViewT<Real>& p) {
  return !p.fracture && !p.bond_damage && !p.min_stretch_next && p.diagnostics &&
         (p.model == static_cast<int>(PdModel::PMB) || p.model == static_cast<int>(PdModel::LPS));
}

template <class Real>
BRECCIA_HD void general_energy_row(const PdViewT<Real>& p, int64_t i) {
  double w = 0.0;
  const bool lps = p.model == static_cast<int>(PdModel::LPS);
  Real m_i = Real(0), theta_i = Real(0);
  double dev_sum = 0.0;
  if (lps) {
    m_i = p.weighted_volume[i];
    theta_i = p.dilatation[i];
  }
  const double keep = 1.0;  // the general row's share left: 1 with nothing softened
  for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
    const uint8_t st = p.state[k];
    if (!st) continue;
    const int64_t j = p.neighbor[k];
    const Real xi = p.xi_len[k];
    const BondGeometryT<Real> g = bond_geometry(p.x0, p.u, i, j, xi);
    if (lps) {
      if (st & kOwnIntact) {
        const Real e = g.extension;
        const double dev = double(e) - double(theta_i) * xi / p.lps[i].dilatation_factor;
        dev_sum += keep * p.k_own[k] * dev * dev * p.volume[j];
      }
    } else {
      w += keep * pmb_energy_density<double>(p.k_own[k], p.k_dual[k], st, g.stretch, xi);
    }
  }
  if (lps) w = lps_bulk_energy(p.lps[i], double(theta_i)) + 0.5 * (p.lps[i].shear_term / m_i) * dev_sum;
  p.energy_density[i] = w;
}

template <bool kDiagnostics, class Real>
BRECCIA_HD void general_force_loop(const PdViewT<Real>& p, int64_t i) {
#if !defined(__CUDA_ARCH__)
  if (!kDiagnostics && !p.fracture && fast_bond_loop(p) && has_bond_vectors(p)) {
    const bool lps = p.model == static_cast<int>(PdModel::LPS);
    const LpsForceFactors<Real> own_factors =
        lps ? lps_force_factors(p.lps[i], p.weighted_volume[i], p.dilatation[i]) : LpsForceFactors<Real>{};
    two_stage_force_loop<double>(p, i, GeneralUnbrokenPath<Real>{BondOriginT<Real>(p, i), own_factors, lps});
    return;
  }
#endif
  general_force_row<kDiagnostics>(p, i, p.offsets[i + 1] - p.offsets[i], CsrRow{p.offsets[i]}, NoBreakHook{});
}

// Does force_kernel take the general loop (variable horizons, or a path the symmetric loops
// do not carry)? The SELL layout's dual-horizon pass applies exactly there (sell_kernels.hpp).
template <class Real>
BRECCIA_HD bool takes_general_loop(const PdViewT<Real>& p) {
  if (p.symmetric_halves && has_bond_vectors(p) && p.model == static_cast<int>(PdModel::PMB)) return false;
  return !(p.symmetric_halves && p.lps_a && has_bond_vectors(p));
}

// Internal force density, strain-energy density, damage and breaking for particle i (the
// diagnostics only when p.diagnostics asks for them).
template <class Real>
BRECCIA_HD void force_kernel(const PdViewT<Real>& p, int64_t i) {
  if (!takes_general_loop(p)) {  // one constant horizon: the symmetric loops
    if (p.model == static_cast<int>(PdModel::PMB)) pmb_symmetric_force_kernel(p, i);
    else lps_symmetric_force_kernel(p, i);
    return;
  }
  if (p.diagnostics) general_force_loop<true>(p, i);
  else general_force_loop<false>(p, i);
}

// Short-range forces (model.short_range_forces): LAMMPS PERI's contact term (PairPeriPMB and
// PairPeriLPS compute(), after Silling's EMU code; Parks et al. 2008). Two members of a
// family, bonded or broken, whose distance r falls below d = min(0.9 |xi|, 1.35 l) repel
// with the force density 15 c V_j (d - r) / delta on i, c = 18 K / (pi delta^4) the PMB
// micromodulus; l is the lattice spacing (here the mean of the two particles' spacings) and
// 15 c / delta is short_range_k. Unequal constants (a graded mesh: k ~ delta^-5) combine
// as springs in series, 2 ki kj / (ki + kj), as two bodies in contact do, so the pair's
// forces are equal and opposite and neither end feels a stiffer spring than against its
// own kind (the arithmetic mean gave a fine particle against a coarse one several times
// that, past the bonds' stable step: docs/theory.md); equal constants are taken as they are
// (LAMMPS's one horizon, bit for bit). The pair's energy 1/2 k V_i V_j (d - r)^2 is shared
// between its ends.
// Adds to force (after force_kernel) and to energy_density on diagnostic passes.
//
// One pair (i, j) at deformed vector d = x_j - x_i of length len inside its reach: adds the
// push on i to (fx, fy, fz) and i's half of the pair energy to w (both kernels below).
template <class Real>
BRECCIA_HD void add_short_range_pair(const PdViewT<Real>& p, int64_t i, int64_t j, Real reach, Real dx, Real dy,
                                     Real dz, Real len, Real& fx, Real& fy, Real& fz, double& w) {
  const Real ki = p.short_range_k[i], kj = p.short_range_k[j];
  const Real stiffness = (ki == kj ? ki : Real(2) * ki * (kj / (ki + kj))) * p.volume[j];
  const Real gap = reach - len;
  const Real f = -stiffness * gap / len;  // along j - i: pushes i away from j
  fx += f * dx;
  fy += f * dy;
  fz += f * dz;
  if (p.diagnostics) w += 0.25 * double(stiffness) * double(gap) * double(gap);
}

template <class Real>
BRECCIA_HD void short_range_kernel(const PdViewT<Real>& p, int64_t i) {
  const bool gather = has_bond_vectors(p);
  const BondOriginT<Real> origin = gather ? BondOriginT<Real>(p, i) : BondOriginT<Real>();
  const Real l_i = p.spacing[i];
  Real fx = Real(0), fy = Real(0), fz = Real(0);
  double w = 0.0;
  for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) {
    const int64_t j = p.neighbor[k];
    const Real xi = p.xi_len[k];
    const Real lattice = Real(0.675) * (l_i + p.spacing[j]);  // 1.35 x the mean spacing
    const Real reach = Real(0.9) * xi < lattice ? Real(0.9) * xi : lattice;
    Real dx, dy, dz, len;
    if (gather) {
      origin.to(p, j, xi, dx, dy, dz, len);
    } else {
      const BondGeometryT<Real> g = bond_geometry(p.x0, p.u, i, j, xi);
      dx = g.dx; dy = g.dy; dz = g.dz; len = g.length;
    }
    if (!(len < reach) || !(len > Real(0))) continue;
    add_short_range_pair(p, i, j, reach, dx, dy, dz, len, fx, fy, fz, w);
  }
  p.force[3 * i] += fx;
  p.force[3 * i + 1] += fy;
  p.force[3 * i + 2] += fz;
  if (p.diagnostics) p.energy_density[i] += w;
}

// a = (f_int + b) / rho of particle i's components (every one, prescribed or not).
template <class Real>
BRECCIA_HD void accelerations_kernel(const PdViewT<Real>& p, int64_t i) {
  const Real inv_rho = Real(1) / p.density[i];
  for (int d = 0; d < 3; ++d) p.a[3 * i + d] = (p.force[3 * i + d] + p.body[3 * i + d]) * inv_rho;
}

// The accelerations, then the second half kick of velocity Verlet on the free components.
template <class Real>
BRECCIA_HD void acceleration_kernel(const PdViewT<Real>& p, int64_t i, double half_dt) {
  accelerations_kernel(p, i);
  const Real h = static_cast<Real>(half_dt);
  for (int d = 0; d < 3; ++d)
    if (!(p.fixed_dof[i] & (1u << d))) p.v[3 * i + d] += h * p.a[3 * i + d];
}

// First half kick and drift for free components (prescribed ones are set by the caller).
template <class Real>
BRECCIA_HD void kick_drift_kernel(const PdViewT<Real>& p, int64_t i, double half_dt, double dt) {
  const Real h = static_cast<Real>(half_dt), step = static_cast<Real>(dt);
  for (int d = 0; d < 3; ++d) {
    const int64_t c = 3 * i + d;
    if (p.fixed_dof[i] & (1u << d)) continue;
    p.v[c] += h * p.a[c];
    p.u[c] += step * p.v[c];
  }
}

}  // namespace breccia::solver

#if defined(BRECCIA_HOST_PACK)
#pragma GCC diagnostic pop
#endif
