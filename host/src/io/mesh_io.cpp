#include <cstreams/io/file_input.hpp>
#include <cstreams/io/file_output.hpp>
#include <cstreams/io/mesh_io.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace cstreams {

namespace {

std::string read_file(const std::string& path)
{
  std::ifstream file = open_input(path, "mesh file", true);
  std::ostringstream data;
  data << file.rdbuf();
  if (file.bad()) throw InputError(path + ": read error");
  return data.str();
}

std::string extension_of(const std::string& path)
{
  const auto dot = path.rfind('.');
  if (dot == std::string::npos || path.find('/', dot) != std::string::npos) return {};
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// `where` names the face for messages ("name: face 12", "name:40: face").
void check_face(const Face& face, std::size_t vertex_count, const std::string& where)
{
  for (std::uint32_t index : face)
    if (index >= vertex_count)
      throw InputError(where + " refers to vertex " + std::to_string(index) + " but the mesh has " +
                       std::to_string(vertex_count) + " vertices");
  if (face[0] == face[1] || face[1] == face[2] || face[0] == face[2])
    throw InputError(where + " repeats vertex " + std::to_string(face[0] == face[1] || face[0] == face[2] ? face[0] : face[1]));
}

void check_finite(const Vec3& p, const std::string& where)
{
  if (!p.allFinite()) throw InputError(where + " has a NaN or infinite coordinate");
}

bool host_is_big_endian()
{
  const std::uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

// ---------------------------------------------------------------- PLY

enum class PlyType { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

bool parse_ply_type(const std::string& s, PlyType& type)
{
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::int8},     {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
      {"uint8", PlyType::uint8},   {"short", PlyType::int16},     {"int16", PlyType::int16},
      {"ushort", PlyType::uint16}, {"uint16", PlyType::uint16},   {"int", PlyType::int32},
      {"int32", PlyType::int32},   {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
      {"float", PlyType::float32}, {"float32", PlyType::float32}, {"double", PlyType::float64},
      {"float64", PlyType::float64}};
  for (const auto& [n, t] : names)
    if (s == n) {
      type = t;
      return true;
    }
  return false;
}

std::size_t size_of(PlyType t)
{
  switch (t) {
    case PlyType::int8:
    case PlyType::uint8: return 1;
    case PlyType::int16:
    case PlyType::uint16: return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 0;
}

bool is_integer(PlyType t) { return t != PlyType::float32 && t != PlyType::float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;
  bool list = false;
  PlyType count_type = PlyType::uint8;
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { ascii, little, big };

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;  // first byte after end_header's newline
  std::size_t body_line = 0;    // line number of the first body line
};

PlyHeader parse_ply_header(std::string_view bytes, const std::string& name)
{
  PlyHeader header;
  std::size_t pos = 0, line_number = 0;
  bool have_format = false;
  auto fail = [&](const std::string& what) -> InputError {
    return InputError(name + ":" + std::to_string(line_number) + ": " + what);
  };
  for (;;) {
    if (pos >= bytes.size()) {
      line_number++;
      throw fail("PLY header ends without end_header");
    }
    std::size_t end = bytes.find('\n', pos);
    if (end == std::string_view::npos) end = bytes.size();
    std::string line(bytes.substr(pos, end - pos));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = end + 1;
    ++line_number;
    std::istringstream in(line);
    std::string keyword;
    in >> keyword;
    if (line_number == 1) {
      if (keyword != "ply") throw fail("not a PLY file (first line is not 'ply')");
      continue;
    }
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      std::string format, version;
      in >> format >> version;
      if (format == "ascii") header.format = PlyFormat::ascii;
      else if (format == "binary_little_endian") header.format = PlyFormat::little;
      else if (format == "binary_big_endian") header.format = PlyFormat::big;
      else throw fail("unknown PLY format '" + format + "'");
      have_format = true;
    } else if (keyword == "element") {
      PlyElement e;
      long long count = -1;
      in >> e.name >> count;
      if (e.name.empty() || !in || count < 0) throw fail("malformed element line '" + line + "'");
      e.count = std::size_t(count);
      header.elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (header.elements.empty()) throw fail("property before any element");
      PlyProperty p;
      std::string type;
      in >> type;
      if (type == "list") {
        std::string count_type, item_type;
        in >> count_type >> item_type >> p.name;
        p.list = true;
        if (!parse_ply_type(count_type, p.count_type) || !is_integer(p.count_type))
          throw fail("bad list count type '" + count_type + "'");
        if (!parse_ply_type(item_type, p.type)) throw fail("unknown property type '" + item_type + "'");
      } else {
        in >> p.name;
        if (!parse_ply_type(type, p.type)) throw fail("unknown property type '" + type + "'");
      }
      if (p.name.empty()) throw fail("property without a name");
      header.elements.back().properties.push_back(p);
    } else if (keyword == "end_header") {
      if (!have_format) throw fail("PLY header has no format line");
      header.body_offset = std::min(pos, bytes.size());
      header.body_line = line_number + 1;
      return header;
    } else {
      throw fail("unexpected PLY header line '" + line + "'");
    }
  }
}

// Reads values of the body one at a time, binary or ascii, and says where it is.
class PlyReader {
public:
  PlyReader(std::string_view bytes, const PlyHeader& header, const std::string& name)
      : bytes_(bytes), pos_(header.body_offset), line_(header.body_line), format_(header.format), name_(name)
  {
  }

  double number(PlyType type, const char* element, std::size_t index)
  {
    return format_ == PlyFormat::ascii ? ascii(type, element, index) : binary(type, element, index);
  }

private:
  InputError truncated(const char* element, std::size_t index) const
  {
    return InputError(name_ + ": file ends inside " + element + " " + std::to_string(index) + " (truncated)");
  }

  double binary(PlyType type, const char* element, std::size_t index)
  {
    const std::size_t n = size_of(type);
    if (pos_ + n > bytes_.size()) throw truncated(element, index);
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, n);
    pos_ += n;
    if ((format_ == PlyFormat::big) != host_is_big_endian()) std::reverse(raw, raw + n);
    switch (type) {
      case PlyType::int8: return double(std::int8_t(raw[0]));
      case PlyType::uint8: return double(raw[0]);
      case PlyType::int16: { std::int16_t v; std::memcpy(&v, raw, 2); return v; }
      case PlyType::uint16: { std::uint16_t v; std::memcpy(&v, raw, 2); return v; }
      case PlyType::int32: { std::int32_t v; std::memcpy(&v, raw, 4); return v; }
      case PlyType::uint32: { std::uint32_t v; std::memcpy(&v, raw, 4); return v; }
      case PlyType::float32: { float v; std::memcpy(&v, raw, 4); return v; }
      case PlyType::float64: { double v; std::memcpy(&v, raw, 8); return v; }
    }
    return 0;
  }

  double ascii(PlyType type, const char* element, std::size_t index)
  {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) {
      if (bytes_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ >= bytes_.size()) throw truncated(element, index);
    std::size_t end = pos_;
    while (end < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[end]))) ++end;
    const char* first = bytes_.data() + pos_;
    const char* last = bytes_.data() + end;
    double value = 0;
    std::from_chars_result r;
    if (is_integer(type)) {
      long long v = 0;
      r = std::from_chars(first, last, v);
      value = double(v);
    } else {
      r = std::from_chars(first, last, value);
    }
    if (r.ec != std::errc() || r.ptr != last)
      throw InputError(name_ + ":" + std::to_string(line_) + ": " + element + " " + std::to_string(index) +
                       ": cannot read '" + std::string(first, last) + "' as a number");
    pos_ = end;
    return value;
  }

  std::string_view bytes_;
  std::size_t pos_;
  std::size_t line_;
  PlyFormat format_;
  const std::string& name_;
};

}  // namespace

