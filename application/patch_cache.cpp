// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/patch_cache.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <vector>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

/// Two independent 64-bit streams (splitmix64 finalizer over the words, different seeds): 128
/// bits, so two different patches collide with probability ~2^-128 per pair.
class Hasher {
 public:
  void word(std::uint64_t w) {
    a_ = mix(a_ ^ w) + 0x9E3779B97F4A7C15ull;
    b_ = mix(b_ + w * 0xC2B2AE3D27D4EB4Full) ^ 0x165667B19E3779F9ull;
  }
  void number(double x) {
    std::uint64_t w;
    std::memcpy(&w, &x, sizeof w);
    word(w);
  }
  void integer(long long x) { word(static_cast<std::uint64_t>(x)); }
  std::uint64_t a() const { return mix(a_); }
  std::uint64_t b() const { return mix(b_); }

 private:
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::uint64_t a_ = 0x243F6A8885A308D3ull, b_ = 0x13198A2E03707344ull;
};

}  // namespace

namespace {

void hash_mesh(Hasher& h, const TriangleMesh& mesh) {
  h.integer(mesh.vertex_count());
  for (const Vec3& p : mesh.vertices())
    for (int k = 0; k < 3; ++k) h.number(p[k]);
  h.integer(mesh.face_count());
  for (const Face& f : mesh.faces())
    for (int v : f) h.integer(v);
}

/// The options every patch's work depends on (not those of the automatic corners' search).
void hash_patch_options(Hasher& h, const DesignOptions& options) {
  const TargetPatchOptions& patch = options.patch;
  h.integer(static_cast<int>(patch.geodesic.method));
  h.number(patch.cut.snap_fraction);
  h.number(patch.coverability.eta_max);
  h.integer(patch.coverability.max_smoothing_iterations);
  h.number(patch.coverability.smoothing_step);
  h.integer(patch.coverability.member_distance_samples);
  h.integer(patch.smooth);
  h.integer(options.maps.resolution);
}

PatchKey finish(const Hasher& h, const TriangleMesh& mesh) {
  PatchKey key;
  key.hash[0] = h.a();
  key.hash[1] = h.b();
  key.vertices = mesh.vertex_count();
  key.faces = mesh.face_count();
  return key;
}

}  // namespace

PatchKey patch_key(const TriangleMesh& mesh, const CornerSpec& corners,
                   const DesignOptions& options) {
  Hasher h;
  hash_mesh(h, mesh);
  h.integer(static_cast<int>(corners.kind));  // only the kind's own fields are set
  if (corners.kind == CornerSpec::Kind::Vertices)
    for (int v : corners.vertices) h.integer(v);
  if (corners.kind == CornerSpec::Kind::Points)
    for (const Vec3& p : corners.points)
      for (int k = 0; k < 3; ++k) h.number(p[k]);
  const TargetPatchOptions& patch = options.patch;
  hash_patch_options(h, options);
  if (corners.kind == CornerSpec::Kind::Auto) {  // the search checks the planar angle too
    h.number(patch.auto_corners.min_corner_angle);
    h.number(patch.auto_corners.max_corner_angle);
    h.integer(patch.auto_corners.max_cuts);
    h.integer(patch.auto_corners.max_evaluations);
    h.number(options.cladding.k_min);
    h.number(options.cladding.k_max);
    h.number(options.cladding.min_planar_angle);
  }
  h.integer(options.maps.max_vertices);
  h.integer(patch.coverability.max_vertices);
  return finish(h, mesh);
}

PatchKey layout_patch_key(const TriangleMesh& mesh, const PatchLayout& layout, int patch,
                          const DesignOptions& options) {
  Hasher h;
  h.word(0x4C41594F5554ull);  // "LAYOUT": never a single patch's key
  hash_mesh(h, mesh);
  h.integer(static_cast<long long>(layout.corners.size()));
  for (const LayoutCorner& c : layout.corners) {
    h.integer(c.vertex);
    if (c.vertex < 0)
      for (int k = 0; k < 3; ++k) h.number(c.point[k]);
  }
  h.integer(static_cast<long long>(layout.patches.size()));
  for (size_t j = 0; j < layout.patches.size(); ++j) {
    const std::string name =
        layout.patches[j].name.empty() ? "P" + std::to_string(j + 1) : layout.patches[j].name;
    h.integer(static_cast<long long>(name.size()));
    for (char c : name) h.integer(static_cast<unsigned char>(c));
    for (int c : layout.patches[j].corners) h.integer(c);
  }
  h.integer(patch);
  hash_patch_options(h, options);
  // The layout's checks look for a feasible planar angle on the maps.
  h.number(options.cladding.k_min);
  h.number(options.cladding.k_max);
  h.number(options.cladding.min_planar_angle);
  h.integer(options.maps.max_vertices);
  h.integer(options.patch.coverability.max_vertices);
  return finish(h, mesh);
}

