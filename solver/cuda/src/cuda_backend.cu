// The CUDA backend: one thread per particle runs the kernel bodies of pd_kernels.hpp (and of
// load_kernels.hpp for loads and constraints) on device copies of a PdSystem's arrays
// (docs/cuda.md). No physics is written here, only launches, data movement and reductions.
// With FMA contraction off (CMakeLists.txt) each particle's arithmetic rounds as on the CPU.
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <string>
#include <type_traits>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/solver/cuda_backend.hpp"
#include "breccia/solver/correspondence.hpp"
#include "breccia/solver/correspondence_kernels.hpp"
#include "breccia/solver/cuda_kernel_clock.cuh"
#include "breccia/solver/cuda_launch.cuh"
#include "breccia/solver/cuda_memory.cuh"
#include "breccia/solver/float32_state.hpp"
#include "breccia/solver/load_kernels.hpp"
#include "breccia/solver/pd_kernels.hpp"
#include "breccia/solver/sell_layout.hpp"
#include "breccia/solver/step.hpp"

namespace breccia::solver {
namespace {

constexpr int kBlock = 256;
constexpr int kMaxReduceBlocks = 1024;  // partial sums per reduction: fixed, so results are reproducible
// model.cuda_layout: sell: a slice is a warp; rows sorted by length within 32 slices (docs/cuda.md).
constexpr int kSellChunk = 32;
constexpr int kSellSigma = 1024;
constexpr int kSampleFractions = partial_volume_sample_total(3) + 1;  // the host table's length (pd_physics.hpp)

using cuda::check;
using cuda::check_launch;
using cuda::DeviceArray;

int64_t blocks_for(int64_t n) { return (n + kBlock - 1) / kBlock; }

// ---------------------------------------------------------------------------------------
// Kernels: each is a launcher around BRECCIA_HD bodies; the only arithmetic of their own is
// the work-of-loads bookkeeping of cpu_step.

__device__ int64_t thread_index() { return static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x; }

// ---------------------------------------------------------------------------------------
// Reductions: grid-stride partial sums into at most kMaxReduceBlocks values, then one block
// folds them. The grid is fixed, so a run's sums are reproducible from run to run.

template <class Load>
__global__ void reduce_partial_cuda(int64_t n, Load load, typename Load::Value* partial) {
  using Value = typename Load::Value;
  __shared__ Value shared[kBlock];
  Value acc = Load::identity();
  for (int64_t k = thread_index(); k < n; k += static_cast<int64_t>(gridDim.x) * blockDim.x)
    acc = Load::combine(acc, load(k));
  shared[threadIdx.x] = acc;
  __syncthreads();
  for (int half = kBlock / 2; half > 0; half /= 2) {
    if (threadIdx.x < half) shared[threadIdx.x] = Load::combine(shared[threadIdx.x], shared[threadIdx.x + half]);
    __syncthreads();
  }
  if (threadIdx.x == 0) partial[blockIdx.x] = shared[0];
}

template <class Load, class Finish>
__global__ void reduce_final_cuda(int count, const typename Load::Value* partial, Finish finish) {
  using Value = typename Load::Value;
  __shared__ Value shared[kBlock];
  Value acc = Load::identity();
  for (int k = threadIdx.x; k < count; k += blockDim.x) acc = Load::combine(acc, partial[k]);
  shared[threadIdx.x] = acc;
  __syncthreads();
  for (int half = kBlock / 2; half > 0; half /= 2) {
    if (threadIdx.x < half) shared[threadIdx.x] = Load::combine(shared[threadIdx.x], shared[threadIdx.x + half]);
    __syncthreads();
  }
  if (threadIdx.x == 0) finish(shared[0]);
}

// Plain aggregates (no member initialisers): they live in __shared__ arrays (StepSums too,
// step.hpp).
struct MeasureSums {
  double kinetic, strain, max_damage;
  long long broken_half_bonds;
  long long bad_particle;  // largest index with a non-finite u or v; -1 if none
};

// Scalars that live on the device across steps (the host mirror is refreshed on demand).
struct DeviceScalars {
  double external_work;
  double dissipated_energy;
  MeasureSums measured;
};

struct MeasureLoad {
  using Value = MeasureSums;
  PdView p;
  __device__ static Value identity() { return {0.0, 0.0, 0.0, 0, -1}; }
  __device__ static Value combine(Value a, Value b) {
    return {a.kinetic + b.kinetic, a.strain + b.strain, a.max_damage > b.max_damage ? a.max_damage : b.max_damage,
            a.broken_half_bonds + b.broken_half_bonds, a.bad_particle > b.bad_particle ? a.bad_particle : b.bad_particle};
  }
  __device__ Value operator()(int64_t i) const {
    double v2 = 0.0;
    bool finite = true;
    for (int d = 0; d < 3; ++d) {
      v2 += p.v[3 * i + d] * p.v[3 * i + d];
      finite = finite && isfinite(p.u[3 * i + d]) && isfinite(p.v[3 * i + d]);
    }
    long long broken = 0;
    for (int64_t k = p.offsets[i]; k < p.offsets[i + 1]; ++k) broken += entry_broken(p, k);
    return {0.5 * p.density[i] * p.volume[i] * v2, p.volume[i] * p.energy_density[i], p.damage[i], broken,
            finite ? -1 : static_cast<long long>(i)};
  }
};

struct MeasureFinish {
  DeviceScalars* scalars;
  __device__ void operator()(MeasureSums s) const { scalars->measured = s; }
};

// A distributed run's halo on the device (halo_transport.hpp): one array's `bytes` per item
// gathered from the owned particles the peers read into its place in the packed items, and
// back from the received items into the ghosts. One thread per byte: any element size and
// alignment, for the few thousand ghosts of a rank's surface.
struct PackHalo {
  const char* from;
  size_t bytes;
  const int32_t* index;  // the send list (local indices of owned particles)
  char* to;
  size_t per, offset;  // item size and this array's place in an item
  __device__ void operator()(int64_t k) const {
    const int64_t q = k / static_cast<int64_t>(bytes), b = k % static_cast<int64_t>(bytes);
    to[q * per + offset + b] = from[static_cast<int64_t>(index[q]) * bytes + b];
  }
};

struct UnpackHalo {
  const char* from;
  size_t per, offset;
  char* to;
  size_t bytes;
  int64_t owned;  // ghost g is local index owned + g
  __device__ void operator()(int64_t k) const {
    const int64_t g = k / static_cast<int64_t>(bytes), b = k % static_cast<int64_t>(bytes);
    to[(owned + g) * static_cast<int64_t>(bytes) + b] = from[g * per + offset + b];
  }
};

int g_device = 0;  // the device CudaSystems use (cuda_use_device)

// The arrays the kernels stream, in one precision: PdSystem's (double) or its Float32State's
// (float), which hold them under the same names and rules. Uploaded and pointed at alike.
template <class Real>
struct StreamedArrays {
  DeviceArray<Real> x0, u, v, a, force, body, volume, density, weighted_volume, dilatation, lps_a, lps_b;
  DeviceArray<Real> xi_len, k_own, k_dual, vol_own, short_range_k, spacing;
  DeviceArray<Real> u_before;  // step scratch (3n)

