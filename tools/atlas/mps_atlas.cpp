// MPS rows of the atlas (docs/atlas.md): the stress-based MPS solid (solver/mps, Solid) on
// problems with known answers, swept over the particle spacing, and its stability map in
// tension.
//  mps_wave_speed:       fundamental free-free mode of a 2D strip in uniaxial strain (every
//                        particle held in y), so the speed is c_L = sqrt((lambda + 2 mu)/rho).
//  thick_cylinder:       elastic thick-walled cylinder under internal pressure, plane strain,
//                        against Lame (the set-up of tests/mps/test_solid.cpp,
//                        mps/thick_cylinder.hpp).
//  thick_cylinder_hill:  the same, elastic-perfectly plastic (von Mises), against Hill.
//  stability (tension):  a strip pulled at both ends to a nominal strain, pressure form x
//                        hourglass alpha; the clumping measure of mps/stability_checks.hpp.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>

// The MPS headers define BRECCIA_HD empty (their functions say `inline` themselves), the
// PD headers as `inline`: the MPS ones come first and the macro is reset for the PD ones.
#include "breccia/common/csv.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/stability_checks.hpp"
#include "breccia/mps/strip_pull.hpp"
#include "breccia/mps/thick_cylinder.hpp"
#undef BRECCIA_HD
#include "atlas.hpp"
#include "breccia/common/error.hpp"

namespace breccia::atlas {
namespace {

using std::numbers::pi;

struct Rock {  // the PD atlas material
  double young = 50e9, poisson = 0.25, density = 2600;
  double lambda() const { return young * poisson / ((1 + poisson) * (1 - 2 * poisson)); }
  double mu() const { return young / (2 * (1 + poisson)); }
};

mps::SolidLaw elastic_law(const Rock& r) {
  mps::SolidLaw law;
  law.lame_lambda_pa = r.lambda();
  law.shear_modulus_pa = r.mu();
  return law;
}

// Square lattice nx x ny, spacing h, centred cells; volumes h^2 x thickness h.
void strip(int nx, int ny, double h, std::vector<double>& position, std::vector<double>& volume) {
  position.clear();
  volume.clear();
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      position.insert(position.end(), {(i + 0.5) * h, (j + 0.5) * h, 0.0});
      volume.push_back(h * h * h);
    }
}

AtlasRow mps_row(const std::string& problem, const std::string& kind, double re, double spacing, int threads) {
  AtlasRow r;
  r.problem = problem;
  r.model = "mps";
  r.dimension = 2;
  r.particles_kind = kind;
  r.m = re;
  r.spacing_m = spacing;
  r.threads = threads;
  return r;
}

// Fundamental mode u_x = A cos(pi x / L): the modal amplitude first crosses zero at a
// quarter period L / (2 c); returns |c / c_L - 1| (1 if it never crossed).
double mps_mode_speed_error(const Rock& rock, double L, double W, double h, double re, AtlasRow& row) {
  std::vector<double> pos, vol;
  const int nx = static_cast<int>(std::lround(L / h)), ny = std::max(1, static_cast<int>(std::lround(W / h)));
  strip(nx, ny, h, pos, vol);
  mps::SolidOptions opt;
  opt.dimension = 2;
  opt.spacing_m = h;
  opt.thickness_m = h;
  opt.re_over_spacing = re;
  mps::Solid solid(pos, vol, rock.density, elastic_law(rock), opt);
  mps::PrescribedSet hold;
  for (int i = 0; i < nx * ny; ++i) hold.particles.push_back(i);
  hold.components = {false, true, false};
  solid.add_prescribed(hold);
  const double amplitude = 1e-6 * L;
  std::vector<double> mode(solid.size());
  double norm = 0;
  for (size_t i = 0; i < solid.size(); ++i) {
    mode[i] = std::cos(pi * pos[3 * i] / L);
    norm += mode[i] * mode[i];
    solid.displacement(0)[i] = amplitude * mode[i];
  }
  auto modal = [&] {
    double a = 0;
    for (size_t i = 0; i < solid.size(); ++i) a += mode[i] * solid.displacement(0)[i];
    return a / norm;
  };
  const double c_l = std::sqrt((rock.lambda() + 2 * rock.mu()) / rock.density);
  const double t_quarter = L / (2 * c_l);
  double previous = modal(), t_prev = 0.0, error = 1.0;
  while (solid.time_s() < 2 * t_quarter) {
    solid.step();
    const double now = modal();
    if (previous > 0 && now <= 0) {
      const double t_cross = t_prev + (solid.time_s() - t_prev) * previous / (previous - now);
      error = std::fabs(L / (2 * t_cross) / c_l - 1.0);
      break;
    }
    previous = now;
    t_prev = solid.time_s();
  }
  row.particles = solid.size();
  row.bonds = solid.bonds().size();
  row.steps = solid.steps();
  return error;
}

}  // namespace

