#pragma once
// The error measures of the atlas problems, shared by breccia-atlas and the planner's tests
// (a proposal is checked by running it and measuring its error exactly as the atlas did).
#include <functional>
#include <memory>
#include <string>

#include "breccia/solver/pd_system.hpp"
#include "breccia/solver/run.hpp"

namespace breccia::atlas {

// Builds the backend that steps a system from its current state (the CUDA backend's
// make_cuda_step_backend); empty: the CPU (cpu_step).
using BackendFactory = std::function<std::unique_ptr<solver::StepBackend>(solver::PdSystem&)>;

// Wave speed in a thin bar of length `length_m` along x: the fundamental free-free mode
// u = A cos(pi x / L) has period 2 L / c0; the modal amplitude first crosses zero at a
// quarter period, so c = L / (2 t_quarter). Returns |c / c0 - 1| (1 if no crossing).
// Advances s (explicit steps from rest), on `backend` when given (u is read back every step).
double fundamental_mode_speed_error(solver::PdSystem& s, double length_m, double c0_m_s,
                                    const BackendFactory& backend = {});

// Quasi-static bar relaxed by ADR: sets `free_end - held_end` mean displacement against
// sigma L_eff / E (sets "xmin" held, "xmax" loaded; L_eff between their mean positions).
// Holds the particle nearest the origin in y as well (no rigid sideways drift).
// Returns |u_end / (sigma L_eff / E) - 1|, or a negative value when ADR did not converge.
double bar_end_displacement_error(solver::PdSystem& s, double traction_pa, double youngs_modulus_pa,
                                  long long* iterations = nullptr);

// Quasi-static bar relaxed by ADR, loaded and held over boundary layers (the traction spread
// over `depth: horizon`, the grip a layer as deep): the strain of the span between the layers,
// the least-squares slope of u_x over x_lo <= x <= x_hi (every particle), against sigma / E.
// Holds the particle nearest the origin in y as well. Returns |slope / (sigma / E) - 1|, or a
// negative value when ADR did not converge.
double bar_span_strain_error(solver::PdSystem& s, double traction_pa, double youngs_modulus_pa, double x_lo,
                             double x_hi, long long* iterations = nullptr);

// Peak nominal stress of a bar pulled by a velocity constraint (the grip): the force on the
// grip's particles (`s.constraints[grip]`) over `area_m2`, the maximum over explicit CPU steps
// until `end_s`. The quasi-brittle test and the atlas's softening_strength rows share it.
struct PeakStress {
  double stress_pa = 0.0, time_s = 0.0;
};
PeakStress pulled_bar_peak_stress(solver::PdSystem& s, size_t grip, double area_m2, double end_s);

// The quasi-brittle bar: 30 mm long along x, 6 mm wide (3D: square section), concrete-like
// (E 30 GPa, rho 2400, G0 100 J/m2, sigma_t given), pulled at 0.05 m/s at each end for 300 us
// by grips `grip_depth_m` deep (x prescribed, lateral motion free; constraint 1 is the x-max
// grip). Returns the case text after `specimen:` and `model:`.
struct SofteningBar {
  static constexpr double length_m = 0.03, width_m = 0.006, thickness_m = 0.001, end_s = 300e-6;
};
std::string softening_bar_case_text(int dimension, double grip_depth_m, double poisson_ratio,
                                    const std::string& tensile_strength);

// Work to break every bond crossing the plane x = 0, per unit area of the plane, over g0: the
// bonds whose crossing point lies in a half-open window of the plane, |y| and |z| below
// window / 2 after a shift of shift x window (2D: |y| only, the area window x thickness;
// a shift off the lattice's symmetry planes keeps crossing points off the window's edges).
// Both entries of a pair hold their part. A brittle bond's work is its energy at s0, a
// softening bond's U s_t s_u along its law. The calibration test and the atlas's
// fracture_energy rows share it.
double crossing_fracture_energy_ratio(const solver::PdSystem& s, double window, double shift, double g0);

// A right-going P pulse in uniaxial strain (the caller holds y) along a strip whose
// resolution changes at x = interface_x: Gaussian u = A exp(-(x - x0)^2 / 2 w^2) moving
// at c_p, run until its centre is four widths past the change. Returns the share of the
// initial energy left of the interface (minus the largest horizon) then: the reflection.
// Advances s. The dual-horizon test and the atlas's graded study share it.
double reflected_pulse_energy(solver::PdSystem& s, double interface_x, double pulse_x, double pulse_width,
                              double c_p);

// A graded 2D particle file (plane, thickness h): strip [0, L] x [0, W], square lattice of
// spacing h for x < L/2 and r h beyond, volumes s^2 h, one material "rock". Written to
// `path` (returned). The graded-mesh study of the atlas and the dual-horizon tests share it.
std::string write_graded_strip(const std::string& path, double L, double W, double h, double r);

}  // namespace breccia::atlas
