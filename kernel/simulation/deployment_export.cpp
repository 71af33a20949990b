// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/simulation/deployment_export.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace gridshell {
namespace {

void append(std::string& out, const char* format, double a, double b, double c) {
  char line[128];
  std::snprintf(line, sizeof line, format, a, b, c);
  out += line;
}

}  // namespace

std::string deployed_obj(const DeploymentRun& run, double width, double thickness) {
  std::string out = "# gridshell deployed lamellas (";
  out += run.notches ? "with" : "without";
  out += " notches): boxes of width " + std::to_string(width) + " and thickness " +
         std::to_string(thickness) + "\n";
  int base = 1;  // OBJ indices start at 1
  for (const SimulatedLamella& l : run.lamellas) {
    const int n = static_cast<int>(l.centerline.size());
    if (n < 2) continue;
    out += std::string("o ") + (l.family == Family::G ? "g" : "h") + std::to_string(l.index) + "\n";
    // Four corners per vertex, counter-clockwise around the tangent: (+w,+t) (-w,+t) (-w,-t)
    // (+w,-t) in the (width, normal) plane.
    const double sw[4] = {0.5, -0.5, -0.5, 0.5}, st[4] = {0.5, 0.5, -0.5, -0.5};
    for (int v = 0; v < n; ++v)
      for (int c = 0; c < 4; ++c) {
        const Vec3 p =
            l.centerline[v] + sw[c] * width * l.widths[v] + st[c] * thickness * l.normals[v];
        append(out, "v %.9g %.9g %.9g\n", p.x(), p.y(), p.z());
      }
    // The frame (t, m1, m2) is right-handed with m2 = t x m1; the corner order runs
    // (+m2,+m1) -> (-m2,+m1) -> ..., i.e. clockwise seen along +t; side quads below are
    // ordered so that their normals point away from the centerline.
    for (int v = 0; v + 1 < n; ++v)
      for (int c = 0; c < 4; ++c) {
        const int a = base + 4 * v + c, b = base + 4 * v + (c + 1) % 4;
        out += "f " + std::to_string(a) + " " + std::to_string(a + 4) + " " +
               std::to_string(b + 4) + " " + std::to_string(b) + "\n";
      }
    const int first = base, last = base + 4 * (n - 1);
    out += "f " + std::to_string(first) + " " + std::to_string(first + 1) + " " +
           std::to_string(first + 2) + " " + std::to_string(first + 3) + "\n";
    out += "f " + std::to_string(last + 3) + " " + std::to_string(last + 2) + " " +
           std::to_string(last + 1) + " " + std::to_string(last) + "\n";
    base += 4 * n;
  }
  return out;
}

std::string deviation_ply(const DeploymentRun& run, double max_deviation) {
  int vertices = 0, edges = 0;
  for (const SimulatedLamella& l : run.lamellas) {
    vertices += static_cast<int>(l.centerline.size());
    edges += std::max(0, static_cast<int>(l.centerline.size()) - 1);
  }
  const double top = max_deviation > 0 ? max_deviation : std::max(run.max_deviation, 1e-300);
  std::string out = "ply\nformat ascii 1.0\n";
  out += "comment gridshell deployment ";
  out += run.notches ? "with" : "without";
  out += " notches: rod vertices coloured by distance to the target, blue 0 to red " +
         std::to_string(top) + "\n";
  out += "element vertex " + std::to_string(vertices) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "property float deviation\n";
  out += "element edge " + std::to_string(edges) + "\n";
  out += "property int vertex1\nproperty int vertex2\nend_header\n";
  char line[160];
  for (const SimulatedLamella& l : run.lamellas)
    for (size_t v = 0; v < l.centerline.size(); ++v) {
      const double d = v < l.deviation.size() ? l.deviation[v] : 0.0;
      const double f = std::clamp(d / top, 0.0, 1.0);
      // blue -> green -> red
      const double r = std::clamp(2 * f - 1, 0.0, 1.0), b = std::clamp(1 - 2 * f, 0.0, 1.0),
                   g = 1 - r - b;
      const Vec3& p = l.centerline[v];
      std::snprintf(line, sizeof line, "%.9g %.9g %.9g %d %d %d %.9g\n", p.x(), p.y(), p.z(),
                    static_cast<int>(std::lround(255 * r)), static_cast<int>(std::lround(255 * g)),
                    static_cast<int>(std::lround(255 * b)), d);
      out += line;
    }
  int base = 0;
  for (const SimulatedLamella& l : run.lamellas) {
    const int n = static_cast<int>(l.centerline.size());
    for (int v = 0; v + 1 < n; ++v)
      out += std::to_string(base + v) + " " + std::to_string(base + v + 1) + "\n";
    base += n;
  }
  return out;
}

}  // namespace gridshell
