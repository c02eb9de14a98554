// The bond families built on the GPU at set-up (docs/cuda.md): family_build.hpp's driver with
// its kernels (family_kernels.hpp) launched by cuda::for_each, the step's launch, on device
// copies of the positions, horizons and pads; the offsets and partners come back to the host,
// whose set-up goes on from them. The same arrays as build_families', bit for bit: the
// kernels are independent of launch order (tests/solver/test_family_build.cpp) and their
// arithmetic rounds as the host's (--fmad=false, CMakeLists.txt).
#include <cuda_runtime.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/common/family_build.hpp"
#include "breccia/common/huge_pages.hpp"
#include "breccia/solver/cuda_backend.hpp"
#include "breccia/solver/cuda_families.hpp"
#include "breccia/solver/cuda_launch.cuh"
#include "breccia/solver/cuda_memory.cuh"

namespace breccia::solver {
namespace {

// family_build.hpp's execution space on the device.
struct CudaFamilyExec {
  bool synchronize = false;  // BRECCIA_CUDA_SYNC=1: attribute asynchronous faults to their kernel
  template <class F>
  void for_each(int64_t n, const F& f, const char* name) const {
    cuda::for_each(n, f, name, synchronize);
  }
};

// family_build.hpp's arrays on the device (freed with this object); the output copied into
// the Families by finish.
class CudaFamilyMemory {
public:
  template <class T>
  T* make(size_t count) {
    arrays_.push_back(std::make_unique<cuda::DeviceArray<char>>());
    arrays_.back()->allocate(count * sizeof(T), "families: device array");
    return reinterpret_cast<T*>(arrays_.back()->get());
  }
  template <class T>
  const T* input(std::span<const T> data) {
    T* at = make<T>(data.size());
    if (!data.empty())
      cuda::check(cudaMemcpy(at, data.data(), data.size_bytes(), cudaMemcpyHostToDevice), "families: upload");
    return at;
  }
  int64_t read(const int64_t* at) const {
    int64_t value = 0;
    cuda::check(cudaMemcpy(&value, at, sizeof(value), cudaMemcpyDeviceToHost), "families: entry count");
    return value;
  }
  int64_t* offsets(Families&, size_t count) {
    offset_count_ = count;
    return offsets_ = make<int64_t>(count);
  }
  int32_t* neighbors(Families&, size_t count) {
    neighbor_count_ = count;
    return neighbors_ = make<int32_t>(count);
  }
  // cudaMemcpy waits for the kernels before it copies.
  void finish(Families& fam) {
    fam.offsets.assign(offset_count_, 0);
    if (offset_count_ > 0)
      cuda::check(cudaMemcpy(fam.offsets.data(), offsets_, offset_count_ * sizeof(int64_t), cudaMemcpyDeviceToHost),
                  "families: download of the offsets");
    assign_on_huge_pages(fam.neighbors, neighbor_count_);
    if (neighbor_count_ > 0)
      cuda::check(cudaMemcpy(fam.neighbors.data(), neighbors_, neighbor_count_ * sizeof(int32_t), cudaMemcpyDeviceToHost),
                  "families: download of the partners");
  }

private:
  std::vector<std::unique_ptr<cuda::DeviceArray<char>>> arrays_;
  int64_t* offsets_ = nullptr;
  int32_t* neighbors_ = nullptr;
  size_t offset_count_ = 0, neighbor_count_ = 0;
};

}  // namespace

Families cuda_build_families(std::span<const double> position, std::span<const double> horizon_m,
                             std::span<const double> pad_m, int64_t row_begin, int64_t row_end, bool notes) {
  std::string why;
  if (!cuda_device_available()) {
    why = "no CUDA device is available";
  } else {
    try {
      cuda::check(cudaSetDevice(cuda_device_in_use()), "cudaSetDevice");
      const char* sync = std::getenv("BRECCIA_CUDA_SYNC");
      const CudaFamilyExec exec{sync && std::string(sync) == "1"};
      CudaFamilyMemory mem;
      return build_families_with(exec, mem, position, horizon_m, pad_m, row_begin, row_end);
    } catch (const RunError& e) {  // a CUDA call failed (out of memory, a launch): the host builds them
      why = e.what();
    }
  }
  if (notes) std::fprintf(stderr, "note: bond families built on the host (the device path is unavailable: %s)\n", why.c_str());
  return build_families(position, horizon_m, pad_m, row_begin, row_end);
}

}  // namespace breccia::solver