  // `held`: the particles held (the n stepped, then a distributed run's ghosts); `label`: the
  // arrays' names' prefix in messages ("" or "float ").
  template <class State>
  void upload(const State& s, size_t n, size_t held, const std::string& label) {
    auto name = [&](const char* what) { return label + what; };
    x0.upload(s.x0, name("x0").c_str());
    u.upload(s.u, name("u").c_str());
    v.upload(s.v, name("v").c_str());
    a.upload(s.a, name("a").c_str());
    force.upload(s.force, name("force").c_str());
    body.upload(s.body, name("body").c_str());
    volume.upload(s.volume, name("volume").c_str());
    density.upload(s.density, name("density").c_str());
    weighted_volume.upload(s.weighted_volume, name("weighted_volume").c_str());
    dilatation.upload(s.dilatation, name("dilatation").c_str());
    // The fast LPS path's per-particle factors exist only where set-up allocated them.
    if (s.lps_a.size() == held && s.lps_b.size() == held) {
      lps_a.upload(s.lps_a, name("lps_a").c_str());
      lps_b.upload(s.lps_b, name("lps_b").c_str());
    }
    xi_len.upload(s.xi_len, name("xi_len").c_str());
    k_own.upload(s.k_own, name("k_own").c_str());
    // k_dual: empty where the dual halves are shared (pd_system.hpp): none on the device;
    // vol_own: empty where the own counts serve
    k_dual.upload(s.k_dual, name("k_dual").c_str());
    vol_own.upload(s.vol_own, name("vol_own").c_str());
    if (!s.short_range_k.empty()) {
      short_range_k.upload(s.short_range_k, name("short_range_k").c_str());
      spacing.upload(s.spacing, name("spacing").c_str());
    }
    u_before.allocate(3 * n, name("u_before").c_str());
  }

  // The view's fields of these arrays: the own halves serve as the dual ones where they are
  // shared; vol_own is null where the own counts serve (`counted`, pd_kernels.hpp own_volume).
  void point(PdViewT<Real>& p, bool dual_shared, bool counted) const {
    p.x0 = x0.get(); p.u = u.get(); p.v = v.get(); p.a = a.get(); p.force = force.get(); p.body = body.get();
    p.volume = volume.get(); p.density = density.get(); p.xi_len = xi_len.get();
    p.k_own = k_own.get(); p.k_dual = dual_shared ? p.k_own : k_dual.get();
    p.vol_own = counted ? nullptr : vol_own.get();
    p.short_range_k = short_range_k.get(); p.spacing = spacing.get();
    p.weighted_volume = weighted_volume.get(); p.dilatation = dilatation.get();
    p.lps_a = lps_a.get(); p.lps_b = lps_b.get();
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------

bool cuda_device_available() {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess) {
    cudaGetLastError();  // no driver / no device: clear the error, answer no
    return false;
  }
  return count > 0;
}

std::string cuda_device_description() {
  if (!cuda_device_available()) return "";
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, g_device) != cudaSuccess) return "";
  char text[512];
  std::snprintf(text, sizeof text, "%s, %.1f GiB, compute capability %d.%d", prop.name,
                prop.totalGlobalMem / 1073741824.0, prop.major, prop.minor);
  return text;
}

int cuda_use_device(int index) {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess || count == 0) {
    cudaGetLastError();
    return -1;
  }
  g_device = (index % count + count) % count;
  return g_device;
}

int cuda_device_in_use() { return g_device; }

