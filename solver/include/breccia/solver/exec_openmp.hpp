#pragma once
// The CPU's execution space for the step of step.hpp: loops over particles on OpenMP threads
// (static schedule), sums combined per thread and then in thread order (reproducible for a
// given thread count), and the host-side pieces a step needs from the PdSystem (its s_min
// buffers, the cell grid of the short-range contact).
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "breccia/solver/pd_system.hpp"
#include "breccia/solver/step.hpp"

namespace breccia::solver {

class OpenMpExec {
public:
  explicit OpenMpExec(PdSystem& sys) : sys_(sys) {}

  template <class F>
  void for_each(int64_t n, const F& f, const char* /*name*/) const {
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; ++i) f(i);
  }

  template <class Load, class Finish>
  void reduce(int64_t n, const Load& load, const Finish& finish, const char* /*name*/) const {
    using Value = typename Load::Value;
    constexpr int kMaxThreads = 512;
    Value partial[kMaxThreads];
    const int threads = std::min(omp_get_max_threads(), kMaxThreads);
    for (int t = 0; t < threads; ++t) partial[t] = Load::identity();
#pragma omp parallel num_threads(threads)
    {
      Value acc = Load::identity();
      // nowait: each thread's partial is its own; the region's end is the one barrier.
#pragma omp for schedule(static) nowait
      for (int64_t i = 0; i < n; ++i) acc = Load::combine(acc, load(i));
      partial[omp_get_thread_num()] = acc;
    }
    Value total = Load::identity();
    for (int t = 0; t < threads; ++t) total = Load::combine(total, partial[t]);
    finish(total);
  }

  // commit_min_stretch (pd_system.hpp) on the PdSystem's buffers; the step's views follow.
  template <class Real>
  void commit_min_stretch(StepArrays<Real>& a) const {
    if (sys_.min_stretch.empty()) return;
    solver::commit_min_stretch(sys_);
    a.p.min_stretch = a.d.min_stretch = sys_.min_stretch.data();
    a.p.min_stretch_next = a.d.min_stretch_next = sys_.min_stretch_next.data();
  }

  // Short-range forces between particles outside each other's family (contact_cells.hpp),
  // on a cell grid of the current positions in double.
  template <class Real>
  void contact(const StepArrays<Real>& a) const {
    short_range_contact(sys_, a.p, contact_positions(a));
  }

  // The current positions the contact grid is built on: absolute, in double (3 per particle,
  // at least the n the system steps).
  template <class Real>
  const double* contact_positions(const StepArrays<Real>& a) const {
    if constexpr (std::is_same_v<Real, double>) {
      return a.x;
    } else {
      // Float keeps positions relative to the body's centre: the grid wants them absolute.
      sys_.x.resize(3 * sys_.n);
      const int64_t n3 = static_cast<int64_t>(3 * sys_.n);
      const Float32State& f = sys_.f32;
#pragma omp parallel for schedule(static)
      for (int64_t k = 0; k < n3; ++k) sys_.x[k] = f.origin[k % 3] + double(f.x0[k]) + double(f.u[k]);
      return sys_.x.data();
    }
  }

  // The gas load (gas.hpp) keeps its arrays in the host's GasState.
  GasBuffers gas_buffers(GasState& gas) const { return host_gas_buffers(gas); }
  const GasSums* gas_block_sums_on_host(GasState&, const GasSums* sums, int64_t) const { return sums; }

private:
  PdSystem& sys_;
};

// The loads' and constraints' index lists of the host's PdSystem as the step reads them.
template <class Real>
void fill_load_sets(const PdSystem& s, StepArrays<Real>& a) {
  a.facets = s.facets.view();
  a.constraint_sets.clear();
  a.constraint_values.clear();
  for (const auto& c : s.constraints) {
    a.constraint_sets.push_back({static_cast<int64_t>(c.particles.size()), c.particles.data()});
    a.constraint_values.push_back(c.field ? c.values.data() : nullptr);
  }
  a.body_load_sets.clear();
  for (const auto& b : s.body_loads)
    a.body_load_sets.push_back(b.every_particle ? SetView{static_cast<int64_t>(s.n), nullptr}
                                                   : SetView{static_cast<int64_t>(b.particles.size()), b.particles.data()});
  a.external_work = const_cast<double*>(&s.external_work);
  a.dissipated_energy = const_cast<double*>(&s.dissipated_energy);
}

// The step's arrays over the host's state: double (cpu_backend.cpp) and float
// (float32_backend.cpp, the float state of float32_state.hpp with the double mirror as `d`).
StepArrays<double> cpu_step_arrays(PdSystem& s);
StepArrays<float> float32_step_arrays(PdSystem& s);
// cpu_compute_forces (pd_system.hpp) for some rows only (one process; PMB or LPS without
// short-range forces): the positions of every particle, LPS's dilatation of `dilatation_rows` (the force rows and
// their partners, ascending), then the bond forces of `force_rows` (with the energy density,
// damage and max stretch where sys.diagnostics is on). The same kernels on the same inputs,
// so those rows get the whole pass's values bit for bit; the other rows' are left as they
// were. No released-energy sum.
void cpu_compute_forces_on_rows(PdSystem& sys, std::span<const int64_t> force_rows,
                                std::span<const int64_t> dilatation_rows);
// The energy densities of `rows` alone, as cpu_compute_forces_on_rows(sys, rows, rows) with
// sys.diagnostics on writes them, bit for bit (general_energy_row: no forces), where that pass
// would take the general loop and can change no bond (energy_only_row_applies); returns false,
// having done nothing, elsewhere. LPS: the rows' dilatation first, as that pass computes it.
bool cpu_energy_density_on_rows(PdSystem& sys, std::span<const int64_t> rows);

// The set-up's linear passes (fracture off: the stable-step estimate, the energy-scatter
// check) on a softening system whose bonds hold no damage yet: with fracture off, soften()
// returns the stored damage, 0, so every entry keeps 1.0 of its force and 1.0 of its
// dilatation weight, and 1.0 * x is x: the kernels give the same bits with the damage array
// hidden from them, and then take the unbroken paths (fast_bond_loop: the two-stage general
// loop and dilatation) instead of the per-entry softening loop, which the probe's passes ran
// at twice the cost on the full concrete case (docs/performance-log.md). Hidden only while this
// lives, only where no bond has any damage; put back untouched (a move, no copy).
class DamageHiddenWhileUndamaged {
 public:
  explicit DamageHiddenWhileUndamaged(PdSystem& sys) : sys_(sys) {
    if (sys.config.fracture || sys.bond_damage.empty()) return;  // (callers turn fracture off first)
    const int64_t entries = static_cast<int64_t>(sys.bond_damage.size());
    const float* d = sys.bond_damage.data();
    bool undamaged = true;
#pragma omp parallel for schedule(static) reduction(&& : undamaged)
    for (int64_t k = 0; k < entries; ++k) undamaged = undamaged && d[k] == 0.0f;
    if (undamaged) hidden_.swap(sys.bond_damage);
  }
  DamageHiddenWhileUndamaged(const DamageHiddenWhileUndamaged&) = delete;
  DamageHiddenWhileUndamaged& operator=(const DamageHiddenWhileUndamaged&) = delete;
  ~DamageHiddenWhileUndamaged() {
    if (!hidden_.empty()) hidden_.swap(sys_.bond_damage);
  }

 private:
  PdSystem& sys_;
  decltype(PdSystem::bond_damage) hidden_;
};

}  // namespace breccia::solver
