// SPDX-License-Identifier: GPL-3.0-or-later
// The patch routing key (application/include/gridshell/application/patch_routing_key.h): the
// documented byte layout hashed by an independent SHA-256 call gives the same key; the key ignores
// what a redesign changes and follows what changes the patch's cache entry; a design result carries
// it.
#include <gtest/gtest.h>
#include <openssl/sha.h>

#include <cstring>
#include <string>

#include "gridshell/application/patch_cache.h"
#include "gridshell/application/patch_routing_key.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"

namespace gridshell {
namespace {

v1::DesignRequest square_request() {
  // The 3 x 3 grid of docs/api.md.
  v1::DesignRequest request;
  v1::Mesh& mesh = *request.mutable_mesh();
  mesh.set_name("square.obj");
  for (double v : {0.0, 0.0,  0.0, 5.0, 0.0, 0.5,  10.0, 0.0, 0.0,  0.0, 5.0,  0.5,  5.0, 5.0,
                   1.5, 10.0, 5.0, 0.5, 0.0, 10.0, 0.0,  5.0, 10.0, 0.5, 10.0, 10.0, 0.0})
    mesh.add_positions(v);
  for (int i : {0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 3, 4, 7, 3, 7, 6, 4, 5, 8, 4, 8, 7})
    mesh.add_indices(i);
  for (int v : {0, 2, 8, 6}) request.mutable_corners()->add_vertices(v);
  request.mutable_options()->set_resolution(16);
  return request;
}

// The layout of docs/api.md written out by hand, hashed with OpenSSL's one-shot SHA256.
std::string documented_key(const v1::DesignRequest& request, int resolution) {
  std::string bytes = "gridshell-patch-key-v1\n";
  auto u32 = [&](std::uint32_t v) { bytes.append(reinterpret_cast<const char*>(&v), 4); };
  auto f64 = [&](double v) { bytes.append(reinterpret_cast<const char*>(&v), 8); };
  u32(request.mesh().positions_size() / 3);
  for (double p : request.mesh().positions()) f64(p);
  u32(request.mesh().indices_size() / 3);
  for (int i : request.mesh().indices()) u32(i);
  bytes += '\1';
  for (int v : request.corners().vertices()) u32(v);
  u32(4);
  bytes += "fast";
  f64(1.0015);
  u32(60);
  bytes += '\1';
  u32(resolution);
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), digest);
  std::string hex;
  for (int i = 0; i < 16; ++i) {
    char two[3];
    std::snprintf(two, sizeof two, "%02x", digest[i]);
    hex += two;
  }
  return hex;
}

TEST(PatchRoutingKey, IsTheDocumentedSha256) {
  const v1::DesignRequest request = square_request();
  const std::string key = patch_routing_key(request);
  EXPECT_EQ(key.size(), 32u);
  EXPECT_EQ(key.find_first_not_of("0123456789abcdef"), std::string::npos);
  EXPECT_EQ(key, documented_key(request, 16));
  v1::DesignRequest unset = request;
  unset.mutable_options()->clear_resolution();  // the default, 100
  EXPECT_EQ(patch_routing_key(unset), documented_key(unset, 100));
}

TEST(PatchRoutingKey, FollowsThePatchNotTheRedesign) {
  const v1::DesignRequest base = square_request();
  const std::string key = patch_routing_key(base);
  // What a redesign changes: the same key (the same cache entry).
  for (auto change : std::vector<void (*)(v1::DesignRequest&)>{
           [](v1::DesignRequest& r) { r.mutable_options()->set_alpha("max"); },
           [](v1::DesignRequest& r) { r.mutable_options()->set_members_u(5); },
           [](v1::DesignRequest& r) { r.mutable_options()->set_lamella_width(0.2); },
           [](v1::DesignRequest& r) { r.mutable_options()->set_interior_anchors(1); },
           [](v1::DesignRequest& r) { r.mutable_mesh()->set_name("other.obj"); },
       }) {
    v1::DesignRequest r = base;
    change(r);
    EXPECT_EQ(patch_routing_key(r), key);
  }
  // What changes the patch: another key.
  for (auto change : std::vector<void (*)(v1::DesignRequest&)>{
           [](v1::DesignRequest& r) { r.mutable_options()->set_resolution(17); },
           [](v1::DesignRequest& r) { r.mutable_options()->set_eta_max(1.01); },
           [](v1::DesignRequest& r) { r.mutable_options()->set_geodesic_method("cgal"); },
           [](v1::DesignRequest& r) { r.mutable_corners()->set_vertices(3, 7); },
           [](v1::DesignRequest& r) { r.mutable_corners()->clear_vertices(); },
           [](v1::DesignRequest& r) { r.mutable_mesh()->set_positions(14, 1.5000001); },
       }) {
    v1::DesignRequest r = base;
    change(r);
    EXPECT_NE(patch_routing_key(r), key);
  }
}

TEST(PatchRoutingKey, AnExampleByNameAndByItsArraysShareAKeyAndTheResultCarriesIt) {
  // The web page sends an example by name and computes the key from the arrays Load returned.
  v1::DesignRequest by_name;
  by_name.mutable_mesh()->set_example("double-vault");
  by_name.mutable_options()->set_resolution(16);
  by_name.mutable_options()->set_members_u(3);
  by_name.mutable_options()->set_members_v(3);
  const ExampleSurface example = make_example("double-vault");
  for (int v : example.corners) by_name.mutable_corners()->add_vertices(v);
  v1::DesignRequest by_arrays = by_name;
  *by_arrays.mutable_mesh() = to_proto(example.mesh, "example:double-vault");
  EXPECT_EQ(patch_routing_key(by_name), patch_routing_key(by_arrays));
  const v1::DesignResult result = run_design(by_name, {}, {1});
  EXPECT_EQ(result.report().patch_key(), patch_routing_key(by_arrays));
}

}  // namespace
}  // namespace gridshell
