#include "checkpoint.hpp"

#include <hdf5.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace spate {

namespace {

constexpr const char* kFormat = "spate-checkpoint-1";

hid_t h5_type(std::size_t elem_size) { return elem_size == 1 ? H5T_NATIVE_UINT8 : H5T_NATIVE_FLOAT; }
hid_t h5_type(const FieldRef& f) { return f.name == "id" ? H5T_NATIVE_UINT32 : h5_type(f.elem_size); }

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
  write_string_attr(file, "format", kFormat);
  write_attr(file, "step", H5T_NATIVE_INT64, &meta.step);
  write_attr(file, "time", H5T_NATIVE_DOUBLE, &meta.time);
  write_attr(file, "dt", H5T_NATIVE_DOUBLE, &meta.dt);
  write_attr(file, "dimensions", H5T_NATIVE_INT, &dim);
  write_string_attr(file, "case_name", meta.case_name);
  write_string_attr(file, "case_yaml", meta.case_yaml);
  write_string_attr(file, "steering_log", meta.steering_log);
  hid_t group = H5Gcreate2(file, "particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t n = count;
  ParticleStore layout(dim);  // empty: only the field list (names, sizes, flags)
  const auto fields = layout.fields();
  std::vector<char> buffer;  // one field at a time
  for (std::size_t k = 0; k < fields.size(); ++k) {
    const FieldRef& f = fields[k];
    if (!f.checkpoint) continue;
    buffer.resize(count * f.elem_size);
    if (count > 0) fill(k, buffer.data());
    hid_t space = H5Screate_simple(1, &n, nullptr);
    hid_t dset = H5Dcreate2(group, std::string(f.name).c_str(), h5_type(f), space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (n > 0) check(H5Dwrite(dset, h5_type(f), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()), tmp, "writing " + std::string(f.name));
    H5Dclose(dset);
    H5Sclose(space);
  }
  H5Gclose(group);
  check(H5Fclose(file), tmp, "closing");
  std::filesystem::rename(tmp, path);
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
  if (read_string_attr(file, "format") != kFormat)
    throw std::runtime_error(path.string() + ": not a spate checkpoint (attribute 'format' is not '" + kFormat + "')");
  CheckpointMeta meta;
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
  for (auto& f : particles.fields()) {
    if (!f.checkpoint) continue;
    hid_t dset = H5Dopen2(group, std::string(f.name).c_str(), H5P_DEFAULT);
    if (dset < 0) throw std::runtime_error(path.string() + ": checkpoint lacks field '" + std::string(f.name) + "'");
    if (n > 0 && H5Dread(dset, h5_type(f), H5S_ALL, H5S_ALL, H5P_DEFAULT, f.bytes()) < 0)
      throw std::runtime_error(path.string() + ": cannot read field '" + std::string(f.name) + "'");
    H5Dclose(dset);
  }
  H5Gclose(group);
  particles.set_owned(n);
  return meta;
}

}  // namespace spate
