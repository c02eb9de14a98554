// The gas load's host side (gas.hpp): its set-up from the case and the particle file, and
// the per-step update of its scalars (volume -> outflow -> pressure -> work).
#include "breccia/solver/gas.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "breccia/common/error.hpp"
#include "breccia/common/huge_pages.hpp"
#include "breccia/common/units.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

// GCC and Clang on x86-64 compile it twice and pick the AVX2 one at load time where the CPU
// has it (ifunc): 4 square roots and divisions at once instead of 2. No "fma" in the target
// (and no -ffast-math): every operation rounds as in the portable build, so the sums and the
// motion are the same bit for bit on either (Gas.TheChunkedCrackPassSumsAsTheOneEntryLoopBitForBit).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__NVCC__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define BRECCIA_GAS_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef BRECCIA_GAS_CLONES
#define BRECCIA_GAS_CLONES
#endif

BRECCIA_GAS_CLONES void gas_chunk_openings(const double* position, const double* kappa_volume, const int32_t* neighbor,
                                           const double* xi_len, const int32_t* pick, int count, double kappa_i,
                                           double volume_i, double xx, double xy, double xz, GasChunkTerms& out) {
  double* e = out.e;
  double* ux = out.ux;
  double* uy = out.uy;
  double* uz = out.uz;
  double* a = out.a;
  double* share = out.share;
  double* px = out.px;
  double* py = out.py;
  double* pz = out.pz;
BRECCIA_SIMD
  for (int c = 0; c < count; ++c) {
    e[c] = gas_entry_opening(position, kappa_volume, neighbor, xi_len, kappa_i, xx, xy, xz, pick[c], ux[c], uy[c],
                             uz[c], a[c]);
    const bool open = e[c] > 0.0;
    share[c] = open ? a[c] * volume_i * e[c] * 0.5 : 0.0;
    px[c] = open ? a[c] * ux[c] : 0.0;
    py[c] = open ? a[c] * uy[c] : 0.0;
    pz[c] = open ? a[c] * uz[c] : 0.0;
  }
}

double GasState::front_speed() const {
  if (fixed_front_speed > 0.0) return fixed_front_speed;
  // A gas expanding into an empty channel cannot move faster than its escape speed (the
  // centred rarefaction of a gas released into vacuum; gas_law.hpp).
  const double rho = reference_density * mass_fraction * reference_volume / std::max(volume, 1e-30);
  if (rho <= 0.0 || pressure_abs <= 0.0) return 1e-30;
  return gas_escape_speed(pressure_abs, rho, mass_fraction * reference_volume / volume, law);
}

void GasState::advance(double wall, const GasSums& cracks, double t, double dt) {
  const double crack = cracks.volume;
  if (!vented && cracks.vents > 0.0) {
    vented = true;
    vent_time = t;
  }
  // A cavity cannot close up: keep a sliver of V0 (only a crushed, inverted wall gets here).
  const double v_now = std::max(reference_volume + wall + crack, 1e-6 * reference_volume);
  // Outflow over the step, explicit at the last state (its time scale V / (Gamma A c) is
  // hundreds of steps for a charge hole).
  if (vented && dt > 0.0 && pressure_abs > ambient && mass_fraction > 0.0) {
    const double gamma = gas_local_gamma(pressure_abs, mass_fraction * reference_volume / volume, law);
    const double rho = reference_density * mass_fraction * reference_volume / volume;
    const double mdot = choked_flow_factor(gamma) * outflow_area() * std::sqrt(gamma * pressure_abs * rho);
    mass_fraction = std::max(0.0, mass_fraction - dt * mdot / (reference_density * reference_volume));
  }
  const double p_ref = ambient + spec->history.at(t);
  double p = gas_isentrope_pressure(p_ref, mass_fraction * reference_volume / v_now, law);
  if (vented) p = std::max(p, ambient);  // air fills a vented cavity
  double gauge = std::max(0.0, p - ambient);
  peak_pressure = std::max(peak_pressure, gauge);
  if (vented && gauge < 1e-3 * peak_pressure) {  // spent: from now on it pushes no more
    spent = true;
    gauge = 0.0;
  }
  // Work on the solid: the volume the motion made, without the crack the front just reached.
  const double v_moved = std::max(reference_volume + wall + cracks.volume_before, 1e-6 * reference_volume);
  // and the entries that joined: their force starts now, over this step's displacement.
  // The wall particles and crack entries that left now: their last force over this step's displacement.
  work += 0.5 * (pressure + gauge) * (v_moved - volume) + 0.5 * gauge * cracks.joined + 0.5 * pressure * cracks.left;
  volume = v_now;
  wall_volume = wall;
  crack_volume = crack;
  crack_vent_area = cracks.vent_area;  // the mouths at this state: the next step's outflow
  pressure = gauge;
  pressure_abs = p;
}

