// Pressure through the facets of a real gmsh mesh: the concrete block's blind charge hole.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "breccia/solver/calibration.hpp"
#include "breccia/solver/run.hpp"
#include "helpers.hpp"
#include "measures.hpp"  // tools/atlas: the quasi-static bar's span strain

using namespace breccia;
using namespace breccia::solver;
using namespace breccia::solver::testing;

TEST(Loads, PressureInABlindHoleOfAMeshPushesOnlyOnTheHoleBottom) {
  // The hole wall is closed around the axis, so its pressure resultant vanishes; what is
  // left is P times the (faceted) bottom disc, pointing down into the block.
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/mesh_loads";
  std::filesystem::create_directories(dir);
  const std::string spec = std::string(BRECCIA_SOURCE_DIR) + "/cases/concrete-blast/specimen-quick.yaml";
  const std::string cmd = std::string(BRECCIA_MESH_EXE) + " " + spec + " -o " + dir + "/s.msh --quiet > /dev/null 2>&1 && " +
                          BRECCIA_PLACE_EXE + " " + dir + "/s.msh -o " + dir + "/particles.h5 > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  PdSystem s = system_from_yaml("mesh_loads", "specimen: {particles: " + dir + "/particles.h5}\n"
      "model: {type: lps, horizon_factor: 3.015}\n"
      "materials: [{name: concrete, density: 2320, youngs_modulus: 34.2 GPa, poisson_ratio: 0.25}]\n"
      "loads: [{type: pressure, surface: charge_hole, history: {type: constant, value: 1 GPa}}]\n"
      "time: {steps: 1}\n");
  compute_external(s, 0.0);
  double f[3] = {0, 0, 0};
  for (size_t i = 0; i < s.n; ++i)
    for (int d = 0; d < 3; ++d) f[d] += s.volume[i] * s.body[3 * i + d];
  // Exactly P times the area of the hole's bottom facets (round-off) ...
  const SurfaceFacets* hole = s.particles.find_surface("charge_hole");
  double bottom = 0, wall = 0;
  for (size_t k = 0; k < hole->size(); ++k) {
    wall += hole->area_m2[k] * 1e9;
    if (hole->normal[3 * k + 2] > 0.999) bottom += hole->area_m2[k];
  }
  EXPECT_NEAR(f[2], -1e9 * bottom, 1e-9 * wall) << "vertical resultant " << f[2] << " N";
  // ... and that area is the faceted disc of radius 10 mm: a polygon of 7 or more sides
  // inscribed in the circle holds between 0.871 (heptagon) and 1 of pi r^2.
  const double ratio = bottom / (std::numbers::pi * 0.01 * 0.01);
  EXPECT_GT(ratio, 0.85);
  EXPECT_LE(ratio, 1.0);
  // The wall's sideways resultant cancels: round-off against the wall's total |force|.
  EXPECT_LT(std::hypot(f[0], f[1]), 1e-9 * wall);
}

