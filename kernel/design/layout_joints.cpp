// SPDX-License-Identifier: GPL-3.0-or-later
// Seam joints of a designed layout (see gridshell/design/layout.h): each patch's boundary
// lamella along a shared seam, and a bolt wherever a member of either patch ends on it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "gridshell/design/design.h"
#include "gridshell/design/layout.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

/// The boundary member of `design` that runs along `seam` (either direction).
SeamLamella boundary_along(const Design& design, int patch, const LayoutSeam& seam,
                           double tolerance) {
  const Vec3& a = seam.points.front();
  const Vec3& b = seam.points.back();
  for (Family family : {Family::G, Family::H}) {
    const std::vector<Member>& members = family == Family::G ? design.grid.g : design.grid.h;
    if (members.empty()) continue;
    for (int index : {0, static_cast<int>(members.size()) - 1}) {
      const Member& m = members[index];
      if (m.surface.size() < 2) continue;
      const Vec3& p = m.surface.front();
      const Vec3& q = m.surface.back();
      const bool forward = (p - a).norm() <= tolerance && (q - b).norm() <= tolerance;
      const bool backward = (p - b).norm() <= tolerance && (q - a).norm() <= tolerance;
      if (forward || backward) return {patch, family, index, forward, m.length};
    }
  }
  throw Infeasible("layout.patches[" + std::to_string(patch) + "]",
                   "no boundary member of its design runs along the seam between corners " +
                       std::to_string(seam.corners[0]) + " and " + std::to_string(seam.corners[1]));
}

/// The point at arc length s along a polyline.
Vec3 point_at(const std::vector<Vec3>& points, double s) {
  for (size_t k = 0; k + 1 < points.size(); ++k) {
    const double length = (points[k + 1] - points[k]).norm();
    if (s <= length || k + 2 == points.size()) {
      const double t = length > 0 ? std::clamp(s / length, 0.0, 1.0) : 0.0;
      return points[k] + t * (points[k + 1] - points[k]);
    }
    s -= length;
  }
  return points.empty() ? Vec3::Zero() : points.front();
}

}  // namespace

std::vector<SeamJoints> seam_joints(const LayoutResult& layout,
                                    const std::vector<const Design*>& designs) {
  std::vector<SeamJoints> out;
  Vec3 lo = Vec3::Constant(1e300), hi = -lo;
  for (const Vec3& p : layout.corners) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double scale = layout.corners.empty() ? 1.0 : std::max(1.0, (hi - lo).norm());
  for (size_t i = 0; i < layout.seams.size(); ++i) {
    const LayoutSeam& seam = layout.seams[i];
    if (!seam.shared() || seam.points.size() < 2) continue;
    const int j1 = seam.uses[0].first, j2 = seam.uses[1].first;
    if (j1 >= static_cast<int>(designs.size()) || j2 >= static_cast<int>(designs.size()) ||
        !designs[j1] || !designs[j2])
      continue;
    SeamJoints joints;
    joints.seam = static_cast<int>(i);
    // Both designs were made on the cut patches, whose sides along the seam are its points.
    const double tolerance = 1e-7 * scale;
    joints.lamellas = {boundary_along(*designs[j1], j1, seam, tolerance),
                       boundary_along(*designs[j2], j2, seam, tolerance)};
    joints.length_difference = std::abs(joints.lamellas[0].length - joints.lamellas[1].length);
    // Every crossing on either boundary lamella is a member's end on the seam.
    struct End {
      double s;
      std::tuple<int, Family, int> member;
    };
    std::vector<End> ends;
    for (const SeamLamella& lamella : joints.lamellas) {
      const Design& design = *designs[lamella.patch];
      for (const Crossing& c : design.grid.crossings) {
        const bool on_g = lamella.family == Family::G && c.g == lamella.member;
        const bool on_h = lamella.family == Family::H && c.h == lamella.member;
        if (!on_g && !on_h) continue;
        const double along = on_g ? c.s_g : c.s_h;
        const double s = lamella.forward ? along : lamella.length - along;
        ends.push_back(
            {std::clamp(s, 0.0, seam.length), on_g ? std::tuple{lamella.patch, Family::H, c.h}
                                                   : std::tuple{lamella.patch, Family::G, c.g}});
      }
    }
    std::sort(ends.begin(), ends.end(), [](const End& x, const End& y) { return x.s < y.s; });
    const double merge = 1e-6 * seam.length;
    for (const End& end : ends) {
      if (joints.joints.empty() || end.s - joints.joints.back().s > merge) {
        SeamJoint joint;
        joint.s = end.s;
        joints.joints.push_back(joint);
      }
      joints.joints.back().ends.push_back(end.member);
    }
    for (SeamJoint& joint : joints.joints) joint.point = point_at(seam.points, joint.s);
    out.push_back(std::move(joints));
  }
  return out;
}

std::vector<SeamMember> seam_members(const std::vector<SeamJoints>& joints) {
  std::vector<SeamMember> out;
  for (const SeamJoints& seam : joints)
    for (const SeamLamella& l : seam.lamellas) out.push_back({l.patch, l.family, l.member});
  return out;
}

WholeAnchors whole_anchors(const std::vector<const std::vector<Anchor>*>& anchors,
                           const std::vector<const Grid*>& grids,
                           const std::vector<SeamMember>& seams) {
  if (anchors.size() != grids.size())
    throw std::invalid_argument("whole_anchors: one grid per patch's anchors");
  WholeAnchors out;
  out.patches.resize(anchors.size());
  size_t kept = 0;
  for (size_t j = 0; j < anchors.size(); ++j) {
    if (!anchors[j] || !grids[j]) continue;
    const Grid& grid = *grids[j];
    const auto on_seam = [&](Family family, int member) {
      for (const SeamMember& s : seams)
        if (s.patch == static_cast<int>(j) && s.family == family && s.member == member) return true;
      return false;
    };
    const auto boundary = [](const std::vector<Member>& members, int index) {
      return index >= 0 && index < static_cast<int>(members.size()) && members[index].boundary;
    };
    for (const Anchor& a : *anchors[j]) {
      const bool on_g = boundary(grid.g, a.g), on_h = boundary(grid.h, a.h);
      const bool inside = (!on_g || on_seam(Family::G, a.g)) && (!on_h || on_seam(Family::H, a.h));
      // Inner anchors (on no boundary member) hold the whole too.
      if ((on_g || on_h) && inside) continue;
      out.patches[j].push_back(a);
    }
    kept += out.patches[j].size();
  }
  if (kept > 0) return out;
  double lowest_z = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < anchors.size(); ++j) {
    if (!anchors[j] || !grids[j] || anchors[j]->empty()) continue;
    double z = 0;
    for (const Anchor& a : *anchors[j]) z += a.position.z();
    z /= static_cast<double>(anchors[j]->size());
    if (z < lowest_z) lowest_z = z, out.held_by = static_cast<int>(j);
  }
  if (out.held_by >= 0) out.patches[out.held_by] = *anchors[out.held_by];
  return out;
}

}  // namespace gridshell
