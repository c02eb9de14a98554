#include "breccia/mps/fracture.hpp"

#include <algorithm>
#include <numeric>

#include "breccia/common/union_find.hpp"

namespace breccia::mps {

// Below this many particles thread start-up costs more than the loop (as in solid.cpp).
constexpr long long kFractureParallelMin = 8192;

namespace {

// Cuts bond k, from a to b, in both directions: its weight and that of b's bond back to a set to 0.
void cut_both_ways(BondList& bonds, long long k, long long a, long long b) {
  bonds.weight[k] = 0.0;
  for (long long m = bonds.offset[b]; m < bonds.offset[b + 1]; ++m)
    if (bonds.neighbour[m] == a) bonds.weight[m] = 0.0;
}

}  // namespace

FractureModel::FractureModel(const FractureLaw& law, const BondList& bonds, double spacing_m)
    : law_(law), cut_radius_m_(0.5 * spacing_m) {
  const size_t n = bonds.particles();
  initial_bonds_.assign(n, 0);
  for (size_t i = 0; i < n; ++i)
    for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k) initial_bonds_[i] += bonds.weight[k] > 0.0;
  tensile_.assign(n, Mat3{});
  compressive_.assign(n, Mat3{});
  tensile_nonzero_.assign(n, 0);
  inverted_.assign(n, 0);
  separation_pa_.assign(n, 0.0);
  first_failure_time_s_.assign(n, -1.0);
  normal_.assign(n, {0.0, 0.0, 0.0});
  first_normal_.assign(n, {0.0, 0.0, 0.0});
  failures_.assign(n, 0);
}

void FractureModel::evaluate(const BondList& bonds, const State& s) {
  const long long n = static_cast<long long>(bonds.particles());
  SeparationInputs in;
  in.bonds = bonds.view();
  in.volume_m3 = s.volume_m3;
  in.tensile = tensile_.data();
  in.compressive = compressive_.data();
  in.matrices = s.matrices;
  in.dimension = s.dimension;
  in.tensile_nonzero = tensile_nonzero_.data();
#pragma omp parallel for schedule(static) if (n > kFractureParallelMin)
  for (long long i = 0; i < n; ++i)
    separation_parts_at(i, s.stress, s.matrices, s.dimension, tensile_.data(), compressive_.data(),
                        tensile_nonzero_.data());
#pragma omp parallel for schedule(static) if (n > kFractureParallelMin)
  for (long long i = 0; i < n; ++i) {
    const Separation sep = separation_at(i, in);
    separation_pa_[i] = sep.stress_pa;
    normal_[i] = {sep.normal[0], sep.normal[1], sep.normal[2]};
  }
}

std::vector<long long> FractureModel::fail_and_cut(BondList& bonds, const State& s) {
  const long long n = static_cast<long long>(bonds.particles());
  evaluate(bonds, s);
  std::vector<long long> candidates;
  for (long long i = 0; i < n; ++i)
    if (separation_pa_[i] >= law_.tensile_strength_pa) candidates.push_back(i);
  std::vector<long long> touched;
  if (candidates.empty()) return touched;
  std::stable_sort(candidates.begin(), candidates.end(),
                   [&](long long a, long long b) { return separation_pa_[a] > separation_pa_[b]; });
  std::vector<char> failed_now(n, 0);
  for (long long i : candidates) {
    bool near_new_crack = failed_now[i];
    for (long long k = bonds.offset[i]; k < bonds.offset[i + 1] && !near_new_crack; ++k)
      near_new_crack = failed_now[bonds.neighbour[k]];
    if (near_new_crack) continue;
    failed_now[i] = 1;
    double normal[3] = {normal_[i][0], normal_[i][1], normal_[i][2]};
    // n and -n are the same plane; fix the sign so that the side particle i joins does not
    // depend on the eigen-solver's sign.
    if (normal[0] + 1e-3 * normal[1] + 1e-6 * normal[2] < 0.0)
      for (double& c : normal) c = -c;
    if (failures_[i] == 0) {
      first_failure_time_s_[i] = s.time_s;
      first_normal_[i] = {normal[0], normal[1], normal[2]};
    }
    ++failures_[i];
    cut_plane(bonds, s, i, normal, touched);
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  return touched;
}

// Cut every intact bond a-b of i's neighbourhood whose current segment crosses the plane
// through x_i with normal n within cut_radius of x_i (see the header).
void FractureModel::cut_plane(BondList& bonds, const State& s, long long i, const double n[3],
                              std::vector<long long>& touched) {
  const VectorField& u = s.displacement;
  auto moved = [&](long long k, long long from, long long to, int axis) {  // current bond vector
    const double r[3] = {bonds.rx[k], bonds.ry[k], bonds.rz[k]};
    const double* field = axis == 0 ? u.x : axis == 1 ? u.y : u.z;
    return r[axis] + field[to] - field[from];
  };
  // Members: i itself (offset 0) and its reference neighbours (current offset from x_i).
  std::vector<std::pair<long long, std::array<double, 3>>> members{{i, {0.0, 0.0, 0.0}}};
  for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k) {
    const long long a = bonds.neighbour[k];
    members.push_back({a, {moved(k, i, a, 0), moved(k, i, a, 1), moved(k, i, a, 2)}});
  }
  for (const auto& [a, xa] : members) {
    const double da = xa[0] * n[0] + xa[1] * n[1] + xa[2] * n[2];
    for (long long k = bonds.offset[a]; k < bonds.offset[a + 1]; ++k) {
      if (bonds.weight[k] == 0.0) continue;
      const long long b = bonds.neighbour[k];
      const double xb[3] = {xa[0] + moved(k, a, b, 0), xa[1] + moved(k, a, b, 1), xa[2] + moved(k, a, b, 2)};
      const double db = xb[0] * n[0] + xb[1] * n[1] + xb[2] * n[2];
      if ((da > 0.0) == (db > 0.0)) continue;
      const double t = da / (da - db);
      double dist2 = 0.0;
      for (int p = 0; p < 3; ++p) dist2 += std::pow(xa[p] + t * (xb[p] - xa[p]), 2);
      if (dist2 > cut_radius_m_ * cut_radius_m_ * (1.0 + 1e-9)) continue;
      cut_both_ways(bonds, k, a, b);
      ++cut_bonds_;
      touched.push_back(a);
      touched.push_back(b);
    }
  }
}

