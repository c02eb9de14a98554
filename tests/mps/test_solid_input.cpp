// Case keys of the stress formulation (model.formulation: stress): validation errors name
// the file and field; the CLI runs a stress case end to end and exits 2 on bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/common/json_file.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/solid_case.hpp"
#include "mps_test_util.hpp"

using namespace breccia::mps;

namespace {

// A 2D steel block falling at 1 m/s onto a rigid floor 0.5 mm below it.
const std::string kStress = R"(
specimen:
  lattice: {dimension: 2, box: [0, 0.5 mm, 10 mm, 5.5 mm], spacing: 0.5 mm, thickness: 1 mm}
model: {type: mps, formulation: stress, hourglass: 0.1, pressure_force: conservative}
materials:
  - {name: steel, density: 7850, youngs_modulus: 210 GPa, poisson_ratio: 0.3,
     plasticity: {yield_stress: 240 MPa, hardening_modulus: 1 GPa}}
initial: {velocity: [0, -1 m/s]}
contact: {floor: {point: [0, 0], normal: [0, 1]}}
time: {end: 1 us, safety: 0.3}
)";

std::string replaced(const std::string& from, const std::string& to) { return test::replace_once(kStress, from, to); }

std::string error_of(const std::string& yaml) {
  return test::input_error_of([&] { make_solid(parse_case_text(yaml, "case.yaml")); });
}

struct CliResult {
  int exit_code = -1;
  std::string stderr_text;
};

CliResult run_cli(const std::string& yaml, const std::filesystem::path& dir) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "case.yaml") << yaml;
  const std::string cmd = std::string(BRECCIA_MPS_EXE) + " " + (dir / "case.yaml").string() + " -o " +
                          (dir / "out").string() + " --threads 1 2> " + (dir / "stderr.txt").string();
  const int status = std::system(cmd.c_str());
  CliResult r;
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  std::ifstream err(dir / "stderr.txt");
  std::ostringstream text;
  text << err.rdbuf();
  r.stderr_text = text.str();
  return r;
}

}  // namespace

TEST(MpsSolidInput, GoodStressCaseBuildsWithItsKeys) {
  const CaseSpec spec = parse_case_text(kStress, "case.yaml");
  EXPECT_EQ(spec.formulation, Formulation::Stress);
  ASSERT_TRUE(spec.material.plasticity.has_value());
  EXPECT_DOUBLE_EQ(spec.material.plasticity->yield_stress_pa, 240e6);
  EXPECT_DOUBLE_EQ(spec.material.plasticity->hardening_modulus_pa, 1e9);
  ASSERT_TRUE(spec.floor.has_value());
  EXPECT_DOUBLE_EQ(spec.initial_velocity_m_s[1], -1.0);
  const Solid solid = make_solid(spec);
  EXPECT_EQ(solid.size(), 200u);  // 20 x 10 lattice
  EXPECT_TRUE(solid.law().plastic);
  EXPECT_DOUBLE_EQ(solid.velocity(1)[0], -1.0);
}

TEST(MpsSolidInput, NonPositiveYieldStressIsRejectedNamingTheField) {
  for (const std::string bad : {"yield_stress: 0", "yield_stress: -240 MPa"}) {
    const auto msg = error_of(replaced("yield_stress: 240 MPa", bad));
    EXPECT_NE(msg.find("case.yaml"), std::string::npos) << msg;
    EXPECT_NE(msg.find("materials[0].plasticity.yield_stress"), std::string::npos) << msg;
    EXPECT_NE(msg.find("yield stress > 0"), std::string::npos) << msg;
  }
}

TEST(MpsSolidInput, NegativeHardeningModulusIsRejectedNamingTheField) {
  const auto msg = error_of(replaced("hardening_modulus: 1 GPa", "hardening_modulus: -1 GPa"));
  EXPECT_NE(msg.find("materials[0].plasticity.hardening_modulus"), std::string::npos) << msg;
  EXPECT_NE(msg.find(">= 0"), std::string::npos) << msg;
}

TEST(MpsSolidInput, StressOnlyKeysAreRejectedForTheDisplacementFormulation) {
  auto msg = error_of(replaced("formulation: stress, hourglass: 0.1, pressure_force: conservative", "formulation: displacement"));
  EXPECT_NE(msg.find("plasticity"), std::string::npos) << msg;
  EXPECT_NE(msg.find("formulation: stress"), std::string::npos) << msg;
  msg = error_of(replaced("formulation: stress, ", ""));
  EXPECT_NE(msg.find("model.hourglass"), std::string::npos) << msg;
}

