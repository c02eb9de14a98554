// breccia-post: cracks, fragments, size distribution, energy balance and probe spectra of
// one solver run directory. Outputs go to RUN_DIR/post/ (docs/postproc.md).
//
//   breccia-post RUN_DIR [--particles FILE] [--step K | --all] [--cracks] [--fragments]
//                [--energy] [--spectrum PROBE [--frequency F] [--hann] [--gate T0,T1]
//                                             [--resolution DF] [--band W]]
//                [--damage-threshold D] [--crack-criterion bond|damage]
//                [--min-fragment-particles N] [--size sieve|diameter] [--no-plots]
//
// No selector (--cracks, --fragments, --energy, --spectrum) means everything that applies.
// The command line is CLI11's with the tools' conventions (common/cli.hpp).
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <tuple>
#include <vector>

#include "breccia/common/cli.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"
#include "breccia/postproc/post.hpp"

namespace {

constexpr const char* kAbout =
    "breccia-post: cracks, fragments, fragment size distribution, energy balance and probe spectra of\n"
    "one solver run directory (results.h5 + history.csv). No selector (--cracks, --fragments, --energy,\n"
    "--spectrum) means everything that applies.";
constexpr const char* kFooter =
    "Input: RUN_DIR, a breccia-solve output folder. Output: RUN_DIR/post/: cracks.vtp, damage_iso.vtp,\n"
    "crack_history.csv, fragments.csv/.vtu, deformed.vtu, size_distribution.csv, fragment_sizes.png,\n"
    "energy.png, probe_*.csv/.png, spectrum_*.csv/.png, post.json (docs/postproc.md). Times and\n"
    "frequencies in SI or with a unit (\"17 us\", \"2 MHz\"). Bad input: exit code 2, one message.";

using breccia::InputError;

// The options as given; quantities are read once the command line is parsed.
struct Given {
  breccia::postproc::PostOptions o;
  bool cracks = false, fragments = false, energy = false;
  std::string run_dir, frequency, gate, resolution, band, crack_criterion, size;
  bool hann = false;
};

double frequency_of(const std::string& flag, const std::string& text) {
  return breccia::parse_quantity(text, breccia::Quantity::Frequency, "command line", flag);
}

breccia::postproc::PostOptions finish(Given g) {
  breccia::postproc::PostOptions& o = g.o;
  o.run_dir = g.run_dir;
  o.hann = g.hann;
  std::string spectrum_detail;  // one of --gate/--resolution/--band given
  if (!g.gate.empty()) {
    // T0,T1: two times (seconds, or with a unit: "17 us,28 us"); inside the record is checked
    // against history.csv.
    const std::string& v = g.gate;
    const size_t comma = v.find(',');
    const std::string expected = "T0,T1: two times with T0 < T1, e.g. 17e-6,28e-6 (s)";
    if (comma == std::string::npos || v.find(',', comma + 1) != std::string::npos)
      throw InputError("command line", "--gate", "'" + v + "'", expected);
    const double t0 = breccia::parse_quantity(v.substr(0, comma), breccia::Quantity::Time, "command line", "--gate");
    const double t1 = breccia::parse_quantity(v.substr(comma + 1), breccia::Quantity::Time, "command line", "--gate");
    if (!(t0 < t1)) throw InputError("command line", "--gate", "'" + v + "'", expected);
    o.gate_s = std::pair{t0, t1};
    spectrum_detail = "--gate";
  }
  for (const auto& [flag, text, into] :
       {std::tuple{"--frequency", &g.frequency, &o.frequency_Hz}, std::tuple{"--resolution", &g.resolution, &o.resolution_Hz},
        std::tuple{"--band", &g.band, &o.band_Hz}}) {
    if (text->empty()) continue;
    const double f = frequency_of(flag, *text);
    if (!(f > 0)) throw InputError("command line", flag, std::to_string(f) + " Hz", "a positive frequency");
    *into = f;
    if (into != &o.frequency_Hz) spectrum_detail = flag;
  }
  if (!(o.damage_threshold >= 0.0 && o.damage_threshold <= 1.0))
    throw InputError("command line", "--damage-threshold", std::to_string(o.damage_threshold),
                     "a damage value in [0, 1]");
  if (g.crack_criterion == "damage") o.crack_criterion = breccia::postproc::CrackCriterion::Damage;
  o.size_by_diameter = g.size == "diameter";
  if (o.step && o.all_steps) throw InputError("command line", "--step", "given with --all", "one of --step K or --all");
  if ((!g.frequency.empty() || g.hann) && o.spectrum_probes.empty())
    throw InputError("command line", !g.frequency.empty() ? "--frequency" : "--hann", "without --spectrum",
                     "--spectrum PROBE");
  if (!spectrum_detail.empty() && o.spectrum_probes.empty())
    throw InputError("command line", spectrum_detail, "without --spectrum", "--spectrum PROBE");
  if (g.cracks || g.fragments || g.energy || !o.spectrum_probes.empty()) {
    o.cracks = g.cracks;
    o.fragments = g.fragments;
    o.energy = g.energy;
    o.probes = !o.spectrum_probes.empty();
    o.spectrum_all = false;
    o.history_required = g.energy || o.probes;
  }
  if (const char* py = std::getenv("PYTHON")) o.python = py;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  using breccia::cli::whole_number;
  Given g;
  breccia::postproc::PostOptions& o = g.o;
  CLI::App app{kAbout, "breccia-post"};
  breccia::cli::configure(app, kFooter);
  app.add_option("RUN_DIR", g.run_dir, "directory with results.h5 (and history.csv) written by breccia-solve")
      ->required()
      ->type_name("DIR");
  app.add_option("--particles", o.particles_file, "particle file instead of the one results.h5 names (same content_id)")
      ->type_name("FILE");
  app.add_option_function<long long>(
         "--step", [&](long long k) { o.step = k; }, "analyse the output written at solver step K (default: the last)")
      ->type_name("K")
      ->check(whole_number(0, LLONG_MAX));
  app.add_flag("--all", o.all_steps, "every output: per-output files (_<step> suffix) and ParaView .pvd collections");
  app.add_flag("--cracks", g.cracks, "crack surfaces, damage isosurface, crack history");
  app.add_flag("--fragments", g.fragments, "fragments, fragment meshes, deformed mesh, size distribution");
  app.add_flag("--energy", g.energy, "energy balance from history.csv and the dissipation check");
  app.add_option("--spectrum", o.spectrum_probes, "probe history and amplitude spectrum of probe PROBE (repeatable)")
      ->type_name("PROBE")
      ->allow_extra_args(false);
  app.add_option("--frequency", g.frequency,
                 "reference frequency of the normalisation (default: the largest non-DC peak)")
      ->type_name("F");
  app.add_flag("--hann", g.hann, "Hann window before the transform (periodic; symmetric over a --gate)");
  app.add_option("--gate", g.gate, "transform only the samples with T0 <= time_s <= T1 (inside the record)")
      ->type_name("T0,T1");
  app.add_option("--resolution", g.resolution, "zero-pad to a power-of-two length with bins at most DF apart")
      ->type_name("DF");
  app.add_option("--band", g.band, "peak search half-width around the reference and its harmonics (default: 1 bin)")
      ->type_name("W");
  app.add_option("--damage-threshold", o.damage_threshold,
                 "level of the damage isosurface and of the damage crack criterion (default 0.5)")
      ->type_name("D")
      ->check(breccia::cli::real_number());
  app.add_option("--crack-criterion", g.crack_criterion,
                 "a face is cracked when its bond is broken, or when both particles' damage > D (default bond)")
      ->type_name("bond|damage")
      ->check(breccia::cli::one_of({"bond", "damage"}));
  app.add_option_function<long long>(
         "--min-fragment-particles", [&](long long n) { o.min_fragment_particles = n; },
         "smaller fragments are left out of the table and the distribution (default 1)")
      ->type_name("N")
      ->check(whole_number(1, LLONG_MAX));
  app.add_option("--size", g.size, "size measure of the distribution (default sieve)")
      ->type_name("sieve|diameter")
      ->check(breccia::cli::one_of({"sieve", "diameter"}));
  app.add_flag_callback(
      "--no-plots", [&] { o.plots = false; }, "skip the PNG charts");
  app.add_flag_callback(
      "--quiet", [&] { o.progress = false; }, "no progress on stderr");
  app.add_option("--threads", o.threads,
                 "threads (default: OpenMP's, all cores): the crack history beside the outputs, charts beside both")
      ->type_name("N")
      ->check(whole_number(1, 4096));
  if (const auto code = breccia::cli::parse(app, argc, argv)) return *code;
  return breccia::cli::run_reporting_errors([&]() -> int {
    const breccia::postproc::PostOptions options = finish(g);
    const auto summary = breccia::postproc::run_post(options);
    std::fprintf(stderr, "breccia-post: wrote %zu files to %s\n", summary.written.size(), summary.post_dir.string().c_str());
    if (o.progress) {  // where the time went (the whole-chain profile)
      std::string phases;
      for (const auto& [name, seconds] : summary.phases) {
        char item[96];
        std::snprintf(item, sizeof item, "%s%s %.2f s", phases.empty() ? "" : ", ", name.c_str(), seconds);
        phases += item;
      }
      std::fprintf(stderr, "breccia-post: phases: %s\n", phases.c_str());
    }
    for (const auto& f : summary.plot_failures) std::fprintf(stderr, "breccia-post: chart not drawn: %s\n", f.c_str());
    return 0;
  });
}
