// breccia-mps CASE.yaml -o DIR [--threads N]: run an MPS case on its own (the same entry
// point breccia-solve calls for `model: {type: mps}`).
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "breccia/common/error.hpp"
#include "breccia/mps/run_case.hpp"

int main(int argc, char** argv) {
  std::string case_file, out_dir;
  int threads = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "-o" || arg == "--out") && i + 1 < argc) {
      out_dir = argv[++i];
    } else if (arg == "--threads" && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
      if (threads < 1) {
        std::fprintf(stderr, "error: --threads: '%s' is not a positive integer\n", argv[i]);
        return breccia::kExitBadInput;
      }
    } else if (arg == "-h" || arg == "--help") {
      std::printf("usage: breccia-mps CASE.yaml -o DIR [--threads N]\n");
      return 0;
    } else if (!arg.empty() && arg[0] != '-' && case_file.empty()) {
      case_file = arg;
    } else {
      std::fprintf(stderr, "error: unexpected argument '%s'\nusage: breccia-mps CASE.yaml -o DIR [--threads N]\n", arg.c_str());
      return breccia::kExitBadInput;
    }
  }
  if (case_file.empty() || out_dir.empty()) {
    std::fprintf(stderr, "error: a case file and -o DIR are required\nusage: breccia-mps CASE.yaml -o DIR [--threads N]\n");
    return breccia::kExitBadInput;
  }
  try {
    return breccia::mps::run_case(case_file, out_dir, threads);
  } catch (const breccia::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return breccia::kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return breccia::kExitRunFailed;
  }
}
