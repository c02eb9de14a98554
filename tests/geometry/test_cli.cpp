// breccia-place as a user runs it: good meshes and lattices give particles.h5; each kind
// of bad input gives exit code 2, a message naming the file and the entity, and no file.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../common/cli_contract.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/particle_file.hpp"
#include "test_meshes.hpp"

namespace breccia::geometry {
namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

std::string dir() { return testing::scratch_dir(); }

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

RunResult run_place(const std::string& args) {
  const std::string out = dir() + "/stdout.txt", err = dir() + "/stderr.txt";
  const std::string command = std::string("'") + BRECCIA_PLACE_EXE + "' " + args + " > '" + out + "' 2> '" + err + "'";
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = dir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// A gmsh 2.2 file with the given nodes ("tag x y z" lines) and elements
// ("tag type 2 physical entity nodes..." lines).
std::string msh22(const std::vector<std::string>& nodes, const std::vector<std::string>& elements) {
  std::string s = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" + std::to_string(nodes.size()) + "\n";
  for (const auto& n : nodes) s += n + "\n";
  s += "$EndNodes\n$Elements\n" + std::to_string(elements.size()) + "\n";
  for (const auto& e : elements) s += e + "\n";
  return s + "$EndElements\n";
}

const std::vector<std::string> kUnitTetNodes = {"1 0 0 0", "2 1 0 0", "3 0 1 0", "4 0 0 1"};

// Runs the CLI on `mesh` and checks the bad-input contract.
void expect_rejected(const std::string& mesh, const std::string& extra_args,
                     const std::vector<std::string>& message_parts) {
  const std::string output = dir() + "/rejected.h5";
  fs::remove(output);
  const RunResult r = run_place("'" + mesh + "' -o '" + output + "' " + extra_args);
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
  EXPECT_NE(r.err.find("error: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(mesh), std::string::npos) << "message names the file: " << r.err;
  for (const auto& part : message_parts) EXPECT_NE(r.err.find(part), std::string::npos) << "'" << part << "' in: " << r.err;
  EXPECT_FALSE(fs::exists(output));
  EXPECT_FALSE(fs::exists(output + ".partial"));
}

TEST(PlaceCli, BlockMeshBecomesAParticleFileWithASummary) {
  const std::string mesh = dir() + "/block.msh";
  testing::write_block_with_hole(mesh, testing::BlockWithHole{1.0, 0.6, 0.4, 0.1, 0.15});
  const testing::MeshMeasure reference = testing::measure_msh(mesh, 4);
  const std::string output = dir() + "/block_particles.h5";
  const RunResult r = run_place("'" + mesh + "' -o '" + output + "' --require-groups concrete,hole");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* part : {"particles", "volume", "material concrete", "surface  hole", "spacing", "time"})
    EXPECT_NE(r.out.find(part), std::string::npos) << part << " in:\n" << r.out;
  const ParticleModel m = read_particle_file(output);
  EXPECT_EQ(m.size(), reference.elements);
  EXPECT_EQ(m.source, mesh);
  EXPECT_TRUE(fs::exists(dir() + "/block_particles.xdmf"));
}

TEST(PlaceCli, LatticeOptionsWriteALattice) {
  const std::string output = dir() + "/lattice.h5";
  RunResult r = run_place("--lattice cubic --box 0,0,0,1,0.5,0.3 --spacing '100 mm' -o '" + output + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ParticleModel cubic = read_particle_file(output);
  EXPECT_EQ(cubic.size(), 150u);
  EXPECT_EQ(cubic.find_surface("zmax")->size(), 50u);
  r = run_place("--lattice square --box 0,0,0.4,0.2 --spacing 0.01 --thickness 5mm -o '" + output + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ParticleModel square = read_particle_file(output);
  EXPECT_EQ(square.size(), 800u);
  EXPECT_NEAR(square.thickness_m, 0.005, 1e-15);
}

// A particle file named .xdmf was overwritten by its own XDMF sidecar (exit 0, the particles
// gone); a ':' would split the sidecar's file:/dataset reference. Both refused, nothing
// written. A name with XML's reserved characters is escaped in the sidecar.
TEST(PlaceCli, AnOutputTheSidecarWouldClashWithIsRefusedAndNamesAreEscaped) {
  for (const std::string name : {"model.xdmf", "a:b.h5"}) {
    const std::string output = dir() + "/" + name;
    const RunResult r = run_place("--lattice square --box 0,0,0.04,0.02 --spacing 0.01 --thickness 5mm -o '" + output + "'");
    EXPECT_EQ(r.exit_code, kExitBadInput) << name << ": " << r.err;
    EXPECT_FALSE(fs::exists(output)) << name;
  }
  const std::string odd = dir() + "/a&b<1>.h5";
  const RunResult r = run_place("--lattice square --box 0,0,0.04,0.02 --spacing 0.01 --thickness 5mm -o '" + odd + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir() + "/a&b<1>.xdmf");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("a&amp;b&lt;1&gt;.h5:/particles/position"), std::string::npos) << text;
}

TEST(PlaceCli, MissingFileIsRejected) {
  expect_rejected(dir() + "/no_such_mesh.msh", "", {"does not exist"});
}

// An output folder that cannot be made (a file stands where it should be) is a usage error
// naming -o, found before the placing (it was a failure, exit 3, after it).
TEST(PlaceCli, OutputFolderThatCannotBeMadeIsRejectedBeforePlacing) {
  const std::string mesh = dir() + "/block_for_out.msh";
  testing::write_block_with_hole(mesh, testing::BlockWithHole{1.0, 0.6, 0.4, 0.1, 0.15});
  const std::string blocker = write_file("place_out_blocker", "a file, not a folder\n");
  const RunResult r = run_place("'" + mesh + "' -o '" + blocker + "/particles.h5'");
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
  EXPECT_NE(r.err.find("error: command line: -o: '" + blocker + "' not writable"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("particles"), std::string::npos) << "placed before the check: " << r.out;
}

TEST(PlaceCli, NonMeshFileIsRejected) {
  expect_rejected(write_file("notes.msh", "hello, not a mesh\n"), "", {"not a gmsh mesh header", "$MeshFormat"});
}

TEST(PlaceCli, TruncatedMeshIsRejected) {
  expect_rejected(write_file("truncated.msh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n"),
                  "", {"gmsh could not read"});
}

TEST(PlaceCli, InvertedTetrahedronIsRejectedByTagAndVolume) {
  // Nodes 1 3 2 4 wind the unit corner tet the wrong way: volume -1/6.
  expect_rejected(write_file("inverted.msh", msh22(kUnitTetNodes, {"7 4 2 1 1 1 3 2 4"})), "",
                  {"element 7", "inverted", "-0.166667"});
}

TEST(PlaceCli, FlatTetrahedronIsRejectedByTagAndVolume) {
  expect_rejected(write_file("flat.msh", msh22({"1 0 0 0", "2 1 0 0", "3 0 1 0", "4 1 1 0"}, {"9 4 2 1 1 1 2 3 4"})),
                  "", {"element 9", "zero-volume", "volume 0"});
}

TEST(PlaceCli, PrismsAmongTetrahedraAreRejectedNamingTheTypes) {
  const std::vector<std::string> nodes = {"1 0 0 0", "2 1 0 0", "3 0 1 0", "4 0 0 1", "5 1 0 1", "6 0 1 1", "7 0 0 -1"};
  expect_rejected(write_file("mixed.msh", msh22(nodes, {"1 6 2 1 1 1 2 3 4 5 6", "2 4 2 1 1 1 3 2 7"})), "",
                  {"Prism 6", "Tetrahedron 4", "only linear tetrahedra"});
}

TEST(PlaceCli, HexahedralMeshIsRejectedNamingTheType) {
  const std::vector<std::string> nodes = {"1 0 0 0", "2 1 0 0", "3 1 1 0", "4 0 1 0",
                                          "5 0 0 1", "6 1 0 1", "7 1 1 1", "8 0 1 1"};
  expect_rejected(write_file("hex.msh", msh22(nodes, {"1 5 2 1 1 1 2 3 4 5 6 7 8"})), "", {"Hexahedron 8"});
}

TEST(PlaceCli, SurfaceOnlyMeshHasNoVolumeElements) {
  expect_rejected(write_file("surface.msh", msh22({"1 0 0 1", "2 1 0 1", "3 0 1 1"}, {"1 2 2 1 1 1 2 3"})), "",
                  {"no volume elements"});
}

TEST(PlaceCli, TwoDimensionalMeshNeedsAThickness) {
  const std::string mesh = write_file("tri.msh", msh22({"1 0 0 0", "2 1 0 0", "3 0 1 0"}, {"1 2 2 1 1 1 2 3"}));
  expect_rejected(mesh, "", {"--thickness", "2D"});
  const std::string output = dir() + "/tri.h5";
  const RunResult r = run_place("'" + mesh + "' -o '" + output + "' --thickness 0.01");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NEAR(read_particle_file(output).volume_m3.at(0), 0.5 * 0.01, 1e-15);  // area 1/2 x thickness
}

TEST(PlaceCli, DegenerateTriangleIsRejected) {
  expect_rejected(write_file("flat_tri.msh", msh22({"1 0 0 0", "2 1 0 0", "3 2 0 0"}, {"4 2 2 1 1 1 2 3"})),
                  "--thickness 0.01", {"element 4", "degenerate"});
}

// msh 4.1 with a physical surface "loadface" whose entity has no elements.
const char* kEmptyGroupMesh = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 2 "loadface"
3 1 "body"
$EndPhysicalNames
$Entities
0 0 1 1
1 0 0 0 1 1 0 1 2 0
1 0 0 0 1 1 1 1 1 0
$EndEntities
$Nodes
1 4 1 4
3 1 0 4
1
2
3
4
0 0 0
1 0 0
0 1 0
0 0 1
$EndNodes
$Elements
1 1 1 1
3 1 4 1
1 1 2 3 4
$EndElements
)";

TEST(PlaceCli, RequiredGroupThatIsMissingIsRejected) {
  expect_rejected(write_file("groups_missing.msh", kEmptyGroupMesh), "--require-groups body,borehole",
                  {"physical group 'borehole'", "missing", "body (volume)"});
}

TEST(PlaceCli, RequiredGroupThatIsEmptyIsRejected) {
  expect_rejected(write_file("groups_empty.msh", kEmptyGroupMesh), "--require-groups loadface",
                  {"physical group 'loadface'", "empty"});
}

TEST(PlaceCli, UnknownVolumeGroupIsRejected) {
  expect_rejected(write_file("groups_volume.msh", kEmptyGroupMesh), "--volume-groups granite",
                  {"--volume-groups", "'granite'"});
}

// --help, --version, and usage errors (exit 2 naming the option): the tools' shared contract.
// Lengths are quantities ("5 mm"): a malformed one is named the same way.
TEST(PlaceCli, FollowsTheToolsCommandLineContract) {
  const std::string output = dir() + "/never.h5";
  fs::remove(output);
  // A value given twice: the last one counts (the malformed values come after the good ones).
  breccia::testing::expect_cli_contract(
      BRECCIA_PLACE_EXE, "breccia-place",
      "--lattice square --box 0,0,1,1 --spacing 0.5 --thickness 1mm -o '" + output + "'",
      {{"--spacing", "10x"}, {"--thickness", "two"}});
  EXPECT_FALSE(fs::exists(output));
}

}  // namespace
}  // namespace breccia::geometry