TEST(MpsSolidInput, UnknownChoicesAndCracksAreRejected) {
  auto msg = error_of(replaced("pressure_force: conservative", "pressure_force: attractive"));
  EXPECT_NE(msg.find("repulsive"), std::string::npos) << msg;  // the allowed choices are named
  msg = error_of(replaced("formulation: stress", "formulation: strain"));
  EXPECT_NE(msg.find("model.formulation"), std::string::npos) << msg;
  msg = error_of(kStress + "cracks: [{segment: [[4 mm, 2.25 mm], [6 mm, 2.25 mm]], static_friction: 0.5}]\n");
  EXPECT_NE(msg.find("cracks[0]"), std::string::npos) << msg;
  msg = error_of(replaced("normal: [0, 1]", "normal: [0, 0]"));
  EXPECT_NE(msg.find("contact.floor.normal"), std::string::npos) << msg;
}

TEST(MpsSolidCli, BadYieldStressExitsWithCode2AndNamesTheField) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_solid_cli_bad";
  const CliResult r = run_cli(replaced("yield_stress: 240 MPa", "yield_stress: 0 MPa"), dir);
  EXPECT_EQ(r.exit_code, breccia::kExitBadInput);
  EXPECT_EQ(r.stderr_text.rfind("error: ", 0), 0u) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("materials[0].plasticity.yield_stress"), std::string::npos) << r.stderr_text;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "results.h5"));
}

TEST(MpsSolidCli, StressCaseWritesStressAndPlasticStrainSnapshots) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_solid_cli_run";
  const CliResult r = run_cli(kStress + "output: {every: 5, energy: true, progress: false}\n", dir);
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  breccia::h5::File f((dir / "out" / "results.h5").string(), breccia::h5::File::Mode::Read);
  const auto groups = f.children("/output");
  ASSERT_GE(groups.size(), 2u);
  const auto stress = f.read_doubles("/output/" + groups.back() + "/stress");
  EXPECT_EQ(stress.size(), 6u * 200u);
  EXPECT_EQ(f.read_doubles("/output/" + groups.back() + "/eq_plastic_strain").size(), 200u);
  std::ifstream hist(dir / "out" / "history.csv");
  std::string header;
  std::getline(hist, header);
  // With a floor: its reaction (the impact force) closes the row.
  EXPECT_EQ(header,
            "time_s,plastic_fraction,kinetic_energy_J,stress_work_J,hourglass_energy_J,contact_energy_J,gravity_energy_J,"
            "floor_force_N");
  const breccia::Json summary = breccia::read_json_file(dir / "out" / "summary.json");  // strict parse
  EXPECT_EQ(summary.at("formulation"), "stress") << summary;
  EXPECT_TRUE(summary.at("friction_dissipation_j").is_number());
}

// Material damping (materials[].damping_ratio, docs/mps.md "Material damping"): the
// dissipation gets its history column and summary entries.
TEST(MpsSolidCli, MaterialDampingWritesItsDissipation) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_solid_cli_damped";
  std::string yaml = replaced("plasticity: {yield_stress: 240 MPa, hardening_modulus: 1 GPa}",
                              "damping_ratio: 0.05, damping_frequency: 100 kHz");
  // The floor 0.01 mm above the bottom row's centres: the block is struck from the start.
  yaml = test::replace_once(yaml, "floor: {point: [0, 0]", "floor: {point: [0, 0.76 mm]");
  const CliResult r = run_cli(yaml + "output: {every: 5, energy: true, progress: false}\n", dir);
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("material damping 0.05 at 1e+05 Hz"), std::string::npos) << r.stderr_text;
  std::ifstream hist(dir / "out" / "history.csv");
  std::string header;
  std::getline(hist, header);
  EXPECT_EQ(header,
            "time_s,kinetic_energy_J,stress_work_J,hourglass_energy_J,contact_energy_J,gravity_energy_J,"
            "material_damping_J,floor_force_N");
  const breccia::Json summary = breccia::read_json_file(dir / "out" / "summary.json");
  EXPECT_DOUBLE_EQ(summary.at("damping_ratio").get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(summary.at("damping_frequency_hz").get<double>(), 1e5);
  // The struck block vibrates, and its vibration is damped.
  EXPECT_GT(summary.at("material_damping_j").get<double>(), 0.0);
}

