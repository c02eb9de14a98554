// The OpenMP backend: the step of step.hpp on the host's double arrays through OpenMpExec,
// plus the host-side pieces outside a step (energies, the stable-step estimate).
#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "breccia/solver/correspondence.hpp"
#include "breccia/solver/exec_openmp.hpp"
#include "breccia/solver/forall.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

StepArrays<double> cpu_step_arrays(PdSystem& s) {
  if (s.x.size() != s.x0.size()) s.x.resize(s.x0.size());  // before view(): it points at x when sized
  StepArrays<double> a;
  a.p = s.view();
  a.d = a.p;
  a.x = s.x.data();
  s.u_before.resize(3 * s.n);  // kept between steps: the step allocates nothing of size N
  s.f_before.resize(3 * s.n);
  a.u_before = s.u_before.data();
  a.f_before = s.f_before.data();
  fill_load_sets(s, a);
  if (s.config.model == PdModel::Correspondence) a.corr = correspondence_view(s);
  return a;
}

void cpu_compute_forces(PdSystem& sys) {
  if (sys.f32.active) {  // model.precision: float32 — callers hold their state in double
    float32_upload(sys);
    float32_compute_forces(sys);
    float32_download(sys);
    return;
  }
  OpenMpExec exec(sys);
  const StepArrays<double> a = cpu_step_arrays(sys);
  pd_force_pass(exec, a, true);
}

namespace {
template <class Real>
void contact_pass(PdSystem& sys, const PdViewT<Real>& p, const double* x_now, std::span<const int32_t> members,
                  int64_t indices, const int32_t* key) {
  sys.contact_cells.build(x_now, members.empty() ? p.n : indices, sys.contact_cell_edge, members, key);
  const ContactCellsView g = sys.contact_cells.view();
  for_each_particle(p.n, [&](int64_t i) { short_range_contact_kernel(p, g, i); });
}
}  // namespace

void short_range_contact(PdSystem& sys, const PdViewT<double>& p, const double* x_now, std::span<const int32_t> members,
                         int64_t indices, const int32_t* key) {
  contact_pass(sys, p, x_now, members, indices, key);
}
void short_range_contact(PdSystem& sys, const PdViewT<float>& p, const double* x_now, std::span<const int32_t> members,
                         int64_t indices, const int32_t* key) {
  contact_pass(sys, p, x_now, members, indices, key);
}

void commit_min_stretch(PdSystem& sys) {
  if (!sys.min_stretch.empty()) sys.min_stretch.swap(sys.min_stretch_next);
}

void compute_external(PdSystem& sys, double t) {
  // Callers outside the step may have edited surface_loads (tests do): group them afresh.
  sys.facets = group_facets_by_particle(sys);
  OpenMpExec exec(sys);
  const StepArrays<double> a = cpu_step_arrays(sys);
  pd_external(exec, a, sys, t);
}

void apply_constraints(PdSystem& sys, double t, double dt) {
  OpenMpExec exec(sys);
  const StepArrays<double> a = cpu_step_arrays(sys);
  pd_constraints(exec, a, sys, t, dt);
}

void cpu_step(PdSystem& sys) {
  if (sys.f32.active) {  // float32: the time loop keeps the float state (make_float32_backend)
    float32_upload(sys);
    float32_step(sys);
    float32_download(sys);
    return;
  }
  OpenMpExec exec(sys);
  StepArrays<double> a = cpu_step_arrays(sys);
  pd_step(exec, a, sys);
}

