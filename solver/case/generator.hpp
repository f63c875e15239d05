#pragma once
// Case -> particles on the lattice (i + 1/2) dp: fluid blocks, wet bed, solids (hollow shells of
// wall particles) and the tank's wall layers; and the global cell lattice that holds them.
#include <cstdint>
#include <string>

#include "../domain/particle_checks.hpp"
#include "../grid/lattice.hpp"
#include "../particles/particle_store.hpp"
#include "case.hpp"

namespace spate {

struct ParticleCounts {
  std::int64_t fluid = 0;
  std::int64_t wall = 0;  // tank walls and solids
  std::int64_t total() const { return fluid + wall; }
};

Lattice make_lattice(const Case& c);
// Where fluid may leave the domain for good (open top, headroom): escaped(), particle_checks.hpp.
OpenSides open_sides(const Case& c);
// What makes the particle set of a case (dimensions, dp, tank, fluid blocks, wet bed, solids), one
// "key: value" line each, exact; and its 64-bit FNV-1a hash in hex. A checkpoint stores the hash:
// a restart from the checkpoint of another case is refused even when the counts agree.
std::string geometry_signature(const Case& c);
std::string geometry_hash(const Case& c);

// How deep x lies below face `face` (2 axis + (0 lower, 1 upper side)) of box b.
double face_depth(const Box& b, const double x[3], int face);
// Heat transfer: the starting temperature of a particle of material `kind` at x: its fluid block's
// (the first of its fluid that holds x), the tank's or its solid's, else heat.initial_temperature.
double initial_temperature(const Case& c, const MaterialTable& M, std::uint8_t kind, const double x[3]);
// Whether the tank, a solid or a fluid block has a shape other than a box (shape.hpp).
bool has_shapes(const Case& c);
// Counts without allocating: in closed form for boxes (spate info answers at once at any dp), by
// visiting every site when a solid or fluid block has a shape.
ParticleCounts count_particles(const Case& c);
// All particles, ids 0..n-1 in generation order, all owned.
ParticleStore generate_particles(const Case& c);

}  // namespace spate
