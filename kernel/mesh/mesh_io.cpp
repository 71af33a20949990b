// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — mesh reading (OBJ, OFF, PLY, STL) with repairs and a load report; OBJ writing.
//
// Every format is first parsed into a RawMesh (vertices and polygons in file order, plus the
// line each came from), then one common pipeline validates indices, fan-triangulates, welds
// duplicate vertices, drops degenerate faces and isolated vertices, makes the orientation
// consistent and checks the topology.

#include "gridshell/mesh/mesh_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_topology.h"

namespace gridshell {
namespace {
namespace fs = std::filesystem;

/// `field` names the input (the file's path, or the name given to the arrays), `message` what
/// is wrong and where in it ("line 12: ...").
[[noreturn]] void fail(const std::string& field, const std::string& message) {
  throw InvalidInput(field, message);
}

std::string count_of(long long n, const char* singular, const char* plural) {
  return std::to_string(n) + " " + (n == 1 ? singular : plural);
}

/// A token quoted for an error message: at most 40 characters, unprintable bytes as '?'.
std::string quote_token(std::string_view token) {
  std::string out = "'";
  const size_t n = std::min<size_t>(token.size(), 40);
  for (size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (token.size() > n) out += "...";
  return out + "'";
}

std::string format_point(const Vec3& p) {
  std::ostringstream out;
  out << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return out.str();
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

/// Parses a whole token as a double ("nan"/"inf" parse and are rejected later as non-finite).
bool parse_double(std::string_view s, double& out) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, out, std::chars_format::general);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {  // overflow -> +-inf, underflow -> 0 or denormal
    out = std::strtod(std::string(s).c_str(), nullptr);
    return true;
  }
  return ec == std::errc();
}

bool parse_integer(std::string_view s, long long& out) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, out);
  return ec == std::errc() && ptr == end;
}

// ---------------------------------------------------------------------------------------------
// Parsed file contents before any repair.

struct RawMesh {
  std::string format;
  int index_base = 0;               ///< how the file numbers vertices: 1 for OBJ, 0 otherwise
  bool stl = false;                 ///< vertices are facet corners
  bool arrays = false;              ///< given as arrays in memory, not read from a file
  const char* source = "the file";  ///< how messages refer to the whole input
  std::vector<Vec3> vertices;
  std::vector<int> vertex_line;  ///< per vertex; 0 when the format has no lines (binary)
  std::vector<int> corners;      ///< polygon corners, flattened (file vertex indices, 0-based)
  std::vector<size_t> polygon_begin{0};
  std::vector<int> polygon_line;  ///< per polygon; 0 when binary

  int polygon_count() const { return static_cast<int>(polygon_line.size()); }
  void add_vertex(const Vec3& p, int line) {
    vertices.push_back(p);
    vertex_line.push_back(line);
  }
  void end_polygon(int line) {
    polygon_begin.push_back(corners.size());
    polygon_line.push_back(line);
  }
};

/// Where a face is: "line 12: " for text formats, "face 7: " for binary ones; for arrays the
/// field itself names it ("mesh.faces[7]") and the prefix is empty.
struct Place {
  std::string field;
  std::string prefix;
};
Place face_place(const std::string& name, const RawMesh& raw, int polygon) {
  if (raw.polygon_line[polygon] > 0)
    return {name, "line " + std::to_string(raw.polygon_line[polygon]) + ": "};
  if (raw.arrays) return {join_field(name, "faces[" + std::to_string(polygon) + "]"), ""};
  return {name, (raw.stl ? "facet " : "face ") + std::to_string(polygon) + ": "};
}

/// A file vertex as the user finds it in the file: "vertex 5 (line 9) at (1, 2, 3)".
std::string vertex_label(const RawMesh& raw, int v) {
  std::string out;
  if (raw.stl)
    out = "corner " + std::to_string(v % 3) + " of facet " + std::to_string(v / 3);
  else
    out = "vertex " + std::to_string(v + raw.index_base);
  if (raw.vertex_line[v] > 0) out += " (line " + std::to_string(raw.vertex_line[v]) + ")";
  return out + " at " + format_point(raw.vertices[v]);
}

std::string face_label(const RawMesh& raw, int polygon) {
  if (raw.polygon_line[polygon] > 0)
    return "the face on line " + std::to_string(raw.polygon_line[polygon]);
  return (raw.stl ? "facet " : "face ") + std::to_string(polygon);
}

// ---------------------------------------------------------------------------------------------
// Tokenizer for the whitespace-separated text formats (OFF, ASCII PLY, ASCII STL).

class Lexer {
 public:
  Lexer(std::string_view text, size_t pos, int line, bool hash_comments)
      : text_(text), pos_(pos), line_(line), token_line_(line), hash_(hash_comments) {}

  /// Next token, on any line. False at the end of the input.
  bool next(std::string_view& token) {
    skip(true);
    return read(token);
  }
  /// Next token on the current line only. False at the end of the line.
  bool next_in_line(std::string_view& token) {
    skip(false);
    if (pos_ < text_.size() && text_[pos_] == '\n') return false;
    return read(token);
  }
  /// Drops the rest of the current line.
  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    if (pos_ < text_.size()) {
      ++pos_;
      ++line_;
    }
  }
  int line() const { return token_line_; }  ///< line of the last token
  int current_line() const { return line_; }

 private:
  void skip(bool newlines) {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        if (!newlines) return;
        ++line_;
        ++pos_;
      } else if (is_space(c)) {
        ++pos_;
      } else if (hash_ && c == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
      } else {
        return;
      }
    }
  }
  bool read(std::string_view& token) {
    if (pos_ >= text_.size()) return false;
    const size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n' && !is_space(text_[pos_]) &&
           !(hash_ && text_[pos_] == '#'))
      ++pos_;
    token = text_.substr(start, pos_ - start);
    token_line_ = line_;
    return true;
  }

  std::string_view text_;
  size_t pos_;
  int line_;
  int token_line_;
  bool hash_;
};

