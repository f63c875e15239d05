#pragma once
// What the CUDA runtime says about this machine. Plain C++ (the runtime API is a C library), so the
// program can ask without nvcc; in a build without CUDA every answer is "no device".
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "../step_kernels.hpp"

namespace spate::gpu {

struct DeviceInfo {
  int index = 0;
  std::string name;
  std::size_t memory_bytes = 0;
  int compute_major = 0, compute_minor = 0;
};

bool built_with_cuda();
// Visible devices (CUDA_VISIBLE_DEVICES applies); 0 when there is no device, driver or CUDA build.
int device_count();
std::vector<DeviceInfo> devices();
// Whether device `from` can read and write device `to`'s memory directly (peer-to-peer).
bool can_access_peer(int from, int to);
// Throws std::runtime_error("no CUDA device: <reason>") when device_count() is 0.
void require_device();

// The CUDA physics loops for one slab on device `device` (see cuda_kernels.cu).
std::unique_ptr<StepKernels> make_cuda_kernels(int device, int dim);
// The resident arrays alone (device_arrays.cu), for the tests that hold them against their host
// twin, HostSlabArrays.
std::unique_ptr<SlabArrays> make_device_arrays(int device, int dim);

}  // namespace spate::gpu
