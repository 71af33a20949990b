// SPDX-License-Identifier: GPL-3.0-or-later
// The daemon's cache of per-patch work (application/patch_cache.cpp): a cached redesign gives
// the bytes an uncached one gives, the key tells patches apart, the LRU bound holds, 0 turns it
// off, and concurrent requests for one patch are safe.
#include <gtest/gtest.h>
#include <malloc.h>

#if defined(__SANITIZE_ADDRESS__)
#define GRIDSHELL_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define GRIDSHELL_TEST_ASAN 1
#endif
#endif
#ifndef GRIDSHELL_TEST_ASAN
#define GRIDSHELL_TEST_ASAN 0
#endif
#if GRIDSHELL_TEST_ASAN
// The sanitizer runtime's allocator statistics (clang's sanitizer/allocator_interface.h; GCC
// ships the function in libasan but not that header).
extern "C" std::size_t __sanitizer_get_current_allocated_bytes();
#endif

#include <atomic>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "gridshell/application/files.h"
#include "gridshell/application/patch_cache.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"

namespace gridshell {
namespace {

v1::DesignRequest example_request(const std::string& name, int resolution = 40) {
  const ExampleSurface example = make_example(name);
  v1::DesignRequest request;
  *request.mutable_mesh() = to_proto(example.mesh, "example:" + name);
  for (int v : example.corners) request.mutable_corners()->add_vertices(v);
  request.mutable_options()->set_resolution(resolution);
  return request;
}

/// design.json of a design result (no timings in it: those are in report.json only).
std::string design_json(const v1::DesignResult& result) {
  return design_files(result).at("design.json");
}

RunSettings with_cache(PatchCache& cache) {
  RunSettings settings;
  settings.threads = 1;
  settings.patch_cache = &cache;
  return settings;
}

TEST(PatchCache, CachedRedesignIsByteIdenticalToAnUncachedOne) {
  PatchCache cache(256u << 20);
  v1::DesignRequest request = example_request("double-vault");
  const v1::DesignResult cold = run_design(request, {}, with_cache(cache));
  EXPECT_FALSE(cold.report().distance_maps_cached());
  EXPECT_EQ(design_json(cold), design_json(run_design(request, {}, {1})));
  EXPECT_GT(cold.report().stage_seconds().at("distance_maps"), 0);

  // ᾱ changed twice inside the feasible range, then the member counts: all from the cache.
  const double lo = cold.design().alpha_bar_range(0), hi = cold.design().alpha_bar_range(1);
  ASSERT_LT(lo, hi);
  for (double t : {0.3, 0.7}) {
    request.mutable_options()->set_alpha(std::to_string(lo + t * (hi - lo)));
    const v1::DesignResult warm = run_design(request, {}, with_cache(cache));
    EXPECT_TRUE(warm.report().distance_maps_cached()) << t;
    EXPECT_EQ(warm.report().stage_seconds().at("distance_maps"), 0);
    const v1::DesignResult fresh = run_design(request, {}, {1});
    EXPECT_FALSE(fresh.report().distance_maps_cached());
    EXPECT_EQ(design_json(warm), design_json(fresh)) << t;
    EXPECT_NE(design_json(warm), design_json(cold)) << "ᾱ did not change the design";
  }
  request.mutable_options()->set_alpha("min");
  request.mutable_options()->set_members_u(cold.report().members_g() - 1);
  request.mutable_options()->set_members_v(cold.report().members_h() + 1);
  const v1::DesignResult counts = run_design(request, {}, with_cache(cache));
  EXPECT_TRUE(counts.report().distance_maps_cached());
  EXPECT_EQ(counts.report().members_g(), cold.report().members_g() - 1);
  EXPECT_EQ(counts.report().members_h(), cold.report().members_h() + 1);
  EXPECT_EQ(design_json(counts), design_json(run_design(request, {}, {1})));
  // One family's count changed alone: the other family's members come from the patch's member
  // memo. Then an angle visited before: every member from it. The same bytes as fresh designs.
  const DesignInputs in = prepare_design(request);
  bool hit = false;
  const auto work = cache.get(
      patch_key(in.mesh, in.corners, in.options), [] { return PatchWork{}; }, &hit);
  ASSERT_TRUE(hit && work->members);
  std::uint64_t found = work->members->hits();
  request.mutable_options()->set_members_u(cold.report().members_g() - 2);  // g: new positions
  request.mutable_options()->set_members_v(0);  // h: automatic at ᾱ_min, as in the cold design
  const v1::DesignResult one = run_design(request, {}, with_cache(cache));
  EXPECT_GE(work->members->hits() - found, static_cast<std::uint64_t>(cold.report().members_h()))
      << "the h-members of the cold design (and g-members that earlier designs had too)";
  EXPECT_EQ(design_json(one), design_json(run_design(request, {}, {1})));
  found = work->members->hits();
  request.mutable_options()->set_members_u(0);
  request.mutable_options()->set_alpha(std::to_string(lo + 0.3 * (hi - lo)));
  const v1::DesignResult again = run_design(request, {}, with_cache(cache));
  EXPECT_EQ(work->members->hits() - found,
            static_cast<std::uint64_t>(again.report().members_g() + again.report().members_h()));
  EXPECT_EQ(design_json(again), design_json(run_design(request, {}, {1})));
  EXPECT_LE(work->members->bytes(), work->members->max_bytes());
  EXPECT_GT(work->members->size(), 0u);

  const PatchCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.misses, 1u);
  EXPECT_EQ(stats.hits, 6u);
  EXPECT_EQ(stats.entries, 1u);
  EXPECT_GT(stats.bytes, 0u);
}

TEST(PatchCache, OtherCornersMeshOrMapOptionsMiss) {
  PatchCache cache(256u << 20);
  const v1::DesignRequest base = example_request("sphere", 24);
  EXPECT_FALSE(run_design(base, {}, with_cache(cache)).report().distance_maps_cached());
  EXPECT_TRUE(run_design(base, {}, with_cache(cache)).report().distance_maps_cached());

  v1::DesignRequest corners = base;  // one corner one vertex further
  const ExampleSurface sphere = make_example("sphere");
  corners.mutable_corners()->set_vertices(2, sphere.corners[2] - 1);
  v1::DesignRequest mesh = base;  // one vertex moved by 1e-9 of the model size
  mesh.mutable_mesh()->set_positions(0, mesh.mesh().positions(0) + 1e-7);
  v1::DesignRequest resolution = base;
  resolution.mutable_options()->set_resolution(25);
  v1::DesignRequest eta = base;
  eta.mutable_options()->set_eta_max(1.01);  // default 1.0015
  for (const auto* request : {&corners, &mesh, &resolution, &eta}) {
    const v1::DesignResult result = run_design(*request, {}, with_cache(cache));
    EXPECT_FALSE(result.report().distance_maps_cached());
  }
  // And the keys themselves differ.
  auto key = [](const v1::DesignRequest& request) {
    const DesignInputs in = prepare_design(request);
    return patch_key(in.mesh, in.corners, in.options);
  };
  const PatchKey k = key(base);
  for (const auto* request : {&corners, &mesh, &resolution, &eta}) EXPECT_NE(key(*request), k);
  // Options the patch work does not depend on keep the key.
  v1::DesignRequest alpha = base;
  alpha.mutable_options()->set_alpha("max");
  alpha.mutable_options()->set_members_u(5);
  alpha.mutable_options()->set_interior_anchors(2);
  EXPECT_EQ(key(alpha), k);
  EXPECT_EQ(cache.stats().misses, 5u);
}

/// A PatchWork of about `mib` MiB (its distance maps), for the LRU tests.
PatchWork work_of(double mib) {
  PatchWork work;
  const int n = static_cast<int>(std::sqrt(mib * (1 << 20) / 16));
  work.maps.g.distances = Eigen::MatrixXd::Zero(n, n);
  work.maps.h.distances = Eigen::MatrixXd::Zero(n, n);
  return work;
}

PatchKey key_of(int id) {
  PatchKey key;
  key.hash[0] = static_cast<std::uint64_t>(id);
  return key;
}

TEST(PatchCache, EvictsTheLeastRecentlyUsedAndKeepsItsBound) {
  const std::size_t one = memory_bytes(work_of(1));
  ASSERT_GE(one, 1u << 20);
  PatchCache cache(3 * one + one / 2);  // room for three
  int made = 0;
  auto get = [&](int id) {
    bool hit = false;
    cache.get(
        key_of(id),
        [&] {
          ++made;
          return work_of(1);
        },
        &hit);
    EXPECT_LE(cache.stats().bytes, cache.stats().max_bytes);
    return hit;
  };
  EXPECT_FALSE(get(1));
  EXPECT_FALSE(get(2));
  EXPECT_FALSE(get(3));
  EXPECT_TRUE(get(1));   // 1 is now the most recent: 2 is the least
  EXPECT_FALSE(get(4));  // evicts 2
  EXPECT_EQ(cache.stats().evictions, 1u);
  EXPECT_EQ(cache.stats().entries, 3u);
  EXPECT_TRUE(get(1));
  EXPECT_TRUE(get(3));
  EXPECT_TRUE(get(4));
  EXPECT_FALSE(get(2));  // was evicted; now evicts 1 (used before 3 and 4)
  EXPECT_FALSE(get(1));
  EXPECT_EQ(made, 6);
  EXPECT_EQ(cache.stats().bytes, 3 * one);

  // An entry larger than the bound is returned but not kept, and evicts nothing.
  bool hit = true;
  const auto big = cache.get(
      key_of(9), [] { return work_of(8); }, &hit);
  EXPECT_FALSE(hit);
  EXPECT_GT(big->maps.g.distances.size(), 0);
  EXPECT_EQ(cache.stats().entries, 3u);
  EXPECT_LE(cache.stats().bytes, cache.stats().max_bytes);
}

TEST(PatchCache, ZeroBytesKeepsNothing) {
  PatchCache cache(0);
  int made = 0;
  for (int i = 0; i < 3; ++i) {
    bool hit = true;
    cache.get(
        key_of(1),
        [&] {
          ++made;
          return work_of(0.01);
        },
        &hit);
    EXPECT_FALSE(hit);
  }
  EXPECT_EQ(made, 3);
  EXPECT_EQ(cache.stats().entries, 0u);
  EXPECT_EQ(cache.stats().bytes, 0u);
  // And a real design through it reports no cache use.
  const v1::DesignRequest request = example_request("plane", 16);
  EXPECT_FALSE(run_design(request, {}, with_cache(cache)).report().distance_maps_cached());
  EXPECT_FALSE(run_design(request, {}, with_cache(cache)).report().distance_maps_cached());
}

TEST(PatchCache, ConcurrentGetsOfOneKeyAreConsistent) {
  PatchCache cache(64u << 20);
  std::atomic<int> made{0};
  constexpr int kThreads = 8;
  std::vector<std::shared_ptr<const PatchWork>> results(kThreads);
  std::vector<int> hits(kThreads, -1);
  {
    std::vector<std::jthread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([&, t] {
        bool hit = false;
        results[t] = cache.get(
            key_of(7),
            [&] {
              ++made;
              std::this_thread::sleep_for(std::chrono::milliseconds(50));
              PatchWork work = work_of(0.5);
              work.maps_seconds = 1.5;
              return work;
            },
            &hit);
        hits[t] = hit;
      });
  }
  EXPECT_EQ(made.load(), 1) << "one patch computed once";
  for (int t = 0; t < kThreads; ++t) {
    ASSERT_TRUE(results[t]);
    EXPECT_EQ(results[t], results[0]) << t;
    EXPECT_EQ(results[t]->maps_seconds, 1.5);
  }
  int misses = 0;
  for (int h : hits) misses += h == 0;
  EXPECT_EQ(misses, 1);
  const PatchCache::Stats stats = cache.stats();
  EXPECT_EQ(stats.entries, 1u);
  EXPECT_EQ(stats.bytes, memory_bytes(*results[0]));
}

TEST(PatchCache, AFailedComputationIsNotKeptAndReachesEveryWaiter) {
  PatchCache cache(64u << 20);
  std::atomic<int> made{0}, failures{0};
  {
    std::vector<std::jthread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&] {
        try {
          bool hit = false;
          cache.get(
              key_of(3),
              [&]() -> PatchWork {
                ++made;
                std::this_thread::sleep_for(std::chrono::milliseconds(30));
                throw std::runtime_error("no patch");
              },
              &hit);
        } catch (const std::runtime_error&) {
          ++failures;
        }
      });
  }
  EXPECT_EQ(failures.load(), 4);
  EXPECT_GE(made.load(), 1);
  EXPECT_EQ(cache.stats().entries, 0u);
  bool hit = true;
  cache.get(
      key_of(3), [] { return work_of(0.01); }, &hit);  // tried again, now it works
  EXPECT_FALSE(hit);
  EXPECT_EQ(cache.stats().entries, 1u);
}

