#include "breccia/geometry/summary.hpp"

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <string>

namespace breccia::geometry {
namespace {

template <typename... Args>
void line(std::string& out, const char* format, Args... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, format, args...);
  out += buf;
}

}  // namespace

std::string summarize(const ParticleModel& m) {
  std::string out;
  const size_t n = m.size();
  line(out, "source      %s\n", m.source.c_str());
  line(out, "dimension   %d%s\n", m.dimension,
       m.dimension == 2 ? (" (thickness " + std::to_string(m.thickness_m) + " m)").c_str() : "");
  line(out, "particles   %zu\n", n);
  line(out, "volume      %.9g m^3\n", std::accumulate(m.volume_m3.begin(), m.volume_m3.end(), 0.0));
  std::vector<double> per_material(m.material_names.size(), 0.0);
  std::vector<size_t> count_material(m.material_names.size(), 0);
  for (size_t i = 0; i < n; ++i) {
    const auto id = static_cast<size_t>(m.material_id[i]);
    if (id < per_material.size()) {
      per_material[id] += m.volume_m3[i];
      ++count_material[id];
    }
  }
  for (size_t k = 0; k < per_material.size(); ++k)
    line(out, "  material %-20s %10zu particles  %.9g m^3\n", m.material_names[k].c_str(), count_material[k],
         per_material[k]);
  if (!m.spacing_m.empty()) {
    const auto [lo, hi] = std::minmax_element(m.spacing_m.begin(), m.spacing_m.end());
    line(out, "spacing     min %.6g m, max %.6g m\n", *lo, *hi);
  }
  for (const auto& s : m.sets) line(out, "  set      %-20s %10zu particles\n", s.name.c_str(), s.indices.size());
  for (const auto& s : m.surfaces)
    line(out, "  surface  %-20s %10zu facets     %.9g m^2\n", s.name.c_str(), s.size(),
         std::accumulate(s.area_m2.begin(), s.area_m2.end(), 0.0));
  return out;
}

}  // namespace breccia::geometry
