// The CUDA launcher of the MPS stress formulation: Solid::step's substep as launches of the
// BRECCIA_HD phases of solid_phases.hpp over device copies of the state (docs/cuda.md, "MPS").
// No physics is written here: launches, data movement, and the reductions behind the checks
// that Solid makes every kClumpingCheckEvery steps (shortest squeezed bond, clumped bonds).
// Compiled with --fmad=false (CMakeLists.txt), so each particle's arithmetic rounds as on the CPU.
#include <cuda_runtime.h>
#include <thrust/device_ptr.h>
#include <thrust/scan.h>

#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "breccia/common/error.hpp"
#include "breccia/mps/contact_grid.hpp"
#include "breccia/mps/cuda_solid.hpp"
#include "breccia/mps/solid.hpp"
#include "breccia/mps/solid_phases.hpp"
#include "breccia/mps/stability_checks.hpp"
#include "breccia/solver/cuda_device.hpp"
#include "breccia/solver/cuda_memory.cuh"
#include "mps_cuda_common.cuh"

namespace breccia::mps {
namespace {

using cuda::check;
using cuda::DeviceArray;

// Phase 1; inverted particles are flagged and counted (integers: the atomic sum is exact).
__global__ void stress_phase_cuda(long long n, SolidStressInputs in, SolidStressState s, char* inverted_flag,
                                  unsigned long long* inverted) {
  const long long i = thread_index();
  if (i >= n) return;
  const bool folded = stress_phase_at(i, in, s) < 0.0;
  inverted_flag[i] = folded;
  if (folded) atomicAdd(inverted, 1ull);
}

// FractureModel::evaluate's two passes; only the largest value leaves the device. NaN and
// infinities are passed over (the host's candidate test, S >= strength, skips a NaN too), and
// for non-negative doubles the bit patterns order as the values, so atomicMax on them is the
// maximum.
__global__ void separation_parts_cuda(long long n, const SymTensor* stress, const ForceMatrices* matrices,
                                      int dimension, Mat3* tensile, Mat3* compressive, char* tensile_nonzero) {
  const long long i = thread_index();
  if (i < n) separation_parts_at(i, stress, matrices, dimension, tensile, compressive, tensile_nonzero);
}

__global__ void largest_separation_cuda(long long n, SeparationInputs in, unsigned long long* largest_bits) {
  const long long i = thread_index();
  if (i >= n) return;
  const double s = separation_at(i, in).stress_pa;
  if (s > 0.0 && s <= 1.7976931348623157e308)
    atomicMax(largest_bits, static_cast<unsigned long long>(__double_as_longlong(s)));
}

__global__ void pressure_floor_cuda(long long n, BondsView b, const char* full_stencil, const double* pressure,
                                    double* floor) {
  const long long i = thread_index();
  if (i < n) floor[i] = pressure_floor_at(i, b, full_stencil, pressure);
}

// Rigid planes (PlaneContact each) with their friction springs, one per plane and particle
// (plane-major, as Contact keeps them). The sum over the planes starts from zero for every
// particle, as Contact::compute_forces does; each particle keeps its own running total of the
// slip's dissipation and the energy of its springs now (friction_totals sums them).
__global__ void half_spaces_cuda(long long n, int dimension, const double* position, VectorField u, VectorField v,
                                 int planes, const PlaneContact* plane, double dt, FrictionState* springs,
                                 double* dissipated, double* spring_energy, bool onto_pairs, DeviceField contact) {
  const long long i = thread_index();
  if (i >= n) return;
  const double ui[3] = {u.x[i], u.y[i], u.z[i]};
  double x[3];
  for (int a = 0; a < 3; ++a) x[a] = position[3 * i + a] + (a < dimension ? ui[a] : 0.0);
  const double vi[3] = {v.x[i], v.y[i], dimension == 3 ? v.z[i] : 0.0};
  // After the particle pairs' forces when there are any, as Contact::compute_forces adds them.
  double sum[3] = {onto_pairs ? contact.x[i] : 0.0, onto_pairs ? contact.y[i] : 0.0, onto_pairs ? contact.z[i] : 0.0};
  double slip = 0.0, spring = 0.0;
  for (int p = 0; p < planes; ++p) {
    double f[3] = {0.0, 0.0, 0.0};
    if (half_space_contact_at(x, vi, plane[p], dt, springs[p * n + i], f, &slip, &spring) <= 0.0) continue;
    for (int a = 0; a < 3; ++a) sum[a] += f[a];
  }
  contact.x[i] = sum[0];
  contact.y[i] = sum[1];
  contact.z[i] = sum[2];
  dissipated[i] += slip;
  spring_energy[i] = spring;
}

// Particle contact (contact_grid.hpp): current positions, cell and bucket per particle, counted
// per bucket; after the scan each particle is placed in its bucket (the order within a bucket
// does not matter: partners are sorted); surface directions for the distribution normal;
// then each particle gathers its partners and sums its pair forces.
__global__ void contact_cells_cuda(long long n, int dimension, const double* position, VectorField u, double cell_m,
                                   unsigned long long buckets, double* x, long long* cell, unsigned long long* bucket,
                                   int* count) {
  const long long i = thread_index();
  if (i >= n) return;
  x[3 * i] = position[3 * i] + u.x[i];
  x[3 * i + 1] = position[3 * i + 1] + u.y[i];
  x[3 * i + 2] = position[3 * i + 2] + (dimension == 3 ? u.z[i] : 0.0);
  grid_cell_of(&x[3 * i], cell_m, dimension, &cell[3 * i]);
  bucket[i] = grid_bucket(&cell[3 * i], buckets);
  atomicAdd(&count[bucket[i]], 1);
}

__global__ void contact_place_cuda(long long n, const unsigned long long* bucket, const int* start, int* cursor,
                                   int* order) {
  const long long i = thread_index();
  if (i < n) order[start[bucket[i]] + atomicAdd(&cursor[bucket[i]], 1)] = static_cast<int>(i);
}

__global__ void surface_direction_cuda(long long n, BondsView b, const double* x, double* surface) {
  const long long i = thread_index();
  if (i < n) neighbour_distribution_direction(i, b, x, &surface[3 * i]);
}

constexpr int kContactPartners = 64;

__global__ void particle_contact_cuda(long long n, ContactGrid grid, const double* x, BondsView b, double reach,
                                      const double* surface, PairContactParams params, DeviceField contact,
                                      unsigned long long* pairs, unsigned long long* overflow) {
  const long long i = thread_index();
  if (i >= n) return;
  int partners[kContactPartners];
  const int count = contact_partners_at(i, grid, x, b, reach, partners, kContactPartners);
  if (count < 0) atomicAdd(overflow, 1ull);
  double sum[3] = {0.0, 0.0, 0.0};
  long long mine = 0;
  if (count > 0) particle_contact_force_at(i, partners, count, x, surface, params, sum, &mine);
  contact.x[i] = sum[0];
  contact.y[i] = sum[1];
  contact.z[i] = sum[2];
  if (mine > 0) atomicAdd(pairs, static_cast<unsigned long long>(mine));
}

__global__ void acceleration_cuda(long long n, SolidAccelerationInputs in, DeviceField a) {
  const long long i = thread_index();
  if (i < n) solid_acceleration_at(i, in, a.x, a.y, a.z);
}

// For non-negative doubles the IEEE bit patterns order as the values do, so atomicMin on
// them is a minimum of the lengths.
__global__ void shortest_bond_cuda(long long n, BondsView b, VectorField u, VectorField v, double window_s,
                                   double spacing_m, unsigned long long* shortest_bits) {
  const long long i = thread_index();
  if (i >= n) return;
  double shortest = spacing_m;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    if (b.weight[k] == 0.0) continue;  // cut: carries no force
    const long long j = b.neighbour[k];
    const double r[3] = {b.rx[k], b.ry[k], b.rz[k]};
    const double d[3] = {r[0] + u.x[j] - u.x[i], r[1] + u.y[j] - u.y[i], r[2] + u.z[j] - u.z[i]};
    const double w[3] = {v.x[j] - v.x[i], v.y[j] - v.y[i], v.z[j] - v.z[i]};
    const double length = squeezed_bond_length(r, d, w, window_s, spacing_m, false);
    shortest = length < shortest ? length : shortest;  // NaN is passed over, as std::min does
  }
  atomicMin(shortest_bits, static_cast<unsigned long long>(__double_as_longlong(shortest)));
}

__global__ void crack_face_cuda(long long n, BondsView b, double near_m, char* on_face) {
  const long long i = thread_index();
  if (i < n) on_face[i] = on_crack_face_at(i, b, near_m);
}

// measure_clumping's count (stability_checks.cpp): bonds below the ratio, NaN included, not
// counting bonds between two crack-face particles.
__global__ void clumping_cuda(long long n, BondsView b, VectorField u, const Mat3* gradient, double near_m,
                              const char* on_face, unsigned long long* clumped) {
  const long long i = thread_index();
  if (i >= n) return;
  unsigned long long count = 0;
  for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) {
    double ratio = 1.0;
    if (!clumping_ratio(b, i, k, u, gradient[i], near_m, &ratio)) continue;
    if (on_face[i] && on_face[b.neighbour[k]]) continue;
    if (!(ratio >= kMinNeighbourDistanceRatio)) ++count;
  }
  if (count > 0) atomicAdd(clumped, count);
}

