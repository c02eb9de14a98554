#pragma once
// The correspondence model's host side: per-particle moduli at set-up, the OpenMP launch of
// its two kernels (correspondence_kernels.hpp), and the run-time zero-energy-mode detector.
// The CUDA backend (cuda_backend.cu) launches the same two kernels on its device arrays.
#include <string>
#include <vector>

#include "breccia/solver/calibration.hpp"
#include "breccia/solver/correspondence_kernels.hpp"
#include "breccia/solver/pd_system.hpp"

namespace breccia::solver {

// Fills the moduli and the per-particle tensors; `elastic` is indexed by material.
void setup_correspondence(PdSystem& s, const std::vector<ElasticInput>& elastic);

// The view's damage limit (CorrespondenceView::damage_limit) from the case: 2, off, unless
// model.stress_damage_limit is given.
inline double correspondence_damage_limit(const CaseConfig& c) {
  return c.stress_damage_limit > 0.0 ? c.stress_damage_limit : 2.0;
}

// The two passes' view of the host state (the step of step.hpp launches them).
CorrespondenceView correspondence_view(PdSystem& s);

// sum_i V_i (h/2) sum_j w |Y - F_i xi|^2 V_j [J]: the energy the particles' non-affine
// motion would hold under a unit penalty (filled on diagnostics steps).
double nonaffine_energy(const PdSystem& s);

// Whether the non-affine energy `nonaffine` (nonaffine_energy, or its sum over a distributed
// run's ranks) grew beyond kMaxNonAffineRatio x (kinetic + strain): zero-energy modes.
bool zero_energy_modes_grew(const Energies& e, double nonaffine);
// The message that stops the run then: zero-energy modes, where (`largest`: the particle of
// largest non-affine energy), and what to do.
std::string zero_energy_mode_message(const PdSystem& s, const Energies& e, double nonaffine,
                                     const NamedParticle& largest);

}  // namespace breccia::solver
