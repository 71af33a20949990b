// SPDX-License-Identifier: GPL-3.0-or-later
// One fabrication kit for every patch of a layout (see gridshell/fabrication/layout_kit.h).
#include "gridshell/fabrication/layout_kit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>

#include "gridshell/fabrication/kit_export.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

/// A bolt position and the lamellas it holds.
struct Position {
  Vec3 point;
  std::set<std::string> lamellas;
  bool seam = false;  ///< a seam bolt is here
};

}  // namespace

std::string layout_part_name(const std::string& patch, Family family, int index) {
  return patch + "-" + (family == Family::G ? "g" : "h") + std::to_string(index);
}

std::optional<std::pair<Family, int>> parse_layout_part_name(const std::string& name,
                                                             const std::string& patch) {
  const std::string prefix = patch + "-";
  if (name.size() < prefix.size() + 2 || name.compare(0, prefix.size(), prefix) != 0)
    return std::nullopt;
  const char family = name[prefix.size()];
  const std::string index = name.substr(prefix.size() + 1);
  if ((family != 'g' && family != 'h') || index.size() > 8 ||
      !std::all_of(index.begin(), index.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::nullopt;
  return std::pair{family == 'g' ? Family::G : Family::H, std::stoi(index)};
}

LayoutKit make_layout_kit(const std::vector<LayoutKitPatch>& patches,
                          const std::vector<KitSeam>& seams, const FabricationOptions& options,
                          const Progress& progress) {
  LayoutKit out;
  // Each patch's parts as its own kit makes them, named by patch.
  for (size_t p = 0; p < patches.size(); ++p) {
    progress.report("fabricate: parts of " + patches[p].name,
                    static_cast<double>(p) / patches.size());
    Kit kit;
    try {
      kit = make_kit(*patches[p].design, options, progress.checker());
    } catch (const Cancelled&) {
      throw;
    } catch (const Error& e) {
      throw Error(e.code(), e.field(), "patch " + patches[p].name + ": " + e.message(), e.reason());
    }
    for (Part& part : kit.parts) {
      part.name = patches[p].name + "-" + part.name;
      for (PartFeature& f : part.features) f.partner_name = patches[p].name + "-" + f.partner_name;
    }
    if (p == 0) {
      out.kit.options = kit.options;
      out.kit.top_family = kit.top_family;
    }
    out.kit.holes += kit.holes;
    out.kit.slots += kit.slots;
    out.patch_kits.push_back(kit);
    for (const Part& part : kit.parts) out.kit.parts.push_back(part);
  }
  const double mm = out.kit.options.millimetres_per_unit;
  // Seam bolts: a hole in each lamella where it has none.
  std::map<std::string, size_t> part_of;
  for (size_t i = 0; i < out.kit.parts.size(); ++i) part_of[out.kit.parts[i].name] = i;
  std::vector<SeamBolt> bolts;
  for (const KitSeam& seam : seams) bolts.insert(bolts.end(), seam.bolts.begin(), seam.bolts.end());
  for (size_t k = 0; k < bolts.size(); ++k) {
    const SeamBolt& bolt = bolts[k];
    for (int side = 0; side < 2; ++side) {
      const auto it = part_of.find(bolt.lamellas[side]);
      if (it == part_of.end())
        throw InvalidInput("seams", "no patch has the lamella " + bolt.lamellas[side] +
                                        " of seam bolt " + std::to_string(k + 1));
      Part& part = out.kit.parts[it->second];
      const double x = bolt.along[side] * mm - part.start;
      if (x < -1e-6 || x > part.length + 1e-6)
        throw InvalidInput(
            "seams", "seam bolt " + std::to_string(k + 1) + " lies outside lamella " + part.name);
      // A bolt within half a hole of a hole the lamella has goes through that hole.
      const double tolerance = 0.5 * out.kit.options.hole_diameter;
      const bool has_hole =
          std::any_of(part.features.begin(), part.features.end(), [&](const PartFeature& f) {
            return std::abs(f.x0 - x) <= tolerance || std::abs(f.x1 - x) <= tolerance;
          });
      if (has_hole) continue;
      PartFeature hole;
      hole.kind = FeatureKind::Hole;
      hole.crossing = -1;  // a seam bolt, not a crossing of the patch
      hole.s_bar = hole.s = bolt.along[side];
      hole.x0 = hole.x1 = x;
      hole.diameter = out.kit.options.hole_diameter;
      hole.partner_name = bolt.lamellas[1 - side];
      part.features.push_back(hole);
      std::sort(part.features.begin(), part.features.end(),
                [](const PartFeature& a, const PartFeature& b) { return a.x0 < b.x0; });
      ++out.kit.holes;
      ++out.seam_holes;
    }
  }
  progress.report("fabricate: nesting", 0.5);
  nest_kit(out.kit);

  // Bolts: every crossing and every seam bolt, one where they coincide (at seams and corners).
  std::vector<Position> shared;  // positions on a patch's boundary or a seam
  int inner = 0;
  for (const LayoutKitPatch& patch : patches)
    for (const Crossing& c : patch.design->grid.crossings) {
      if (!c.on_boundary) {
        ++inner;
        continue;
      }
      shared.push_back({c.surface_point,
                        {layout_part_name(patch.name, Family::G, c.g),
                         layout_part_name(patch.name, Family::H, c.h)},
                        false});
    }
  for (const SeamBolt& bolt : bolts)
    shared.push_back({bolt.point, {bolt.lamellas[0], bolt.lamellas[1]}, true});
  // One bolt where positions are within half a hole of each other, as a seam bolt goes through
  // a lamella's hole that close (above).
  const double tolerance = 0.5 * out.kit.options.hole_diameter / mm;
  std::vector<Position> merged;
  for (const Position& p : shared) {
    Position* same = nullptr;
    for (Position& m : merged)
      if ((m.point - p.point).norm() <= tolerance) {
        same = &m;
        break;
      }
    if (same) {
      same->lamellas.insert(p.lamellas.begin(), p.lamellas.end());
      same->seam = same->seam || p.seam;
    } else {
      merged.push_back(p);
    }
  }
  if (inner > 0) out.bolts_by_grip[2] += inner;
  for (const Position& m : merged) {
    out.bolts_by_grip[static_cast<int>(m.lamellas.size())] += 1;
    out.seam_bolts += m.seam;
  }
  progress.report("fabricate: nesting", 1);
  return out;
}

std::string layout_supports_csv(const std::vector<LayoutKitPatch>& patches, double scale,
                                const std::string& unit) {
  double ground = 1e300;
  for (const LayoutKitPatch& p : patches) ground = std::min(ground, ground_height(*p.design));
  std::string out = supports_header(unit);
  for (const LayoutKitPatch& p : patches)
    for (const Anchor& a : p.supports) {
      // Numbered as on the patch's assembly sheet: its place among the design's anchors.
      size_t number = 0;
      for (size_t i = 0; i < p.design->anchors.size(); ++i)
        if (p.design->anchors[i].g == a.g && p.design->anchors[i].h == a.h) number = i + 1;
      out += support_row(p.name + "-A" + std::to_string(number), a, ground, scale);
    }
  return out;
}

std::string layout_bom_csv(const std::vector<LayoutKitPatch>& patches, const LayoutKit& kit,
                           const std::string& material) {
  const FabricationOptions& o = kit.kit.options;
  char line[512];
  std::string out = "item,quantity,unit,description\n";
  for (Family family : {Family::G, Family::H}) {
    int count = 0;
    double total = 0, longest = 0;
    for (const Part& p : kit.kit.parts)
      if (p.family == family) {
        ++count;
        total += p.length;
        longest = std::max(longest, p.length);
      }
    std::snprintf(line, sizeof line,
                  "lamellas %s,%d,pcs,\"%.1f mm in all, longest %.1f mm, %.2f mm thick; %zu "
                  "patches\"\n",
                  family == Family::G ? "g" : "h", count, total, longest, o.thickness,
                  patches.size());
    out += line;
  }
  std::snprintf(line, sizeof line, "sheets,%zu,pcs,\"%.1f x %.1f x %.2f mm %s, %.1f %% used\"\n",
                kit.kit.sheets.size(), o.sheet_width, o.sheet_height, o.thickness, material.c_str(),
                100 * kit.kit.utilisation);
  out += line;
  int bolts = 0;
  for (const auto& [grip, count] : kit.bolts_by_grip) {
    std::snprintf(line, sizeof line,
                  "bolts grip %d,%d,pcs,\"for %.2f mm holes, grip at least %.2f mm (%d "
                  "lamellas)\"\n",
                  grip, count, o.hole_diameter, grip * o.thickness, grip);
    out += line;
    bolts += count;
  }
  std::snprintf(line, sizeof line,
                "seam bolts,%d,pcs,\"of the bolts above: through both boundary lamellas of a "
                "seam (%d holes added for them)\"\n",
                kit.seam_bolts, kit.seam_holes);
  out += line;
  std::snprintf(line, sizeof line,
                "nuts,%d,pcs,\"to match the bolts; lock nuts where a crossing does not slide\"\n",
                bolts);
  out += line;
  std::snprintf(line, sizeof line, "washers,%d,pcs,\"under the nuts on slots (%d slots)\"\n",
                2 * bolts, kit.kit.slots);
  out += line;
  std::snprintf(line, sizeof line, "holes,%d,pcs,\"round holes, %.2f mm (cut %.2f mm)\"\n",
                kit.kit.holes, o.hole_diameter, o.hole_diameter - o.kerf);
  out += line;
  std::snprintf(line, sizeof line, "slots,%d,pcs,\"%.2f mm wide (cut %.2f mm)\"\n", kit.kit.slots,
                o.hole_diameter, o.hole_diameter - o.kerf);
  out += line;
  size_t anchors = 0;
  for (const LayoutKitPatch& p : patches) anchors += p.supports.size();
  std::snprintf(line, sizeof line,
                "supports,%zu,pcs,\"one per anchor that holds the whole (supports.csv)\"\n",
                anchors);
  out += line;
  return out;
}

std::vector<JoiningStep> joining_order(const std::vector<LayoutKitPatch>& patches,
                                       const std::vector<KitSeam>& seams) {
  std::map<std::string, size_t> index;
  for (size_t p = 0; p < patches.size(); ++p) index[patches[p].name] = p;
  std::vector<char> standing(patches.size(), 0), bolted(seams.size(), 0);
  std::vector<JoiningStep> steps;
  for (size_t start = 0; start < patches.size(); ++start) {
    if (standing[start]) continue;
    std::vector<size_t> queue{start};
    standing[start] = 1;
    for (size_t q = 0; q < queue.size(); ++q) {
      const size_t p = queue[q];
      JoiningStep step;
      step.patch = patches[p].name;
      // Bolt every seam between this patch and one already standing.
      for (size_t k = 0; k < seams.size(); ++k) {
        if (bolted[k]) continue;
        const auto a = index.find(seams[k].patches[0]), b = index.find(seams[k].patches[1]);
        if (a == index.end() || b == index.end()) continue;
        const size_t other = a->second == p ? b->second : b->second == p ? a->second : p;
        if (other == p || !standing[other]) continue;
        bool placed = false;  // `other` stands already (before p in this order)
        for (const JoiningStep& s : steps)
          if (s.patch == patches[other].name) placed = true;
        if (!placed) continue;
        bolted[k] = 1;
        step.seams.push_back(static_cast<int>(k));
      }
      steps.push_back(step);
      // Its neighbours next.
      for (const KitSeam& seam : seams) {
        const auto a = index.find(seam.patches[0]), b = index.find(seam.patches[1]);
        if (a == index.end() || b == index.end()) continue;
        for (const auto& [x, y] :
             {std::pair{a->second, b->second}, std::pair{b->second, a->second}})
          if (x == p && !standing[y]) {
            standing[y] = 1;
            queue.push_back(y);
          }
      }
    }
  }
  return steps;
}

std::string joining_svg(const std::vector<LayoutKitPatch>& patches,
                        const std::vector<KitSeam>& seams) {
  std::vector<Vec3> points;
  for (const KitSeam& seam : seams)
    for (const SeamBolt& b : seam.bolts) points.push_back(b.point);
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : points) centre += p;
  if (!points.empty()) centre /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) covariance += (p - centre) * (p - centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  const Vec3 ex = eigen.eigenvectors().col(2), ey = eigen.eigenvectors().col(1);
  const auto plan = [&](const Vec3& p) { return Vec2((p - centre).dot(ex), (p - centre).dot(ey)); };
  Vec2 lo(0, 0), hi(0, 0);
  for (const Vec3& p : points) lo = lo.cwiseMin(plan(p)), hi = hi.cwiseMax(plan(p));
  const double size = std::max(1e-9, (hi - lo).maxCoeff());
  const double margin = 0.1 * size, font = 0.03 * size;
  const std::vector<JoiningStep> steps = joining_order(patches, seams);
  size_t lines = 2 + steps.size();
  for (const JoiningStep& s : steps) lines += s.seams.size();
  const double width = hi.x() - lo.x() + 2 * margin;
  const double drawing = hi.y() - lo.y() + 2 * margin;
  const double height = drawing + 1.5 * font * static_cast<double>(lines);
  const auto X = [&](const Vec2& p) { return p.x() - lo.x() + margin; };
  const auto Y = [&](const Vec2& p) { return hi.y() - p.y() + margin; };
  char buffer[512];
  std::string out;
  std::snprintf(buffer, sizeof buffer,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 %.6g %.6g\" "
                "font-family=\"sans-serif\">\n<rect width=\"100%%\" height=\"100%%\" "
                "fill=\"white\"/>\n",
                width, height);
  out += buffer;
  // Seams: a line through the bolts, a dot per bolt, the patches and count at the middle.
  std::map<std::string, std::pair<Vec2, int>> patch_middle;
  for (const KitSeam& seam : seams) {
    if (seam.bolts.empty()) continue;
    out += "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"" +
           std::to_string(0.004 * size) + "\" points=\"";
    for (const SeamBolt& b : seam.bolts) {
      std::snprintf(buffer, sizeof buffer, "%.6g,%.6g ", X(plan(b.point)), Y(plan(b.point)));
      out += buffer;
    }
    out += "\"/>\n";
    for (const SeamBolt& b : seam.bolts) {
      std::snprintf(buffer, sizeof buffer, "<circle cx=\"%.6g\" cy=\"%.6g\" r=\"%.4g\"/>\n",
                    X(plan(b.point)), Y(plan(b.point)), 0.005 * size);
      out += buffer;
    }
    const Vec2 middle = plan(seam.bolts[seam.bolts.size() / 2].point);
    std::snprintf(buffer, sizeof buffer,
                  "<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.4g\" fill=\"#993300\">%s | %s: "
                  "%zu bolts</text>\n",
                  X(middle), Y(middle) - 0.3 * font, 0.7 * font, seam.patches[0].c_str(),
                  seam.patches[1].c_str(), seam.bolts.size());
    out += buffer;
    for (const std::string& p : seam.patches) {
      patch_middle[p].first += middle;
      patch_middle[p].second += 1;
    }
  }
  for (const auto& [name, sum] : patch_middle) {
    const Vec2 at = sum.first / std::max(1, sum.second);
    std::snprintf(buffer, sizeof buffer,
                  "<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.4g\" text-anchor=\"middle\" "
                  "fill=\"#003399\">%s</text>\n",
                  X(at), Y(at) + 1.2 * font, font, name.c_str());
    out += buffer;
  }
  // The order of work.
  double y = drawing + font;
  const auto line = [&](const std::string& text) {
    std::snprintf(buffer, sizeof buffer, "<text x=\"%.6g\" y=\"%.6g\" font-size=\"%.4g\">", margin,
                  y, font);
    out += buffer + text + "</text>\n";
    y += 1.5 * font;
  };
  line("Order of work: deploy each patch on its own (its assembly sheet), then bolt its seams");
  int n = 0;
  for (const JoiningStep& step : steps) {
    line(std::to_string(++n) + ". Deploy " + step.patch + ".");
    for (int k : step.seams) {
      const KitSeam& seam = seams[k];
      line("    Bolt seam " + seam.patches[0] + " | " + seam.patches[1] + " (corners " +
           std::to_string(seam.corners[0]) + "-" + std::to_string(seam.corners[1]) +
           "): " + std::to_string(seam.bolts.size()) + " bolts through both boundary lamellas.");
    }
  }
  out += "</svg>\n";
  return out;
}

}  // namespace gridshell
