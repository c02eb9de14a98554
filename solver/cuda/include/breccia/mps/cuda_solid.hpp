#pragma once
// The CUDA launcher of the MPS stress formulation (docs/cuda.md, "MPS"): the BRECCIA_HD
// phases of solid_phases.hpp launched one GPU thread per particle, in the order of
// Solid::step, so that a run agrees with the CPU to rounding.
//
// Plain C++ header (no CUDA types): breccia-solve includes it without nvcc.
#include <memory>

namespace breccia::mps {

class Solid;
class SolidStepDevice;

// A SolidStepDevice holding a copy of `solid`'s current state on device 0; pass it to
// solid.attach_device(). Throws RunError when no CUDA device is available ("no CUDA device
// ..."; remedy --backend cpu) or a CUDA call fails (naming the call or kernel).
std::unique_ptr<SolidStepDevice> make_cuda_solid_device(const Solid& solid);

}  // namespace breccia::mps
