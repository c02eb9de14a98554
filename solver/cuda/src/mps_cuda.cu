// The CUDA launcher of the MPS displacement formulation: Simulation::step's phases, in its
// order, as launches of the BRECCIA_HD bodies of kernels.hpp and crack.hpp over device copies
// of the state (docs/cuda.md, "MPS"). No physics is written here: launches, data movement,
// the grouping of crack-pair forces per particle, and the per-step read-back of probe values.
// Compiled with --fmad=false (CMakeLists.txt), so each particle's arithmetic rounds as on the CPU.
#include <cuda_runtime.h>

#include <cstdint>
#include <cstdlib>
#include <string>
#include <unordered_map>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/mps/crack.hpp"
#include "breccia/mps/cuda_simulation.hpp"
#include "breccia/mps/kernels.hpp"
#include "breccia/mps/particles.hpp"
#include "breccia/mps/simulation.hpp"
#include "breccia/solver/cuda_device.hpp"
#include "breccia/solver/cuda_memory.cuh"
#include "mps_cuda_common.cuh"

namespace breccia::mps {
namespace {

using cuda::check;
using cuda::DeviceArray;

// elastic_pass, first half: <div u>_i for every particle.
__global__ void divergence_cuda(long long n, BondsView b, VectorField u, double scale, double* div) {
  const long long i = thread_index();
  if (i < n) div[i] = divergence_at(i, b, u, scale);
}

// elastic_pass, second half: a = graddiv <grad div u> + laplacian <lap u>.
__global__ void elastic_acceleration_cuda(long long n, BondsView b, VectorField u, const double* div, OperatorScales s,
                                          ElasticCoefficients c, DeviceField a) {
  const long long i = thread_index();
  if (i >= n) return;
  double acc[3];
  elastic_acceleration_at(i, b, u, div, s, c, acc);
  a.x[i] = acc[0];
  a.y[i] = acc[1];
  a.z[i] = acc[2];
}

// One thread per pair: the pair's friction state advances and its force is stored; the
// counts of slipping and open pairs (integers, so the atomic sums are exact) feed the history.
__global__ void crack_pairs_cuda(CrackPairsView c, VectorField u, VectorField v, double* pair_force,
                                 unsigned long long* counts) {
  const long long p = thread_index();
  if (p >= c.count) return;
  crack_pair_force_at(p, c, u, v, c.state[p], &pair_force[2 * p]);
  if (c.state[p].slipping) atomicAdd(&counts[0], 1ull);
  if (c.state[p].open) atomicAdd(&counts[1], 1ull);
}

// Pair forces grouped by particle (CSR in pair order): each particle adds its pairs' forces
// in the order the CPU loop over pairs adds them, so the sums round alike.
struct PairIncidenceView {
  long long particles;       // particles that belong to at least one pair
  const int* particle;       // their indices
  const long long* offset;   // entries of particle q: [offset[q], offset[q+1])
  const int* pair;           // pair index, ascending within a particle
  const unsigned char* plus; // 1: + side of that pair
  const double* mass;        // rho V per particle (all particles)
};

__global__ void add_pair_forces_cuda(PairIncidenceView inc, const double* pair_force, DeviceField a) {
  const long long q = thread_index();
  if (q >= inc.particles) return;
  const int i = inc.particle[q];
  for (long long e = inc.offset[q]; e < inc.offset[q + 1]; ++e)
    add_pair_acceleration(a.x[i], a.y[i], &pair_force[2 * inc.pair[e]], inc.mass[i], inc.plus[e] != 0);
}

// The per-step read-back: u and v of the watched particles (probes), then the pair counts.
__global__ void gather_watch_cuda(long long count, const int* particles, VectorField u, VectorField v,
                                  const unsigned long long* counts, double* out) {
  const long long q = thread_index();
  if (q < count) {
    const int i = particles[q];
    const double values[6] = {u.x[i], u.y[i], u.z[i], v.x[i], v.y[i], v.z[i]};
    for (int k = 0; k < 6; ++k) out[6 * q + k] = values[k];
  }
  if (q == 0) {
    out[6 * count] = static_cast<double>(counts[0]);
    out[6 * count + 1] = static_cast<double>(counts[1]);
  }
}

class CudaStepDevice final : public StepDevice {
public:
  explicit CudaStepDevice(const Simulation& sim);
  ~CudaStepDevice() override {
    if (readback_host_) cudaFreeHost(readback_host_);
  }
  void step(double time_after_s) override;
  void download(std::array<std::vector<double>, 3>& u, std::array<std::vector<double>, 3>& v,
                std::array<std::vector<double>, 3>& a, std::vector<PairState>& pair_states) override;
  void download_pair_states(std::vector<PairState>& pair_states) override {
    finish_readback();
    pair_state_.download(pair_states, "pair states");
  }
  double sample(int particle, int axis, bool velocity) override;
  long long slipping_pairs() override { return static_cast<long long>(read_counts()[0]); }
  long long open_pairs() override { return static_cast<long long>(read_counts()[1]); }
  std::string description() const override { return "cuda (" + solver::cuda_device_description() + ")"; }

private:
  void after_launch(const char* kernel) const { cuda::check_launch(kernel, sync_after_launch_); }
  void compute_acceleration();
  void apply_prescribed(double t);
  void launch_readback();
  void finish_readback();
  const double* read_counts();
  DeviceField field(DeviceArray<double>* f) const { return {f[0].get(), f[1].get(), f[2].get()}; }
  VectorField view(const DeviceArray<double>* f) const { return {f[0].get(), f[1].get(), f[2].get()}; }

