#include "breccia/solver/particle_field.hpp"

#include <cmath>
#include <filesystem>

#include "breccia/common/csv.hpp"
#include "breccia/common/error.hpp"
#include "breccia/common/h5.hpp"

namespace breccia::solver {

namespace {

// Runs of consecutive rows among ascending `rows`.
std::vector<h5::RowRun> runs_of(const std::vector<int64_t>& rows) {
  std::vector<h5::RowRun> runs;
  for (const int64_t r : rows)
    if (!runs.empty() && static_cast<int64_t>(runs.back().first + runs.back().rows) == r) ++runs.back().rows;
    else runs.push_back({static_cast<hsize_t>(r), 1});
  return runs;
}

ParticleField read_h5_field(const std::string& path, const std::string& dataset, const std::string& case_file,
                            const std::string& key, size_t particles, const std::vector<int64_t>* rows) {
  const h5::File f(path, h5::File::Mode::Read);
  if (!f.exists(dataset))
    throw InputError(case_file, key + ".dataset", "no dataset '" + dataset + "' in '" + path + "'",
                     "the name of an N x 2 or N x 3 dataset of that file");
  const auto dims = f.dims(dataset);
  if (dims.size() != 2 || (dims[1] != 2 && dims[1] != 3))
    throw InputError(path, dataset, "a dataset of rank " + std::to_string(dims.size()),
                     "N x 2 or N x 3 numbers (one row per particle)");
  if (!rows) return {f.read_doubles(dataset), static_cast<int>(dims[1])};
  if (dims[0] != particles)  // the whole count, checked before rows are picked
    throw InputError(path, dataset, std::to_string(dims[0]) + " rows",
                     std::to_string(particles) + " rows, one per particle of the particle file in its order");
  return {f.read_double_runs(dataset, runs_of(*rows)), static_cast<int>(dims[1])};
}

// CSV: one row of 2 or 3 numbers per particle; a first line of names is optional.
ParticleField read_csv_field(const std::string& path) {
  const CsvColumns csv = read_csv_columns(
      path, {.header_optional = true, .comments = true, .finite = true,
             .expected = "one row per particle in the particle file's order: vx, vy[, vz] (or ux, uy[, uz])"});
  const size_t columns = csv.columns.size();
  if (columns != 2 && columns != 3)
    throw InputError(path, "columns", std::to_string(columns) + " columns", "2 or 3 numbers a row");
  ParticleField f{{}, static_cast<int>(columns)};
  const size_t rows = csv.columns[0].size();
  f.values.resize(rows * columns);
  for (size_t r = 0; r < rows; ++r)
    for (size_t c = 0; c < columns; ++c) f.values[r * columns + c] = csv.columns[c][r];
  return f;
}

}  // namespace

ParticleField read_particle_field(const std::string& path, const std::string& dataset, size_t particles,
                                  const std::string& case_file, const std::string& key,
                                  const std::vector<int64_t>* rows) {
  if (!std::filesystem::is_regular_file(path))
    throw InputError(case_file, key + ".file", "cannot open '" + path + "'",
                     "a readable HDF5 (.h5) or CSV file, relative to the case file");
  // The case parser pairs a dataset with an .h5 file and none with a CSV one.
  ParticleField field =
      dataset.empty() ? read_csv_field(path) : read_h5_field(path, dataset, case_file, key, particles, rows);
  for (size_t k = 0; k < field.values.size(); ++k)  // (the CSV reader refused them by line)
    if (!std::isfinite(field.values[k])) {
      const size_t row = k / static_cast<size_t>(field.columns);  // the file's row (a rank's rows: its own)
      throw InputError(path, dataset,
                       std::to_string(field.values[k]) + " in row " +
                           std::to_string(rows && !dataset.empty() ? static_cast<size_t>((*rows)[row]) : row),
                       "finite numbers");
    }
  if (rows && !dataset.empty()) return field;  // its rows alone, the count checked
  const size_t read = field.values.size() / static_cast<size_t>(field.columns);
  if (read != particles)
    throw InputError(path, dataset.empty() ? "rows" : dataset, std::to_string(read) + " rows",
                     std::to_string(particles) + " rows, one per particle of the particle file in its order");
  if (rows) {  // a CSV file's wanted rows
    const size_t w = static_cast<size_t>(field.columns);
    std::vector<double> kept;
    kept.reserve(w * rows->size());
    for (const int64_t r : *rows)
      kept.insert(kept.end(), field.values.begin() + static_cast<int64_t>(w) * r,
                  field.values.begin() + static_cast<int64_t>(w) * (r + 1));
    field.values = std::move(kept);
  }
  return field;
}

}  // namespace breccia::solver
