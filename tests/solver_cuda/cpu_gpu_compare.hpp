#pragma once
// What the CPU/GPU comparisons of the PD and MPS launchers share: a field difference and
// history.csv as numbers.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace breccia::cuda_test {

// max_k |a_k - b_k| / max_k |b_k|: relative to the field's scale, since single components
// pass through zero.
inline double field_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double diff = 0.0, scale = 0.0;
  for (size_t k = 0; k < b.size(); ++k) {
    diff = std::max(diff, std::fabs(a[k] - b[k]));
    scale = std::max(scale, std::fabs(b[k]));
  }
  return scale > 0 ? diff / scale : diff;
}

// Every row after the header, each cell as a double.
inline std::vector<std::vector<double>> read_history_rows(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<double>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace breccia::cuda_test
