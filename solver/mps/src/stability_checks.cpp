#include "breccia/mps/stability_checks.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "breccia/common/error.hpp"

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
  const auto is_near = [&](long long k) { return std::sqrt(b.rx[k] * b.rx[k] + b.ry[k] * b.ry[k] + b.rz[k] * b.rz[k]) <= near; };
  // Crack-face particles: the first layer on a crack, those with a cut nearest-neighbour bond
  // (fracture or Solid::cut_bonds, weight 0); a particle whose only cut bonds reach further
  // (two spacings, across the crack) is inside the material and stays measured.
  std::vector<char> on_face(n, 0);
  for (long long i = 0; i < n; ++i)
    for (long long k = b.offset[i]; k < b.offset[i + 1] && !on_face[i]; ++k) on_face[i] = b.weight[k] == 0.0 && is_near(k);
  for (long long i = 0; i < n; ++i) {
    const Mat3& h = grad[i];
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
      // A cut bond (fracture, weight 0) carries nothing: its two particles closing in is a
      // crack face or debris coming back, not clumping (and a detached particle has no F).
      if (b.weight[k] == 0.0) continue;
      if (!is_near(k)) continue;
      const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
      const int j = b.neighbour[k];
      double predicted2 = 0.0;
      for (int a = 0; a < 3; ++a) {
        const double fr = r[a] + h(a, 0) * r[0] + h(a, 1) * r[1] + h(a, 2) * r[2];
        predicted2 += fr * fr;
      }
      // Reference bond vectors may be periodic images: the current one is r + u_j - u_i.
      const double d[3] = {r[0] + ux[j] - ux[i], r[1] + uy[j] - uy[i], r[2] + uz[j] - uz[i]};
      const double length2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      // Clumping pulls neighbours together: a bond no shorter than its reference length is
      // not clumping, whatever F_i predicts. Without this, particles moved as one rigid block
      // (a driven or held end) next to a stretching region read 1 / (1 + strain): F_i, fitted
      // over a stencil reaching into the stretching part, predicts a stretch that the block's
      // own bonds do not have (measured: 0.64 at 70 % nominal strain, 0.50 at 100 %).
      if (length2 >= r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) continue;
      const double ratio = std::sqrt(length2 / predicted2);
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
