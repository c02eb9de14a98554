#pragma once
// Neighbour (bond) lists for MPS: built once on the reference configuration with a cell
// list (O(N)), stored as CSR with the reference bond vector and weight of each bond.
#include <array>
#include <functional>
#include <vector>

#include "breccia/mps/kernels.hpp"

namespace breccia::mps {

// Periodic directions of a lattice (box length in m; 0 = not periodic).
struct Periodicity {
  std::array<double, 3> period_m{0.0, 0.0, 0.0};
  bool any() const { return period_m[0] > 0 || period_m[1] > 0 || period_m[2] > 0; }
};

struct BondList {
  int dimension = 2;
  double radius_re_m = 0.0;
  std::vector<long long> offset;  // N + 1
  std::vector<int> neighbour;
  std::vector<double> rx, ry, rz, weight;

  size_t particles() const { return offset.empty() ? 0 : offset.size() - 1; }
  size_t size() const { return neighbour.size(); }
  BondsView view() const {
    return {offset.data(), neighbour.data(), rx.data(), ry.data(), rz.data(), weight.data()};
  }
};

// All pairs closer than radius_re (minimum image in periodic directions). positions: 3N.
BondList build_bonds(int dimension, const std::vector<double>& position_m, double radius_re_m,
                     const Periodicity& periodic = {});

// Drop bonds for which cut(i, j, k) is true (k: bond index); keeps the list symmetric when
// cut is symmetric in i, j.
void remove_bonds(BondList& bonds, const std::function<bool(long long i, long long j, long long k)>& cut);

// n0 and lambda from the particle with the fullest neighbourhood (an interior particle of a
// regular lattice): n0 = sum_j w_ij, lambda = sum_j w_ij |r_ij|^2 / sum_j w_ij.
struct Normalisation {
  double number_density_n0 = 0.0;
  double laplacian_lambda_m2 = 0.0;
  OperatorScales scales(int dimension) const {
    return {dimension / number_density_n0, 2.0 * dimension / (laplacian_lambda_m2 * number_density_n0)};
  }
};
Normalisation reference_normalisation(const BondList& bonds);

}  // namespace breccia::mps
