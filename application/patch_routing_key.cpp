// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/application/patch_routing_key.h"

#include <openssl/evp.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

#include "gridshell/application/requests.h"

namespace gridshell {
namespace {

static_assert(std::endian::native == std::endian::little, "the key's bytes are little-endian");

/// The key's byte string (layout in the header).
class Bytes {
 public:
  void u8(std::uint8_t v) { data_.push_back(v); }
  void u32(std::uint32_t v) { append(&v, sizeof v); }
  void f64(double v) { append(&v, sizeof v); }
  void text(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    append(s.data(), s.size());
  }
  void append(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    data_.insert(data_.end(), b, b + n);
  }
  const std::vector<std::uint8_t>& data() const { return data_; }

 private:
  std::vector<std::uint8_t> data_;
};

}  // namespace

std::string patch_routing_key(const TriangleMesh& mesh, const CornerSpec& corners,
                              const DesignOptions& options) {
  Bytes b;
  const std::string magic = "gridshell-patch-key-v1\n";
  b.append(magic.data(), magic.size());
  b.u32(static_cast<std::uint32_t>(mesh.vertex_count()));
  for (const Vec3& p : mesh.vertices())
    for (int k = 0; k < 3; ++k) b.f64(p[k]);
  b.u32(static_cast<std::uint32_t>(mesh.face_count()));
  for (const Face& f : mesh.faces())
    for (int v : f) b.u32(static_cast<std::uint32_t>(v));
  switch (corners.kind) {
    case CornerSpec::Kind::Auto:
      b.u8(0);
      break;
    case CornerSpec::Kind::Vertices:
      b.u8(1);
      for (int v : corners.vertices) b.u32(static_cast<std::uint32_t>(v));
      break;
    case CornerSpec::Kind::Points:
      b.u8(2);
      for (const Vec3& p : corners.points)
        for (int k = 0; k < 3; ++k) b.f64(p[k]);
      break;
  }
  const TargetPatchOptions& patch = options.patch;
  b.text(to_string(patch.geodesic.method));
  b.f64(patch.coverability.eta_max);
  b.u32(static_cast<std::uint32_t>(patch.coverability.max_smoothing_iterations));
  b.u8(patch.smooth ? 1 : 0);
  b.u32(static_cast<std::uint32_t>(options.maps.resolution));

  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(b.data().data(), b.data().size(), digest, &length, EVP_sha256(), nullptr) != 1 ||
      length < 16)
    throw std::runtime_error("SHA-256 failed");
  static const char* hex = "0123456789abcdef";
  std::string key;
  for (int i = 0; i < 16; ++i) {
    key += hex[digest[i] >> 4];
    key += hex[digest[i] & 15];
  }
  return key;
}

std::string patch_routing_key(const v1::DesignRequest& request) {
  const DesignInputs in = prepare_design(request);
  return patch_routing_key(in.mesh, in.corners, in.options);
}

}  // namespace gridshell
