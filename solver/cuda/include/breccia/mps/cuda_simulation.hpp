#pragma once
// The CUDA launcher of the MPS displacement formulation (docs/cuda.md, "MPS"): the
// BRECCIA_HD bodies of kernels.hpp (divergence, elastic acceleration, integrators) and
// crack.hpp (friction pairs) launched one GPU thread per particle (per pair for the crack
// pairs), in the order of Simulation::step, so that a run agrees with the CPU to rounding.
//
// Plain C++ header (no CUDA types): breccia-solve includes it without nvcc.
// Declarations only: breccia-solve includes this beside the PD headers, whose BRECCIA_HD
// differs from MPS's; the kernels stay out of that translation unit.
#include <memory>

namespace breccia::mps {

class Simulation;
class StepDevice;

// A StepDevice holding a copy of `sim`'s current state (u, v, a, crack-pair states) on
// device 0; pass it to sim.attach_device(). Throws RunError when no CUDA device is available
// ("no CUDA device ..."; remedy --backend cpu) or a CUDA call fails (naming the call or kernel).
std::unique_ptr<StepDevice> make_cuda_step_device(const Simulation& sim);

}  // namespace breccia::mps
