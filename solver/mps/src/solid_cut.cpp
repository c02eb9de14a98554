#include "breccia/mps/solid.hpp"

namespace breccia::mps {

// A pre-cut crack (tests, set-up): the same bond state as a fractured one, so crack faces
// made either way meet through particle contact (contact.cpp skips only bonds with
// nonzero weight).
long long Solid::cut_bonds(const std::function<bool(long long i, long long j)>& cut) {
  const long long n = static_cast<long long>(size());
  std::vector<long long> changed;
  long long count = 0;
  for (long long i = 0; i < n; ++i) {
    bool lost = false;
    for (long long k = bonds_.offset[i]; k < bonds_.offset[i + 1]; ++k) {
      const long long j = bonds_.neighbour[k];
      if (bonds_.weight[k] == 0.0 || !(i < j ? cut(i, j) : cut(j, i))) continue;
      bonds_.weight[k] = 0.0;
      lost = true;
      count += i < j;
    }
    if (lost) changed.push_back(i);
  }
  refresh_cut_stencils(changed);
  return count;
}

}  // namespace breccia::mps
