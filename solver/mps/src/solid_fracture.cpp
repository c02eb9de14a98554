// The Solid's side of brittle fracture (fracture.hpp): after the stress update of a step,
// fail particles whose separation stress reaches the strength, cut their bonds, and bring
// the cut stencils up to date so that the forces of the same step already see the crack.
#include "breccia/mps/solid.hpp"

#include "breccia/common/error.hpp"

namespace breccia::mps {

void Solid::set_fracture(const FractureLaw& law) {
  // A stencil rebuild would search the cut bonds' particles again and rejoin the crack.
  if (options_.updated_lagrangian) throw RunError("mps solid: fracture needs total Lagrangian stencils");
  fracture_.emplace(law, bonds_, options_.spacing_m);
}

void Solid::apply_fracture() {
  FractureModel::State state;
  state.displacement = {stencil_displacement(0).data(), stencil_displacement(1).data(), stencil_displacement(2).data()};
  state.volume_m3 = stencil_volume_m3_.data();
  state.stress = stress_.data();
  state.matrices = matrices_.data();
  state.dimension = options_.dimension;
  state.time_s = time_s_;
  std::vector<long long> changed = fracture_->detach_flagged(bonds_);
  refresh_cut_stencils(changed);
  std::vector<long long> cut = fracture_->fail_and_cut(bonds_, state);
  refresh_cut_stencils(cut);
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
  }
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
    moment_inverse_[i] = inverse_moment_matrix_at(i, b, stencil_volume_m3_.data(), options_.dimension, mps_scale);
    double number_density = 0.0;
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) number_density += b.weight[k];
    full_stencil_[i] = number_density >= 0.97 * norm_.number_density_n0;
    if (number_density == 0.0) stress_[i] = SymTensor{};  // a detached particle carries no stress
    const Mat3 h = displacement_gradient_at(i, b, u, stencil_volume_m3_.data(), moment_inverse_[i]);
    Mat3 f = h;
    f(0, 0) += 1.0;
    f(1, 1) += 1.0;
    f(2, 2) += 1.0;
    gradient_[i] = h;
    f_inverse_[i] = det(f) > 0.0 ? inverse(f) : identity3();
    matrices_[i] = force_matrices(stress_[i], gradient_[i], f_inverse_[i], moment_inverse_[i],
                                  matrices_[i].hourglass_stiffness);
  }
}

}  // namespace breccia::mps
