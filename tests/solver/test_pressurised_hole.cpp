// Quasi-static pressurised hole in a thick ring of the concrete of cases/concrete-blast, with
// its quasi-brittle (bilinear softening) bonds, at the case's demo resolution near the hole
// (tets of 5 mm at the wall, 19 mm far; LPS, Gaussian influence, dual horizon, m = 3.015).
//
// Specimen: a cylinder of outer radius b = 150 mm (the block's inscribed cylinder), 45 mm
// high, with a through hole of radius a = 10 mm along its axis; top, bottom and outside free.
// Its faces are free, so the elastic answer is Lame's thick cylinder in plane stress
// (Timoshenko & Goodier, Theory of Elasticity, 3rd ed., 1970, sec. 28):
//   u_r(r) = p a^2 / (E (b^2 - a^2)) [ (1 - nu) r + (1 + nu) b^2 / r ],
//   sigma_theta(a) = p (b^2 + a^2) / (b^2 - a^2) = 1.009 p,
// so the hoop stress reaches sigma_t = 3.0 MPa at p = 2.97 MPa (docs/benchmarks.md,
// "Pressurised hole").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "breccia/solver/pd_system.hpp"
#include "helpers.hpp"

using namespace breccia;
using namespace breccia::solver;
using namespace breccia::solver::testing;

namespace {

constexpr double kE = 34.2e9, kNu = 0.25, kSigmaT = 3.0e6, kA = 0.010, kB = 0.150, kHeight = 0.045;

std::string ring_particles(const std::string& name, const std::string& hole_size, const std::string& far_size) {
  return mesh_and_place(name,
                        "dimension: 3\n"
                        "body: {shape: cylinder, name: concrete, origin: [0, 0, 0], radius: 150 mm, height: 45 mm}\n"
                        "holes: [{name: charge_hole, centre: [0, 0, 45 mm], axis: [0, 0, -1], radius: 10 mm}]\n"
                        "mesh: {size: " + far_size + ", refine: [{near: charge_hole, size: " + hole_size +
                            ", distance_min: 5 mm, distance_max: 80 mm}], optimize: true, algorithm_3d: delaunay}\n");
}

// The case's model and material (cases/concrete-blast/case.yaml) without the Weibull scatter,
// a pressure on the hole's wall, relaxed by ADR.
std::string ring_case(const std::string& particles, const std::string& material_extra = "",
                      const std::string& model_extra = "", const std::string& tolerance = "3e-5",
                      const std::string& max_steps = "5000") {
  EXPECT_FALSE(particles.empty()) << "could not mesh the ring";
  return "specimen: {particles: " + particles + "}\n"
         "model: {type: lps, influence: gaussian, variable_horizon: true, horizon_factor: 3.015" + model_extra + "}\n"
         "materials: [{name: concrete, density: 2320 kg/m3, youngs_modulus: 34.2 GPa, poisson_ratio: 0.25,"
         " fracture_energy: 25 J/m2, tensile_strength: 3.0 MPa" + material_extra + "}]\n"
         "loads: [{type: pressure, surface: charge_hole, history: {type: constant, value: 1 MPa}}]\n"
         "time: {integrator: adr, adr_tolerance: " + tolerance + ", adr_max_steps: " + max_steps + "}\n";
}

double lame_ur(double p, double r, double b = kB) {
  return p * kA * kA / (kE * (b * b - kA * kA)) * ((1 - kNu) * r + (1 + kNu) * b * b / r);
}

// The pressure on an open tube of facets leaves a small net force (its residual is the ADR's
// floor), which drifts the body rigidly: u_r is measured from the volume-weighted mean motion.
void mean_drift(const PdSystem& s, double drift[2]) {
  double v = 0;
  drift[0] = drift[1] = 0;
  for (size_t i = 0; i < s.n; ++i) {
    drift[0] += s.u[3 * i] * s.volume[i];
    drift[1] += s.u[3 * i + 1] * s.volume[i];
    v += s.volume[i];
  }
  drift[0] /= v;
  drift[1] /= v;
}

struct RingState {
  double wall_r = 0, wall_hoop = 0, lame_hoop = 0;  // the wall particles' mean radius, u_r / r, Lame's there
  double max_ratio = 0;                             // largest bond stretch / onset stretch
  double max_ratio_r = 0, max_ratio_cos = 0;        // its particle's radius, |cos| of its bond to the radial
  int softening = 0, broken_particles = 0;          // particles with damage > 0.01, > 0.5
  double crack_reach = 0;                           // largest radius of a particle with damage > 0.5
  long long broken_bonds = 0;
};

RingState measure_ring(PdSystem& s, double p, double b = kB) {
  s.diagnostics = true;
  cpu_compute_forces(s);
  RingState m;
  double drift[2];
  mean_drift(s, drift);
  const auto* hole = s.particles.find_surface("charge_hole");
  std::vector<char> wall(s.n, 0);
  for (size_t f = 0; f < hole->size(); ++f) wall[s.internal_index[hole->particle[f]]] = 1;
  int nw = 0;
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], y = s.x0[3 * i + 1];
    const double r = std::hypot(x, y);
    if (wall[i]) {
      const double ur = ((s.u[3 * i] - drift[0]) * x + (s.u[3 * i + 1] - drift[1]) * y) / r;
      m.wall_r += r;
      m.wall_hoop += ur / r;
      m.lame_hoop += lame_ur(p, r, b) / r;
      ++nw;
    }
    if (s.damage[i] > 0.01) ++m.softening;
    if (s.damage[i] > 0.5) {
      ++m.broken_particles;
      m.crack_reach = std::max(m.crack_reach, r);
    }
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
      if (!s.state[k]) {  // both halves broken
        ++m.broken_bonds;
        continue;
      }
      const size_t j = static_cast<size_t>(s.neighbor[k]);
      double d[3], len = 0;
      for (int c = 0; c < 3; ++c) d[c] = s.x[3 * j + c] - s.x[3 * i + c], len += d[c] * d[c];
      const double stretch = (std::sqrt(len) - s.xi_len[k]) / s.xi_len[k];
      const double ratio = stretch / s.s_onset[k];
      if (ratio > m.max_ratio) {
        m.max_ratio = ratio;
        m.max_ratio_r = r;
        const double e0[3] = {s.x0[3 * j] - x, s.x0[3 * j + 1] - s.x0[3 * i + 1], s.x0[3 * j + 2] - s.x0[3 * i + 2]};
        m.max_ratio_cos = std::abs(e0[0] * x + e0[1] * y) / (r * s.xi_len[k]);
      }
    }
  }
  m.wall_r /= nw;
  m.wall_hoop /= nw;
  m.lame_hoop /= nw;
  return m;
}

