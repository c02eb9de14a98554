#include "breccia/postproc/run_data.hpp"

#include <cstdio>

#include "breccia/common/error.hpp"
#include "breccia/common/h5.hpp"
#include "breccia/postproc/bond_graph.hpp"

namespace breccia::postproc {
namespace fs = std::filesystem;
namespace {

std::string group_name(size_t k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "/output/%06zu", k);
  return buf;
}

void require(const h5::File& f, const std::string& obj, const std::string& expected) {
  if (!f.exists(obj)) throw InputError(f.path(), obj, "missing", expected);
}

void require_attr(const h5::File& f, const std::string& obj, const std::string& name) {
  if (!f.has_attr(obj, name))
    throw InputError(f.path(), (obj == "/" ? "/" : obj + "/") + "@" + name, "missing attribute",
                     "written by breccia-solve (format breccia-results 2)");
}

template <class T>
std::vector<T> sized(std::vector<T> v, size_t expected, const std::string& file, const std::string& name,
                     const std::string& shape) {
  if (v.size() != expected)
    throw InputError(file, name, "size " + std::to_string(v.size()), shape);
  return v;
}

// A per-particle vector: N rows of 3 (row-major). The element count alone would take a 3 x N
// dataset, whose rows read as garbage.
std::vector<double> rows_of_3(const h5::File& f, const std::string& name, size_t n) {
  const std::vector<hsize_t> d = f.dims(name);
  if (!(d.size() == 2 && d[0] == n && d[1] == 3)) {
    std::string shape;
    for (size_t k = 0; k < d.size(); ++k) shape += (k ? " x " : "") + std::to_string(d[k]);
    throw InputError(f.path(), name, "shape " + (shape.empty() ? std::string("scalar") : shape),
                     "N x 3 with N = " + std::to_string(n) + " particles");
  }
  return f.read_doubles(name);
}

size_t bit_bytes(size_t bonds) { return (bonds + 7) / 8; }

// A bit array over the bond list: ceil(B / 8) bytes, the bits past B clear.
std::vector<uint8_t> read_bits(const h5::File& f, const std::string& name, size_t bonds) {
  std::vector<uint8_t> bits = sized(f.read_uint8(name), bit_bytes(bonds), f.path(), name,
                                    "ceil(B / 8) = " + std::to_string(bit_bytes(bonds)) + " bytes for B = " +
                                        std::to_string(bonds) + " bonds in /bonds/neighbors");
  if (bonds % 8 != 0 && (bits.back() >> (bonds % 8)) != 0)
    throw InputError(f.path(), name, "bits set past bond " + std::to_string(bonds), "the bits after the last bond clear");
  return bits;
}

// /bonds: CSR of each bond once from its lower index. Checked in full (a bad index would
// send the union-find or a face lookup out of bounds).
void read_bonds(const h5::File& f, size_t n, RunData& run) {
  const std::string rp = f.path();
  for (const char* d : {"/bonds/offsets", "/bonds/neighbors", "/bonds/within_horizon"})
    require(f, d, "written by breccia-solve (format breccia-results 2)");
  run.bonds.offsets = sized(f.read_int64("/bonds/offsets"), n + 1, rp, "/bonds/offsets", "N + 1 row starts");
  run.bonds.neighbors = f.read_int32("/bonds/neighbors");
  const auto& off = run.bonds.offsets;
  const auto& nb = run.bonds.neighbors;
  if (off[0] != 0 || off[n] != static_cast<int64_t>(nb.size()))
    throw InputError(rp, "/bonds/offsets", "starts at " + std::to_string(off[0]) + ", ends at " + std::to_string(off[n]),
                     "0 .. " + std::to_string(nb.size()) + " (the length of /bonds/neighbors)");
  for (size_t i = 0; i < n; ++i)
    if (off[i + 1] < off[i])
      throw InputError(rp, "/bonds/offsets[" + std::to_string(i + 1) + "]", std::to_string(off[i + 1]),
                       "non-decreasing row starts");
  for (size_t i = 0; i < n; ++i) {
    for (int64_t b = off[i]; b < off[i + 1]; ++b) {
      const int64_t lower = b == off[i] ? static_cast<int64_t>(i) : nb[b - 1];
      if (nb[b] <= lower || static_cast<size_t>(nb[b]) >= n)
        throw InputError(rp, "/bonds/neighbors[" + std::to_string(b) + "]",
                         std::to_string(nb[b]) + " in the row of particle " + std::to_string(i),
                         "partners j > i in [0, " + std::to_string(n) + "), ascending within a row");
    }
  }
  run.within_horizon = read_bits(f, "/bonds/within_horizon", nb.size());
  run.within_horizon_count = count_bits(run.within_horizon);
}

}  // namespace

