#pragma once
// One MPS run: particles, reference bonds, crack pairs, state, and the time step. step()
// reads like the paper's algorithm: acceleration from eq. (6) (or the Navier form), crack
// friction forces (eqs 9-10), then the integrator (eqs 7-8 or velocity Verlet).
#include <array>
#include <string>
#include <vector>

#include "breccia/mps/case_spec.hpp"
#include "breccia/mps/crack.hpp"
#include "breccia/mps/neighbours.hpp"
#include "breccia/mps/particles.hpp"

namespace breccia::mps {

class Simulation {
public:
  explicit Simulation(const CaseSpec& spec);

  // Advance one time step.
  void step();
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
  const CrackPairs& cracks() const { return pairs_; }
  const CaseSpec& spec() const { return spec_; }

  const std::vector<double>& position_m() const { return position_m_; }  // 3N reference
  const std::vector<double>& volume_m3() const { return volume_m3_; }
  double thickness_m() const { return thickness_m_; }
  const std::string& particles_content_id() const { return content_id_; }  // "" for a lattice
  const std::vector<double>& displacement(int axis) const { return u_[axis]; }
  const std::vector<double>& velocity(int axis) const { return v_[axis]; }
  std::vector<double>& displacement(int axis) { return u_[axis]; }
  std::vector<double>& velocity(int axis) { return v_[axis]; }

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
  CrackPairs pairs_;
  std::vector<PrescribedSet> prescribed_;
  std::array<std::vector<double>, 3> u_, v_, a_;
  std::vector<double> div_;
  double dt_s_ = 0.0, cfl_dt_s_ = 0.0, spectral_dt_limit_s_ = 0.0;
  double time_s_ = 0.0;
  long long steps_ = 0;
  bool acceleration_valid_ = false;
};

}  // namespace breccia::mps
