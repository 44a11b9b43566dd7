// load_obj (tinyobjloader plus checks that name the offending line) and write_obj.
//
// tinyobjloader (2.0.0rc10, float build) parses the file, but it cannot tell where a problem is:
// it reads "nan", "inf" or any garbage coordinate silently as 0, reports out-of-range indices
// with the number of the file's last line, and stores face sizes in an unsigned char. So the
// text is scanned first to check coordinates and to map each vertex and face to its line.
// Polygons are split here rather than by tinyobjloader, whose ear clipping can silently drop
// parts of a polygon, so that every triangle keeps the line of its face.
#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>

#include <sys/stat.h>
#include <tiny_obj_loader.h>

#include "mesh/mesh_checks.h"

namespace crumple {
namespace {

using Vec3 = std::array<double, 3>;

// Where each element of the file is, and the coordinates as read here (tinyobjloader's own
// reading is not used for them: it reads "+-1" or "1e99999" as 0).
struct ObjLayout {
  std::vector<Vec3> vertex_position;  // coordinates of each 'v' element, in file order
  std::vector<int> vertex_line;    // line of each 'v' element, in file order
  std::vector<int> face_line;      // line of each 'f' element, in file order
  std::vector<int> vertices_before;  // number of 'v' elements above each face (relative indices)
  // What tinyobjloader gets: the 'v', 'vt', 'vn' and 'f' lines, every other line blank (line
  // numbers kept). Its readers of other elements convert unchecked numbers to int ('vw' joint
  // ids: undefined behaviour, found by fuzzing) or size vectors from them ('t' tags).
  std::string geometry;
};

// One face as tinyobjloader resolved it.
struct Face {
  int line;                  // its line in the file
  std::vector<int> corners;  // 0-based vertex indices, in order
};

[[noreturn]] void fail_at(const std::string& path, int line, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line) + ": " + what);
}

// Refuses anything but a regular file (a FIFO would block, a device never ends) and files
// larger than kMaxObjBytes, then reads it whole.
std::string read_text(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) throw InputError(path + ": cannot open: " + std::strerror(errno));
  if (S_ISDIR(info.st_mode)) throw InputError(path + ": cannot read: is a directory");
  if (!S_ISREG(info.st_mode)) throw InputError(path + ": cannot read: not a regular file");
  if (static_cast<std::uint64_t>(info.st_size) > kMaxObjBytes) {
    throw InputError(path + ": file has " + std::to_string(info.st_size) + " bytes, more than the " +
                     std::to_string(kMaxObjBytes >> 20) + " MiB an OBJ may have");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  std::string text(static_cast<std::size_t>(info.st_size) + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw InputError(path + ": cannot read: " + std::strerror(errno));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > static_cast<std::size_t>(info.st_size)) throw InputError(path + ": cannot read: the file grew while read");
  return text;
}

// Splits on spaces and tabs.
std::vector<std::string_view> tokens(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (true) {
    i = s.find_first_not_of(" \t", i);
    if (i == std::string_view::npos) return out;
    const std::size_t end = std::min(s.find_first_of(" \t", i), s.size());
    out.push_back(s.substr(i, end - i));
    i = end;
  }
}

// One coordinate: a decimal number with an optional sign, nothing else ("+-1", "1.5x" and
// "0x10" are not numbers). Overflow is reported, underflow reads as 0 or a subnormal.
double parse_coordinate(std::string_view word, const std::string& path, int line, const std::string& name) {
  std::string quoted(1, '\'');  // built this way: "'" + std::string(word) trips -Wrestrict (g++ 12)
  (quoted += word) += '\'';
  std::string_view digits = word;
  if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-') digits.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  const bool number = ec == std::errc() || ec == std::errc::result_out_of_range;
  if (!number || end != digits.data() + digits.size()) {
    fail_at(path, line, name + " coordinate " + quoted + " is not a number");
  }
  if (ec == std::errc::result_out_of_range) value = std::strtod(std::string(digits).c_str(), nullptr);
  if (!std::isfinite(value)) fail_at(path, line, name + " coordinate " + quoted + " is not finite");
  return value;
}

// The coordinates of the vertex on `line` (the text after "v").
Vec3 read_coordinates(std::string_view rest, const std::string& path, int line, int vertex) {
  const auto words = tokens(rest);
  const std::string name = "vertex " + std::to_string(vertex);
  if (words.size() < 3) {
    fail_at(path, line, name + " has " + std::to_string(words.size()) + " coordinates, needs 3");
  }
  Vec3 p{};
  for (int d = 0; d < 3; ++d) p[d] = parse_coordinate(words[d], path, line, name);
  return p;
}

