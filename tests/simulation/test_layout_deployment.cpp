// SPDX-License-Identifier: GPL-3.0-or-later
// A layout's patches designed and deployed (kernel/design/layout_joints.cpp,
// kernel/simulation/layout_deployment.cpp): the seam joints of a barrel vault in two patches
// (both boundary lamellas are the seam, every member end on it has a bolt), the seam gaps and the
// whole's RMS against closed forms on made-up runs, then the real deployment of both patches.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "gridshell/design/design.h"
#include "gridshell/design/layout.h"
#include "gridshell/simulation/layout_deployment.h"
#include "support.h"

namespace gridshell {
namespace {

constexpr double kPi = std::numbers::pi;

/// A barrel vault (a quarter cylinder of radius 10 along x, 60 long) in two patches that share
/// the ruling... the circular arc at x = 30.
struct TwoPatchVault {
  TriangleMesh mesh;
  LayoutResult layout;
  std::vector<Design> designs;
};

const TwoPatchVault& vault() {
  static const TwoPatchVault v = [] {
    TwoPatchVault out;
    const int nu = 30, nv = 8;
    out.mesh = testing::grid_mesh(nu, nv, [](double u, double v) {
      const double phi = kPi / 4 + v * kPi / 2;
      return Vec3(60 * u, 10 * std::cos(phi), 10 * std::sin(phi));
    });
    PatchLayout layout;
    for (int j : {0, nv})
      for (int i : {0, nu / 2, nu}) layout.corners.push_back({j * (nu + 1) + i, Vec3::Zero()});
    layout.patches = {{"A", {0, 1, 4, 3}}, {"B", {1, 2, 5, 4}}};
    out.layout = cut_layout(out.mesh, layout);
    DesignOptions options;
    options.members_g = 5;
    options.members_h = 4;
    for (const LayoutPatch& p : out.layout.patches)
      out.designs.push_back(design_grid(*p.target, options));
    return out;
  }();
  return v;
}

double distance_to_polyline(const Vec3& p, const std::vector<Vec3>& line) {
  double best = 1e300;
  for (size_t k = 0; k + 1 < line.size(); ++k) {
    const Vec3 ab = line[k + 1] - line[k];
    const double t = std::clamp((p - line[k]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (p - (line[k] + t * ab)).norm());
  }
  return best;
}

TEST(LayoutDeployment, BothBoundaryLamellasOfASeamAreTheSeamAndEveryMemberEndHasABolt) {
  const TwoPatchVault& v = vault();
  const std::vector<SeamJoints> joints = seam_joints(v.layout, {&v.designs[0], &v.designs[1]});
  ASSERT_EQ(joints.size(), 1u);
  const SeamJoints& seam = joints[0];
  const LayoutSeam& cut = v.layout.seams[seam.seam];
  EXPECT_NEAR(cut.length, 10 * kPi / 2, 0.01 * cut.length);
  // Both lamellas are the seam: the same length, end to end.
  EXPECT_LE(seam.length_difference, 1e-9 * 60);
  EXPECT_NEAR(seam.lamellas[0].length, cut.length, 1e-9 * 60);
  EXPECT_NE(seam.lamellas[0].patch, seam.lamellas[1].patch);
  // One bolt per member end of either patch on the seam: the inner members of the other family
  // of each patch, plus the two corners, where both patches' boundary members end together.
  int inner_ends = 0;
  for (const SeamLamella& l : seam.lamellas) {
    const Grid& grid = v.designs[l.patch].grid;
    inner_ends += static_cast<int>((l.family == Family::G ? grid.h : grid.g).size()) - 2;
  }
  ASSERT_GE(seam.joints.size(), 2u);
  int ends = 0;
  for (const SeamJoint& joint : seam.joints) ends += static_cast<int>(joint.ends.size());
  EXPECT_EQ(ends, inner_ends + 4);
  EXPECT_NEAR(seam.joints.front().s, 0, 1e-9 * 60);
  EXPECT_NEAR(seam.joints.back().s, cut.length, 1e-9 * 60);
  for (const SeamJoint* corner : {&seam.joints.front(), &seam.joints.back()}) {
    std::set<int> patches;
    for (const auto& [patch, family, member] : corner->ends) patches.insert(patch);
    EXPECT_EQ(patches.size(), 2u);
  }
  // Bolts in order along the seam, on it, and where each patch's member really ends.
  for (size_t k = 0; k < seam.joints.size(); ++k) {
    const SeamJoint& joint = seam.joints[k];
    if (k > 0) {
      EXPECT_GT(joint.s, seam.joints[k - 1].s);
    }
    EXPECT_LE(distance_to_polyline(joint.point, cut.points), 1e-9 * 60);
    for (const auto& [patch, family, member] : joint.ends) {
      const Member& m =
          (family == Family::G ? v.designs[patch].grid.g : v.designs[patch].grid.h)[member];
      const double end = std::min((m.surface.front() - joint.point).norm(),
                                  (m.surface.back() - joint.point).norm());
      EXPECT_LE(end, 1e-6 * 60) << "patch " << patch << " member " << member;
    }
  }
}

TEST(LayoutDeployment, SeamGapsAndTheWholeRmsMatchClosedFormsOnMadeUpRuns) {
  // Two straight lamellas of rest length 10 along x, one 0.3 above the other in z, the second
  // running backwards: a joint at s is 0.3 apart when both are at their rest length, and
  // sqrt(0.3^2 + (0.1 s)^2) when the second is stretched by 10 % from its end at x = 10.
  SeamJoints seam;
  seam.lamellas[0] = {0, Family::G, 0, true, 10};
  seam.lamellas[1] = {1, Family::H, 3, false, 10};
  for (double s : {0.0, 2.5, 7.0, 10.0}) seam.joints.push_back({s, Vec3(s, 0, 0), {}});
  DeploymentRun a, b;
  a.lamellas.push_back({});
  a.lamellas[0].family = Family::G;
  a.lamellas[0].index = 0;
  for (int k = 0; k <= 10; ++k) a.lamellas[0].centerline.push_back(Vec3(k, 0, 0));
  b.lamellas.push_back({});
  b.lamellas[0].family = Family::H;
  b.lamellas[0].index = 3;
  for (int k = 0; k <= 10; ++k) b.lamellas[0].centerline.push_back(Vec3(10 - 1.1 * k, 0, 0.3));
  const std::vector<SeamGaps> gaps = seam_gaps({seam}, {&a, &b});
  ASSERT_EQ(gaps.size(), 1u);
  ASSERT_EQ(gaps[0].gaps.size(), 4u);
  double sum = 0, worst = 0;
  for (size_t k = 0; k < 4; ++k) {
    const double s = seam.joints[k].s;
    // The second lamella's point at arc length 10 - s from its start: x = 10 - 1.1 (10 - s).
    const double expected = std::hypot(s - (10 - 1.1 * (10 - s)), 0.3);
    EXPECT_NEAR(gaps[0].gaps[k], expected, 1e-12) << "s = " << s;
    sum += expected * expected;
    worst = std::max(worst, expected);
  }
  EXPECT_NEAR(gaps[0].max_gap, worst, 1e-12);
  EXPECT_NEAR(gaps[0].rms_gap, std::sqrt(sum / 4), 1e-12);

  // The whole: RMS over all rod vertices.
  a.grid_vertices = 100, a.rms = 0.2, a.max_deviation = 0.5, a.converged = true;
  b.grid_vertices = 300, b.rms = 0.4, b.max_deviation = 0.9, b.converged = true;
  const DeploymentRun whole = combine_runs({&a, nullptr, &b});
  EXPECT_EQ(whole.grid_vertices, 400);
  EXPECT_NEAR(whole.rms, std::sqrt((100 * 0.04 + 300 * 0.16) / 400), 1e-15);
  EXPECT_EQ(whole.max_deviation, 0.9);
  EXPECT_TRUE(whole.converged);
  EXPECT_EQ(whole.lamellas.size(), 2u);
  b.converged = false;
  EXPECT_FALSE(combine_runs({&a, &b}).converged);
  EXPECT_FALSE(combine_runs({nullptr}).converged);
}

TEST(LayoutDeployment, TwoPatchesOfABarrelVaultDeployAndTheirSeamIsMeasured) {
  const TwoPatchVault& v = vault();
  const std::vector<SeamJoints> joints = seam_joints(v.layout, {&v.designs[0], &v.designs[1]});
  std::vector<DeploymentRun> runs;
  for (size_t j = 0; j < 2; ++j) {
    const Design& d = v.designs[j];
    runs.push_back(simulate_deployment(d.grid, d.anchors, d.target.patch.mesh, d.lamella_width,
                                       d.lamella_thickness));
    EXPECT_TRUE(runs.back().converged) << runs.back().termination;
  }
  const std::vector<SeamGaps> gaps = seam_gaps(joints, {&runs[0], &runs[1]});
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_EQ(gaps[0].gaps.size(), joints[0].joints.size());
  // A developable vault deploys close to its target on each side, so the two boundary lamellas
  // of the seam (both anchored at its corners) are close: within 1 % of the vault's diagonal.
  const double diagonal = bounding_box_size(v.mesh).norm();
  EXPECT_LT(gaps[0].max_gap, 0.01 * diagonal);
  const DeploymentRun whole = combine_runs({&runs[0], &runs[1]});
  EXPECT_EQ(whole.grid_vertices, runs[0].grid_vertices + runs[1].grid_vertices);
  EXPECT_GE(whole.rms, std::min(runs[0].rms, runs[1].rms));
  EXPECT_LE(whole.rms, std::max(runs[0].rms, runs[1].rms));
  EXPECT_LT(whole.rms, 0.005 * diagonal);
}

TEST(LayoutDeployment, OnePartWithoutBoltsIsTheSinglePatchDeploymentBitForBit) {
  const Design& d = vault().designs[0];
  const DeploymentRun alone = simulate_deployment(d.grid, d.anchors, d.target.patch.mesh,
                                                  d.lamella_width, d.lamella_thickness);
  const JoinedDeploymentRun joined =
      simulate_joined({DeploymentPart{&d.grid, d.anchors}}, {}, d.target.patch.mesh,
                      d.lamella_width, d.lamella_thickness);
  ASSERT_EQ(joined.parts.size(), 1u);
  EXPECT_TRUE(joined.bolts.empty());
  for (const DeploymentRun* run : {&joined.whole, &joined.parts[0]}) {
    EXPECT_EQ(run->rms, alone.rms);
    EXPECT_EQ(run->iterations, alone.iterations);
    ASSERT_EQ(run->lamellas.size(), alone.lamellas.size());
    for (size_t k = 0; k < alone.lamellas.size(); ++k)
      EXPECT_EQ(run->lamellas[k].centerline, alone.lamellas[k].centerline);
    ASSERT_EQ(run->connections.size(), alone.connections.size());
  }
  EXPECT_EQ(joined.whole.energies, alone.energies);
}

TEST(LayoutDeployment, TwoPatchesOfABarrelVaultJoinedAtTheirSeamCloseItInOneEquilibrium) {
  const TwoPatchVault& v = vault();
  const std::vector<SeamJoints> joints = seam_joints(v.layout, {&v.designs[0], &v.designs[1]});
  ASSERT_EQ(joints.size(), 1u);
  // The anchors that hold the whole: none on the seam, every other one kept.
  std::vector<DeploymentPart> parts;
  const WholeAnchors held =
      whole_anchors({&v.designs[0].anchors, &v.designs[1].anchors},
                    {&v.designs[0].grid, &v.designs[1].grid}, seam_members(joints));
  EXPECT_EQ(held.held_by, -1);  // outer sides hold it
  for (int j = 0; j < 2; ++j) {
    const Design& d = v.designs[j];
    const std::vector<Anchor>& kept = held.patches[j];
    int on_seam = 0;
    for (const Anchor& a : d.anchors) {
      const bool seam_g = joints[0].lamellas[j].family == Family::G &&
                          a.g == joints[0].lamellas[j].member,
                 seam_h = joints[0].lamellas[j].family == Family::H &&
                          a.h == joints[0].lamellas[j].member;
      const bool outer_g = d.grid.g[a.g].boundary && !seam_g,
                 outer_h = d.grid.h[a.h].boundary && !seam_h;
      // On the seam and on no outer side (the seam's two corners are on outer sides too).
      if ((seam_g || seam_h) && !outer_g && !outer_h) ++on_seam;
    }
    EXPECT_EQ(kept.size() + on_seam, d.anchors.size());
    for (const Anchor& a : kept) {
      const SeamLamella& l = joints[0].lamellas[j];
      const bool on_this_seam = l.family == Family::G ? a.g == l.member : a.h == l.member;
      if (on_this_seam) {
        EXPECT_TRUE(a.corner) << "anchor (" << a.g << ", " << a.h << ")";
      }
    }
    parts.push_back({&d.grid, kept});
  }
  const std::vector<PartBolt> bolts = seam_bolts(joints, {0, 1});
  ASSERT_EQ(bolts.size(), joints[0].joints.size());
  for (const PartBolt& b : bolts) {
    EXPECT_EQ(b.part[0], 0);  // the first patch's lamella first
    EXPECT_EQ(b.part[1], 1);
    // Each lamella at its own patch's height: g half a thickness below, h above.
    const double expected =
        (b.family[1] == Family::G ? -0.5 : 0.5) - (b.family[0] == Family::G ? -0.5 : 0.5);
    EXPECT_EQ(b.offset, expected);
  }
  const TriangleMesh whole_target =
      merge_meshes({&v.designs[0].target.patch.mesh, &v.designs[1].target.patch.mesh});
  EXPECT_EQ(whole_target.face_count(), v.designs[0].target.patch.mesh.face_count() +
                                           v.designs[1].target.patch.mesh.face_count());
  const Design& d = v.designs[0];
  ASSERT_EQ(d.lamella_width, v.designs[1].lamella_width);
  const JoinedDeploymentRun joined =
      simulate_joined(parts, bolts, whole_target, d.lamella_width, d.lamella_thickness);
  EXPECT_TRUE(joined.whole.converged) << joined.whole.termination;
  ASSERT_EQ(joined.parts.size(), 2u);
  ASSERT_EQ(joined.bolts.size(), bolts.size());
  EXPECT_EQ(joined.whole.grid_vertices,
            joined.parts[0].grid_vertices + joined.parts[1].grid_vertices);
  EXPECT_EQ(joined.whole.lamellas.size(),
            joined.parts[0].lamellas.size() + joined.parts[1].lamellas.size());
  EXPECT_TRUE(joined.whole.energies.count("bolts"));
  const double diagonal = bounding_box_size(v.mesh).norm();
  EXPECT_LT(joined.whole.rms, 0.005 * diagonal);
  // Closed: at every bolt the two lamellas' points are their offset apart, up to the bolt's
  // reported gap, and far closer than 0.1 % of the diagonal. The points are read as seam_gaps
  // reads them (its closed-form test above), on the joined run's patches.
  const std::vector<SeamGaps> apart = seam_gaps(joints, {&joined.parts[0], &joined.parts[1]});
  ASSERT_EQ(apart.size(), 1u);
  ASSERT_EQ(apart[0].gaps.size(), bolts.size());
  for (size_t k = 0; k < bolts.size(); ++k) {
    EXPECT_LT(joined.bolts[k].gap, 1e-3 * diagonal);
    // The centerline is sampled at rod vertices: the bolt's point between them is off the
    // chord by the lamella's sag over one edge, far below the thickness.
    EXPECT_NEAR(apart[0].gaps[k], std::abs(bolts[k].offset) * d.lamella_thickness,
                joined.bolts[k].gap + 0.2 * d.lamella_thickness)
        << "bolt " << k;
    EXPECT_GT(joined.bolts[k].force, 0);
    EXPECT_TRUE(std::isfinite(joined.bolts[k].force));
  }
  EXPECT_EQ(joined.force_unit, "Pa*unit^2");
}

TEST(LayoutDeployment, BadBoltsAndStartsAreRefusedNamingTheirField) {
  const TwoPatchVault& v = vault();
  const Design& a = v.designs[0];
  const Design& b = v.designs[1];
  const std::vector<DeploymentPart> parts{{&a.grid, a.anchors}, {&b.grid, b.anchors}};
  const TriangleMesh target = merge_meshes({&a.target.patch.mesh, &b.target.patch.mesh});
  auto refused = [&](const std::vector<DeploymentPart>& p, const PartBolt& bolt) {
    try {
      simulate_joined(p, {bolt}, target, a.lamella_width, a.lamella_thickness);
    } catch (const InvalidInput& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  PartBolt bolt;
  bolt.part = {0, 1};
  bolt.member = {0, 0};
  EXPECT_EQ(refused(parts, bolt), "accepted");
  PartBolt missing = bolt;
  missing.member[1] = 99;
  EXPECT_EQ(refused(parts, missing), "bolts[0]");
  PartBolt beyond = bolt;
  beyond.s[0] = 2 * a.grid.g[0].planar_length;
  EXPECT_EQ(refused(parts, beyond), "bolts[0]");
  PartBolt no_part = bolt;
  no_part.part[1] = 2;
  EXPECT_EQ(refused(parts, no_part), "bolts[0]");
  // A start that is not this grid's deployment: a lamella short, or a rod of another resolution.
  DeploymentRun own = simulate_deployment(a.grid, a.anchors, a.target.patch.mesh, a.lamella_width,
                                          a.lamella_thickness);
  std::vector<DeploymentPart> started = parts;
  started[0].start = &own;
  EXPECT_EQ(refused(started, bolt), "accepted");
  own.lamellas[1].centerline.pop_back();
  EXPECT_EQ(refused(started, bolt), "parts[0].start.lamellas[1]");
  own.lamellas.pop_back();
  EXPECT_EQ(refused(started, bolt), "parts[0].start");
}

}  // namespace
}  // namespace gridshell
