#pragma once
// The per-particle predicates of the domain and health checks, one definition for the host worker
// and the device reductions (SPATE_HD): a GPU that finds "the lowest faulty id" by a reduction and
// the host that then writes the message must agree on which particles are faulty.
#include <cmath>
#include <cstdint>

#include "../grid/lattice.hpp"
#include "../physics/host_device.hpp"
#include "../physics/params.hpp"

namespace spate {

SPATE_HD bool finite_value(float v) {
#if defined(__CUDA_ARCH__)
  return isfinite(v);
#else
  return std::isfinite(v);
#endif
}

// Brings a position that left a periodic axis back by one period (the owner does it once per step).
// A position a hair below the lower end rounds to the upper end itself once the period is added
// (-1e-8 + 1 is 1.0f), which is outside [lower, upper): it goes to the lower end instead. The
// lattice's cell decides as well as the coordinate: a position an ulp below the upper end can have
// (x - origin) / cell_size round up to the cell count, a cell that does not exist (a 1 mm
// Poiseuille channel at dp = L/80 stopped on "left the domain along x (position 0.0006 m, domain
// [0, 0.0006] m)"); it wraps too, and lands on the lower end if the subtraction rounds below it.
// Positions that never reached either end are left as they are (bit for bit).
SPATE_HD void wrap_periodic(const Lattice& L, float& x, int axis) {
  if (!L.periodic[axis] || !finite_value(x)) return;  // a NaN or infinity: the position check reports it
  if (x >= L.upper(axis) || L.cell_of(x, axis) >= L.cells[axis]) {
    x -= L.period[axis];
    if (x < L.origin[axis] || L.cell_of(x, axis) < 0) x = L.origin[axis];
  } else if (x < L.origin[axis]) {
    x += L.period[axis];
    if (x >= L.upper(axis) || L.cell_of(x, axis) >= L.cells[axis]) x = L.origin[axis];
  }
}

enum class PositionFault : std::uint8_t { None = 0, NonFinite = 1, Outside = 2 };

// Whether a (wrapped) coordinate can be given a cell of the global lattice.
SPATE_HD PositionFault position_fault(const Lattice& L, float x, int axis) {
  if (!finite_value(x)) return PositionFault::NonFinite;
  const float lo = L.origin[axis];
  const bool inside = x >= lo - L.cell_size[axis] && x <= L.upper(axis) + L.cell_size[axis] && L.cell_of(x, axis) >= 0 &&
                      L.cell_of(x, axis) < L.cells[axis];
  return inside ? PositionFault::None : PositionFault::Outside;
}

// The open sides of the domain, where fluid may leave for good (a splash over the walls of an
// open-top tank, or higher than the headroom above it). Such particles are removed and counted,
// as DualSPHysics does, and the run goes on; anything else that leaves the domain (through a wall,
// through the floor or a closed lid), or a NaN, remains an instability.
struct OpenSides {
  bool open = false;     // the tank has an open top
  int vertical = 2;      // dim - 1
  float top = 0.0f;      // the top of the tank walls
  float ceiling = 0.0f;  // top + headroom: the top of the domain
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  // outer faces of the wall layers (periodic axes: +-infinity)
  std::uint8_t fluids = 1;  // materials [0, fluids) are fluids (MaterialTable): only they leave
  // A moving tank: where a point now was, relative to the tank, at t = 0 (the sides above are the
  // tank's then): p0 = centre + back (x - centre - shift); the identity while the tank stands
  // still. Without it, water that went over a swaying tank's wall fell down outside it, beside
  // the wall's place at t = 0, and left the domain through its floor (an instability).
  bool moving = false;
  float centre[3] = {0, 0, 0}, shift[3] = {0, 0, 0};
  float back[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
};

// A fluid particle (material) above the walls that is past their outer faces, or above the
// ceiling, in the tank's frame: gone. NaN coordinates compare false everywhere: they stay a fault.
SPATE_HD bool escaped(const OpenSides& o, int dim, std::uint8_t material, const float x[3]) {
  if (!o.open || material >= o.fluids) return false;
  const float* pos = x;
  float p0[3];
  if (o.moving) {
    float r[3];
    for (int a = 0; a < 3; ++a) r[a] = x[a] - o.centre[a] - o.shift[a];
    for (int a = 0; a < 3; ++a) p0[a] = o.centre[a] + (o.back[a][0] * r[0] + o.back[a][1] * r[1] + o.back[a][2] * r[2]);
    pos = p0;
  }
  const float z = pos[o.vertical];
  if (!(z > o.top)) return false;
  if (z > o.ceiling) return true;
  for (int a = 0; a < dim; ++a)
    if (a != o.vertical && (pos[a] < o.lo[a] || pos[a] > o.hi[a])) return true;
  return false;
}

// The health check of a fluid particle: finite state and density within [min, max] x rho0 of its
// material.
struct HealthLimits {
  float min_ratio = 0.0f;
  float max_ratio = 1e30f;
  std::uint8_t fluids = 1;         // materials [0, fluids) are fluids (the others are not checked)
  float rho0[kMaxFluids] = {1000.0f};
  HealthLimits() = default;
  HealthLimits(const MaterialTable& m, float min, float max) : min_ratio(min), max_ratio(max), fluids(m.fluids) {
    for (int k = 0; k < m.fluids; ++k) rho0[k] = m.fluid[k].rho0;
  }
  SPATE_HD bool checked(std::uint8_t material) const { return material < fluids; }
};
SPATE_HD bool state_finite(int dim, const float pos[3], const float vel[3], float density) {
  bool finite = finite_value(density);
  for (int a = 0; a < dim; ++a) finite = finite && finite_value(pos[a]) && finite_value(vel[a]);
  return finite;
}
SPATE_HD bool healthy(const HealthLimits& h, bool finite, float density, std::uint8_t material) {
  const float ratio = density / h.rho0[material];
  return finite && ratio >= h.min_ratio && ratio <= h.max_ratio;
}

}  // namespace spate