class CudaSolidDevice final : public SolidStepDevice {
public:
  explicit CudaSolidDevice(const Solid& solid);
  void stress_phase() override;
  void motion_phase(double dt, double time_after_s) override;
  long long inverted_particles() override {
    if (particle_contact_ && take_counter(kOverflow) > 0)
      throw RunError("mps solid: a particle found more than " + std::to_string(kContactPartners) +
                     " contact partners on the GPU (particles crushed together; the CPU has no such limit): "
                     "use --backend cpu");
    return take_counter(kInverted);
  }
  void inverted_flags(std::vector<char>& flags) override { inverted_flag_.download(flags, "inverted flags"); }
  double largest_separation_pa() override;
  void upload_cut(const SolidCutState& host, const std::vector<long long>& particles) override;
  double shortest_squeezed_bond_m(double window_s) override;
  long long clumped_bonds() override;
  void friction_totals(double* spring_energy_j, double* dissipated_j) override;
  long long contact_pairs() override { return particle_contact_ ? read_counter(kPairs) : 0; }
  void download(const SolidHostState& host, bool kinematics_only) override;
  std::string description() const override { return "cuda (" + solver::cuda_device_description() + ")"; }

private:
  enum Counter { kInverted = 0, kClumped = 1, kShortest = 2, kSeparation = 3, kPairs = 4, kOverflow = 5 };
  void particle_contact_forces();
  void after_launch(const char* kernel) const { cuda::check_launch(kernel, sync_after_launch_); }
  long long take_counter(Counter c);  // waits, reads, resets
  long long read_counter(Counter c);  // waits, reads
  DeviceField field(DeviceArray<double>* f) const { return {f[0].get(), f[1].get(), f[2].get()}; }
  VectorField view(const DeviceArray<double>* f) const { return {f[0].get(), f[1].get(), f[2].get()}; }