// Contact keys (docs/mps.md, "Contact"): two bodies, a frictional floor, a rigid polygon.
const std::string kBodies = R"(
specimen:
  bodies:
    dimension: 2
    spacing: 1 mm
    shapes:
      - {name: a, type: box, box: [0, 1 mm, 10 mm, 6 mm], velocity: [1 m/s, 0]}
      - {name: b, type: annulus, center: [20 mm, 4 mm], inner_radius: 0, outer_radius: 3 mm}
model: {type: mps, formulation: stress}
materials:
  - {name: rubber, density: 1000, youngs_modulus: 10 MPa, poisson_ratio: 0.3}
contact:
  particles: {distance_factor: 1, stiffness_factor: 1}
  floor: {point: [0, 0], normal: [0, 1], static_friction: 0.5, kinetic_friction: 0.4}
  rigid_bodies:
    - {name: wall, vertices: [[30 mm, 0], [40 mm, 0], [40 mm, 10 mm], [30 mm, 10 mm]], static_friction: 0.3}
time: {end: 1 us}
)";

std::string bodies_with(const std::string& from, const std::string& to) {
  std::string s = kBodies;
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return s.replace(pos, from.size(), to);
}

TEST(MpsSolidInput, TwoBodiesFloorAndPolygonBuildWithTheirKeys) {
  const CaseSpec spec = parse_case_text(kBodies, "case.yaml");
  ASSERT_TRUE(spec.bodies);
  EXPECT_EQ(spec.bodies->shapes.size(), 2u);
  EXPECT_DOUBLE_EQ(spec.floor->friction.kinetic_friction, 0.4);
  ASSERT_EQ(spec.rigid_bodies.size(), 1u);
  EXPECT_DOUBLE_EQ(spec.rigid_bodies[0].friction.kinetic_friction, 0.3);  // defaults to mu_s
  const Solid solid = make_solid(spec);
  EXPECT_EQ(solid.contact().polygon_count(), 1u);
  EXPECT_DOUBLE_EQ(solid.velocity(0)[0], 1.0);            // body a moves
  EXPECT_DOUBLE_EQ(solid.velocity(0)[solid.size() - 1], 0.0);  // body b does not
}

TEST(MpsSolidInput, NegativeFrictionAndKineticAboveStaticAreRejectedNamingTheField) {
  EXPECT_NE(error_of(bodies_with("static_friction: 0.5", "static_friction: -0.1")).find("contact.floor.static_friction"),
            std::string::npos);
  const std::string e = error_of(bodies_with("static_friction: 0.3}", "static_friction: 0.3, kinetic_friction: 0.5}"));
  EXPECT_NE(e.find("contact.rigid_bodies[0].kinetic_friction"), std::string::npos) << e;
  EXPECT_NE(e.find("kinetic friction <= static friction"), std::string::npos) << e;
}

TEST(MpsSolidInput, OverlappingBodiesAtTheStartAreRejectedNamingTheBody) {
  const std::string e = error_of(bodies_with("center: [20 mm, 4 mm]", "center: [11 mm, 4 mm]"));
  EXPECT_NE(e.find("specimen.bodies.shapes[1]"), std::string::npos) << e;
  EXPECT_NE(e.find("overlaps body 'a'"), std::string::npos) << e;
}