/// Splits one line into whitespace-separated tokens.
std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !is_space(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

// ---------------------------------------------------------------------------------------------
// OBJ

RawMesh parse_obj(const std::string& path, std::string_view text) {
  RawMesh raw;
  raw.format = "obj";
  raw.index_base = 1;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 byte order mark
  static const char* const kIgnored[] = {
      "vt",        "vn",    "vp",       "g",        "o",    "s",      "usemtl", "mtllib",
      "l",         "p",     "cstype",   "deg",      "bmat", "step",   "curv",   "curv2",
      "surf",      "parm",  "trim",     "hole",     "scrv", "sp",     "end",    "con",
      "mg",        "bevel", "c_interp", "d_interp", "lod",  "maplib", "usemap", "shadow_obj",
      "trace_obj", "ctech", "stech",    "call",     "csh"};
  size_t pos = 0;
  int line_no = 0;
  std::string joined;
  while (pos < text.size()) {
    // One logical line: a trailing backslash continues it on the next physical line.
    const int line = ++line_no;
    joined.clear();
    std::string_view current;
    bool continued = false;
    while (true) {
      const size_t eol = text.find('\n', pos);
      std::string_view physical =
          text.substr(pos, eol == std::string_view::npos ? std::string_view::npos : eol - pos);
      pos = eol == std::string_view::npos ? text.size() : eol + 1;
      while (!physical.empty() && is_space(physical.back())) physical.remove_suffix(1);
      const bool more = !physical.empty() && physical.back() == '\\' && pos < text.size();
      if (more) physical.remove_suffix(1);
      if (more || continued) {
        joined.append(physical);
        joined.push_back(' ');
        continued = true;
      } else {
        current = physical;
      }
      if (!more) break;
      ++line_no;
    }
    if (continued) current = joined;
    const size_t hash = current.find('#');
    if (hash != std::string_view::npos) current = current.substr(0, hash);
    const std::vector<std::string_view> tokens = split(current);
    if (tokens.empty()) continue;
    const std::string where = "line " + std::to_string(line) + ": ";
    const std::string_view keyword = tokens[0];
    if (keyword == "v") {
      if (tokens.size() < 4)
        fail(path,
             where + "vertex has " +
                 count_of(static_cast<long long>(tokens.size()) - 1, "coordinate", "coordinates") +
                 ", expected 3");
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        if (!parse_double(tokens[k + 1], p[k]))
          fail(path, where + "cannot parse vertex coordinate " + quote_token(tokens[k + 1]));
        if (!std::isfinite(p[k]))
          fail(path, where + "vertex coordinate " + quote_token(tokens[k + 1]) +
                         " is not a finite number (NaN or Inf)");
      }
      raw.add_vertex(p, line);
    } else if (keyword == "f") {
      if (tokens.size() < 4)
        fail(path, where + "face has " +
                       count_of(static_cast<long long>(tokens.size()) - 1, "vertex", "vertices") +
                       ", needs at least 3");
      const long long defined = static_cast<long long>(raw.vertices.size());
      for (size_t k = 1; k < tokens.size(); ++k) {
        const std::string_view corner = tokens[k];
        const std::string_view index_text = corner.substr(0, corner.find('/'));
        long long index = 0;
        if (!parse_integer(index_text, index))
          fail(path, where + "cannot parse face vertex index " + quote_token(corner));
        if (index == 0)
          fail(path, where + "face vertex index 0 is out of range (OBJ indices start at 1)");
        if (index < 0) {
          if (index < -defined)  // not -index > defined: -INT64_MIN overflows (fuzz_mesh_obj)
            fail(path, where + "relative face vertex index " + std::to_string(index) +
                           " is out of range (only " +
                           count_of(defined, "vertex is", "vertices are") +
                           " defined before this line)");
          index += defined;  // -1 is the last vertex defined so far
        } else {
          index -= 1;
        }
        if (index > std::numeric_limits<int>::max()) index = std::numeric_limits<int>::max();
        raw.corners.push_back(static_cast<int>(index));
      }
      raw.end_polygon(line);
    } else if (std::find(std::begin(kIgnored), std::end(kIgnored), keyword) == std::end(kIgnored)) {
      fail(path, where + "cannot parse line: unknown OBJ statement " + quote_token(keyword));
    }
  }
  return raw;
}

// ---------------------------------------------------------------------------------------------
// OFF

RawMesh parse_off(const std::string& path, std::string_view text) {
  RawMesh raw;
  raw.format = "off";
  Lexer lex(text, 0, 1, true);
  std::string_view token;
  auto where = [&](int line) { return "line " + std::to_string(line) + ": "; };
  lex.next(token);
  static const char* const kHeaders[] = {"OFF",   "COFF",   "NOFF",   "CNOFF",
                                         "STOFF", "STCOFF", "STNOFF", "STCNOFF"};
  if (std::find(std::begin(kHeaders), std::end(kHeaders), token) == std::end(kHeaders)) {
    if (token.size() >= 3 && token.substr(token.size() - 3) == "OFF")
      fail(path, where(lex.line()) + "unsupported OFF variant " + quote_token(token) +
                     " (4D and n-dimensional OFF are not supported)");
    fail(path, where(lex.line()) + "not an OFF file: expected the header 'OFF', found " +
                   quote_token(token));
  }
  auto read_count = [&](const char* what, bool same_line) {
    const bool ok = same_line ? lex.next_in_line(token) : lex.next(token);
    if (!ok)
      fail(path, where(same_line ? lex.line() : lex.current_line()) + "missing " + what +
                     " count in the OFF header");
    if (token == "BINARY") fail(path, where(lex.line()) + "binary OFF is not supported");
    long long n = 0;
    if (!parse_integer(token, n) || n < 0 || n > std::numeric_limits<int>::max())
      fail(path, where(lex.line()) + "cannot parse " + what + " count " + quote_token(token));
    return static_cast<int>(n);
  };
  const int nv = read_count("vertex", false);
  const int nf = read_count("face", true);
  lex.skip_line();  // the edge count is ignored
  raw.vertices.reserve(std::min<size_t>(nv, text.size() / 6));
  for (int i = 0; i < nv; ++i) {
    if (!lex.next(token))
      fail(path, where(lex.current_line()) + "file ends after " + std::to_string(i) + " of " +
                     count_of(nv, "vertex", "vertices") + " (truncated)");
    const int line = lex.line();
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      if (k > 0 && !lex.next_in_line(token))
        fail(path, where(line) + "vertex " + std::to_string(i) + " has " +
                       count_of(k, "coordinate", "coordinates") + ", expected 3");
      if (!parse_double(token, p[k]))
        fail(path, where(line) + "cannot parse coordinate of vertex " + std::to_string(i) + ": " +
                       quote_token(token));
      if (!std::isfinite(p[k]))
        fail(path, where(line) + "vertex " + std::to_string(i) + " coordinate " +
                       quote_token(token) + " is not a finite number (NaN or Inf)");
    }
    raw.add_vertex(p, line);
    lex.skip_line();  // colours, normals, texture coordinates
  }
  for (int f = 0; f < nf; ++f) {
    if (!lex.next(token))
      fail(path, where(lex.current_line()) + "file ends after " + std::to_string(f) + " of " +
                     count_of(nf, "face", "faces") + " (truncated)");
    const int line = lex.line();
    long long n = 0;
    if (!parse_integer(token, n))
      fail(path, where(line) + "cannot parse vertex count of face " + std::to_string(f) + ": " +
                     quote_token(token));
    if (n < 3)
      fail(path, where(line) + "face " + std::to_string(f) + " has " +
                     count_of(n, "vertex", "vertices") + ", needs at least 3");
    for (long long k = 0; k < n; ++k) {
      if (!lex.next_in_line(token))
        fail(path, where(line) + "face " + std::to_string(f) + " lists " +
                       count_of(k, "vertex index", "vertex indices") + ", expected " +
                       std::to_string(n));
      long long index = 0;
      if (!parse_integer(token, index))
        fail(path, where(line) + "cannot parse vertex index of face " + std::to_string(f) + ": " +
                       quote_token(token));
      raw.corners.push_back(static_cast<int>(std::clamp<long long>(
          index, std::numeric_limits<int>::min(), std::numeric_limits<int>::max())));
    }
    raw.end_polygon(line);
    lex.skip_line();  // face colour
  }
  return raw;
}

