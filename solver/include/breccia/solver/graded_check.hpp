#pragma once
// Start-up check for graded particle arrangements (docs/atlas.md, stability map "graded").
// With one horizon for the whole body (model.variable_horizon: false, the default) the
// horizon is horizon_factor x the median spacing, so where the particles are coarser than
// the median the local horizon ratio m_i = horizon / spacing_i falls. Nothing blows up:
// measured on a graded strip (2D, PMB, horizon_factor 3.015; docs/atlas.md), the worse of the
// uniaxial and shear strain energies of the coarse interior is off by 1.7 % at local m 2.0,
// -18 % at 1.5, -56 % at 1.0, and at 0.75 and below the coarse region has no shear stiffness
// or no bonds at all, silently. The check refuses a set-up in which more than
// kMaxUnderResolvedShare of the particles see a local ratio below kMinLocalHorizonRatio and
// names model.variable_horizon (dual horizon keeps m_i = horizon_factor everywhere and the
// coarse energy within 1 % at every grading measured, 1.5 to 6).
//
// Dual horizon has a limit too, of accuracy, not stability: a P pulse crossing the change
// reflects 0.2-0.4 % of its energy at gradings 1.5-3, 3.9 % at 4 and 35 % at 6 (the pulse is
// also only four coarse spacings wide there). graded_horizon_warning() says so at start-up.
#include <cstdint>
#include <string>

#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

// Between the last ratio measured good (2.0: 1.7 %) and the first measured bad (1.5: 18 %).
inline constexpr double kMinLocalHorizonRatio = 1.75;
// Dual horizon: spacing ratio between bonded neighbours from which the atlas measured
// reflections of several percent (4: 3.9 %, 6: 35 %).
inline constexpr double kWarnNeighbourSpacingJump = 4.0;
// A few large cells of an irregular mesh are the energy-scatter check's business
// (family_check.hpp); a coarse region is a share of the body (the graded strip: 10 %).
inline constexpr double kMaxUnderResolvedShare = 0.01;
// Only particles this much coarser than the median count as a coarse region: the cells of
// one tet mesh of uniform target size reach 1.41x the median (12 mm cube, measured), so at
// horizon_factor 2 they see local ratios down to 1.43 without being a graded arrangement.
inline constexpr double kCoarseSpacingFactor = 1.45;

struct HorizonGrading {
  double min_local_ratio = 0.0;   // min over particles of horizon_i / spacing_i
  double max_local_ratio = 0.0;
  double spacing_ratio = 1.0;     // largest / smallest particle spacing
  size_t under_resolved = 0;      // particles coarser than kCoarseSpacingFactor x median with
                                  // horizon_i / spacing_i < kMinLocalHorizonRatio
  int64_t worst_particle = -1;    // internal index of the smallest ratio
  double max_neighbour_jump = 1.0;  // largest spacing_j / spacing_i over bonds
};

HorizonGrading horizon_grading(const PdSystem& s);

// Throws InputError (model.variable_horizon) for a single horizon that under-resolves the
// coarse part of a graded arrangement. setup_system calls it unless time.check_stability is
// false. Dual horizon (variable_horizon: true) and a given fixed horizon (checked against
// the largest spacing by setup) pass.
void require_graded_horizon(const PdSystem& s);

// Empty, or a warning (printed by setup_system) that bonded neighbours differ in spacing by
// kWarnNeighbourSpacingJump or more: waves reflect at the change (docs/atlas.md).
std::string graded_horizon_warning(const PdSystem& s);

}  // namespace breccia::solver