size_t RunData::output_index_of_step(long long step) const {
  for (size_t k = 0; k < outputs.size(); ++k)
    if (outputs[k].step == step) return k;
  // The steps themselves, up to 12 of them; a longer list by its first and last few.
  std::string have = outputs.empty() ? std::string("no outputs") : std::to_string(outputs.size()) + " outputs, steps ";
  for (size_t k = 0; k < outputs.size(); ++k) {
    if (outputs.size() > 12 && k == 6) {
      have += " ..";
      k = outputs.size() - 6;
    }
    if (k) have += ' ';
    have += std::to_string(outputs[k].step);
  }
  throw InputError(results_path.string(), "--step", "no output at step " + std::to_string(step),
                   "the step of one of the outputs (" + have + ")");
}

RunData open_run(const fs::path& run_dir, const std::string& particles_override) {
  RunData run;
  run.run_dir = run_dir;
  run.results_path = run_dir / "results.h5";
  const std::string rp = run.results_path.string();
  if (!fs::is_directory(run_dir))
    throw InputError(run_dir.string(), "", "not a directory", "a run directory written by breccia-solve");
  if (!fs::exists(run.results_path))
    throw InputError(rp, "", "file does not exist", "a run directory containing results.h5 written by breccia-solve");
  h5::File f(rp, h5::File::Mode::Read);
  require_attr(f, "/", "format");
  if (f.attr_string("/", "format") != "breccia-results")
    throw InputError(rp, "/@format", "'" + f.attr_string("/", "format") + "'", "'breccia-results'");
  require_attr(f, "/", "format_version");
  if (f.attr_int("/", "format_version") != 2)
    throw InputError(rp, "/@format_version", std::to_string(f.attr_int("/", "format_version")),
                     "2 (version 1 files, PD ones with broken-bond pairs or MPS ones without a bond list, cannot be "
                     "read: rerun breccia-solve to write the bond list and bit arrays)");
  for (const char* a : {"particles_file", "particles_content_id", "dimension", "output_count"})
    require_attr(f, "/", a);
  run.dimension = static_cast<int>(f.attr_int("/", "dimension"));
  if (run.dimension != 2 && run.dimension != 3)
    throw InputError(rp, "/@dimension", std::to_string(run.dimension), "2 or 3");
  run.thickness_m = f.has_attr("/", "thickness_m") ? f.attr_double("/", "thickness_m") : 1.0;
  run.model = f.has_attr("/", "model") ? f.attr_string("/", "model") : "";

  fs::path pf = particles_override.empty() ? fs::path(f.attr_string("/", "particles_file"))
                                           : fs::path(particles_override);
  if (particles_override.empty() && pf.is_relative()) pf = run_dir / pf;
  run.particles_path = pf;
  if (!fs::exists(pf)) {
    // Name where the path came from: the option the user gave, or the run's own record of it.
    if (!particles_override.empty())
      throw InputError("command line", "--particles", "'" + pf.string() + "' does not exist",
                       "the particles.h5 the run in " + run_dir.string() + " was computed from");
    throw InputError(rp, "/@particles_file", "particles file '" + pf.string() + "' does not exist",
                     "the particles.h5 this run was computed from (or --particles FILE)");
  }
  run.particles = read_particle_file(pf.string());
  const std::string quoted = f.attr_string("/", "particles_content_id");
  if (quoted != run.particles.content_id)
    throw InputError(rp, "/@particles_content_id",
                     "'" + quoted + "' but " + pf.string() + " has content_id '" + run.particles.content_id + "'",
                     "the particles file this run was computed from (same content_id)");

  for (const char* d : {"/particles/position", "/particles/volume", "/particles/density", "/particles/horizon",
                        "/particles/material_id"})
    require(f, d, "written by breccia-solve");
  const size_t n = f.dims("/particles/volume").at(0);
  if (n != run.particles.size())
    throw InputError(rp, "/particles/volume", std::to_string(n) + " particles",
                     std::to_string(run.particles.size()) + " as in " + pf.string());
  run.position_m = rows_of_3(f, "/particles/position", n);
  run.volume_m3 = sized(f.read_doubles("/particles/volume"), n, rp, "/particles/volume", "N");
  run.density_kg_m3 = sized(f.read_doubles("/particles/density"), n, rp, "/particles/density", "N");
  run.horizon_m = sized(f.read_doubles("/particles/horizon"), n, rp, "/particles/horizon", "N");
  run.material_id = sized(f.read_int32("/particles/material_id"), n, rp, "/particles/material_id", "N");
  if (f.exists("/materials/names")) run.material_names = f.read_strings("/materials/names");
  if (f.exists("/materials/fracture_energy")) run.fracture_energy_J_m2 = f.read_doubles("/materials/fracture_energy");
  for (size_t i = 0; i < n; ++i)
    if (run.material_id[i] < 0 ||
        (!run.fracture_energy_J_m2.empty() && static_cast<size_t>(run.material_id[i]) >= run.fracture_energy_J_m2.size()))
      throw InputError(rp, "/particles/material_id[" + std::to_string(i) + "]", std::to_string(run.material_id[i]),
                       "an index into /materials/fracture_energy");
  if (f.exists("/precrack_bonds")) {
    run.precrack_bonds = f.read_int64("/precrack_bonds");
    validate_pairs(run.precrack_bonds, n, rp, "/precrack_bonds");
  }

  read_bonds(f, n, run);

  const long long count = f.attr_int("/", "output_count");
  for (long long k = 0; k < count; ++k) {
    OutputInfo o;
    o.group = group_name(static_cast<size_t>(k));
    require(f, o.group, "output_count = " + std::to_string(count) + " consecutive output groups");
    require_attr(f, o.group, "step");
    require_attr(f, o.group, "time_s");
    o.step = f.attr_int(o.group, "step");
    o.time_s = f.attr_double(o.group, "time_s");
    run.outputs.push_back(o);
  }
  return run;
}