// ---------------------------------------------------------------------------------------------
// PLY

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool ply_type(std::string_view name, PlyType& type) {
  static const std::pair<const char*, PlyType> kTypes[] = {
      {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& [n, t] : kTypes)
    if (name == n) {
      type = t;
      return true;
    }
  return false;
}

size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
      return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
      return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  long long count = 0;
  int line = 0;
  std::vector<PlyProperty> properties;
};

enum class ReadResult { Ok, End, Bad };

class PlyBinaryReader {
 public:
  PlyBinaryReader(std::string_view data, size_t pos, bool big_endian)
      : data_(data), pos_(pos), swap_(big_endian != (std::endian::native == std::endian::big)) {}

  ReadResult read(PlyType type, double& out) {
    const size_t n = ply_size(type);
    if (pos_ + n > data_.size()) return ReadResult::End;
    unsigned char b[8];
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    if (swap_) std::reverse(b, b + n);
    switch (type) {
      case PlyType::Int8:
        out = load<std::int8_t>(b);
        break;
      case PlyType::UInt8:
        out = load<std::uint8_t>(b);
        break;
      case PlyType::Int16:
        out = load<std::int16_t>(b);
        break;
      case PlyType::UInt16:
        out = load<std::uint16_t>(b);
        break;
      case PlyType::Int32:
        out = load<std::int32_t>(b);
        break;
      case PlyType::UInt32:
        out = load<std::uint32_t>(b);
        break;
      case PlyType::Float32:
        out = load<float>(b);
        break;
      case PlyType::Float64:
        out = load<double>(b);
        break;
    }
    return ReadResult::Ok;
  }
  std::string where() const { return ""; }
  std::string token() const { return {}; }
  int line() const { return 0; }
  static constexpr bool kBinary = true;

 private:
  template <class T>
  static double load(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof(T));
    return static_cast<double>(v);
  }
  std::string_view data_;
  size_t pos_;
  bool swap_;
};

class PlyAsciiReader {
 public:
  PlyAsciiReader(std::string_view text, size_t pos, int line) : lex_(text, pos, line, false) {}
  ReadResult read(PlyType, double& out) {
    if (!lex_.next(token_)) {
      ended_ = true;
      return ReadResult::End;
    }
    return parse_double(token_, out) ? ReadResult::Ok : ReadResult::Bad;
  }
  std::string where() const {
    return "line " + std::to_string(ended_ ? lex_.current_line() : lex_.line()) + ": ";
  }
  std::string token() const { return quote_token(token_); }
  int line() const { return lex_.line(); }
  static constexpr bool kBinary = false;

 private:
  Lexer lex_;
  std::string_view token_;
  bool ended_ = false;
};

template <class Reader>
void read_ply_body(const std::string& path, Reader& reader, const std::vector<PlyElement>& elements,
                   int vertex_element, int face_element, const int xyz[3], int index_property,
                   RawMesh& raw) {
  for (int e = 0; e < static_cast<int>(elements.size()); ++e) {
    const PlyElement& element = elements[e];
    const bool is_vertex = e == vertex_element, is_face = e == face_element;
    if (element.properties.empty()) continue;  // nothing stored, nothing to read
    for (long long item = 0; item < element.count; ++item) {
      auto item_name = [&] { return element.name + " " + std::to_string(item); };
      auto check = [&](ReadResult r, const PlyProperty& property) {
        if (r == ReadResult::End) {
          fail(path, reader.where() + (Reader::kBinary ? "truncated binary data: " : "") +
                         "file ends in " + item_name() + " of " + std::to_string(element.count) +
                         " (element '" + element.name + "', property '" + property.name + "')" +
                         (Reader::kBinary ? "" : " (truncated)"));
        }
        if (r == ReadResult::Bad)
          fail(path, reader.where() + "cannot parse property '" + property.name + "' of " +
                         item_name() + ": " + reader.token());
      };
      Vec3 p = Vec3::Zero();
      int line = 0;
      for (int k = 0; k < static_cast<int>(element.properties.size()); ++k) {
        const PlyProperty& property = element.properties[k];
        double value = 0;
        if (!property.list) {
          check(reader.read(property.type, value), property);
          if (k == 0) line = reader.line();
          if (is_vertex)
            for (int c = 0; c < 3; ++c)
              if (k == xyz[c]) {
                if (!std::isfinite(value))
                  fail(path, reader.where() + "vertex " + std::to_string(item) +
                                 " has a non-finite coordinate " + property.name + " = " +
                                 (std::isnan(value) ? "NaN" : "Inf"));
                p[c] = value;
              }
          continue;
        }
        check(reader.read(property.count_type, value), property);
        if (k == 0) line = reader.line();
        const bool indices = is_face && k == index_property;
        if (!(value >= 0 && value == std::floor(value) && value <= 1e9))
          fail(path, reader.where() + "invalid list length " + std::to_string(value) +
                         " in property '" + property.name + "' of " + item_name());
        const long long n = static_cast<long long>(value);
        if (indices && n < 3)
          fail(path, reader.where() + "face " + std::to_string(item) + " has " +
                         count_of(n, "vertex", "vertices") + ", needs at least 3");
        for (long long j = 0; j < n; ++j) {
          check(reader.read(property.type, value), property);
          if (!indices) continue;
          if (value != std::floor(value))
            fail(path, reader.where() + "face " + std::to_string(item) +
                           " has a non-integer vertex index " + std::to_string(value));
          raw.corners.push_back(static_cast<int>(std::clamp<double>(
              value, std::numeric_limits<int>::min(), std::numeric_limits<int>::max())));
        }
      }
      if (is_vertex) raw.add_vertex(p, line);
      if (is_face) raw.end_polygon(line);
    }
  }
}

