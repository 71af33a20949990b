// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/design/design_export.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace gridshell {
namespace {

// Six significant digits: enough for a picture (the distance maps).
std::string fmt(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

// The shortest text that reads back as the same double: the flat grid is a drawing to scale,
// and its smallest notch slots are a thousandth of the model (six digits were off by 3 %).
std::string exact(double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, end);
}

// Diverging colour for x in [-1,1]: blue - white - red.
std::string diverging(double x) {
  x = std::clamp(x, -1.0, 1.0);
  const int r = x > 0 ? 255 : static_cast<int>(255 * (1 + x));
  const int b = x < 0 ? 255 : static_cast<int>(255 * (1 - x));
  const int g = static_cast<int>(255 * (1 - std::abs(x)));
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "#%02x%02x%02x", r, g, b);
  return buffer;
}

}  // namespace

std::string planar_svg(const Design& design, double lamella_width) {
  Vec2 lo = design.planar.corners[0], hi = lo;
  for (const Vec2& c : design.planar.corners) lo = lo.cwiseMin(c), hi = hi.cwiseMax(c);
  const double margin = 0.05 * (hi - lo).maxCoeff() + 2 * lamella_width;
  lo.array() -= margin;
  hi.array() += margin;
  const Vec2 size = hi - lo;
  // SVG y points down: flip y so the drawing matches the usual orientation.
  auto X = [&](const Vec2& p) { return exact(p.x() - lo.x()); };
  auto Y = [&](const Vec2& p) { return exact(hi.y() - p.y()); };
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << exact(size.x()) << "mm\" height=\""
      << exact(size.y()) << "mm\" viewBox=\"0 0 " << exact(size.x()) << " " << exact(size.y())
      << "\">\n<title>gridshell planar grid: alpha_bar = " << exact(design.alpha_bar)
      << " rad; 1 unit = 1 mesh unit</title>\n<rect width=\"100%\" height=\"100%\" "
         "fill=\"white\"/>\n";
  const double label = std::max(lamella_width * 1.5, 0.012 * size.maxCoeff());
  for (const auto* family : {&design.grid.g, &design.grid.h})
    for (const Member& m : *family) {
      const char* colour = m.family == Family::G ? "#c8813a" : "#3a7fc8";
      svg << "<line x1=\"" << X(m.planar[0]) << "\" y1=\"" << Y(m.planar[0]) << "\" x2=\""
          << X(m.planar[1]) << "\" y2=\"" << Y(m.planar[1]) << "\" stroke=\"" << colour
          << "\" stroke-opacity=\"0.55\" stroke-width=\"" << exact(lamella_width) << "\"/>\n";
      const Vec2 at = m.planar[0] - (m.planar[1] - m.planar[0]).normalized() * label;
      svg << "<text x=\"" << X(at) << "\" y=\"" << Y(at) << "\" font-size=\"" << exact(label)
          << "\" text-anchor=\"middle\" dominant-baseline=\"middle\" font-family=\"sans-serif\">"
          << (m.family == Family::G ? "g" : "h") << m.index << "</text>\n";
    }
  for (const Crossing& x : design.grid.crossings) {
    const Member& g = design.grid.g[x.g];
    const Member& h = design.grid.h[x.h];
    for (const auto& [member, notch] : {std::pair{&g, x.notch_g()}, std::pair{&h, x.notch_h()}}) {
      if (notch == 0.0) continue;
      const Vec2 dir = (member->planar[1] - member->planar[0]).normalized();
      const Vec2 end = x.planar_point + notch * dir;
      svg << "<line x1=\"" << X(x.planar_point) << "\" y1=\"" << Y(x.planar_point) << "\" x2=\""
          << X(end) << "\" y2=\"" << Y(end)
          << "\" stroke=\"#d62728\" stroke-linecap=\"round\" stroke-width=\""
          << exact(0.4 * lamella_width) << "\"/>\n";
    }
    svg << "<circle cx=\"" << X(x.planar_point) << "\" cy=\"" << Y(x.planar_point) << "\" r=\""
        << exact(0.25 * lamella_width) << "\" fill=\"black\"/>\n";
  }
  for (const Anchor& a : design.anchors) {
    const Vec2 p = design.grid.crossings.empty() ? Vec2::Zero() : [&] {
      for (const Crossing& x : design.grid.crossings)
        if (x.g == a.g && x.h == a.h) return x.planar_point;
      return Vec2(Vec2::Zero());
    }();
    const double s = 1.2 * lamella_width;
    svg << "<rect x=\"" << exact(p.x() - lo.x() - s / 2) << "\" y=\""
        << exact(hi.y() - p.y() - s / 2) << "\" width=\"" << exact(s) << "\" height=\"" << exact(s)
        << "\" fill=\"none\" stroke=\"#2ca02c\" stroke-width=\"" << exact(0.3 * lamella_width)
        << "\"/>\n";
  }
  svg << "</svg>\n";
  return svg.str();
}