namespace {

// Particles at the centroids of a gmsh mesh of the body in `specimen` (a breccia-mesh
// specimen file's text), meshed once per process under `name`; empty if meshing failed.
std::string meshed_particles(const std::string& name, const std::string& specimen, const std::string& place_options) {
  const std::string path = breccia::solver::testing::process_temp_dir() + "/" + name + "/particles.h5";
  if (std::filesystem::exists(path)) return path;
  return breccia::solver::testing::mesh_and_place(name, specimen, place_options);
}

// Particles at the centroids of a uniform gmsh tet mesh of a 100 mm cube (~10,000 tets).
std::string tet_cube_particles() {
  return meshed_particles("tet_cube", "dimension: 3\nbody: {shape: box, name: solid, origin: [0, 0, 0], "
                                      "size: [100 mm, 100 mm, 100 mm]}\nmesh: {size: 8 mm}\n", "");
}

// Volume-weighted mean relative error of the strain-energy density over particles more
// than two horizons from every face of the cube.
double interior_energy_error(const char* model, double nu, const double eps[9]) {
  const std::string file = tet_cube_particles();
  EXPECT_FALSE(file.empty()) << "could not mesh the test cube";
  PdSystem s = system_from_yaml(std::string("tet_energy_") + model,
      "specimen: {particles: " + file + "}\nmodel: {type: " + model + ", horizon_factor: 3.015}\n"
      "materials: [{name: solid, density: 2000, youngs_modulus: 10 GPa, poisson_ratio: " + std::to_string(nu) + "}]\n"
      "time: {steps: 1}\n");
  impose_affine(s, eps);
  cpu_compute_forces(s);
  ElasticInput in{3, Planar::None, 10e9, nu, 1.0};
  const double w_classical = classical_energy_density(in, eps);
  const double margin = 2.0 * s.horizon[0];
  double sum = 0, vol = 0;
  for (size_t i = 0; i < s.n; ++i) {
    bool interior = true;
    for (int d = 0; d < 3; ++d) interior = interior && s.x0[3 * i + d] > margin && s.x0[3 * i + d] < 0.1 - margin;
    if (!interior) continue;
    sum += s.volume[i] * s.energy_density[i];
    vol += s.volume[i];
  }
  EXPECT_GT(vol, 0.0);
  return (sum / vol - w_classical) / w_classical;
}

}  // namespace

// 3% on tet-centroid particles (looser than on a lattice): an irregular family is
// not isotropic particle by particle; averaged over the interior its fourth-order moment
// deviates by up to a few percent from isotropy at m = 3 (measured here: PMB -0.9%,
// LPS +0.2% for uniaxial strain, shear and expansion), while the
// calibration makes isotropic expansion exact on average by construction.
TEST(StrainEnergy, TetCentroidParticlesFromAGmshMeshMatchClassicalEnergyOnAverage) {
  const double uniaxial[9] = {1e-4, 0, 0, 0, 0, 0, 0, 0, 0};
  const double shear[9] = {0, 1e-4, 0, 1e-4, 0, 0, 0, 0, 0};
  const double expansion[9] = {1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4};
  for (const double* eps : {uniaxial, shear, expansion}) {
    const double pmb = interior_energy_error("pmb", 0.25, eps), lps = interior_energy_error("lps", 0.3, eps);
    std::printf("tet-centroid interior energy error: PMB %+.4f  LPS %+.4f\n", pmb, lps);
    EXPECT_NEAR(pmb, 0.0, 0.03);
    EXPECT_NEAR(lps, 0.0, 0.03);
  }
}

TEST(Precracks, ANamedMeshSurfaceCutsExactlyTheBondsItsPolygonCuts) {
  // A 40 mm cube with a 20 x 20 mm crack embedded at mid-height (gmsh fragment: the mesh
  // conforms to it). The named surface's facets are recovered exactly from their owner
  // tets, so it must remove the same bonds as the analytic square polygon; the former
  // disc-per-facet rule both leaked (gaps at facet corners) and over-cut (disc edges).
  const std::string dir = breccia::solver::testing::process_temp_dir() + "/named_crack";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/spec.yaml") << "dimension: 3\n"
      "body: {shape: box, name: block, origin: [0, 0, 0], size: [40 mm, 40 mm, 40 mm]}\n"
      "notches:\n  - {name: notch, type: crack, corner: [10 mm, 10 mm, 20 mm], edge_a: [20 mm, 0, 0], edge_b: [0, 20 mm, 0]}\n"
      "mesh: {size: 4 mm}\n";
  const std::string cmd = std::string(BRECCIA_MESH_EXE) + " " + dir + "/spec.yaml -o " + dir + "/s.msh --quiet > /dev/null 2>&1 && " +
                          BRECCIA_PLACE_EXE + " " + dir + "/s.msh -o " + dir + "/particles.h5 > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const std::string head = "specimen: {particles: " + dir + "/particles.h5}\nmodel: {type: pmb, horizon_factor: 3.015}\n"
      "materials: [{name: block, density: 2000, youngs_modulus: 30 GPa, poisson_ratio: 0.25}]\ntime: {steps: 1}\n";
  PdSystem by_surface = system_from_yaml("named_crack_surface", head + "precracks: [{type: surface, surface: notch}]\n");
  PdSystem by_polygon = system_from_yaml("named_crack_polygon", head +
      "precracks: [{type: polygon, points: [[0.01, 0.01, 0.02], [0.03, 0.01, 0.02], [0.03, 0.03, 0.02], [0.01, 0.03, 0.02]]}]\n");
  ASSERT_GT(by_polygon.precrack_pairs.size(), 100u);
  // Exact: both are exact geometry and no particle lies on the plane (centroids of tets
  // on either side of a conforming surface).
  EXPECT_EQ(by_surface.precrack_pairs, by_polygon.precrack_pairs);
}