namespace {

/// Heap bytes of one allocation of `n` bytes: glibc's chunk (8 bytes of header, 16-byte
/// alignment, 32 at least). Tens of thousands of small vectors (a vertex's faces) make this
/// overhead a third of their size.
std::size_t heap(std::size_t n) {
  return n == 0 ? 0 : std::max<std::size_t>(32, (n + 8 + 15) & ~std::size_t{15});
}

template <class T>
std::size_t heap(const std::vector<T>& v) {
  return heap(v.capacity() * sizeof(T));
}

}  // namespace

std::size_t memory_bytes(const PatchWork& work) {
  const Patch& patch = work.target.patch;
  const TriangleMesh& mesh = patch.mesh;
  std::size_t bytes = heap(sizeof(PatchWork)) + 16;  // + the shared_ptr's control block
  bytes += heap(mesh.vertices()) + heap(mesh.faces());
  const MeshTopology& topology = mesh.topology();
  bytes += heap(sizeof(MeshTopology)) + 16;
  bytes += heap(topology.face_neighbors) + heap(topology.is_boundary_vertex);
  bytes += heap(topology.vertex_faces) + heap(topology.boundary_loops);
  for (const auto& faces : topology.vertex_faces) bytes += heap(faces);
  for (const auto& loop : topology.boundary_loops) bytes += heap(loop);
  for (const auto& side : patch.sides) bytes += heap(side);
  bytes += heap(patch.input_vertex);
  for (const DistanceMap* map : {&work.maps.g, &work.maps.h})
    bytes += heap(static_cast<std::size_t>(map->distances.size()) * sizeof(double));
  if (work.maps.copy) bytes += heap(sizeof(MapCopy)) + 16 + work.maps.copy->memory_bytes();
  bytes += 96 * work.target.stage_seconds.size();  // map nodes with their strings
  if (work.members) bytes += heap(sizeof(MemberMemo)) + work.members->max_bytes();  // its bound
  return bytes;
}

std::shared_ptr<MemberMemo> member_memo_for(const PatchWork& work) {
  const std::size_t maps =
      (work.maps.g.distances.size() + work.maps.h.distances.size()) * sizeof(double);
  return std::make_shared<MemberMemo>((2u << 20) + (memory_bytes(work) - maps) / 4);
}

PatchCache::PatchCache(std::size_t max_bytes) { stats_.max_bytes = max_bytes; }

std::shared_ptr<const PatchWork> PatchCache::get(const PatchKey& key,
                                                 const std::function<PatchWork()>& make, bool* hit,
                                                 const Progress& progress) {
  using Result = std::shared_ptr<const PatchWork>;
  for (;;) {
    std::promise<Result> promise;
    {
      std::unique_lock lock(mutex_);
      const auto it = index_.find(key);
      if (it != index_.end()) {
        lru_.splice(lru_.begin(), lru_, it->second);  // now the most recent
        ++stats_.hits;
        if (hit) *hit = true;
        return it->second->work;
      }
      const auto pending = computing_.find(key);
      if (pending != computing_.end()) {
        // Another request computes it: wait for its result (checking our own cancellation).
        const std::shared_future<Result> future = pending->second;
        lock.unlock();
        while (future.wait_for(std::chrono::milliseconds(20)) != std::future_status::ready)
          progress.check();
        try {
          Result work = future.get();
          std::lock_guard relock(mutex_);
          ++stats_.hits;
          if (hit) *hit = true;
          return work;
        } catch (const Cancelled&) {
          continue;  // that request was cancelled, not this one: compute it here
        }
      }
      ++stats_.misses;
      computing_.emplace(key, promise.get_future().share());
    }
    if (hit) *hit = false;
    Result work;
    try {
      work = std::make_shared<const PatchWork>(make());  // outside the lock: seconds of work
    } catch (...) {
      std::lock_guard lock(mutex_);
      computing_.erase(key);
      promise.set_exception(std::current_exception());
      throw;
    }
    const std::size_t bytes = memory_bytes(*work);
    std::lock_guard lock(mutex_);
    computing_.erase(key);
    promise.set_value(work);
    insert_locked(key, work, bytes);
    return work;
  }
}

void PatchCache::insert_locked(const PatchKey& key, std::shared_ptr<const PatchWork> work,
                               std::size_t bytes) {
  if (bytes > stats_.max_bytes || index_.count(key)) return;
  lru_.push_front({key, std::move(work), bytes});
  index_[key] = lru_.begin();
  stats_.bytes += bytes;
  while (stats_.bytes > stats_.max_bytes && !lru_.empty()) {
    const Entry& last = lru_.back();
    stats_.bytes -= last.bytes;
    index_.erase(last.key);
    lru_.pop_back();
    ++stats_.evictions;
  }
  stats_.entries = lru_.size();
}

void PatchCache::put(const PatchKey& key, std::shared_ptr<const PatchWork> work) {
  const std::size_t bytes = memory_bytes(*work);
  std::lock_guard lock(mutex_);
  insert_locked(key, std::move(work), bytes);
}

PatchCache::Stats PatchCache::stats() const {
  std::lock_guard lock(mutex_);
  Stats out = stats_;
  out.entries = lru_.size();
  return out;
}

}  // namespace gridshell