bool FractureModel::absorb_inversion(long long i, const BondList& bonds) {
  int intact = 0;
  for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k) intact += bonds.weight[k] > 0.0;
  if (intact == initial_bonds_[i]) return false;
  if (!inverted_[i]) {  // called for distinct particles by the threads of one loop
    inverted_[i] = 1;
#pragma omp atomic
    ++flagged_;
  }
  return true;
}

bool FractureModel::absorb_remnant(long long i, const BondList& bonds, const double* volume_m3, int dimension) {
  int intact = 0;
  for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k) intact += bonds.weight[k] > 0.0;
  if (intact == 0 || intact == initial_bonds_[i] || inverted_[i]) return false;
  const double conditioning = stencil_conditioning(i, bonds.view(), volume_m3, dimension);
  if (!(conditioning < kRemnantConditioning && conditioning >= kCollinearStencil)) return false;
  inverted_[i] = 1;
  ++flagged_;
  ++remnants_;
  return true;
}

std::vector<long long> FractureModel::detach_flagged(BondList& bonds) {
  std::vector<long long> touched;
  const long long n = static_cast<long long>(bonds.particles());
  for (long long i = 0; i < n; ++i) {
    if (!inverted_[i]) continue;
    inverted_[i] = 0;
    --flagged_;
    ++detached_;
    for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k) {
      if (bonds.weight[k] == 0.0) continue;
      const long long j = bonds.neighbour[k];
      cut_both_ways(bonds, k, i, j);
      ++cut_bonds_;
      touched.push_back(j);
    }
    touched.push_back(i);
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  return touched;
}

std::vector<double> FractureModel::damage(const BondList& bonds) const {
  const size_t n = bonds.particles();
  std::vector<double> d(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    if (initial_bonds_[i] == 0) continue;
    int intact = 0;
    for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k) intact += bonds.weight[k] > 0.0;
    d[i] = 1.0 - static_cast<double>(intact) / initial_bonds_[i];
  }
  return d;
}

std::vector<int> FractureModel::fragment_labels(const BondList& bonds) {
  const size_t n = bonds.particles();
  UnionFind uf(n);
  for (size_t i = 0; i < n; ++i)
    for (long long k = bonds.offset[i]; k < bonds.offset[i + 1]; ++k)
      if (bonds.weight[k] > 0.0) uf.unite(static_cast<int32_t>(i), bonds.neighbour[k]);
  // Pieces numbered largest first; equal sizes in the order of their first particle.
  int32_t count = 0;
  const std::vector<int32_t> piece = uf.labels(&count);
  std::vector<size_t> size(static_cast<size_t>(count), 0);
  for (int32_t p : piece) ++size[static_cast<size_t>(p)];
  std::vector<int> by_size(static_cast<size_t>(count));
  std::iota(by_size.begin(), by_size.end(), 0);
  std::stable_sort(by_size.begin(), by_size.end(), [&](int a, int b) { return size[a] > size[b]; });
  std::vector<int> label_of_piece(static_cast<size_t>(count)), labels(n);
  for (size_t r = 0; r < by_size.size(); ++r) label_of_piece[static_cast<size_t>(by_size[r])] = static_cast<int>(r);
  for (size_t i = 0; i < n; ++i) labels[i] = label_of_piece[static_cast<size_t>(piece[i])];
  return labels;
}

int FractureModel::fragment_count(const std::vector<int>& labels, int min_particles) {
  std::vector<int> size;
  for (int l : labels) {
    if (l >= static_cast<int>(size.size())) size.resize(l + 1, 0);
    ++size[l];
  }
  return static_cast<int>(std::count_if(size.begin(), size.end(), [&](int s) { return s >= min_particles; }));
}

long long FractureModel::failed_particles() const {
  return std::count_if(failures_.begin(), failures_.end(), [](int f) { return f > 0; });
}

double FractureModel::max_separation_pa() const {
  return separation_pa_.empty() ? 0.0 : *std::max_element(separation_pa_.begin(), separation_pa_.end());
}

}  // namespace breccia::mps