  long long n_ = 0;
  int dimension_ = 2;
  double dt_ = 0.0;
  Integrator integrator_ = Integrator::SymplecticEuler;
  OperatorScales scales_;
  ElasticCoefficients coeffs_;
  bool acceleration_valid_ = false;
  bool sync_after_launch_ = false;

  DeviceArray<double> u_[3], v_[3], a_[3], div_, mass_;
  DeviceBonds bond_arrays_;
  BondsView bonds_{};

  // crack pairs
  DeviceArray<int> pair_plus_, pair_minus_, pair_crack_;
  DeviceArray<double> pair_nx_, pair_ny_, pair_sx_, pair_sy_, pair_force_;
  DeviceArray<FrictionLaw> laws_;
  DeviceArray<PairState> pair_state_;
  DeviceArray<unsigned long long> pair_counts_;
  CrackPairsView pairs_{};
  DeviceArray<int> inc_particle_, inc_pair_;
  DeviceArray<long long> inc_offset_;
  DeviceArray<unsigned char> inc_plus_;
  PairIncidenceView incidence_{};

  // prescribed displacement sets (histories evaluated on the host each step)
  std::vector<PrescribedSet> prescribed_;
  std::vector<DeviceArray<int>> prescribed_particles_;

  // probes: particles gathered after every step, one pinned buffer read back asynchronously
  std::vector<int> watch_;
  std::unordered_map<int, long long> watch_slot_;
  DeviceArray<int> watch_device_;
  DeviceArray<double> readback_device_;
  double* readback_host_ = nullptr;
  size_t readback_capacity_ = 0;
  long long gathered_ = 0;  // watched particles in the buffer (a later request is read directly)
  bool readback_pending_ = false;
  bool readback_valid_ = false;
};

CudaStepDevice::CudaStepDevice(const Simulation& sim) {
  if (!solver::cuda_device_available())
    throw RunError("CUDA backend: no CUDA device is available (no GPU, or no NVIDIA driver); use --backend cpu");
  check(cudaSetDevice(0), "cudaSetDevice(0)");
  const char* sync = std::getenv("BRECCIA_CUDA_SYNC");
  sync_after_launch_ = sync && std::string(sync) == "1";
  const CaseSpec& spec = sim.spec();
  n_ = static_cast<long long>(sim.size());
  dimension_ = sim.dimension();
  dt_ = sim.dt_s();
  integrator_ = spec.integrator;
  scales_ = sim.scales();
  coeffs_ = sim.coefficients();
  acceleration_valid_ = sim.acceleration_valid();

  static const char* names[3] = {"u", "v", "a"};
  for (int d = 0; d < 3; ++d) {
    u_[d].upload(sim.displacement(d), names[0]);
    v_[d].upload(sim.velocity(d), names[1]);
    a_[d].upload(sim.acceleration(d), names[2]);
  }
  div_.allocate(n_, "div");
  const double rho = spec.material.density_kg_m3;
  std::vector<double> mass(n_);
  for (long long i = 0; i < n_; ++i) mass[i] = rho * sim.volume_m3()[i];  // as the CPU's rho * volume
  mass_.upload(mass, "mass");

  bonds_ = bond_arrays_.upload(sim.bonds());

  const CrackPairs& c = sim.cracks();
  pair_plus_.upload(c.plus, "pair + particles");
  pair_minus_.upload(c.minus, "pair - particles");
  pair_crack_.upload(c.crack, "pair cracks");
  pair_nx_.upload(c.normal_x, "pair normals");
  pair_ny_.upload(c.normal_y, "pair normals");
  pair_sx_.upload(c.tangent_x, "pair tangents");
  pair_sy_.upload(c.tangent_y, "pair tangents");
  laws_.upload(c.law, "friction laws");
  pair_state_.upload(c.state, "pair states");
  pair_force_.allocate(2 * c.size(), "pair forces");
  pair_counts_.upload(std::vector<unsigned long long>{0, 0}, "pair counts");
  pairs_ = {static_cast<long long>(c.size()), pair_plus_.get(), pair_minus_.get(), pair_crack_.get(), pair_nx_.get(),
            pair_ny_.get(), pair_sx_.get(), pair_sy_.get(), laws_.get(), pair_state_.get()};
  const PairIncidence inc = pair_incidence(c);
  inc_particle_.upload(inc.particle, "pair incidence");
  inc_offset_.upload(inc.offset, "pair incidence offsets");
  inc_pair_.upload(inc.pair, "pair incidence pairs");
  inc_plus_.upload(inc.plus_side, "pair incidence sides");
  incidence_ = {static_cast<long long>(inc.particle.size()), inc_particle_.get(), inc_offset_.get(), inc_pair_.get(),
                inc_plus_.get(), mass_.get()};

  prescribed_ = sim.prescribed();
  prescribed_particles_ = std::vector<DeviceArray<int>>(prescribed_.size());
  for (size_t k = 0; k < prescribed_.size(); ++k) prescribed_particles_[k].upload(prescribed_[k].particles, "boundary set");
}

void CudaStepDevice::compute_acceleration() {
  const VectorField u = view(u_), v = view(v_);
  divergence_cuda<<<blocks_for(n_), kBlock>>>(n_, bonds_, u, scales_.gradient, div_.get());
  after_launch("divergence_at");
  elastic_acceleration_cuda<<<blocks_for(n_), kBlock>>>(n_, bonds_, u, div_.get(), scales_, coeffs_, field(a_));
  after_launch("elastic_acceleration_at");
  if (pairs_.count == 0) return;
  check(cudaMemsetAsync(pair_counts_.get(), 0, 2 * sizeof(unsigned long long)), "clearing the pair counts");
  crack_pairs_cuda<<<blocks_for(pairs_.count), kBlock>>>(pairs_, u, v, pair_force_.get(), pair_counts_.get());
  after_launch("crack_pair_force_at");
  add_pair_forces_cuda<<<blocks_for(incidence_.particles), kBlock>>>(incidence_, pair_force_.get(), field(a_));
  after_launch("add_pair_acceleration");
}

void CudaStepDevice::apply_prescribed(double t) {
  launch_prescribed(prescribed_, prescribed_particles_, t, field(u_), field(v_), sync_after_launch_);
}

void CudaStepDevice::step(double t) {
  if (n_ == 0) return;
  const double dt = dt_;
  if (integrator_ == Integrator::SymplecticEuler) {
    compute_acceleration();
    integrate_cuda<Integration::SymplecticEuler>
        <<<blocks_for(n_), kBlock>>>(n_, dimension_, field(u_), field(v_), view(a_), 0.5 * dt, dt);
    after_launch("symplectic_euler_at");
    apply_prescribed(t);
  } else {
    const double half_dt = 0.5 * dt;
    if (!acceleration_valid_) compute_acceleration();
    integrate_cuda<Integration::VerletKickDrift>
        <<<blocks_for(n_), kBlock>>>(n_, dimension_, field(u_), field(v_), view(a_), half_dt, dt);
    after_launch("verlet_kick_drift_at");
    apply_prescribed(t);
    compute_acceleration();
    integrate_cuda<Integration::VerletKick>
        <<<blocks_for(n_), kBlock>>>(n_, dimension_, field(u_), field(v_), view(a_), half_dt, dt);
    after_launch("verlet_kick_at");
    apply_prescribed(t);
    acceleration_valid_ = true;
  }
  launch_readback();
}

// Gather the watched values and pair counts into pinned memory without waiting; the host
// waits only when it reads them (finish_readback), once per step at most.
void CudaStepDevice::launch_readback() {
  readback_valid_ = false;
  const long long count = static_cast<long long>(watch_.size());
  if (count == 0 && pairs_.count == 0) return;
  const size_t values = 6 * watch_.size() + 2;
  if (values > readback_capacity_) {
    finish_readback();  // no copy may be in flight into the buffer being freed
    if (readback_host_) cudaFreeHost(readback_host_);
    readback_host_ = nullptr;
    check(cudaMallocHost(&readback_host_, values * sizeof(double)), "cudaMallocHost of the probe buffer");
    readback_device_.allocate(values, "probe buffer");
    readback_capacity_ = values;
  }
  gather_watch_cuda<<<blocks_for(count > 0 ? count : 1), kBlock>>>(count, watch_device_.get(), view(u_), view(v_),
                                                                  pair_counts_.get(), readback_device_.get());
  after_launch("probe gather");
  gathered_ = count;
  check(cudaMemcpyAsync(readback_host_, readback_device_.get(), values * sizeof(double), cudaMemcpyDeviceToHost),
        "probe read-back");
  readback_pending_ = true;
}

void CudaStepDevice::finish_readback() {
  if (!readback_pending_) return;
  check(cudaStreamSynchronize(0), "waiting for the step");
  readback_pending_ = false;
  readback_valid_ = true;
}

const double* CudaStepDevice::read_counts() {
  finish_readback();
  static const double none[2] = {0.0, 0.0};
  if (!readback_valid_) return none;  // no pairs: nothing gathered
  return readback_host_ + 6 * gathered_;
}

double CudaStepDevice::sample(int particle, int axis, bool velocity) {
  finish_readback();
  const auto it = watch_slot_.find(particle);
  if (it != watch_slot_.end() && readback_valid_ && it->second < gathered_) return readback_host_[6 * it->second + (velocity ? 3 : 0) + axis];
  // First request of this particle: read it directly, and gather it after every later step.
  double value = 0.0;
  const DeviceArray<double>& f = velocity ? v_[axis] : u_[axis];
  check(cudaMemcpy(&value, f.get() + particle, sizeof(double), cudaMemcpyDeviceToHost), "probe value");
  if (it == watch_slot_.end()) {
    watch_slot_[particle] = static_cast<long long>(watch_.size());
    watch_.push_back(particle);
    watch_device_.upload(watch_, "probe particles");
  }
  return value;
}

void CudaStepDevice::download(std::array<std::vector<double>, 3>& u, std::array<std::vector<double>, 3>& v,
                              std::array<std::vector<double>, 3>& a, std::vector<PairState>& pair_states) {
  finish_readback();
  for (int d = 0; d < 3; ++d) {
    u_[d].download(u[d], "u");
    v_[d].download(v[d], "v");
    a_[d].download(a[d], "a");
  }
  pair_state_.download(pair_states, "pair states");
}

}  // namespace

std::unique_ptr<StepDevice> make_cuda_step_device(const Simulation& sim) {
  return std::make_unique<CudaStepDevice>(sim);
}

}  // namespace breccia::mps
