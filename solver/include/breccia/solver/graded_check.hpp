#pragma once
// Start-up check for graded particle arrangements (docs/atlas.md, stability map "graded").
// With one horizon for the whole body (model.variable_horizon: false, the default) the
// horizon is horizon_factor x the median spacing, so where the particles are coarser than
// the median the local horizon ratio m_i = horizon / spacing_i falls. Nothing blows up:
// measured on a graded strip (2D, horizon_factor 3.015; docs/atlas.md), the worse of the
// uniaxial and shear strain energies of the coarse interior is, for PMB, off by 1.3 % at local
// m 1.77, -12 % at 1.68, -18 % at 1.5, -56 % at 1.0; LPS holds out longer (+2.7 % at 1.51, -7 %
// at 1.34, -20 % at 1.21, -45 % at 1.0); at 0.75 and below the coarse region has no shear
// stiffness or no bonds at all, silently. Correspondence is exact (to 1e-11) wherever a coarse
// family still spans the plane, down to local m 0.59: its F reproduces any affine field by
// construction (docs/theory.md), so it is limited only where the coarse particles lose their
// bonds (0.57: the set-up refuses "no neighbours"). The check refuses a set-up in which more than
// kMaxUnderResolvedShare of the particles see a local ratio below the model's limit
// (GradedLimits below) and names model.variable_horizon (dual horizon keeps
// m_i = horizon_factor everywhere and the coarse energy within 1 % at every grading measured,
// 1.5 to 6).
//
// Dual horizon has a limit too, of accuracy, not stability: a P pulse crossing the change
// reflects 0.1-1 % of its energy up to grading 3 (PMB), 2.75 (LPS) or 4.5 (correspondence),
// then several percent (PMB 5.5 % at 3.5, 35 % at 6, where the pulse is only four coarse
// spacings wide; LPS 1.8 % at 3, 5.5 % at 5; correspondence 1.1 % at 5, 7.9 % at 5.5).
// graded_horizon_warning() says so at start-up.
#include <cstdint>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

// Per-model limits, measured (breccia-atlas --only-stability --stability-studies graded
// --models pmb,lps,correspondence --gradings 1.5,...,6; docs/atlas.md "Per-model graded
// limits"; 2D strip, horizon_factor 3.015, grading r -> coarse local ratio 3.015 / r;
// correspondence with its default penalty stabilisation, G = 1).
//  One horizon: refused where the worse of the uniaxial and shear strain energies of the
//  coarse interior is off by more than 5 % (the atlas's looser band). The limit is the
//  midpoint between the smallest local ratio measured within 5 % and the largest measured
//  beyond it.
//  Dual horizon: warned about where a P pulse crossing the change reflects more than 1 % of
//  its energy (the atlas's tighter band; statics stay right, so it is not refused). The limit
//  is the midpoint between the largest spacing jump measured below 1 % (every smaller
//  grading below 1 % too) and the first measured above.
struct GradedLimits {
  const char* model;         // whose measurement the numbers are
  double min_local_ratio;    // one horizon: refuse below this horizon_i / spacing_i
  double good_ratio, good_error;  // smallest local ratio measured within 5 %, its energy error
  double bad_ratio, bad_error;    // largest local ratio measured beyond 5 %, its energy error
  double warn_jump;          // dual horizon: warn from this spacing jump between bonded neighbours
  double quiet_jump, quiet_reflected;  // largest jump measured below 1 % reflected, its value
  double loud_jump, loud_reflected;    // first jump measured above 1 %, its value
};
inline constexpr GradedLimits kPmbGradedLimits{"PMB", 1.72, 1.774, 0.01284, 1.675, -0.1175,
                                               3.25, 3.0, 0.002499, 3.5, 0.05466};
inline constexpr GradedLimits kLpsGradedLimits{"LPS", 1.42, 1.508, 0.02703, 1.34, -0.07143,
                                               2.875, 2.75, 0.008552, 3.0, 0.0176};
// Correspondence: within at 0.591 (r = 5.1, energy +3e-12: round-off), beyond at 0.574 (r = 5.25:
// a coarse particle has no bonds of non-zero weight and the set-up refuses it, so -100 %).
// The criterion sees the affine response only; the particle-scale response of a coarse particle
// bonded to its nearest neighbours alone is held by the penalty and is not measured here.
inline constexpr GradedLimits kCorrespondenceGradedLimits{"correspondence", 0.583, 0.591, 3.1e-12, 0.574, -1.0,
                                                          4.75, 4.5, 0.003154, 5.0, 0.01103};
// The limits measured for a model.
const GradedLimits& graded_limits(PdModel model);
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
                                  // horizon_i / spacing_i < the model's min_local_ratio
  int64_t worst_particle = -1;    // internal index of the smallest ratio
  double max_neighbour_jump = 1.0;  // largest spacing_j / spacing_i over bonds
};

HorizonGrading horizon_grading(const PdSystem& s);

// Throws InputError (model.variable_horizon) for a single horizon that under-resolves the
// coarse part of a graded arrangement. setup_system calls it unless time.check_stability is
// false. Dual horizon (variable_horizon: true) and a given fixed horizon (checked against
// the largest spacing by setup) pass.
void require_graded_horizon(const PdSystem& s);
// Its parts, for a grading folded from the ranks' blocks (setup.cpp, a distributed set-up):
// whether the body of n particles is refused, and the refusal naming the worst particle
// (its horizon, file row and position).
bool graded_horizon_refused(const CaseConfig& c, const HorizonGrading& g, int64_t n);
InputError graded_horizon_refusal(const CaseConfig& c, const HorizonGrading& g, int64_t n, double horizon,
                                  int64_t file_row, const double* x);

// Empty, or a warning (printed by setup_system) that bonded neighbours differ in spacing by
// more than the model's warn_jump: waves reflect at the change (docs/atlas.md).
std::string graded_horizon_warning(const PdSystem& s);
// The same from a grading already measured (a distributed set-up takes the largest jump over
// every rank's rows: each holds its own).
std::string graded_horizon_warning(const PdSystem& s, const HorizonGrading& g);

}  // namespace breccia::solver