TEST(MpsSolidInput, OpenDegenerateOrSelfCrossingPolygonsAreRejected) {
  const std::string square = "[[30 mm, 0], [40 mm, 0], [40 mm, 10 mm], [30 mm, 10 mm]]";
  const std::string field = "contact.rigid_bodies[0].vertices";
  const std::string open = error_of(bodies_with(square, "[[30 mm, 0], [40 mm, 0]]"));
  EXPECT_NE(open.find(field), std::string::npos) << open;
  EXPECT_NE(open.find("not a closed polygon"), std::string::npos) << open;
  const std::string flat = error_of(bodies_with(square, "[[30 mm, 0], [35 mm, 0], [40 mm, 0]]"));
  EXPECT_NE(flat.find("zero area"), std::string::npos) << flat;
  const std::string bow = error_of(bodies_with(square, "[[30 mm, 0], [40 mm, 10 mm], [40 mm, 0], [30 mm, 10 mm]]"));
  EXPECT_NE(bow.find("self-intersecting"), std::string::npos) << bow;
  const std::string repeated = error_of(bodies_with(square, "[[30 mm, 0], [40 mm, 0], [40 mm, 0], [30 mm, 10 mm]]"));
  EXPECT_NE(repeated.find("degenerate edge"), std::string::npos) << repeated;
  // Closing the polygon explicitly (first vertex repeated) is fine.
  EXPECT_EQ(error_of(bodies_with(square, "[[30 mm, 0], [40 mm, 0], [40 mm, 10 mm], [30 mm, 10 mm], [30 mm, 0]]")), "");
  // A polygon that holds particles at the start.
  const std::string inside = error_of(bodies_with(square, "[[5 mm, 0], [12 mm, 0], [12 mm, 10 mm], [5 mm, 10 mm]]"));
  EXPECT_NE(inside.find(field), std::string::npos) << inside;
  EXPECT_NE(inside.find("holds"), std::string::npos) << inside;
}

TEST(MpsSolidInput, BodiesAndRigidBodiesNeedTheStressFormulationAnd2D) {
  std::string e = error_of(bodies_with("formulation: stress", "formulation: displacement"));
  EXPECT_NE(e.find("specimen.bodies"), std::string::npos) << e;
  e = error_of(bodies_with("inner_radius: 0, outer_radius: 3 mm", "inner_radius: 2.5 mm, outer_radius: 3 mm"));
  EXPECT_NE(e.find("specimen.bodies.shapes[1].outer_radius"), std::string::npos) << e;
}

// model.lagrangian: updated (docs/mps.md, "Taylor bar"): its threshold only with it, and not
// with fracture (rebuilt stencils would rejoin cut bonds).
TEST(MpsSolidInput, UpdatedLagrangianKeysAreCheckedNamingTheField) {
  const CaseSpec ok = parse_case_text(replaced("pressure_force: conservative", "lagrangian: updated, stencil_update_strain: 0.2"),
                                      "case.yaml");
  EXPECT_TRUE(ok.updated_lagrangian);
  EXPECT_DOUBLE_EQ(ok.stencil_update_strain, 0.2);
  EXPECT_FALSE(parse_case_text(kStress, "case.yaml").updated_lagrangian);  // total is the default
  auto msg = error_of(replaced("pressure_force: conservative", "lagrangian: eulerian"));
  EXPECT_NE(msg.find("model.lagrangian"), std::string::npos) << msg;
  msg = error_of(replaced("pressure_force: conservative", "stencil_update_strain: 0.2"));
  EXPECT_NE(msg.find("model.stencil_update_strain"), std::string::npos) << msg;
  EXPECT_NE(msg.find("lagrangian: updated"), std::string::npos) << msg;
  msg = error_of(replaced("pressure_force: conservative", "lagrangian: updated, stencil_update_strain: 2"));
  EXPECT_NE(msg.find("0 < stencil_update_strain <= 1"), std::string::npos) << msg;
  msg = error_of(replaced("plasticity: {yield_stress: 240 MPa, hardening_modulus: 1 GPa}",
                          "fracture: {tensile_strength: 100 MPa}").replace(kStress.find("pressure_force: conservative"),
                                                                           28, "lagrangian: updated"));
  EXPECT_NE(msg.find("materials[0].fracture"), std::string::npos) << msg;
  EXPECT_NE(msg.find("lagrangian: total"), std::string::npos) << msg;
}

