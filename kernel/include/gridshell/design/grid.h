// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the grid: members as exact geodesics on the surface patch and straight segments in
// the planar patch, and all their crossings (paper Sections 4.1, 4.4, 4.5).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

#include "gridshell/design/distance_map.h"
#include "gridshell/design/members.h"
#include "gridshell/design/patch.h"
#include "gridshell/design/planar_patch.h"
#include "gridshell/foundation/progress.h"
#include "gridshell/geodesic/geodesic.h"

namespace gridshell {

/// One lamella: a member of family G or H, on both patches.
struct Member {
  Family family = Family::G;
  int index = 0;  ///< 0 and n+1 are the boundary members, 1..n the inner ones, by u_start
  bool boundary = false;
  double u_start = 0;  ///< parameter on the family's first boundary (identical on both patches)
  double u_end = 0;    ///< parameter on the second boundary
  std::vector<SurfacePoint> surface_path;  ///< exact shortest geodesic on the patch, start first
  std::vector<Vec3> surface;               ///< its positions
  std::array<Vec2, 2> planar{};            ///< straight segment in the plane, start first
  double length = 0;                       ///< surface polyline length
  double planar_length = 0;
};

/// Where member g (family G) crosses member h (family H), on both patches.
struct Crossing {
  int g = 0, h = 0;  ///< member indices in their families
  Vec3 surface_point = Vec3::Zero();
  Vec2 planar_point = Vec2::Zero();
  double s_g = 0, s_bar_g = 0;  ///< arc length along g on the surface / in the plane
  double s_h = 0, s_bar_h = 0;
  bool on_boundary = false;  ///< one of the two members is a boundary member
  /// Notch lengths l = s - s̄ (paper 4.5): the connection may slide by l along the member, in the
  /// direction of the sign. Zero on boundary crossings (criterion ii).
  double notch_g() const { return on_boundary ? 0.0 : s_g - s_bar_g; }
  double notch_h() const { return on_boundary ? 0.0 : s_h - s_bar_h; }
};

struct Grid {
  std::vector<Member> g;  ///< g.front() is boundary c0-c3 (u=0), g.back() boundary c1-c2 (u=1)
  std::vector<Member> h;  ///< h.front() is boundary c1-c0 (v=0), h.back() boundary c2-c3 (v=1)
  std::vector<Crossing> crossings;  ///< every g with every h, sorted by (g, h)
  /// Inner members whose end was not within the piece of the opposite boundary their first,
  /// goal-pruned solve covered, so that they took a complete solve too (GridOptions::goal_pruning).
  /// Not part of the design's value.
  int complete_member_solves = 0;
};

struct GridOptions {
  /// Each inner member's end parameter u_end is refined on the exact distances (not the sampled
  /// map) until surface and planar lengths agree to this relative tolerance (criterion i).
  double length_tolerance = 1e-10;
  int threads = 0;  // 0 = hardware concurrency; the result does not depend on it
  /// Each inner member's solve is first exact only near its expected end (SolveOptions::goal,
  /// about a third of a complete solve's work); false: complete solves only. Both give the same
  /// members up to rounding (tests/design/test_grid.cpp); kept for that comparison.
  bool goal_pruning = true;
  /// Member solves run at once only while their estimated memory (twice the largest solve of
  /// their family so far; before the first, 22 KB per patch vertex) fits in this many bytes next
  /// to the ones in flight; one always runs. The windows a member's exact solve keeps for its
  /// path are most of a large design's memory: at 59k vertices 80 MB for one family and up to
  /// 0.65 GB for the other, two at once peaked at 1.4 GB. 0 = no limit. Does not change the
  /// result. Default 768 MiB.
  std::size_t member_memory = std::size_t{768} << 20;
};

/// Inner members already built on one patch with one solver, for redesigns that meet the same
/// member again: the family whose count did not change when the other's did, or an angle
/// visited before. An inner member is a function of its family, its positions u1, u2, the planar
/// corners and the length tolerance only (on a given patch and solver), so a member found here
/// is, bit for bit, the one build_grid would compute. Bounded in bytes (oldest out first);
/// thread-safe.
class MemberMemo {
 public:
  explicit MemberMemo(std::size_t max_bytes) : max_bytes_(max_bytes) {}
  /// The bit patterns of everything an inner member depends on.
  struct Key {
    std::array<std::uint64_t, 12> bits{};
    int family = 0;
    auto operator<=>(const Key&) const = default;
  };
  static Key key(Family family, const MemberPosition& position, const PlanarPatch& planar,
                 double length_tolerance, bool goal_pruning);
  std::optional<Member> find(const Key& key) const;
  void insert(const Key& key, const Member& member);
  std::size_t max_bytes() const { return max_bytes_; }
  std::size_t bytes() const;
  std::size_t size() const;
  std::uint64_t hits() const;  ///< members found so far
  /// Heap bytes of a member's polylines (what the memo counts).
  static std::size_t member_bytes(const Member& member);

 private:
  const std::size_t max_bytes_;
  mutable std::mutex mutex_;
  std::map<Key, Member> members_;
  std::deque<Key> order_;  // oldest first
  std::size_t bytes_ = 0;
  mutable std::uint64_t hits_ = 0;
};

/// Builds both member families (boundary members + the placed inner members) and all crossings.
/// Throws Infeasible if criterion (iii) fails: a g and an h do not cross exactly once on either
/// patch, or two members of one family cross in the plane. With `memo` (kept with the patch by
/// the daemon's cache), inner members found there are reused and the new ones added: the same
/// grid either way.
Grid build_grid(const Patch& patch, const GeodesicSolver& solver, const PlanarPatch& planar,
                const std::vector<MemberPosition>& g_members,
                const std::vector<MemberPosition>& h_members, const GridOptions& options = {},
                const Progress& progress = {}, MemberMemo* memo = nullptr);

}  // namespace gridshell