RawMesh parse_ply(const std::string& path, std::string_view text) {
  RawMesh raw;
  raw.format = "ply";
  size_t pos = 0;
  int line_no = 0;
  auto next_line = [&](std::string_view& line) {
    if (pos >= text.size()) return false;
    const size_t eol = text.find('\n', pos);
    line = text.substr(pos, eol == std::string_view::npos ? std::string_view::npos : eol - pos);
    pos = eol == std::string_view::npos ? text.size() : eol + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return true;
  };
  auto where = [&] { return "line " + std::to_string(line_no) + ": "; };
  std::string_view line;
  next_line(line);
  if (split(line) != std::vector<std::string_view>{"ply"})
    fail(path,
         where() + "not a PLY file: the first line must be 'ply', found " + quote_token(line));
  enum class Format { None, Ascii, Little, Big } format = Format::None;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (!ended && next_line(line)) {
    const std::vector<std::string_view> t = split(line);
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "format") {
      if (t.size() < 2) fail(path, where() + "PLY format line names no format");
      if (t[1] == "ascii")
        format = Format::Ascii;
      else if (t[1] == "binary_little_endian")
        format = Format::Little;
      else if (t[1] == "binary_big_endian")
        format = Format::Big;
      else
        fail(path, where() + "unknown PLY format " + quote_token(t[1]));
    } else if (t[0] == "element") {
      long long count = 0;
      if (t.size() != 3 || !parse_integer(t[2], count) || count < 0)
        fail(path, where() + "cannot parse PLY element line " + quote_token(line));
      elements.push_back({std::string(t[1]), count, line_no, {}});
    } else if (t[0] == "property") {
      if (elements.empty()) fail(path, where() + "PLY property before any element");
      PlyProperty property;
      bool ok = false;
      if (t.size() == 5 && t[1] == "list") {
        property.list = true;
        property.name = t[4];
        ok = ply_type(t[2], property.count_type) && ply_type(t[3], property.type);
      } else if (t.size() == 3) {
        property.name = t[2];
        ok = ply_type(t[1], property.type);
      }
      if (!ok) fail(path, where() + "cannot parse PLY property line " + quote_token(line));
      if (property.list &&
          (property.count_type == PlyType::Float32 || property.count_type == PlyType::Float64))
        fail(path,
             where() + "PLY list length type must be an integer type in " + quote_token(line));
      elements.back().properties.push_back(property);
    } else if (t[0] == "end_header") {
      ended = true;
    } else {
      fail(path, where() + "cannot parse PLY header line " + quote_token(line));
    }
  }
  if (!ended) fail(path, "PLY header has no 'end_header' line (wrong header or truncated)");
  if (format == Format::None) fail(path, "PLY header has no 'format' line");

  int vertex_element = -1, face_element = -1, index_property = -1;
  int xyz[3] = {-1, -1, -1};
  for (int e = 0; e < static_cast<int>(elements.size()); ++e) {
    if (elements[e].name == "vertex" && vertex_element < 0) vertex_element = e;
    if (elements[e].name == "face" && face_element < 0) face_element = e;
  }
  if (vertex_element < 0) fail(path, "PLY header declares no 'vertex' element");
  {
    const PlyElement& v = elements[vertex_element];
    static const char* const kAxes[] = {"x", "y", "z"};
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < static_cast<int>(v.properties.size()); ++k)
        if (v.properties[k].name == kAxes[c]) xyz[c] = k;
      if (xyz[c] < 0 || v.properties[xyz[c]].list)
        fail(path, "line " + std::to_string(v.line) + ": PLY vertex element has no scalar '" +
                       kAxes[c] + "' property");
    }
  }
  if (face_element >= 0) {
    const PlyElement& f = elements[face_element];
    for (int k = 0; k < static_cast<int>(f.properties.size()); ++k)
      if (f.properties[k].name == "vertex_indices" || f.properties[k].name == "vertex_index")
        index_property = k;
    if (index_property < 0 || !f.properties[index_property].list)
      fail(path,
           "line " + std::to_string(f.line) +
               ": PLY face element has no 'vertex_indices' (or 'vertex_index') list property");
  }
  raw.vertices.reserve(std::min<size_t>(elements[vertex_element].count, text.size() / 3));
  if (format == Format::Ascii) {
    PlyAsciiReader reader(text, pos, line_no + 1);
    read_ply_body(path, reader, elements, vertex_element, face_element, xyz, index_property, raw);
  } else {
    PlyBinaryReader reader(text, pos, format == Format::Big);
    read_ply_body(path, reader, elements, vertex_element, face_element, xyz, index_property, raw);
  }
  return raw;
}

// ---------------------------------------------------------------------------------------------
// STL

bool looks_like_text(std::string_view data) {
  for (char ch : data) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c < 32 && !is_space(ch) && ch != '\n') return false;
    if (c >= 127) return false;
  }
  return true;
}

RawMesh parse_stl_binary(const std::string& path, std::string_view data, std::uint32_t n) {
  RawMesh raw;
  raw.format = "stl";
  raw.stl = true;
  raw.vertices.reserve(size_t{3} * n);
  raw.vertex_line.reserve(size_t{3} * n);
  raw.corners.reserve(size_t{3} * n);
  size_t pos = 84;
  for (std::uint32_t f = 0; f < n; ++f) {
    pos += 12;  // facet normal, recomputed from the corners
    for (int c = 0; c < 3; ++c) {
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        std::uint32_t bits;
        std::memcpy(&bits, data.data() + pos, 4);
        if constexpr (std::endian::native == std::endian::big) bits = __builtin_bswap32(bits);
        p[k] = std::bit_cast<float>(bits);
        pos += 4;
      }
      if (!p.allFinite())
        fail(path, "facet " + std::to_string(f) + ": corner " + std::to_string(c) +
                       " has a non-finite coordinate (NaN or Inf)");
      raw.corners.push_back(static_cast<int>(raw.vertices.size()));
      raw.add_vertex(p, 0);
    }
    raw.end_polygon(0);
    pos += 2;  // attribute byte count
  }
  return raw;
}

RawMesh parse_stl_ascii(const std::string& path, std::string_view text) {
  RawMesh raw;
  raw.format = "stl";
  raw.stl = true;
  Lexer lex(text, 0, 1, false);
  std::string_view token;
  auto where = [&](int line) { return "line " + std::to_string(line) + ": "; };
  auto expect = [&](std::string_view word) {
    if (!lex.next(token))
      fail(path, where(lex.current_line()) + "file ends inside a facet, expected '" +
                     std::string(word) + "' (truncated)");
    if (token != word)
      fail(path, where(lex.line()) + "cannot parse STL: expected '" + std::string(word) +
                     "', found " + quote_token(token));
  };
  expect("solid");
  lex.skip_line();  // solid name
  int facet = 0;
  while (lex.next(token)) {
    if (token == "endsolid") {
      lex.skip_line();
      if (!lex.next(token)) break;
      if (token != "solid")
        fail(path, where(lex.line()) +
                       "cannot parse STL: expected 'solid' or the end of the file, "
                       "found " +
                       quote_token(token));
      lex.skip_line();
      continue;
    }
    if (token != "facet")
      fail(path, where(lex.line()) + "cannot parse STL: expected 'facet' or 'endsolid', found " +
                     quote_token(token));
    const int facet_line = lex.line();
    expect("normal");
    for (int k = 0; k < 3; ++k)
      if (!lex.next(token))
        fail(path, where(lex.current_line()) + "file ends inside a facet normal (truncated)");
    expect("outer");
    expect("loop");
    int corners = 0;
    while (true) {
      if (!lex.next(token))
        fail(path, where(lex.current_line()) + "file ends inside facet " + std::to_string(facet) +
                       " (truncated)");
      if (token == "endloop") break;
      if (token != "vertex")
        fail(path, where(lex.line()) + "cannot parse STL: expected 'vertex' or 'endloop', found " +
                       quote_token(token));
      const int line = lex.line();
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        if (!lex.next_in_line(token))
          fail(path, where(line) + "vertex has " + count_of(k, "coordinate", "coordinates") +
                         ", expected 3");
        if (!parse_double(token, p[k]))
          fail(path, where(line) + "cannot parse vertex coordinate " + quote_token(token));
        if (!std::isfinite(p[k]))
          fail(path, where(line) + "vertex coordinate " + quote_token(token) +
                         " is not a finite number (NaN or Inf)");
      }
      raw.corners.push_back(static_cast<int>(raw.vertices.size()));
      raw.add_vertex(p, line);
      ++corners;
    }
    if (corners < 3)
      fail(path, where(facet_line) + "facet " + std::to_string(facet) + " has " +
                     count_of(corners, "vertex", "vertices") + ", needs at least 3");
    expect("endfacet");
    raw.end_polygon(facet_line);
    ++facet;
  }
  return raw;
}