Energies measure(const PdSystem& sys) {
  Energies e;
  double ke = 0.0, se = 0.0, dmax = 0.0;
  long long broken = 0;
  int64_t bad = -1;
  const int64_t n = static_cast<int64_t>(sys.n);
  const PdView p = const_cast<PdSystem&>(sys).view();
#pragma omp parallel for reduction(+ : ke, se, broken) reduction(max : dmax, bad)
  for (int64_t i = 0; i < n; ++i) {
    double v2 = 0.0;
    bool finite = true;
    for (int d = 0; d < 3; ++d) {
      v2 += sys.v[3 * i + d] * sys.v[3 * i + d];
      finite = finite && std::isfinite(sys.u[3 * i + d]) && std::isfinite(sys.v[3 * i + d]);
    }
    if (!finite) bad = std::max<int64_t>(bad, i);
    ke += 0.5 * sys.density[i] * sys.volume[i] * v2;
    se += sys.volume[i] * sys.energy_density[i];
    dmax = std::max(dmax, sys.damage[i]);
    for (int64_t k = sys.offsets[i]; k < sys.offsets[i + 1]; ++k) broken += entry_broken(p, k);
  }
  e.kinetic = ke;
  e.strain = se;
  e.max_damage = dmax;
  e.broken_half_bonds = broken;
  e.finite = bad < 0 && std::isfinite(ke) && std::isfinite(se);
  e.bad_particle = bad;
  return e;
}

namespace {
// The largest eigenvalue of the symmetric tridiagonal matrix with diagonal alpha and
// off-diagonal beta (beta[k] couples k and k + 1), by bisection on the Sturm count.
double largest_tridiagonal_eigenvalue(const std::vector<double>& alpha, const std::vector<double>& beta) {
  const size_t m = alpha.size();
  double lo = 1e300, hi = -1e300;  // Gershgorin interval
  for (size_t k = 0; k < m; ++k) {
    const double r = (k > 0 ? std::fabs(beta[k - 1]) : 0.0) + (k + 1 < m ? std::fabs(beta[k]) : 0.0);
    lo = std::min(lo, alpha[k] - r);
    hi = std::max(hi, alpha[k] + r);
  }
  // Eigenvalues above x: sign changes of the LDL^T pivots of T - x I.
  auto count_above = [&](double x) {
    int above = 0;
    double d = 1.0;
    for (size_t k = 0; k < m; ++k) {
      const double b2 = k > 0 ? beta[k - 1] * beta[k - 1] : 0.0;
      d = alpha[k] - x - (k > 0 ? b2 / d : 0.0);
      if (d == 0.0) d = -1e-300 * (std::fabs(alpha[k]) + 1.0);
      above += d > 0.0;
    }
    return above;
  };
  for (int it = 0; it < 200 && hi - lo > 1e-15 * std::max(std::fabs(lo), std::fabs(hi)); ++it) {
    const double mid = 0.5 * (lo + hi);
    if (count_above(mid) > 0) lo = mid;
    else hi = mid;
  }
  return hi;
}
// A copy of v on huge pages (huge_pages.hpp): the probe's saved bond states are 60 MB on the
// full concrete case, whose first touch on 4 KiB pages is a fault per page. The same bytes.
template <class T>
std::vector<T> copy_on_huge_pages(const std::vector<T>& v) {
  std::vector<T> copy;
  copy.reserve(v.size());
  advise_huge_pages(copy.data(), v.size() * sizeof(T));
  copy.assign(v.begin(), v.end());
  return copy;
}

// What both stable-step estimates do to the system: K applied through the force kernel at a
// displacement small enough to be linear, in double, with fracture off and without the
// diagnostics (energy density, damage, max stretch: no probe reads them, and the force
// kernels compute the same forces with or without them, bit for bit); everything a probe
// changes is put back when it ends, and the force and energy fields recomputed at the real
// displacement.
class LinearForceProbe {
 public:
  // keeps_u: the caller writes no displacement to sys (a distributed estimate writes the
  // ranks' systems'), so sys.u is not saved. `ranks` (a distributed estimate): the largest
  // cell is taken over the ranks' own particles (their systems' half cells, chained: a
  // maximum, the same bits), the global system's ranks other than 0 holding none.
  LinearForceProbe(PdSystem& sys, const ForcePass& forces, bool keeps_u = false, const StableStepRanks* ranks = nullptr)
      : sys_(sys), forces_(forces), keeps_u_(keeps_u), u_saved_(keeps_u ? std::vector<double>{} : sys.u),
        state_saved_(copy_on_huge_pages(sys.state)), fracture_(sys.config.fracture),
        dissipated_(sys.dissipated_energy), float32_(sys.f32.active), diagnostics_(sys.diagnostics) {
    // Strains of 1e-9 are below float's resolution: the estimate is always made in double.
    sys.f32.active = false;
    sys.config.fracture = false;
    sys.diagnostics = false;
    // The kernels' unbroken paths where no bond is damaged yet; a distributed or device pass
    // (forces) reads its own copy of the bonds.
    if (!forces) undamaged_.emplace(sys);
    double length_scale = 0.0;
    if (ranks && ranks->pass) {
      const std::vector<double>& half_cell = ranks->system->half_cell;
      const size_t own = static_cast<size_t>(ranks->end - ranks->begin);
      length_scale = ranks->chain([&](double scale) {
        for (size_t i = 0; i < own; ++i) scale = std::max(scale, 2.0 * half_cell[i]);
        return scale;
      });
    } else {
      for (size_t i = 0; i < sys.n; ++i) length_scale = std::max(length_scale, 2.0 * sys.half_cell[i]);
    }
    amplitude = 1e-9 * length_scale;
  }
  LinearForceProbe(const LinearForceProbe&) = delete;
  LinearForceProbe& operator=(const LinearForceProbe&) = delete;
  ~LinearForceProbe() {
    undamaged_.reset();  // the damage back before the pass at the real displacement
    if (!keeps_u_) sys_.u = u_saved_;
    sys_.state = state_saved_;
    sys_.config.fracture = fracture_;
    sys_.dissipated_energy = dissipated_;
    sys_.f32.active = float32_;
    sys_.diagnostics = diagnostics_;
    // A distributed set-up's global system has handed its bonds to the rank's own system
    // (distributed_setup.hpp): the distributed pass fills its owned fields instead.
    if (forces_ && !sys_.distributed_rows.empty()) forces_(sys_);
    else cpu_compute_forces(sys_);
  }
  // The forces at the displacement the caller wrote to sys.u (amplitude x / |x|: the same
  // displacement scale whatever x's norm).
  // `rows` (optional, one process only): u is zero outside rows.force, so only those rows'
  // forces are read; they need the dilatation of rows.dilatation (LPS: the force rows and
  // their partners). The same kernels on the same inputs give those rows the whole pass's
  // forces bit for bit; the other rows' forces are left stale.
  struct Rows {
    std::vector<int64_t> force, dilatation;
  };
  void push(const Rows* rows = nullptr) {
    if (forces_) forces_(sys_);
    else if (rows) cpu_compute_forces_on_rows(sys_, rows->force, rows->dilatation);
    else cpu_compute_forces(sys_);
  }
  double amplitude = 0.0;