struct CudaSystem::Impl {
  // the arrays the kernels stream (double; float below)
  StreamedArrays<double> doubles;
  // per particle
  DeviceArray<double> x;
  DeviceArray<uint8_t> fixed_dof;
  DeviceArray<double> energy_density, dissipated, damage, max_stretch;
  DeviceArray<LpsCoefficients> lps;
  // bonds
  DeviceArray<int64_t> offsets;
  DeviceArray<int32_t> neighbor;
  DeviceArray<float> s0_own, s0_dual;
  DeviceArray<uint8_t> state;
  DeviceArray<uint8_t> own_count;  // the own halves' sample counts, where vol_own is not held (pd_system.hpp)
  DeviceArray<double> sample_fraction;  // their fractions (pd_physics.hpp partial_volume_sample_fractions)
  DeviceArray<double> family_volume, ffamily_volume;  // per particle, the damage's denominator (pd_system.hpp)
  // compressive enhancement: s_min read and written by a pass (swapped at each step's start,
  // commit_min_stretch)
  DeviceArray<float> min_stretch, min_stretch_next;
  DeviceArray<float> s_onset, bond_damage;  // softening bonds (pd_kernels.hpp)
  // model.cuda_layout: sell (sell_layout.hpp): the layout and, in its order, the per-entry
  // arrays of its passes (double and float copies of the lengths and moduli; the dual halves
  // and the damage weights with variable horizons only, whose diagnostic passes it carries)
  DeviceArray<int64_t> sell_slice_offset, sell_csr_entry;
  DeviceArray<int32_t> sell_particle, sell_row_length, sell_neighbor;
  DeviceArray<double> sell_xi_len, sell_k_own, sell_k_dual, sell_vol_own;
  DeviceArray<float> sell_fxi_len, sell_fk_own, sell_fk_dual, sell_fvol_own, sell_s0_own, sell_s0_dual;
  DeviceArray<uint8_t> sell_state, sell_own_count;
  // step scratch (u_before: the streamed arrays')
  DeviceArray<double> f_before;
  // loads and constraints (index lists uploaded once)
  DeviceArray<int32_t> facet_particle, facet_load;
  DeviceArray<int64_t> facet_offsets;
  DeviceArray<double> facet_area, facet_normal, load_vector;
  DeviceArray<uint8_t> load_is_pressure;
  std::vector<DeviceArray<int32_t>> body_load_particles;   // one per sys.body_loads entry
  std::vector<DeviceArray<int32_t>> constraint_particles;  // one per sys.constraints entry
  std::vector<DeviceArray<double>> constraint_values;      // per entry: a field's values (boundary_field.hpp)
  // the gas load (gas.hpp): device copies of GasState's arrays, and the partial sums of its
  // fixed-order sums (GasBuffers' device path); the scalars stay on the host
  DeviceArray<double> gas_wall_dv, gas_wall_left, gas_arrival, gas_arrival_next, gas_kappa_volume, gas_vent_area;
  DeviceArray<double> gas_position, gas_push;
  DeviceArray<uint8_t> gas_wall_on, gas_halves, gas_front_done, gas_in_crack, gas_attached, gas_row_mark,
      gas_chunk_live;
  DeviceArray<GasSums> gas_block_sums, gas_particle_sums;
  GasBuffers gas{};
  void upload_gas(const GasState& g, int64_t n);
  // reductions
  DeviceArray<StepSums> step_partial;
  DeviceArray<MeasureSums> measure_partial;
  DeviceArray<DeviceScalars> scalars;
  // model.precision: float32 (float32_state.hpp): the arrays the kernels stream, in float;
  // the double arrays above keep what a float run keeps in double (loads, constraints'
  // ramps, diagnostics, every reduction) and receive u and v before a measure or download.
  bool f32 = false;
  StreamedArrays<float> floats;
  PdViewT<float> fview;
  // correspondence model: per-particle moduli (kCorrModuli), F and A_i (9 each), non-affine energy
  DeviceArray<double> corr_moduli, corr_deformation, corr_force_tensor, corr_nonaffine;
  int dimension = 3;

  PdView view;
  FacetView facets{};
  bool sync_after_launch = false;  // BRECCIA_CUDA_SYNC=1: attribute asynchronous faults to their kernel
  cuda::KernelClock clock;         // --kernel-times: events around every launch after the warm-up
  // cudaMemGetInfo's free memory before the upload, the device's total, and what the upload took
  size_t memory_free_before = 0, memory_total = 0, memory_uploaded = 0;

  // The step's arrays (step.hpp) over the device copies, double and float; built once, their
  // views copies of `view` and `fview` (refresh_step_views keeps them so).
  StepArrays<double> arrays;
  StepArrays<float> farrays;
  void refresh_step_views() {
    arrays.p = arrays.d = farrays.d = view;
    arrays.corr.p = view;
    farrays.p = fview;
  }

  // Every phase of the step is a functor of step.hpp (BRECCIA_HD): cuda::for_each launches
  // any of them over [0, n), one thread per index (cuda_launch.cuh, shared with the set-up's
  // family kernels).
  template <class F>
  void for_each(int64_t n, const F& f, const char* name) {
    if (n == 0) return;  // no launch (cuda::for_each), nothing to time
    clock.before();
    cuda::for_each(n, f, name, sync_after_launch);
    clock.after(name);
  }
  template <class From, class To>
  void convert(int64_t count, const From* from, To* to, const char* what) {
    for_each(count, Convert<From, To>{from, to}, what);
  }
  // The run loop turns diagnostics off between output steps; every launch reads the flag.
  void sync_flags(const PdSystem& sys) {
    view.diagnostics = fview.diagnostics = sys.diagnostics;
    view.symmetric_halves = fview.symmetric_halves = sys.symmetric_halves;
    refresh_step_views();
  }
  void float_kinematics_to_double();  // floats' u, v -> doubles' (a float run's measure and probes)

  // A distributed run's halo (null on one process): the send list on the device, the packed
  // items on the device, and their pinned host copies for an MPI that takes host memory only.
  HaloTransport* halo = nullptr;
  bool rate_law = false;  // the displacement's exchange carries the velocity too (halo_arrays)
  DeviceArray<int32_t> halo_send;
  DeviceArray<char> halo_send_items, halo_recv_items;
  cuda::PinnedBuffer halo_host_send, halo_host_recv;
  void exchange(const HaloArrays& h);
};