void mps_problems(const SweepPlan& plan, const RowSink& sink) {
  auto wanted = [&](const char* p) { return std::find(plan.problems.begin(), plan.problems.end(), p) != plan.problems.end(); };
  const Rock rock;
  if (wanted("mps_wave_speed")) {
    const std::vector<double> spacings = plan.quick ? std::vector<double>{2e-3, 1e-3} : std::vector<double>{2e-3, 1e-3, 0.5e-3, 0.25e-3};
    for (double re : {2.1, 3.1})
      for (double h : spacings) {
        AtlasRow row = mps_row("mps_wave_speed", "lattice", re, h, plan.threads);
        row.error_measure = "|c/c_L-1| fundamental mode in uniaxial strain";
        const auto t0 = std::chrono::steady_clock::now();
        try {
          row.error = mps_mode_speed_error(rock, 0.1, 0.01, h, re, row);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "[atlas] mps_wave_speed re %.1f dx %.3g mm: %s\n", re, h * 1e3, e.what());
          continue;
        }
        row.wall_s = seconds_since(t0);
        sink(row);
      }
  }
  for (const bool plastic : {false, true}) {
    const char* name = plastic ? "thick_cylinder_hill" : "thick_cylinder";
    if (!wanted(name)) continue;
    const std::vector<int> rings = plan.quick ? std::vector<int>{5, 10} : std::vector<int>{5, 10, 20};
    for (int n : rings) {
      mps::ThickCylinder c;  // steel, a 0.1 m, b 0.2 m (tests/mps/test_solid.cpp)
      double hill_c = 0.0, k = 0.0;
      if (plastic) {
        c.yield_pa = 240e6;
        k = c.yield_pa / std::sqrt(3.0);
        hill_c = 0.15;  // plastic radius halfway through the wall
        c.pressure_pa = 2 * k * (std::log(hill_c / c.inner_m) + 0.5 * (1 - hill_c * hill_c / (c.outer_m * c.outer_m)));
      }
      c.rings = n;
      AtlasRow row = mps_row(name, "rings", 2.1, (c.outer_m - c.inner_m) / n, plan.threads);
      row.error_measure = plastic ? "max over circles 2..n |mean stress - Hill|/p" : "max over circles 2..n |mean stress - Lame|/p";
      const auto t0 = std::chrono::steady_clock::now();
      mps::RingProfile prof;
      try {
        prof = mps::load_thick_cylinder(c);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "[atlas] %s rings %d: %s\n", name, n, e.what());
        continue;
      }
      row.wall_s = seconds_since(t0);
      double worst = 0.0;
      // The first circle is skipped: its stencils reach beyond the surface (as in the test).
      for (int ring = 1; ring < n; ++ring) {
        const double r = prof.radius[ring];
        double sr, st;
        if (!plastic) {
          mps::lame_stresses(c, r, sr, st);
        } else if (r < hill_c) {
          sr = -c.pressure_pa + 2 * k * std::log(r / c.inner_m);
          st = sr + 2 * k;
        } else {
          const double b = c.outer_m;
          sr = -k * hill_c * hill_c / (b * b) * (b * b / (r * r) - 1);
          st = k * hill_c * hill_c / (b * b) * (b * b / (r * r) + 1);
        }
        worst = std::max({worst, std::fabs(prof.sigma_r[ring] - sr), std::fabs(prof.sigma_theta[ring] - st)});
      }
      row.error = worst / c.pressure_pa;
      row.particles = static_cast<size_t>(prof.particles);
      row.bonds = static_cast<size_t>(prof.bonds);
      row.steps = prof.steps;
      sink(row);
    }
  }
}

