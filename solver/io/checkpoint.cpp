#include "checkpoint.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fmt/format.h>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "../case/generator.hpp"
#include "../domain/particle_checks.hpp"
#include "../sim/memory_estimate.hpp"
#include "../sim/steering.hpp"
#include "output_file.hpp"

namespace spate {

namespace {

// "spate-checkpoint-<version>"; versions 2 and up also have an integer attribute format_version.
constexpr const char* kFormatPrefix = "spate-checkpoint-";
// The first version with the checksums, the geometry hash and the removed count.
constexpr int kCheckedVersion = 3;
// Texts in the header (the case, the steering history) are small; a header that claims more is damaged.
constexpr std::size_t kLargestText = 16u << 20;
// Step numbers beyond this are not from a run (at 1e6 steps a second: 30 years).
constexpr std::int64_t kLargestStep = 1'000'000'000'000'000;
// Particles per chunk of a dataset: the unit Fletcher32 checks (256 KiB of floats).
constexpr hsize_t kChunk = 65536;

// HDF5 prints its error stack to stderr by default, pages of it for one bad file; spate reports
// one message instead (hdf5_reason()).
void quiet_hdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// A file whose close failed (a full disk while HDF5 flushes it) stays in HDF5's tables, and HDF5's
// own clean-up at exit then crashes on it (1.10: H5F__close_cb). spate closes every file itself,
// so that clean-up is not needed: it is switched off before the library starts (a static object
// of this file, constructed before main).
struct NoHdf5Atexit {
  NoHdf5Atexit() { H5dont_atexit(); }
} no_hdf5_atexit;

// The innermost description on HDF5's error stack (what went wrong at the bottom); the stack is
// cleared.
std::string hdf5_reason() {
  std::string deepest;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* e, void* data) -> herr_t {
        if (n == 0 && e && e->desc) *static_cast<std::string*>(data) = e->desc;
        return 0;
      },
      &deepest);
  H5Eclear2(H5E_DEFAULT);
  // A failed system call comes as "... errno = 28, error message = 'No space left on device', ...":
  // the system's reason is the message.
  const auto quoted = deepest.find("error message = '");
  if (quoted != std::string::npos) {
    const auto begin = quoted + 17, end = deepest.find('\'', begin);
    if (end != std::string::npos) return deepest.substr(begin, end - begin);
  }
  deepest = deepest.substr(0, deepest.find('\n'));
  return deepest.empty() ? "HDF5 error" : deepest;
}

// An HDF5 identifier closed on every way out: a write that fails half way must not leave objects
// open (HDF5 would try to flush them again at exit, on a full disk).
class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*closer)(hid_t)) : id_(id), close_(closer) {}
  ~Handle() { close(); }
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      close();
      id_ = std::exchange(o.id_, -1);
      close_ = o.close_;
    }
    return *this;
  }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  herr_t close() {
    herr_t r = 0;
    if (id_ >= 0 && close_) r = close_(id_);
    id_ = -1;
    return r;
  }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

hid_t h5_type(FieldType t) {
  switch (t) {
    case FieldType::F32: return H5T_NATIVE_FLOAT;
    case FieldType::U32: return H5T_NATIVE_UINT32;
    case FieldType::U8: return H5T_NATIVE_UINT8;
  }
  return H5T_NATIVE_FLOAT;
}

std::string format_name(int version) { return kFormatPrefix + std::to_string(version); }

// 64-bit FNV-1a over the header values, in a fixed byte order: a flipped bit in an attribute (which
// HDF5's checksums of object headers may not see in old-style headers) shows as a mismatch.
std::string header_checksum(const CheckpointMeta& m, int dim) {
  std::uint64_t h = 14695981039346656037ull;
  auto bytes = [&](const void* data, std::size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < n; ++k) h = (h ^ c[k]) * 1099511628211ull;
  };
  auto text = [&](const std::string& s) {
    const std::uint64_t n = s.size();
    bytes(&n, sizeof n);
    bytes(s.data(), s.size());
  };
  text(format_name(m.format_version));
  bytes(&m.step, sizeof m.step);
  bytes(&m.time, sizeof m.time);
  bytes(&m.dt, sizeof m.dt);
  bytes(&dim, sizeof dim);
  bytes(&m.removed, sizeof m.removed);
  text(m.case_name);
  text(m.case_yaml);
  text(m.steering_log);
  text(m.geometry_hash);
  if (!m.bodies.empty()) text(m.bodies);  // files without floating solids keep their checksum
  if (!m.drive.empty()) text(m.drive);    // and files without a drive theirs
  if (!m.closed_volume.empty()) text(m.closed_volume);
  return fmt::format("{:016x}", h);
}

