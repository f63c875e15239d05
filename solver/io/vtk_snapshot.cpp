#include "vtk_snapshot.hpp"

#include "../physics/materials.hpp"
#include "output_file.hpp"

#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <type_traits>


namespace spate {

namespace {

// VTK's zlib compression of appended data: each array is cut into blocks of kBlock bytes, each
// compressed on its own (so they compress in parallel), behind a header of UInt64 words
// [blocks, block size, size of the last block if partial (else 0), compressed size of each block].
// Level 1: particle floats barely compress further at higher levels, and it is the fastest.
constexpr std::size_t kBlock = std::size_t{1} << 20;
constexpr int kLevel = 1;
constexpr const char* kCompressor = "vtkZLibDataCompressor";

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

std::string compress(const std::vector<char>& raw) {
  const std::size_t blocks = (raw.size() + kBlock - 1) / kBlock;
  std::vector<std::string> packed(blocks);
  bool ok = true;
#pragma omp parallel for schedule(dynamic) reduction(&& : ok) if (blocks > 1)
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::size_t size = std::min(kBlock, raw.size() - b * kBlock);
    uLongf out = compressBound(size);
    packed[b].resize(out);
    ok = ok && compress2(reinterpret_cast<Bytef*>(packed[b].data()), &out, reinterpret_cast<const Bytef*>(raw.data() + b * kBlock), size,
                         kLevel) == Z_OK;
    packed[b].resize(out);
  }
  if (!ok) throw std::runtime_error("zlib failed to compress a snapshot array");
  std::vector<std::uint64_t> header = {blocks, kBlock, raw.size() % kBlock};
  for (auto& p : packed) header.push_back(p.size());
  std::string out(reinterpret_cast<const char*>(header.data()), header.size() * sizeof(std::uint64_t));
  for (auto& p : packed) out += p;
  return out;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The value of attribute `name` in an XML tag's text, or `fallback`.
std::string attribute(const std::string& tag, const std::string& name, const std::string& fallback = {}) {
  const std::regex re("\\b" + name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(tag, m, re) ? m[1].str() : fallback;
}

// One appended array of a piece: its bytes, uncompressed.
std::vector<char> appended_array(const std::string& file, std::size_t data_start, std::uint64_t offset, bool wide_header,
                                 bool compressed, const std::filesystem::path& path, const std::string& name) {
  auto fail = [&](const std::string& why) { throw std::runtime_error(path.string() + ": array '" + name + "': " + why); };
  std::size_t at = data_start + offset;
  const std::size_t word = wide_header ? 8 : 4;
  auto next_word = [&]() -> std::uint64_t {
    if (at + word > file.size()) fail("truncated");
    std::uint64_t v = 0;
    std::memcpy(&v, file.data() + at, word);  // little endian
    at += word;
    return v;
  };
  std::vector<char> out;
  if (!compressed) {
    const std::uint64_t size = next_word();
    if (at + size > file.size()) fail("truncated");
    out.assign(file.data() + at, file.data() + at + size);
    return out;
  }
  const std::uint64_t blocks = next_word(), block = next_word(), last = next_word();
  std::vector<std::uint64_t> sizes(blocks);
  for (auto& s : sizes) s = next_word();
  out.resize(blocks == 0 ? 0 : (blocks - 1) * block + (last ? last : block));
  for (std::uint64_t b = 0; b < blocks; ++b) {
    uLongf size = (b + 1 == blocks && last) ? last : block;
    if (at + sizes[b] > file.size()) fail("truncated");
    if (uncompress(reinterpret_cast<Bytef*>(out.data() + b * block), &size, reinterpret_cast<const Bytef*>(file.data() + at), sizes[b]) != Z_OK)
      fail("corrupt compressed data");
    at += sizes[b];
  }
  return out;
}

}  // namespace

// Every exported field of the registry (field_registry.hpp): positions as the points, the others
// as point data under their exported names, then the owning slab ("device") and, with several
// fluids, the phase ("phase").
void write_vtp_piece(const std::filesystem::path& path, ParticleStore& p, int slab, int fluids) {
  const std::size_t n = p.owned();
  std::vector<Array> point_data;
  Array points;
  for (const ExportedField& f : exported_fields(p)) {
    if (f.spec->member == "pos") points = field_array(f, n), points.name = "Points";
    else point_data.push_back(field_array(f, n));
  }
  std::vector<std::int32_t> owner(n, slab);
  point_data.push_back(make_array<std::int32_t>("device", "Int32", 1, n, {owner.data()}));
  if (fluids > 1) {  // several fluids: each particle's phase (materials.hpp, phase_of)
    std::vector<std::int8_t> phase(n);
    for (std::size_t i = 0; i < n; ++i) phase[i] = phase_of(p.material[i], fluids);
    point_data.push_back(make_array<std::int8_t>("phase", "Int8", 1, n, {phase.data()}));
  }
  // One vertex cell per particle: connectivity 0..n-1, offsets 1..n, 32-bit while they fit.
  Array connectivity, offsets;
  auto cells = [&]<class T>(const char* type) {
    std::vector<T> conn(n), offs(n);
    for (std::size_t i = 0; i < n; ++i) conn[i] = static_cast<T>(i), offs[i] = static_cast<T>(i + 1);
    connectivity = make_array<T>("connectivity", type, 1, n, {conn.data()});
    offsets = make_array<T>("offsets", type, 1, n, {offs.data()});
  };
  if (n < static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) cells.template operator()<std::int32_t>("Int32");
  else cells.template operator()<std::int64_t>("Int64");

  std::vector<std::string> blobs;
  std::ostringstream xml;
  std::uint64_t offset = 0;
  auto header = [&](const Array& a) {
    xml << "<DataArray type=\"" << a.type << "\" Name=\"" << a.name << "\" NumberOfComponents=\"" << a.components
        << "\" format=\"appended\" offset=\"" << offset << "\"/>\n";
    blobs.push_back(compress(a.bytes));
    offset += blobs.back().size();
  };
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\""
      << kCompressor << "\">\n<PolyData>\n<Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"" << n
      << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n<PointData Scalars=\"pressure\" Vectors=\"velocity\">\n";
  for (auto& a : point_data) header(a);
  xml << "</PointData>\n<Points>\n";
  header(points);
  xml << "</Points>\n<Verts>\n";
  header(connectivity);
  header(offsets);
  xml << "</Verts>\n</Piece>\n</PolyData>\n<AppendedData encoding=\"raw\">\n_";
  std::string text = xml.str();
  for (auto& b : blobs) text += b;
  text += "\n</AppendedData>\n</VTKFile>\n";
  if (path.has_parent_path()) create_output_folder(path.parent_path());
  write_file_atomically(path, text);
}

void write_vtm(const std::filesystem::path& path, const std::vector<std::string>& piece_files, const FieldData& field_data) {
  std::ostringstream xml;
  xml.precision(17);
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<vtkMultiBlockDataSet>\n";
  for (std::size_t k = 0; k < piece_files.size(); ++k)
    xml << "  <DataSet index=\"" << k << "\" name=\"slab_" << k << "\" file=\"" << piece_files[k] << "\"/>\n";
  xml << "</vtkMultiBlockDataSet>\n";
  if (!field_data.empty()) {
    xml << "<FieldData>\n";
    for (auto& [name, value] : field_data)
      xml << "  <DataArray type=\"Float64\" Name=\"" << name << "\" NumberOfTuples=\"1\" format=\"ascii\">" << value << "</DataArray>\n";
    xml << "</FieldData>\n";
  }
  xml << "</VTKFile>\n";
  write_file_atomically(path, xml.str());
}

ParticleStore read_vtp_piece(const std::filesystem::path& path, int dim) {
  const std::string file = read_file(path);
  auto fail = [&](const std::string& why) { throw std::runtime_error(path.string() + ": " + why); };
  const std::size_t appended = file.find("<AppendedData");
  if (appended == std::string::npos) fail("not a spate snapshot piece (no appended data)");
  const std::size_t underscore = file.find('_', appended);
  if (underscore == std::string::npos) fail("not a spate snapshot piece (no appended data)");
  const std::string header = file.substr(0, appended);
  const std::size_t vtk_file = header.find("<VTKFile");
  if (vtk_file == std::string::npos) fail("not a VTK XML file");
  const std::string root = header.substr(vtk_file, header.find('>', vtk_file) - vtk_file);
  const bool wide = attribute(root, "header_type", "UInt32") == "UInt64";
  const std::string compressor = attribute(root, "compressor");
  if (!compressor.empty() && compressor != kCompressor) fail("compressor " + compressor + " is not supported");
  const std::size_t piece = header.find("<Piece");
  if (piece == std::string::npos) fail("no <Piece>");
  const std::size_t n = std::stoull(attribute(header.substr(piece, header.find('>', piece) - piece), "NumberOfPoints", "0"));

  // Every exported field of the registry is filled from the array of its exported name (vectors:
  // the first dim of the 3 components); arrays the registry does not know ("device") are skipped.
  ParticleStore s(dim);
  s.resize(n);
  std::map<std::string, std::string> tags;
  const std::regex array_tag("<DataArray[^>]*>");
  for (auto it = std::sregex_iterator(header.begin(), header.end(), array_tag); it != std::sregex_iterator(); ++it)
    tags[attribute(it->str(), "Name")] = it->str();
  for (const ExportedField& f : exported_fields(s)) {
    const std::string name(f.spec->exported);
    const auto tag = tags.find(name);
    if (tag == tags.end()) continue;  // a field this file predates: stays zero
    const int components = std::stoi(attribute(tag->second, "NumberOfComponents", "1"));
    const int expected = f.spec->shape == FieldShape::Vector ? 3 : 1;
    const std::string type = attribute(tag->second, "type"), offset = attribute(tag->second, "offset");
    if (type != vtk_type(f.spec->type) || components != expected || offset.empty())
      fail("array '" + name + "' is " + std::to_string(components) + " x " + type + ", expected " + std::to_string(expected) + " x " +
           vtk_type(f.spec->type));
    const std::vector<char> raw = appended_array(file, underscore + 1, std::stoull(offset), wide, !compressor.empty(), path, name);
    const std::size_t size = f.spec->elem_size();
    if (raw.size() != n * components * size) fail("array '" + name + "' has the wrong size");
    for (int k = 0; k < f.components; ++k)
      for (std::size_t i = 0; i < n; ++i) std::memcpy(f.data[k] + i * size, raw.data() + (i * components + k) * size, size);
  }
  s.set_owned(n);
  return s;
}

double Snapshot::value(const std::string& name, double fallback) const {
  for (auto& [n, v] : field_data)
    if (n == name) return v;
  return fallback;
}

Snapshot read_snapshot(const std::filesystem::path& vtm, int dim) {
  const std::string text = read_file(vtm);
  if (text.find("vtkMultiBlockDataSet") == std::string::npos) throw std::runtime_error(vtm.string() + ": not a VTK multiblock (.vtm) file");
  Snapshot s;
  const std::regex data_set("<DataSet[^>]*>"), field("<DataArray[^>]*Name=\"([^\"]+)\"[^>]*>([^<]*)</DataArray>");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), data_set); it != std::sregex_iterator(); ++it) {
    const std::string tag = it->str(), file = attribute(tag, "file");
    if (file.empty()) continue;
    s.pieces.push_back(read_vtp_piece(vtm.parent_path() / file, dim));
    s.slabs.push_back(std::stoi(attribute(tag, "index", std::to_string(s.slabs.size()))));
  }
  if (s.pieces.empty()) throw std::runtime_error(vtm.string() + ": the snapshot lists no pieces");
  const std::size_t fields_at = text.find("<FieldData>");
  if (fields_at != std::string::npos) {
    const std::string part = text.substr(fields_at);
    for (auto it = std::sregex_iterator(part.begin(), part.end(), field); it != std::sregex_iterator(); ++it)
      s.field_data.emplace_back((*it)[1].str(), std::stod((*it)[2].str()));
  }
  return s;
}

std::vector<std::pair<double, std::string>> read_pvd(const std::filesystem::path& path) {
  std::vector<std::pair<double, std::string>> entries;
  std::ifstream in(path);
  const std::regex entry("timestep=\"([^\"]+)\"[^>]*file=\"([^\"]+)\"");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, entry)) continue;
    // The index is read back as found: an entry whose time does not parse is dropped.
    const std::string text = m[1];
    char* end = nullptr;
    const double t = std::strtod(text.c_str(), &end);
    if (end != text.c_str() && *end == '\0') entries.emplace_back(t, m[2]);
  }
  return entries;
}

void PvdIndex::add(double time, const std::string& relative_file) {
  entries_.emplace_back(time, relative_file);
  std::ostringstream xml;
  xml.precision(17);
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n";
  for (auto& [t, f] : entries_) xml << "  <DataSet timestep=\"" << t << "\" group=\"\" part=\"0\" file=\"" << f << "\"/>\n";
  xml << "</Collection>\n</VTKFile>\n";
  write_file_atomically(path_, xml.str());
}

void PvdIndex::load_existing(double up_to_time) {
  entries_.clear();
  for (auto& e : read_pvd(path_))
    if (e.first <= up_to_time) entries_.push_back(e);
}

}  // namespace spate
