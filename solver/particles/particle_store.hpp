#pragma once
// Structure-of-arrays particle storage on the host: float32 fields, one array per component.
// Particles [0, owned) belong to this slab, [owned, size) are ghosts (halo copies and periodic
// images). The fields are the registry's (field_registry.hpp): the members below are generated
// from it, and fields() lists them all (plus any run-time extension) so that sorting, migration,
// halos and I/O treat every field alike.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "field_registry.hpp"
#include "particle_memory.hpp"

namespace spate {

// The one place the particle arrays' allocation is chosen: particle_memory.hpp (the heap, or the
// shared arena an in-situ helper process maps, so that Catalyst sees the solver's own pages).
template <class T>
using FieldVector = std::vector<T, ParticleAllocator<T>>;
template <class T, FieldShape S>
struct FieldColumns {
  using type = FieldVector<T>;
};
template <class T>
struct FieldColumns<T, FieldShape::Vector> {
  using type = FieldVector<T>[3];  // components beyond dim stay empty
};

// One component of one field, type-erased: what the generic layers (packing, permutation, I/O,
// device arrays) work with.
struct FieldRef {
  const FieldSpec* spec;   // the registry entry
  int component;           // 0 for scalars, the axis for vector components
  std::string_view name;   // checkpoint dataset name of this component
  void* data;              // points at a FieldVector<T>
  std::size_t elem_size;   // sizeof(T)
  void (*resize)(void*, std::size_t);
  char* (*storage)(void*);
  char* bytes() const { return storage(data); }  // start of the vector's storage
  bool has(std::uint16_t flags) const { return spec->has(flags); }
  bool builtin() const;    // a registry field (a ParticleStore member), not a run-time extension
};

// Fields registered at run time with the same FieldSpec: the store allocates them generically and
// every layer that iterates fields() carries them (the registry test adds one this way; optional
// features may too). Register before the stores that should have them are made, and keep the
// registration alive while they exist (their FieldRefs point at it).
class FieldExtension {
 public:
  explicit FieldExtension(const FieldSpec& spec);
  ~FieldExtension();
  FieldExtension(const FieldExtension&) = delete;
  FieldExtension& operator=(const FieldExtension&) = delete;
};
// The registered extensions, in registration order (stable addresses).
std::vector<const FieldSpec*> field_extensions();

// The optional registry fields (the groups of kOptionalGroups: kOptional, e.g. surface tension's
// colour gradient; kThermal, the temperature) are part of the stores made while an OptionalFields
// enabling their group is alive, and of no other: a run that needs them holds one for its whole
// length (Simulation::run), so all of its stores, buffers and device arrays agree on the fields;
// every other run has the stores, halos and footprint it had without them.
enum class FieldGroups : std::uint16_t {};  // a mask of kOptionalGroups flags
class OptionalFields {
 public:
  explicit OptionalFields(bool enable) : OptionalFields(static_cast<FieldGroups>(enable ? std::uint16_t{kOptional} : std::uint16_t{0})) {}
  explicit OptionalFields(FieldGroups groups);
  ~OptionalFields();
  OptionalFields(const OptionalFields&) = delete;
  OptionalFields& operator=(const OptionalFields&) = delete;

 private:
  std::uint16_t groups_;
};
// Whether stores made now carry the kOptional fields; the groups they carry.
bool optional_fields_enabled();
std::uint16_t optional_field_groups_enabled();

class ParticleStore;

// A field as snapshots and in-situ consumers see it (kExported): the registry entry and its
// component arrays (null beyond dim; vectors are shown with 3 components).
struct ExportedField {
  const FieldSpec* spec;
  int components;          // dim for vectors, 1 for scalars
  char* data[3];           // start of each component's array
};
// The exported fields of `p`, in registry order then the extensions.
std::vector<ExportedField> exported_fields(ParticleStore& p);

class ParticleStore {
 public:
  explicit ParticleStore(int dim = 3);

  int dim() const { return dim_; }
  std::size_t size() const { return id.size(); }
  std::size_t owned() const { return owned_; }
  std::size_t ghosts() const { return size() - owned_; }
  void set_owned(std::size_t n) { owned_ = n; }

  void resize(std::size_t n);
  // All fields, in registry order, then the extensions. Components beyond dim are not listed, nor
  // the optional fields of a store made without them (OptionalFields).
  std::vector<FieldRef> fields();
  // Bytes held per particle by the per-particle arrays (the headline memory figure).
  std::size_t bytes_per_particle() const;

  // Keep particles [first, first + perm.size()) reordered so that new slot k holds old perm[k].
  void permute(std::size_t first, std::span<const std::uint32_t> perm);
  // Append particle `src` of `from` (all fields) at the end.
  void append_from(const ParticleStore& from, std::size_t src);
  // Drop particles whose flag is set, among [0, owned); ghosts are discarded too.
  void remove_owned_if(const std::vector<std::uint8_t>& flag);
  // Swap old and new rates (the integrator keeps the previous step's rates).
  void swap_rates();

  // The registry's fields (public: the drivers in backend/ read them directly), e.g.
  // FieldVector<float> pos[3], vel[3], ...; density, pressure, ...; id (uint32); material (uint8).
#define SPATE_STORE_MEMBER(member, ctype, shape, ...) typename FieldColumns<ctype, FieldShape::shape>::type member;
  SPATE_PARTICLE_FIELDS(SPATE_STORE_MEMBER)
#undef SPATE_STORE_MEMBER

 private:
  struct Extension {
    const FieldSpec* spec;
    FieldVector<std::uint32_t> words[3];  // 4-byte fields (bit copies)
    FieldVector<std::uint8_t> bytes[3];   // 1-byte fields
  };
  int dim_;
  std::uint16_t groups_;  // the optional groups it carries (OptionalFields)
  bool carries(const FieldSpec& f) const { return (f.flags & kOptionalGroups & ~groups_) == 0; }
  std::size_t owned_ = 0;
  std::vector<Extension> extensions_;
  std::vector<std::uint32_t> scratch_;  // permute(): one word per particle for every field type
  std::vector<std::pair<std::uint32_t, std::uint32_t>> runs_;  // permute(): the slot ranges that change
};

}  // namespace spate
