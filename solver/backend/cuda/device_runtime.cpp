#include "device_runtime.hpp"

#include <cstdlib>
#include <stdexcept>

#include "device_plan.hpp"

#if defined(SPATE_WITH_CUDA)
#include <cuda_runtime_api.h>
#endif

namespace spate::gpu {

namespace {
[[maybe_unused]] constexpr const char* kNotBuilt = "no CUDA device: this spate was built without CUDA (SPATE_ENABLE_CUDA=OFF or no nvcc)";
}  // namespace

#if defined(SPATE_WITH_CUDA)

bool built_with_cuda() { return true; }

int device_count() {
  int n = 0;
  // Without a driver or a device this returns an error (cudaErrorNoDevice, cudaErrorInsufficientDriver).
  if (cudaGetDeviceCount(&n) != cudaSuccess) {
    (void)cudaGetLastError();  // clear the sticky-free error so later calls start clean
    return 0;
  }
  return n;
}

std::vector<DeviceInfo> devices() {
  std::vector<DeviceInfo> out;
  for (int d = 0; d < device_count(); ++d) {
    cudaDeviceProp prop{};
    if (cudaGetDeviceProperties(&prop, d) != cudaSuccess) continue;
    out.push_back({d, prop.name, prop.totalGlobalMem, prop.major, prop.minor});
  }
  return out;
}

bool can_access_peer(int from, int to) {
  if (from == to) return true;
  int ok = 0;
  return cudaDeviceCanAccessPeer(&ok, from, to) == cudaSuccess && ok != 0;
}

#else

bool built_with_cuda() { return false; }
int device_count() { return 0; }
std::vector<DeviceInfo> devices() { return {}; }
bool can_access_peer(int from, int to) { return from == to; }
std::unique_ptr<StepKernels> make_cuda_kernels(int, int) {
  throw std::runtime_error(kNotBuilt);
}
std::unique_ptr<SlabArrays> make_device_arrays(int, int) {
  throw std::runtime_error(kNotBuilt);
}

#endif

void require_device() {
  if (!built_with_cuda())
    throw std::runtime_error(kNotBuilt);
  if (device_count() == 0) throw std::runtime_error("no CUDA device: " + no_device_reason(std::getenv("CUDA_VISIBLE_DEVICES")));
}

}  // namespace spate::gpu