 private:
  PdSystem& sys_;
  const ForcePass& forces_;
  const bool keeps_u_;
  const std::vector<double> u_saved_;
  const std::vector<uint8_t> state_saved_;
  const bool fracture_;
  const double dissipated_;
  const bool float32_;
  const bool diagnostics_;
  std::optional<DamageHiddenWhileUndamaged> undamaged_;
};
}  // namespace

namespace {
// A pass over named rows, in one parallel region: every particle's current position (the rows
// read their partners'), LPS's dilatation of `dilatation_rows`, then `row(i)` for each of
// `rows`. The force pass and the energy-only pass over a start-up check's sampled rows.
template <class RowKernel>
void pass_over_rows(const StepArrays<double>& a, size_t n, std::span<const int64_t> rows,
                    std::span<const int64_t> dilatation_rows, const RowKernel& row) {
  const int64_t n3 = static_cast<int64_t>(3 * n);
  const CurrentPositions positions{a.p.x0, a.p.u, a.x};
  const Dilatation<double> dilatation{a.p};
  const bool lps = a.p.model == static_cast<int>(PdModel::LPS);
  const int64_t nd = static_cast<int64_t>(dilatation_rows.size()), nr = static_cast<int64_t>(rows.size());
#pragma omp parallel
  {
#pragma omp for schedule(static)
    for (int64_t k = 0; k < n3; ++k) positions(k);
    if (lps) {
#pragma omp for schedule(dynamic, 256)
      for (int64_t q = 0; q < nd; ++q) dilatation(dilatation_rows[q]);
    }
#pragma omp for schedule(dynamic, 256)
    for (int64_t q = 0; q < nr; ++q) row(rows[q]);
  }
}
}  // namespace