// True if s is a non-zero integer that fits an int, written as digits with an optional '-'
// (tinyobjloader reads indices with atoi: "3abc", "3.9" and 4294967299 would all read as 3).
bool is_index(std::string_view s) {
  int value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  return !s.empty() && ec == std::errc() && end == s.data() + s.size() && value != 0;
}

// Checks one corner of a face: "v", "v/vt", "v//vn" or "v/vt/vn", each index an is_index.
void check_corner(std::string_view corner, const std::string& path, int line) {
  std::size_t part = 0;
  for (std::size_t start = 0;; ++part) {
    const std::size_t slash = std::min(corner.find('/', start), corner.size());
    const std::string_view index = corner.substr(start, slash - start);
    const bool optional = part == 1 && slash < corner.size();  // the vt of "v//vn"
    if (part > 2 || (!is_index(index) && !(optional && index.empty()))) {
      fail_at(path, line, "face corner '" + std::string(corner) +
                              "' is not a vertex index (a non-zero integer, optionally /vt/vn)");
    }
    if (slash == corner.size()) return;
    start = slash + 1;
  }
}

// Scans the text with tinyobjloader's rules (lines end at \n, \r\n or \r; leading blanks are
// skipped; "v" and "f" must be followed by a blank) and checks what tinyobjloader would not.
ObjLayout scan_layout(const std::string& text, const std::string& path) {
  ObjLayout layout;
  int line = 0;
  for (std::size_t pos = 0; pos < text.size();) {
    const std::size_t stop = std::min(text.find_first_of("\r\n", pos), text.size());
    std::string_view s(text.data() + pos, stop - pos);
    pos = stop + (text.compare(stop, 2, "\r\n") == 0 ? 2 : 1);
    ++line;
    s = s.substr(0, s.find('\0'));  // tinyobjloader reads a line as a C string
    const std::size_t first = std::min(s.find_first_not_of(" \t"), s.size());
    s.remove_prefix(first);
    const bool element = s.size() >= 2 && (s[1] == ' ' || s[1] == '\t');
    const bool texture_or_normal =
        s.size() >= 3 && s[0] == 'v' && (s[1] == 't' || s[1] == 'n') && (s[2] == ' ' || s[2] == '\t');
    if ((element && (s[0] == 'v' || s[0] == 'f')) || texture_or_normal) layout.geometry += s;
    layout.geometry += '\n';
    if (!element) continue;
    if (s[0] == 'v') {
      layout.vertex_line.push_back(line);
      layout.vertex_position.push_back(
          read_coordinates(s.substr(2), path, line, static_cast<int>(layout.vertex_line.size())));
    } else if (s[0] == 'f') {
      const auto words = tokens(s.substr(2));
      const std::size_t corners = words.size();
      if (corners < 3) {
        fail_at(path, line, "face has " + std::to_string(corners) + " vertices, needs at least 3");
      }
      if (corners > 255) {  // tinyobjloader stores face sizes in an unsigned char
        fail_at(path, line, "face has " + std::to_string(corners) + " vertices, at most 255 are supported");
      }
      for (std::string_view corner : words) check_corner(corner, path, line);
      layout.face_line.push_back(line);
      layout.vertices_before.push_back(static_cast<int>(layout.vertex_line.size()));
    }
  }
  return layout;
}

// The first line of a tinyobjloader message, and the line number it names (0 if none).
std::pair<std::string, int> first_message(const std::string& text) {
  std::istringstream in(text);
  std::string msg;
  while (std::getline(in, msg) && msg.find_first_not_of(" \t\r.") == std::string::npos) {
  }
  while (!msg.empty() && (msg.back() == '\r' || msg.back() == ' ')) msg.pop_back();
  int line = 0;
  const std::size_t at = msg.find("line ");
  if (at != std::string::npos) line = std::atoi(msg.c_str() + at + 5);
  return {msg, line};
}

[[noreturn]] void fail_tinyobj(const std::string& path, const std::string& text) {
  const auto [msg, line] = first_message(text);
  if (msg.rfind("Failed parse `", 0) == 0 && line > 0) {  // e.g. "Failed parse `f' line(..."
    const std::string element = msg.substr(14, msg.find('\'', 14) - 14);
    fail_at(path, line, "cannot parse '" + element + "' element: zero or malformed index");
  }
  const std::string what = "tinyobjloader: " + (msg.empty() ? std::string("unknown error") : msg);
  if (line > 0) fail_at(path, line, what);
  throw InputError(path + ": " + what);
}