  long long n_ = 0;
  int dimension_ = 3;
  double spacing_m_ = 0.0;
  bool sync_after_launch_ = false;
  bool repulsive_ = false;
  int planes_ = 0;
  SolidStressInputs stress_in_{};
  SolidStressState state_{};
  SolidAccelerationInputs accel_in_{};

  DeviceArray<double> u_[3], v_[3], a_[3], external_[3], contact_[3];
  DeviceArray<double> position_, volume_, stencil_volume_, stress_work_, eq_plastic_, pressure_, pressure_floor_;
  DeviceArray<PlaneContact> plane_;
  DeviceArray<FrictionState> springs_;
  DeviceArray<double> dissipated_, spring_energy_;
  double dissipated_before_j_ = 0.0;  // by the solid before the device was built
  // Particle contact (contact_grid.hpp).
  bool particle_contact_ = false;
  PairContactParams pair_params_{};
  unsigned long long buckets_ = 1;
  DeviceArray<double> contact_x_, surface_;
  DeviceArray<long long> cell_;
  DeviceArray<unsigned long long> bucket_;
  DeviceArray<int> bucket_count_, bucket_start_, bucket_cursor_, order_;
  DeviceArray<Mat3> gradient_, f_inverse_, moment_inverse_;
  DeviceArray<SymTensor> stress_;
  DeviceArray<ForceMatrices> matrices_;
  DeviceArray<char> full_stencil_, on_face_, inverted_flag_;
  // Fracture only: the separation's per-particle parts (fracture.hpp, SeparationInputs).
  DeviceArray<Mat3> tensile_, compressive_;
  DeviceArray<char> tensile_nonzero_;
  SeparationInputs separation_in_{};
  DeviceBonds bond_arrays_;
  BondsView bonds_{};
  DeviceArray<unsigned long long> counters_;
  std::vector<PrescribedSet> prescribed_;
  std::vector<DeviceArray<int>> prescribed_particles_;
};

