#include "checkpoint.hpp"

#include <hdf5.h>

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace spate {

namespace {

// "spate-checkpoint-<version>"; version 2 also has an integer attribute format_version.
constexpr const char* kFormatPrefix = "spate-checkpoint-";

hid_t h5_type(FieldType t) {
  switch (t) {
    case FieldType::F32: return H5T_NATIVE_FLOAT;
    case FieldType::U32: return H5T_NATIVE_UINT32;
    case FieldType::U8: return H5T_NATIVE_UINT8;
  }
  return H5T_NATIVE_FLOAT;
}

void check(herr_t status, const std::filesystem::path& path, const std::string& what) {
  if (status < 0) throw std::runtime_error(path.string() + ": HDF5 error while " + what);
}

void write_attr(hid_t loc, const char* name, hid_t type, const void* value) {
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t attr = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attr, type, value);
  H5Aclose(attr);
  H5Sclose(space);
}

void write_string_attr(hid_t loc, const char* name, const std::string& value) {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.empty() ? 1 : value.size());
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t attr = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(attr, type, value.empty() ? "" : value.data());
  H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
}

bool read_attr(hid_t loc, const char* name, hid_t type, void* value) {
  if (H5Aexists(loc, name) <= 0) return false;
  hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
  const herr_t s = H5Aread(attr, type, value);
  H5Aclose(attr);
  return s >= 0;
}

