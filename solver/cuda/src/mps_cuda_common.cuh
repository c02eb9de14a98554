#pragma once
// Launch helpers and kernels that both MPS launchers use (mps_cuda.cu: displacement
// formulation; mps_solid_cuda.cu: stress formulation): the thread index, a mutable vector
// field, the integrators and the prescribed values. Only those two .cu files include this.
// The kernels sit in an unnamed namespace: each launcher gets its own copy, as it would with
// whole-program compilation (no relocatable device code is needed).
#include <cuda_runtime.h>

#include <vector>

#include "breccia/mps/kernels.hpp"
#include "breccia/mps/neighbours.hpp"
#include "breccia/mps/particles.hpp"
#include "breccia/solver/cuda_memory.cuh"

namespace breccia::mps {
namespace {

constexpr int kBlock = 256;

long long blocks_for(long long n) { return (n + kBlock - 1) / kBlock; }

__device__ long long thread_index() { return static_cast<long long>(blockIdx.x) * blockDim.x + threadIdx.x; }

// Mutable view of a vector field on the device (VectorField is const).
struct DeviceField {
  double* x;
  double* y;
  double* z;
};

// The reference bond list (CSR) on the device; upload() returns the view the kernels take.
struct DeviceBonds {
  cuda::DeviceArray<long long> offset;
  cuda::DeviceArray<int> neighbour;
  cuda::DeviceArray<double> rx, ry, rz, weight;
  BondsView upload(const BondList& b) {
    offset.upload(b.offset, "bond offsets");
    neighbour.upload(b.neighbour, "bond neighbours");
    rx.upload(b.rx, "bond rx");
    ry.upload(b.ry, "bond ry");
    rz.upload(b.rz, "bond rz");
    weight.upload(b.weight, "bond weights");
    return {offset.get(), neighbour.get(), rx.get(), ry.get(), rz.get(), weight.get()};
  }
};

// Integrators on components 0..dimension-1: one kernel, the kernels.hpp body chosen at
// compile time (symplectic_euler_update, Simulation::step, Solid::step).
enum class Integration { SymplecticEuler, VerletKickDrift, VerletKick };

template <Integration kind>
__global__ void integrate_cuda(long long n, int dimension, DeviceField u, DeviceField v, VectorField a, double half_dt,
                               double dt) {
  const long long i = thread_index();
  if (i >= n) return;
  double* uc[3] = {u.x, u.y, u.z};
  double* vc[3] = {v.x, v.y, v.z};
  const double* ac[3] = {a.x, a.y, a.z};
  // Unrolled over a constant bound so the pointer arrays stay in registers.
#pragma unroll
  for (int d = 0; d < 3; ++d) {
    if (d >= dimension) continue;
    if constexpr (kind == Integration::SymplecticEuler) symplectic_euler_at(uc[d][i], vc[d][i], ac[d][i], dt);
    else if constexpr (kind == Integration::VerletKickDrift) verlet_kick_drift_at(uc[d][i], vc[d][i], ac[d][i], half_dt, dt);
    else verlet_kick_at(vc[d][i], ac[d][i], half_dt);
  }
}

// One prescribed set at this step (apply_prescribed): the history is evaluated on the host.
__global__ void prescribe_cuda(long long count, const int* particles, unsigned components, double u_value,
                               double v_value, DeviceField u, DeviceField v) {
  const long long q = thread_index();
  if (q >= count) return;
  const int i = particles[q];
  double* uc[3] = {u.x, u.y, u.z};
  double* vc[3] = {v.x, v.y, v.z};
  for (int d = 0; d < 3; ++d)
    if (components & (1u << d)) {
      uc[d][i] = u_value;
      vc[d][i] = v_value;
    }
}

// The prescribed sets at time t (Simulation::apply_prescribed, Solid::apply_prescribed): each
// set's history evaluated here, its particles set on the device.
inline void launch_prescribed(const std::vector<PrescribedSet>& sets, const std::vector<cuda::DeviceArray<int>>& particles,
                              double t, DeviceField u, DeviceField v, bool sync_after_launch) {
  for (size_t k = 0; k < sets.size(); ++k) {
    const PrescribedSet& set = sets[k];
    const double u_value = set.burst ? burst_displacement(*set.burst, t) : 0.0;
    const double v_value = set.burst ? burst_velocity(*set.burst, t) : 0.0;
    unsigned components = 0;
    for (int d = 0; d < 3; ++d)
      if (set.components[d]) components |= 1u << d;
    const long long count = static_cast<long long>(particles[k].size());
    if (count == 0 || components == 0) continue;
    prescribe_cuda<<<blocks_for(count), kBlock>>>(count, particles[k].get(), components, u_value, v_value, u, v);
    cuda::check_launch("prescribed displacement", sync_after_launch);
  }
}

}  // namespace
}  // namespace breccia::mps
