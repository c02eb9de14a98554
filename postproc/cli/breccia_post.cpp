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
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/common/units.hpp"
#include "breccia/postproc/post.hpp"

namespace {

constexpr const char* kUsage =
    "usage: breccia-post RUN_DIR [--particles FILE] [--step K | --all] [--cracks] [--fragments]\n"
    "                    [--energy] [--spectrum PROBE [--frequency F] [--hann] [--gate T0,T1]\n"
    "                                                 [--resolution DF] [--band W]]\n"
    "                    [--damage-threshold D] [--crack-criterion bond|damage]\n"
    "                    [--min-fragment-particles N] [--size sieve|diameter] [--no-plots] [--quiet]\n"
    "Writes RUN_DIR/post/: cracks.vtp, damage_iso.vtp, crack_history.csv, fragments.csv/.vtu,\n"
    "deformed.vtu, size_distribution.csv, fragment_sizes.png, energy.png, probe_*.csv/.png,\n"
    "spectrum_*.csv/.png, post.json. No selector = everything that applies.\n";

using breccia::InputError;

std::string value_of(const std::vector<std::string>& args, size_t& k) {
  if (k + 1 >= args.size()) throw InputError("command line", args[k], "no value", "a value after " + args[k]);
  return args[++k];
}

long long integer_of(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0') throw InputError("command line", flag, "'" + text + "'", "an integer");
  return v;
}

breccia::postproc::PostOptions parse(const std::vector<std::string>& args) {
  breccia::postproc::PostOptions o;
  bool cracks = false, fragments = false, energy = false, any = false;
  std::string run_dir;
  bool have_frequency = false, have_hann = false;
  std::string spectrum_detail;  // the last of --gate/--resolution/--band given
  for (size_t k = 0; k < args.size(); ++k) {
    const std::string& a = args[k];
    if (a == "--particles") o.particles_file = value_of(args, k);
    else if (a == "--step") o.step = integer_of(a, value_of(args, k));
    else if (a == "--all") o.all_steps = true;
    else if (a == "--cracks") cracks = any = true;
    else if (a == "--fragments") fragments = any = true;
    else if (a == "--energy") energy = any = true;
    else if (a == "--spectrum") { o.spectrum_probes.push_back(value_of(args, k)); any = true; }
    else if (a == "--frequency") {
      o.frequency_Hz = breccia::parse_quantity(value_of(args, k), breccia::Quantity::Frequency, "command line", a);
      have_frequency = true;
    } else if (a == "--hann") { o.hann = true; have_hann = true; }
    else if (a == "--gate") {
      // T0,T1: two times (seconds, or with a unit: "17 us,28 us"); inside the record is checked
      // against history.csv.
      const std::string v = value_of(args, k);
      const size_t comma = v.find(',');
      const std::string expected = "T0,T1: two times with T0 < T1, e.g. 17e-6,28e-6 (s)";
      if (comma == std::string::npos || v.find(',', comma + 1) != std::string::npos)
        throw InputError("command line", a, "'" + v + "'", expected);
      const double t0 = breccia::parse_quantity(v.substr(0, comma), breccia::Quantity::Time, "command line", a);
      const double t1 = breccia::parse_quantity(v.substr(comma + 1), breccia::Quantity::Time, "command line", a);
      if (!(t0 < t1)) throw InputError("command line", a, "'" + v + "'", expected);
      o.gate_s = std::pair{t0, t1};
      spectrum_detail = a;
    } else if (a == "--resolution" || a == "--band") {
      const double f = breccia::parse_quantity(value_of(args, k), breccia::Quantity::Frequency, "command line", a);
      if (!(f > 0)) throw InputError("command line", a, std::to_string(f) + " Hz", "a positive frequency");
      (a == "--band" ? o.band_Hz : o.resolution_Hz) = f;
      spectrum_detail = a;
    }
    else if (a == "--damage-threshold") {
      const std::string v = value_of(args, k);
      char* end = nullptr;
      o.damage_threshold = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !(o.damage_threshold >= 0.0 && o.damage_threshold <= 1.0))
        throw InputError("command line", a, "'" + v + "'", "a damage value in [0, 1]");
    } else if (a == "--crack-criterion") {
      const std::string v = value_of(args, k);
      if (v == "bond") o.crack_criterion = breccia::postproc::CrackCriterion::Bond;
      else if (v == "damage") o.crack_criterion = breccia::postproc::CrackCriterion::Damage;
      else throw InputError("command line", a, "'" + v + "'", "bond or damage");
    } else if (a == "--min-fragment-particles") {
      o.min_fragment_particles = integer_of(a, value_of(args, k));
      if (o.min_fragment_particles < 1) throw InputError("command line", a, std::to_string(o.min_fragment_particles), ">= 1");
    } else if (a == "--size") {
      const std::string v = value_of(args, k);
      if (v != "sieve" && v != "diameter") throw InputError("command line", a, "'" + v + "'", "sieve or diameter");
      o.size_by_diameter = v == "diameter";
    } else if (a == "--no-plots") o.plots = false;
    else if (a == "--quiet") o.progress = false;
    else if (!a.empty() && a[0] == '-') throw InputError("command line", a, "unknown option", "one of the options in the usage");
    else if (run_dir.empty()) run_dir = a;
    else throw InputError("command line", a, "a second run directory", "one RUN_DIR");
  }
  if (run_dir.empty()) throw InputError("command line", "RUN_DIR", "missing", "a run directory");
  if (o.step && o.all_steps) throw InputError("command line", "--step", "given with --all", "one of --step K or --all");
  if ((have_frequency || have_hann) && o.spectrum_probes.empty())
    throw InputError("command line", have_frequency ? "--frequency" : "--hann", "without --spectrum", "--spectrum PROBE");
  if (!spectrum_detail.empty() && o.spectrum_probes.empty())
    throw InputError("command line", spectrum_detail, "without --spectrum", "--spectrum PROBE");
  o.run_dir = run_dir;
  if (any) {
    o.cracks = cracks;
    o.fragments = fragments;
    o.energy = energy;
    o.probes = !o.spectrum_probes.empty();
    o.spectrum_all = false;
    o.history_required = energy || o.probes;
  }
  if (const char* py = std::getenv("PYTHON")) o.python = py;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args)
    if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    }
  try {
    const breccia::postproc::PostOptions options = parse(args);
    const auto summary = breccia::postproc::run_post(options);
    std::fprintf(stderr, "breccia-post: wrote %zu files to %s\n", summary.written.size(), summary.post_dir.string().c_str());
    for (const auto& f : summary.plot_failures) std::fprintf(stderr, "breccia-post: chart not drawn: %s\n", f.c_str());
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    if (args.empty()) std::fputs(kUsage, stderr);
    return breccia::kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return breccia::kExitRunFailed;
  }
}