// Mean u_r / Lame's u_r in radial bins (mm edges), and the wall bonds' onset stretch.
void print_profile(const PdSystem& s, double p, double b) {
  const double edges[] = {0, 12, 15, 20, 30, 50, 80, 120, 1e9};
  double num[8] = {0}, den[8] = {0};
  int cnt[8] = {0};
  double drift[2];
  mean_drift(s, drift);
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], y = s.x0[3 * i + 1], r = std::hypot(x, y);
    int k = 0;
    while (r * 1e3 >= edges[k + 1]) ++k;
    num[k] += ((s.u[3 * i] - drift[0]) * x + (s.u[3 * i + 1] - drift[1]) * y) / r;
    den[k] += lame_ur(p, r, b);
    ++cnt[k];
  }
  std::printf("u_r / Lame by ring:");
  for (int k = 0; k < 8; ++k)
    if (cnt[k]) std::printf(" [%g,%g) %.4f (%d)", edges[k], edges[k + 1], num[k] / den[k], cnt[k]);
  const int64_t w = s.internal_index[s.particles.find_surface("charge_hole")->particle[0]];
  std::printf("\nonset stretch at the wall %.4e = sigma_t / E / %.4f\n", s.s_onset[s.offsets[w]],
              kSigmaT / kE / s.s_onset[s.offsets[w]]);
}

void set_pressure(PdSystem& s, double p) {
  for (auto& load : s.config.loads) load.history.value = p;
}

// The quick ring: b = 40 mm, 20 mm high, the demo's 5 mm tets at the wall (1,952 particles).
std::string small_ring_particles() {
  return mesh_and_place("ring_small",
                        "dimension: 3\n"
                        "body: {shape: cylinder, name: concrete, origin: [0, 0, 0], radius: 40 mm, height: 20 mm}\n"
                        "holes: [{name: charge_hole, centre: [0, 0, 20 mm], axis: [0, 0, -1], radius: 10 mm}]\n"
                        "mesh: {size: 8 mm, refine: [{near: charge_hole, size: 5 mm, distance_min: 5 mm, distance_max: 25 mm}],"
                        " optimize: true, algorithm_3d: delaunay}\n");
}

}  // namespace

