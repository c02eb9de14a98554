#include "measures.hpp"

#include "breccia/common/particle_file.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "breccia/solver/run.hpp"

namespace breccia::atlas {

double fundamental_mode_speed_error(solver::PdSystem& s, double length_m, double c0_m_s, const BackendFactory& backend) {
  const double L = length_m;
  std::vector<double> shape(s.n);
  double norm = 0.0;
  for (size_t i = 0; i < s.n; ++i) {
    shape[i] = std::cos(std::numbers::pi * s.x0[3 * i] / L);
    s.u[3 * i] = 1e-6 * shape[i];
    norm += s.volume[i] * shape[i] * shape[i];
  }
  auto modal = [&] {
    double q = 0.0;
    for (size_t i = 0; i < s.n; ++i) q += s.volume[i] * shape[i] * s.u[3 * i];
    return q / norm;
  };
  solver::cpu_compute_forces(s);  // the first step's a(0) is taken from these forces (pd_step)
  s.diagnostics = false;  // energies are not needed: only displacements
  const long long max_steps = static_cast<long long>(4.0 * L / (2.0 * c0_m_s) / s.dt) + 10;
  const std::unique_ptr<solver::StepBackend> device = backend ? backend(s) : nullptr;  // from the state above
  double t_quarter = -1.0, q = modal();
  while (s.step < max_steps && t_quarter < 0) {
    const double before = q;
    if (device) {
      device->step(s);
      device->download_kinematics(s);
    } else {
      solver::cpu_step(s);
    }
    q = modal();
    if (before > 0 && q <= 0) t_quarter = s.time - s.dt * q / (q - before);
  }
  return t_quarter > 0 ? std::fabs(L / (2.0 * t_quarter) / c0_m_s - 1.0) : 1.0;
}

namespace {
// Holds the particle nearest the origin in y (no rigid sideways drift) and relaxes by ADR;
// false when ADR did not converge.
bool relax_bar(solver::PdSystem& s, long long* iterations) {
  size_t corner = 0;
  for (size_t i = 0; i < s.n; ++i)
    if (std::hypot(s.x0[3 * i], s.x0[3 * i + 1]) < std::hypot(s.x0[3 * corner], s.x0[3 * corner + 1])) corner = i;
  s.fixed_dof[corner] |= 2u;
  const long long done = solver::relax_to_equilibrium(s, false);
  if (iterations) *iterations = done;
  return done >= 0;
}
}  // namespace

double bar_span_strain_error(solver::PdSystem& s, double traction_pa, double youngs_modulus_pa, double x_lo,
                             double x_hi, long long* iterations) {
  if (!relax_bar(s, iterations)) return -1.0;
  double n = 0, sx = 0, su = 0, sxx = 0, sxu = 0;
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], u = s.u[3 * i];
    if (x < x_lo || x > x_hi) continue;
    n += 1, sx += x, su += u, sxx += x * x, sxu += x * u;
  }
  const double slope = (n * sxu - sx * su) / (n * sxx - sx * sx);
  return std::fabs(slope / (traction_pa / youngs_modulus_pa) - 1.0);
}

double bar_end_displacement_error(solver::PdSystem& s, double traction_pa, double youngs_modulus_pa,
                                  long long* iterations) {
  if (!relax_bar(s, iterations)) return -1.0;
  auto layer_mean = [&](const char* set, const std::vector<double>& field) {
    double sum = 0, vol = 0;
    for (auto f : s.particles.find_set(set)->indices) {
      const int32_t i = s.internal_index[f];
      sum += s.volume[i] * field[3 * i];
      vol += s.volume[i];
    }
    return sum / vol;
  };
  const double L_eff = layer_mean("xmax", s.x0) - layer_mean("xmin", s.x0);
  const double u_end = layer_mean("xmax", s.u) - layer_mean("xmin", s.u);
  return std::fabs(u_end / (traction_pa * L_eff / youngs_modulus_pa) - 1.0);
}

double reflected_pulse_energy(solver::PdSystem& s, double interface_x, double pulse_x, double pulse_width,
                              double c_p) {
  const double A = 1e-6, w = pulse_width;
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i] - pulse_x;
    const double g = A * std::exp(-x * x / (2 * w * w));
    s.u[3 * i] = g;
    s.v[3 * i] = c_p * g * x / (w * w);  // right-going: v = -c dg/dx
  }
  s.diagnostics = true;  // the strain energy density is needed at every step
  solver::cpu_compute_forces(s);  // the first step's a(0) is taken from these forces (pd_step)
  auto energy_left_of = [&](double xcut) {
    double e = 0;
    for (size_t i = 0; i < s.n; ++i)
      if (s.x0[3 * i] < xcut)
        e += 0.5 * s.density[i] * s.volume[i] * s.v[3 * i] * s.v[3 * i] + s.volume[i] * s.energy_density[i];
    return e;
  };
  const double e0 = energy_left_of(interface_x);
  const double t_end = (interface_x + 4 * w - pulse_x) / c_p;
  while (s.time < t_end) {
    s.diagnostics = true;
    solver::cpu_step(s);
  }
  double reach = 0;
  for (size_t i = 0; i < s.n; ++i) reach = std::max(reach, s.horizon[i]);
  return e0 > 0 ? energy_left_of(interface_x - reach) / e0 : NAN;
}