TEST(Precracks, ASegmentEndingOnABondLineCutsBothHalvesOfEveryPair) {
  // A 2D lattice (centres at (k + 1/2) h) and a crack along the row gap y = 5 mm whose tip
  // moves in quarter spacings: at x = 10 mm the tip lies exactly on the line of the
  // diagonal bonds (9.75, 4.75)-(10.25, 5.25) mm. The crossing test is then decided by a
  // vanishing orientation whose sign depends on the bond's direction; a pair cut on one
  // side only gave unbalanced forces (a fracture-free DCB gained 39 % of the work). The
  // rule: every pair is cut on both sides or on neither (exact, a property of the set-up).
  for (const char* tip : {"0.01", "0.010125", "0.01025", "0.0105", "0.011", "0.0115"}) {
    const std::string yaml = std::string(
        "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}\n"
        "model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}\n"
        "materials: [{name: glass, density: 2440, youngs_modulus: 72 GPa, poisson_ratio: 0.3333333333333333, fracture_energy: 3.8}]\n"
        "precracks: [{type: segment, from: [0, 0.005], to: [") + tip + ", 0.005]}]\ntime: {steps: 1}\n";
    const PdSystem s = system_from_yaml("tip_on_bond_line", yaml);
    ASSERT_GT(s.precrack_pairs.size(), 10u) << "tip " << tip;
    size_t one_sided = 0;
    for (size_t i = 0; i < s.n; ++i)
      for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) {
        const int32_t j = s.neighbor[k];
        for (int64_t r = s.offsets[j]; r < s.offsets[j + 1]; ++r)
          if (s.neighbor[r] == static_cast<int32_t>(i) && (s.state[r] == 0) != (s.state[k] == 0)) ++one_sided;
      }
    EXPECT_EQ(one_sided, 0u) << "tip at x = " << tip << " m";
  }
}

// LPS with the energy surface correction on coarse triangle centroids: the quasi-static strip
// of docs/atlas.md "Quasi-static bar" (100 x 20 mm, plane stress, 100 MPa end traction, the
// atlas's triangle mesh at dx 2 mm: 538 particles, ~10 across the width). At m = 5 the horizon
// is half the width, so no family is complete. Analytic answer: uniform uniaxial stress, strain
// sigma / E away from the ends (Saint-Venant). Measured (2026-12-04): the gauge strain
// (least-squares slope of u_x over 30 <= x <= 70 mm, every particle) is -0.55 % (m = 3) and
// -0.22 % (m = 5) off sigma / E with the correction, -12.5 % and -14.0 % (too stiff: the
// truncated families' fourth moment along the faces) without it. Tolerance 1.5 %: LPS's own
// calibration error on tet centroids, the homogeneous strain energy 0.18-1.4 % at m = 5
// (docs/atlas.md, "Homogeneous strain energy"). The end-to-end displacement the atlas reports
// (21 % at m = 5) is another thing: the pull-out of the single loaded (and held) particle
// layer over one horizon at each end, the same with and without the correction (docs/atlas.md).
namespace {
double coarse_strip_gauge_strain_error(const std::string& correction, double m) {
  const std::string file =
      meshed_particles("tri_strip", "dimension: 2\nbody: {shape: rectangle, name: solid, origin: [0, 0], "
                                    "size: [0.1, 0.02]}\nmesh: {size: 0.00303030303}\n", "--thickness 0.001");
  EXPECT_FALSE(file.empty()) << "could not mesh the strip";
  if (file.empty()) return 1.0;
  PdSystem s = system_from_yaml("tri_strip_" + correction,
      "specimen: {particles: " + file + "}\nmodel: {type: lps, planar: plane_stress, horizon_factor: " +
      std::to_string(m + 0.015) + ", surface_correction: " + correction + "}\n"
      "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]\n"
      "boundary: [{type: fixed, set: xmin, components: [x]}]\n"
      "loads: [{type: traction, surface: xmax, value: [100 MPa, 0, 0]}]\n"
      "time: {integrator: adr, adr_tolerance: 1e-7, adr_max_steps: 400000}\n");
  s.fixed_dof[nearest(s, 0, 0, 0)] |= 2u;  // no sideways drift
  const long long iterations = relax_to_equilibrium(s, false);
  EXPECT_GT(iterations, 0) << "ADR did not converge";
  double n = 0, sx = 0, su = 0, sxx = 0, sxu = 0;
  for (size_t i = 0; i < s.n; ++i) {
    const double x = s.x0[3 * i], u = s.u[3 * i];
    if (x < 0.03 || x > 0.07) continue;
    n += 1, sx += x, su += u, sxx += x * x, sxu += x * u;
  }
  const double slope = (n * sxu - sx * su) / (n * sxx - sx * sx);
  return slope / (100e6 / 200e9) - 1.0;
}
}  // namespace