void cpu_compute_forces_on_rows(PdSystem& sys, std::span<const int64_t> force_rows,
                                std::span<const int64_t> dilatation_rows) {
  const StepArrays<double> a = cpu_step_arrays(sys);
  const BondForces<double> bond_forces{a.p};
  pass_over_rows(a, sys.n, force_rows, dilatation_rows, [&](int64_t i) { bond_forces(i); });
}

bool cpu_energy_density_on_rows(PdSystem& sys, std::span<const int64_t> rows) {
  const StepArrays<double> a = cpu_step_arrays(sys);
  if (!sys.short_range_k.empty() || !energy_only_row_applies(a.p) || !takes_general_loop(a.p)) return false;
  const PdViewT<double> p = a.p;
  pass_over_rows(a, sys.n, rows, rows, [&](int64_t i) { general_energy_row(p, i); });
  return true;
}

namespace {
// The stiff region of the stable-step estimate. Each particle's local frequency scale
// omega_i^2 ~ E / (rho_i delta_i^2) (a bond's stiffness over its mass at a fixed horizon
// ratio); the region holds those at least `ratio` of the largest (the set-up's 0.35: omega_i
// >= 0.59 omega_max). Where that is half the particles or more (a uniform lattice: all of
// them) the estimate runs on the whole system, as it did: `marks` empty.
// The marks are of the `own` particles of `ref` (its first ones), read from its reference
// arrays; the largest scale and the marked count are taken over every rank by `over_ranks`
// (one process: the sum itself; a distributed run: StableStepRanks::chain, a maximum and a
// sum of integers, exact, so one process's region). `count`: the particles the estimate
// moves, of the whole body's sys.n (every particle where the marks are empty).
struct StableStepRegion {
  std::vector<uint8_t> marks;
  size_t count = 0;
};
using OverRanks = std::function<double(const std::function<double(double)>&)>;
StableStepRegion stiff_region(const PdSystem& sys, const PdSystem& ref, size_t own, double ratio,
                              const OverRanks& over_ranks, size_t body) {
  StableStepRegion r;
  r.count = body;
  if (body == 0 || !(ratio > 0.0)) return r;
  std::vector<double> scale(own);
  for (size_t i = 0; i < own; ++i) {
    const double delta = ref.horizon[i];
    scale[i] = sys.config.materials[ref.material[i]].youngs_modulus / (ref.density[i] * delta * delta);
  }
  const double top = over_ranks([&](double t) {
    for (const double v : scale) t = std::max(t, v);
    return t;
  });
  std::vector<uint8_t> marks(own, 0);
  size_t mine = 0;
  for (size_t i = 0; i < own; ++i) {
    marks[i] = scale[i] >= ratio * top;
    mine += marks[i];
  }
  const size_t count = static_cast<size_t>(over_ranks([&](double c) { return c + static_cast<double>(mine); }));
  if (!(top > 0.0) || 2 * count >= body) return r;
  r.marks = std::move(marks);
  r.count = count;
  return r;
}
double one_process(const std::function<double(double)>& f) { return f(0.0); }
// For the estimate: one process's marks of every particle, or under a distributed run
// (`ranks`) the rank's own particles' (i - begin) from its system's reference arrays.
StableStepRegion stable_step_region_of(const PdSystem& sys, double ratio, const StableStepRanks* ranks) {
  if (ranks && ranks->pass)
    return stiff_region(sys, *ranks->system, static_cast<size_t>(ranks->end - ranks->begin), ratio, ranks->chain,
                        ranks->particles > 0 ? static_cast<size_t>(ranks->particles) : sys.n);
  return stiff_region(sys, sys, sys.n, ratio, one_process, sys.n);
}
}  // namespace