/// Bytes the process has allocated from the heap (all arenas, mmap'ed blocks included). Under
/// AddressSanitizer malloc is ASan's and glibc's mallinfo2 reports 0: ask ASan's allocator.
std::size_t heap_bytes() {
#if GRIDSHELL_TEST_ASAN
  return __sanitizer_get_current_allocated_bytes();
#else
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
#endif
}

TEST(PatchCache, MemoryBytesMatchesWhatTheWorkReallyAllocates) {
  // Real patch work (waves-bump: the largest example patch), single-threaded so that no pool
  // thread's scratch memory is counted; one computation first, so that the kernel's reused
  // scratch buffers exist before the measurement.
  const ExampleSurface example = make_example("waves-bump");
  const CornerSpec corners = CornerSpec::at_vertices(example.corners);
  DesignOptions options;
  options.maps.threads = options.grid.threads = options.patch.coverability.threads = 1;
  auto make = [&](int resolution) {
    options.maps.resolution = resolution;
    return prepare_patch_work(make_target_patch(example.mesh, corners, options.patch), options);
  };
  (void)make(60);
  std::vector<std::unique_ptr<const PatchWork>> kept;
  std::size_t estimated = 0;
  const std::size_t before = heap_bytes();
  for (int resolution : {60, 100, 140}) {
    kept.push_back(std::make_unique<const PatchWork>(make(resolution)));
    estimated += memory_bytes(*kept.back());
  }
  const std::size_t measured = heap_bytes() - before;
  std::printf("patch work: memory_bytes %zu, heap growth %zu (%.2f)\n", estimated, measured,
              static_cast<double>(estimated) / measured);
  EXPECT_GE(estimated, 0.9 * measured) << "the cache would hold more than its bound";
  EXPECT_LE(estimated, 1.3 * measured) << "the cache would hold needlessly little";
}

}  // namespace
}  // namespace gridshell