// The ghosts' values of the arrays `h` names from their owners: packed on the device from the
// send list, handed to MPI (the device buffers themselves where the library is CUDA-aware,
// else pinned host copies), unpacked on the device into the ghosts. The bytes are the
// owners', so a ghost holds what the CPU's exchange gives it.
void CudaSystem::Impl::exchange(const HaloArrays& h) {
  const size_t per = h.bytes_per_item();
  if (!halo || per == 0) return;
  const size_t sends = halo_send.size(), ghosts = static_cast<size_t>(halo->ghosts());
  if (halo_send_items.size() < sends * per) halo_send_items.allocate(sends * per, "halo send items");
  if (halo_recv_items.size() < ghosts * per) halo_recv_items.allocate(ghosts * per, "halo receive items");
  size_t offset = 0;
  for (int k = 0; k < h.count; ++k) {
    const HaloArray& a = h.item[k];
    for_each(static_cast<int64_t>(sends * a.bytes),
             PackHalo{static_cast<const char*>(a.data), a.bytes, halo_send.get(), halo_send_items.get(), per, offset},
             "halo_pack");
    offset += a.bytes;
  }
  if (halo->device_buffers()) {
    check(cudaDeviceSynchronize(), "halo packing");  // MPI reads the items as soon as it is called
    halo->exchange_packed(halo_send_items.get(), halo_recv_items.get(), per);
  } else {
    void* send = halo_host_send.reserve(std::max<size_t>(sends * per, 1), "halo send items");
    void* recv = halo_host_recv.reserve(std::max<size_t>(ghosts * per, 1), "halo receive items");
    // cudaMemcpy waits for the packing kernels (the default stream) and returns when done.
    if (sends > 0)
      check(cudaMemcpy(send, halo_send_items.get(), sends * per, cudaMemcpyDeviceToHost), "halo send items to the host");
    halo->exchange_packed(send, recv, per);
    if (ghosts > 0)
      check(cudaMemcpy(halo_recv_items.get(), recv, ghosts * per, cudaMemcpyHostToDevice), "halo items to the device");
  }
  offset = 0;
  for (int k = 0; k < h.count; ++k) {
    const HaloArray& a = h.item[k];
    for_each(static_cast<int64_t>(ghosts * a.bytes),
             UnpackHalo{halo_recv_items.get(), per, offset, static_cast<char*>(a.data), a.bytes, view.n}, "halo_unpack");
    offset += a.bytes;
  }
}

namespace {

// Its two launches are one kernel of --kernel-times (m.clock), as Impl::for_each's launch is.
template <class Load, class Finish>
void reduce(CudaSystem::Impl& m, int64_t n, const Load& load, typename Load::Value* partial, Finish finish,
            const char* name) {
  const int grid = static_cast<int>(std::clamp<int64_t>(blocks_for(n), 1, kMaxReduceBlocks));
  m.clock.before();
  reduce_partial_cuda<Load><<<grid, kBlock>>>(n, load, partial);
  check_launch(name, m.sync_after_launch);
  reduce_final_cuda<Load, Finish><<<1, kBlock>>>(grid, partial, finish);
  check_launch(name, m.sync_after_launch);
  m.clock.after(name);
}

// The CUDA execution space of step.hpp: launches on the device copies; sums stay on the
// device (the energy accumulators of DeviceScalars) until a measure reads them.
class CudaExec {
public:
  explicit CudaExec(CudaSystem::Impl& m) : m_(m) {}
  template <class F>
  void for_each(int64_t n, const F& f, const char* name) const { m_.for_each(n, f, name); }
  template <class Load, class Finish>
  void reduce(int64_t n, const Load& load, const Finish& finish, const char* name) const {
    static_assert(std::is_same_v<typename Load::Value, StepSums>, "the step's reductions sum StepSums");
    solver::reduce(m_, n, load, m_.step_partial.get(), finish, name);
  }
  // commit_min_stretch: the device buffers trade places; every view follows (`a` is one of
  // the Impl's step arrays, refreshed with the others).
  template <class Real>
  void commit_min_stretch(StepArrays<Real>&) const {
    if (m_.min_stretch.size() == 0) return;
    m_.min_stretch.swap(m_.min_stretch_next);
    m_.view.min_stretch = m_.fview.min_stretch = m_.min_stretch.get();
    m_.view.min_stretch_next = m_.fview.min_stretch_next = m_.min_stretch_next.get();
    m_.refresh_step_views();
    // Under MPI: the ghosts' minimum stretches the coming pass reads are their owners' (the
    // CPU's MpiExec does the same).
    if (m_.halo) {
      HaloArrays h;
      h.item[h.count++] = {m_.min_stretch.get(), sizeof(float)};
      m_.exchange(h);
    }
  }
  // A distributed run's exchanges (step.hpp exchange_halo): the arrays halo_arrays names, on
  // the device. Nothing on one process.
  template <class Real>
  void exchange(const StepArrays<Real>& a, HaloField field) const {
    if (m_.halo) m_.exchange(halo_arrays(a, field, m_.rate_law));
  }
  template <class Real>
  void contact(const StepArrays<Real>&) const {
    throw RunError("CUDA backend: model.short_range_forces needs the contact search of the CPU; use --backend cpu");
  }
  // The gas load (gas.hpp): its passes on the device copies; its block sums (a few per 256
  // particles) come back to the host each step, where its scalars are updated.
  GasBuffers gas_buffers(GasState&) const { return m_.gas; }
  const GasSums* gas_block_sums_on_host(GasState& gas, const GasSums* sums, int64_t blocks) const {
    gas.block_sums.resize(static_cast<size_t>(blocks));
    check(cudaMemcpy(gas.block_sums.data(), sums, blocks * sizeof(GasSums), cudaMemcpyDeviceToHost),
          "copy of the gas's block sums");
    return gas.block_sums.data();
  }
  // A boundary by expression: the host's refreshed values into the device copy the step reads.
  void upload_boundary_values(size_t c, const std::vector<double>& values) const {
    m_.constraint_values[c].copy_in(values, "boundary values");
  }

private:
  CudaSystem::Impl& m_;
};

}  // namespace

