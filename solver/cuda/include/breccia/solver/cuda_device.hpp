#pragma once
// Is there a CUDA device, and which: the one query every launcher (PD, MPS) and the CLI
// share. Plain C++ with no solver headers, so MPS code can include it without PD's.
#include <string>

namespace breccia::solver {

// True when a CUDA driver and at least one device are present. Never throws: a machine
// without a GPU or without the driver library simply answers false.
bool cuda_device_available();

// Name and memory of the device in use (0 unless cuda_use_device chose another), for logs ("NVIDIA H100 80GB HBM3, 79.1 GiB"); empty if none.
std::string cuda_device_description();

}  // namespace breccia::solver