Mesh parse_ply(std::string_view bytes, const std::string& name)
{
  const PlyHeader header = parse_ply_header(bytes, name);
  const PlyElement* vertex = nullptr;
  const PlyElement* face = nullptr;
  for (const auto& e : header.elements) {
    if (e.name == "vertex") vertex = &e;
    if (e.name == "face") face = &e;
  }
  if (!vertex) throw InputError(name + ": PLY file has no vertex element");
  int axis_of[3] = {-1, -1, -1};
  std::vector<int> vertex_axis(vertex->properties.size(), -1);
  for (std::size_t i = 0; i < vertex->properties.size(); ++i) {
    const auto& p = vertex->properties[i];
    for (int a = 0; a < 3; ++a)
      if (p.name == std::string(1, char('x' + a)) && !p.list) axis_of[a] = int(i), vertex_axis[i] = a;
  }
  for (int a = 0; a < 3; ++a)
    if (axis_of[a] < 0) throw InputError(name + ": PLY vertex element has no '" + std::string(1, char('x' + a)) + "' property");
  int index_property = -1;
  if (face)
    for (std::size_t i = 0; i < face->properties.size(); ++i)
      if (face->properties[i].list &&
          (face->properties[i].name == "vertex_indices" || face->properties[i].name == "vertex_index"))
        index_property = int(i);
  if (face && index_property < 0) throw InputError(name + ": PLY face element has no vertex_indices list");

  // A count that cannot fit in the file is rejected before anything is allocated for it.
  const std::size_t body = bytes.size() - header.body_offset;
  for (const auto& e : header.elements) {
    std::size_t min_bytes = 0;
    for (const auto& p : e.properties) min_bytes += header.format == PlyFormat::ascii ? 2 : size_of(p.list ? p.count_type : p.type);
    if (min_bytes && e.count > body / min_bytes + 1)
      throw InputError(name + ": PLY element " + e.name + " declares " + std::to_string(e.count) +
                       " items, more than the file can hold (truncated)");
  }

  Mesh mesh;
  PlyReader reader(bytes, header, name);
  for (const auto& e : header.elements) {
    // An element without properties holds no bytes, whatever count it declares (a
    // fuzzer's 12222222221 empty items once looped here for minutes).
    if (e.properties.empty()) continue;
    const bool is_vertex = &e == vertex, is_face = &e == face;
    const char* label = is_vertex ? "vertex" : is_face ? "face" : e.name.c_str();
    if (is_vertex) mesh.positions.resize(e.count);
    if (is_face) mesh.faces.resize(e.count);
    for (std::size_t i = 0; i < e.count; ++i) {
      for (std::size_t p = 0; p < e.properties.size(); ++p) {
        const auto& prop = e.properties[p];
        if (!prop.list) {
          const double v = reader.number(prop.type, label, i);
          if (is_vertex && vertex_axis[p] >= 0) mesh.positions[i][vertex_axis[p]] = v;
          continue;
        }
        const double count = reader.number(prop.count_type, label, i);
        if (count < 0 || count > 1e6)
          throw InputError(name + ": " + label + " " + std::to_string(i) + " has a list of " + std::to_string(count) + " items");
        if (is_face && int(p) == index_property && count != 3)
          throw InputError(name + ": face " + std::to_string(i) + " has " + std::to_string(int(count)) +
                           " vertices; only triangles are supported");
        for (int k = 0; k < int(count); ++k) {
          const double v = reader.number(prop.type, label, i);
          if (is_face && int(p) == index_property) {
            if (v < 0 || v > 4294967295.0 || v != std::floor(v))
              throw InputError(name + ": face " + std::to_string(i) + " has an invalid vertex index " + std::to_string(v));
            mesh.faces[i][std::size_t(k)] = std::uint32_t(v);
          }
        }
      }
    }
  }
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    check_finite(mesh.positions[v], name + ": vertex " + std::to_string(v));
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    check_face(mesh.faces[f], mesh.positions.size(), name + ": face " + std::to_string(f));
  return mesh;
}