TEST(QuasiStatic, LpsWithSurfaceCorrectionOnCoarseTriangleCentroidsHasTheBulkStrainInTheGauge) {
  // m = 5, the atlas's worst end-to-end error (m = 3 measured as well, above).
  const double error = coarse_strip_gauge_strain_error("energy", 5.0);
  std::printf("LPS coarse triangle strip, m = 5: gauge strain / (sigma / E) - 1 = %+.4f\n", error);
  EXPECT_NEAR(error, 0.0, 0.015);
}

// The same strip loaded and held over boundary layers one horizon deep (the traction's
// `depth: horizon`, a grip of the particles within a horizon of xmin held in x), the set-up
// of the atlas's quasi_static_bar: between the layers the stress is uniform, so the strain
// of that span (least-squares slope of u_x over delta <= x <= L - delta, every particle) is
// sigma / E (Saint-Venant; uniaxial plane stress). Tolerance 1.5 %: LPS's own calibration
// error on tet centroids, as above. Measured 2026-12-04 (m = 5, with the correction): 0.13 %
// with the layers; the same span of the single-layer set-up reads 0.01 % (printed, not
// checked: the pull-out stays within a horizon of the end layers, outside the span).
namespace {
double coarse_strip_span_strain_error(bool layered, double m) {
  const std::string file =
      meshed_particles("tri_strip", "dimension: 2\nbody: {shape: rectangle, name: solid, origin: [0, 0], "
                                    "size: [0.1, 0.02]}\nmesh: {size: 0.00303030303}\n", "--thickness 0.001");
  EXPECT_FALSE(file.empty()) << "could not mesh the strip";
  if (file.empty()) return 1.0;
  const double delta = (m + 0.015) * 0.002;  // the atlas's horizon at its 2 mm triangle spacing
  const std::string ends =
      layered ? "sets: [{name: grip, near_surface: {surface: xmin, distance: " + std::to_string(delta) +
                    "}}]\nboundary: [{type: fixed, set: grip, components: [x]}]\n"
                    "loads: [{type: traction, surface: xmax, value: [100 MPa, 0, 0], depth: horizon}]\n"
              : "boundary: [{type: fixed, set: xmin, components: [x]}]\n"
                "loads: [{type: traction, surface: xmax, value: [100 MPa, 0, 0]}]\n";
  PdSystem s = system_from_yaml(std::string("tri_strip_span_") + (layered ? "layered" : "single"),
      "specimen: {particles: " + file + "}\nmodel: {type: lps, planar: plane_stress, horizon_factor: " +
      std::to_string(m + 0.015) + ", surface_correction: energy}\n"
      "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]\n" +
      ends + "time: {integrator: adr, adr_tolerance: 1e-7, adr_max_steps: 400000}\n");
  long long iterations = 0;
  const double error = atlas::bar_span_strain_error(s, 100e6, 200e9, delta, 0.1 - delta, &iterations);
  EXPECT_GT(iterations, 0) << "ADR did not converge";
  return error;
}
}  // namespace

