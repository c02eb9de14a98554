#pragma once
// What the distributed tests share (test_distributed.cpp, test_distributed_cuda.cpp): running
// breccia-solve on P ranks, and comparing a run's files with one process's: results.h5 and
// checkpoint.h5 dataset by dataset, byte for byte; history.csv as text except the energies;
// summary.json's energies to 1e-12 (their sums over ranks run in another order,
// docs/parallel.md). BRECCIA_SOLVE_EXE and BRECCIA_MPIEXEC name the executables (compiled in;
// the environment's variables of those names replace them, as on the device machine, where
// the build's paths do not exist).
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace breccia::solver::testing {

// An executable: the environment's `variable` when set, else the build's path.
inline std::string executable(const char* variable, const char* built) {
  const char* set = std::getenv(variable);
  return set && *set ? set : built;
}

// mpirun as root (CI runs as root) and with more ranks than cores; shared-memory transport
// without the kernel's cross-process copy, which containers often forbid.
inline void mpi_environment() {
  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  setenv("OMPI_MCA_btl_vader_single_copy_mechanism", "none", 1);
  setenv("OMPI_MCA_rmaps_base_oversubscribe", "1", 1);
}

struct Outcome {
  int exit_code = -1;
  std::string err;
};

// breccia-solve on `ranks` processes (1: without mpirun) and `threads` threads each.
inline Outcome solve(const std::string& case_file, const std::string& out, int ranks, int threads,
              const std::string& extra = "") {
  mpi_environment();
  const std::string log = out + ".stderr";
  std::ostringstream cmd;
  if (ranks > 1) cmd << executable("BRECCIA_MPIEXEC", BRECCIA_MPIEXEC) << " -np " << ranks << " ";
  cmd << executable("BRECCIA_SOLVE_EXE", BRECCIA_SOLVE_EXE) << " " << case_file << " -o " << out << " --threads " << threads << " --quiet " << extra
      << " > /dev/null 2> " << log;
  const int status = std::system(cmd.str().c_str());
  Outcome o;
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log);
  o.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return o;
}

// Every dataset of an HDF5 file as raw bytes of its stored type (strings as their text).
inline std::map<std::string, std::string> datasets(const std::string& path) {
  std::map<std::string, std::string> out;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return out;
  H5Ovisit(
      file, H5_INDEX_NAME, H5_ITER_INC,
      [](hid_t loc, const char* name, const H5O_info_t* info, void* data) -> herr_t {
        if (info->type != H5O_TYPE_DATASET) return 0;
        const hid_t d = H5Dopen(loc, name, H5P_DEFAULT);
        const hid_t type = H5Dget_type(d);
        const hid_t space = H5Dget_space(d);
        const hssize_t count = H5Sget_simple_extent_npoints(space);
        std::string bytes;
        if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) > 0) {
          std::vector<char*> strings(static_cast<size_t>(count));
          H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, strings.data());
          for (char* s : strings) bytes += std::string(s ? s : "") + '\n';
          H5Dvlen_reclaim(type, space, H5P_DEFAULT, strings.data());
        } else {
          bytes.resize(static_cast<size_t>(count) * H5Tget_size(type));
          H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data());
        }
        (*static_cast<std::map<std::string, std::string>*>(data))[name] = bytes;
        H5Sclose(space);
        H5Tclose(type);
        H5Dclose(d);
        return 0;
      },
      &out);
  H5Fclose(file);
  return out;
}

// The names of the datasets that differ (or exist in one file only). A file that cannot be
// read, or holds no dataset, is a difference of its own: two missing files do not compare equal.
inline std::vector<std::string> differing(const std::string& a, const std::string& b) {
  const auto da = datasets(a), db = datasets(b);
  std::vector<std::string> diff;
  for (const auto& [path, sets] : {std::pair{a, &da}, std::pair{b, &db}})
    if (sets->empty()) diff.push_back(path + ": no dataset read (missing or unreadable)");
  for (const auto& [name, bytes] : da) {
    const auto it = db.find(name);
    if (it == db.end() || it->second != bytes) diff.push_back(name);
  }
  for (const auto& [name, bytes] : db)
    if (!da.count(name)) diff.push_back(name + " (only in " + b + ")");
  return diff;
}

inline nlohmann::json summary(const std::string& dir) {
  std::ifstream in(dir + "/summary.json");
  return nlohmann::json::parse(in);
}

