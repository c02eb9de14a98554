// The atlas (docs/atlas/atlas.csv, written by `make atlas`): measured error against
// settings for problems with known answers. The planner reads it; it never writes it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "breccia/common/csv.hpp"
#include "breccia/common/data_dir.hpp"
#include "breccia/common/error.hpp"
#include "breccia/plan/plan.hpp"

namespace breccia::plan {
namespace {

const char* kHeader =
    "problem,model,dimension,particles_kind,m,spacing_m,precision,backend,threads,particles,bonds,steps,wall_s,error,"
    "error_measure";

bool is_double_precision(const std::string& p) { return p == "float64" || p == "double" || p == "fp64"; }

struct Point {
  double resolution, error;
};

// Rows of one group, one point per resolution (the worst error where several backends or
// thread counts measured the same setting), coarse to fine.
std::vector<Point> group_points(const std::vector<AtlasRow>& atlas, const std::string& problem, const std::string& model,
                                int dimension, const std::string& kind, double m) {
  std::map<long long, Point> by_res;
  for (const auto& r : atlas) {
    if (r.problem != problem || r.model != model || r.dimension != dimension || r.particles_kind != kind) continue;
    if (!is_double_precision(r.precision) || std::fabs(r.m - m) > 1e-6) continue;
    const long long key = std::llround(r.resolution() * 1000);
    auto [it, fresh] = by_res.try_emplace(key, Point{r.resolution(), r.error});
    if (!fresh) it->second.error = std::max(it->second.error, r.error);
  }
  std::vector<Point> pts;
  for (const auto& [k, p] : by_res) pts.push_back(p);
  return pts;
}

std::vector<double> measured_m(const std::vector<AtlasRow>& atlas, const std::string& problem, const std::string& model,
                               int dimension, const std::string& kind) {
  std::vector<double> ms;
  for (const auto& r : atlas)
    if (r.problem == problem && r.model == model && r.dimension == dimension && r.particles_kind == kind &&
        is_double_precision(r.precision) &&
        std::none_of(ms.begin(), ms.end(), [&](double x) { return std::fabs(x - r.m) < 1e-6; }))
      ms.push_back(r.m);
  std::sort(ms.begin(), ms.end());
  return ms;
}

double log_interp(double x, double x0, double y0, double x1, double y1) {
  const double lx0 = std::log(x0), lx1 = std::log(x1);
  const double ly0 = std::log(std::max(y0, 1e-300)), ly1 = std::log(std::max(y1, 1e-300));
  const double t = (std::log(x) - lx0) / (lx1 - lx0);
  return std::exp(ly0 + t * (ly1 - ly0));
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

}  // namespace

double horizon_factor_of_row_m(double m) {
  const bool nominal = std::fabs(2.0 * m - std::round(2.0 * m)) < 1e-9;
  return nominal ? m + 0.015 : m;
}

double AtlasRow::resolution() const {
  return std::pow(static_cast<double>(std::max<long long>(1, particles)), 1.0 / std::max(1, dimension));
}

std::string default_atlas_path() {
  // Installed as share/breccia/plan/atlas.csv (in the build tree: a link to docs/atlas/atlas.csv).
  return data_path("BRECCIA_PLAN_ATLAS", "plan/atlas.csv").string();
}

std::vector<AtlasRow> read_atlas(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open the atlas", "docs/atlas/atlas.csv from `make atlas` (or --atlas FILE)");
  std::string line;
  std::getline(in, line);
  const std::string header = split_csv_line(line, 1)[0];  // the whole line, trimmed
  if (header != kHeader) throw InputError(path, "header", "'" + header + "'", std::string("'") + kHeader + "'");
  std::vector<AtlasRow> rows;
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.find_first_not_of(" \r\n") == std::string::npos || line[0] == '#') continue;
    // error_measure (the 15th field) is free text written unquoted: it takes the rest of the line.
    const auto f = split_csv_line(line, 15);
    const std::string where = "line " + std::to_string(lineno);
    if (f.size() != 15) throw InputError(path, where, std::to_string(f.size()) + " fields", "15 fields as in the header");
    AtlasRow r;
    auto num = [&](int k, const char* name) {
      char* end = nullptr;
      const double v = std::strtod(f[k].c_str(), &end);
      if (f[k].empty() || *end != '\0' || !std::isfinite(v))
        throw InputError(path, where + " " + name, "'" + f[k] + "'", "a number");
      return v;
    };
    // A positive number (m, spacing, counts), and a whole one where it counts something.
    auto positive = [&](int k, const char* name, bool whole) {
      const double v = num(k, name);
      if (!(v > 0) || (whole && v != std::floor(v)))
        throw InputError(path, where + " " + name, "'" + f[k] + "'", whole ? "a whole number >= 1" : "a number > 0");
      return v;
    };
    r.problem = f[0];
    r.model = f[1];
    r.dimension = static_cast<int>(positive(2, "dimension", true));
    r.particles_kind = f[3];
    r.m = positive(4, "m", false);
    r.spacing_m = positive(5, "spacing_m", false);
    r.precision = f[6];
    r.backend = f[7];
    r.threads = static_cast<int>(positive(8, "threads", true));
    r.particles = std::llround(positive(9, "particles", true));
    r.bonds = std::llround(num(10, "bonds"));
    r.steps = std::llround(num(11, "steps"));
    r.wall_s = num(12, "wall_s");
    {
      // A measurement that produced no number (inf, nan) says nothing about the error: skipped.
      const double e = std::strtod(f[13].c_str(), nullptr);
      if (!std::isfinite(e) && !f[13].empty()) continue;
      r.error = std::fabs(num(13, "error"));
    }
    r.error_measure = f[14];
    if (r.dimension != 2 && r.dimension != 3) throw InputError(path, where + " dimension", f[2], "2 or 3");
    rows.push_back(std::move(r));
  }
  return rows;
}

