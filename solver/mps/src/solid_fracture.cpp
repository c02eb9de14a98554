// The Solid's side of brittle fracture (fracture.hpp): after the stress update of a step,
// fail particles whose separation stress reaches the strength, cut their bonds, and bring
// the cut stencils up to date so that the forces of the same step already see the crack.
#include "breccia/mps/solid.hpp"

#include <algorithm>

#include "breccia/common/error.hpp"

namespace breccia::mps {

void Solid::set_fracture(const FractureLaw& law) {
  // A stencil rebuild would search the cut bonds' particles again and rejoin the crack.
  if (options_.updated_lagrangian) throw RunError("mps solid: fracture needs total Lagrangian stencils");
  fracture_.emplace(law, bonds_, options_.spacing_m);
}

FractureModel::State Solid::fracture_state() const {
  FractureModel::State state;
  state.displacement = {stencil_displacement(0).data(), stencil_displacement(1).data(), stencil_displacement(2).data()};
  state.volume_m3 = stencil_volume_m3_.data();
  state.stress = stress_.data();
  state.matrices = matrices_.data();
  state.dimension = options_.dimension;
  state.time_s = time_s_;
  return state;
}

std::vector<long long> Solid::apply_fracture() {
  const FractureModel::State state = fracture_state();
  std::vector<long long> all;
  std::vector<long long> changed = fracture_->detach_flagged(bonds_);
  refresh_cut_stencils(changed);
  all.insert(all.end(), changed.begin(), changed.end());
  std::vector<long long> cut = fracture_->fail_and_cut(bonds_, state);
  refresh_cut_stencils(cut);
  all.insert(all.end(), cut.begin(), cut.end());
  changed.insert(changed.end(), cut.begin(), cut.end());
  // Remnant stencils left by this step's cuts are detached now, before the forces use them;
  // detaching one may leave a neighbour a remnant in turn, so repeat on what changed.
  for (int pass = 0; pass < 8 && !changed.empty(); ++pass) {
    bool any = false;
    for (long long i : changed)
      any = fracture_->absorb_remnant(i, bonds_, stencil_volume_m3_.data(), options_.dimension) || any;
    if (!any) break;
    changed = fracture_->detach_flagged(bonds_);
    refresh_cut_stencils(changed);
    all.insert(all.end(), changed.begin(), changed.end());
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

// Device path. An inverted particle that fracture takes as debris is left unchanged by the
// stress phase, as on the CPU, and detached by the next apply_fracture; any other stops the
// run with the CPU's message (the time before the substep, as compute_acceleration names it).
void Solid::absorb_inverted_on_device(long long inverted) {
  if (fracture_) {
    std::vector<char> flags;
    device_->inverted_flags(flags);
    inverted = 0;
    for (size_t i = 0; i < flags.size(); ++i)
      if (flags[i] && !fracture_->absorb_inversion(static_cast<long long>(i), bonds_)) ++inverted;
  }
  if (inverted > 0) throw_inverted(inverted, time_s_);
}

// The cutting is host code (rare, irregular, in order of load). The device only says whether
// some particle reached the strength; on those substeps (and when debris waits to be
// detached) the state comes to the host, apply_fracture runs on it exactly as on the CPU,
// and what it changed goes back. Other substeps move no data.
void Solid::fracture_on_device() {
  if (!fracture_->has_flagged() && !(device_->largest_separation_pa() >= fracture_->law().tensile_strength_pa)) {
    separation_current_ = false;
    return;
  }
  sync_host(false);
  const std::vector<long long> changed = apply_fracture();
  separation_current_ = true;
  if (changed.empty()) return;
  SolidCutState cut;
  cut.bonds = &bonds_;
  cut.moment_inverse = &moment_inverse_;
  cut.full_stencil = &full_stencil_;
  cut.gradient = &gradient_;
  cut.f_inverse = &f_inverse_;
  cut.stress = &stress_;
  cut.matrices = &matrices_;
  device_->upload_cut(cut, changed);
}

// The separation values the CPU would show: FractureModel::evaluate on the downloaded state of
// the last stress phase (the motion phase changes neither stress nor force matrices).
void Solid::sync_fracture() const {
  if (!fracture_ || !device_ || separation_current_) return;
  sync_host(false);
  fracture_->evaluate(bonds_, fracture_state());
  separation_current_ = true;
}

void Solid::refresh_cut_stencils(const std::vector<long long>& changed) {
  // A particle that lost bonds gets the moment matrix of its remaining stencil, and its
  // gradient is re-measured on that stencil at the current displacement, so that the next
  // step's increment H_new - H_old compares like with like (otherwise the change of
  // stencil would enter the stress as a spurious strain increment). The stress itself is
  // kept: the crack faces unload through the equation of motion, as a free surface does.
  const BondsView b = bonds_.view();
  const VectorField u{stencil_displacement(0).data(), stencil_displacement(1).data(), stencil_displacement(2).data()};
  const double mps_scale = options_.dimension / norm_.number_density_n0;
  for (long long i : changed) {
    refresh_bond_coefficients(i);
    moment_inverse_[i] = inverse_moment_matrix_at(i, b, stencil_volume_m3_.data(), options_.dimension, mps_scale);
    double number_density = 0.0;
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) number_density += b.weight[k];
    full_stencil_[i] = number_density >= 0.97 * norm_.number_density_n0;
    if (number_density == 0.0) stress_[i] = SymTensor{};  // a detached particle carries no stress
    const Mat3 h = displacement_gradient_at(i, b, u, stencil_volume_m3_.data(), moment_inverse_[i], options_.dimension,
                                            bond_coefficient_.data());
    const Mat3 f = deformation_gradient(h);
    gradient_[i] = h;
    f_inverse_[i] = det(f, options_.dimension) > 0.0 ? inverse(f, options_.dimension) : identity3();
    matrices_[i] = force_matrices(stress_in_force(i), gradient_[i], f_inverse_[i], moment_inverse_[i],
                                  matrices_[i].hourglass_stiffness, options_.dimension);
  }
}

}  // namespace breccia::mps
