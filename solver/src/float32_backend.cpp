// model.precision: float32 on the CPU (float32_state.hpp): the float copy of the state, the
// step on it, and the time loop's backend. The kernels are pd_kernels.hpp with Real = float.
#include <algorithm>
#include <cmath>

#include "breccia/solver/exec_openmp.hpp"
#include "breccia/solver/float32_state.hpp"
#include "breccia/solver/forall.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_system.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::solver {
namespace {

template <class From, class To>
void convert(const std::vector<From>& from, std::vector<To>& to) {
  to.resize(from.size());
  const int64_t n = static_cast<int64_t>(from.size());
#pragma omp parallel for schedule(static)
  for (int64_t k = 0; k < n; ++k) to[k] = static_cast<To>(from[k]);
}

}  // namespace

std::array<double, 6> float32_extent(const std::vector<double>& x0) {
  std::array<double, 6> lo_hi{};
  const size_t held = x0.size() / 3;
  for (int d = 0; d < 3; ++d) {
    double lo = 1e300, hi = -1e300;
    for (size_t i = 0; i < held; ++i) {
      lo = std::min(lo, x0[3 * i + d]);
      hi = std::max(hi, x0[3 * i + d]);
    }
    lo_hi[d] = lo;
    lo_hi[3 + d] = hi;
  }
  return lo_hi;
}

std::array<double, 3> float32_origin(const std::vector<double>& x0) {
  const std::array<double, 6> e = float32_extent(x0);
  std::array<double, 3> origin{};
  for (int d = 0; d < 3; ++d) origin[d] = x0.size() < 3 ? 0.0 : 0.5 * (e[d] + e[3 + d]);
  return origin;
}

void float32_enable(PdSystem& s, const double* origin) {
  Float32State& f = s.f32;
  // Coordinates relative to the bounding box centre: float resolves 6e-8 of |x0 - origin|,
  // which perturbs the reference geometry by that much but not the stretch (xi_len below is
  // measured on the same float positions, so an undeformed bond has zero stretch). A rank of
  // a distributed run takes the whole body's origin, so its float coordinates are the serial
  // run's. x0 may hold more particles than s.n (a rank's ghosts): all are converted.
  const size_t held = s.x0.size() / 3;
  const std::array<double, 3> centre = origin ? std::array<double, 3>{origin[0], origin[1], origin[2]} : float32_origin(s.x0);
  for (int d = 0; d < 3; ++d) f.origin[d] = centre[d];
  if (!s.distributed_rows.empty()) {
    // A distributed set-up's global system holds no bonds (they live in the ranks' systems):
    // it keeps the flag and the origin, with which each rank's system converts its own
    // particles and bonds (copy_rank_state), so no whole-system float copy is made.
    f.active = true;
    return;
  }
  f.x0.resize(3 * held);
  for (size_t k = 0; k < 3 * held; ++k) f.x0[k] = static_cast<float>(s.x0[k] - f.origin[k % 3]);
  convert(s.volume, f.volume);
  convert(s.density, f.density);
  convert(s.weighted_volume, f.weighted_volume);
  convert(s.dilatation, f.dilatation);
  convert(s.lps_a, f.lps_a);
  convert(s.lps_b, f.lps_b);
  convert(s.k_own, f.k_own);
  convert(s.k_dual, f.k_dual);
  convert(s.vol_own, f.vol_own);  // empty where the own counts serve (pd_system.hpp own_count)
  convert(s.short_range_k, f.short_range_k);
  convert(s.spacing, f.spacing);
  f.xi_len.resize(s.bond_count());
  const int64_t n = static_cast<int64_t>(s.n);
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
      const int64_t j = s.neighbor[k];
      double len2 = 0.0;  // exact differences of the float coordinates, summed in double
      for (int d = 0; d < 3; ++d) {
        const double dx = static_cast<double>(f.x0[3 * j + d]) - static_cast<double>(f.x0[3 * i + d]);
        len2 += dx * dx;
      }
      f.xi_len[k] = static_cast<float>(std::sqrt(len2));
    }
  f.active = true;
  f.family_volume.clear();
  f.family_volume = family_volumes(float32_view(s));
  float32_upload(s);
  convert(s.force, f.force);
}

