#pragma once
// One MPS run: particles, reference bonds, crack pairs, state, and the time step. step()
// reads like the paper's algorithm: acceleration from eq. (6) (or the Navier form), crack
// friction forces (eqs 9-10), then the integrator (eqs 7-8 or velocity Verlet).
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/crack.hpp"
#include "breccia/mps/neighbours.hpp"
#include "breccia/mps/particles.hpp"

namespace breccia::mps {

// Where Simulation::step runs instead of the OpenMP loops: a device with its own copy of
// u, v, a and the crack-pair states (the CUDA launcher, breccia/mps/cuda_simulation.hpp).
// It runs the same phases in the same order with the same BRECCIA_HD bodies. The host
// arrays are a cache, refreshed by download() only when something reads them; probe values
// and the slipping/open counts come from a small per-step read-back instead.
class StepDevice {
public:
  virtual ~StepDevice() = default;
  // One step of the case's integrator; the prescribed displacements take their values at
  // time_after_s (the end of the step), as Simulation::apply_prescribed does.
  virtual void step(double time_after_s) = 0;
  virtual void download(std::array<std::vector<double>, 3>& u, std::array<std::vector<double>, 3>& v,
                        std::array<std::vector<double>, 3>& a, std::vector<PairState>& pair_states) = 0;
  // The pair states alone (a few hundred bytes: cheap enough for every history row).
  virtual void download_pair_states(std::vector<PairState>& pair_states) = 0;
  // Component `axis` of u (velocity = false) or v of one particle after the last step.
  virtual double sample(int particle, int axis, bool velocity) = 0;
  virtual long long slipping_pairs() = 0;
  virtual long long open_pairs() = 0;
  virtual std::string description() const = 0;  // backend and device, for logs and summary.json
};

class Simulation {
public:
  explicit Simulation(const CaseSpec& spec);

  // Advance one time step (on the attached device, if any).
  void step();
  // Hand the stepping to a device built from this simulation's current state; from then on
  // the host arrays are refreshed from the device when read. Set initial values first:
  // writes through the non-const accessors after attaching do not reach the device.
  void attach_device(std::unique_ptr<StepDevice> device);
  bool on_device() const { return device_ != nullptr; }
  std::string backend_description() const;  // "cpu (OpenMP, N threads)" or the device's
  double time_s() const { return time_s_; }
  long long steps() const { return steps_; }
  double dt_s() const { return dt_s_; }
  double cfl_dt_s() const { return cfl_dt_s_; }
  double spectral_dt_limit_s() const { return spectral_dt_limit_s_; }
  double spacing_m() const { return spacing_m_; }
  size_t size() const { return volume_m3_.size(); }
  int dimension() const { return dimension_; }
  const BondList& bonds() const { return bonds_; }
  const Normalisation& normalisation() const { return norm_; }
  const CrackPairs& cracks() const {  // with a device: its latest pair states, not u and v
    sync_pair_states();
    return pairs_;
  }
  // What a device launcher needs beyond the public state.
  OperatorScales scales() const { return scales_; }
  ElasticCoefficients coefficients() const { return coeffs_; }
  const std::vector<PrescribedSet>& prescribed() const { return prescribed_; }
  bool acceleration_valid() const { return acceleration_valid_; }
  const std::vector<double>& acceleration(int axis) const {
    sync_host();
    return a_[axis];
  }
  const CaseSpec& spec() const { return spec_; }

  const std::vector<double>& position_m() const { return position_m_; }  // 3N reference
  const std::vector<double>& volume_m3() const { return volume_m3_; }
  double thickness_m() const { return thickness_m_; }
  const std::string& particles_content_id() const { return content_id_; }  // "" for a lattice
  const std::vector<double>& displacement(int axis) const {
    sync_host();
    return u_[axis];
  }
  const std::vector<double>& velocity(int axis) const {
    sync_host();
    return v_[axis];
  }
  std::vector<double>& displacement(int axis) {
    sync_host();
    return u_[axis];
  }
  std::vector<double>& velocity(int axis) {
    sync_host();
    return v_[axis];
  }

  double kinetic_energy_j() const;
  double elastic_energy_j() const;  // continuum part (eq. 6 potential) + crack springs in stick
  int nearest_particle(const std::array<double, 3>& p) const;
  // Probe value: field name as in ProbeSpec.
  double sample(int particle, const std::string& field) const;
  double slipping_fraction() const;
  double open_fraction() const;

private:
  void build_particles();
  void build_cracks();
  void build_boundary();
  void choose_time_step();
  void compute_acceleration(bool update_crack_state);
  void apply_prescribed(double t);
  // Refresh the host arrays from the device after it has stepped (no-op without one).
  void sync_host() const;
  void sync_pair_states() const;
  // a = M^-1 K u for the linear part (continuum + crack springs as in stick), for the
  // power iteration that finds the stability limit.
  void linear_operator(const std::array<std::vector<double>, 3>& u, std::array<std::vector<double>, 3>& out,
                       bool with_crack_springs) const;

  CaseSpec spec_;
  int dimension_ = 2;
  double spacing_m_ = 0.0, thickness_m_ = 1.0;
  Periodicity periodic_;
  std::vector<double> position_m_, volume_m3_;
  std::string content_id_;
  std::vector<std::string> set_names_;
  std::vector<std::vector<int64_t>> set_members_;
  BondList bonds_;
  Normalisation norm_;
  OperatorScales scales_;
  ElasticCoefficients coeffs_;
  // mutable: with a device attached these are a cache of its state (sync_host).
  mutable CrackPairs pairs_;
  std::vector<PrescribedSet> prescribed_;
  mutable std::array<std::vector<double>, 3> u_, v_, a_;
  std::vector<double> div_;
  double dt_s_ = 0.0, cfl_dt_s_ = 0.0, spectral_dt_limit_s_ = 0.0;
  double time_s_ = 0.0;
  long long steps_ = 0;
  bool acceleration_valid_ = false;
  std::unique_ptr<StepDevice> device_;
  mutable bool host_current_ = true;   // host arrays hold the device's latest state
  mutable bool pairs_current_ = true;  // host pair states do
};

}  // namespace breccia::mps
