#pragma once
// A parametric specimen as read from a YAML spec (docs/specimen-format.md): one body
// (box, cylinder, plate; rectangle, disc, plate in 2D), holes and slots cut out of it,
// pre-crack surfaces embedded in it, inclusions of another material, named boundary
// groups and mesh-size settings. All lengths are SI metres after load_specimen().
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace breccia::mesher {

using Vec3 = std::array<double, 3>;

enum class BodyShape { Box, Cylinder, Rectangle, Disc };

struct Body {
  BodyShape shape = BodyShape::Box;
  std::string name = "body";       // physical volume (3D) / surface (2D) group
  Vec3 origin{0, 0, 0};            // box/rectangle: min corner; cylinder/disc: centre of the bottom
  Vec3 size{0, 0, 0};              // box/rectangle edge lengths
  double radius_m = 0;             // cylinder/disc
  double height_m = 0;             // cylinder (along +z)
};

// A cylindrical hole (3D) or circular hole (2D). In 3D it starts at `entry` and runs
// along `axis` for `depth_m`; no depth means it goes through the whole body.
struct Hole {
  std::string name;
  Vec3 entry{0, 0, 0};
  Vec3 axis{0, 0, -1};             // unit vector
  double radius_m = 0;
  std::optional<double> depth_m;
};

// A notch: a slot of finite width cut out of the body, or a zero-thickness pre-crack
// embedded in the mesh (the solver removes bonds across it). In 3D the notch plane is
// the parallelogram corner + s*edge_a + t*edge_b (s, t in [0, 1]); in 2D it is the
// segment corner -> corner + edge_a.
struct Notch {
  enum class Kind { Slot, Crack };
  std::string name;
  Kind kind = Kind::Crack;
  Vec3 corner{0, 0, 0};
  Vec3 edge_a{0, 0, 0};
  Vec3 edge_b{0, 0, 0};            // 3D only
  double width_m = 0;              // slots only
};

// A sphere (3D) or circle (2D) of another material, meshed as its own volume/surface.
struct Inclusion {
  std::string name;
  Vec3 centre{0, 0, 0};
  double radius_m = 0;
};

struct Refinement {
  std::string near;                // a physical group name
  double size_m = 0;
  double distance_min_m = 0;
  double distance_max_m = 0;
};

enum class Algorithm3D { Delaunay, Hxt };

struct MeshSettings {
  double size_m = 0;               // element size away from refinements
  std::vector<Refinement> refine;
  bool optimize = true;
  Algorithm3D algorithm_3d = Algorithm3D::Delaunay;
};

struct Specimen {
  std::string file;                // where it was read from, for messages
  int dimension = 3;
  double thickness_m = 1.0;        // 2D: out-of-plane thickness; 3D plate: its z extent
  Body body;
  std::vector<Hole> holes;
  std::vector<Notch> notches;
  std::vector<Inclusion> inclusions;
  std::map<std::string, std::vector<std::string>> group_aliases;  // name -> union of groups
  MeshSettings mesh;
};

// Read and validate a spec; throws InputError naming the file and field on any problem
// (unknown key, wrong unit, negative size, feature outside the body, ...).
Specimen load_specimen(const std::string& file);

// The boundary group names the body provides before any holes or notches are added.
std::vector<std::string> body_boundary_groups(const Specimen& spec);

}  // namespace breccia::mesher
