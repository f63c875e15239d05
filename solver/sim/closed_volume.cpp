#include "closed_volume.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "slab_worker.hpp"

namespace spate {

namespace {
constexpr double kUnit = 1073741824.0;  // 2^30: rho0 / rho near 1 to 1e-9; 2^33 particles before overflow
}

std::int64_t fluid_volume_sum(SlabWorker& w) {
  const ParticleStore& p = w.particles();
  const PhysicsParams& P = w.params();
  std::vector<std::int64_t> sum(1, 0);
  for (std::size_t i = 0; i < p.owned(); ++i) {
    const std::uint8_t m = p.material[i];
    if (P.is_fluid(m)) sum[0] += std::llround(static_cast<double>(P.materials.of(m).rho0) / p.density[i] * kUnit);
  }
  w.transport().sum(sum);
  return sum[0];
}

void ClosedVolume::start(SlabWorker& w) {
  if (on_) reference_ = fluid_volume_sum(w);
}

void ClosedVolume::hold(SlabWorker& w) {
  if (!on_) return;
  const std::int64_t now = fluid_volume_sum(w);
  const double ratio = static_cast<double>(now) / static_cast<double>(reference_);
  if (std::fabs(ratio - 1.0) <= kTolerance) return;
  // rho_i -> rho_i S / S0 gives sum rho0 / rho_i -> S0 (to first order in S / S0 - 1).
  ParticleStore& p = w.particles();
  const PhysicsParams& P = w.params();
  for (std::size_t i = 0; i < p.owned(); ++i)
    if (P.is_fluid(p.material[i])) p.density[i] = static_cast<float>(static_cast<double>(p.density[i]) * ratio);
  ++scalings_;
}

std::string ClosedVolume::save() const { return on_ ? fmt::format("reference {}\n", reference_) : std::string{}; }

void ClosedVolume::restore(const std::string& text) {
  if (!on_) {
    if (!text.empty()) throw std::runtime_error("it holds a closed volume's reference, and the case has no density.closed_volume");
    return;
  }
  if (text.empty()) throw std::runtime_error("the case has density.closed_volume, and the checkpoint holds no reference volume");
  long long value = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "reference %lld %c", &value, &tail) != 1 || value <= 0)
    throw std::runtime_error(fmt::format("'{}' is not 'reference <a positive integer>'", text.substr(0, text.find('\n'))));
  reference_ = value;
}

}  // namespace spate