// model.elastic_law (docs/mps.md, "Elastic law"): neo_hookean by default for an elastic solid
// on total stencils, rate with plasticity (the only law allowed there, as with updated
// stencils) and by default with fracture (allowed either way); an explicit neo_hookean with
// plasticity or updated stencils is refused naming the key.
TEST(MpsSolidInput, ElasticLawDefaultsAndRefusals) {
  const std::string plastic = "plasticity: {yield_stress: 240 MPa, hardening_modulus: 1 GPa}";
  const std::string elastic = replaced(plastic + "}", "}");
  EXPECT_FALSE(parse_case_text(elastic, "case.yaml").rate_elastic_law);
  EXPECT_TRUE(make_solid(parse_case_text(elastic, "case.yaml")).law().elastic == ElasticLaw::NeoHookean);
  EXPECT_TRUE(parse_case_text(kStress, "case.yaml").rate_elastic_law);
  EXPECT_TRUE(parse_case_text(replaced(plastic, "fracture: {tensile_strength: 100 MPa}"), "case.yaml").rate_elastic_law);
  EXPECT_FALSE(parse_case_text(test::replace_once(replaced(plastic, "fracture: {tensile_strength: 100 MPa}"),
                                                  "pressure_force: conservative", "elastic_law: neo_hookean"),
                               "case.yaml")
                   .rate_elastic_law);
  EXPECT_TRUE(parse_case_text(test::replace_once(elastic, "pressure_force: conservative", "elastic_law: rate"), "case.yaml")
                  .rate_elastic_law);
  auto msg = error_of(replaced("pressure_force: conservative", "elastic_law: neo_hookean"));
  EXPECT_NE(msg.find("model.elastic_law"), std::string::npos) << msg;
  EXPECT_NE(msg.find("materials[0].plasticity"), std::string::npos) << msg;
  msg = error_of(test::replace_once(elastic, "pressure_force: conservative", "elastic_law: neo_hookean, lagrangian: updated"));
  EXPECT_NE(msg.find("lagrangian: updated"), std::string::npos) << msg;
  msg = error_of(test::replace_once(elastic, "pressure_force: conservative", "elastic_law: hyper"));
  EXPECT_NE(msg.find("model.elastic_law"), std::string::npos) << msg;
}

// A periodic lattice axis with the stress formulation is refused: its stencils were built on
// the open lattice, so a strip periodic in y squeezed in x read as one with free faces
// (sigma_yy ~ 0 where uniaxial strain gives lambda eps).
TEST(MpsSolidInput, APeriodicAxisWithTheStressFormulationIsRefused) {
  const std::string msg =
      error_of(replaced("spacing: 0.5 mm, thickness: 1 mm}", "spacing: 0.5 mm, thickness: 1 mm, periodic: [false, true]}"));
  EXPECT_NE(msg.find("specimen.lattice.periodic"), std::string::npos) << msg;
  EXPECT_NE(msg.find("formulation: displacement"), std::string::npos) << msg;
}

// A free rigid body's angular velocity in Hz is turns per second: 1 Hz is 2 pi rad/s (read
// as a frequency it was 1 rad/s); rpm and rad/s too.
TEST(MpsSolidInput, AnAngularVelocityInHertzIsTurnsPerSecond) {
  for (const auto& [text, expected] : std::vector<std::pair<std::string, double>>{
           {"1 Hz", 2 * M_PI}, {"60 rpm", 2 * M_PI}, {"3 rad/s", 3.0}, {"3", 3.0}}) {
    const CaseSpec spec = parse_case_text(
        test::replace_once(kStress, "contact: {floor: {point: [0, 0], normal: [0, 1]}}",
                           "contact:\n  rigid_bodies:\n    - {name: wheel, vertices: [[0, 7 mm], [2 mm, 7 mm], [2 mm, 9 mm], "
                           "[0, 9 mm]], fixed: false, density: 7850, angular_velocity: " + text + "}"),
        "case.yaml");
    ASSERT_EQ(spec.rigid_bodies.size(), 1u);
    EXPECT_NEAR(spec.rigid_bodies[0].angular_velocity_rad_s, expected, 1e-12 * expected) << text;
  }
}

// A run stopped on the way (here a particle inverted by the first step) leaves no
// results.xdmf: results.h5 gets its name only at the end, and the XDMF written at every
// output named a file that was not there, or, in a folder reused, an earlier run's.
TEST(MpsSolidCli, ARunStoppedOnTheWayLeavesNoResultsXdmf) {
  const auto dir = std::filesystem::temp_directory_path() / "breccia_mps_solid_cli_stopped";
  // u_x = A exp(-(x - c)^2 / w^2) with A = 3 mm, w = 2 mm: du_x/dx reaches -A sqrt(2/e)/w = -1.3.
  const CliResult r = run_cli(test::replace_once(kStress, "initial: {velocity: [0, -1 m/s]}",
                                                 "initial: {displacement: {type: gaussian, center: [5 mm, 3 mm], "
                                                 "width: 2 mm, amplitude: [3 mm, 0]}}") +
                                  "output: {every: 1, progress: false}\n",
                              dir);
  EXPECT_EQ(r.exit_code, breccia::kExitRunFailed) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("inverted"), std::string::npos) << r.stderr_text;
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "results.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "results.xdmf"));
}