ProblemClass classify_problem(const solver::CaseConfig& c) {
  if (c.quasi_static)
    return {"quasi_static_bar",
            "time.integrator is adr (static equilibrium): the atlas's static problem with a known answer is the "
            "quasi-static bar (strain against sigma/E)"};
  const bool softens = c.fracture && std::any_of(c.materials.begin(), c.materials.end(), [](const auto& m) {
    return m.fracture_energy > 0 && m.tensile_strength > 0;
  });
  if (softens)
    return {"softening_strength",
            "bonds soften from a tensile strength (quasi-brittle law): the error that decides where and when the body "
            "cracks is in the strength it reaches, which the atlas measures as the peak stress of a pulled bar against "
            "tensile_strength (fracture_energy rows: the energy, which the law keeps by construction)"};
  const bool breaks = c.fracture && std::any_of(c.materials.begin(), c.materials.end(),
                                                [](const auto& m) { return m.fracture_energy > 0; });
  if (breaks)
    return {"fracture_energy",
            "bonds can break (a material has a fracture energy): the error that decides the outcome is in the energy "
            "a crack dissipates, which the atlas measures on the fracture-energy test (kalthoff_winkler rows measure a "
            "crack angle, a different quantity)"};
  return {"wave_speed_bar",
          "an elastic dynamic run (velocity Verlet, nothing breaks): its error is in how fast and how faithfully "
          "waves travel, which the atlas measures on the wave-speed bar"};
}