Mesh parse_obj(std::string_view bytes, const std::string& name)
{
  Mesh mesh;
  std::vector<std::size_t> face_lines;
  std::size_t pos = 0, line_number = 0;
  while (pos < bytes.size()) {
    std::size_t end = bytes.find('\n', pos);
    if (end == std::string_view::npos) end = bytes.size();
    std::string_view line = bytes.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    auto fail = [&](const std::string& what) {
      return InputError(name + ":" + std::to_string(line_number) + ": " + what);
    };
    std::vector<std::string_view> tokens;
    for (std::size_t i = 0; i < line.size();) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      std::size_t j = i;
      while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
      if (j > i) tokens.push_back(line.substr(i, j - i));
      i = j;
    }
    if (tokens.empty() || tokens[0][0] == '#') continue;
    if (tokens[0] == "v") {
      if (tokens.size() < 4) throw fail("vertex needs three coordinates");
      Vec3 p;
      for (int a = 0; a < 3; ++a) {
        const auto t = tokens[std::size_t(a) + 1];
        auto r = std::from_chars(t.data(), t.data() + t.size(), p[a]);
        if (r.ec != std::errc() || r.ptr != t.data() + t.size())
          throw fail("cannot read '" + std::string(t) + "' as a coordinate");
      }
      check_finite(p, name + ":" + std::to_string(line_number) + ": vertex");
      mesh.positions.push_back(p);
    } else if (tokens[0] == "f") {
      if (tokens.size() != 4)
        throw fail("face has " + std::to_string(tokens.size() - 1) + " vertices; only triangles are supported");
      Face f{};
      for (std::size_t k = 0; k < 3; ++k) {
        const auto t = tokens[k + 1];
        const auto slash = t.find('/');
        const auto index_text = t.substr(0, slash);
        long long index = 0;
        auto r = std::from_chars(index_text.data(), index_text.data() + index_text.size(), index);
        if (r.ec != std::errc() || r.ptr != index_text.data() + index_text.size() || index == 0)
          throw fail("cannot read '" + std::string(t) + "' as a vertex index");
        const long long resolved = index > 0 ? index - 1 : (long long)mesh.positions.size() + index;
        if (resolved < 0 || resolved > 4294967295LL) throw fail("vertex index " + std::to_string(index) + " is out of range");
        f[k] = std::uint32_t(resolved);
      }
      mesh.faces.push_back(f);
      face_lines.push_back(line_number);
    }
    // vt, vn, o, g, s, usemtl, mtllib and the rest carry nothing CCD needs.
  }
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    check_face(mesh.faces[f], mesh.positions.size(), name + ":" + std::to_string(face_lines[f]) + ": face");
  return mesh;
}