CudaSystem::CudaSystem(const PdSystem& s, HaloTransport* halo) : impl_(std::make_unique<Impl>()) {
  if (!cuda_device_available())
    throw RunError("CUDA backend: no CUDA device is available (no GPU, or no NVIDIA driver); use --backend cpu");
  // Refused here, before anything is uploaded or a caller that skips breccia-solve's check
  // (breccia-atlas) opens its outputs; the step's contact() would refuse only at the first pass.
  if (!s.short_range_k.empty())
    throw RunError("CUDA backend: model.short_range_forces needs the contact search of the CPU; use --backend cpu");
  check(cudaSetDevice(g_device), "cudaSetDevice(" + std::to_string(g_device) + ")");
  Impl& m = *impl_;
  // The particles held: the n stepped, then a distributed run's ghosts (rank_system.hpp),
  // whose per-particle arrays are uploaded with the owned ones' and filled by the exchanges.
  const size_t held = s.x0.size() / 3;
  const char* sync = std::getenv("BRECCIA_CUDA_SYNC");
  m.sync_after_launch = sync && std::string(sync) == "1";
  check(cudaMemGetInfo(&m.memory_free_before, &m.memory_total), "cudaMemGetInfo");

  m.doubles.upload(s, s.n, held, "");
  {  // current positions: refreshed by every force pass, but a download before the first one
     // (an output right after a restart) must not read uninitialised memory
    std::vector<double> x(s.x0.size());
    for (size_t k = 0; k < x.size(); ++k) x[k] = s.x0[k] + s.u[k];
    m.x.upload(x, "x");
  }
  m.fixed_dof.upload(s.fixed_dof, "fixed_dof");
  m.energy_density.upload(s.energy_density, "energy_density");
  m.dissipated.upload(s.dissipated, "dissipated");
  m.damage.upload(s.damage, "damage");
  m.max_stretch.upload(s.max_stretch, "max_stretch");
  m.lps.upload(s.lps, "lps");
  m.offsets.upload(s.offsets, "offsets");
  m.neighbor.upload(s.neighbor, "neighbor");
  m.own_count.upload(s.own_count, "own_count");  // empty with the analytic partial volume
  m.family_volume.upload(s.family_volume, "family volumes");  // empty: the passes sum them (pd_kernels.hpp)
  m.s0_own.upload(s.s0_own, "s0_own");
  m.s0_dual.upload(s.s0_dual, "s0_dual");
  m.state.upload(s.state, "state");
  if (!s.min_stretch.empty()) {
    m.min_stretch.upload(s.min_stretch, "min_stretch");
    m.min_stretch_next.upload(s.min_stretch_next, "min_stretch_next");
  }
  if (!s.bond_damage.empty()) {
    m.s_onset.upload(s.s_onset, "s_onset");
    m.bond_damage.upload(s.bond_damage, "bond_damage");
  }
  if (s.config.model == PdModel::Correspondence) {
    m.corr_moduli.upload(s.corr_moduli, "correspondence moduli");
    m.corr_deformation.upload(s.corr_deformation, "correspondence F");
    m.corr_force_tensor.upload(s.corr_force_tensor, "correspondence force tensors");
    m.corr_nonaffine.upload(s.corr_nonaffine, "correspondence non-affine energy");
  }
  m.dimension = s.dimension;
  if (s.f32.active) {
    m.f32 = true;
    m.floats.upload(s.f32, s.n, held, "float ");
    m.ffamily_volume.upload(s.f32.family_volume, "float family volumes");
  }
  m.f_before.allocate(3 * s.n, "f_before");

  // Every field set here by name; one added to PdView later stays nullptr (its optional
  // feature off) until it is added here, rather than pointing at host memory.
  PdView& p = m.view;
  p.n = static_cast<int64_t>(s.n);
  p.model = static_cast<int>(s.config.model);
  p.fracture = s.config.fracture;
  p.diagnostics = s.diagnostics;
  p.symmetric_halves = s.symmetric_halves;
  const bool dual_shared = s.dual_halves_shared;  // the own arrays serve as the dual ones
  // The own halves' volumes (pd_kernels.hpp own_volume): the counts with the double volumes, else vol_own.
  const bool counted = !s.own_count.empty();
  m.doubles.point(p, dual_shared, counted);
  p.x = m.x.get(); p.fixed_dof = m.fixed_dof.get();
  p.offsets = m.offsets.get(); p.neighbor = m.neighbor.get();
  p.own_count = counted ? m.own_count.get() : nullptr;
  p.volume_exact = m.doubles.volume.get();
  m.sample_fraction.upload(std::vector<double>(s.own_count_fractions(), s.own_count_fractions() + kSampleFractions),
                           "sample fractions");
  p.sample_fraction = counted ? m.sample_fraction.get() : nullptr;
  p.family_volume = m.family_volume.get();  // null where none were uploaded
  p.s0_own = m.s0_own.get(); p.s0_dual = dual_shared ? p.s0_own : m.s0_dual.get(); p.state = m.state.get();
  if (m.min_stretch.size() > 0) {
    p.alpha = static_cast<float>(s.config.compressive_enhancement);
    p.min_stretch = m.min_stretch.get();
    p.min_stretch_next = m.min_stretch_next.get();
  }
  p.break_after_force = s.config.break_after_force;
  p.s_onset = m.s_onset.get();
  p.s_ultimate = m.s0_own.get();  // the rate law's raised ultimates (pd_kernels.hpp soften)
  p.bond_damage = m.bond_damage.get();
  p.strength_rate = m.bond_damage.size() > 0 ? static_cast<int>(s.config.strength_rate) : 0;
  p.crush_ratio = m.bond_damage.size() > 0 ? static_cast<float>(s.config.crush_ratio) : 0.0f;
  p.lps = m.lps.get();
  p.energy_density = m.energy_density.get(); p.dissipated = m.dissipated.get();
  p.damage = m.damage.get(); p.max_stretch = m.max_stretch.get();
  if (m.f32) {  // as float32_view: float where the state is float, the shared rest from above
    PdViewT<float>& q = m.fview;
    q.n = p.n; q.model = p.model; q.fracture = p.fracture; q.diagnostics = p.diagnostics;
    q.symmetric_halves = p.symmetric_halves;
    m.floats.point(q, dual_shared, counted);  // vol_own: float32_view's choice
    q.x = nullptr;  // float never forms x0 + u
    q.fixed_dof = p.fixed_dof; q.offsets = p.offsets; q.neighbor = p.neighbor;
    q.own_count = p.own_count; q.volume_exact = p.volume_exact; q.sample_fraction = p.sample_fraction;
    q.family_volume = m.ffamily_volume.get();  // the float passes' sums (float32_enable)
    q.s0_own = p.s0_own; q.s0_dual = p.s0_dual; q.state = p.state; q.lps = p.lps;
    q.alpha = p.alpha; q.min_stretch = p.min_stretch; q.min_stretch_next = p.min_stretch_next;
    q.break_after_force = p.break_after_force;
    q.s_onset = p.s_onset;
    q.s_ultimate = p.s_ultimate;
    q.bond_damage = p.bond_damage;
    q.strength_rate = p.strength_rate;
    q.crush_ratio = p.crush_ratio;
    q.energy_density = p.energy_density; q.dissipated = p.dissipated; q.damage = p.damage; q.max_stretch = p.max_stretch;
  }

  // Surface-load facets grouped by particle (set-up's FacetLayout, the CPU's order).
  m.facet_particle.upload(s.facets.particle, "facet particles");
  m.facet_offsets.upload(s.facets.offsets, "facet offsets");
  m.facet_load.upload(s.facets.load, "facet loads");
  m.facet_area.upload(s.facets.area, "facet areas");
  m.facet_normal.upload(s.facets.normal, "facet normals");
  m.load_is_pressure.upload(s.facets.is_pressure, "load kinds");
  m.load_vector.upload(s.facets.vectors, "load vectors");
  m.facets = {static_cast<int64_t>(s.facets.particle.size()), m.facet_particle.get(), m.facet_offsets.get(),
              m.facet_load.get(), m.facet_area.get(), m.facet_normal.get(), m.load_is_pressure.get(),
              m.load_vector.get()};

  m.body_load_particles = std::vector<DeviceArray<int32_t>>(s.body_loads.size());
  for (size_t b = 0; b < s.body_loads.size(); ++b) m.body_load_particles[b].upload(s.body_loads[b].particles, "body-load set");
  m.constraint_particles = std::vector<DeviceArray<int32_t>>(s.constraints.size());
  for (size_t c = 0; c < s.constraints.size(); ++c) m.constraint_particles[c].upload(s.constraints[c].particles, "boundary set");
  m.constraint_values = std::vector<DeviceArray<double>>(s.constraints.size());
  for (size_t c = 0; c < s.constraints.size(); ++c) m.constraint_values[c].upload(s.constraints[c].values, "boundary values");

  if (s.gas.active) m.upload_gas(s.gas, static_cast<int64_t>(s.n));

  m.step_partial.allocate(kMaxReduceBlocks, "step partial sums");
  m.measure_partial.allocate(kMaxReduceBlocks, "measure partial sums");
  const std::vector<DeviceScalars> scalars{{s.external_work, s.dissipated_energy, {0.0, 0.0, 0.0, 0, -1}}};
  m.scalars.upload(scalars, "energy accumulators");

  // The step's arrays: the same StepArrays the CPU builds, over device memory.
  auto fill = [&](auto& a) {
    a.x = m.x.get();
    a.f_before = m.f_before.get();
    a.facets = m.facets;
    for (size_t c = 0; c < s.constraints.size(); ++c) {
      a.constraint_sets.push_back({static_cast<int64_t>(m.constraint_particles[c].size()), m.constraint_particles[c].get()});
      a.constraint_values.push_back(s.constraints[c].field ? m.constraint_values[c].get() : nullptr);
    }
    for (size_t b = 0; b < s.body_loads.size(); ++b)
      a.body_load_sets.push_back(s.body_loads[b].every_particle
                                     ? SetView{static_cast<int64_t>(s.n), nullptr}
                                     : SetView{static_cast<int64_t>(m.body_load_particles[b].size()),
                                               m.body_load_particles[b].get()});
    a.external_work = &m.scalars.get()->external_work;
    a.dissipated_energy = &m.scalars.get()->dissipated_energy;
  };
  fill(m.arrays);
  m.arrays.u_before = m.doubles.u_before.get();
  if (halo) {
    m.halo = halo;
    m.rate_law = s.config.strength_rate != StrengthRateLaw::None;
    m.halo_send.upload(halo->send_indices(), "halo send list");
    m.arrays.ghosts = m.farrays.ghosts = halo->ghosts();
  }
  if (s.config.model == PdModel::Correspondence) {
    m.arrays.corr.dimension = m.dimension;
    m.arrays.corr.moduli = m.corr_moduli.get();
    m.arrays.corr.deformation = m.corr_deformation.get();
    m.arrays.corr.force_tensor = m.corr_force_tensor.get();
    m.arrays.corr.nonaffine = m.corr_nonaffine.get();
    m.arrays.corr.damage_limit = correspondence_damage_limit(s.config);
  }
  if (m.f32) {
    fill(m.farrays);
    m.farrays.u_before = m.floats.u_before.get();
  }
  if (s.config.cuda_sell_layout) {
    // The layout's passes (step.hpp pd_force_pass): one thread per slice lane. The fast passes
    // of one constant horizon, or the dual-horizon pass (sell_kernels.hpp sell_general_pass);
    // a case that takes neither would pay the layout's state refresh after every pass for nothing.
    const bool bond_model = s.config.model == PdModel::PMB || s.config.model == PdModel::LPS;
    const bool fast = s.symmetric_halves && s.min_stretch.empty() &&
                      (s.config.model == PdModel::PMB || s.lps_a.size() == held);
    const bool dual = !s.symmetric_halves;
    if (!bond_model || !s.bond_damage.empty() || !(fast || dual))
      throw RunError("CUDA backend: model.cuda_layout: sell serves the bond passes of PMB and LPS with brittle bonds "
                     "(one constant horizon without compressive enhancement, or variable horizons); use "
                     "model.cuda_layout: csr");
    const SellLayout layout = build_sell_layout(s.offsets, kSellChunk, kSellSigma);
    m.sell_slice_offset.upload(layout.slice_offset, "SELL slice offsets");
    m.sell_csr_entry.upload(layout.csr_entry, "SELL CSR entries");
    m.sell_particle.upload(layout.particle, "SELL lane particles");
    m.sell_row_length.upload(layout.row_length, "SELL row lengths");
    const SellBondArrays<double> b =
        dual ? gather_sell_bonds(layout, s.neighbor, s.xi_len, s.k_own, s.s0_own, s.state, s.k_dual_halves(),
                                 s.s0_dual_halves(), s.vol_own, s.own_count)
             : gather_sell_bonds(layout, s.neighbor, s.xi_len, s.k_own, s.s0_own, s.state);
    m.sell_neighbor.upload(b.neighbor, "SELL neighbours");
    m.sell_xi_len.upload(b.xi_len, "SELL bond lengths");
    m.sell_k_own.upload(b.k_own, "SELL moduli");
    m.sell_s0_own.upload(b.s0_own, "SELL critical stretches");
    m.sell_state.upload(b.state, "SELL bond states");
    if (dual) {
      m.sell_k_dual.upload(b.k_dual, "SELL dual moduli");
      m.sell_s0_dual.upload(b.s0_dual, "SELL dual critical stretches");
      m.sell_vol_own.upload(b.vol_own, "SELL damage weights");             // or
      m.sell_own_count.upload(b.own_count, "SELL damage weights' counts");  // (pd_system.hpp own_count)
    }
    const SellView view{layout.lanes(), kSellChunk, m.sell_slice_offset.get(), m.sell_particle.get(),
                        m.sell_row_length.get(), m.sell_csr_entry.get(), m.state.get()};
    m.arrays.sell = view;
    m.arrays.sell_entries = {m.sell_neighbor.get(), m.sell_xi_len.get(), m.sell_k_own.get(), m.sell_s0_own.get(),
                             m.sell_state.get(),    dual ? m.sell_k_dual.get() : nullptr,
                             dual ? m.sell_s0_dual.get() : nullptr, dual ? m.sell_vol_own.get() : nullptr,
                             dual ? m.sell_own_count.get() : nullptr};
    if (m.f32) {
      m.sell_fxi_len.upload(layout.gather(s.f32.xi_len, 1.0f), "SELL float bond lengths");
      m.sell_fk_own.upload(layout.gather(s.f32.k_own, 0.0f), "SELL float moduli");
      if (dual) {
        m.sell_fk_dual.upload(layout.gather(s.f32_k_dual_halves(), 0.0f),
                              "SELL float dual moduli");
        if (!s.f32.vol_own.empty()) m.sell_fvol_own.upload(layout.gather(s.f32.vol_own, 0.0f), "SELL float damage weights");
      }
      m.farrays.sell = view;
      m.farrays.sell_entries = {m.sell_neighbor.get(), m.sell_fxi_len.get(), m.sell_fk_own.get(), m.sell_s0_own.get(),
                                m.sell_state.get(),    dual ? m.sell_fk_dual.get() : nullptr,
                                dual ? m.sell_s0_dual.get() : nullptr, dual ? m.sell_fvol_own.get() : nullptr,
                                dual ? m.sell_own_count.get() : nullptr};
    }
  }
  m.refresh_step_views();
  m.memory_uploaded = device_memory().system_bytes;
}

