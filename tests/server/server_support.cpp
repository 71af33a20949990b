// SPDX-License-Identifier: GPL-3.0-or-later
#include "server_support.h"

#include <grpcpp/generic/generic_stub.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"

namespace gridshell::testing {

// A thread-safe in-memory log the daemon writes its JSON lines into.
struct TestDaemon::Log : std::streambuf {
  mutable std::mutex mutex;
  std::string text;
  std::ostream stream{this};
  int overflow(int c) override {
    if (c != EOF) {
      std::lock_guard lock(mutex);
      text += static_cast<char>(c);
    }
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    std::lock_guard lock(mutex);
    text.append(s, static_cast<size_t>(n));
    return n;
  }
};

server::DaemonOptions test_options(int workers, int queue) {
  server::DaemonOptions options;
  options.listen = "127.0.0.1:0";
  options.http = "127.0.0.1:0";
  options.workers = workers;
  options.queue = queue;
  options.shutdown_grace_seconds = 0;
  return options;
}

TestDaemon::TestDaemon(server::DaemonOptions options) : log_(std::make_shared<Log>()) {
  if (options.listen == "127.0.0.1:50051") options = test_options();  // never the real ports
  options.log = &log_->stream;
  daemon_ = std::make_unique<server::Daemon>(options);
  daemon_->start();
}

TestDaemon::~TestDaemon() { daemon_->shutdown(); }

std::string TestDaemon::grpc_address() const {
  return "127.0.0.1:" + std::to_string(daemon_->grpc_port());
}
std::string TestDaemon::http_address() const {
  return "127.0.0.1:" + std::to_string(daemon_->http_port());
}

std::shared_ptr<grpc::Channel> TestDaemon::channel(const std::string& ca_pem) const {
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(-1);
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (!ca_pem.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = ca_pem;
    credentials = grpc::SslCredentials(ssl);
  }
  return grpc::CreateCustomChannel(grpc_address(), credentials, arguments);
}

std::unique_ptr<v1::Gridshell::Stub> TestDaemon::stub(const std::string& ca_pem) const {
  return v1::Gridshell::NewStub(channel(ca_pem));
}

std::string TestDaemon::log() const {
  std::lock_guard lock(log_->mutex);
  return log_->text;
}

bool TestDaemon::wait_for(const std::function<bool(const server::JobQueue::Stats&)>& condition,
                          double seconds) const {
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::microseconds(static_cast<long long>(seconds * 1e6));
  while (std::chrono::steady_clock::now() < end) {
    if (condition(daemon_->stats())) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return condition(daemon_->stats());
}

v1::PatchRequest patch_request(const std::string& example) {
  const ExampleSurface surface = make_example(example);
  v1::PatchRequest request;
  *request.mutable_mesh() = to_proto(surface.mesh, "example:" + example);
  CornerSpec corners;
  corners.kind = CornerSpec::Kind::Vertices;
  corners.vertices = surface.corners;
  *request.mutable_corners() = to_proto(corners, "example");
  return request;
}

v1::DesignRequest design_request(const std::string& example, int resolution) {
  const v1::PatchRequest patch = patch_request(example);
  v1::DesignRequest request;
  *request.mutable_mesh() = patch.mesh();
  *request.mutable_corners() = patch.corners();
  if (resolution > 0) request.mutable_options()->set_resolution(resolution);
  return request;
}

namespace {

template <class Event, class Request>
CallResult<std::remove_cvref_t<decltype(std::declval<Event>().result())>> call(
    std::unique_ptr<grpc::ClientReader<Event>> (v1::Gridshell::Stub::*method)(grpc::ClientContext*,
                                                                              const Request&),
    v1::Gridshell::Stub& stub, const Request& request, grpc::ClientContext* context) {
  CallResult<std::remove_cvref_t<decltype(std::declval<Event>().result())>> out;
  grpc::ClientContext local;
  grpc::ClientContext& ctx = context ? *context : local;
  auto reader = (stub.*method)(&ctx, request);
  Event event;
  while (reader->Read(&event)) {
    if (event.has_progress()) out.progress.push_back(event.progress());
    if (event.has_result()) out.result = event.result();
  }
  out.status = reader->Finish();
  return out;
}

}  // namespace

CallResult<v1::PatchResult> call_patch(v1::Gridshell::Stub& stub, const v1::PatchRequest& request,
                                       grpc::ClientContext* context) {
  return call(&v1::Gridshell::Stub::Patch, stub, request, context);
}

CallResult<v1::DesignResult> call_design(v1::Gridshell::Stub& stub,
                                         const v1::DesignRequest& request,
                                         grpc::ClientContext* context) {
  return call(&v1::Gridshell::Stub::Design, stub, request, context);
}

CallResult<v1::SimulateResult> call_simulate(v1::Gridshell::Stub& stub,
                                             const v1::SimulateRequest& request,
                                             grpc::ClientContext* context) {
  return call(&v1::Gridshell::Stub::Simulate, stub, request, context);
}

CallResult<v1::RunResult> call_run(v1::Gridshell::Stub& stub, const v1::RunRequest& request,
                                   grpc::ClientContext* context) {
  return call(&v1::Gridshell::Stub::Run, stub, request, context);
}

CallResult<v1::GeodesicResult> call_geodesic(v1::Gridshell::Stub& stub,
                                             const v1::GeodesicRequest& request,
                                             grpc::ClientContext* context) {
  return call(&v1::Gridshell::Stub::Geodesic, stub, request, context);
}

namespace {

std::string bytes_of(const grpc::ByteBuffer& buffer) {
  std::vector<grpc::Slice> slices;
  std::string text;
  if (!buffer.Dump(&slices).ok()) return text;
  for (const grpc::Slice& s : slices)
    text.append(reinterpret_cast<const char*>(s.begin()), s.size());
  return text;
}

}  // namespace

RawReply raw_unary(const std::shared_ptr<grpc::Channel>& channel, const std::string& method,
                   const std::string& bytes, const std::string& authorization) {
  grpc::GenericStub generic(channel);
  grpc::Slice slice{bytes};
  grpc::ByteBuffer request(&slice, 1), response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  if (!authorization.empty()) context.AddMetadata("authorization", authorization);
  grpc::CompletionQueue queue;
  auto call = generic.PrepareUnaryCall(&context, method, request, &queue);
  call->StartCall();
  RawReply reply;
  call->Finish(&response, &reply.status, reinterpret_cast<void*>(1));
  void* tag;
  bool ok;
  if (!queue.Next(&tag, &ok)) throw std::runtime_error("raw_unary: the completion queue ended");
  if (reply.status.ok()) reply.messages.push_back(bytes_of(response));
  return reply;
}

RawReply raw_stream(const std::shared_ptr<grpc::Channel>& channel, const std::string& method,
                    const std::string& bytes, const std::string& authorization) {
  grpc::GenericStub generic(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  if (!authorization.empty()) context.AddMetadata("authorization", authorization);
  grpc::CompletionQueue queue;
  auto call = generic.PrepareCall(&context, method, &queue);
  void* tag;
  bool ok;
  // Every operation's tag comes back (with ok false when the call failed); Next() returns false
  // only once the queue is shut down, which nothing here does.
  const auto next = [&] {
    if (!queue.Next(&tag, &ok)) throw std::runtime_error("raw_stream: the completion queue ended");
    return ok;
  };
  call->StartCall(reinterpret_cast<void*>(1));
  next();
  grpc::Slice slice{bytes};
  grpc::ByteBuffer request(&slice, 1), response;
  call->WriteLast(request, grpc::WriteOptions(), reinterpret_cast<void*>(2));
  next();
  RawReply reply;
  for (int reads = 0; reads < 10000; ++reads) {  // the answers, then the end of the stream
    call->Read(&response, reinterpret_cast<void*>(3));
    if (!next()) break;
    reply.messages.push_back(bytes_of(response));
  }
  call->Finish(&reply.status, reinterpret_cast<void*>(4));
  next();
  return reply;
}

const v1::Design& small_design() {
  static const v1::Design design = run_design(design_request("plane", 16)).design();
  return design;
}

// HTTP ---------------------------------------------------------------------------------------

namespace {
namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;

template <class Stream>
HttpReply exchange(Stream& stream, const std::string& method, const std::string& target,
                   const std::string& body, const std::map<std::string, std::string>& headers,
                   int port) {
  http::request<http::string_body> request{http::string_to_verb(method), target, 11};
  request.set(http::field::host, "127.0.0.1:" + std::to_string(port));
  for (const auto& [name, value] : headers) request.set(name, value);
  request.body() = body;
  request.prepare_payload();
  http::write(stream, request);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.body_limit(std::numeric_limits<std::uint64_t>::max());
  if (method == "HEAD") parser.skip(true);
  http::read(stream, buffer, parser);
  HttpReply reply;
  const auto& response = parser.get();
  reply.status = response.result_int();
  for (const auto& field : response) {
    std::string name(field.name_string().data(), field.name_string().size());
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    reply.headers[name] = std::string(field.value().data(), field.value().size());
  }
  reply.body = response.body();
  return reply;
}

}  // namespace

HttpReply http_request(int port, const std::string& method, const std::string& target,
                       const std::string& body, const std::map<std::string, std::string>& headers,
                       const std::string& ca_pem) {
  net::io_context io;
  net::ip::tcp::endpoint endpoint(net::ip::make_address("127.0.0.1"),
                                  static_cast<unsigned short>(port));
  if (ca_pem.empty()) {
    beast::tcp_stream stream(io);
    stream.expires_after(std::chrono::seconds(120));
    stream.connect(endpoint);
    return exchange(stream, method, target, body, headers, port);
  }
  net::ssl::context tls(net::ssl::context::tls_client);
  tls.add_certificate_authority(net::buffer(ca_pem));
  tls.set_verify_mode(net::ssl::verify_peer);
  beast::ssl_stream<beast::tcp_stream> stream(io, tls);
  beast::get_lowest_layer(stream).expires_after(std::chrono::seconds(120));
  beast::get_lowest_layer(stream).connect(endpoint);
  stream.handshake(net::ssl::stream_base::client);
  return exchange(stream, method, target, body, headers, port);
}

// The bad-input set ----------------------------------------------------------------------------

namespace {

v1::Mesh mesh_of(const std::vector<double>& positions, const std::vector<int>& indices) {
  v1::Mesh mesh;
  mesh.set_name("bad.obj");
  for (double p : positions) mesh.add_positions(p);
  for (int i : indices) mesh.add_indices(i);
  return mesh;
}

// A 3x3-vertex square grid (8 triangles), the starting point of several bad meshes.
std::vector<double> grid_positions() {
  std::vector<double> p;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) p.insert(p.end(), {double(i), double(j), 0.0});
  return p;
}
std::vector<int> grid_indices() {
  std::vector<int> f;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const int a = j * 3 + i, b = a + 1, c = a + 3, d = a + 4;
      f.insert(f.end(), {a, b, d, a, d, c});
    }
  return f;
}

std::string patch_json(const v1::Mesh& mesh) {
  v1::PatchRequest request;
  *request.mutable_mesh() = mesh;
  return to_json(request, false);
}

/// Adds bad inputs of one request type to `set`: each case edits a copy of `base` and is sent
/// to `method`.
template <class Request>
auto case_adder(std::vector<BadInput>& set, Request base, const char* method) {
  return [&set, base = std::move(base), method](
             std::string name, const std::function<void(Request&)>& edit, std::string expected) {
    Request request = base;
    edit(request);
    set.push_back({std::move(name), method, to_json(request, false), std::move(expected)});
  };
}

}  // namespace

std::vector<BadInput> bad_inputs() {
  std::vector<BadInput> set;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto mesh_case = [&](std::string name, v1::Mesh mesh, std::string expected) {
    set.push_back({std::move(name), "Patch", patch_json(mesh), std::move(expected)});
  };
  // Meshes (issue 2, item 3).
  mesh_case("EmptyMesh", mesh_of({}, {}), "mesh.positions: empty");
  mesh_case("NoFaces", mesh_of(grid_positions(), {}), "mesh.indices: empty");
  mesh_case("PositionsNotTriples", mesh_of({0, 0, 0, 1}, {0, 0, 0}),
            "mesh.positions: 4 numbers is not a multiple of 3");
  mesh_case("IndicesNotTriples", mesh_of(grid_positions(), {0, 1}),
            "mesh.indices: 2 numbers is not a multiple of 3");
  {
    auto p = grid_positions();
    p[7] = nan;
    mesh_case("NanCoordinate", mesh_of(p, grid_indices()), "mesh.positions[7]: NaN");
    p[7] = 0;
    p[12] = -inf;
    mesh_case("InfCoordinate", mesh_of(p, grid_indices()), "mesh.positions[12]: infinite");
  }
  {
    auto f = grid_indices();
    f[5] = 9;
    mesh_case("IndexOutOfRange", mesh_of(grid_positions(), f),
              "mesh.indices[5]: vertex index 9 is out of range");
    f[5] = -1;
    mesh_case("NegativeIndex", mesh_of(grid_positions(), f),
              "mesh.indices[5]: vertex index -1 is out of range");
  }
  {
    // Two more triangles on the grid's edge (0,1): an edge shared by three faces.
    auto p = grid_positions();
    p.insert(p.end(), {0.5, -1, 0.5, 0.5, -1, -0.5});
    auto f = grid_indices();
    f.insert(f.end(), {1, 0, 9, 0, 1, 10});
    mesh_case("NonManifoldEdge", mesh_of(p, f), "non-manifold edge");
  }
  {
    // Two squares touching at one corner (vertex 8 of the grid).
    auto p = grid_positions();
    p.insert(p.end(), {3, 2, 0, 3, 3, 0, 2, 3, 0});
    auto f = grid_indices();
    f.insert(f.end(), {8, 9, 10, 8, 10, 11});
    mesh_case("NonManifoldVertex", mesh_of(p, f), "non-manifold vertex");
  }
  // Closed surfaces, several boundary loops and separate pieces are valid targets since issue
  // 18 (the patch cut out of them must be a disk, an Infeasible check of the cut): not here.
  mesh_case("OnlyDegenerateFaces", mesh_of({0, 0, 0, 1, 0, 0, 2, 0, 0}, {0, 1, 2}), "degenerate");

  // Corners and options, on the plane example.
  const v1::DesignRequest base = design_request("plane", 16);
  const auto design_case = case_adder(set, base, "Design");
  design_case(
      "ThreeCorners", [](auto& r) { r.mutable_corners()->mutable_vertices()->RemoveLast(); },
      "corners.vertices: expected 4 vertex indices, got 3");
  design_case(
      "CornerOutOfRange", [](auto& r) { r.mutable_corners()->set_vertices(3, 999999); },
      "corners.vertices[3]: vertex index 999999 is out of range");
  design_case(
      "NegativeCorner", [](auto& r) { r.mutable_corners()->set_vertices(0, -4); },
      "corners.vertices[0]: vertex index -4 is out of range");
  design_case(
      "CoincidentCorners",
      [](auto& r) { r.mutable_corners()->set_vertices(1, r.corners().vertices(0)); }, "corners");
  design_case(
      "VerticesAndPoints", [](auto& r) { r.mutable_corners()->add_points(1); },
      "corners: give either vertices or points, not both");
  design_case(
      "ElevenPointNumbers",
      [](auto& r) {
        r.mutable_corners()->clear_vertices();
        for (int k = 0; k < 11; ++k) r.mutable_corners()->add_points(k);
      },
      "corners.points: expected 4 points (12 numbers x, y, z), got 11 numbers");
  design_case(
      "NanCornerPoint",
      [&](auto& r) {
        r.mutable_corners()->clear_vertices();
        for (int k = 0; k < 12; ++k) r.mutable_corners()->add_points(k == 4 ? nan : k);
      },
      "corners.points[4]: not a finite number");
  design_case(
      "EtaMaxBelowOne", [](auto& r) { r.mutable_options()->set_eta_max(0.5); },
      "options.eta_max: must be between 1 and 10");
  design_case(
      "EtaMaxNan", [&](auto& r) { r.mutable_options()->set_eta_max(nan); },
      "options.eta_max: must be between 1 and 10");
  design_case(
      "EtaMaxInfinite", [&](auto& r) { r.mutable_options()->set_eta_max(inf); },
      "options.eta_max: must be between 1 and 10");
  design_case(
      "EtaMaxHuge", [&](auto& r) { r.mutable_options()->set_eta_max(1e308); },
      "options.eta_max: must be between 1 and 10");
  design_case(
      "LongMeshName", [](auto& r) { r.mutable_mesh()->set_name(std::string(1025, 'n')); },
      "mesh.name: too long: 1025 bytes, at most 1024");
  design_case(
      "LongMeshWarning",
      [](auto& r) {
        r.mutable_mesh()->add_warnings("fine");
        r.mutable_mesh()->add_warnings(std::string(5000, 'w'));
      },
      "mesh.warnings[1]: too long: 5000 bytes");
  design_case(
      "ManyMeshWarnings",
      [](auto& r) {
        for (int k = 0; k < 1001; ++k) r.mutable_mesh()->add_warnings("w");
      },
      "mesh.warnings: too many entries: 1001, at most 1000");
  design_case(
      "HeatMethod", [](auto& r) { r.mutable_options()->set_geodesic_method("heat"); },
      "options.geodesic_method: expected one of fast, cgal, got 'heat'");
  design_case(
      "UnknownMethod", [](auto& r) { r.mutable_options()->set_geodesic_method("fastest"); },
      "options.geodesic_method: expected one of fast, cgal, got 'fastest'");
  design_case(
      "AlphaOutOfRange", [](auto& r) { r.mutable_options()->set_alpha("7"); },
      "options.alpha: the planar corner angle must be between 0 and pi");
  design_case(
      "AlphaNotANumber", [](auto& r) { r.mutable_options()->set_alpha("steep"); },
      "options.alpha: expected min, max");
  design_case(
      "NegativeMembers", [](auto& r) { r.mutable_options()->set_members_u(-1); },
      "options.members_u: must be between 1 and 1000 (or 0: automatic), got -1");
  design_case(
      "TooManyMembers", [](auto& r) { r.mutable_options()->set_members_v(5000); },
      "options.members_v: must be between 1 and 1000 (or 0: automatic)");
  design_case(
      "NegativeInteriorAnchors", [](auto& r) { r.mutable_options()->set_interior_anchors(-2); },
      "options.interior_anchors: must be between 0 and 100");
  design_case(
      "NegativeLamellaWidth", [](auto& r) { r.mutable_options()->set_lamella_width(-1); },
      "options.lamella_width: must be positive, in mesh units (or 0: 1% of the longest patch "
      "side)");
  design_case(
      "InfiniteLamellaWidth", [&](auto& r) { r.mutable_options()->set_lamella_width(inf); },
      "options.lamella_width: must be positive, in mesh units (or 0: 1% of the longest patch "
      "side)");
  design_case(
      "NanLamellaThickness", [&](auto& r) { r.mutable_options()->set_lamella_thickness(nan); },
      "options.lamella_thickness: must be positive, in mesh units (or 0: width / 10)");
  design_case(
      "LamellaWiderThanHalfThePatch", [](auto& r) { r.mutable_options()->set_lamella_width(1e4); },
      "options.lamella_width: 10000 is outside [1e-6, 0.5] x the longest patch side");
  design_case(
      "ResolutionTooSmall", [](auto& r) { r.mutable_options()->set_resolution(5); },
      "options.resolution: must be between 8 and 1000 (or 0: adaptive)");
  {
    v1::PatchRequest request = patch_request("plane");
    request.mutable_options()->set_max_smoothing_iterations(-3);
    set.push_back({"NegativeSmoothingIterations", "Patch", to_json(request, false),
                   "options.max_smoothing_iterations: must be between 0"});
  }

  // Simulate: options, and designs that are not what Design returns.
  v1::SimulateRequest simulate;
  *simulate.mutable_design() = small_design();
  simulate.mutable_options()->set_notches("on");
  const auto simulate_case = case_adder(set, simulate, "Simulate");
  simulate_case(
      "NoDesign", [](auto& r) { r.clear_design(); }, "design.");
  simulate_case(
      "NotchesSometimes", [](auto& r) { r.mutable_options()->set_notches("sometimes"); },
      "options.notches");
  simulate_case(
      "UnknownMaterial", [](auto& r) { r.mutable_options()->set_material("balsa"); },
      "options.material: expected one of lime-wood, birch-plywood");
  simulate_case(
      "NegativeYoungModulus", [](auto& r) { r.mutable_options()->set_young_modulus(-1e9); },
      "options.young_modulus");
  simulate_case(
      "NanFriction", [&](auto& r) { r.mutable_options()->set_friction_mu(nan); },
      "options.friction_mu");
  simulate_case(
      "TooManyEdgesPerInterval", [](auto& r) { r.mutable_options()->set_edges_per_interval(500); },
      "options.edges_per_interval");
  simulate_case(
      "NegativeIterationCap", [](auto& r) { r.mutable_options()->set_max_iterations(-5); },
      "options.max_iterations");
  simulate_case(
      "UnknownUnit", [](auto& r) { r.mutable_options()->set_unit("furlong"); }, "options.unit");
  simulate_case(
      "UnknownSolver", [](auto& r) { r.mutable_options()->set_solver("guess"); }, "options.solver");
  simulate_case(
      "UnknownInteriorAnchors", [](auto& r) { r.mutable_options()->set_interior_anchors("3"); },
      "options.interior_anchors: expected one of \"\", auto, got");
  simulate_case(
      "AnchorGoalWithoutAutomaticAnchors", [](auto& r) { r.mutable_options()->set_anchor_goal(1); },
      "options.anchor_goal: applies to interior_anchors auto only");
  simulate_case(
      "AnchorGoalOutOfRange",
      [](auto& r) {
        r.mutable_options()->set_interior_anchors("auto");
        r.mutable_options()->set_anchor_goal(std::nan(""));
      },
      "options.anchor_goal: must be between 0 and 100 %");
  simulate_case(
      "CrossingOutOfRange", [](auto& r) { r.mutable_design()->mutable_crossings(3)->set_h(999); },
      "design.crossings[3].h");
  simulate_case(
      "NoMembers", [](auto& r) { r.mutable_design()->clear_members(); }, "design.members");
  simulate_case(
      "NoPatch", [](auto& r) { r.mutable_design()->clear_patch(); }, "design.patch");
  simulate_case(
      "TextInSurfacePoint",
      [](auto& r) {
        auto* point = r.mutable_design()->mutable_members(2)->mutable_surface()->mutable_values(1);
        point->mutable_list_value()->mutable_values(0)->set_string_value("x");
      },
      "design.members[2].surface");

  // Geodesic: the mesh checks are shared; the source and the engines are its own.
  v1::GeodesicRequest geodesic;
  *geodesic.mutable_mesh() = base.mesh();
  const auto geodesic_case = case_adder(set, geodesic, "Geodesic");
  geodesic_case(
      "GeodesicSourceOutOfRange", [](auto& r) { r.set_source(1 << 20); },
      "source: vertex index 1048576 is out of range");
  geodesic_case(
      "GeodesicNegativeSource", [](auto& r) { r.set_source(-1); },
      "source: vertex index -1 is out of range");
  geodesic_case(
      "GeodesicUnknownMethod", [](auto& r) { r.set_method("fastest"); },
      "method: unknown geodesic method 'fastest'");
  geodesic_case(
      "GeodesicUnknownReference", [](auto& r) { r.set_compare("exact"); },
      "compare: unknown geodesic method 'exact'");
  geodesic_case(
      "GeodesicTooManyRepeats", [](auto& r) { r.set_repeat(100000); },
      "repeat: must be between 1 and 1000");
  geodesic_case(
      "GeodesicEmptyMesh", [](auto& r) { r.mutable_mesh()->clear_positions(); },
      "mesh.positions: empty");

  // Run: the design request inside, and the simulation options.
  v1::RunRequest run;
  *run.mutable_design() = base;
  const auto run_case = case_adder(set, run, "Run");
  run_case(
      "RunWithoutMesh", [](auto& r) { r.mutable_design()->clear_mesh(); },
      "design.mesh.positions: empty");
  run_case(
      "RunCornerOutOfRange",
      [](auto& r) { r.mutable_design()->mutable_corners()->set_vertices(1, -2); },
      "design.corners.vertices[1]: vertex index -2 is out of range");
  run_case(
      "RunNotchesSometimes", [](auto& r) { r.mutable_simulation()->set_notches("sometimes"); },
      "simulation.notches");
  run_case(
      "RunUnknownMaterial", [](auto& r) { r.mutable_simulation()->set_material("balsa"); },
      "simulation.material: expected one of lime-wood");
  return set;
}

// TLS -------------------------------------------------------------------------------------------

Certificate make_self_signed_certificate() {
  EVP_PKEY* key = EVP_EC_gen("P-256");
  if (!key) throw std::runtime_error("EVP_EC_gen failed");
  X509* cert = X509_new();
  X509_set_version(cert, 2);
  ASN1_INTEGER_set(X509_get_serialNumber(cert), 1);
  X509_gmtime_adj(X509_getm_notBefore(cert), -3600);
  X509_gmtime_adj(X509_getm_notAfter(cert), 24 * 3600);
  X509_set_pubkey(cert, key);
  X509_NAME* name = X509_get_subject_name(cert);
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC,
                             reinterpret_cast<const unsigned char*>("localhost"), -1, -1, 0);
  X509_set_issuer_name(cert, name);
  X509V3_CTX context;
  X509V3_set_ctx(&context, cert, cert, nullptr, nullptr, 0);
  for (const auto& [nid, value] : {std::pair{NID_subject_alt_name, "DNS:localhost,IP:127.0.0.1"},
                                   {NID_basic_constraints, "critical,CA:TRUE"},
                                   {NID_key_usage, "critical,digitalSignature,keyCertSign"}}) {
    X509_EXTENSION* extension = X509V3_EXT_conf_nid(nullptr, &context, nid, value);
    X509_add_ext(cert, extension, -1);
    X509_EXTENSION_free(extension);
  }
  X509_sign(cert, key, EVP_sha256());
  auto to_pem = [](auto write) {
    BIO* bio = BIO_new(BIO_s_mem());
    write(bio);
    char* data = nullptr;
    const long size = BIO_get_mem_data(bio, &data);
    std::string pem(data, static_cast<size_t>(size));
    BIO_free(bio);
    return pem;
  };
  Certificate out;
  out.cert_pem = to_pem([&](BIO* bio) { PEM_write_bio_X509(bio, cert); });
  out.key_pem = to_pem(
      [&](BIO* bio) { PEM_write_bio_PrivateKey(bio, key, nullptr, nullptr, 0, nullptr, nullptr); });
  X509_free(cert);
  EVP_PKEY_free(key);
  return out;
}

nlohmann::json deployment_without_timings(const std::string& text) {
  auto json = nlohmann::json::parse(text);
  for (const char* key : {"seconds", "seconds_without_notches", "seconds_with_notches"})
    json.erase(key);
  for (const char* run : {"with_notches", "without_notches"}) {
    if (!json.contains(run)) continue;
    json[run].erase("seconds");
    if (!json[run].contains("solver_profile")) continue;
    for (auto it = json[run]["solver_profile"].begin(); it != json[run]["solver_profile"].end();)
      it =
          it.key().rfind("seconds", 0) == 0 ? json[run]["solver_profile"].erase(it) : std::next(it);
  }
  return json;
}

}  // namespace gridshell::testing
