// A build without Simbody (cmake/SpateBodies.cmake): the case loader refuses floating solids
// (body_support()), so no System is ever made; making one says why.
#include <stdexcept>

#include "multibody.hpp"

namespace spate::multibody {

struct System::Impl {};
System::System(int, const std::array<double, 3>&, const std::vector<BodyInput>&, const std::vector<ObstacleInput>&) {
  throw std::runtime_error("this spate was built without Simbody (libsimbody-dev), which floating solids need");
}
System::~System() = default;
void System::set_loads(const std::vector<Load>&) {}
void System::advance(double, double) {}
std::vector<BodyOutput> System::state() const { return {}; }
std::vector<double> System::q(int) const { return {}; }
std::vector<double> System::u(int) const { return {}; }
bool System::set(int, const std::vector<double>&, const std::vector<double>&) { return false; }
void System::set_spring(int, double, double) {}
void System::set_hinge(int, double, double) {}

}  // namespace spate::multibody