// tinyobjloader warnings that do not concern the geometry (materials, group names).
bool harmless_warning(const std::string& line) {
  if (line.find_first_not_of(" \t\r.") == std::string::npos) return true;
  for (const char* benign : {"aterial", "Empty group name"}) {
    if (line.find(benign) != std::string::npos) return true;
  }
  return false;
}

void check_warnings(const std::string& path, const std::string& warn) {
  std::istringstream in(warn);
  for (std::string line; std::getline(in, line);) {
    if (harmless_warning(line)) continue;
    if (line.rfind("Vertex indices out of bounds", 0) == 0) {
      throw InputError(path + ": a face refers to a vertex beyond the last 'v' line");
    }
    if (line.rfind("Vertex normal indices out of bounds", 0) == 0) {
      throw InputError(path + ": a face refers to a normal beyond the last 'vn' line");
    }
    if (line.rfind("Vertex texcoord indices out of bounds", 0) == 0) {
      throw InputError(path + ": a face refers to a texture coordinate beyond the last 'vt' line");
    }
    // tinyobjloader's line numbers in warnings point at the end of the file; drop them.
    throw InputError(path + ": tinyobjloader: " + line.substr(0, line.find(" (line")));
  }
}

// The faces of all shapes in file order, each checked to refer to existing, distinct vertices.
std::vector<Face> collect_faces(const std::vector<tinyobj::shape_t>& shapes,
                                const ObjLayout& layout, int vertex_count,
                                const std::string& path) {
  std::vector<Face> faces;
  for (const auto& shape : shapes) {
    std::size_t next = 0;
    for (unsigned char size : shape.mesh.num_face_vertices) {
      if (next + size > shape.mesh.indices.size() || faces.size() >= layout.face_line.size()) {
        throw InputError(path + ": cannot match tinyobjloader's faces to the file's 'f' lines");
      }
      Face face{layout.face_line[faces.size()], {}};
      const int before = layout.vertices_before[faces.size()];
      for (std::size_t k = 0; k < size; ++k) {
        const int v = shape.mesh.indices[next + k].vertex_index;
        if (v < 0) {
          fail_at(path, face.line, "face refers to vertex " + std::to_string(v - before) +
                                       " (relative) but only " + std::to_string(before) +
                                       " vertices precede it");
        }
        if (v >= vertex_count) {
          fail_at(path, face.line, "face refers to vertex " + std::to_string(v + 1) +
                                       " but the file has " + std::to_string(vertex_count) +
                                       " vertices");
        }
        if (std::find(face.corners.begin(), face.corners.end(), v) != face.corners.end()) {
          fail_at(path, face.line, "face is degenerate: repeats vertex " + std::to_string(v + 1));
        }
        face.corners.push_back(v);
      }
      next += size;
      faces.push_back(std::move(face));
    }
    if (next != shape.mesh.indices.size()) {
      throw InputError(path + ": cannot match tinyobjloader's faces to the file's 'f' lines");
    }
  }
  if (faces.size() != layout.face_line.size()) {
    throw InputError(path + ": cannot match tinyobjloader's faces to the file's 'f' lines");
  }
  return faces;
}

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Splits a polygon into triangles fanning out from one corner: the first corner whose fan
// triangles all face the polygon's (Newell) normal. For a quad, the corner on the shorter
// diagonal is tried first. Returns false if no corner works (degenerate or too non-convex).
bool split_polygon(const std::vector<int>& c, const std::vector<Vec3>& pos,
                   std::vector<std::array<int, 3>>& out) {
  const std::size_t n = c.size();
  if (n == 3) {  // kept as is; check_triangles reports it if degenerate
    out.push_back({c[0], c[1], c[2]});
    return true;
  }
  Vec3 normal{0.0, 0.0, 0.0};
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const Vec3 s = cross(sub(pos[c[i]], pos[c[0]]), sub(pos[c[i + 1]], pos[c[0]]));
    for (int d = 0; d < 3; ++d) normal[d] += s[d];
  }
  std::vector<std::size_t> apexes(n);
  for (std::size_t i = 0; i < n; ++i) apexes[i] = i;
  if (n == 4) {
    const Vec3 d02 = sub(pos[c[2]], pos[c[0]]), d13 = sub(pos[c[3]], pos[c[1]]);
    if (dot(d13, d13) < dot(d02, d02)) std::swap(apexes[0], apexes[1]);
  }
  for (std::size_t apex : apexes) {
    std::vector<std::array<int, 3>> fan;
    for (std::size_t j = 1; j + 1 < n; ++j) {
      const int a = c[apex], b = c[(apex + j) % n], d = c[(apex + j + 1) % n];
      if (dot(cross(sub(pos[b], pos[a]), sub(pos[d], pos[a])), normal) <= 0.0) break;
      fan.push_back({a, b, d});
    }
    if (fan.size() == n - 2) {
      out.insert(out.end(), fan.begin(), fan.end());
      return true;
    }
  }
  return false;
}