std::string spatial_obj(const Design& design) {
  std::ostringstream obj;
  obj.precision(17);
  const TriangleMesh& mesh = design.target.patch.mesh;
  obj << "# gridshell spatial grid: target patch and geodesic members\no patch\n";
  for (const Vec3& v : mesh.vertices())
    obj << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const Face& f : mesh.faces())
    obj << "f " << f[0] + 1 << " " << f[1] + 1 << " " << f[2] + 1 << "\n";
  int next = mesh.vertex_count() + 1;
  for (const auto* family : {&design.grid.g, &design.grid.h})
    for (const Member& m : *family) {
      obj << "o " << (m.family == Family::G ? "g" : "h") << m.index << "\n";
      for (const Vec3& p : m.surface) obj << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
      obj << "l";
      for (size_t k = 0; k < m.surface.size(); ++k) obj << " " << next + static_cast<int>(k);
      obj << "\n";
      next += static_cast<int>(m.surface.size());
    }
  return obj.str();
}

std::string maps_svg(const Design& design) {
  const double cell = 4.0;  // SVG units per drawn cell
  const int R = design.maps.g.resolution();
  const int n = std::min(R, 64);  // drawn cells per side
  const double side = n * cell;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << fmt(2 * side + 60)
      << "\" height=\"" << fmt(side + 60) << "\">\n<rect width=\"100%\" height=\"100%\" "
      << "fill=\"white\"/>\n";
  const std::array<const DistanceMap*, 2> maps{&design.maps.g, &design.maps.h};
  const std::array<const CladdingFunction*, 2> cladding{&design.cladding_g, &design.cladding_h};
  const std::array<const std::vector<Member>*, 2> members{&design.grid.g, &design.grid.h};
  for (int f = 0; f < 2; ++f) {
    const Family family = static_cast<Family>(f);
    const Eigen::MatrixXd diff = maps[f]->distances - planar_distance_map(design.planar, family, R);
    const double scale = std::max(diff.cwiseAbs().maxCoeff(), 1e-300);
    const double ox = 20 + f * (side + 20), oy = 20;
    svg << "<g>\n<text x=\"" << fmt(ox) << "\" y=\"14\" font-size=\"10\" "
        << "font-family=\"sans-serif\">" << (f == 0 ? "D_u - D̄_u (u1 right, u2 up)" : "D_v - D̄_v")
        << ", max |diff| " << fmt(scale) << "</text>\n";
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const int a = static_cast<int>(std::lround(i * (R - 1.0) / std::max(n - 1, 1)));
        const int b = static_cast<int>(std::lround(j * (R - 1.0) / std::max(n - 1, 1)));
        svg << "<rect x=\"" << fmt(ox + i * cell) << "\" y=\"" << fmt(oy + (n - 1 - j) * cell)
            << "\" width=\"" << fmt(cell) << "\" height=\"" << fmt(cell) << "\" fill=\""
            << diverging(diff(a, b) / scale) << "\"/>\n";
      }
    auto P = [&](double u1, double u2) {
      return fmt(ox + u1 * side) + "," + fmt(oy + (1 - u2) * side);
    };
    svg << "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"1\" points=\"";
    for (const Vec2& p : cladding[f]->points) svg << P(p.x(), p.y()) << " ";
    svg << "\"/>\n";
    for (const Member& m : *members[f])
      svg << "<circle r=\"2.5\" fill=\"" << (m.boundary ? "gray" : "black") << "\" cx=\""
          << fmt(ox + m.u_start * side) << "\" cy=\"" << fmt(oy + (1 - m.u_end) * side) << "\"/>\n";
    svg << "</g>\n";
  }
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace gridshell
