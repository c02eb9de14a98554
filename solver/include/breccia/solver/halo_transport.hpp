#pragma once
// The halo exchange of a distributed run (docs/parallel.md) split into what the execution
// space does (pack the owned values the peers read, unpack the ghosts' values) and what MPI
// does (the messages). The CPU's execution space packs in host memory; the CUDA backend packs
// on the device and hands the messages pinned host buffers, or device buffers where the MPI
// library is CUDA-aware (detected at run time). No MPI and no CUDA here: both backends and the
// MPI code include it.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace breccia::solver {

// One array a halo exchange carries: `bytes` per particle at `data` (local indices: the
// owned particles, then the ghosts).
struct HaloArray {
  void* data;
  size_t bytes;
};

// The arrays one exchange carries, in the order their bytes follow each other in an item.
struct HaloArrays {
  HaloArray item[3];
  int count = 0;
  size_t bytes_per_item() const {
    size_t per = 0;
    for (int k = 0; k < count; ++k) per += item[k].bytes;
    return per;
  }
};

// What a distributed run's ranks exchange (rank_system.hpp): each names the values its
// ghosts receive from their owners.
enum class HaloField : int {
  Displacement,    // u, before a force pass reads the partners' positions
  Lps,             // dilatation and the fast path's factors, between LPS's two passes
  Correspondence,  // the force tensor sigma K^-1 - G h F, between correspondence's passes
};

// The messages of a halo exchange, packed: item q of the send buffer holds the values of
// owned particle send_indices()[q] (every peer's list in turn, in the order the messages
// carry them); item g of the receive buffer is ghost g's (local index owned + g).
class HaloTransport {
public:
  virtual ~HaloTransport() = default;
  virtual const std::vector<int32_t>& send_indices() const = 0;
  virtual int64_t ghosts() const = 0;
  // Sends send_indices().size() items of `per` bytes from `send` and receives ghosts() items
  // into `recv`; returns when both are done. Device memory only where device_buffers().
  virtual void exchange_packed(const void* send, void* recv, size_t per) = 0;
  // Whether exchange_packed may be given device memory: the MPI library is CUDA-aware (asked
  // at run time: a build's headers may say so where the library loaded does not).
  virtual bool device_buffers() const = 0;
};

}  // namespace breccia::solver
