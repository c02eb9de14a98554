#pragma once
// model.precision: float32 — the float copy of everything the bond loop streams, and the
// CPU step that runs on it. The kernels are the same templates as for double
// (pd_kernels.hpp, Real = float); what differs is only where the state lives:
//   float:  reference positions (relative to the body's centre), displacement, velocity,
//           acceleration, forces, external force density, particle volume and density, bond
//           lengths and moduli, LPS weighted volume, dilatation and fast-path factors;
//           force sums per particle accumulate in float.
//   double: the per-particle diagnostics (energy density, damage, dissipated energy),
//           every reduction over the body (energies, external work, released energy), the
//           loads and constraints (evaluated per step in double, then rounded), set-up,
//           the stable step, outputs and checkpoints.
// The double arrays of PdSystem stay allocated (set-up, outputs, checkpoints, ADR read
// them); they are brought up to date by float32_download when a file or a check needs them.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "breccia/solver/pd_kernels.hpp"

namespace breccia::solver {

struct PdSystem;
class StepBackend;

struct Float32State {
  bool active = false;           // the run computes in float (config.precision == Float32)
  double origin[3] = {0, 0, 0};  // x0 is held relative to it: float keeps 24 bits of |x0 - origin|
  std::vector<float> x0, u, v, a, force, body;                        // 3N
  std::vector<float> volume, density, weighted_volume, dilatation;    // N
  std::vector<float> lps_a, lps_b;                                    // N (LPS fast path)
  std::vector<float> xi_len, k_own, k_dual, vol_own;                  // per bond entry (vol_own: lammps partial volume only)
  std::vector<float> short_range_k, spacing;                          // N (short-range forces)
  // N: each family's volume as the float passes sum it, the own halves' volumes rounded to float
  // and added in double (pd_system.hpp family_volume; family_volumes over the float view).
  std::vector<double> family_volume;
  std::vector<float> u_before;   // scratch for the external-work trapezoid
  std::vector<double> f_before;
};

// Build the float state from the double one (after set-up: the stable step is estimated in
// double, since its power iteration uses strains of 1e-9, below float's resolution).
// `origin`: the point float coordinates are relative to (default: the bounding box centre).
// A distributed set-up's global system (no bonds held) takes the flag and origin only.
void float32_enable(PdSystem& sys, const double* origin = nullptr);
// The default origin: the centre of the bounding box of `x0`'s positions (3 per particle;
// 0 without any). The set-up takes it before its stable-step estimate, whose cut lets a
// distributed set-up's ranks other than 0 drop the reference positions.
std::array<double, 3> float32_origin(const std::vector<double>& x0);
// Its folds: the least then the largest coordinate on each axis (1e300 and -1e300 without any),
// which a distributed set-up's ranks take over their blocks of the internal order and fold in
// rank order (std::min and std::max keep the first of equal values: the same doubles).
std::array<double, 6> float32_extent(const std::vector<double>& x0);
PdViewT<float> float32_view(PdSystem& sys);
// Double -> float: displacement, velocity, acceleration, external force density.
void float32_upload(PdSystem& sys);
// Float -> double: displacement, velocity, acceleration, internal force, dilatation.
void float32_download(PdSystem& sys);
// Float -> double: displacement and velocity only (energies, probes).
void float32_download_kinematics(PdSystem& sys);
// Internal forces at the float displacement (the float state is the truth).
void float32_compute_forces(PdSystem& sys);
// One velocity-Verlet step on the float state.
void float32_step(PdSystem& sys);
// The time loop's backend for float runs: keeps the float state between steps and copies to
// the double arrays only when the loop measures or writes.
std::unique_ptr<StepBackend> make_float32_backend(PdSystem& sys);

}  // namespace breccia::solver
