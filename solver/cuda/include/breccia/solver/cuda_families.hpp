#pragma once
// The bond families built on the GPU (cuda_families.cu): build_families' arguments and result,
// bit for bit, for the CUDA backend's set-up (SetupHooks::families, breccia-solve --backend
// cuda). Plain C++, so the CLI can include it without nvcc.
#include <cstdint>
#include <span>

#include "breccia/common/families.hpp"

namespace breccia::solver {

// On the device in use (cuda_device_in_use); where there is none or a CUDA call fails, on the
// host (build_families), with a one-line note on stderr when `notes`.
Families cuda_build_families(std::span<const double> position, std::span<const double> horizon_m,
                             std::span<const double> pad_m, int64_t row_begin, int64_t row_end, bool notes);

}  // namespace breccia::solver