RawMesh parse_stl(const std::string& path, std::string_view data) {
  const bool solid_prefix = [&] {
    size_t i = 0;
    while (i < data.size() && (is_space(data[i]) || data[i] == '\n')) ++i;
    return data.substr(i, 5) == "solid";
  }();
  if (data.size() >= 84) {
    std::uint32_t n;
    std::memcpy(&n, data.data() + 80, 4);
    if constexpr (std::endian::native == std::endian::big) n = __builtin_bswap32(n);
    const std::uint64_t expected = 84 + 50 * std::uint64_t{n};
    // A binary STL may start with "solid" too: the size decides. Only a file that is pure
    // text and starts with "solid" is read as ASCII even if its size happens to match.
    const bool text = solid_prefix && looks_like_text(data);
    if (expected == data.size() && !text) return parse_stl_binary(path, data, n);
    if (!solid_prefix && looks_like_text(data))
      fail(path, "not an STL file: text that does not start with 'solid'");
    if (!text)
      fail(path, "truncated binary data: binary STL header declares " +
                     count_of(n, "triangle", "triangles") + " (" + std::to_string(expected) +
                     " bytes) but the file has " + std::to_string(data.size()) + " bytes");
  } else if (!solid_prefix) {
    fail(path, "not an STL file: too short for a binary STL (" +
                   count_of(static_cast<long long>(data.size()), "byte", "bytes") +
                   ") and does not start with 'solid'");
  }
  return parse_stl_ascii(path, data);
}

// ---------------------------------------------------------------------------------------------
// Repairs and checks shared by every format.

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};
struct CellHash {
  size_t operator()(const CellKey& k) const {
    std::uint64_t h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<size_t>(h);
  }
};

/// For each vertex with `in_range` set, the first earlier such vertex within `tolerance`
/// (itself a representative), or itself; the others are their own. A hash grid with cells of
/// the tolerance size: O(n) expected.
std::vector<int> weld(const std::vector<Vec3>& points, const std::vector<char>& in_range,
                      double tolerance) {
  const int n = static_cast<int>(points.size());
  std::vector<int> rep(n);
  std::iota(rep.begin(), rep.end(), 0);
  int first = 0;
  while (first < n && !in_range[first]) ++first;
  if (first == n) return rep;
  Vec3 lo = points[first], hi = lo;
  for (int i = first; i < n; ++i)
    if (in_range[i]) {
      lo = lo.cwiseMin(points[i]);
      hi = hi.cwiseMax(points[i]);
    }
  const double extent = (hi - lo).norm();
  // Cells no smaller than 1e-15 of the extent keep the cell coordinates within int64.
  double cell = std::max(tolerance, extent * 1e-15);
  if (!(cell > 0)) cell = 1;
  const double tolerance2 = tolerance * tolerance;
  std::unordered_map<CellKey, std::vector<int>, CellHash> grid;
  grid.reserve(points.size());
  for (int i = first; i < n; ++i) {
    if (!in_range[i]) continue;
    const Vec3 q = (points[i] - lo) / cell;
    const CellKey key{static_cast<std::int64_t>(std::floor(q.x())),
                      static_cast<std::int64_t>(std::floor(q.y())),
                      static_cast<std::int64_t>(std::floor(q.z()))};
    int best = i;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = grid.find({key.x + dx, key.y + dy, key.z + dz});
          if (it == grid.end()) continue;
          for (int j : it->second)
            if (j < best && (points[j] - points[i]).squaredNorm() <= tolerance2) best = j;
        }
    rep[i] = best;
    if (best == i) grid[key].push_back(i);
  }
  return rep;
}

bool zero_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Twice the area against the longest edge squared: scale-free, catches collinear corners up
  // to rounding while keeping genuine slivers (aspect ratios up to ~1e12).
  const double longest2 =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  return (b - a).cross(c - a).norm() <= 1e-12 * longest2;
}

std::uint64_t undirected_key(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
         static_cast<std::uint32_t>(std::max(a, b));
}

struct OrientationResult {
  int flipped = 0;
  int conflict_face = -1;                   ///< a face that cannot be oriented consistently, or -1
  std::array<int, 2> crowded_edge{-1, -1};  ///< an edge with more than two faces, or {-1,-1}
};

/// Flips faces so that neighbours across every two-face edge agree. In each connected
/// component the orientation most faces already have is kept.
OrientationResult orient_consistently(std::vector<Face>& faces) {
  OrientationResult result;
  const int nf = static_cast<int>(faces.size());
  struct HalfEdge {
    std::uint64_t key;
    int face;
    bool forward;  // runs from the smaller to the larger vertex index
  };
  std::vector<HalfEdge> edges;
  edges.reserve(size_t{3} * nf);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = faces[f][i], b = faces[f][(i + 1) % 3];
      edges.push_back({undirected_key(a, b), f, a < b});
    }
  std::sort(edges.begin(), edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.face < y.face;
  });
  // Neighbour lists: (face, 1 if the neighbour must be flipped relative to this face).
  std::vector<std::vector<std::pair<int, char>>> neighbors(nf);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    if (j - i == 2) {
      const char relative = edges[i].forward == edges[i + 1].forward;
      neighbors[edges[i].face].push_back({edges[i + 1].face, relative});
      neighbors[edges[i + 1].face].push_back({edges[i].face, relative});
    } else if (j - i > 2 && result.crowded_edge[0] < 0) {
      result.crowded_edge = {static_cast<int>(edges[i].key >> 32),
                             static_cast<int>(edges[i].key & 0xffffffffu)};
    }
    i = j;
  }
  std::vector<signed char> flip(nf, -1);
  std::vector<int> component;
  std::deque<int> queue;
  for (int seed = 0; seed < nf; ++seed) {
    if (flip[seed] >= 0) continue;
    component.clear();
    flip[seed] = 0;
    queue.push_back(seed);
    while (!queue.empty()) {
      const int f = queue.front();
      queue.pop_front();
      component.push_back(f);
      for (const auto& [g, relative] : neighbors[f]) {
        const signed char want = static_cast<signed char>(flip[f] ^ relative);
        if (flip[g] < 0) {
          flip[g] = want;
          queue.push_back(g);
        } else if (flip[g] != want && result.conflict_face < 0) {
          result.conflict_face = g;
        }
      }
    }
    size_t flipped = 0;
    for (int f : component) flipped += flip[f];
    if (2 * flipped > component.size())
      for (int f : component) flip[f] = static_cast<signed char>(1 - flip[f]);
  }
  for (int f = 0; f < nf; ++f)
    if (flip[f] == 1) {
      std::swap(faces[f][1], faces[f][2]);
      ++result.flipped;
    }
  return result;
}