DeviceMemory CudaSystem::device_memory() {
  const Impl& m = *impl_;
  size_t free_now = 0, total = 0;
  check(cudaMemGetInfo(&free_now, &total), "cudaMemGetInfo");
  const size_t used = m.memory_free_before > free_now ? m.memory_free_before - free_now : 0;
  return {static_cast<int64_t>(std::max(used, m.memory_uploaded)), static_cast<int64_t>(m.memory_free_before),
          static_cast<int64_t>(m.memory_total)};
}

// The gas's arrays as the host has them (set-up, or a restart's state), and the view of them.
void CudaSystem::Impl::upload_gas(const GasState& g, int64_t n) {
  gas_wall_dv.upload(g.wall_dv, "gas wall_dv");
  gas_wall_left.upload(g.wall_left, "gas wall_left");
  gas_wall_on.upload(g.wall_on, "gas wall_on");
  gas_kappa_volume.upload(g.kappa_volume, "gas kappa_volume");
  gas_vent_area.upload(g.vent_facet_area, "gas vent_facet_area");
  GasView& v = gas.view;
  v.load = g.load;
  v.wall_dv = gas_wall_dv.get();
  v.wall_left = gas_wall_left.get();
  v.wall_on = gas_wall_on.get();
  v.kappa_volume = gas_kappa_volume.get();
  v.vent_area = gas_vent_area.get();
  if (g.crack_entry) {  // the front and the cracks (GasView's arrival is null without them)
    gas_arrival.upload(g.arrival, "gas arrival");
    gas_arrival_next.upload(g.arrival_next, "gas arrival_next");
    gas_halves.upload(g.halves, "gas halves");
    gas_position.upload(g.position, "gas positions");
    gas_push.upload(g.push, "gas push");
    gas_front_done.upload(g.front_done, "gas front_done");
    gas_in_crack.upload(g.in_crack, "gas in_crack");
    gas_attached.upload(g.attached, "gas attached");
    gas_row_mark.upload(g.row_mark, "gas row_mark");
    gas_chunk_live.upload(g.chunk_live, "gas chunk_live");
    v.arrival = gas_arrival.get();
    v.arrival_next = gas_arrival_next.get();
    v.halves = gas_halves.get();
    v.position = gas_position.get();
    v.push = gas_push.get();
    v.front_done = gas_front_done.get();
    v.in_crack = gas_in_crack.get();
    v.attached = gas_attached.get();
    v.row_mark = g.row_mark.empty() ? nullptr : gas_row_mark.get();
    v.chunk_live = g.chunk_live.empty() ? nullptr : gas_chunk_live.get();
  }
  const int64_t count = std::max<int64_t>(n, static_cast<int64_t>(g.wall_dv.size()));
  gas_particle_sums.allocate(static_cast<size_t>(std::max<int64_t>(count, 1)), "gas per-particle sums");
  gas_block_sums.allocate(static_cast<size_t>(std::max<int64_t>(gas_blocks(count), 1)), "gas block sums");
  gas.particle_sums = gas_particle_sums.get();
  gas.block_sums = gas_block_sums.get();
}