std::string read_string_attr(hid_t loc, const char* name) {
  if (H5Aexists(loc, name) <= 0) return {};
  hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
  hid_t type = H5Aget_type(attr);
  const std::size_t n = H5Tget_size(type);
  std::string s(n, '\0');
  hid_t mem = H5Tcopy(H5T_C_S1);
  H5Tset_size(mem, n);
  H5Aread(attr, mem, s.data());
  H5Tclose(mem);
  H5Tclose(type);
  H5Aclose(attr);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

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
  const std::filesystem::path path = xdmf_sidecar(h5), tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!out) throw std::runtime_error(tmp.string() + ": cannot write");
  }
  std::filesystem::rename(tmp, path);
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
  const std::filesystem::path tmp = path.string() + ".tmp";
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  hid_t file = H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error(tmp.string() + ": cannot create checkpoint file");
  const std::string format = kFormatPrefix + std::to_string(kCheckpointFormatVersion);
  write_string_attr(file, "format", format);
  write_attr(file, "format_version", H5T_NATIVE_INT, &kCheckpointFormatVersion);
  write_attr(file, "step", H5T_NATIVE_INT64, &meta.step);
  write_attr(file, "time", H5T_NATIVE_DOUBLE, &meta.time);
  write_attr(file, "dt", H5T_NATIVE_DOUBLE, &meta.dt);
  write_attr(file, "dimensions", H5T_NATIVE_INT, &dim);
  write_string_attr(file, "case_name", meta.case_name);
  write_string_attr(file, "case_yaml", meta.case_yaml);
  write_string_attr(file, "steering_log", meta.steering_log);
  hid_t group = H5Gcreate2(file, "particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t n = count;
  std::vector<char> buffer;  // one field at a time
  std::vector<CheckpointDataset> datasets = checkpoint_datasets(dim);
  for (auto& d : derived_datasets(dim)) datasets.push_back(d);
  for (const CheckpointDataset& d : datasets) {
    buffer.resize(count * field_type_size(d.type));
    if (count > 0) fill(d.field, buffer.data());
    hid_t space = H5Screate_simple(1, &n, nullptr);
    hid_t dset = H5Dcreate2(group, d.name.c_str(), h5_type(d.type), space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (n > 0) check(H5Dwrite(dset, h5_type(d.type), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()), tmp, "writing " + d.name);
    H5Dclose(dset);
    H5Sclose(space);
  }
  H5Gclose(group);
  check(H5Fclose(file), tmp, "closing");
  std::filesystem::rename(tmp, path);
  write_xdmf(path, meta, dim, count);
}

CheckpointMeta read_checkpoint(const std::filesystem::path& path, ParticleStore& particles) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path.string() + ": no such checkpoint file");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error(path.string() + ": not an HDF5 file (or unreadable)");
  struct Closer {
    hid_t f;
    ~Closer() { H5Fclose(f); }
  } closer{file};
  const std::string format = read_string_attr(file, "format");
  if (!format.starts_with(kFormatPrefix))
    throw std::runtime_error(path.string() + ": not a spate checkpoint (attribute 'format' is not '" + kFormatPrefix + "<version>')");
  int version = 0;
  if (!read_attr(file, "format_version", H5T_NATIVE_INT, &version)) {
    try {
      version = std::stoi(format.substr(std::string_view(kFormatPrefix).size()));
    } catch (const std::exception&) {
      version = 0;
    }
  }
  if (version < 1 || version > kCheckpointFormatVersion)
    throw std::runtime_error(path.string() + ": checkpoint format version " + std::to_string(version) + " ('" + format +
                             "'); this spate reads versions 1 to " + std::to_string(kCheckpointFormatVersion));
  CheckpointMeta meta;
  meta.format_version = version;
  int dim = 0;
  if (!read_attr(file, "step", H5T_NATIVE_INT64, &meta.step) || !read_attr(file, "time", H5T_NATIVE_DOUBLE, &meta.time) ||
      !read_attr(file, "dt", H5T_NATIVE_DOUBLE, &meta.dt) || !read_attr(file, "dimensions", H5T_NATIVE_INT, &dim))
    throw std::runtime_error(path.string() + ": checkpoint header is incomplete");
  meta.case_name = read_string_attr(file, "case_name");
  meta.case_yaml = read_string_attr(file, "case_yaml");
  meta.steering_log = read_string_attr(file, "steering_log");
  particles = ParticleStore(dim);
  hid_t group = H5Gopen2(file, "particles", H5P_DEFAULT);
  if (group < 0) throw std::runtime_error(path.string() + ": checkpoint has no 'particles' group");
  hid_t id_set = H5Dopen2(group, "id", H5P_DEFAULT);
  if (id_set < 0) throw std::runtime_error(path.string() + ": checkpoint has no particle ids");
  hid_t space = H5Dget_space(id_set);
  hsize_t n = 0;
  H5Sget_simple_extent_dims(space, &n, nullptr);
  H5Sclose(space);
  H5Dclose(id_set);
  particles.resize(n);
  auto fields = particles.fields();
  for (const CheckpointDataset& d : checkpoint_datasets(dim, version)) {
    hid_t dset = H5Dopen2(group, d.name.c_str(), H5P_DEFAULT);
    if (dset < 0) throw std::runtime_error(path.string() + ": checkpoint lacks field '" + d.name + "'");
    if (n > 0 && H5Dread(dset, h5_type(d.type), H5S_ALL, H5S_ALL, H5P_DEFAULT, fields[d.field].bytes()) < 0)
      throw std::runtime_error(path.string() + ": cannot read field '" + d.name + "'");
    H5Dclose(dset);
  }
  // The derived fields as they were (files written before they were saved: left zero).
  meta.derived_saved = true;
  for (const CheckpointDataset& d : derived_datasets(dim)) {
    if (H5Lexists(group, d.name.c_str(), H5P_DEFAULT) <= 0) {
      meta.derived_saved = false;
      continue;
    }
    hid_t dset = H5Dopen2(group, d.name.c_str(), H5P_DEFAULT);
    if (dset < 0 || (n > 0 && H5Dread(dset, h5_type(d.type), H5S_ALL, H5S_ALL, H5P_DEFAULT, fields[d.field].bytes()) < 0))
      throw std::runtime_error(path.string() + ": cannot read field '" + d.name + "'");
    H5Dclose(dset);
  }
  H5Gclose(group);
  particles.set_owned(n);
  return meta;
}

}  // namespace spate
