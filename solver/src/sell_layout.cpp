// SELL-C-sigma from a CSR (sell_layout.hpp).
#include "breccia/solver/sell_layout.hpp"

#include <algorithm>
#include <numeric>
#include <string>

namespace breccia::solver {

SellLayout build_sell_layout(const std::vector<int64_t>& offsets, int chunk, int sigma) {
  if (chunk < 1) throw std::invalid_argument("build_sell_layout: chunk " + std::to_string(chunk) + ", expected >= 1");
  if (sigma < 1 || (sigma != 1 && sigma % chunk != 0))
    throw std::invalid_argument("build_sell_layout: sigma " + std::to_string(sigma) +
                                ", expected 1 (no sorting) or a multiple of the chunk " + std::to_string(chunk));
  if (offsets.empty()) throw std::invalid_argument("build_sell_layout: offsets empty, expected n + 1 row offsets");
  const int64_t n = static_cast<int64_t>(offsets.size()) - 1;
  if (n > INT32_MAX) throw std::invalid_argument("build_sell_layout: more than 2^31 - 1 rows");
  for (int64_t i = 0; i < n; ++i)
    if (offsets[i + 1] < offsets[i])
      throw std::invalid_argument("build_sell_layout: offsets decrease at row " + std::to_string(i));
  SellLayout s;
  s.chunk = chunk;
  s.sigma = sigma;
  s.particles = n;
  s.slices = (n + chunk - 1) / chunk;
  auto length = [&](int64_t i) { return offsets[i + 1] - offsets[i]; };
  // The lanes' particles: each window of sigma sorted by row length, longest first; a stable
  // sort keeps equal rows in index order (a uniform lattice's interior stays as it was).
  std::vector<int32_t> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  if (sigma > 1)
    for (int64_t w = 0; w < n; w += sigma) {
      const auto first = order.begin() + w, last = order.begin() + std::min<int64_t>(n, w + sigma);
      std::stable_sort(first, last, [&](int32_t a, int32_t b) { return length(a) > length(b); });
    }
  s.particle.assign(static_cast<size_t>(s.lanes()), -1);
  s.row_length.assign(static_cast<size_t>(s.lanes()), 0);
  std::copy(order.begin(), order.end(), s.particle.begin());
  for (int64_t l = 0; l < n; ++l) s.row_length[l] = static_cast<int32_t>(length(s.particle[l]));
  s.slice_offset.assign(static_cast<size_t>(s.slices + 1), 0);
  for (int64_t c = 0; c < s.slices; ++c) {
    int64_t width = 0;
    for (int64_t l = c * chunk; l < (c + 1) * chunk; ++l) width = std::max<int64_t>(width, s.row_length[l]);
    s.slice_offset[c + 1] = s.slice_offset[c] + width * chunk;
  }
  s.csr_entry.assign(static_cast<size_t>(s.padded_entries()), -1);
  for (int64_t l = 0; l < n; ++l) {
    const int64_t begin = offsets[s.particle[l]];
    for (int64_t k = 0; k < s.row_length[l]; ++k) s.csr_entry[s.view(nullptr).entry(l, k)] = begin + k;
  }
  return s;
}

double SellLayout::padding_factor() const {
  int64_t real = 0;
  for (int32_t r : row_length) real += r;
  return real > 0 ? double(padded_entries()) / double(real) : 1.0;
}

}  // namespace breccia::solver