CudaSystem::~CudaSystem() = default;

// cpu_compute_forces / float32_compute_forces on the device: the force pass of step.hpp.
void CudaSystem::compute_forces(PdSystem& sys) {
  Impl& m = *impl_;
  if (m.view.n == 0) return;
  m.sync_flags(sys);
  CudaExec exec(m);
  if (m.f32) pd_force_pass(exec, m.farrays, true);
  else pd_force_pass(exec, m.arrays, true);
}

// cpu_step / float32_step on the device: the step of step.hpp.
void CudaSystem::step(PdSystem& sys) {
  Impl& m = *impl_;
  m.sync_flags(sys);
  CudaExec exec(m);
  m.clock.step_begins();
  if (m.f32) pd_step(exec, m.farrays, sys);
  else pd_step(exec, m.arrays, sys);
  m.clock.step_ends();
}

void CudaSystem::time_kernels(long long warmup_steps) { impl_->clock.start(warmup_steps); }

std::optional<KernelTimes> CudaSystem::kernel_times() { return impl_->clock.times(); }

void CudaSystem::Impl::float_kinematics_to_double() {
  convert(3 * view.n, floats.u.get(), doubles.u.get(), "float u to double");
  convert(3 * view.n, floats.v.get(), doubles.v.get(), "float v to double");
}