// ---------------------------------------------------------------------------------------------
// From the parsed contents to a checked mesh: the steps of `finish`, in order.

/// The triangles of the polygons (fan-split), each with the polygon it came from. Checks that
/// there are faces, that the used coordinates are within kMaxCoordinate and that every index
/// is in range.
struct Triangles {
  std::vector<Face> faces;
  std::vector<int> polygon;  ///< per triangle
};
Triangles triangulate(const std::string& name, const RawMesh& raw, LoadReport& report) {
  const int nv = static_cast<int>(raw.vertices.size());
  const int np = raw.polygon_count();
  if (np == 0)
    fail(name, std::string("no faces (") + raw.source + " defines " +
                   count_of(nv, "vertex", "vertices") + " but no faces)");
  // Coordinates beyond kMaxCoordinate (the vertices faces use; isolated ones are dropped later).
  for (int index : raw.corners)
    if (index >= 0 && index < nv && raw.vertices[index].cwiseAbs().maxCoeff() > kMaxCoordinate)
      fail(raw.arrays ? join_field(name, "vertices[" + std::to_string(index) + "]") : name,
           vertex_label(raw, index) + ": a coordinate beyond +-1e15 (rescale the model)");
  Triangles out;
  out.faces.reserve(raw.corners.size());
  for (int p = 0; p < np; ++p) {
    const size_t begin = raw.polygon_begin[p], end = raw.polygon_begin[p + 1];
    for (size_t k = begin; k < end; ++k) {
      const int index = raw.corners[k];
      if (index < 0 || index >= nv) {
        const Place place = face_place(name, raw, p);
        fail(place.field, place.prefix + "face vertex index " +
                              std::to_string(static_cast<long long>(index) + raw.index_base) +
                              " is out of range (" + raw.source + " has " +
                              count_of(nv, "vertex", "vertices") + ")");
      }
    }
    if (end - begin > 3) ++report.polygons_triangulated;
    for (size_t k = begin + 1; k + 1 < end; ++k) {
      out.faces.push_back({raw.corners[begin], raw.corners[k], raw.corners[k + 1]});
      out.polygon.push_back(p);
    }
  }
  return out;
}

/// For each file vertex its representative after welding coincident vertices (within
/// options.duplicate_tolerance of the bounding-box diagonal).
std::vector<int> weld_duplicates(const RawMesh& raw, const MeshLoadOptions& options,
                                 LoadReport& report) {
  // Vertices beyond kMaxCoordinate are isolated (triangulate checked the ones faces use) and
  // dropped later; they neither weld nor scale the tolerance. One at 1e308 made the extent
  // infinite and the cell coordinates NaN (fuzz_mesh_obj, isolated_vertex_at_1e308.obj).
  std::vector<char> in_range(raw.vertices.size(), 0);
  for (size_t v = 0; v < raw.vertices.size(); ++v)
    in_range[v] = raw.vertices[v].cwiseAbs().maxCoeff() <= kMaxCoordinate;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t v = 0; v < raw.vertices.size(); ++v)
    if (in_range[v]) {
      lo = lo.cwiseMin(raw.vertices[v]);
      hi = hi.cwiseMax(raw.vertices[v]);
    }
  const double diagonal = (hi - lo).norm();
  const double tolerance = std::max(0.0, options.duplicate_tolerance) * diagonal;
  std::vector<int> rep = weld(raw.vertices, in_range, std::isfinite(tolerance) ? tolerance : 0.0);
  for (size_t v = 0; v < rep.size(); ++v) report.duplicate_vertices_merged += rep[v] != int(v);
  return rep;
}

/// The welded triangles without degenerate ones (repeated vertex or zero area); `triangles`
/// keeps only the survivors, with their polygons.
void drop_degenerate_faces(const std::string& name, const RawMesh& raw, const std::vector<int>& rep,
                           Triangles& triangles, LoadReport& report) {
  Triangles kept;
  for (size_t t = 0; t < triangles.faces.size(); ++t) {
    const Face f = {rep[triangles.faces[t][0]], rep[triangles.faces[t][1]],
                    rep[triangles.faces[t][2]]};
    if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0] ||
        zero_area(raw.vertices[f[0]], raw.vertices[f[1]], raw.vertices[f[2]])) {
      ++report.degenerate_faces_removed;
      continue;
    }
    kept.faces.push_back(f);
    kept.polygon.push_back(triangles.polygon[t]);
  }
  if (kept.faces.empty())
    fail(name, "no faces left: all " +
                   count_of(report.degenerate_faces_removed, "face is", "faces are") +
                   " degenerate (repeated vertex or zero area)");
  triangles = std::move(kept);
}

/// Drops the vertices no face uses; the survivors keep their file order. Renumbers `faces`,
/// fills report.vertex_of_file_vertex and returns the loaded vertex -> file vertex map.
std::vector<int> drop_isolated_vertices(const RawMesh& raw, const std::vector<int>& rep,
                                        std::vector<Face>& faces, std::vector<Vec3>& vertices,
                                        LoadReport& report) {
  const int nv = static_cast<int>(raw.vertices.size());
  std::vector<int> new_index(nv, -1);
  for (const Face& f : faces)
    for (int v : f) new_index[v] = 0;
  std::vector<int> file_vertex_of;
  for (int v = 0; v < nv; ++v) {
    if (rep[v] != v) continue;
    if (new_index[v] < 0) {
      ++report.isolated_vertices_removed;
      continue;
    }
    new_index[v] = static_cast<int>(file_vertex_of.size());
    file_vertex_of.push_back(v);
    vertices.push_back(raw.vertices[v]);
  }
  for (Face& f : faces)
    for (int& v : f) v = new_index[v];
  report.vertex_of_file_vertex.resize(nv);
  for (int v = 0; v < nv; ++v) report.vertex_of_file_vertex[v] = new_index[rep[v]];
  return file_vertex_of;
}