CudaSolidDevice::CudaSolidDevice(const Solid& solid) {
  if (!solver::cuda_device_available())
    throw RunError("CUDA backend: no CUDA device is available (no GPU, or no NVIDIA driver); use --backend cpu");
  check(cudaSetDevice(0), "cudaSetDevice(0)");
  const char* sync = std::getenv("BRECCIA_CUDA_SYNC");
  sync_after_launch_ = sync && std::string(sync) == "1";
  n_ = static_cast<long long>(solid.size());
  dimension_ = solid.dimension();
  spacing_m_ = solid.spacing_m();
  repulsive_ = solid.options().pressure == PressureForce::Repulsive;

  static const char* names[3] = {"u", "v", "external force"};
  for (int d = 0; d < 3; ++d) {
    u_[d].upload(solid.displacement(d), names[0]);
    v_[d].upload(solid.velocity(d), names[1]);
    external_[d].upload(solid.external_force_n(d), names[2]);
    a_[d].upload(std::vector<double>(n_, 0.0), "a");
    contact_[d].upload(std::vector<double>(n_, 0.0), "contact force");
  }
  position_.upload(solid.position_m(), "positions");
  volume_.upload(solid.volume_m3(), "volumes");
  stencil_volume_.upload(solid.stencil_volume_m3(), "stencil volumes");
  stress_work_.upload(solid.stress_work_of_particles_j(), "stress work");
  eq_plastic_.upload(solid.eq_plastic_strain(), "plastic strain");
  pressure_.upload(std::vector<double>(n_, 0.0), "pressure");
  pressure_floor_.upload(std::vector<double>(n_, 0.0), "pressure floor");
  gradient_.upload(solid.displacement_gradient(), "gradients");
  f_inverse_.upload(solid.f_inverse(), "F^-1");
  moment_inverse_.upload(solid.moment_inverse(), "moment matrices");
  stress_.upload(solid.stress_pa(), "stress");
  matrices_.upload(solid.force_matrices_of_particles(), "force matrices");
  full_stencil_.upload(solid.full_stencil(), "surface flags");
  on_face_.allocate(n_, "crack-face flags");
  inverted_flag_.upload(std::vector<char>(n_, 0), "inverted flags");

  bonds_ = bond_arrays_.upload(solid.bonds());

  std::vector<PlaneContact> planes;
  for (const HalfSpace& h : solid.contact().half_spaces()) planes.push_back(plane_contact(h));
  planes_ = static_cast<int>(planes.size());
  plane_.upload(planes, "rigid planes");
  // The springs carry on from the host's (Contact keeps the planes' first; empty before any step).
  const std::vector<FrictionState>& host_springs = solid.contact().obstacle_springs();
  const size_t springs = static_cast<size_t>(planes_) * n_;
  springs_.upload(host_springs.size() >= springs
                      ? std::vector<FrictionState>(host_springs.begin(), host_springs.begin() + springs)
                      : std::vector<FrictionState>(springs),
                  "friction springs");
  dissipated_.upload(std::vector<double>(planes_ > 0 ? n_ : 0, 0.0), "friction dissipation");
  spring_energy_.upload(std::vector<double>(planes_ > 0 ? n_ : 0, 0.0), "friction spring energy");
  dissipated_before_j_ = solid.contact().friction_dissipation_j();
  counters_.upload(std::vector<unsigned long long>(6, 0), "counters");
  particle_contact_ = solid.contact().particle_contact();
  if (particle_contact_) {
    pair_params_ = solid.contact().pair_params();
    while (buckets_ < 2ull * static_cast<unsigned long long>(n_)) buckets_ *= 2;
    contact_x_.allocate(3 * n_, "contact positions");
    cell_.allocate(3 * n_, "contact cells");
    bucket_.allocate(n_, "contact buckets");
    bucket_count_.allocate(buckets_ + 1, "contact bucket counts");
    bucket_start_.allocate(buckets_ + 1, "contact bucket offsets");
    bucket_cursor_.allocate(buckets_, "contact bucket cursors");
    order_.allocate(n_, "contact order");
    if (pair_params_.distribution) surface_.allocate(3 * n_, "surface directions");
  }

  prescribed_ = solid.prescribed();
  prescribed_particles_ = std::vector<DeviceArray<int>>(prescribed_.size());
  for (size_t k = 0; k < prescribed_.size(); ++k) prescribed_particles_[k].upload(prescribed_[k].particles, "boundary set");

  // The inputs of the phases, as Solid::compute_acceleration fills them.
  const VectorField u = view(u_);
  stress_in_.bonds = bonds_;
  stress_in_.u = u;
  stress_in_.volume_m3 = stencil_volume_.get();
  stress_in_.moment_inverse = moment_inverse_.get();
  stress_in_.law = solid.law();
  stress_in_.dimension = dimension_;
  stress_in_.hourglass_stiffness = solid.hourglass_stiffness();
  state_ = {gradient_.get(), f_inverse_.get(), stress_.get(), eq_plastic_.get(), stress_work_.get(), pressure_.get(),
            matrices_.get()};
  accel_in_.forces.bonds = bonds_;
  accel_in_.forces.u = u;
  accel_in_.forces.matrices = matrices_.get();
  accel_in_.forces.pressure_floor_pa = repulsive_ ? pressure_floor_.get() : nullptr;
  accel_in_.forces.volume_m3 = stencil_volume_.get();
  for (int d = 0; d < 3; ++d) {
    accel_in_.external_n[d] = external_[d].get();
    accel_in_.contact_n[d] = planes_ > 0 || particle_contact_ ? contact_[d].get() : nullptr;
    accel_in_.gravity_m_s2[d] = solid.options().gravity_m_s2[d];
  }
  accel_in_.v = view(v_);
  accel_in_.volume_m3 = volume_.get();
  accel_in_.density_kg_m3 = solid.density_kg_m3();
  accel_in_.damping_per_s = solid.options().damping_per_s;
  accel_in_.dimension = dimension_;
  if (solid.fracture()) {
    tensile_.allocate(n_, "separation (tensile part)");
    compressive_.allocate(n_, "separation (compressive part)");
    tensile_nonzero_.allocate(n_, "separation (tension flags)");
    separation_in_.bonds = bonds_;
    separation_in_.volume_m3 = stencil_volume_.get();
    separation_in_.tensile = tensile_.get();
    separation_in_.compressive = compressive_.get();
    separation_in_.matrices = matrices_.get();
    separation_in_.tensile_nonzero = tensile_nonzero_.get();
    separation_in_.dimension = dimension_;
  }
}

