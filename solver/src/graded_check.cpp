#include "breccia/solver/graded_check.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <vector>

#include "breccia/common/error.hpp"

namespace breccia::solver {

const GradedLimits& graded_limits(PdModel model) {
  switch (model) {
    case PdModel::LPS: return kLpsGradedLimits;
    case PdModel::Correspondence: return kCorrespondenceGradedLimits;
    case PdModel::PMB: break;
  }
  return kPmbGradedLimits;
}

namespace {

std::string pct(double fraction, bool sign = true) {
  char b[32];
  std::snprintf(b, sizeof b, sign ? "%+.1f %%" : "%.2g %%", 100.0 * fraction);
  return b;
}

// Where the limits of this model come from, in words, for the messages.
std::string provenance(PdModel model) {
  return std::string(graded_limits(model).model) + " measured on the graded strip (docs/atlas.md, Per-model graded limits)";
}

}  // namespace

HorizonGrading horizon_grading(const PdSystem& s) {
  HorizonGrading g;
  if (s.n == 0) return g;
  const double limit = graded_limits(s.config.model).min_local_ratio;
  g.min_local_ratio = 1e300;
  double h_min = 1e300, h_max = 0.0;
  for (size_t i = 0; i < s.n; ++i) {
    const double spacing = 2.0 * s.half_cell[i];  // setup keeps half the local spacing
    const double m = s.horizon[i] / spacing;
    if (m < g.min_local_ratio) {
      g.min_local_ratio = m;
      g.worst_particle = static_cast<int64_t>(i);
    }
    g.max_local_ratio = std::max(g.max_local_ratio, m);
    h_min = std::min(h_min, spacing);
    h_max = std::max(h_max, spacing);
  }
  std::vector<double> spacing(s.n);
  for (size_t i = 0; i < s.n; ++i) spacing[i] = 2.0 * s.half_cell[i];
  std::nth_element(spacing.begin(), spacing.begin() + s.n / 2, spacing.end());
  const double median = spacing[s.n / 2];
  for (size_t i = 0; i < s.n; ++i)
    if (2.0 * s.half_cell[i] >= kCoarseSpacingFactor * median && s.horizon[i] < limit * 2.0 * s.half_cell[i])
      ++g.under_resolved;
  g.spacing_ratio = h_max / h_min;
  // The largest neighbour's cell over one's own, one division a row: dividing by the same
  // positive number rounds monotonically, so the largest quotient is the largest numerator's,
  // bit for bit (a division per entry was 61 million on the full concrete case).
  // (Before the families exist, as require_graded_horizon runs: no jump.)
  const size_t rows = s.offsets.size() == s.n + 1 ? s.n : 0;
  double jump = 0.0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(max : jump)
  for (size_t i = 0; i < rows; ++i) {
    double widest = 0.0;
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) widest = std::max(widest, s.half_cell[s.neighbor[k]]);
    if (s.offsets[i + 1] > s.offsets[i]) jump = std::max(jump, widest / s.half_cell[i]);
  }
  g.max_neighbour_jump = std::max(g.max_neighbour_jump, jump);
  return g;
}

bool graded_horizon_refused(const CaseConfig& c, const HorizonGrading& g, int64_t n) {
  if (c.variable_horizon || c.horizon_m) return false;  // dual horizon, or a fixed horizon checked in setup
  return g.worst_particle >= 0 && g.under_resolved > kMaxUnderResolvedShare * static_cast<double>(n);
}

InputError graded_horizon_refusal(const CaseConfig& c, const HorizonGrading& g, int64_t n, double horizon,
                                  int64_t file_row, const double* x) {
  const GradedLimits& lim = graded_limits(c.model);
  std::ostringstream found;
  found << "particle spacings vary by " << g.spacing_ratio << "x and the single horizon (" << horizon
        << " m, horizon_factor x median spacing) is " << g.min_local_ratio << " times the spacing of particle "
        << file_row << " at (" << x[0] << ", " << x[1] << ", " << x[2] << "); " << g.under_resolved << " of " << n
        << " particles are below the measured limit of " << lim.min_local_ratio << " spacings for " << c.model_name
        << ": the coarse particles are under-resolved (their stiffness is wrong or they have no bonds). The limit: "
        << provenance(c.model) << ", coarse-interior strain energy " << pct(lim.good_error) << " at local ratio "
        << lim.good_ratio << ", " << pct(lim.bad_error) << " at " << lim.bad_ratio
        << "; refused beyond 5 %, the limit midway";
  return InputError(c.file, "model.variable_horizon", found.str(),
                    "variable_horizon: true (dual horizon: horizon = horizon_factor x local spacing; docs/atlas.md), "
                    "or time.check_stability: false to run anyway");
}

void require_graded_horizon(const PdSystem& s) {
  if (s.config.variable_horizon || s.config.horizon_m) return;
  const HorizonGrading g = horizon_grading(s);
  if (!graded_horizon_refused(s.config, g, static_cast<int64_t>(s.n))) return;
  const int64_t i = g.worst_particle;
  throw graded_horizon_refusal(s.config, g, static_cast<int64_t>(s.n), s.horizon[i], s.original_index[i], &s.x0[3 * i]);
}

std::string graded_horizon_warning(const PdSystem& s) {
  if (!s.config.variable_horizon) return "";
  return graded_horizon_warning(s, horizon_grading(s));
}

std::string graded_horizon_warning(const PdSystem& s, const HorizonGrading& g) {
  if (!s.config.variable_horizon) return "";
  const GradedLimits& lim = graded_limits(s.config.model);
  if (g.max_neighbour_jump < lim.warn_jump) return "";
  std::ostringstream w;
  w << "warning: " << s.config.file << ": bonded particles differ in spacing by up to " << g.max_neighbour_jump
    << "x, beyond the measured limit of " << lim.warn_jump << "x for " << s.config.model_name
    << "; with dual horizon (model.variable_horizon) a wave crossing such a change reflects part of its energy ("
    << provenance(s.config.model) << ": a P pulse reflects " << pct(lim.quiet_reflected, false) << " at "
    << lim.quiet_jump << "x, " << pct(lim.loud_reflected, false) << " at " << lim.loud_jump
    << "x; warned beyond 1 %): grade the mesh more gently for dynamic problems";
  return w.str();
}

}  // namespace breccia::solver