/// Orients the faces consistently (flipping the minority of each piece) and checks that the
/// result is manifold, naming the file's elements. Returns the number of flipped faces.
int orient_and_check_manifold(const std::string& name, const RawMesh& raw,
                              const std::vector<int>& file_vertex_of,
                              const std::vector<int>& polygon, int vertex_count,
                              std::vector<Face>& faces) {
  const OrientationResult orientation = orient_consistently(faces);
  auto label = [&](int v) { return vertex_label(raw, file_vertex_of[v]); };
  auto vertex_field = [&](int v) {
    return raw.arrays ? join_field(name, "vertices[" + std::to_string(file_vertex_of[v]) + "]")
                      : name;
  };
  const TopologyProblem problem = check_manifold(vertex_count, faces);
  using Kind = TopologyProblem::Kind;
  if (problem.kind == Kind::NonManifoldEdge ||
      (problem.kind == Kind::InconsistentOrientation && orientation.conflict_face < 0 &&
       orientation.crowded_edge[0] >= 0)) {
    const int a =
        problem.kind == Kind::NonManifoldEdge ? problem.element : orientation.crowded_edge[0];
    const int b =
        problem.kind == Kind::NonManifoldEdge ? problem.other : orientation.crowded_edge[1];
    fail(vertex_field(a), "non-manifold edge between " + label(a) + " and " + label(b) +
                              ": it is shared by more than two faces");
  }
  if (problem.kind == Kind::NonManifoldVertex)
    fail(vertex_field(problem.element),
         "non-manifold vertex: " + label(problem.element) +
             ": its faces do not form a single fan (surface pieces touch at this vertex)");
  if (problem.kind == Kind::InconsistentOrientation) {
    const int face = orientation.conflict_face >= 0 ? orientation.conflict_face : problem.element;
    const Place place = face_place(name, raw, polygon[face]);
    fail(place.field, place.prefix +
                          "inconsistent orientation that cannot be fixed: the surface is not "
                          "orientable (like a Moebius strip); " +
                          face_label(raw, polygon[face]) + " cannot agree with all its neighbours");
  }
  if (problem.kind != Kind::None) fail(name, problem.message());
  return orientation.flipped;
}

/// Checks that the mesh is a topological disk: one boundary loop, one piece, Euler
/// characteristic 1.
void check_disk(const std::string& name, const TriangleMesh& mesh) {
  const MeshTopology& topology = mesh.topology();
  const size_t loops = topology.boundary_loops.size();
  if (loops == 0)
    fail(name,
         "the surface is closed (no boundary); a gridshell target must be an open "
         "disk-like patch with exactly one boundary loop");
  if (loops > 1)
    fail(name, "the surface has " + std::to_string(loops) +
                   " boundary loops; a gridshell target must be a disk-like patch with exactly "
                   "one (holes or separate pieces are not supported)");
  // One boundary loop is not enough for a disk: a disk plus a separate closed piece, or a
  // surface with handles, also have one. Count pieces, then check the Euler characteristic.
  std::vector<int> piece(mesh.face_count(), -1);
  int pieces = 0;
  for (int seed = 0; seed < mesh.face_count(); ++seed) {
    if (piece[seed] >= 0) continue;
    std::vector<int> stack{seed};
    piece[seed] = pieces;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      for (int g : topology.face_neighbors[f])
        if (g >= 0 && piece[g] < 0) {
          piece[g] = pieces;
          stack.push_back(g);
        }
    }
    ++pieces;
  }
  if (pieces > 1)
    fail(name, "the surface consists of " + std::to_string(pieces) +
                   " separate pieces; a gridshell target must be one disk-like patch");
  long long edges = 0;
  for (const auto& neighbors : topology.face_neighbors)
    for (int g : neighbors) edges += g < 0 ? 2 : 1;  // interior edges are seen twice
  edges /= 2;
  const long long euler = static_cast<long long>(mesh.vertex_count()) - edges + mesh.face_count();
  if (euler != 1)
    fail(name, "the surface is not a topological disk (Euler characteristic " +
                   std::to_string(euler) + ", " + std::to_string((1 - euler) / 2) +
                   " handle(s)); a gridshell target must be a disk-like patch");
}

/// One warning line per repair kind.
void add_repair_warnings(const std::string& name, const RawMesh& raw, const std::vector<int>& rep,
                         int flipped, const MeshLoadOptions& options, LoadReport& report) {
  const int nv = static_cast<int>(raw.vertices.size());
  if (report.duplicate_vertices_merged > 0) {
    if (raw.stl) {
      int distinct = 0;
      for (int v = 0; v < nv; ++v) distinct += rep[v] == v;
      report.warnings.push_back("note: " + name + ": welded " +
                                count_of(nv, "triangle corner", "triangle corners") + " into " +
                                count_of(distinct, "vertex", "vertices") +
                                " (normal for STL, which stores every triangle separately)");
    } else {
      std::ostringstream tol;
      tol << options.duplicate_tolerance;
      report.warnings.push_back(
          "warning: " + name + ": merged " +
          count_of(report.duplicate_vertices_merged, "duplicate vertex", "duplicate vertices") +
          " (closer than " + tol.str() + " x the bounding-box diagonal)");
    }
  }
  if (report.degenerate_faces_removed > 0)
    report.warnings.push_back(
        "warning: " + name + ": removed " +
        count_of(report.degenerate_faces_removed, "degenerate face", "degenerate faces") +
        " (repeated vertex or zero area)");
  if (report.isolated_vertices_removed > 0)
    report.warnings.push_back(
        "warning: " + name + ": removed " +
        count_of(report.isolated_vertices_removed, "isolated vertex", "isolated vertices") +
        " (not used by any face)");
  if (flipped > 0)
    report.warnings.push_back("warning: " + name + ": flipped " +
                              count_of(flipped, "face", "faces") +
                              " to make the orientation consistent");
}

