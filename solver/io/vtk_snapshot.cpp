#include "vtk_snapshot.hpp"

#include <cstdint>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace spate {

namespace {

struct Array {
  std::string name, type;
  int components;
  std::vector<char> bytes;
};

template <class T>
Array make_array(const std::string& name, const std::string& type, int components, std::size_t n,
                 const std::vector<const T*>& sources) {
  Array a{name, type, components, {}};
  a.bytes.resize(n * components * sizeof(T));
  T* out = reinterpret_cast<T*>(a.bytes.data());
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < components; ++k) out[i * components + k] = sources[k] ? sources[k][i] : T{};
  return a;
}

void write_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out) throw std::runtime_error(tmp.string() + ": cannot write");
  }
  std::filesystem::rename(tmp, path);
}

const char* vtk_type(FieldType t) {
  switch (t) {
    case FieldType::F32: return "Float32";
    case FieldType::U32: return "UInt32";
    case FieldType::U8: return "UInt8";
  }
  return "Float32";
}

// Vectors get 3 components (zero beyond dim), as ParaView expects.
Array field_array(const ExportedField& f, std::size_t n) {
  const int components = f.spec->shape == FieldShape::Vector ? 3 : 1;
  const std::string name(f.spec->exported);
  auto sources = [&](auto* type_tag) {
    using T = std::remove_pointer_t<decltype(type_tag)>;
    std::vector<const T*> s(components, nullptr);
    for (int k = 0; k < components; ++k) s[k] = reinterpret_cast<const T*>(f.data[k]);
    return make_array<T>(name, vtk_type(f.spec->type), components, n, s);
  };
  switch (f.spec->type) {
    case FieldType::U32: return sources(static_cast<std::uint32_t*>(nullptr));
    case FieldType::U8: return sources(static_cast<std::uint8_t*>(nullptr));
    default: return sources(static_cast<float*>(nullptr));
  }
}

}  // namespace

// Every exported field of the registry (field_registry.hpp): positions as the points, the others
// as point data under their exported names, then the owning slab ("device").
void write_vtp_piece(const std::filesystem::path& path, ParticleStore& p, int slab) {
  const std::size_t n = p.owned();
  std::vector<Array> point_data;
  Array points;
  for (const ExportedField& f : exported_fields(p)) {
    if (f.spec->member == "pos") points = field_array(f, n), points.name = "Points";
    else point_data.push_back(field_array(f, n));
  }
  std::vector<std::int32_t> owner(n, slab);
  point_data.push_back(make_array<std::int32_t>("device", "Int32", 1, n, {owner.data()}));
  std::vector<std::int64_t> conn(n), offs(n);
  for (std::size_t i = 0; i < n; ++i) conn[i] = static_cast<std::int64_t>(i), offs[i] = static_cast<std::int64_t>(i + 1);
  Array connectivity = make_array<std::int64_t>("connectivity", "Int64", 1, n, {conn.data()});
  Array offsets = make_array<std::int64_t>("offsets", "Int64", 1, n, {offs.data()});

  std::ostringstream xml;
  std::uint64_t offset = 0;
  auto header = [&](const Array& a) {
    xml << "<DataArray type=\"" << a.type << "\" Name=\"" << a.name << "\" NumberOfComponents=\"" << a.components
        << "\" format=\"appended\" offset=\"" << offset << "\"/>\n";
    offset += sizeof(std::uint64_t) + a.bytes.size();
  };
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      << "<PolyData>\n<Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"" << n
      << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n<PointData Scalars=\"pressure\" Vectors=\"velocity\">\n";
  for (auto& a : point_data) header(a);
  xml << "</PointData>\n<Points>\n";
  header(points);
  xml << "</Points>\n<Verts>\n";
  header(connectivity);
  header(offsets);
  xml << "</Verts>\n</Piece>\n</PolyData>\n<AppendedData encoding=\"raw\">\n_";
  std::string text = xml.str();
  auto append = [&](const Array& a) {
    const std::uint64_t size = a.bytes.size();
    text.append(reinterpret_cast<const char*>(&size), sizeof size);
    text.append(a.bytes.data(), a.bytes.size());
  };
  for (auto& a : point_data) append(a);
  append(points);
  append(connectivity);
  append(offsets);
  text += "\n</AppendedData>\n</VTKFile>\n";
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  write_atomically(path, text);
}

void write_vtm(const std::filesystem::path& path, const std::vector<std::string>& piece_files) {
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<vtkMultiBlockDataSet>\n";
  for (std::size_t k = 0; k < piece_files.size(); ++k)
    xml << "  <DataSet index=\"" << k << "\" name=\"device" << k << "\" file=\"" << piece_files[k] << "\"/>\n";
  xml << "</vtkMultiBlockDataSet>\n</VTKFile>\n";
  write_atomically(path, xml.str());
}

void PvdIndex::add(double time, const std::string& relative_file) {
  entries_.emplace_back(time, relative_file);
  std::ostringstream xml;
  xml.precision(17);
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n";
  for (auto& [t, f] : entries_) xml << "  <DataSet timestep=\"" << t << "\" group=\"\" part=\"0\" file=\"" << f << "\"/>\n";
  xml << "</Collection>\n</VTKFile>\n";
  write_atomically(path_, xml.str());
}

void PvdIndex::load_existing(double up_to_time) {
  entries_.clear();
  std::ifstream in(path_);
  if (!in) return;
  const std::regex entry("timestep=\"([^\"]+)\"[^>]*file=\"([^\"]+)\"");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, entry)) {
      const double t = std::stod(m[1]);
      if (t <= up_to_time) entries_.emplace_back(t, m[2]);
    }
  }
}

}  // namespace spate
