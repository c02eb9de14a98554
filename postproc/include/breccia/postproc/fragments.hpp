#pragma once
// Fragments: connected components of the intact bond graph, with their size measures.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace breccia::postproc {

struct Fragment {
  int64_t particle_count = 0;
  double volume_m3 = 0.0, mass_kg = 0.0;
  std::array<double, 3> centroid_reference_m{}, centroid_m{}, velocity_m_s{};
  // Sphere (3D) or circle (2D, area = volume / thickness) of equal volume/area.
  double equivalent_diameter_m = 0.0;
  // Edges of the fragment's bounding box, descending: the principal-axes box or the
  // coordinate-axes box, whichever has the smaller sieve size; the extent along an axis is the
  // spread of particle centres plus the fragment's mean particle spacing.
  std::array<double, 3> box_m{};
  // Sieve opening the fragment passes: 3D the second-largest box edge, 2D the smaller
  // in-plane edge.
  double sieve_size_m = 0.0;
};

struct FragmentInputs {
  int dimension = 3;
  double thickness_m = 1.0;
  std::span<const double> position_m;      // 3N reference
  std::span<const double> displacement_m;  // 3N (may be empty: zero)
  std::span<const double> velocity_m_s;    // 3N (may be empty: zero)
  std::span<const double> volume_m3;       // N
  std::span<const double> density_kg_m3;   // N
};

struct FragmentResult {
  std::vector<int32_t> component;      // N, raw component label (all components)
  std::vector<int32_t> fragment_id;    // N, index into fragments, -1 if filtered out
  std::vector<Fragment> fragments;     // kept fragments, by decreasing mass
  int32_t component_count = 0;
  int32_t filtered_count = 0;          // components below the minimum size
  double filtered_mass_kg = 0.0;
};

// component: labels 0..component_count-1 (from intact_components).
FragmentResult measure_fragments(const FragmentInputs& in, std::span<const int32_t> component,
                                 int32_t component_count, int64_t min_particles);

}  // namespace breccia::postproc
