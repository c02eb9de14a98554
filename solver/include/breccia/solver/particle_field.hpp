#pragma once
// A per-particle field read from a file (`initial[].file`): one row per particle of the
// particle file, in its order, 2 or 3 numbers a row (a vector field's components). HDF5
// (a dataset N x 2 or N x 3) or CSV (N rows; a first line that is not numbers is a header).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace breccia::solver {

struct ParticleField {
  std::vector<double> values;  // row-major, `columns` per particle
  int columns = 0;
};

// HDF5 when `dataset` is given, CSV otherwise. `case_file` and `key` name the case entry in
// errors (exit 2): a missing file or dataset,
// another number of rows than `particles`, or rows of other than 2 or 3 numbers. `rows`
// (ascending file rows): those rows alone, one after another (a distributed set-up's window
// system: its particles' rows; an HDF5 dataset is read by those rows, a CSV file whole).
ParticleField read_particle_field(const std::string& path, const std::string& dataset, size_t particles,
                                  const std::string& case_file, const std::string& key,
                                  const std::vector<int64_t>* rows = nullptr);

}  // namespace breccia::solver
