// Correspondence model on the CPU: moduli at set-up, the OpenMP launch of the two passes,
// and the detector of growing zero-energy (hourglass) modes (docs/theory.md, correspondence).
#include "breccia/solver/correspondence.hpp"

#include <cmath>
#include <sstream>

#include "breccia/solver/forall.hpp"

namespace breccia::solver {

void setup_correspondence(PdSystem& s, const std::vector<ElasticInput>& elastic) {
  const size_t n = s.n;
  const CaseConfig& c = s.config;
  s.corr_moduli.assign(kCorrModuli * n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const ElasticInput& in = elastic[s.material[i]];
    double* m = &s.corr_moduli[kCorrModuli * i];
    m[0] = dimensional_bulk_modulus(in);
    m[1] = shear_modulus(in);
    // The equivalent bond-based material: its micro-modulus sets the penalty's scale, so
    // G = 1 resists non-affine motion about as a PMB body of the same bulk modulus would.
    m[2] = pmb_micromodulus(in, c.influence, s.horizon[i]);
    m[3] = m[2] / (2.0 * s.horizon[i]);
    m[4] = c.stabilisation == "penalty" ? c.stabilisation_coefficient : 0.0;
  }
  s.corr_deformation.assign(9 * n, 0.0);
  s.corr_force_tensor.assign(9 * n, 0.0);
  s.corr_nonaffine.assign(n, 0.0);
}

CorrespondenceView correspondence_view(PdSystem& s) {
  CorrespondenceView v;
  v.p = s.view();
  v.dimension = s.dimension;
  v.moduli = s.corr_moduli.data();
  v.deformation = s.corr_deformation.data();
  v.force_tensor = s.corr_force_tensor.data();
  v.nonaffine = s.corr_nonaffine.data();
  v.damage_limit = correspondence_damage_limit(s.config);
  return v;
}

double nonaffine_energy(const PdSystem& s) {
  double sum = 0.0;
  const int64_t n = static_cast<int64_t>(s.n);
#pragma omp parallel for reduction(+ : sum)
  for (int64_t i = 0; i < n; ++i) sum += s.volume[i] * s.corr_nonaffine[i];
  return sum;
}

bool zero_energy_modes_grew(const Energies& e, double nonaffine) {
  const double mechanical = e.kinetic + e.strain;
  return mechanical > 1e-300 && !(nonaffine <= kMaxNonAffineRatio * mechanical);
}

std::string zero_energy_mode_message(const PdSystem& s, const Energies& e, double nonaffine,
                                     const NamedParticle& largest) {
  const double mechanical = e.kinetic + e.strain;
  std::ostringstream m;
  m << "run became unstable at step " << s.step << " (t = " << s.time
    << " s): zero-energy (hourglass) modes of the correspondence model grew: the non-affine part of the "
       "deformation (Y - F xi) holds "
    << nonaffine / mechanical << " x the body's kinetic + strain energy under a unit penalty (limit "
    << kMaxNonAffineRatio << "); largest at particle " << largest.file_index << " at (" << largest.x0[0] << ", "
    << largest.x0[1] << ", " << largest.x0[2] << "). ";
  if (s.config.stabilisation == "penalty")
    m << "Raise model.stabilisation.coefficient (now " << s.config.stabilisation_coefficient
      << "; 1 or more keeps the ratio below the limit).";
  else
    m << "Use model.stabilisation: {type: penalty, coefficient: 1}.";
  m << " The last good output is kept.";
  return m.str();
}

}  // namespace breccia::solver
