// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — the daemon's cache of per-patch design work: the target patch and its distance
// maps (PatchWork), which do not depend on alpha, the member counts, the lamella size or the
// anchors. With it, moving the alpha slider or changing member counts redesigns without the patch
// stage and the maps (issue 16; docs/decisions.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <future>
#include <list>
#include <map>
#include <memory>
#include <mutex>

#include "gridshell/design/design.h"
#include "gridshell/design/layout.h"

namespace gridshell {

/// What identifies a patch's work: a 128-bit hash of everything PatchWork depends on (the mesh
/// as loaded, the corners, the patch and map options), plus the mesh's counts.
struct PatchKey {
  std::uint64_t hash[2] = {0, 0};
  int vertices = 0;
  int faces = 0;
  auto operator<=>(const PatchKey&) const = default;
};

/// The key of a design on `mesh` with these corners and options (only the options PatchWork
/// depends on are hashed: geodesic engine, patch cut, coverability and smoothing, map resolution).
PatchKey patch_key(const TriangleMesh& mesh, const CornerSpec& corners,
                   const DesignOptions& options);

/// The key of patch `patch` (index) of a layout on `mesh`, cut with these options: its corners
/// (vertices as loaded, points) and its patches (names, "" as "P<k>"), the patch options and
/// those the layout's planar angle check uses. Never equal to a single patch's key.
PatchKey layout_patch_key(const TriangleMesh& mesh, const PatchLayout& layout, int patch,
                          const DesignOptions& options);

/// A member memo for work the cache keeps: room for the members of a few designs, 2 MiB (a
/// design's members are a few hundred KB on the examples) plus a quarter of the patch mesh's
/// bytes, since members grow with the mesh, not with the maps; counted with the entry.
std::shared_ptr<MemberMemo> member_memo_for(const PatchWork& work);

/// Bytes a PatchWork holds (the patch mesh with its topology, the maps, the reports, and the
/// bound of its member memo, which fills as designs on the patch are made): what the cache counts
/// against its bound.
std::size_t memory_bytes(const PatchWork& work);

/// A bounded least-recently-used cache of PatchWork, safe to use from many threads. A key is
/// computed once: requests for a key that is being computed wait for that result (a second tab on
/// the same patch, a slider moved before the first design ended) instead of computing it again.
class PatchCache {
 public:
  /// `max_bytes` 0 = the cache keeps nothing.
  explicit PatchCache(std::size_t max_bytes);

  /// The cached work for `key`, or the result of `make()` (then cached, evicting the least
  /// recently used entries while the total exceeds the bound; an entry larger than the bound is
  /// returned but not kept). `*hit` says which (true also when the work came from another
  /// request's computation). Exceptions of `make` pass through, to the waiters too, except
  /// Cancelled: a waiter whose computing request was cancelled computes the work itself. A
  /// waiter checks `progress` (throws Cancelled when its own request is cancelled).
  std::shared_ptr<const PatchWork> get(const PatchKey& key, const std::function<PatchWork()>& make,
                                       bool* hit, const Progress& progress = {});

  /// Keeps `work` for `key` (computed elsewhere: a layout's cut makes every patch's work at
  /// once), unless the key is kept already or the work alone exceeds the bound.
  void put(const PatchKey& key, std::shared_ptr<const PatchWork> work);

  struct Stats {
    std::size_t entries = 0;
    std::size_t bytes = 0;
    std::size_t max_bytes = 0;
    std::uint64_t hits = 0, misses = 0, evictions = 0;
  };
  Stats stats() const;

 private:
  struct Entry {
    PatchKey key;
    std::shared_ptr<const PatchWork> work;
    std::size_t bytes = 0;
  };
  void insert_locked(const PatchKey& key, std::shared_ptr<const PatchWork> work, std::size_t bytes);
  mutable std::mutex mutex_;
  std::list<Entry> lru_;  // most recent first
  std::map<PatchKey, std::list<Entry>::iterator> index_;
  std::map<PatchKey, std::shared_future<std::shared_ptr<const PatchWork>>> computing_;
  Stats stats_;
};

}  // namespace gridshell