// ---- writing ------------------------------------------------------------------------------------

class Writer {
 public:
  explicit Writer(std::filesystem::path tmp) : tmp_(std::move(tmp)) {}
  [[noreturn]] void fail(const std::string& what) const { throw OutputError(tmp_.string() + ": " + what + ": " + hdf5_reason()); }
  void check(herr_t status, const std::string& what) const {
    if (status < 0) fail(what);
  }
  Handle make(hid_t id, herr_t (*close)(hid_t), const std::string& what) const {
    if (id < 0) fail(what);
    return Handle(id, close);
  }
  void attribute(hid_t loc, const char* name, hid_t type, const void* value) const {
    Handle space = make(H5Screate(H5S_SCALAR), H5Sclose, "creating a dataspace");
    Handle attr = make(H5Acreate2(loc, name, type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, std::string("creating attribute ") + name);
    check(H5Awrite(attr.get(), type, value), std::string("writing attribute ") + name);
    check(attr.close(), std::string("closing attribute ") + name);
  }
  void text(hid_t loc, const char* name, const std::string& value) const {
    Handle type = make(H5Tcopy(H5T_C_S1), H5Tclose, "creating a string type");
    check(H5Tset_size(type.get(), value.empty() ? 1 : value.size()), "sizing a string type");
    attribute(loc, name, type.get(), value.empty() ? "" : value.data());
  }

 private:
  std::filesystem::path tmp_;
};

}  // namespace

std::vector<CheckpointDataset> checkpoint_datasets(int dim, int version) {
  std::vector<CheckpointDataset> out;
  const auto fields = ParticleStore(dim).fields();
  for (std::size_t k = 0; k < fields.size(); ++k) {
    const FieldRef& f = fields[k];
    if (!f.has(kCheckpointed)) continue;
    std::string name(f.name);
    if (version == 1 && f.spec->member == "material") name = "kind";
    out.push_back(CheckpointDataset{name, f.spec->type, k});
  }
  return out;
}

std::vector<CheckpointDataset> derived_datasets(int dim) {
  std::vector<CheckpointDataset> out;
  const auto fields = ParticleStore(dim).fields();
  for (std::size_t k = 0; k < fields.size(); ++k)
    if (fields[k].has(kExported) && !fields[k].has(kCheckpointed)) out.push_back(CheckpointDataset{std::string(fields[k].name), fields[k].spec->type, k});
  return out;
}

std::filesystem::path xdmf_sidecar(const std::filesystem::path& checkpoint) {
  std::filesystem::path p = checkpoint;
  return p.replace_extension(".xmf2");
}

namespace {

// The sidecar: one uniform grid of `count` vertices; geometry from the separate coordinate
// datasets (X_Y_Z, X_Y), each exported vector joined from its component datasets. Extension .xmf2:
// ParaView 5.11 then picks its XDMF (version 2) reader, which reads these files; for .xmf it
// prefers the Xdmf3 reader, which does not.
void write_xdmf(const std::filesystem::path& h5, const CheckpointMeta& meta, int dim, std::size_t count) {
  const std::string file = h5.filename().string();
  auto item = [&](const FieldRef& f) {
    const char* type = f.spec->type == FieldType::F32 ? "Float" : f.spec->type == FieldType::U32 ? "UInt" : "UChar";
    return fmt::format("<DataItem Dimensions=\"{}\" NumberType=\"{}\" Precision=\"{}\" Format=\"HDF\">{}:/particles/{}</DataItem>", count,
                       type, f.elem_size, file, f.name);
  };
  std::string geometry, attributes;
  ParticleStore layout(dim);
  for (const ExportedField& e : exported_fields(layout)) {
    std::string items;
    for (const FieldRef& f : layout.fields())
      if (f.spec == e.spec) items += "\n      " + item(f);
    if (e.spec->member == "pos") {
      geometry = fmt::format("    <Geometry GeometryType=\"{}\">{}\n    </Geometry>\n", dim == 3 ? "X_Y_Z" : "X_Y", items);
      continue;
    }
    if (e.spec->shape == FieldShape::Vector)
      items = fmt::format("\n      <DataItem ItemType=\"Function\" Function=\"JOIN({})\" Dimensions=\"{} {}\">{}\n      </DataItem>",
                          dim == 3 ? "$0, $1, $2" : "$0, $1", count, dim, items);
    attributes += fmt::format("    <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"Node\">{}\n    </Attribute>\n", e.spec->exported,
                              e.spec->shape == FieldShape::Vector ? "Vector" : "Scalar", items);
  }
  const std::string text = fmt::format(
      "<?xml version=\"1.0\" ?>\n<!-- The particles of {} (spate checkpoint, step {}) for ParaView's XDMF reader. -->\n"
      "<Xdmf Version=\"2.0\">\n <Domain>\n  <Grid Name=\"particles\" GridType=\"Uniform\">\n    <Time Value=\"{:.17g}\"/>\n"
      "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{}\" NodesPerElement=\"1\"/>\n{}{}  </Grid>\n </Domain>\n</Xdmf>\n",
      file, meta.step, meta.time, count, geometry, attributes);
  write_file_atomically(xdmf_sidecar(h5), text);
}

}  // namespace

