// SPDX-License-Identifier: GPL-3.0-or-later
#include "cli_syntax.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <system_error>

#include "gridshell/foundation/errors.h"

namespace gridshell::cli {

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::string current;
  for (char c : text) {
    if (c == separator) {
      parts.push_back(current);
      current.clear();
    } else {
      current += c;
    }
  }
  parts.push_back(current);
  return parts;
}

std::string trim(const std::string& text) {
  const auto b = text.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const auto e = text.find_last_not_of(" \t");
  return text.substr(b, e - b + 1);
}

namespace {

double parse_number(const std::string& text, const std::string& what) {
  const std::string t = trim(text);
  double value = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(value))
    throw InvalidInput("--corners", what + " '" + t + "' is not a finite number");
  return value;
}

}  // namespace

CornerSpec parse_corners(const std::string& text) {
  CornerSpec spec;
  const std::string t = trim(text);
  if (t == "auto") {
    spec.kind = CornerSpec::Kind::Auto;
    return spec;
  }
  if (t.find(';') != std::string::npos) {
    const auto points = split(t, ';');
    if (points.size() != 4)
      throw InvalidInput("--corners", "expected 4 points 'x,y,z;x,y,z;x,y,z;x,y,z', got " +
                                          std::to_string(points.size()));
    spec.kind = CornerSpec::Kind::Points;
    for (int i = 0; i < 4; ++i) {
      const auto xyz = split(points[i], ',');
      if (xyz.size() != 3)
        throw InvalidInput("--corners", "point " + std::to_string(i + 1) +
                                            " must have 3 coordinates x,y,z, got '" +
                                            trim(points[i]) + "'");
      for (int k = 0; k < 3; ++k)
        spec.points[i][k] = parse_number(xyz[k], "coordinate of point " + std::to_string(i + 1));
    }
    return spec;
  }
  const auto parts = split(t, ',');
  if (parts.size() != 4)
    throw InvalidInput("--corners",
                       "expected 4 vertex indices 'i,j,k,l', 4 points "
                       "'x,y,z;x,y,z;x,y,z;x,y,z' or 'auto', got '" +
                           text + "'");
  spec.kind = CornerSpec::Kind::Vertices;
  for (int i = 0; i < 4; ++i) {
    const std::string p = trim(parts[i]);
    long long value = -1;
    const auto [end, ec] = std::from_chars(p.data(), p.data() + p.size(), value);
    if (p.empty() || ec != std::errc() || end != p.data() + p.size() || value < 0 ||
        value > std::numeric_limits<int>::max())
      throw InvalidInput("--corners", "vertex index '" + p + "' is not a non-negative integer");
    spec.vertices[i] = static_cast<int>(value);
  }
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (spec.vertices[i] == spec.vertices[j])
        throw InvalidInput("--corners",
                           "vertex " + std::to_string(spec.vertices[i]) + " is given twice");
  return spec;
}

}  // namespace gridshell::cli