std::vector<uint8_t> stable_step_region(const PdSystem& sys, double ratio) {
  return stiff_region(sys, sys, sys.n, ratio, one_process, sys.n).marks;
}

double estimate_max_frequency_lanczos(PdSystem& sys, int max_passes, const ForcePass& forces, double region_ratio,
                                      const StableStepStartWave* wave, const StableStepRanks* ranks) {
  // Lanczos on M^-1 K, self-adjoint in the mass inner product <x, y> = sum rho_i V_i x_i y_i,
  // with K applied through the force kernel at a displacement small enough to be linear
  // (fracture off, state restored afterwards). The largest Ritz value approaches omega_max^2
  // from below, never slower than a power iteration from the same start (its iterate lies in
  // the same Krylov space), and on PD spectra far faster: it stops once the value moves by
  // less than 1e-3 (relative) over two passes. Measured against the 60 power iterations: 19
  // passes on the full concrete case, the stable step 0.34% smaller; the set-up's default.
  // Its step is 0.03% (full case) and 0.04% (demo case) larger than with a 1e-4 tolerance,
  // which took 23 and 20 passes, and 0.03% and 0.05% larger than after 40 passes: well
  // inside the 2% margin below (docs/performance-log.md). No reorthogonalisation: lost
  // orthogonality only repeats converged Ritz values, it does not move the largest.
  //
  // On a graded body the top of the spectrum lives where the particles are finest: the
  // estimate works on the stiff region only (stable_step_region), i.e. on the block of M^-1 K
  // whose rows and columns are that region's, with every other particle held at rest. The
  // block's largest eigenvalue is at most the whole matrix's (Cauchy interlacing), so the
  // estimate stays a bound from below, and the top mode, which decays fast where the local
  // frequency is well below the largest, loses little: at 0.35 of the largest frequency scale
  // the full concrete case moves 9% of its particles and its step is 0.21% larger than with
  // the region at 1/4 (17%), the demo 11% and 0.19%, the quick case 0.05%; the 1/4 region was
  // 0.013% from the whole system's (docs/performance-log.md). The top mode sits at the charge
  // hole's rim on the top face (LPS rows whose families two faces cut), at 0.4-0.8 of the
  // largest scale, not at the finest particles: a region at 1/2 missed it by 1.4%. One process then runs only the rows that block reads; a
  // distributed set-up runs its whole pass, whose forces on the region are the same bits.
  // A distributed run (ranks) reads its own particles' reference values from the rank's
  // system (`ref`, particle i at i - begin: the same doubles), the global system of its
  // ranks other than 0 holding none once the rank's system is cut (StableStepRanks), nor
  // the whole body (a window system): the body's count is the ranks'.
  const bool shared = ranks && ranks->pass;
  const size_t n3 = 3 * (shared && ranks->particles > 0 ? static_cast<size_t>(ranks->particles) : sys.n);
  const PdSystem& ref = shared ? *ranks->system : sys;
  const size_t first = shared ? static_cast<size_t>(ranks->begin) : 0;
  auto at = [first](size_t i) { return i - first; };
  const StableStepRegion stiff = stable_step_region_of(sys, region_ratio, ranks);
  const std::vector<uint8_t>& region = stiff.marks;  // one process: every particle's; else the rank's own
  const bool restricted = !region.empty();
  sys.stable_step_particles = stiff.count;
  LinearForceProbe::Rows rows;
  const bool row_subset = restricted && !forces && sys.short_range_k.empty() && sys.offsets.size() == sys.n + 1 &&
                          sys.config.model != PdModel::Correspondence;
  if (row_subset) {
    // The force rows and, for LPS's dilatation, their partners too (ascending, once each).
    std::vector<uint8_t> read(region);
    for (size_t i = 0; i < sys.n; ++i) {
      if (!region[i]) continue;
      rows.force.push_back(static_cast<int64_t>(i));
      for (int64_t k = sys.offsets[i]; k < sys.offsets[i + 1]; ++k) read[sys.neighbor[k]] = 1;
    }
    for (size_t i = 0; i < sys.n; ++i)
      if (read[i]) rows.dilatation.push_back(static_cast<int64_t>(i));
  }
  double lambda = 0.0;
  {
    // A distributed run (ranks): each rank holds the vectors' entries of its own particles'
    // degrees of freedom only, a contiguous piece of one process's (the rank owns a range of
    // the internal order), and every sum over them is chained over the ranks in rank order
    // (StableStepRanks::chain): rank r continues rank r - 1's running sum, so each sum is
    // one process's loop, term by term, and the estimate one process's to the last bit.
    const size_t k_begin = shared ? 3 * static_cast<size_t>(ranks->begin) : 0;
    const size_t k_end = shared ? 3 * static_cast<size_t>(ranks->end) : n3;
    LinearForceProbe probe(sys, forces, shared, ranks);
    const double amplitude = probe.amplitude;
    const bool planar = sys.dimension == 2;  // z is no degree of freedom
    // The vectors hold the free degrees of freedom only (ascending): one outside the region
    // is held at rest, zero in every vector, so leaving it out changes no sum (it added +0)
    // and spares each pass seven loops over the whole system's 3 N (873,333 on the full
    // concrete case, against 81,153 of its region).
    auto free_dof = [&](size_t k) { return !(planar && k % 3 == 2) && (!restricted || region[at(k / 3)]); };
    std::vector<size_t> dofs;
    size_t free_count = 0;  // reserved first: grown by push_back it held up to twice its size
    for (size_t k = k_begin; k < k_end; ++k) free_count += free_dof(k);
    dofs.reserve(free_count);
    for (size_t k = k_begin; k < k_end; ++k)
      if (free_dof(k)) dofs.push_back(k);
    const size_t m = dofs.size();
    std::vector<double> mass(m);
    for (size_t c = 0; c < m; ++c) mass[c] = ref.density[at(dofs[c] / 3)] * ref.volume[at(dofs[c] / 3)];
    // A sum over every degree of freedom: `f` continues it over this process's from `start`.
    auto whole_sum = [&](const std::function<double(double)>& f) { return shared ? ranks->chain(f) : f(0.0); };
    // Sums in one fixed order (no thread reduction): the stable step must not depend on the
    // thread count, nor on how a distributed run shares the force passes.
    auto dot = [&](const std::vector<double>& x, const std::vector<double>& y) {
      return whole_sum([&](double sum) {
        for (size_t c = 0; c < m; ++c) sum += mass[c] * x[c] * y[c];
        return sum;
      });
    };
    // y = M^-1 K x: the force pass at u = amplitude x / |x| (the same displacement scale
    // whatever x's norm), scaled back; u is zero on every other degree of freedom. A
    // distributed run writes its owned displacements into its rank's system (the ghosts'
    // come from their owners in the pass) and reads its owned forces there.
    double* const u = shared ? ranks->u : sys.u.data();
    const double* const force = shared ? ranks->force : sys.force.data();
    std::fill(u, u + (k_end - k_begin), 0.0);
    auto apply = [&](const std::vector<double>& x, std::vector<double>& y) {
      double norm = whole_sum([&](double sum) {
        for (size_t c = 0; c < m; ++c) sum += x[c] * x[c];
        return sum;
      });
      norm = std::sqrt(norm);
      for (size_t c = 0; c < m; ++c) u[dofs[c] - k_begin] = amplitude * x[c] / norm;
      if (shared) ranks->pass(sys);
      else probe.push(row_subset ? &rows : nullptr);
      for (size_t c = 0; c < m; ++c) y[c] = -force[dofs[c] - k_begin] / ref.density[at(dofs[c] / 3)] / amplitude * norm;
    };
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    std::vector<double> q(m), q_prev(m, 0.0), w(m);
    for (size_t k = 0, c = 0; k < n3; ++k) {
      const double r = uni(rng);  // drawn for every degree of freedom: the region's (the rank's) are the whole start's
      if (c < m && dofs[c] == k) q[c++] = r;
    }
    double q_norm = std::sqrt(dot(q, q));
    for (double& qk : q) qk /= q_norm;
    // A PMB lattice's top is a smooth maximum of its dispersion (many modes close below it):
    // from a random start the Ritz value approaches as 1 / passes^2. Its plane wave, two
    // thirds of the start (the random third keeps every mode in reach), is close to those
    // modes from the first pass. Any start gives a Ritz value: a bound from below.
    const StableStepStartWave found = wave ? StableStepStartWave{} : stable_step_start_wave(sys);
    if (!wave) wave = &found;
    if (wave->found) {
      std::vector<double> g(m);
      for (size_t c = 0; c < m; ++c) {
        const double* x = &ref.x0[3 * at(dofs[c] / 3)];
        g[c] = std::cos(wave->k[0] * x[0] + wave->k[1] * x[1] + wave->k[2] * x[2]) * wave->p[dofs[c] % 3];
      }
      const double g_norm = std::sqrt(dot(g, g));
      if (g_norm > 0.0) {
        for (size_t c = 0; c < m; ++c) q[c] += 2.0 * g[c] / g_norm;
        q_norm = std::sqrt(dot(q, q));
        for (double& qk : q) qk /= q_norm;
      }
    }
    std::vector<double> alpha, beta;
    int calm = 0;  // consecutive passes that moved the estimate by less than the tolerance
    sys.stable_step_passes = 0;
    for (int pass = 0; pass < max_passes; ++pass) {
      apply(q, w);
      const double a = dot(w, q);
      const double b_prev = beta.empty() ? 0.0 : beta.back();
      for (size_t c = 0; c < m; ++c) w[c] -= a * q[c] + b_prev * q_prev[c];
      alpha.push_back(a);
      const double estimate = largest_tridiagonal_eigenvalue(alpha, beta);
      sys.stable_step_passes = pass + 1;
      const bool moved = std::fabs(estimate - lambda) > 1e-3 * std::fabs(estimate);
      lambda = std::max(lambda, estimate);
      calm = moved ? 0 : calm + 1;
      if (calm >= 2) break;
      const double b = std::sqrt(dot(w, w));
      if (!(b > 1e-12 * std::fabs(a))) break;  // an invariant subspace: the estimate is exact
      beta.push_back(b);
      q_prev.swap(q);
      for (size_t c = 0; c < m; ++c) q[c] = w[c] / b;
    }
  }  // the probe puts the system back
  // 2% margin keeps 'stable' honest: the estimate approaches omega_max^2 from below.
  return std::sqrt(std::max(lambda, 1e-300)) * 1.02;
}

