// The Solid's side of brittle fracture (fracture.hpp): after the stress update of a step,
// fail particles whose separation stress reaches the strength, cut their bonds, and bring
// the cut stencils up to date so that the forces of the same step already see the crack.
#include "breccia/mps/solid.hpp"

namespace breccia::mps {

void Solid::set_fracture(const FractureLaw& law) {
  fracture_.emplace(law, bonds_, options_.spacing_m);
}

void Solid::apply_fracture() {
  FractureModel::State state;
  state.displacement = {u_[0].data(), u_[1].data(), u_[2].data()};
  state.volume_m3 = volume_m3_.data();
  state.stress = stress_.data();
  state.matrices = matrices_.data();
  state.dimension = options_.dimension;
  state.time_s = time_s_;
  refresh_cut_stencils(fracture_->detach_flagged(bonds_));
  refresh_cut_stencils(fracture_->fail_and_cut(bonds_, state));
}

void Solid::refresh_cut_stencils(const std::vector<long long>& changed) {
  // A particle that lost bonds gets the moment matrix of its remaining stencil, and its
  // gradient is re-measured on that stencil at the current displacement, so that the next
  // step's increment H_new - H_old compares like with like (otherwise the change of
  // stencil would enter the stress as a spurious strain increment). The stress itself is
  // kept: the crack faces unload through the equation of motion, as a free surface does.
  const BondsView b = bonds_.view();
  const VectorField u{u_[0].data(), u_[1].data(), u_[2].data()};
  const double mps_scale = options_.dimension / norm_.number_density_n0;
  for (long long i : changed) {
    moment_inverse_[i] = inverse_moment_matrix_at(i, b, volume_m3_.data(), options_.dimension, mps_scale);
    double number_density = 0.0;
    for (long long k = b.offset[i]; k < b.offset[i + 1]; ++k) number_density += b.weight[k];
    full_stencil_[i] = number_density >= 0.97 * norm_.number_density_n0;
    if (number_density == 0.0) stress_[i] = SymTensor{};  // a detached particle carries no stress
    const Mat3 h = displacement_gradient_at(i, b, u, volume_m3_.data(), moment_inverse_[i]);
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