PdViewT<float> float32_view(PdSystem& s) {
  Float32State& f = s.f32;
  PdViewT<float> p;
  p.n = static_cast<int64_t>(s.n);
  p.model = static_cast<int>(s.config.model);
  p.fracture = s.config.fracture;
  p.diagnostics = s.diagnostics;
  p.symmetric_halves = s.symmetric_halves;
  p.x0 = f.x0.data();
  p.x = nullptr;  // float never forms x0 + u (float32_state.hpp)
  p.u = f.u.data(); p.v = f.v.data(); p.a = f.a.data(); p.force = f.force.data(); p.body = f.body.data();
  p.volume = f.volume.data(); p.density = f.density.data(); p.fixed_dof = s.fixed_dof.data();
  p.offsets = s.offsets.data(); p.neighbor = s.neighbor.data(); p.xi_len = f.xi_len.data();
  // Shared dual halves (pd_system.hpp k_dual_halves): no float copy either, the own ones serve.
  p.k_own = f.k_own.data(); p.k_dual = s.f32_k_dual_halves().data();
  // The own halves' volumes: from the counts and the double volumes, rounded to float once as
  // convert() rounded the double array; else the float copy.
  s.point_at_own_volumes(p, f.vol_own.data());
  p.family_volume = f.family_volume.empty() ? nullptr : f.family_volume.data();
  p.s0_own = s.s0_own.data(); p.s0_dual = s.s0_dual_halves().data(); p.state = s.state.data();
  if (!s.min_stretch.empty() && s.n) {  // shared with the double view: float in both
    p.alpha = static_cast<float>(s.config.compressive_enhancement);
    p.min_stretch = s.min_stretch.data();
    p.min_stretch_next = s.min_stretch_next.data();
  }
  p.break_after_force = s.config.break_after_force;
  if (!s.bond_damage.empty()) {  // float in both views: shared
    p.s_onset = s.s_onset.data();
    p.s_ultimate = s.s0_own.data();
    p.bond_damage = s.bond_damage.data();
    p.strength_rate = static_cast<int>(s.config.strength_rate);
    p.crush_ratio = static_cast<float>(s.config.crush_ratio);
  }
  if (!f.short_range_k.empty() && s.n) {
    p.short_range_k = f.short_range_k.data();
    p.spacing = f.spacing.data();
  }
  p.lps = s.lps.empty() ? nullptr : s.lps.data();
  p.weighted_volume = f.weighted_volume.data(); p.dilatation = f.dilatation.data();
  p.lps_a = !f.lps_a.empty() && s.n ? f.lps_a.data() : nullptr;
  p.lps_b = !f.lps_b.empty() && s.n ? f.lps_b.data() : nullptr;
  p.energy_density = s.energy_density.data(); p.dissipated = s.dissipated.data();
  p.damage = s.damage.data(); p.max_stretch = s.max_stretch.empty() ? nullptr : s.max_stretch.data();
  return p;
}

void float32_upload(PdSystem& s) {
  convert(s.u, s.f32.u);
  convert(s.v, s.f32.v);
  convert(s.a, s.f32.a);
  convert(s.body, s.f32.body);
}

void float32_download(PdSystem& s) {
  convert(s.f32.u, s.u);
  convert(s.f32.v, s.v);
  convert(s.f32.a, s.a);
  convert(s.f32.force, s.force);
  convert(s.f32.dilatation, s.dilatation);
}

void float32_download_kinematics(PdSystem& s) {
  convert(s.f32.u, s.u);
  convert(s.f32.v, s.v);
}

StepArrays<float> float32_step_arrays(PdSystem& s) {
  Float32State& f = s.f32;
  StepArrays<float> a;
  a.p = float32_view(s);
  a.d = s.view();  // the double mirror: loads are evaluated on it (float32_state.hpp)
  f.u_before.resize(3 * s.n);
  f.f_before.resize(3 * s.n);
  a.u_before = f.u_before.data();
  a.f_before = f.f_before.data();
  fill_load_sets(s, a);
  return a;
}

void float32_compute_forces(PdSystem& s) {
  OpenMpExec exec(s);
  const StepArrays<float> a = float32_step_arrays(s);
  pd_force_pass(exec, a, true);
}

void float32_step(PdSystem& s) {
  OpenMpExec exec(s);
  StepArrays<float> a = float32_step_arrays(s);
  pd_step(exec, a, s);
}

namespace {

class Float32Backend final : public StepBackend {
public:
  explicit Float32Backend(PdSystem& s) { float32_upload(s); }  // a checkpoint may have been read
  void step(PdSystem& s) override { float32_step(s); }
  Energies measure(PdSystem& s) override {
    float32_download_kinematics(s);
    return solver::measure(s);
  }
  void compute_forces(PdSystem& s) override {
    float32_compute_forces(s);
    float32_download(s);
  }
  void download(PdSystem& s) override { float32_download(s); }
  void download_kinematics(PdSystem& s) override { float32_download_kinematics(s); }
};

}  // namespace

std::unique_ptr<StepBackend> make_float32_backend(PdSystem& s) { return std::make_unique<Float32Backend>(s); }

}  // namespace breccia::solver