std::string write_graded_strip(const std::string& path, double L, double W, double h, double r) {
  ParticleModel m;
  m.dimension = 2;
  m.thickness_m = h;
  auto add = [&](double x, double y, double s) {
    m.position_m.insert(m.position_m.end(), {x, y, 0.0});
    m.volume_m3.push_back(s * s * h);
    m.spacing_m.push_back(s);
    m.material_id.push_back(0);
  };
  for (double x = 0.5 * h; x < L / 2; x += h)
    for (double y = 0.5 * h; y < W; y += h) add(x, y, h);
  const double H = r * h;
  for (double x = L / 2 + 0.5 * H; x < L; x += H)
    for (double y = 0.5 * H; y < W; y += H) add(x, y, H);
  m.material_names = {"rock"};
  m.source = "graded strip";
  write_particle_file(path, m);
  return path;
}

PeakStress pulled_bar_peak_stress(solver::PdSystem& s, size_t grip, double area_m2, double end_s) {
  const auto& pulled = s.constraints.at(grip).particles;
  const long long steps = static_cast<long long>(std::ceil(end_s / s.dt));
  PeakStress peak;
  for (long long k = 0; k < steps; ++k) {
    solver::cpu_step(s);
    double f = 0.0;
    for (auto i : pulled) f += s.volume[i] * s.force[3 * i];
    const double stress = std::fabs(f) / area_m2;
    if (stress > peak.stress_pa) peak = {stress, s.time};
  }
  return peak;
}

std::string softening_bar_case_text(int dimension, double grip_depth_m, double poisson_ratio,
                                    const std::string& tensile_strength) {
  auto num = [](double v) { return std::to_string(v); };
  const double L = SofteningBar::length_m;
  // Appended piece by piece: `"[" + num(x0) + ...` drew GCC 12's -Wrestrict false positive.
  auto grip_box = [&](double x0, double x1) {
    std::string box = "[";
    box += num(x0);
    box += dimension == 3 ? ", -1, -1, " : ", -1, ";
    box += num(x1);
    box += dimension == 3 ? ", 1, 1]" : ", 1]";
    return box;
  };
  char nu[32];
  std::snprintf(nu, sizeof nu, "%.16g", poisson_ratio);
  return "materials: [{name: c, density: 2400, youngs_modulus: 30 GPa, poisson_ratio: " + std::string(nu) +
         ", fracture_energy: 100, tensile_strength: " + tensile_strength + "}]\n"
         "sets: [{name: grip_lo, box: " + grip_box(-1, grip_depth_m) + "}, {name: grip_hi, box: " +
         grip_box(L - grip_depth_m, 1) + "}]\n"
         "boundary: [{type: velocity, set: grip_lo, value: [-0.05, 0, 0], components: [x], ramp_time: 20 us},\n"
         "           {type: velocity, set: grip_hi, value: [0.05, 0, 0], components: [x], ramp_time: 20 us}]\n"
         "time: {end: 300 us}\n";
}

double crossing_fracture_energy_ratio(const solver::PdSystem& s, double window, double shift, double g0) {
  const bool lps = s.config.model == solver::PdModel::LPS;
  const bool softening = !s.bond_damage.empty();
  const bool planar = s.dimension == 2;
  double energy = 0.0;
  for (size_t i = 0; i < s.n; ++i)
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
      const int32_t j = s.neighbor[k];
      const double xi = s.x0[3 * i], xj = s.x0[3 * j];
      if (!(xi < 0 && xj > 0)) continue;
      // Crossing point of the bond with the plane x = 0.
      const double t = -xi / (xj - xi);
      const double yc = s.x0[3 * i + 1] + t * (s.x0[3 * j + 1] - s.x0[3 * i + 1]);
      const double zc = s.x0[3 * i + 2] + t * (s.x0[3 * j + 2] - s.x0[3 * i + 2]);
      // Half-open window: on a lattice the crossing points repeat with the lattice period,
      // so a window of whole periods counts each kind of crossing equally often.
      const double y = yc - shift * window, z = zc - shift * window;
      if (y < -window / 2 || y >= window / 2 || (!planar && (z < -window / 2 || z >= window / 2))) continue;
      // s_t s_u of a softening entry's work to break (SofteningLaw.* checks that integral).
      const double st_su = softening ? double(s.s_onset[k]) * s.s0_own[k] : 0.0;
      double pair_energy_from_i;
      if (!lps) {
        const double k_own = s.k_own[k], k_dual = s.k_dual_halves()[k], len = s.xi_len[k];
        pair_energy_from_i = softening ? s.volume[i] * solver::pmb_energy_density(k_own, k_dual, 3, 1.0, len) * st_su
                                       : s.volume[i] * solver::pmb_energy_density(k_own, k_dual, 3, s.s0_own[k], len);
      } else if (softening) {  // LPS deviatoric pair energy at the critical extension, theta = 0
        pair_energy_from_i = 0.5 * s.lps[i].shear_term / s.weighted_volume[i] * s.k_own[k] * st_su * s.xi_len[k] *
                             s.xi_len[k] * s.volume[j] * s.volume[i];
      } else {
        const double e = s.s0_own[k] * s.xi_len[k];
        pair_energy_from_i =
            0.5 * s.lps[i].shear_term / s.weighted_volume[i] * s.k_own[k] * e * e * s.volume[j] * s.volume[i];
      }
      energy += 2.0 * pair_energy_from_i;  // the j -> i entry holds the same amount
    }
  const double area = planar ? window * s.thickness : window * window;
  return energy / area / g0;
}

}  // namespace breccia::atlas
