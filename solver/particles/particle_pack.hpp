#pragma once
// Packing particles into byte buffers for halos, migration and checkpoint gathers. A buffer is a
// particle count followed by one block per selected field, so unpacking is a memcpy per field.
#include <cstdint>
#include <span>
#include <vector>

#include "../grid/lattice.hpp"
#include "particle_store.hpp"

namespace spate {

using Bytes = std::vector<char>;

// Which fields travel, by their registry flags (field_registry.hpp).
enum class FieldSet {
  All,       // kMigrated: migration, the checkpoint gather
  Ghost,     // kGhost: what a ghost needs to act as a neighbour
  Refresh,   // kRefreshed: ghost fields that change after the halo is built (not position, id, material)
};

bool in_set(const FieldRef& f, FieldSet set);

Bytes pack_particles(ParticleStore& p, std::span<const std::uint32_t> indices, FieldSet set, Shift shift = {});
// Appends the packed particles at the end of the store; returns how many.
std::size_t unpack_append(ParticleStore& p, const Bytes& buffer, FieldSet set);
// Writes the packed particles into slots (one per packed particle).
void unpack_into(ParticleStore& p, const Bytes& buffer, FieldSet set, std::span<const std::uint32_t> slots);
std::size_t packed_count(const Bytes& buffer);

}  // namespace spate
