#pragma once
// Entry point of the MPS solver, called by breccia-solve for `model: {type: mps}` and by
// the stand-alone breccia-mps CLI. Writes history.csv, summary.json and results.h5 into
// out_dir. Returns a process exit code; throws breccia::InputError for bad input.
#include <string>

namespace breccia::mps {

int run_case(const std::string& case_file, const std::string& out_dir, int threads);

}  // namespace breccia::mps