void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, ParticleStore& particles) {
  auto fields = particles.fields();
  const std::size_t n = particles.owned();
  write_checkpoint(path, meta, particles.dim(), n, [&](std::size_t k, char* out) {
    std::copy_n(fields[k].bytes(), n * fields[k].elem_size, out);
  });
}

void write_checkpoint(const std::filesystem::path& path, const CheckpointMeta& meta, int dim, std::size_t count,
                      const CheckpointFieldFill& fill) {
  quiet_hdf5();
  if (path.has_parent_path()) create_output_folder(path.parent_path());
  const std::filesystem::path tmp = temporary_path(path);
  // Whatever happens below, no half-written temporary file stays behind.
  struct RemoveUnlessPublished {
    const std::filesystem::path& tmp;
    bool published = false;
    ~RemoveUnlessPublished() {
      std::error_code ec;
      if (!published) std::filesystem::remove(tmp, ec);
    }
  } cleanup{tmp};
  const Writer w(tmp);
  {
    // Format 1.8 object headers and superblock carry HDF5's own metadata checksums.
    Handle fapl = w.make(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "creating file properties");
    w.check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18), "setting the file format");
    w.check(H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG), "setting the close degree");
    Handle file = w.make(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose, "cannot create the checkpoint file");
    CheckpointMeta m = meta;
    m.format_version = kCheckpointFormatVersion;
    const int version = kCheckpointFormatVersion;
    w.text(file.get(), "format", format_name(version));
    w.attribute(file.get(), "format_version", H5T_NATIVE_INT, &version);
    w.attribute(file.get(), "step", H5T_NATIVE_INT64, &m.step);
    w.attribute(file.get(), "time", H5T_NATIVE_DOUBLE, &m.time);
    w.attribute(file.get(), "dt", H5T_NATIVE_DOUBLE, &m.dt);
    w.attribute(file.get(), "dimensions", H5T_NATIVE_INT, &dim);
    w.attribute(file.get(), "removed_particles", H5T_NATIVE_INT64, &m.removed);
    w.text(file.get(), "case_name", m.case_name);
    w.text(file.get(), "case_yaml", m.case_yaml);
    w.text(file.get(), "steering_log", m.steering_log);
    w.text(file.get(), "geometry_hash", m.geometry_hash);
    if (!m.bodies.empty()) w.text(file.get(), "bodies", m.bodies);
    if (!m.drive.empty()) w.text(file.get(), "drive", m.drive);
    if (!m.closed_volume.empty()) w.text(file.get(), "closed_volume", m.closed_volume);
    w.text(file.get(), "header_checksum", header_checksum(m, dim));
    Handle group = w.make(H5Gcreate2(file.get(), "particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "creating group particles");
    const hsize_t n = count;
    const hsize_t chunk = std::max<hsize_t>(1, std::min(n, kChunk));
    std::vector<char> buffer;  // one field at a time
    std::vector<CheckpointDataset> datasets = checkpoint_datasets(dim);
    for (auto& d : derived_datasets(dim)) datasets.push_back(d);
    for (const CheckpointDataset& d : datasets) {
      buffer.resize(count * field_type_size(d.type));
      if (count > 0) fill(d.field, buffer.data());
      Handle space = w.make(H5Screate_simple(1, &n, nullptr), H5Sclose, "creating a dataspace");
      Handle dcpl = w.make(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "creating dataset properties");
      w.check(H5Pset_chunk(dcpl.get(), 1, &chunk), "chunking dataset " + d.name);
      w.check(H5Pset_fletcher32(dcpl.get()), "adding the Fletcher32 checksum to dataset " + d.name);
      Handle dset = w.make(H5Dcreate2(group.get(), d.name.c_str(), h5_type(d.type), space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                           H5Dclose, "creating dataset " + d.name);
      if (n > 0) w.check(H5Dwrite(dset.get(), h5_type(d.type), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()), "writing dataset " + d.name);
      w.check(dset.close(), "writing dataset " + d.name);
    }
    w.check(group.close(), "closing group particles");
    // The data reach the file here (a full disk shows now, if not before).
    w.check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "writing the file");
    w.check(file.close(), "closing the file");
  }
  publish_file(tmp, path);
  cleanup.published = true;
  write_xdmf(path, meta, dim, count);
}