Energies CudaSystem::measure(PdSystem& sys) {
  Impl& m = *impl_;
  Energies e;
  if (m.f32) m.float_kinematics_to_double();  // float32 measures the double copies, as on the CPU
  if (m.view.n > 0)
    reduce(m, m.view.n, MeasureLoad{m.view}, m.measure_partial.get(), MeasureFinish{m.scalars.get()},
           "measure reduction");
  std::vector<DeviceScalars> host;
  m.scalars.download(host, "energy sums");  // synchronises with the default stream
  // The history row counts the particles the gas has reached.
  if (sys.gas.active && sys.gas.crack_entry) m.gas_arrival.download(sys.gas.arrival, "gas arrival");
  // The zero-energy-mode detector (zero_energy_mode_message) reads the non-affine energy.
  if (m.corr_nonaffine.size() > 0) m.corr_nonaffine.download(sys.corr_nonaffine, "correspondence non-affine energy");
  const DeviceScalars& s = host[0];
  sys.external_work = s.external_work;
  sys.dissipated_energy = s.dissipated_energy;
  if (m.view.n == 0) return e;
  e.kinetic = s.measured.kinetic;
  e.strain = s.measured.strain;
  e.max_damage = s.measured.max_damage;
  e.broken_half_bonds = s.measured.broken_half_bonds;
  e.bad_particle = s.measured.bad_particle;
  e.finite = e.bad_particle < 0 && std::isfinite(e.kinetic) && std::isfinite(e.strain);
  return e;
}

void CudaSystem::download_kinematics(PdSystem& sys) {
  if (impl_->f32) impl_->float_kinematics_to_double();
  impl_->doubles.u.download(sys.u, "u");
  impl_->doubles.v.download(sys.v, "v");
}

void CudaSystem::download(PdSystem& sys) {
  Impl& m = *impl_;
  if (m.f32) {  // float32_download: the float state is the truth
    const int64_t n3 = 3 * m.view.n;
    m.convert(n3, m.floats.a.get(), m.doubles.a.get(), "float a to double");
    m.convert(n3, m.floats.force.get(), m.doubles.force.get(), "float force to double");
    m.convert(m.view.n, m.floats.dilatation.get(), m.doubles.dilatation.get(), "float dilatation to double");
  }
  download_kinematics(sys);
  if (!m.f32) m.x.download(sys.x, "x");  // float runs never form x0 + u
  m.doubles.a.download(sys.a, "a");
  m.doubles.force.download(sys.force, "force");
  m.doubles.body.download(sys.body, "body");
  m.energy_density.download(sys.energy_density, "energy_density");
  m.dissipated.download(sys.dissipated, "dissipated");
  m.damage.download(sys.damage, "damage");
  m.max_stretch.download(sys.max_stretch, "max_stretch");
  m.doubles.dilatation.download(sys.dilatation, "dilatation");
  m.state.download(sys.state, "state");
  m.bond_damage.download(sys.bond_damage, "bond_damage");
  if (sys.config.strength_rate != StrengthRateLaw::None) {  // state with a rate law: the raised laws
    m.s_onset.download(sys.s_onset, "s_onset");
    m.s0_own.download(sys.s0_own, "s0_own");
  }
  m.min_stretch.download(sys.min_stretch, "min_stretch");
  m.min_stretch_next.download(sys.min_stretch_next, "min_stretch_next");
  if (sys.gas.active) {  // what a checkpoint keeps of the gas (outputs.cpp)
    m.gas_wall_dv.download(sys.gas.wall_dv, "gas wall_dv");
    m.gas_wall_on.download(sys.gas.wall_on, "gas wall_on");
    if (sys.gas.crack_entry) {
      m.gas_arrival.download(sys.gas.arrival, "gas arrival");
      m.gas_in_crack.download(sys.gas.in_crack, "gas in_crack");
      if (sys.gas.crack_pass_every > 1) m.gas_push.download(sys.gas.push, "gas push");
    }
  }
  std::vector<DeviceScalars> host;
  m.scalars.download(host, "energy sums");
  sys.external_work = host[0].external_work;
  sys.dissipated_energy = host[0].dissipated_energy;
}

}  // namespace breccia::solver