void CudaSolidDevice::stress_phase() {
  if (n_ == 0) return;
  stress_phase_cuda<<<blocks_for(n_), kBlock>>>(n_, stress_in_, state_, inverted_flag_.get(),
                                                counters_.get() + kInverted);
  after_launch("stress_phase_at");
}

void CudaSolidDevice::motion_phase(double dt, double time_after_s) {
  if (n_ == 0) return;
  const long long blocks = blocks_for(n_);
  if (repulsive_) {
    pressure_floor_cuda<<<blocks, kBlock>>>(n_, bonds_, full_stencil_.get(), pressure_.get(), pressure_floor_.get());
    after_launch("pressure_floor_at");
  }
  if (particle_contact_) particle_contact_forces();
  if (planes_ > 0) {
    half_spaces_cuda<<<blocks, kBlock>>>(n_, dimension_, position_.get(), view(u_), view(v_), planes_, plane_.get(), dt,
                                         springs_.get(), dissipated_.get(), spring_energy_.get(), particle_contact_,
                                         field(contact_));
    after_launch("half_space_force_at");
  }
  acceleration_cuda<<<blocks, kBlock>>>(n_, accel_in_, field(a_));
  after_launch("solid_acceleration_at");
  integrate_cuda<Integration::SymplecticEuler>
      <<<blocks, kBlock>>>(n_, dimension_, field(u_), field(v_), view(a_), 0.5 * dt, dt);
  after_launch("symplectic_euler_at");
  launch_prescribed(prescribed_, prescribed_particles_, time_after_s, field(u_), field(v_), sync_after_launch_);
}