// ---- reading ------------------------------------------------------------------------------------

namespace {

class Reader {
 public:
  explicit Reader(const std::filesystem::path& path) : file_(path.string()) {}

  [[noreturn]] void fail(const std::string& what) const { throw CheckpointError(file_ + ": " + what); }
  [[noreturn]] void fail_hdf5(const std::string& what) const { fail(what + ": " + hdf5_reason()); }

  // An attribute with its dataspace and type, or none (not there and not required).
  struct Attribute {
    Handle attr, space, type;
  };
  std::optional<Attribute> attribute(hid_t loc, const char* name, bool required) const {
    const htri_t exists = H5Aexists(loc, name);
    if (exists < 0) fail_hdf5(fmt::format("attribute '{}' cannot be read", name));
    if (exists == 0) {
      if (!required) return std::nullopt;
      fail(fmt::format("attribute '{}' is missing", name));
    }
    Attribute a;
    a.attr = Handle(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
    if (!a.attr.ok()) fail_hdf5(fmt::format("attribute '{}' cannot be opened", name));
    a.space = Handle(H5Aget_space(a.attr.get()), H5Sclose);
    a.type = Handle(H5Aget_type(a.attr.get()), H5Tclose);
    if (!a.space.ok() || !a.type.ok()) fail_hdf5(fmt::format("attribute '{}' cannot be read", name));
    return a;
  }

  // A scalar numeric attribute of HDF5 class `cls`, converted to `type`.
  template <class T>
  T scalar(hid_t loc, const char* name, H5T_class_t cls, hid_t type) const {
    const Attribute a = *attribute(loc, name, true);
    if (H5Sget_simple_extent_npoints(a.space.get()) != 1)
      fail(fmt::format("attribute '{}' must be a single value, it holds {}", name, H5Sget_simple_extent_npoints(a.space.get())));
    if (H5Tget_class(a.type.get()) != cls)
      fail(fmt::format("attribute '{}' must be {}", name, cls == H5T_FLOAT ? "a floating-point number" : "an integer"));
    T value{};
    if (H5Aread(a.attr.get(), type, &value) < 0) fail_hdf5(fmt::format("attribute '{}' cannot be read", name));
    return value;
  }

  // A string attribute, fixed or variable length, at most kLargestText bytes.
  std::string text(hid_t loc, const char* name, bool required = true) const {
    const std::optional<Attribute> a = attribute(loc, name, required);
    if (!a) return {};
    if (H5Sget_simple_extent_npoints(a->space.get()) != 1 || H5Tget_class(a->type.get()) != H5T_STRING)
      fail(fmt::format("attribute '{}' must be one string", name));
    std::string s;
    Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_cset(mem.get(), H5Tget_cset(a->type.get()));  // ASCII or UTF-8 (h5py's default): no conversion
    if (H5Tis_variable_str(a->type.get()) > 0) {
      H5Tset_size(mem.get(), H5T_VARIABLE);
      char* value = nullptr;
      if (H5Aread(a->attr.get(), mem.get(), &value) < 0) fail_hdf5(fmt::format("attribute '{}' cannot be read", name));
      if (value) {
        s.assign(value, strnlen(value, kLargestText + 1));
        H5free_memory(value);
      }
    } else {
      const std::size_t n = H5Tget_size(a->type.get());
      if (n == 0 || n > kLargestText) fail(fmt::format("attribute '{}' is {} bytes long, more than a checkpoint holds", name, n));
      // One byte more than stored: a null-padded string of n characters keeps all n in a
      // null-terminated memory type (HDF5 would drop the last one for the terminator).
      s.assign(n + 1, '\0');
      H5Tset_size(mem.get(), n + 1);
      if (H5Aread(a->attr.get(), mem.get(), s.data()) < 0) fail_hdf5(fmt::format("attribute '{}' cannot be read", name));
      s.resize(strnlen(s.data(), n));
    }
    if (s.size() > kLargestText) fail(fmt::format("attribute '{}' is longer than a checkpoint holds", name));
    return s;
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

// A checkpoint's objects are its own: a link to another file (external) or to another path (soft)
// is refused, so that reading it reads nothing else.
void require_hard_link(const Reader& r, hid_t loc, const char* link, const std::string& what) {
  H5L_info_t info{};
  if (H5Lget_info(loc, link, &info, H5P_DEFAULT) < 0 || info.type != H5L_TYPE_HARD)
    r.fail(fmt::format("'{}' is a link to elsewhere, not part of the file", what));
}

// The dataset of a field, checked before anything is read: a one-dimensional array of `n` values of
// the field's type, with the Fletcher32 checksum (from version 3) and no other filter, its data all
// stored in the file. Returns the open dataset and adds its storage to `stored`.
Handle open_field(const Reader& r, hid_t group, const CheckpointDataset& d, hsize_t n, int version, hsize_t& stored) {
  const std::string name = "particles/" + d.name;
  const htri_t exists = H5Lexists(group, d.name.c_str(), H5P_DEFAULT);
  if (exists <= 0) r.fail(fmt::format("dataset '{}' is missing", name));
  require_hard_link(r, group, d.name.c_str(), name);
  H5O_info_t info{};
  if (H5Oget_info_by_name(group, d.name.c_str(), &info, H5P_DEFAULT) < 0 || info.type != H5O_TYPE_DATASET)
    r.fail(fmt::format("'{}' is not a dataset", name));
  Handle dset(H5Dopen2(group, d.name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!dset.ok()) r.fail_hdf5(fmt::format("dataset '{}' cannot be opened", name));
  Handle space(H5Dget_space(dset.get()), H5Sclose);
  if (!space.ok()) r.fail_hdf5(fmt::format("dataset '{}' cannot be read", name));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != 1) r.fail(fmt::format("dataset '{}' must be one-dimensional, it has rank {}", name, rank));
  hsize_t length = 0;
  H5Sget_simple_extent_dims(space.get(), &length, nullptr);
  if (length != n) r.fail(fmt::format("dataset '{}' holds {} values, the particle ids {}", name, length, n));
  Handle type(H5Dget_type(dset.get()), H5Tclose);
  if (!type.ok()) r.fail_hdf5(fmt::format("dataset '{}' cannot be read", name));
  const H5T_class_t cls = H5Tget_class(type.get());
  const std::size_t size = H5Tget_size(type.get());
  const std::size_t elem_size = field_type_size(d.type);
  const bool is_float = d.type == FieldType::F32;
  const bool type_ok = is_float ? (cls == H5T_FLOAT && size == 4)
                                : (cls == H5T_INTEGER && size == elem_size && H5Tget_sign(type.get()) == H5T_SGN_NONE);
  if (!type_ok)
    r.fail(fmt::format("dataset '{}' must hold {}", name,
                       is_float ? "32-bit floats" : elem_size == 4 ? "unsigned 32-bit integers" : "unsigned 8-bit integers"));
  Handle dcpl(H5Dget_create_plist(dset.get()), H5Pclose);
  if (!dcpl.ok()) r.fail_hdf5(fmt::format("dataset '{}' cannot be read", name));
  // Its data in this file: no external raw files, no virtual dataset mapping other files.
  const H5D_layout_t layout = H5Pget_layout(dcpl.get());
  if ((layout != H5D_CONTIGUOUS && layout != H5D_CHUNKED && layout != H5D_COMPACT) || H5Pget_external_count(dcpl.get()) != 0)
    r.fail(fmt::format("dataset '{}' keeps its data outside the file (external or virtual storage)", name));
  const int filters = H5Pget_nfilters(dcpl.get());
  bool fletcher = false;
  for (int k = 0; k < filters; ++k) {
    unsigned flags = 0;
    std::size_t nvalues = 0;
    const H5Z_filter_t id = H5Pget_filter2(dcpl.get(), static_cast<unsigned>(k), &flags, &nvalues, nullptr, 0, nullptr, nullptr);
    if (id == H5Z_FILTER_FLETCHER32) fletcher = true;
    else r.fail(fmt::format("dataset '{}' has a filter spate does not write (HDF5 filter {})", name, static_cast<int>(id)));
  }
  if (version >= kCheckedVersion && !fletcher) r.fail(fmt::format("dataset '{}' has no Fletcher32 checksum", name));
  // Every value must be in the file: a dataset whose storage was never written reads as zeros.
  const hsize_t storage = H5Dget_storage_size(dset.get());
  if (storage < n * elem_size)
    r.fail(fmt::format("dataset '{}' stores {} bytes, {} values of {} bytes need {} (a short or unwritten dataset)", name, storage, n,
                       elem_size, n * elem_size));
  stored += storage;
  return dset;
}

// The first "key: value" line where two geometry signatures differ.
std::string first_difference(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    const std::size_t ei = std::min(a.find('\n', i), a.size()), ej = std::min(b.find('\n', j), b.size());
    const std::string la = a.substr(i, ei - i), lb = b.substr(j, ej - j);
    if (la != lb) {
      const auto colon = la.find(':');
      const std::string key = colon != std::string::npos ? la.substr(0, colon) : lb.substr(0, lb.find(':'));
      const auto value = [](const std::string& line) {
        const auto c = line.find(": ");
        return c == std::string::npos ? std::string("(none)") : line.substr(c + 2);
      };
      return fmt::format("{} is {} in the checkpoint, {} in the case", key.empty() ? "the particle set" : key, value(la), value(lb));
    }
    i = ei + 1;
    j = ej + 1;
  }
  return "the particle sets differ";
}

// The values after reading: finite, materials the case has, ids unique and below the case's count,
// positions inside the domain (a position outside would index past the cell arrays).
void check_values(const Reader& r, ParticleStore& p, const std::vector<CheckpointDataset>& datasets, const Case& c, const Lattice& L,
                  std::int64_t generated) {
  const std::size_t n = p.size();
  auto fields = p.fields();
  std::string material = "material";
  for (const CheckpointDataset& d : datasets) {
    if (fields[d.field].spec->member == "material") material = d.name;
    if (d.type != FieldType::F32) continue;
    const float* v = reinterpret_cast<const float*>(fields[d.field].bytes());
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isfinite(v[i])) r.fail(fmt::format("dataset 'particles/{}': value {} of particle {} is not finite", d.name, v[i], p.id[i]));
  }
  std::vector<std::uint32_t> ids(p.id.begin(), p.id.end());
  std::sort(ids.begin(), ids.end());
  if (const auto twice = std::adjacent_find(ids.begin(), ids.end()); twice != ids.end())
    r.fail(fmt::format("dataset 'particles/id': id {} appears twice", *twice));
  if (!ids.empty() && ids.back() >= generated)
    r.fail(fmt::format("dataset 'particles/id': id {} is out of range (the case generates {} particles)", ids.back(), generated));
  const MaterialTable M = physics_params(c).materials;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t id = p.id[i];
    const std::uint8_t k = p.material[i];
    if (k >= M.count)
      r.fail(fmt::format("dataset 'particles/{}': particle {} has material {}, which the case does not have (0 to {} fluids, {} the "
                         "tank, then its {} solids)",
                         material, id, static_cast<int>(k), M.fluids - 1, M.tank(), c.solids.size()));
    if (!(p.density[i] > 0)) r.fail(fmt::format("dataset 'particles/density': particle {} has density {}", id, p.density[i]));
    for (int a = 0; a < c.dim; ++a)
      if (position_fault(L, p.pos[a][i], a) != PositionFault::None)
        r.fail(fmt::format("dataset 'particles/{}': particle {} at {} m lies outside the domain [{}, {}] m", "xyz"[a], id, p.pos[a][i],
                           L.origin[a], L.upper(a)));
  }
}

}  // namespace