TEST(QuasiStatic, TractionSpreadOverAHorizonGivesSigmaOverEBetweenTheBoundaryLayersOnCoarseTriangles) {
  const double layered = coarse_strip_span_strain_error(true, 5.0);
  const double single = coarse_strip_span_strain_error(false, 5.0);
  std::printf("LPS coarse triangle strip, m = 5, span between the layers: |strain / (sigma / E) - 1| = %.4f "
              "(load and grip a horizon deep), %.4f (single end layers)\n", layered, single);
  EXPECT_LT(layered, 0.015);
}

// What `depth` does to the load: the surface's total force, spread over the particles within
// the depth of it in proportion to their volume (a uniform body force). Exact up to round-off.
TEST(Loads, TractionDepthSpreadsTheSurfaceForceUniformlyOverTheLayer) {
  const std::string base =
      "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}\n"
      "model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}\n"
      "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]\n"
      "time: {steps: 1}\n";
  PdSystem one = system_from_yaml("depth_one", base + "loads: [{type: traction, surface: xmax, value: [100 MPa, 0, 0]}]\n");
  PdSystem deep = system_from_yaml("depth_deep",
      base + "loads: [{type: traction, surface: xmax, value: [100 MPa, 0, 0], depth: horizon}]\n");
  compute_external(one, 0.0);
  compute_external(deep, 0.0);
  double f_one = 0, f_deep = 0;
  const double delta = 3.015 * 0.5e-3, body = 100e6 * 0.01 * 0.001;  // sigma x end face (10 mm x 1 mm)
  size_t loaded = 0;
  double layer_volume = 0;
  for (size_t i = 0; i < one.n; ++i) {
    f_one += one.volume[i] * one.body[3 * i];
    f_deep += deep.volume[i] * deep.body[3 * i];
    // The lattice's face lies half a spacing beyond the outer particles (x = 0.02 m).
    const bool in_layer = 0.02 - deep.x0[3 * i] <= delta;
    if (in_layer) ++loaded, layer_volume += deep.volume[i];
    EXPECT_EQ(deep.body[3 * i] != 0.0, in_layer) << "particle at x = " << deep.x0[3 * i];
  }
  EXPECT_NEAR(f_one, body, 1e-9 * body);
  EXPECT_NEAR(f_deep, body, 1e-9 * body);
  EXPECT_EQ(loaded, 3u * 20u);  // x = 19.75, 19.25, 18.75 mm: within 1.5075 mm of the face
  for (size_t i = 0; i < deep.n; ++i)
    if (deep.body[3 * i] != 0.0) EXPECT_NEAR(deep.body[3 * i], body / layer_volume, 1e-9 * body / layer_volume);
}

// `depth` belongs to traction loads; elsewhere it is bad input naming the field.
TEST(Loads, TractionDepthOnAPressureLoadOrNotALengthIsAnInputErrorNamingTheField) {
  const std::string base =
      "specimen: {lattice: {dimension: 2, box: [0, 0, 0.02, 0.01], spacing: 0.5 mm, thickness: 1 mm}}\n"
      "model: {type: pmb, planar: plane_stress, horizon_factor: 3.015}\n"
      "materials: [{name: steel, density: 7850, youngs_modulus: 200 GPa, poisson_ratio: 0.3333333333333333}]\n"
      "time: {steps: 1}\n";
  for (const std::string load : {"{type: pressure, surface: xmax, history: {type: constant, value: 1 MPa}, depth: 1 mm}",
                                 "{type: traction, surface: xmax, value: [1 MPa, 0, 0], depth: deep}",
                                 "{type: traction, surface: xmax, value: [1 MPa, 0, 0], depth: -1 mm}"}) {
    try {
      system_from_yaml("depth_bad", base + "loads: [" + load + "]\n");
      ADD_FAILURE() << "accepted " << load;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "loads[0].depth") << e.what();
    }
  }
}