double estimate_max_frequency(PdSystem& sys, int iterations, const ForcePass& forces) {
  // Power iteration on M^-1 K with K applied through the force kernel at a displacement
  // small enough to be linear; fracture off, state restored afterwards.
  const size_t n3 = 3 * sys.n;
  double lambda = 0.0;
  {
    LinearForceProbe probe(sys, forces);
    const double amplitude = probe.amplitude;
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    std::vector<double> x(n3);
    for (size_t k = 0; k < n3; ++k) x[k] = (sys.dimension == 2 && k % 3 == 2) ? 0.0 : uni(rng);
    for (int it = 0; it < iterations; ++it) {
      double norm = 0.0;
      for (double xk : x) norm += xk * xk;
      norm = std::sqrt(norm);
      if (norm == 0) break;
      for (size_t k = 0; k < n3; ++k) sys.u[k] = amplitude * x[k] / norm;
      probe.push();
      double rayleigh = 0.0;
      for (size_t k = 0; k < n3; ++k) {
        const double y = -sys.force[k] / sys.density[k / 3] / amplitude;  // (M^-1 K) x_hat
        rayleigh += (x[k] / norm) * y;
        x[k] = (sys.dimension == 2 && k % 3 == 2) ? 0.0 : y;
      }
      lambda = rayleigh;
      sys.stable_step_passes = it + 1;
    }
  }  // the probe puts the system back
  // Power iteration approaches omega_max^2 from below; 2% margin keeps 'stable' honest.
  return std::sqrt(std::max(lambda, 1e-300)) * 1.02;
}

}  // namespace breccia::solver