Mesh read_ply(const std::string& path) { return parse_ply(read_file(path), path); }
Mesh read_obj(const std::string& path) { return parse_obj(read_file(path), path); }

Mesh read_mesh(const std::string& path)
{
  const std::string ext = extension_of(path);
  if (ext == "ply") return read_ply(path);
  if (ext == "obj") return read_obj(path);
  throw InputError(path + ": unknown mesh format (expected .ply or .obj)");
}

void write_ply(const std::string& path, const Mesh& mesh, PlyEncoding encoding)
{
  const bool binary = encoding == PlyEncoding::binary_little_endian;
  if (binary && host_is_big_endian()) throw Error("write_ply writes little-endian PLY from little-endian hosts only");
  write_file_atomically(
      path,
      [&](std::ostream& out) {
        out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
            << "element vertex " << mesh.positions.size() << "\n"
            << "property double x\nproperty double y\nproperty double z\n"
            << "element face " << mesh.faces.size() << "\n"
            << "property list uchar int vertex_indices\nend_header\n";
        if (binary) {
          for (const auto& p : mesh.positions) out.write(reinterpret_cast<const char*>(p.data()), 24);
          for (const auto& f : mesh.faces) {
            const unsigned char three = 3;
            const std::int32_t idx[3] = {std::int32_t(f[0]), std::int32_t(f[1]), std::int32_t(f[2])};
            out.write(reinterpret_cast<const char*>(&three), 1);
            out.write(reinterpret_cast<const char*>(idx), 12);
          }
        } else {
          out.precision(17);
          for (const auto& p : mesh.positions) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
          for (const auto& f : mesh.faces) out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
        }
      },
      binary);
}

}  // namespace cstreams