CheckpointMeta read_checkpoint(const std::filesystem::path& path, ParticleStore& particles, const Case* run_case) {
  quiet_hdf5();
  const Reader r(path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) r.fail("no such checkpoint file");
  if (std::filesystem::is_directory(path, ec)) r.fail("is a folder, not a checkpoint file");
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) r.fail_hdf5("not an HDF5 file (or unreadable)");

  // The header.
  const std::string format = H5Aexists(file.get(), "format") > 0 ? r.text(file.get(), "format") : std::string();
  if (!format.starts_with(kFormatPrefix))
    r.fail(fmt::format("not a spate checkpoint (attribute 'format' is not '{}<version>')", kFormatPrefix));
  CheckpointMeta meta;
  // The version: the integer attribute (from version 2), else the format string's number.
  int version = 0;
  if (H5Aexists(file.get(), "format_version") > 0) {
    version = r.scalar<int>(file.get(), "format_version", H5T_INTEGER, H5T_NATIVE_INT);
  } else {
    const std::string number = format.substr(std::string_view(kFormatPrefix).size());
    version = number == "1" ? 1 : 0;
  }
  if (format != format_name(version) || version < 1 || version > kCheckpointFormatVersion)
    r.fail(fmt::format("checkpoint format '{}' (version {}); this spate reads versions 1 to {}", format, version, kCheckpointFormatVersion));
  meta.format_version = version;
  meta.step = r.scalar<std::int64_t>(file.get(), "step", H5T_INTEGER, H5T_NATIVE_INT64);
  meta.time = r.scalar<double>(file.get(), "time", H5T_FLOAT, H5T_NATIVE_DOUBLE);
  meta.dt = r.scalar<double>(file.get(), "dt", H5T_FLOAT, H5T_NATIVE_DOUBLE);
  const int dim = r.scalar<int>(file.get(), "dimensions", H5T_INTEGER, H5T_NATIVE_INT);
  meta.case_name = r.text(file.get(), "case_name");
  meta.case_yaml = r.text(file.get(), "case_yaml");
  meta.steering_log = r.text(file.get(), "steering_log", false);
  if (version >= kCheckedVersion) {
    meta.removed = r.scalar<std::int64_t>(file.get(), "removed_particles", H5T_INTEGER, H5T_NATIVE_INT64);
    meta.geometry_hash = r.text(file.get(), "geometry_hash");
    meta.bodies = r.text(file.get(), "bodies", false);
    meta.drive = r.text(file.get(), "drive", false);
    meta.closed_volume = r.text(file.get(), "closed_volume", false);
  }
  if (dim != 2 && dim != 3) r.fail(fmt::format("attribute 'dimensions' is {}, must be 2 or 3", dim));
  if (meta.step < 0 || meta.step > kLargestStep) r.fail(fmt::format("attribute 'step' is {}, not a step number", meta.step));
  if (!std::isfinite(meta.time) || meta.time < 0) r.fail(fmt::format("attribute 'time' is {}, must be finite and >= 0", meta.time));
  if (!std::isfinite(meta.dt) || !(meta.dt > 0)) r.fail(fmt::format("attribute 'dt' is {}, must be finite and > 0", meta.dt));
  if (meta.removed < 0) r.fail(fmt::format("attribute 'removed_particles' is {}, must be >= 0", meta.removed));
  if (version >= kCheckedVersion && r.text(file.get(), "header_checksum") != header_checksum(meta, dim))
    r.fail("attribute 'header_checksum' does not match the header: the file is damaged");

  // The case it ran, as every case is checked, and the particle set it generates.
  Case own;
  try {
    own = parse_case(meta.case_yaml, path.string() + " (attribute case_yaml)");
  } catch (const CaseError& e) {
    r.fail(std::string("attribute 'case_yaml' is not a valid case: ") + e.what());
  }
  if (own.dim != dim) r.fail(fmt::format("attribute 'dimensions' is {}, its case is {}D", dim, own.dim));
  if (version >= kCheckedVersion && meta.geometry_hash != geometry_hash(own))
    r.fail(has_shapes(own) ? "attribute 'geometry_hash' does not belong to attribute 'case_yaml': a mesh file the case names has "
                             "changed since the checkpoint was written (its hash is part of the geometry's), or the file is damaged"
                           : "attribute 'geometry_hash' does not belong to attribute 'case_yaml': the file is damaged");
  if (run_case) {
    if (run_case->dim != dim) r.fail(fmt::format("the checkpoint holds a {}D case ('{}'), {} is {}D", dim, own.name, run_case->file, run_case->dim));
    if (version >= kCheckedVersion && meta.geometry_hash != geometry_hash(*run_case))
      r.fail(fmt::format("the checkpoint holds case '{}' with another particle set than {} ({}); restart with the case that wrote it",
                         own.name, run_case->file, first_difference(geometry_signature(own), geometry_signature(*run_case))));
  }
  const Case& domain_case = run_case ? *run_case : own;
  const ParticleCounts generated = count_particles(domain_case);
  // The steering history through the checks a live change gets.
  std::vector<SteeringChange>& history = meta.steering_history;
  try {
    history = parse_log(meta.steering_log, path.string() + " (attribute steering_log)", dim);
  } catch (const std::exception& e) {
    throw CheckpointError(e.what());
  }
  if (!history.empty() && history.back().step > meta.step)
    r.fail(fmt::format("attribute 'steering_log': a change at step {}, after the checkpoint's step {}", history.back().step, meta.step));
  // A phase_viscosity change must name one of the case's fluids, a face change one of its walls.
  for (const SteeringChange& change : history)
    if (auto why = validate(change, dim, nullptr, &domain_case))
      r.fail(fmt::format("attribute 'steering_log', step {}: {}", change.step, *why));

  // The datasets, before anything is allocated.
  H5O_info_t info{};
  if (H5Lexists(file.get(), "particles", H5P_DEFAULT) <= 0) r.fail("group 'particles' is missing");
  require_hard_link(r, file.get(), "particles", "particles");
  if (H5Oget_info_by_name(file.get(), "particles", &info, H5P_DEFAULT) < 0 || info.type != H5O_TYPE_GROUP)
    r.fail("'particles' is not a group");
  Handle group(H5Gopen2(file.get(), "particles", H5P_DEFAULT), H5Gclose);
  if (!group.ok()) r.fail_hdf5("group 'particles' cannot be opened");
  hsize_t n = 0;
  {
    if (H5Lexists(group.get(), "id", H5P_DEFAULT) <= 0) r.fail("dataset 'particles/id' is missing");
    require_hard_link(r, group.get(), "id", "particles/id");
    Handle ids(H5Dopen2(group.get(), "id", H5P_DEFAULT), H5Dclose);
    if (!ids.ok()) r.fail_hdf5("dataset 'particles/id' cannot be opened");
    Handle space(H5Dget_space(ids.get()), H5Sclose);
    if (!space.ok() || H5Sget_simple_extent_ndims(space.get()) != 1) r.fail("dataset 'particles/id' must be one-dimensional");
    H5Sget_simple_extent_dims(space.get(), &n, nullptr);
  }
  if (static_cast<std::int64_t>(n) + meta.removed != generated.total() || meta.removed > generated.fluid)
    r.fail(fmt::format("the checkpoint holds {} particles and records {} removed, but {} generates {} ({} fluid)", n, meta.removed,
                       run_case ? run_case->file : "its case", generated.total(), generated.fluid));
  // The datasets the field registry declares for this version (a dataset the registry does not
  // know is ignored).
  std::vector<CheckpointDataset> expected = checkpoint_datasets(dim, version);
  std::vector<Handle> datasets;
  hsize_t stored = 0;
  for (const CheckpointDataset& d : expected) datasets.push_back(open_field(r, group.get(), d, n, version, stored));
  // The derived fields as they were, checked the same way when there (older files: left zero).
  meta.derived_saved = true;
  for (const CheckpointDataset& d : derived_datasets(dim)) {
    if (H5Lexists(group.get(), d.name.c_str(), H5P_DEFAULT) <= 0) {
      meta.derived_saved = false;
      continue;
    }
    datasets.push_back(open_field(r, group.get(), d, n, version, stored));
    expected.push_back(d);
  }
  hsize_t file_size = 0;
  if (H5Fget_filesize(file.get(), &file_size) < 0 || stored > file_size)
    r.fail(fmt::format("the datasets claim {} bytes of a file of {} bytes (a truncated file)", stored, file_size));
  const std::int64_t need = checkpoint_read_bytes(dim, static_cast<std::int64_t>(n));
  if (const AvailableMemory have = available_memory(); need > have.bytes)
    r.fail(fmt::format("reading its {} particles needs about {}, more than the {} this machine can give ({})", n,
                       format_bytes(static_cast<double>(need)), format_bytes(static_cast<double>(have.bytes)), have.source));

  // The data (HDF5 verifies every chunk's Fletcher32 checksum here), then the values.
  particles = ParticleStore(dim);
  particles.resize(n);
  auto fields = particles.fields();
  for (std::size_t k = 0; k < expected.size(); ++k) {
    const CheckpointDataset& d = expected[k];
    if (n > 0 && H5Dread(datasets[k].get(), h5_type(d.type), H5S_ALL, H5S_ALL, H5P_DEFAULT, fields[d.field].bytes()) < 0)
      r.fail_hdf5(fmt::format("dataset 'particles/{}' cannot be read (damaged data)", d.name));
  }
  particles.set_owned(n);
  check_values(r, particles, expected, domain_case, make_lattice(domain_case), generated.total());
  return meta;
}

}  // namespace spate