ErrorEstimate expected_error(const std::vector<AtlasRow>& atlas, const std::string& problem, const std::string& model,
                             int dimension, const std::string& kind, double m, double resolution) {
  ErrorEstimate e;
  // The nearest measured horizon factor of the same problem, model, dimension and kind.
  auto ms = measured_m(atlas, problem, model, dimension, kind);
  std::string caveat;
  if (ms.empty()) {
    // The other dimension's rows, on their own resolution axis: a rough guide, said so.
    const int other = dimension == 2 ? 3 : 2;
    ms = measured_m(atlas, problem, model, other, kind);
    if (ms.empty()) {
      e.how = "the atlas has no float64 rows for " + problem + ", " + model + ", " + kind + " particles";
      return e;
    }
    caveat = " [measured in " + std::to_string(other) + "D only: a rough guide for this " + std::to_string(dimension) +
             "D case]";
    resolution = std::pow(std::pow(resolution, dimension), 1.0 / other);
    dimension = other;
  }
  // Nearest by the horizon factor the row actually ran with.
  const double mm = *std::min_element(ms.begin(), ms.end(), [&](double a, double b) {
    return std::fabs(horizon_factor_of_row_m(a) - m) < std::fabs(horizon_factor_of_row_m(b) - m);
  });
  const auto pts = group_points(atlas, problem, model, dimension, kind, mm);
  e.known = true;
  std::string group = problem + ", " + model + ", " + std::to_string(dimension) + "D, " + kind + ", m = " + fmt(mm) +
                      (std::fabs(horizon_factor_of_row_m(mm) - m) > 1e-6 ? " (nearest measured to m = " + fmt(m) + ")" : "");
  if (resolution <= pts.front().resolution) {
    e.error = pts.front().error;
    e.how = group + ": at or below the coarsest measured resolution (" + fmt(pts.front().resolution) +
            " particles per side); the coarsest measured error is taken, the true one may be larger";
  } else if (resolution >= pts.back().resolution) {
    e.error = pts.back().error;
    e.how = group + ": at or beyond the finest measured resolution (" + fmt(pts.back().resolution) +
            " particles per side); the finest measured error is taken (no extrapolation)";
  } else {
    size_t k = 1;
    while (pts[k].resolution < resolution) ++k;
    e.error = log_interp(resolution, pts[k - 1].resolution, pts[k - 1].error, pts[k].resolution, pts[k].error);
    e.how = group + ": interpolated (log-log) between the measured " + fmt(pts[k - 1].resolution) + " and " +
            fmt(pts[k].resolution) + " particles per side";
  }
  e.how += caveat;
  return e;
}

ResolutionNeed resolution_for(const std::vector<AtlasRow>& atlas, const std::string& problem, const std::string& model,
                              int dimension, const std::string& kind, double m, double tolerance) {
  ResolutionNeed need;
  const auto pts = group_points(atlas, problem, model, dimension, kind, m);
  if (pts.empty()) {
    need.how = "no measured rows";
    return need;
  }
  // First setting from which every finer measured setting meets the tolerance: a coarse
  // lucky point followed by a failing finer one does not count.
  size_t first = pts.size();
  for (size_t k = pts.size(); k-- > 0;) {
    if (pts[k].error > tolerance) break;
    first = k;
  }
  if (first == pts.size()) {
    need.resolution = pts.back().resolution;
    need.error_at_need = pts.back().error;
    need.how = "no measured setting meets it (finest measured: " + fmt(pts.back().error) + " at " +
               fmt(pts.back().resolution) + " particles per side)";
    return need;
  }
  need.met = true;
  if (first == 0) {
    need.resolution = pts.front().resolution;
    need.error_at_need = pts.front().error;
    need.how = "the coarsest measured setting (" + fmt(pts.front().resolution) + " particles per side, error " +
               fmt(pts.front().error) + ") already meets it; coarser was not measured, so not proposed";
    return need;
  }
  // The coarsest measured setting from which every finer one meets the tolerance. No
  // interpolation between measured settings: the error between them is not monotone in
  // spacing (cancelling errors: the PMB wave strip measures 0.0038, 0.0061, 0.0054 at 2,
  // 1, 0.5 mm), so only measured settings are proposed.
  const Point& a = pts[first - 1];
  const Point& b = pts[first];
  need.resolution = b.resolution;
  need.error_at_need = b.error;
  need.how = "the coarsest measured setting from which every finer one meets it: " + fmt(b.resolution) +
             " particles per side (error " + fmt(b.error) + "; the next coarser, " + fmt(a.resolution) + ", has " +
             fmt(a.error) + ")";
  return need;
}

}  // namespace breccia::plan