// The faces as tinyobjloader reads them, matched to the file's lines.
std::vector<Face> read_faces(const ObjLayout& layout, const std::string& path) {
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  std::istringstream stream(layout.geometry);
  // No material reader (materials are not needed), no triangulation, no default colors.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, nullptr, false, false)) {
    fail_tinyobj(path, err);
  }
  const int vertex_count = static_cast<int>(attrib.vertices.size() / 3);
  if (static_cast<std::size_t>(vertex_count) != layout.vertex_line.size()) {
    throw InputError(path + ": cannot match tinyobjloader's vertices to the file's 'v' lines");
  }
  std::vector<Face> faces = collect_faces(shapes, layout, vertex_count, path);
  check_warnings(path, warn);
  if (faces.empty()) throw InputError(path + ": no triangles: the file has no faces ('f' lines)");
  return faces;
}

}  // namespace

InputMesh load_obj(const std::string& path) { return parse_obj(read_text(path), path); }

InputMesh parse_obj(std::string text, const std::string& path) {
  // A UTF-8 byte-order mark is not part of the first line (tinyobjloader would skip that line).
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text = text.substr(3);
  const ObjLayout layout = scan_layout(text, path);
  const std::vector<Face> faces = read_faces(layout, path);
  const std::vector<Vec3>& positions = layout.vertex_position;

  // Triangles (original vertex indices) and the line each came from.
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> triangle_line;
  for (const Face& face : faces) {
    if (!split_polygon(face.corners, positions, triangles)) {
      fail_at(path, face.line, "face with " + std::to_string(face.corners.size()) +
                                   " vertices cannot be split into triangles (degenerate or "
                                   "strongly non-convex)");
    }
    triangle_line.resize(triangles.size(), face.line);
  }

  // Drop unreferenced vertices; messages keep naming vertices by their number in the file.
  std::vector<int> new_index(positions.size(), -1);
  for (const auto& tri : triangles) {
    for (int v : tri) new_index[v] = 0;
  }
  InputMesh mesh;
  mesh_detail::MeshLabels labels{path, {}, std::move(triangle_line)};
  for (std::size_t v = 0; v < positions.size(); ++v) {
    if (new_index[v] < 0) continue;
    new_index[v] = static_cast<int>(mesh.positions.size());
    mesh.positions.push_back(positions[v]);
    labels.vertex_number.push_back(static_cast<int>(v) + 1);
  }
  mesh.triangles.reserve(triangles.size());
  for (const auto& tri : triangles) {
    mesh.triangles.push_back({new_index[tri[0]], new_index[tri[1]], new_index[tri[2]]});
  }

  mesh_detail::check_triangles(mesh, labels);
  mesh_detail::check_float_range(mesh, labels);
  mesh_detail::orient_consistently(mesh, labels);
  mesh_detail::check_manifold(mesh, labels);
  return mesh;
}

void write_obj(const std::string& path, const std::vector<std::array<double, 3>>& positions,
               const std::vector<std::array<int, 3>>& triangles) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  // std::to_chars with precision 9 prints exactly what printf("%.9g") prints in the C locale,
  // whatever the program's locale.
  char buf[32];
  auto number = [&](double x) {
    const auto result = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 9);
    return std::string_view(buf, static_cast<std::size_t>(result.ptr - buf));
  };
  std::string line;
  bool ok = true;
  for (const auto& p : positions) {
    line.assign(1, 'v');
    for (double x : p) (line += ' ') += number(x);
    line += '\n';
    ok = ok && std::fputs(line.c_str(), file) >= 0;
  }
  for (const auto& t : triangles) {
    line = "f " + std::to_string(t[0] + 1) + ' ' + std::to_string(t[1] + 1) + ' ' +
           std::to_string(t[2] + 1) + '\n';
    ok = ok && std::fputs(line.c_str(), file) >= 0;
  }
  const int saved = ok ? 0 : errno;
  if (std::fclose(file) != 0 && ok) {
    throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  }
  if (!ok) throw std::runtime_error("cannot write " + path + ": " + std::strerror(saved));
}

}  // namespace crumple