void CudaSolidDevice::particle_contact_forces() {
  const long long blocks = blocks_for(n_);
  const double reach = pair_search_radius(pair_params_);
  check(cudaMemset(bucket_count_.get(), 0, (buckets_ + 1) * sizeof(int)), "clearing contact buckets");
  check(cudaMemset(bucket_cursor_.get(), 0, buckets_ * sizeof(int)), "clearing contact cursors");
  check(cudaMemset(counters_.get() + kPairs, 0, sizeof(unsigned long long)), "clearing a counter");
  contact_cells_cuda<<<blocks, kBlock>>>(n_, dimension_, position_.get(), view(u_), reach, buckets_, contact_x_.get(),
                                         cell_.get(), bucket_.get(), bucket_count_.get());
  after_launch("grid_cell_of");
  // start[b] = sum of the counts before b (the extra last count is 0, so start[buckets] = n).
  thrust::exclusive_scan(thrust::device_ptr<int>(bucket_count_.get()),
                         thrust::device_ptr<int>(bucket_count_.get() + buckets_ + 1),
                         thrust::device_ptr<int>(bucket_start_.get()));
  after_launch("exclusive_scan of the contact buckets");
  contact_place_cuda<<<blocks, kBlock>>>(n_, bucket_.get(), bucket_start_.get(), bucket_cursor_.get(), order_.get());
  after_launch("contact_place");
  if (pair_params_.distribution) {
    surface_direction_cuda<<<blocks, kBlock>>>(n_, bonds_, contact_x_.get(), surface_.get());
    after_launch("neighbour_distribution_direction");
  }
  ContactGrid grid;
  grid.cell_m = reach;
  grid.buckets = buckets_;
  grid.dimension = dimension_;
  grid.cell = cell_.get();
  grid.start = bucket_start_.get();
  grid.order = order_.get();
  particle_contact_cuda<<<blocks, kBlock>>>(n_, grid, contact_x_.get(), bonds_, reach, surface_.get(), pair_params_,
                                            field(contact_), counters_.get() + kPairs, counters_.get() + kOverflow);
  after_launch("particle_contact_force_at");
}

double CudaSolidDevice::largest_separation_pa() {
  if (n_ == 0 || !tensile_.get()) return 0.0;
  const long long blocks = blocks_for(n_);
  separation_parts_cuda<<<blocks, kBlock>>>(n_, stress_.get(), matrices_.get(), dimension_, tensile_.get(),
                                            compressive_.get(), tensile_nonzero_.get());
  after_launch("separation_parts_at");
  largest_separation_cuda<<<blocks, kBlock>>>(n_, separation_in_, counters_.get() + kSeparation);
  after_launch("separation_at");
  const long long bits = take_counter(kSeparation);
  double largest = 0.0;
  std::memcpy(&largest, &bits, sizeof largest);
  return largest;
}