namespace {

// Height along m_hat of the mouth's plane: the highest facet vertex of the surface, found in
// the cells that own the facets (the facet's vertices are the cell's nodes on its plane).
double mouth_height(const ParticleModel& pm, const SurfaceFacets& sf, const double m_hat[3], bool& found) {
  found = false;
  double best = -std::numeric_limits<double>::infinity();
  const int per_cell = pm.nodes_per_cell;
  if (per_cell == 0 || pm.mesh_cells.empty()) return best;
  for (size_t f = 0; f < sf.size(); ++f) {
    const int64_t cell = sf.particle[f];
    const double scale = std::sqrt(sf.area_m2[f]);
    for (int a = 0; a < per_cell; ++a) {
      const double* x = pm.node_position(pm.cell_nodes(cell)[a]);
      double off = 0.0, h = 0.0;
      for (int d = 0; d < 3; ++d) {
        off += sf.normal[3 * f + d] * (x[d] - sf.centroid_m[3 * f + d]);
        h += m_hat[d] * x[d];
      }
      if (std::fabs(off) > 1e-6 * scale) continue;  // the cell's node off the facet
      best = std::max(best, h);
      found = true;
    }
  }
  return best;
}

}  // namespace

void setup_gas(PdSystem& s, int load_index, const std::string& field) {
  const CaseConfig& c = s.config;
  GasState& g = s.gas;
  if (g.active)
    throw InputError(c.file, field + ".type", "a second gas load", "one gas load per case (one charge hole)");
  const LoadSpec& ls = *s.surface_loads[load_index].spec;
  const GasSpec& spec = ls.gas;
  const SurfaceFacets& sf = *s.particles.find_surface(ls.surface);
  g.active = true;
  g.load = load_index;
  g.spec = &ls;
  g.law = spec.law;
  g.reference_density = spec.density;
  g.ambient = spec.ambient_pressure;
  g.fixed_front_speed = spec.front_speed;
  g.crack_entry = spec.crack_entry;
  g.crack_pass_every = spec.crack_pass_every;
  g.crack_pass_tolerance = spec.crack_pass_tolerance;
  g.crack_pass_new_crack_at_once = spec.crack_pass_new_crack_at_once;
  g.crack_pass_countdown = 0;
  g.crack_pass_interval = 1;
  g.crack_pass_done = false;
  const int dim = s.dimension;

  // Reference volume by the divergence theorem over the wall, closed by the mouth's plane:
  // V0 = (1/d) [ -sum A n.c + |M| h_mouth ], M = sum A n (the mouth's area vector, zero for a
  // closed cavity), n outward from the body. Exact for a faceted wall and a planar mouth.
  double m[3] = {0, 0, 0}, moment = 0.0, total_area = 0.0;
  for (size_t f = 0; f < sf.size(); ++f) {
    total_area += sf.area_m2[f];
    for (int d = 0; d < 3; ++d) {
      m[d] += sf.area_m2[f] * sf.normal[3 * f + d];
      moment += sf.area_m2[f] * sf.normal[3 * f + d] * sf.centroid_m[3 * f + d];
    }
  }
  const double mouth_area = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
  const bool open_surface = mouth_area > 1e-6 * total_area;
  if (spec.cavity_volume > 0.0) {
    g.reference_volume = spec.cavity_volume;
  } else {
    double v0 = -moment / dim;
    if (open_surface) {
      const double m_hat[3] = {m[0] / mouth_area, m[1] / mouth_area, m[2] / mouth_area};
      bool found = false;
      const double h = mouth_height(s.particles, sf, m_hat, found);
      if (!found)
        throw InputError(c.file, field + ".cavity_volume", "missing, and surface '" + ls.surface +
                         "' is open (a hole's mouth) in a particle file without its mesh",
                         "the cavity's volume in m3 (the mouth's plane cannot be found without the mesh)");
      v0 += mouth_area * h / dim;
    }
    if (!(v0 > 0.0))
      throw InputError(c.file, field + ".surface", "facets of '" + ls.surface + "' enclose a volume of " +
                       short_number(v0) + " m3", "the wall of a cavity (normals pointing into it), or give cavity_volume");
    g.reference_volume = v0;
  }
  // The fixed vent area: the case's, or the mouth's when it is open; with vent_area:
  // crack_opening the cracks' mouths on the vent surfaces come on top (GasCrackSum).
  g.vent_crack_opening = spec.vent_crack_opening;
  const bool mouth_vents = open_surface && (spec.stemming_open || !g.vent_crack_opening);
  const bool can_vent = spec.stemming_open || !spec.vent_surfaces.empty();
  // A gas that cannot vent has no outflow area (history.csv's gas_vent_area_m2 said the mouth's).
  g.vent_area = !can_vent ? 0.0 : spec.vent_area > 0.0 ? spec.vent_area : mouth_vents ? mouth_area : 0.0;
  if (can_vent && !(g.vent_area > 0.0) && !(g.vent_crack_opening && !spec.vent_surfaces.empty()))
    throw InputError(c.file, field + ".vent_area", "missing, and the cavity has no mouth to take it from",
                     "the area through which the gas escapes once it vents (m2), or crack_opening");

  const size_t n = s.n;
  g.vent_facet_area.assign(n, 0.0);
  for (size_t v = 0; v < spec.vent_surfaces.size(); ++v) {
    const std::string key = field + ".vent_surfaces[" + std::to_string(v) + "]";
    const SurfaceFacets* vent = s.particles.find_surface(spec.vent_surfaces[v]);
    if (!vent)
      throw InputError(c.file, key, "'" + spec.vent_surfaces[v] + "' is not a surface of the particle file",
                       "the name of a boundary surface group");
    // Named twice, its facet areas were added twice (twice the outflow); the gas's own wall
    // can never vent (its particles are reached at the start, never by the front).
    for (size_t w = 0; w < v; ++w)
      if (spec.vent_surfaces[w] == spec.vent_surfaces[v])
        throw InputError(c.file, key, "'" + spec.vent_surfaces[v] + "' again (also vent_surfaces[" + std::to_string(w) + "])",
                         "each vent surface once");
    if (spec.vent_surfaces[v] == ls.surface)
      throw InputError(c.file, key, "'" + ls.surface + "', the gas's own surface",
                       "a free surface the gas reaches through cracks (the cavity's mouth: stemming: open)");
    for (size_t f = 0; f < vent->size(); ++f)  // (a window system: its window's particles)
      if (const int32_t i = s.system_of_file(vent->particle[f]); i >= 0) g.vent_facet_area[i] += vent->area_m2[f];
  }
  // Crack-face area factor kappa_i = 2 d / sum_j V_j |xi| (gas.hpp). A distributed set-up
  // holds the rank's rows only (the others are empty here): setup_system gathers the owners'.
  g.kappa_volume.assign(2 * n, 0.0);
  // (Each row's own sum, in entry order: the same bits on any thread count.)
#pragma omp parallel for schedule(dynamic, 1024)
  for (size_t i = 0; i < n; ++i) {
    double mi = 0.0;
    for (int64_t k = s.offsets[i]; k < s.offsets[i + 1]; ++k) mi += s.volume[s.neighbor[k]] * s.xi_len[k];
    g.kappa_volume[2 * i] = mi > 0.0 ? 2.0 * dim / mi : 0.0;
    g.kappa_volume[2 * i + 1] = s.volume[i];
  }
  if (g.crack_entry) {
    g.arrival.assign(n, std::numeric_limits<double>::infinity());
    for (int64_t p : sf.particle)  // the wall is wetted
      if (const int32_t i = s.system_of_file(p); i >= 0) g.arrival[i] = 0.0;
    g.arrival_next = g.arrival;
    g.push.assign(3 * n, 0.0);
    g.front_done.assign(n, 0);
    g.attached.assign(n, 1);
    g.row_mark.assign(n, 1);  // every row picked in full at the first pass (GasView::row_mark)
    g.chunk_live.assign(s.neighbor.size(), 0);
    // Per entry: the rank's rows under a distributed set-up (finish_distributed_setup gathers
    // in_crack whole, the state a checkpoint keeps; halves move into the rank's system).
    // The two per-entry byte arrays (60 MB each on the full concrete case) on huge pages
    // (huge_pages.hpp): on 4 KiB pages their first touch cost about 0.5 CPU s of the set-up
    // there (a fault per page); the same values.
    assign_on_huge_pages(g.in_crack, s.neighbor.size(), uint8_t{0});
    g.position.assign(3 * n, 0.0);
    // The halves each entry has (gas_entry_open), so the open test reads two bytes.
    assign_on_huge_pages(g.halves, s.neighbor.size());
    // One byte per entry from its own values (0.21 s on one thread on the full concrete case).
    const std::vector<double>& k_dual = s.k_dual_halves();
    const int64_t entries = static_cast<int64_t>(s.neighbor.size());
#pragma omp parallel for schedule(static)
    for (int64_t k = 0; k < entries; ++k)
      g.halves[k] = static_cast<uint8_t>((s.own_half_exists(k) ? kOwnIntact : 0) | (k_dual[k] > 0.0 ? kDualIntact : 0));
  }
  // gas_fixed_order_sum's block sums, for the walls' and the particles' sums alike: sized
  // once here, so that no step allocates.
  g.block_sums.assign(gas_blocks(std::max<int64_t>(static_cast<int64_t>(n), static_cast<int64_t>(s.facets.particle.size()))),
                      GasSums{});
  g.wall_dv.assign(s.facets.particle.size(), 0.0);
  g.wall_left.assign(s.facets.particle.size(), 0.0);
  g.wall_on.assign(s.facets.particle.size(), 1);
  g.vented = spec.stemming_open;
  g.vent_time = spec.stemming_open ? 0.0 : -1.0;
  g.volume = g.reference_volume;
  g.mass_fraction = 1.0;
  g.pressure_abs = g.ambient;
  g.pressure = 0.0;
  g.advance(0.0, GasSums{}, s.time, 0.0);  // the state at the start, no work yet
  g.work = 0.0;
}

}  // namespace breccia::solver
