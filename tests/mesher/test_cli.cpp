// breccia-mesh on bad input: exit 2 with one message naming the file, the field or entity,
// and what was expected; no output file left behind. And a good run stays quiet: gmsh's
// own log never reaches the terminal.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../common/cli_contract.hpp"
#include "mesh_probe.hpp"

namespace {

using breccia::mesher::testing::write_temp_file;

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

CliResult run_cli(const std::string& args) {
  const std::string out = write_temp_file("cli.stdout", ""), err = write_temp_file("cli.stderr", "");
  const std::string cmd = std::string(BRECCIA_MESH_EXE) + " " + args + " >" + out + " 2>" + err;
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

const std::string kQuickSpec = slurp(BRECCIA_CASES_DIR "/concrete-blast/specimen-quick.yaml");

// The quick concrete spec with one substring replaced: a realistic file with one mistake.
std::string spec_with(const std::string& name, const std::string& from, const std::string& to) {
  std::string text = kQuickSpec;
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test setup: '" << from << "' not in specimen-quick.yaml";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return write_temp_file(name, text);
}

void expect_bad_input(const std::string& input, const std::vector<std::string>& message_parts) {
  const std::string output = write_temp_file("never.msh", "");
  std::filesystem::remove(output);
  const CliResult r = run_cli(input + " -o " + output);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: "), std::string::npos) << r.err;
  for (const auto& part : message_parts) EXPECT_NE(r.err.find(part), std::string::npos) << "missing '" << part << "' in: " << r.err;
  EXPECT_FALSE(std::filesystem::exists(output));
  EXPECT_FALSE(std::filesystem::exists(output + ".partial"));
}

TEST(MeshCliBadInput, MissingFileIsNamed) {
  expect_bad_input("/nonexistent/specimen.yaml", {"/nonexistent/specimen.yaml", "does not exist"});
}

// An output folder that cannot be made (a file stands where it should be) is a usage error
// naming -o, found before the meshing (it was a failure, exit 3, after it).
TEST(MeshCliBadInput, OutputFolderThatCannotBeMadeIsNamedBeforeMeshing) {
  const std::string blocker = write_temp_file("mesh_out_blocker", "a file, not a folder\n");
  const CliResult r = run_cli(write_temp_file("good.yaml", kQuickSpec) + " -o " + blocker + "/out.msh");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("error: command line: -o: '" + blocker + "' not writable"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("mesh summary"), std::string::npos) << "meshed before the check: " << r.out;
  EXPECT_EQ(r.err.find("[writing]"), std::string::npos) << "meshed before the check: " << r.err;
}

TEST(MeshCliBadInput, YamlSyntaxErrorGivesTheLine) {
  const auto path = write_temp_file("syntax.yaml", "dimension: 3\nbody: [box, \nmesh: {size: 1}\n");
  expect_bad_input(path, {"syntax.yaml", "line", "YAML syntax error"});
}

TEST(MeshCliBadInput, UnknownKeyIsNamedWithTheAllowedKeys) {
  expect_bad_input(spec_with("unknown.yaml", "    depth: 150 mm", "    depth: 150 mm\n    colour: red"),
                   {"unknown.yaml", "holes[0].colour", "unknown key", "radius, depth"});
}

TEST(MeshCliBadInput, WrongTypeIsNamed) {
  expect_bad_input(spec_with("type.yaml", "radius: 10 mm", "radius: [10 mm, 12 mm]"),
                   {"type.yaml", "holes[0].radius", "not a single value", "length"});
}

TEST(MeshCliBadInput, PressureUnitForARadiusIsRejected) {
  expect_bad_input(spec_with("unit.yaml", "radius: 10 mm", "radius: 5 MPa"),
                   {"unit.yaml", "holes[0].radius", "MPa", "mm"});
}

TEST(MeshCliBadInput, NegativeSizeIsRejected) {
  expect_bad_input(spec_with("negative.yaml", "size: 34 mm", "size: -34 mm"),
                   {"negative.yaml", "mesh.size", "not positive"});
}

TEST(MeshCliBadInput, HoleOutsideTheBodyIsRejected) {
  expect_bad_input(spec_with("hole_out.yaml", "centre: [150 mm, 150 mm, 300 mm]", "centre: [450 mm, 150 mm, 300 mm]"),
                   {"hole_out.yaml", "holes[0].centre", "outside the body"});
}

// Without depth the hole goes through; a radius of 200 mm in a 300 mm block used to reach
// the meshing and fail there naming a face group (xmin) rather than the hole.
TEST(MeshCliBadInput, ThroughHoleWiderThanTheBodyIsRejectedNamingTheRadius) {
  expect_bad_input(spec_with("through_wide.yaml", "    radius: 10 mm\n    depth: 150 mm", "    radius: 200 mm"),
                   {"through_wide.yaml", "holes[0].radius", "hole wall (radius 200 mm) reaches outside the body"});
}

TEST(MeshCliBadInput, InclusionOutsideTheBodyIsRejected) {
  expect_bad_input(spec_with("inclusion_out.yaml", "mesh:", "inclusions: [{name: stone, centre: [290 mm, 50 mm, 50 mm], radius: 20 mm}]\nmesh:"),
                   {"inclusion_out.yaml", "inclusions[0]", "outside the body"});
}

TEST(MeshCliBadInput, RefinementNearAnUnknownGroupListsTheKnownGroups) {
  expect_bad_input(spec_with("near.yaml", "near: charge_hole", "near: charge_holes"),
                   {"near.yaml", "mesh.refine[0].near", "charge_holes", "charge_hole, concrete"});
}

TEST(MeshCliBadInput, UnknownFileExtensionIsRejected) {
  expect_bad_input(write_temp_file("shape.obj", "v 0 0 0\n"), {"shape.obj", "unknown file extension '.obj'", ".step"});
}

TEST(MeshCliBadInput, MshFileThatIsNotAMeshIsRejectedWithGmshsReason) {
  expect_bad_input(write_temp_file("garbage.msh", "this is not a mesh\n"), {"garbage.msh", "gmsh cannot read it", "msh file"});
}

TEST(MeshCliBadInput, MshFileWithoutElementsIsRejected) {
  expect_bad_input(write_temp_file("empty.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"),
                   {"empty.msh", "no 2D or 3D elements"});
}

TEST(MeshCli, GoodRunPrintsStagesAndSummaryButNoGmshLog) {
  const std::string output = write_temp_file("quick_cli.msh", "");
  const CliResult r = run_cli(std::string(BRECCIA_CASES_DIR "/concrete-blast/specimen-quick.yaml") + " -o " + output);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* stage : {"[geometry]", "[mesh 1D]", "[mesh 2D]", "[mesh 3D]", "[optimising]", "[writing]"})
    EXPECT_NE(r.err.find(stage), std::string::npos) << stage;
  EXPECT_EQ(r.err.find("Info"), std::string::npos) << "gmsh log leaked: " << r.err;
  for (const char* item : {"tetrahedra", "nodes", "element size", "charge_hole", "concrete"})
    EXPECT_NE(r.out.find(item), std::string::npos) << item;
  EXPECT_TRUE(std::filesystem::exists(output));
}

// --help, --version, and usage errors (exit 2 naming the option): the tools' shared contract.
TEST(MeshCli, FollowsTheToolsCommandLineContract) {
  breccia::testing::expect_cli_contract(BRECCIA_MESH_EXE, "breccia-mesh", "spec.yaml -o out.msh",
                                        {{"--threads", "4x"}, {"--threads", "-1"}, {"--threads", "0"}});
  const CliResult r = run_cli("spec.yaml -o out.msh --threads");  // the value missing at the end
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--threads: no value"), std::string::npos) << r.err;
}

}  // namespace
