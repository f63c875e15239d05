#include "device_plan.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "../../domain/slab_layout.hpp"

namespace spate::gpu {

LaunchShape launch_shape(std::size_t items, unsigned threads) {
  if (threads == 0) throw std::invalid_argument("launch_shape: zero threads per block");
  const std::size_t blocks = (items + threads - 1) / threads;
  if (blocks > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::length_error("launch_shape: more than 2^31 - 1 blocks");
  return {static_cast<unsigned>(blocks), threads};
}

std::size_t grown_capacity(std::size_t needed, std::size_t current) {
  if (needed <= current) return current;
  const std::size_t want = needed + needed / 8;
  return (want + kCapacityQuantum - 1) / kCapacityQuantum * kCapacityQuantum;
}

DeviceFootprint device_footprint(int dim) {
  DeviceFootprint f;
  // Every field of the registry (field_registry.hpp), as the device holds ParticleStore::fields().
  for (const FieldRef& r : ParticleStore(dim).fields()) f.field_bytes += r.elem_size;
  // key (4), two 64-bit (key, id) words (16), two permutation entries (8): cub::DoubleBuffer.
  f.sort_bytes = sizeof(std::uint32_t) + 2 * sizeof(std::uint64_t) + 2 * sizeof(std::uint32_t);
  f.scratch_bytes = sizeof(float);
  return f;
}

std::size_t staged_bytes(int dim, FieldSet set) {
  std::size_t b = 0;
  for (auto& f : ParticleStore(dim).fields())
    if (in_set(f, set)) b += f.elem_size;
  return b;
}

std::size_t halo_bytes_per_ghost(int dim) { return 2 * staged_bytes(dim, FieldSet::Ghost) + sizeof(std::uint32_t); }

std::size_t cub_scratch_estimate(std::size_t slots) { return (std::size_t{1} << 20) + slots; }

int bits_for(std::uint64_t values) {
  int bits = 0;
  while (bits < 64 && (std::uint64_t{1} << bits) < values) ++bits;
  return bits;
}

SortWord sort_word(std::uint32_t key_count, std::uint32_t id_bound) {
  SortWord w;
  w.id_bits = bits_for(id_bound);
  w.end_bit = w.id_bits + bits_for(key_count);
  return w;
}

std::vector<SlabMemory> device_memory_per_slab(const Lattice& lattice, std::int64_t particles, int devices) {
  if (devices < 1) throw std::invalid_argument("device_memory_per_slab: devices must be >= 1");
  const SlabLayout layout = SlabLayout::uniform(lattice.cells[0], devices);
  const std::int64_t columns_total = std::max(1, lattice.cells[0]);
  const std::int64_t cells_per_column = static_cast<std::int64_t>(lattice.dim >= 2 ? lattice.cells[1] : 1) *
                                        (lattice.dim >= 3 ? lattice.cells[2] : 1);
  const DeviceFootprint f = device_footprint(lattice.dim);
  std::vector<SlabMemory> out;
  for (int s = 0; s < devices; ++s) {
    SlabMemory m;
    m.slab = s;
    m.columns = layout.faces[s + 1] - layout.faces[s];
    m.owned = (particles * m.columns + columns_total - 1) / columns_total;
    const int ghost_columns = (s > 0 || lattice.periodic[0]) + (s + 1 < devices || lattice.periodic[0]);
    m.ghosts = (particles * ghost_columns + columns_total - 1) / columns_total;
    // The grid's ghost box has one layer on every side (CellGrid::configure): an upper bound.
    m.cells = static_cast<std::int64_t>(m.columns) * cells_per_column +
              static_cast<std::int64_t>(m.columns + 2) * (lattice.dim >= 2 ? lattice.cells[1] + 2 : 1) *
                  (lattice.dim >= 3 ? lattice.cells[2] + 2 : 1);
    m.capacity = grown_capacity(static_cast<std::size_t>(m.owned + m.ghosts), 0);
    // The key table has three bins past the cells (KeyBins).
    m.bytes = m.capacity * f.per_particle() + static_cast<std::size_t>(m.cells + 4) * sizeof(std::uint32_t) +
              static_cast<std::size_t>(m.ghosts) * halo_bytes_per_ghost(lattice.dim) + cub_scratch_estimate(m.capacity);
    out.push_back(m);
  }
  return out;
}

namespace {
bool parsable_entry(const std::string& e) {
  if (e.empty()) return false;
  if (e.rfind("GPU-", 0) == 0 || e.rfind("MIG-", 0) == 0) return true;
  return std::all_of(e.begin(), e.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}
}  // namespace

std::optional<std::vector<std::string>> visible_devices(const char* env) {
  if (env == nullptr) return std::nullopt;
  std::vector<std::string> entries;
  const std::string s(env);
  std::size_t b = 0;
  while (b <= s.size()) {
    std::size_t e = s.find(',', b);
    if (e == std::string::npos) e = s.size();
    std::string item = s.substr(b, e - b);
    const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
    item = first == std::string::npos ? std::string() : item.substr(first, last - first + 1);
    if (!parsable_entry(item)) break;
    entries.push_back(item);
    b = e + 1;
  }
  return entries;
}

std::string no_device_reason(const char* env) {
  const auto v = visible_devices(env);
  if (v && v->empty())
    return "CUDA_VISIBLE_DEVICES='" + std::string(env) + "' hides every device";
  if (v) return "CUDA_VISIBLE_DEVICES='" + std::string(env) + "' lists devices, but the CUDA runtime found none of them";
  return "the CUDA runtime found no device (no GPU, or no NVIDIA driver)";
}

bool per_thread_pair_loop(const char* env) {
  const std::string v = env ? env : "";
  if (v.empty() || v == "lanes") return false;
  if (v == "thread") return true;
  throw std::invalid_argument("SPATE_GPU_PAIR_LOOP='" + v + "': expected lanes or thread");
}

int device_for_worker(int worker, int workers_per_process, int local_rank, int visible) {
  if (visible < 1) throw std::invalid_argument("device_for_worker: no visible device");
  if (worker < 0 || workers_per_process < 1 || worker >= workers_per_process || local_rank < 0)
    throw std::invalid_argument("device_for_worker: worker outside [0, workers_per_process)");
  return (local_rank * workers_per_process + worker) % visible;
}

int node_local_rank(const char* (*getenv)(const char*)) {
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "MV2_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID"}) {
    const char* v = getenv ? getenv(name) : std::getenv(name);
    if (v == nullptr || *v == '\0') continue;
    char* end = nullptr;
    const long r = std::strtol(v, &end, 10);
    if (*end == '\0' && r >= 0) return static_cast<int>(r);
  }
  return 0;
}

}  // namespace spate::gpu