// The onset of softening at the wall, from one elastic ADR solve at p_ref = 1 MPa: the first
// bond reaches its onset stretch at p_ref / max(stretch / onset) (linear below it). Lame's
// estimate of the crack's start, sigma_theta(a) = sigma_t, is p_L = sigma_t (b^2 - a^2) /
// (b^2 + a^2) = 2.65 MPa here. The bonds soften earlier than that by construction: the onset
// stretch is sigma_t / (E Phi) with Phi = 1.448 at this horizon (the homogeneous peak over the
// onset, docs/theory.md "Quasi-brittle bonds"), and at the wall the radial compression adds
// nu to the hoop strain, eps_theta = (1 + nu) sigma_theta / E; so a local continuum with these
// bonds starts to soften at p_L / (Phi (1 + nu)) = 1.46 MPa. Measured 0.98 MPa: the wall's
// particles, whose families the hole cuts and whose layer alone carries the pressure, take
// 1.27 times Lame's hoop strain. A wall made too strong (facets with too little area, normals
// pointing wrong, bonds stiffened at the surface) would push the onset above the local
// estimate: the bound below. The lower bound, half the local estimate, allows the measured
// skin's 1.27 with a margin of 1.2 (a crack starting at 0.6 MPa would be a defect too).
TEST(PressurisedHole, TheWallStartsToSoftenBeforeLamesHoopStressReachesTheTensileStrength) {
  const double b = 0.040;
  PdSystem s = system_from_yaml("ring_small", ring_case(small_ring_particles(), "", "", "1e-9", "300"));
  set_pressure(s, 1e6);
  relax_to_equilibrium(s, false);  // 300 iterations: the residual's floor (3.6e-4, the open tube's net force) by ~100
  const RingState m = measure_ring(s, 1e6, b);
  ASSERT_EQ(m.softening, 0) << "p_ref must lie below the onset";
  const double p_onset = 1e6 / m.max_ratio;
  const double p_lame = kSigmaT * (b * b - kA * kA) / (b * b + kA * kA);
  const int64_t w = s.internal_index[s.particles.find_surface("charge_hole")->particle[0]];
  const double phi = kSigmaT / kE / s.s_onset[s.offsets[w]];
  EXPECT_NEAR(phi, 1.448, 0.01) << "the calibration's Phi at this horizon";
  const double p_local = p_lame / (phi * (1 + kNu));
  EXPECT_LE(p_onset, p_local) << "onset " << p_onset << " Pa, local estimate " << p_local << " Pa, Lame " << p_lame;
  EXPECT_GE(p_onset, 0.5 * p_local) << "onset " << p_onset << " Pa, local estimate " << p_local << " Pa";
  EXPECT_LT(m.max_ratio_r, kA + 0.003) << "the first bond to soften lies at the wall";
  // The wall's hoop strain against Lame's (plane stress, the particles' own radii): 1.27
  // measured; more than 1.5 or less than Lame's would be a new defect of the wall's load.
  EXPECT_GT(m.wall_hoop / m.lame_hoop, 1.0);
  EXPECT_LT(m.wall_hoop / m.lame_hoop, 1.5);
}

// The ring of docs/benchmarks.md ("Pressurised hole"), elastic at 1 MPa, without and with the
// surface correction: u_r against Lame by ring, the wall's hoop strain, the first bond's onset.
TEST(PressurisedHoleMeasurement, DISABLED_ElasticDemoRing) {
  for (const std::string model_extra : {"", ", surface_correction: energy"}) {
    PdSystem s = system_from_yaml("ring_demo", ring_case(ring_particles("ring_demo", "5 mm", "19 mm"), "", model_extra, "1e-9", "300"));
    set_pressure(s, 1e6);
    relax_to_equilibrium(s, false);
    const RingState m = measure_ring(s, 1e6);
    std::printf("%s: particles %zu wall hoop / Lame %.4f max stretch/onset %.4f at r %.1f mm |cos| %.2f softening %d\n",
                model_extra.c_str(), s.n, m.wall_hoop / m.lame_hoop, m.max_ratio, m.max_ratio_r * 1e3, m.max_ratio_cos, m.softening);
    print_profile(s, 1e6, kB);
    std::fflush(stdout);
  }
}
