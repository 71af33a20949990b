// SPDX-License-Identifier: GPL-3.0-or-later
// One kit for a layout (kernel/fabrication/layout_kit.cpp): a dome in two patches, each
// designed; every part of both is in the kit under its patch's name, every seam bolt has a hole
// in both lamellas of its seam at its arc length, and the bolts counted by grip hold every hole
// exactly once. The order of work deploys and joins every patch.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "gridshell/design/design.h"
#include "gridshell/design/layout.h"
#include "gridshell/fabrication/layout_kit.h"
#include "support.h"

namespace gridshell {
namespace {


struct Vault {
  LayoutResult layout;
  std::vector<Design> designs;
  std::vector<SeamJoints> joints;
  std::vector<LayoutKitPatch> patches;
  std::vector<KitSeam> seams;
};

std::string part_name(const std::string& patch, Family family, int index) {
  return patch + "-" + (family == Family::G ? "g" : "h") + std::to_string(index);
}

/// A shallow dome (40 x 40, 3 high) in two patches: curved both ways, so the member ends of the
/// two fall at different points of their seam.
const Vault& vault() {
  static const Vault v = [] {
    Vault out;
    const int n = 24;
    const TriangleMesh mesh = testing::grid_mesh(n, n, [](double u, double v) {
      return Vec3(40 * u, 40 * v,
                  3 * (1 - (2 * u - 1) * (2 * u - 1)) * (1 - (2 * v - 1) * (2 * v - 1)));
    });
    PatchLayout layout;
    for (int j : {0, n})
      for (int i : {0, n / 2, n}) layout.corners.push_back({j * (n + 1) + i, Vec3::Zero()});
    layout.patches = {{"A", {0, 1, 4, 3}}, {"B", {1, 2, 5, 4}}};
    out.layout = cut_layout(mesh, layout);
    DesignOptions options;
    options.members_g = 4;
    options.members_h = 5;
    for (const LayoutPatch& p : out.layout.patches)
      out.designs.push_back(design_grid(*p.target, options));
    std::vector<const Design*> pointers;
    for (const Design& d : out.designs) pointers.push_back(&d);
    out.joints = seam_joints(out.layout, pointers);
    for (size_t j = 0; j < out.designs.size(); ++j)
      out.patches.push_back({out.layout.patches[j].name, &out.designs[j], out.designs[j].anchors});
    for (const SeamJoints& s : out.joints) {
      KitSeam seam;
      for (int k = 0; k < 2; ++k) seam.patches[k] = out.layout.patches[s.lamellas[k].patch].name;
      seam.corners = out.layout.seams[s.seam].corners;
      for (const SeamJoint& j : s.joints) {
        SeamBolt bolt;
        for (int k = 0; k < 2; ++k) {
          const SeamLamella& l = s.lamellas[k];
          bolt.lamellas[k] = part_name(seam.patches[k], l.family, l.member);
          bolt.along[k] = l.forward ? j.s : l.length - j.s;
        }
        for (const auto& [patch, family, member] : j.ends)
          bolt.members.push_back(part_name(out.layout.patches[patch].name, family, member));
        bolt.point = j.point;
        seam.bolts.push_back(bolt);
      }
      out.seams.push_back(seam);
    }
    return out;
  }();
  return v;
}

FabricationOptions options() {
  FabricationOptions o;
  o.millimetres_per_unit = 100;  // decimetres: a dome 4 m wide
  o.sheet_width = 8000;
  o.sheet_height = 1200;
  return o;
}

TEST(LayoutKit, EveryPartOfEveryPatchIsInTheKitUnderItsPatchsName) {
  const Vault& v = vault();
  ASSERT_EQ(v.seams.size(), 1u);
  const LayoutKit kit = make_layout_kit(v.patches, v.seams, options());
  size_t parts = 0;
  std::set<std::string> names;
  for (size_t j = 0; j < v.designs.size(); ++j) {
    const Grid& grid = v.designs[j].grid;
    parts += grid.g.size() + grid.h.size();
    for (const Member& m : grid.g) names.insert(part_name(v.patches[j].name, Family::G, m.index));
    for (const Member& m : grid.h) names.insert(part_name(v.patches[j].name, Family::H, m.index));
  }
  ASSERT_EQ(kit.kit.parts.size(), parts);
  std::set<std::string> got;
  for (const Part& p : kit.kit.parts) {
    got.insert(p.name);
    EXPECT_GE(p.sheet, 0);
    EXPECT_LT(p.sheet, static_cast<int>(kit.kit.sheets.size()));
    for (const PartFeature& f : p.features) {
      // Partners are named by patch too: the same patch for a crossing, the neighbour's seam
      // lamella for a seam bolt.
      EXPECT_EQ(f.partner_name.find('-'), 1u) << p.name << " " << f.partner_name;
      EXPECT_GE(f.x0, -1e-9);
      EXPECT_LE(f.x1, p.length + 1e-9);
    }
  }
  EXPECT_EQ(got, names);
  ASSERT_EQ(kit.patch_kits.size(), 2u);
  EXPECT_EQ(kit.patch_kits[1].parts.front().name.rfind("B-", 0), 0u);
}

TEST(LayoutKit, EverySeamBoltHasAHoleInBothLamellasAndEveryHoleOneBolt) {
  const Vault& v = vault();
  const FabricationOptions o = options();
  const LayoutKit kit = make_layout_kit(v.patches, v.seams, o);
  std::map<std::string, const Part*> part;
  for (const Part& p : kit.kit.parts) part[p.name] = &p;
  // Expected from the seam's own joints: a lamella needs a hole for a bolt unless a member of its
  // own patch ends within half a hole of it (the bolt then goes through that member's hole), and
  // bolts within half a hole of each other along the seam are one.
  const double half_hole = 0.5 * o.hole_diameter / o.millimetres_per_unit;  // design units
  int bolts_on_seams = 0, holes_needed = 0;
  for (const SeamJoints& seam : v.joints) {
    for (size_t i = 0; i < seam.joints.size(); ++i) {
      if (i == 0 || seam.joints[i].s - seam.joints[i - 1].s > half_hole) ++bolts_on_seams;
      for (const SeamLamella& l : seam.lamellas) {
        bool own = false;
        for (const SeamJoint& other : seam.joints)
          if (std::abs(other.s - seam.joints[i].s) <= half_hole)
            for (const auto& [patch, family, member] : other.ends) own = own || patch == l.patch;
        holes_needed += !own;
      }
    }
  }
  for (const KitSeam& seam : v.seams)
    for (const SeamBolt& bolt : seam.bolts)
      for (int k = 0; k < 2; ++k) {
        // Each lamella has a hole within half a hole of every bolt on it.
        const Part& p = *part.at(bolt.lamellas[k]);
        const double x = bolt.along[k] * o.millimetres_per_unit - p.start;
        double nearest = 1e300;
        for (const PartFeature& f : p.features) nearest = std::min(nearest, std::abs(f.x0 - x));
        EXPECT_LE(nearest, 0.5 * o.hole_diameter) << bolt.lamellas[k] << " at " << x;
      }
  EXPECT_EQ(kit.seam_holes, holes_needed);
  EXPECT_GT(kit.seam_holes, 0);
  // Every hole and slot of the kit is held by exactly one bolt: the grips add up to the
  // crossings' two lamellas each plus one per seam hole.
  int crossings = 0, grips = 0, features = 0;
  for (const Design& d : v.designs) crossings += static_cast<int>(d.grid.crossings.size());
  for (const auto& [grip, count] : kit.bolts_by_grip) grips += grip * count;
  for (const Part& p : kit.kit.parts) features += static_cast<int>(p.features.size());
  EXPECT_EQ(grips, 2 * crossings + kit.seam_holes);
  EXPECT_EQ(features, grips);
  EXPECT_EQ(kit.kit.holes + kit.kit.slots, features);
  // The seam's ends on the outer boundary hold both patches' corner crossings (grip 4).
  EXPECT_GE(kit.bolts_by_grip.at(4), 2);
  EXPECT_EQ(kit.seam_bolts, bolts_on_seams);
  const std::string bom = layout_bom_csv(v.patches, kit, "birch");
  EXPECT_NE(bom.find("seam bolts," + std::to_string(kit.seam_bolts) + ","), std::string::npos)
      << bom;
}

TEST(LayoutKit, TheOrderOfWorkDeploysEveryPatchAndBoltsEverySeamOnce) {
  const Vault& v = vault();
  const std::vector<JoiningStep> steps = joining_order(v.patches, v.seams);
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_EQ(steps[0].patch, "A");
  EXPECT_TRUE(steps[0].seams.empty());
  std::set<int> bolted;
  std::set<std::string> standing;
  for (const JoiningStep& s : steps) {
    standing.insert(s.patch);
    for (int k : s.seams) {
      EXPECT_TRUE(bolted.insert(k).second) << "seam " << k << " bolted twice";
      // Both patches of a seam stand when it is bolted.
      EXPECT_TRUE(standing.count(v.seams[k].patches[0]) && standing.count(v.seams[k].patches[1]));
    }
  }
  EXPECT_EQ(bolted.size(), v.seams.size());
  const std::string svg = joining_svg(v.patches, v.seams);
  EXPECT_NE(svg.find("2. Deploy B."), std::string::npos);
  EXPECT_NE(svg.find("Bolt seam A | B"), std::string::npos) << svg.substr(0, 400);
}

}  // namespace
}  // namespace gridshell