/// Parsed contents -> checked, repaired mesh. `name` is the field every error names.
TriangleMesh finish(const std::string& name, const RawMesh& raw, LoadReport& report,
                    const MeshLoadOptions& options) {
  report.format = raw.format;
  report.file_vertices = static_cast<int>(raw.vertices.size());
  report.file_faces = raw.polygon_count();
  Triangles triangles = triangulate(name, raw, report);
  const std::vector<int> rep = weld_duplicates(raw, options, report);
  drop_degenerate_faces(name, raw, rep, triangles, report);
  std::vector<Vec3> vertices;
  const std::vector<int> file_vertex_of =
      drop_isolated_vertices(raw, rep, triangles.faces, vertices, report);
  const int flipped = orient_and_check_manifold(name, raw, file_vertex_of, triangles.polygon,
                                                static_cast<int>(vertices.size()), triangles.faces);
  TriangleMesh mesh(std::move(vertices), std::move(triangles.faces));
  if (options.require_single_boundary) check_disk(name, mesh);
  add_repair_warnings(name, raw, rep, flipped, options, report);
  return mesh;
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory)
    fail(path, "cannot open mesh file: " + ec.message());
  if (!fs::exists(status)) fail(path, "cannot open mesh file: no such file");
  if (fs::is_directory(status)) fail(path, "cannot read mesh file: it is a directory");
  // A FIFO would block in open() (uninterruptibly), a device such as /dev/zero never ends.
  if (!fs::is_regular_file(status))
    fail(path, "cannot read mesh file: not a regular file (a device, FIFO or socket)");
  constexpr std::uintmax_t kMaxBytes = std::uintmax_t{4} << 30;
  if (const std::uintmax_t size = fs::file_size(path, ec); !ec && size > kMaxBytes)
    fail(path, "cannot read mesh file: " + std::to_string(size >> 20) +
                   " MiB, more than the 4096 MiB gridshell reads");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open mesh file: ") + std::strerror(errno));
  std::ostringstream out;
  out << in.rdbuf();
  if (in.bad()) fail(path, std::string("cannot read mesh file: ") + std::strerror(errno));
  return out.str();
}

std::string format_double(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, end);
}

}  // namespace

std::optional<MeshFormat> mesh_format_from_name(const std::string& name) {
  std::string t = name;
  std::transform(t.begin(), t.end(), t.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (!t.empty() && t.front() == '.') t.erase(0, 1);
  const std::string extension = fs::path(t).extension().string();
  if (!extension.empty()) t = extension.substr(1);
  if (t == "obj") return MeshFormat::Obj;
  if (t == "off") return MeshFormat::Off;
  if (t == "ply") return MeshFormat::Ply;
  if (t == "stl") return MeshFormat::Stl;
  return std::nullopt;
}

const char* to_string(MeshFormat format) {
  switch (format) {
    case MeshFormat::Obj:
      return "obj";
    case MeshFormat::Off:
      return "off";
    case MeshFormat::Ply:
      return "ply";
    case MeshFormat::Stl:
      return "stl";
  }
  return "obj";
}

TriangleMesh read_mesh(std::string_view data, MeshFormat format, const std::string& name,
                       LoadReport* report, const MeshLoadOptions& options) {
  if (std::all_of(data.begin(), data.end(), [](char c) { return is_space(c) || c == '\n'; }))
    fail(name, "the file is empty");
  RawMesh raw = format == MeshFormat::Obj   ? parse_obj(name, data)
                : format == MeshFormat::Off ? parse_off(name, data)
                : format == MeshFormat::Ply ? parse_ply(name, data)
                                            : parse_stl(name, data);
  LoadReport local;
  LoadReport& out = report ? *report : local;
  out = LoadReport{};
  return finish(name, raw, out, options);
}

std::vector<Vec3> read_points(std::string_view data, MeshFormat format, const std::string& name) {
  if (std::all_of(data.begin(), data.end(), [](char c) { return is_space(c) || c == '\n'; }))
    fail(name, "the file is empty");
  const RawMesh raw = format == MeshFormat::Obj   ? parse_obj(name, data)
                      : format == MeshFormat::Off ? parse_off(name, data)
                      : format == MeshFormat::Ply ? parse_ply(name, data)
                                                  : parse_stl(name, data);
  return raw.vertices;
}

std::string read_file_bytes(const std::string& path) { return read_file(path); }

TriangleMesh load_mesh(const std::string& path, LoadReport* report,
                       const MeshLoadOptions& options) {
  std::string extension = fs::path(path).extension().string();
  const std::optional<MeshFormat> format =
      extension.empty() ? std::nullopt : mesh_format_from_name(extension);
  if (!format)
    fail(path, "unknown mesh file extension " +
                   (extension.empty() ? std::string("(none)") : quote_token(extension)) +
                   "; supported: .obj, .off, .ply, .stl");
  const std::string data = read_file(path);
  return read_mesh(data, *format, path, report, options);
}

TriangleMesh mesh_from_arrays(const std::string& name, const std::vector<Vec3>& vertices,
                              const std::vector<Face>& faces, LoadReport* report,
                              const MeshLoadOptions& options) {
  RawMesh raw;
  raw.format = "arrays";
  raw.arrays = true;
  raw.source = "the mesh";
  if (vertices.empty()) fail(join_field(name, "vertices"), "empty: the mesh has no vertices");
  raw.vertices.reserve(vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) {
    if (!vertices[v].allFinite())
      fail(join_field(name, "vertices[" + std::to_string(v) + "]"),
           "non-finite coordinate " + format_point(vertices[v]));
    raw.add_vertex(vertices[v], 0);
  }
  raw.corners.reserve(3 * faces.size());
  for (const Face& f : faces) {
    raw.corners.insert(raw.corners.end(), f.begin(), f.end());
    raw.end_polygon(0);
  }
  LoadReport local;
  LoadReport& out = report ? *report : local;
  out = LoadReport{};
  return finish(name, raw, out, options);
}

std::string obj_text(const TriangleMesh& mesh) { return obj_text(mesh.vertices(), mesh.faces()); }

std::string obj_text(const std::vector<Vec3>& vertices, const std::vector<Face>& faces) {
  std::string text = "# gridshell mesh: " + std::to_string(vertices.size()) + " vertices, " +
                     std::to_string(faces.size()) + " faces\n";
  text.reserve(text.size() + vertices.size() * 60 + faces.size() * 24);
  for (const Vec3& p : vertices)
    text += "v " + format_double(p.x()) + " " + format_double(p.y()) + " " + format_double(p.z()) +
            "\n";
  for (const Face& f : faces)
    text += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " +
            std::to_string(f[2] + 1) + "\n";
  return text;
}

void save_obj(const TriangleMesh& mesh, const std::string& path) {
  write_file_atomically(path, obj_text(mesh));
}

void write_file_atomically(const std::string& path, const std::string& contents) {
  const fs::path target(path);
  if (target.filename().empty()) fail(path, "cannot write file: not a file name");
  fs::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  static std::atomic<unsigned> counter{0};
  std::string temporary;
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    temporary = (dir / ("." + target.filename().string() + ".tmp" + std::to_string(getpid()) + "-" +
                        std::to_string(counter++)))
                    .string();
    fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) fail(path, std::string("cannot write file: ") + std::strerror(errno));
  auto abandon = [&](int error) {
    ::close(fd);
    ::unlink(temporary.c_str());
    fail(path, std::string("cannot write file: ") + std::strerror(error));
  };
  size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      abandon(errno);
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) abandon(errno);
  if (::close(fd) != 0) {
    const int error = errno;
    ::unlink(temporary.c_str());
    fail(path, std::string("cannot write file: ") + std::strerror(error));
  }
  std::error_code ec;
  fs::rename(temporary, target, ec);
  if (ec) {
    ::unlink(temporary.c_str());
    fail(path, "cannot write file: " + ec.message());
  }
}

}  // namespace gridshell
