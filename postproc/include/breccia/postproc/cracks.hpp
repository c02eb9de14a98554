#pragma once
// Crack surfaces. Candidate faces are the places where a crack can run between two
// particles: a mesh face (3D: triangle, 2D: edge) shared by two cells, or for lattices
// (no mesh) the bisector square/segment between two face-adjacent lattice cells. A
// candidate is a crack face when the bond of its two particles is broken or pre-cracked
// (criterion Bond), or when both particles' damage exceeds a threshold (criterion Damage).
#include <cstdint>
#include <span>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "breccia/postproc/bond_graph.hpp"

namespace breccia::postproc {

struct CandidateFaces {
  int dimension = 3;
  int vertices_per_face = 3;         // 3 (tet faces), 4 (lattice squares), 2 (2D segments)
  std::vector<double> points_m;      // 3P, reference positions of face vertices
  std::vector<int64_t> vertices;     // F * vertices_per_face, indices into points
  std::vector<int32_t> particle_a, particle_b;  // F, a < b
  std::vector<double> area_m2;       // F; in 2D: length times thickness
  std::vector<double> length_m;      // F; 2D only (segment length), else 0
  size_t size() const { return particle_a.size(); }
};

// Mesh faces shared by two cells (tets or triangles).
CandidateFaces mesh_candidate_faces(const ParticleModel& particles);
// Lattice (no mesh): pairs of family members at distance within 1 % of their mean spacing.
CandidateFaces lattice_candidate_faces(const ParticleModel& particles, const Families& families);
CandidateFaces candidate_faces(const ParticleModel& particles, const Families& families);

enum class CrackCriterion { Bond, Damage };

enum FaceState : uint8_t { kIntact = 0, kFractured = 1, kPrecrack = 2 };

struct CrackResult {
  std::vector<uint8_t> state;     // F, FaceState
  std::vector<int32_t> crack_id;  // F, -1 for intact faces; connected components
  int32_t crack_count = 0;        // components over shared vertices (pre-cracks included)
  double area_m2 = 0.0;           // all crack faces (2D: length x thickness)
  double fracture_area_m2 = 0.0;  // faces created by fracture (not pre-cracks)
  double precrack_area_m2 = 0.0;
  double length_m = 0.0;          // 2D only: total crack length
  double fracture_length_m = 0.0;
  // Mesh faces follow an oblique crack as a staircase, which overstates its area (up to ~2x
  // on structured tet meshes). The smoothed measure projects each crack face on the local
  // crack plane, fitted (principal axes) to the centroids of the crack faces within
  // smoothing_radius_m: exact for planar cracks, O(h / curvature radius) for curved ones.
  double smoothed_area_m2 = 0.0;           // all crack faces
  double smoothed_fracture_area_m2 = 0.0;  // fracture faces only
  double smoothed_length_m = 0.0;          // 2D: smoothed_area / thickness
  double smoothing_radius_m = 0.0;
  double G0_area_J = 0.0;  // sum over fracture faces of area x mean G0 of the two materials
  double G0_smoothed_area_J = 0.0;
  size_t face_count = 0;
  // Through-cracks: fracture faces whose two particles lie in different fragments (components
  // of the intact bond graph). Broken bonds scattered inside a piece add crack faces but
  // separate nothing; these measures leave them out. Faces next to a debris fragment (fewer
  // particles than CrackInputs::debris_particles) count half: a chip sitting in the crack has
  // faces on both of its sides, but the crack runs through it once. Set when
  // CrackInputs::fragment_of is given.
  bool has_separating = false;
  size_t separating_face_count = 0;
  double separating_fracture_area_m2 = 0.0;
  double smoothed_separating_fracture_area_m2 = 0.0;  // smoothed among separating faces only
  double G0_smoothed_separating_area_J = 0.0;
};

struct CrackInputs {
  const BondSet* broken = nullptr;     // bonds broken by fracture (state 1)
  const BondSet* precracks = nullptr;  // bonds removed by pre-cracks (state 2)
  std::span<const double> damage;               // N (Damage criterion)
  std::span<const int32_t> material_id;         // N (for G0)
  std::span<const double> fracture_energy_J_m2; // per material
  std::span<const int32_t> fragment_of;         // N fragment (component) labels; empty: no separating measures
  int64_t debris_particles = 0;                  // fragments with fewer particles are debris (faces count half)
};

CrackResult find_cracks(const CandidateFaces& faces, const CrackInputs& in, CrackCriterion criterion,
                        double damage_threshold);

}  // namespace breccia::postproc
