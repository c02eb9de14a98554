#pragma once
// The whole post-processing of one run directory, as breccia-post runs it. Outputs go to
// RUN_DIR/post/; the list of files and their fields is in docs/postproc.md.
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "breccia/postproc/cracks.hpp"

namespace breccia::postproc {

struct PostOptions {
  std::filesystem::path run_dir;
  std::string particles_file;          // override of results.h5's particles_file
  std::optional<long long> step;       // solver step of the output to analyse; default last
  bool all_steps = false;              // per-output files for every output
  bool cracks = true, fragments = true, energy = true, probes = true;
  std::vector<std::string> spectrum_probes;  // probes to transform (named by --spectrum)
  bool spectrum_all = true;            // also transform every probe when none is named
  bool history_required = false;       // history.csv must exist (energy/spectrum asked for)
  std::optional<double> frequency_Hz;
  bool hann = false;
  // Spectra of the rows with gate_s->first <= time_s <= gate_s->second only (--gate); with
  // --hann the window is then the symmetric Hann over the gate (spectrum.hpp, Window).
  std::optional<std::pair<double, double>> gate_s;
  std::optional<double> resolution_Hz;  // zero padding to bins at most this wide (--resolution)
  std::optional<double> band_Hz;        // peak search half-width (--band); unset: +-1 bin
  double damage_threshold = 0.5;
  CrackCriterion crack_criterion = CrackCriterion::Bond;
  long long min_fragment_particles = 1;
  bool size_by_diameter = false;       // size distribution on equivalent diameter, not sieve
  bool plots = true;
  std::string python = "/usr/bin/python3";
  std::filesystem::path scripts_dir;   // empty: the built-in default
  bool progress = true;
  // Threads (0: OpenMP's count, OMP_NUM_THREADS or every core). With two or more, the crack
  // history runs beside the analysis of the selected outputs and the charts are drawn beside
  // the rest; the files written are the same with any count.
  int threads = 0;
};

struct PostSummary {
  std::filesystem::path post_dir;
  std::vector<std::string> written;       // file names under post_dir
  std::vector<std::string> plot_failures; // "file: reason"
  // Wall time of each phase of the run, in order (breccia-post prints them).
  std::vector<std::pair<std::string, double>> phases;
};

PostSummary run_post(const PostOptions& options);

std::filesystem::path default_scripts_dir();

}  // namespace breccia::postproc
