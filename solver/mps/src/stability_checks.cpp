#include "breccia/mps/stability_checks.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/mps/solid_phases.hpp"

namespace breccia::mps {

Clumping measure_clumping(const Solid& solid) {
  Clumping c;
  const BondList& b = solid.bonds();
  const double near = 1.5 * solid.spacing_m();
  const auto& ux = solid.stencil_displacement(0);  // bond vectors are the stencils' reference
  const auto& uy = solid.stencil_displacement(1);
  const auto& uz = solid.stencil_displacement(2);
  const auto& grad = solid.displacement_gradient();
  const long long n = static_cast<long long>(solid.size());
  const VectorField u{ux.data(), uy.data(), uz.data()};
  const BondsView bv = b.view();
  // Crack-face particles: the first layer on a crack, those with a cut nearest-neighbour bond
  // (fracture or Solid::cut_bonds, weight 0); a particle whose only cut bonds reach further
  // (two spacings, across the crack) is inside the material and stays measured.
  std::vector<char> on_face(n, 0);
  for (long long i = 0; i < n; ++i) on_face[i] = on_crack_face_at(i, bv, near);
  for (long long i = 0; i < n; ++i) {
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      // Not measured (solid_phases.hpp): a cut bond carries nothing, and its two particles
      // closing in is a crack face or debris coming back, not clumping (a detached particle
      // has no F); bonds beyond the nearest neighbours; bonds no shorter than their
      // reference length.
      double ratio = 1.0;
      if (!clumping_ratio(bv, i, k, u, grad[i], near, &ratio)) continue;
      const int j = b.neighbour[k];
      // An intact bond between two crack-face particles is a bond along a crack flank. There
      // F_i is fitted on a one-sided stencil that cannot follow the flank sliding and closing
      // under the compression ahead of a crack tip, so the ratio reads the flank's motion, not
      // a tensile instability of the material (ring at 0.25 mm: one such bond at 0.48 for
      // ~1 us, back above 0.7 within 5 us, det F >= 0.93, energy balance within 0.55 %;
      // docs/mps.md). A face pair that does collapse is caught by the fracture model instead:
      // a damaged particle that inverts or keeps a remnant stencil is detached as debris.
      if (on_face[i] && on_face[j]) {
        if (!(ratio >= kMinNeighbourDistanceRatio)) ++c.skipped_face_bonds;
        continue;
      }
      if (!(ratio >= kMinNeighbourDistanceRatio)) ++c.clumped_bonds;  // NaN counts
      if (!(ratio >= c.min_ratio)) {
        c.min_ratio = ratio;
        c.worst_particle = i;
      }
    }
  }
  return c;
}

void require_no_clumping(const Solid& solid) {
  const Clumping c = measure_clumping(solid);
  if (c.clumped_bonds == 0) return;
  const long long i = c.worst_particle;
  const auto& p = solid.position_m();
  std::ostringstream msg;
  msg << "mps solid: particles clumping at t = " << solid.time_s() << " s: " << c.clumped_bonds
      << " nearest-neighbour bond(s) shorter than " << kMinNeighbourDistanceRatio
      << " of the length their particle's deformation gradient predicts (worst " << c.min_ratio << " at particle " << i
      << ", reference position (" << p[3 * i] << ", " << p[3 * i + 1] << ", " << p[3 * i + 2]
      << ")): tensile instability or hourglass (zero-energy) modes; raise model.hourglass (default 0.1), "
         "try model.pressure_force: repulsive, or refine";
  throw RunError(msg.str());
}

}  // namespace breccia::mps