inline void expect_same_energies(const nlohmann::json& a, const nlohmann::json& b, const std::string& what) {
  for (const char* key : {"kinetic_J", "strain_J", "external_work_J", "dissipated_J"}) {
    const double x = a[key].get<double>(), y = b[key].get<double>();
    EXPECT_LE(std::fabs(x - y), 1e-12 * std::max(std::fabs(x), std::fabs(y))) << what << ": " << key << " " << x << " vs " << y;
  }
  EXPECT_EQ(a["broken_bonds"], b["broken_bonds"]) << what;
  EXPECT_EQ(a["max_damage"], b["max_damage"]) << what;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The last row's value of history.csv's column `name` (NaN when there is none).
inline double last_history_value(const std::string& dir, const std::string& name) {
  std::istringstream text(read_text(dir + "/history.csv"));
  std::string line, header, last;
  while (std::getline(text, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header.empty()) header = line;
    else last = line;
  }
  std::istringstream h(header), v(last);
  std::string column, value;
  while (std::getline(h, column, ',') && std::getline(v, value, ','))
    if (column == name) return std::stod(value);
  return std::nan("");
}

// history.csv of a run on ranks against one process's: the same rows and columns, every
// column's text equal except the energies (kinetic, strain, external work, dissipated and
// their balance), which the ranks add up in another order (Backend::measure's MPI_Allreduce):
// those agree to 1e-12 of the row's largest energy, the bound summary.json's energies meet
// too (expect_same_energies). Compared as text they agree only while the rounding happens
// to fall alike: the balance, a difference of terms ~5000 times larger, showed it.
inline void expect_same_history(const std::string& one_dir, const std::string& ranks_dir) {
  const auto rows = [](const std::string& dir) {
    std::vector<std::vector<std::string>> out;
    std::istringstream text(read_text(dir + "/history.csv"));
    for (std::string line; std::getline(text, line);) {
      std::vector<std::string> cells;
      std::istringstream l(line);
      for (std::string c; std::getline(l, c, ',');) cells.push_back(c);
      out.push_back(cells);
    }
    return out;
  };
  const auto a = rows(one_dir), b = rows(ranks_dir);
  ASSERT_FALSE(a.empty()) << one_dir << ": no history";
  ASSERT_EQ(a.size(), b.size()) << ranks_dir << ": history rows";
  ASSERT_EQ(a[0], b[0]) << ranks_dir << ": history columns";
  const std::vector<std::string> energies = {"kinetic_J", "strain_J", "external_work_J", "dissipated_J", "total_J"};
  for (size_t r = 1; r < a.size(); ++r) {
    ASSERT_EQ(a[r].size(), b[r].size()) << ranks_dir << ": history row " << r;
    double scale = 0.0;
    for (size_t c = 0; c < a[0].size(); ++c)
      if (std::find(energies.begin(), energies.end(), a[0][c]) != energies.end())
        scale = std::max({scale, std::fabs(std::stod(a[r][c])), std::fabs(std::stod(b[r][c]))});
    for (size_t c = 0; c < a[0].size(); ++c) {
      if (std::find(energies.begin(), energies.end(), a[0][c]) == energies.end()) {
        EXPECT_EQ(a[r][c], b[r][c]) << ranks_dir << ": history row " << r << ", " << a[0][c];
      } else {
        EXPECT_LE(std::fabs(std::stod(a[r][c]) - std::stod(b[r][c])), 1e-12 * scale)
            << ranks_dir << ": history row " << r << ", " << a[0][c] << " " << a[r][c] << " vs " << b[r][c];
      }
    }
  }
}

// A run on ranks (`out`) against one process's (`one`): results.h5 and checkpoint.h5 byte for
// byte, the history (expect_same_history) and summary.json's energies (expect_same_energies).
// checkpoint.h5 where either run wrote one (a relaxation writes none).
inline void expect_one_process_files(const std::string& one, const std::string& out) {
  for (const char* f : {"/results.h5", "/checkpoint.h5"}) {
    if (std::string(f) == "/checkpoint.h5" && !std::filesystem::exists(one + f) && !std::filesystem::exists(out + f)) continue;
    EXPECT_EQ(differing(one + f, out + f), std::vector<std::string>{}) << out << f;
  }
  expect_same_history(one, out);
  expect_same_energies(summary(one), summary(out), out);
}

}  // namespace breccia::solver::testing
