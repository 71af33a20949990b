// SPDX-License-Identifier: GPL-3.0-or-later
// The deployment of a layout's patches taken together (see
// gridshell/simulation/layout_deployment.h).
#include "gridshell/simulation/layout_deployment.h"

#include <algorithm>
#include <cmath>

namespace gridshell {
namespace {

/// The point at arc length fraction t in [0, 1] along a polyline.
Vec3 point_at_fraction(const std::vector<Vec3>& points, double t) {
  double total = 0;
  for (size_t k = 0; k + 1 < points.size(); ++k) total += (points[k + 1] - points[k]).norm();
  double s = std::clamp(t, 0.0, 1.0) * total;
  for (size_t k = 0; k + 1 < points.size(); ++k) {
    const double length = (points[k + 1] - points[k]).norm();
    if (s <= length || k + 2 == points.size()) {
      const double u = length > 0 ? std::clamp(s / length, 0.0, 1.0) : 0.0;
      return points[k] + u * (points[k + 1] - points[k]);
    }
    s -= length;
  }
  return points.empty() ? Vec3::Zero() : points.front();
}

const SimulatedLamella* find_lamella(const DeploymentRun& run, Family family, int index) {
  for (const SimulatedLamella& l : run.lamellas)
    if (l.family == family && l.index == index) return &l;
  return nullptr;
}

}  // namespace

std::vector<SeamGaps> seam_gaps(const std::vector<SeamJoints>& joints,
                                const std::vector<const DeploymentRun*>& runs) {
  std::vector<SeamGaps> out;
  for (const SeamJoints& seam : joints) {
    std::array<const SimulatedLamella*, 2> lamellas{};
    for (int k = 0; k < 2; ++k) {
      const SeamLamella& l = seam.lamellas[k];
      const DeploymentRun* run = l.patch < static_cast<int>(runs.size()) ? runs[l.patch] : nullptr;
      lamellas[k] = run ? find_lamella(*run, l.family, l.member) : nullptr;
    }
    if (!lamellas[0] || !lamellas[1]) continue;
    SeamGaps gaps;
    gaps.seam = seam.seam;
    double sum = 0;
    for (const SeamJoint& joint : seam.joints) {
      std::array<Vec3, 2> at;
      for (int k = 0; k < 2; ++k) {
        const SeamLamella& l = seam.lamellas[k];
        const double along = l.forward ? joint.s : l.length - joint.s;
        at[k] = point_at_fraction(lamellas[k]->centerline, l.length > 0 ? along / l.length : 0);
      }
      const double gap = (at[0] - at[1]).norm();
      gaps.gaps.push_back(gap);
      gaps.max_gap = std::max(gaps.max_gap, gap);
      sum += gap * gap;
    }
    gaps.rms_gap = gaps.gaps.empty() ? 0 : std::sqrt(sum / gaps.gaps.size());
    out.push_back(std::move(gaps));
  }
  return out;
}

DeploymentRun combine_runs(const std::vector<const DeploymentRun*>& runs) {
  DeploymentRun whole;
  whole.converged = true;
  double squares = 0;
  bool any = false;
  for (const DeploymentRun* run : runs) {
    if (!run) continue;
    any = true;
    whole.notches = run->notches;
    whole.lamellas.insert(whole.lamellas.end(), run->lamellas.begin(), run->lamellas.end());
    whole.grid_vertices += run->grid_vertices;
    squares += run->rms * run->rms * run->grid_vertices;
    whole.max_deviation = std::max(whole.max_deviation, run->max_deviation);
    whole.iterations += run->iterations;
    whole.outer_iterations += run->outer_iterations;
    whole.connection_moves += run->connection_moves;
    whole.connections_at_vertices += run->connections_at_vertices;
    whole.converged = whole.converged && run->converged;
    whole.gradient_norm = std::max(whole.gradient_norm, run->gradient_norm);
    whole.seconds += run->seconds;
    for (const auto& [term, energy] : run->energies) whole.energies[term] += energy;
    whole.energy_unit = run->energy_unit;
  }
  whole.converged = whole.converged && any;
  whole.rms = whole.grid_vertices > 0 ? std::sqrt(squares / whole.grid_vertices) : 0;
  return whole;
}

std::vector<PartBolt> seam_bolts(const std::vector<SeamJoints>& joints,
                                 const std::vector<int>& part_of) {
  std::vector<PartBolt> out;
  auto part = [&](int patch) {
    return patch >= 0 && patch < static_cast<int>(part_of.size()) ? part_of[patch] : -1;
  };
  // A rod starts half a thickness below the surface (g) or above it (h).
  auto height = [](Family family) { return family == Family::G ? -0.5 : 0.5; };
  for (const SeamJoints& seam : joints) {
    std::array<const SeamLamella*, 2> ends{&seam.lamellas[0], &seam.lamellas[1]};
    if (ends[1]->patch < ends[0]->patch) std::swap(ends[0], ends[1]);
    if (part(ends[0]->patch) < 0 || part(ends[1]->patch) < 0) continue;
    for (const SeamJoint& joint : seam.joints) {
      PartBolt bolt;
      for (int k = 0; k < 2; ++k) {
        const SeamLamella& l = *ends[k];
        bolt.part[k] = part(l.patch);
        bolt.family[k] = l.family;
        bolt.member[k] = l.member;
        bolt.s[k] = std::clamp(l.forward ? joint.s : l.length - joint.s, 0.0, l.length);
      }
      bolt.offset = height(ends[1]->family) - height(ends[0]->family);
      out.push_back(bolt);
    }
  }
  return out;
}

TriangleMesh merge_meshes(const std::vector<const TriangleMesh*>& meshes) {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;
  for (const TriangleMesh* mesh : meshes) {
    const int offset = static_cast<int>(vertices.size());
    vertices.insert(vertices.end(), mesh->vertices().begin(), mesh->vertices().end());
    for (Face f : mesh->faces()) {
      for (int& v : f) v += offset;
      faces.push_back(f);
    }
  }
  return TriangleMesh(std::move(vertices), std::move(faces));
}

}  // namespace gridshell
