#pragma once
// A solver run directory as post-processing sees it: results.h5 (reference particle data,
// materials, pre-cracks, the list of outputs) checked against the particles.h5 it quotes.
// Layout of results.h5: docs/postproc.md ("Inputs").
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "breccia/common/particle_file.hpp"
#include "breccia/common/families.hpp"

namespace breccia::postproc {

struct OutputInfo {
  std::string group;  // "/output/000012"
  long long step = 0;
  double time_s = 0.0;
};

struct RunData {
  std::filesystem::path run_dir, results_path, particles_path;
  int dimension = 3;
  double thickness_m = 1.0;
  std::string model;  // pmb | lps | mps
  std::vector<double> position_m;     // 3N reference
  std::vector<double> volume_m3;      // N
  std::vector<double> density_kg_m3;  // N
  std::vector<double> horizon_m;      // N
  std::vector<int32_t> material_id;   // N
  std::vector<std::string> material_names;
  std::vector<double> fracture_energy_J_m2;  // per material, mean G0
  std::vector<int64_t> precrack_bonds;       // 2P, pairs i < j
  // The run's bonds, each pair once from its lower index (partners j > i, ascending): the
  // list the per-output broken bits index. /bonds in results.h5; not rebuilt here.
  Families bonds;
  // Bit per bond: within max(horizon_i, horizon_j), i.e. in the fragment graph (the rest
  // are the solver's partial-volume bonds whose neighbour cell only reaches the horizon).
  std::vector<uint8_t> within_horizon;
  size_t within_horizon_count = 0;
  std::vector<OutputInfo> outputs;
  ParticleModel particles;  // the source particles.h5 (mesh, spacing)

  size_t size() const { return volume_m3.size(); }
  double mass_kg(size_t i) const { return volume_m3[i] * density_kg_m3[i]; }
  // Index into outputs of the output written at solver step `step`; InputError if none.
  size_t output_index_of_step(long long step) const;
};

struct OutputFrame {
  OutputInfo info;
  std::vector<double> displacement_m;  // 3N
  std::vector<double> velocity_m_s;    // 3N
  std::vector<double> damage;          // N
  std::vector<uint8_t> broken;         // bit per bond of RunData::bonds: broken by fracture (cumulative)
  size_t broken_count = 0;             // bits set
};

// Open RUN_DIR/results.h5 and the particles file it names (or `particles_override`), and
// check provenance (particles_content_id == content_id). InputError on any defect.
RunData open_run(const std::filesystem::path& run_dir, const std::string& particles_override = "");

// Both reads may be called from several threads at once: they take results_file_mutex().
OutputFrame read_output(const RunData& run, size_t output_index);
// Only the broken bonds and damage: what a crack-area history needs for every output.
OutputFrame read_output_cracks_only(const RunData& run, size_t output_index);

// Held by every read of results.h5 after open_run: the HDF5 library Debian ships is not built
// thread-safe, so two threads must never be inside it at once (post's crack history reads
// outputs beside the analysis of the last one).
std::mutex& results_file_mutex();

}  // namespace breccia::postproc
