#pragma once
// Small-strain, rate-independent J2 (von Mises) plasticity with linear isotropic
// ("bilinear") hardening, integrated by the backward-Euler radial return (Simo & Hughes
// 1998, Computational Inelasticity, box 3.1; de Souza Neto, Peric & Owen 2008, sec. 7.3.2).
// Used by the stress-based MPS solid (solid.hpp) on the co-rotated stress, one particle
// at a time. Plain data and BRECCIA_HD inline functions, so a CUDA launcher calls the
// same bodies as the OpenMP loop.
#include <cmath>

#include "breccia/mps/kernels.hpp"  // BRECCIA_HD

namespace breccia::mps {

// Symmetric 3x3 tensor (stress or strain, tensor shear components, not Voigt doubled).
struct SymTensor {
  double xx = 0.0, yy = 0.0, zz = 0.0, xy = 0.0, yz = 0.0, zx = 0.0;
};

BRECCIA_HD inline double trace(const SymTensor& t) { return t.xx + t.yy + t.zz; }

// s:s of the deviator of t.
BRECCIA_HD inline double deviator_norm2(const SymTensor& t) {
  const double m = trace(t) / 3.0;
  const double dx = t.xx - m, dy = t.yy - m, dz = t.zz - m;
  return dx * dx + dy * dy + dz * dz + 2.0 * (t.xy * t.xy + t.yz * t.yz + t.zx * t.zx);
}

// q = sqrt(3/2 s:s), the von Mises equivalent stress.
BRECCIA_HD inline double von_mises_stress(const SymTensor& t) { return std::sqrt(1.5 * deviator_norm2(t)); }

// Pressure p = -tr(sigma)/3 (positive in compression).
BRECCIA_HD inline double pressure_of(const SymTensor& t) { return -trace(t) / 3.0; }

// Isotropic Hooke increment: d sigma = lambda tr(d eps) I + 2 mu d eps.
BRECCIA_HD inline void add_hooke_increment(SymTensor& stress, const SymTensor& strain_increment, double lame_lambda_pa,
                                           double shear_modulus_pa) {
  const double vol = lame_lambda_pa * trace(strain_increment);
  const double two_mu = 2.0 * shear_modulus_pa;
  stress.xx += vol + two_mu * strain_increment.xx;
  stress.yy += vol + two_mu * strain_increment.yy;
  stress.zz += vol + two_mu * strain_increment.zz;
  stress.xy += two_mu * strain_increment.xy;
  stress.yz += two_mu * strain_increment.yz;
  stress.zx += two_mu * strain_increment.zx;
}

// Yield function f = q - (sigma_y0 + H eps_p), eps_p the equivalent plastic strain.
// hardening_modulus_pa is H = d sigma_y / d eps_p (the plastic modulus; the elasto-plastic
// tangent of a uniaxial stress test is E H / (E + H)).
struct VonMisesHardening {
  double shear_modulus_pa = 0.0;
  double yield_stress_pa = 0.0;      // initial uniaxial yield stress sigma_y0 > 0
  double hardening_modulus_pa = 0.0; // H >= 0 (0: perfectly plastic)

  BRECCIA_HD double yield_stress_at(double eq_plastic_strain) const {
    return yield_stress_pa + hardening_modulus_pa * eq_plastic_strain;
  }
};

// Backward-Euler radial return. `stress` holds the elastic trial stress on entry and the
// returned stress on exit; eq_plastic_strain is advanced. Returns the plastic multiplier
// increment delta_gamma (= increment of the equivalent plastic strain; 0 when elastic).
// With linear hardening the consistency condition is linear in delta_gamma, so the return
// is closed-form (no iteration):
//   delta_gamma = f_trial / (3 mu + H),   s = (1 - 3 mu delta_gamma / q_trial) s_trial,
// the pressure is untouched (plastic flow is isochoric) and after the return
// q = sigma_y0 + H (eps_p + delta_gamma) exactly.
BRECCIA_HD inline double radial_return(const VonMisesHardening& m, SymTensor& stress, double& eq_plastic_strain) {
  const double q_trial = von_mises_stress(stress);
  const double f_trial = q_trial - m.yield_stress_at(eq_plastic_strain);
  if (f_trial <= 0.0) return 0.0;
  const double delta_gamma = f_trial / (3.0 * m.shear_modulus_pa + m.hardening_modulus_pa);
  const double scale = 1.0 - 3.0 * m.shear_modulus_pa * delta_gamma / q_trial;
  const double mean = trace(stress) / 3.0;
  stress.xx = mean + scale * (stress.xx - mean);
  stress.yy = mean + scale * (stress.yy - mean);
  stress.zz = mean + scale * (stress.zz - mean);
  stress.xy *= scale;
  stress.yz *= scale;
  stress.zx *= scale;
  eq_plastic_strain += delta_gamma;
  return delta_gamma;
}

}  // namespace breccia::mps