void mps_tension_stability(const SweepPlan& plan, CsvTable& table) {
  const Rock rock;
  const double h = 1e-3, L = 0.04;
  const int nx = 40, ny = 10;
  const std::vector<double> strains = plan.quick ? std::vector<double>{0.01, 0.1, 0.5}
                                                 : std::vector<double>{0.01, 0.03, 0.1, 0.2, 0.3, 0.5, 1.0};
  const double c_l = std::sqrt((rock.lambda() + 2 * rock.mu()) / rock.density);
  // Ramp over eight transit times (quasi-static pull) or half of one (a tension wave).
  for (const double ramp_transits : {8.0, 0.5})
  for (const bool repulsive : {false, true})
    for (const double alpha : {0.0, 0.1})
      for (const double strain : strains) {
        std::vector<double> pos, vol;
        strip(nx, ny, h, pos, vol);
        mps::SolidOptions opt;
        opt.dimension = 2;
        opt.spacing_m = h;
        opt.thickness_m = h;
        opt.hourglass = alpha;
        opt.pressure = repulsive ? mps::PressureForce::Repulsive : mps::PressureForce::Conservative;
        mps::Solid solid(pos, vol, rock.density, elastic_law(rock), opt);
        // Two particle columns at each end are driven: u_x = -/+ strain(t) L / 2, the strain
        // ramped smoothly over the ramp, then held for four transit times (strip_pull.hpp).
        const double ramp = ramp_transits * L / c_l, end = ramp + 4 * L / c_l;
        const mps::StripPull pull = mps::strip_pull(solid, L, h, strain, ramp);
        std::string status = "stable", detected = "-", message;
        double min_ratio = 1.0, max_speed = 0.0, worst_x = 0.0, worst_y = 0.0;
        long long first_detection = -1;
        try {
          while (solid.time_s() < end) {
            solid.step();
            const double t = solid.time_s();
            mps::drive_strip_pull(solid, pull);
            if (solid.steps() % 10 == 0) {
              const mps::Clumping cl = mps::measure_clumping(solid);
              if (cl.min_ratio < min_ratio) {
                min_ratio = cl.min_ratio;
                worst_x = pos[3 * cl.worst_particle];
                worst_y = pos[3 * cl.worst_particle + 1];
              }
              if (cl.clumped_bonds > 0 && first_detection < 0) first_detection = solid.steps();
              for (size_t i = 0; i < solid.size(); ++i)
                if (!std::isfinite(solid.displacement(0)[i]) || !std::isfinite(solid.displacement(1)[i])) {
                  throw RunError("non-finite displacement at t = " + std::to_string(t) + " s");
                }
            }
          }
        } catch (const RunError& e) {
          status = std::string(e.what()).find("clumping") != std::string::npos ? "stopped" : "unstable";
          // The ratio at the stop (the study's own measure runs after the step that threw).
          if (status == "stopped") min_ratio = std::min(min_ratio, mps::measure_clumping(solid).min_ratio);
          message = e.what();
          detected = message.find("det F") != std::string::npos      ? "det F <= 0 (Solid::step)"
                     : message.find("clumping") != std::string::npos ? "clumping check (Solid::step)"
                                                                     : "non-finite";
        }
        if (first_detection >= 0) {
          if (status == "stable") status = "clumping";
          detected = (detected == "-" ? "" : detected + " + ") + "clumping check at step " + std::to_string(first_detection);
        }
        for (size_t i = 0; i < solid.size(); ++i)
          max_speed = std::max(max_speed, std::hypot(solid.velocity(0)[i], solid.velocity(1)[i]));
        char line[512];
        std::snprintf(line, sizeof line, "%.3g,%s,%.3g,%.4g,%zu,%zu,%lld,%.4g,%.4g,%s,%s,", ramp_transits, repulsive ? "repulsive" : "conservative",
                      alpha, strain, solid.size(), solid.bonds().size(), solid.steps(), min_ratio,
                      max_speed / (strain * c_l + 1e-300), status.c_str(), detected.c_str());
        table.add(std::string(line) + message_field(message));
        std::fprintf(stderr, "[atlas] stability mps ramp %.1f %s alpha %.2f strain %.3g: %s, min neighbour ratio %.3g at (%.1f, %.1f) mm (%s)\n",
                     ramp_transits, repulsive ? "repulsive" : "conservative", alpha, strain, status.c_str(), min_ratio, worst_x * 1e3, worst_y * 1e3, detected.c_str());
      }
}

}  // namespace breccia::atlas
