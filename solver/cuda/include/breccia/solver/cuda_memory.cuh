#pragma once
// Device memory and error checks shared by the CUDA launchers (cuda_backend.cu for PD,
// mps_cuda.cu for MPS). Only .cu files include this: it needs cuda_runtime.h.
#include <cuda_runtime.h>

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "breccia/common/error.hpp"

namespace breccia::cuda {

inline void check(cudaError_t status, const std::string& what) {
  if (status != cudaSuccess)
    throw RunError("CUDA backend: " + what + " failed: " + cudaGetErrorName(status) + " (" +
                   cudaGetErrorString(status) + ")");
}

// Every launch is followed by this: the error state is checked with the kernel's name.
// synchronize (BRECCIA_CUDA_SYNC=1) attributes an asynchronous fault to the kernel causing it.
inline void check_launch(const char* kernel, bool synchronize) {
  check(cudaGetLastError(), std::string("launch of ") + kernel);
  if (synchronize) check(cudaDeviceSynchronize(), std::string("kernel ") + kernel);
}

// One cudaMalloc'd array; nullptr when empty, as the kernels' views expect for absent arrays.
template <class T>
class DeviceArray {
public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  DeviceArray(DeviceArray&& other) noexcept : ptr_(other.ptr_), count_(other.count_) {
    other.ptr_ = nullptr;
    other.count_ = 0;
  }
  ~DeviceArray() {
    if (ptr_) cudaFree(ptr_);
  }
  void swap(DeviceArray& other) noexcept {
    std::swap(ptr_, other.ptr_);
    std::swap(count_, other.count_);
  }
  void allocate(size_t count, const char* name) {  // replaces any earlier allocation
    if (ptr_) cudaFree(ptr_);
    ptr_ = nullptr;
    count_ = count;
    if (count == 0) return;
    check(cudaMalloc(&ptr_, count * sizeof(T)), std::string("cudaMalloc of ") + name);
  }
  template <class A>
  void upload(const std::vector<T, A>& host, const char* name) {
    allocate(host.size(), name);
    if (count_ == 0) return;
    check(cudaMemcpy(ptr_, host.data(), count_ * sizeof(T), cudaMemcpyHostToDevice),
          std::string("upload of ") + name);
  }
  // Into the present allocation (its device pointer stays valid in the views that hold it).
  template <class A>
  void copy_in(const std::vector<T, A>& host, const char* name) {
    if (host.size() != count_)
      throw std::runtime_error(std::string("copy of ") + name + ": size differs from the device array's");
    if (count_ == 0) return;
    check(cudaMemcpy(ptr_, host.data(), count_ * sizeof(T), cudaMemcpyHostToDevice), std::string("copy of ") + name);
  }
  template <class A>
  void download(std::vector<T, A>& host, const char* name) const {
    if (count_ == 0) return;
    host.resize(count_);
    check(cudaMemcpy(host.data(), ptr_, count_ * sizeof(T), cudaMemcpyDeviceToHost),
          std::string("download of ") + name);
  }
  T* get() const { return ptr_; }
  size_t size() const { return count_; }

private:
  T* ptr_ = nullptr;
  size_t count_ = 0;
};

// Page-locked host memory (cudaMallocHost): a copy to or from it runs at the link's full rate
// and needs no staging copy by the driver (the halo of a distributed run: cuda_backend.cu).
// Grows on demand and keeps its allocation between uses.
class PinnedBuffer {
public:
  PinnedBuffer() = default;
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;
  ~PinnedBuffer() {
    if (ptr_) cudaFreeHost(ptr_);
  }
  void* reserve(size_t bytes, const char* name) {
    if (bytes > bytes_) {
      if (ptr_) cudaFreeHost(ptr_);
      ptr_ = nullptr;
      bytes_ = 0;
      check(cudaMallocHost(&ptr_, bytes), std::string("cudaMallocHost of ") + name);
      bytes_ = bytes;
    }
    return ptr_;
  }

private:
  void* ptr_ = nullptr;
  size_t bytes_ = 0;
};

}  // namespace breccia::cuda