namespace {

OutputFrame read_frame(const RunData& run, size_t k, bool full) {
  const std::lock_guard<std::mutex> lock(results_file_mutex());
  if (k >= run.outputs.size())
    throw InputError(run.results_path.string(), "/output", "output index " + std::to_string(k),
                     "< output_count = " + std::to_string(run.outputs.size()));
  const std::string rp = run.results_path.string();
  h5::File f(rp, h5::File::Mode::Read);
  OutputFrame fr;
  fr.info = run.outputs[k];
  const std::string& g = fr.info.group;
  const size_t n = run.size();
  for (const char* d : {"/damage", "/broken"}) require(f, g + d, "written by breccia-solve");
  fr.damage = sized(f.read_doubles(g + "/damage"), n, rp, g + "/damage", "N");
  fr.broken = read_bits(f, g + "/broken", run.bonds.bond_count());
  fr.broken_count = count_bits(fr.broken);
  if (f.has_attr(g, "broken_count") && f.attr_int(g, "broken_count") != static_cast<long long>(fr.broken_count))
    throw InputError(rp, g + "/@broken_count", std::to_string(f.attr_int(g, "broken_count")),
                     std::to_string(fr.broken_count) + ", the bits set in " + g + "/broken");
  if (full) {
    for (const char* d : {"/displacement", "/velocity"}) require(f, g + d, "written by breccia-solve");
    fr.displacement_m = rows_of_3(f, g + "/displacement", n);
    fr.velocity_m_s = rows_of_3(f, g + "/velocity", n);
  }
  return fr;
}

}  // namespace

std::mutex& results_file_mutex() {
  static std::mutex m;
  return m;
}

OutputFrame read_output(const RunData& run, size_t k) { return read_frame(run, k, true); }
OutputFrame read_output_cracks_only(const RunData& run, size_t k) { return read_frame(run, k, false); }

}  // namespace breccia::postproc