// A few particles per cutting substep: one small copy per array and particle (their CSR rows
// of bond weights, their stencil state) is cheaper than moving the arrays.
void CudaSolidDevice::upload_cut(const SolidCutState& host, const std::vector<long long>& particles) {
  const BondList& b = *host.bonds;
  auto put = [](auto* device, const auto& host_array, long long i, long long count, const char* what) {
    check(cudaMemcpy(device + i, host_array.data() + i, count * sizeof host_array[0], cudaMemcpyHostToDevice), what);
  };
  for (long long i : particles) {
    put(bond_arrays_.weight.get(), b.weight, b.offset[i], b.offset[i + 1] - b.offset[i], "uploading cut bond weights");
    put(moment_inverse_.get(), *host.moment_inverse, i, 1, "uploading a cut stencil (moment matrix)");
    put(full_stencil_.get(), *host.full_stencil, i, 1, "uploading a cut stencil (surface flag)");
    put(gradient_.get(), *host.gradient, i, 1, "uploading a cut stencil (gradient)");
    put(f_inverse_.get(), *host.f_inverse, i, 1, "uploading a cut stencil (F^-1)");
    put(stress_.get(), *host.stress, i, 1, "uploading a cut stencil (stress)");
    put(matrices_.get(), *host.matrices, i, 1, "uploading a cut stencil (force matrices)");
  }
}

long long CudaSolidDevice::read_counter(Counter c) {
  unsigned long long value = 0;
  check(cudaMemcpy(&value, counters_.get() + c, sizeof value, cudaMemcpyDeviceToHost), "reading a counter");
  return static_cast<long long>(value);
}

long long CudaSolidDevice::take_counter(Counter c) {
  const long long value = read_counter(c);
  check(cudaMemset(counters_.get() + c, 0, sizeof(unsigned long long)), "clearing a counter");
  return value;
}

double CudaSolidDevice::shortest_squeezed_bond_m(double window_s) {
  unsigned long long start = 0;
  std::memcpy(&start, &spacing_m_, sizeof start);
  check(cudaMemcpy(counters_.get() + kShortest, &start, sizeof start, cudaMemcpyHostToDevice), "setting a counter");
  if (n_ > 0) {
    shortest_bond_cuda<<<blocks_for(n_), kBlock>>>(n_, bonds_, view(u_), view(v_), window_s, spacing_m_,
                                                   counters_.get() + kShortest);
    after_launch("squeezed_bond_length");
  }
  unsigned long long bits = 0;
  check(cudaMemcpy(&bits, counters_.get() + kShortest, sizeof bits, cudaMemcpyDeviceToHost), "reading a counter");
  double shortest = 0.0;
  std::memcpy(&shortest, &bits, sizeof shortest);
  return shortest;
}

long long CudaSolidDevice::clumped_bonds() {
  if (n_ == 0) return 0;
  const double near = 1.5 * spacing_m_;  // as measure_clumping
  crack_face_cuda<<<blocks_for(n_), kBlock>>>(n_, bonds_, near, on_face_.get());
  after_launch("on_crack_face_at");
  clumping_cuda<<<blocks_for(n_), kBlock>>>(n_, bonds_, view(u_), gradient_.get(), near, on_face_.get(),
                                            counters_.get() + kClumped);
  after_launch("clumping_ratio");
  return take_counter(kClumped);
}

// Summed on the host in particle order (a few MB per call; read with the history rows).
void CudaSolidDevice::friction_totals(double* spring_energy_j, double* dissipated_j) {
  *spring_energy_j = 0.0;
  *dissipated_j = dissipated_before_j_;
  if (planes_ == 0) return;
  std::vector<double> values;
  spring_energy_.download(values, "friction spring energy");
  for (double e : values) *spring_energy_j += e;
  dissipated_.download(values, "friction dissipation");
  for (double d : values) *dissipated_j += d;
}

void CudaSolidDevice::download(const SolidHostState& host, bool kinematics_only) {
  for (int d = 0; d < 3; ++d) {
    u_[d].download((*host.u)[d], "u");
    v_[d].download((*host.v)[d], "v");
  }
  if (kinematics_only) return;
  gradient_.download(*host.gradient, "gradients");
  f_inverse_.download(*host.f_inverse, "F^-1");
  stress_.download(*host.stress, "stress");
  eq_plastic_.download(*host.eq_plastic_strain, "plastic strain");
  stress_work_.download(*host.stress_work_j, "stress work");
  matrices_.download(*host.matrices, "force matrices");
}

}  // namespace

std::unique_ptr<SolidStepDevice> make_cuda_solid_device(const Solid& solid) {
  return std::make_unique<CudaSolidDevice>(solid);
}

}  // namespace breccia::mps
