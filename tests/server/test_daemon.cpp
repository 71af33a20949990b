// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld over gRPC, in-process on ephemeral loopback ports: results identical to in-process
// runs, concurrency, cancellation and deadlines, the bounded queue, status codes for every bad
// input, health checking, reflection, the log line and shutdown.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <thread>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "server_support.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::TestDaemon;

// How fast cancellation stops the kernel is a speed, measured by `gridshell bench service`
// (docs/benchmarks.md), not asserted here: these tests check that the work stops before it
// completes, that the daemon says why, and that it keeps serving.

// A request that runs for seconds on one core: long enough to cancel in the middle.
v1::DesignRequest long_request() { return testing::design_request("waves-bump"); }

/// Runs a design call on its own thread; cancels it on request. The stages of the progress
/// events that came back are kept, and waits are on those events (a condition variable), not on
/// time; the waits' limits only keep a broken daemon from hanging the test.
class BackgroundCall {
 public:
  BackgroundCall(v1::Gridshell::Stub& stub, v1::DesignRequest request,
                 std::chrono::milliseconds deadline = std::chrono::milliseconds(0)) {
    if (deadline.count() > 0) context_.set_deadline(std::chrono::system_clock::now() + deadline);
    thread_ = std::thread([this, &stub, request = std::move(request)] {
      auto reader = stub.Design(&context_, request);
      v1::DesignEvent event;
      while (reader->Read(&event)) {
        std::lock_guard lock(mutex_);
        if (event.has_progress() && (stages_.empty() || stages_.back() != event.progress().stage()))
          stages_.push_back(event.progress().stage());
        if (event.has_result()) got_result_ = true;
        changed_.notify_all();
      }
      const grpc::Status status = reader->Finish();
      std::lock_guard lock(mutex_);
      status_ = status;
      done_ = true;
      changed_.notify_all();
    });
  }
  ~BackgroundCall() {
    context_.TryCancel();
    thread_.join();
  }
  /// Waits until the kernel reports progress of its own (the job runs on a worker).
  bool wait_working() {
    return wait([this] {
      return std::any_of(stages_.begin(), stages_.end(),
                         [](const auto& s) { return s != "queued"; });
    });
  }
  /// Waits until a progress event of `stage` came back; false if the call ended without one.
  bool wait_stage(const std::string& stage) {
    return wait([&] { return std::find(stages_.begin(), stages_.end(), stage) != stages_.end(); });
  }
  /// Waits until the design reached stage `k` of `order` (the stages of a whole run, in
  /// order): an event of it or of a later stage came back. The daemon coalesces progress
  /// events (only the latest waits for the stream), so a short stage's event may be overtaken
  /// by the next one's. Returns the stage reached, "" if the call ended before.
  std::string wait_reached(const std::vector<std::string>& order, size_t k) {
    std::string reached;
    wait([&] {
      int position = -1;
      for (const std::string& stage : stages_)
        for (size_t j = std::max(position, 0); j < order.size(); ++j)
          if (order[j] == stage) {
            position = static_cast<int>(j);
            break;
          }
      if (position >= 0 && static_cast<size_t>(position) >= k) reached = order[position];
      return !reached.empty();
    });
    return reached;
  }
  void cancel() { context_.TryCancel(); }
  grpc::Status finish() {
    thread_.join();
    thread_ = std::thread([] {});
    return status_;
  }
  bool got_result() const {
    std::lock_guard lock(mutex_);
    return got_result_;
  }
  bool done() const {
    std::lock_guard lock(mutex_);
    return done_;
  }

 private:
  template <class Ready>
  bool wait(Ready ready) {
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, std::chrono::seconds(120), [&] { return ready() || done_; });
    return ready();
  }
  grpc::ClientContext context_;
  std::thread thread_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<std::string> stages_;  // of the progress events, in the order they came, once each
  bool done_ = false, got_result_ = false;
  grpc::Status status_;
};

TEST(Daemon, RemoteDesignIsByteIdenticalToInProcess) {
  TestDaemon daemon;
  const v1::DesignRequest request = testing::design_request("double-vault");
  const FileBundle local = design_files(run_design(request, {}, {1}));
  const auto remote = testing::call_design(*daemon.stub(), request);
  ASSERT_TRUE(remote.status.ok()) << remote.status.error_message();
  ASSERT_TRUE(remote.result);
  const FileBundle files = design_files(*remote.result);
  for (const char* name : {"design.json", "planar.svg", "spatial.obj", "maps.svg"}) {
    ASSERT_TRUE(files.count(name)) << name;
    EXPECT_EQ(files.at(name), local.at(name)) << name;
  }
  EXPECT_FALSE(remote.progress.empty());
  // report.json: same numbers except the timings and the process's memory.
  auto report = nlohmann::json::parse(files.at("report.json"));
  auto local_report = nlohmann::json::parse(local.at("report.json"));
  for (const char* key :
       {"seconds", "t_smooth", "t_grid", "stage_seconds", "cpu_seconds", "peak_memory_bytes"})
    report.erase(key), local_report.erase(key);
  EXPECT_EQ(report, local_report);
}

// Geodesic over gRPC: the same distances, bit for bit, and the same report except the timings;
// compared with CGAL on the daemon's side too.
TEST(Daemon, RemoteGeodesicEqualsInProcess) {
  TestDaemon daemon;
  v1::GeodesicRequest request;
  *request.mutable_mesh() = testing::design_request("double-vault").mesh();
  request.set_source(17);
  request.set_compare("cgal");
  request.set_distances(true);
  const v1::GeodesicResult local = run_geodesic(request);
  const auto remote = testing::call_geodesic(*daemon.stub(), request);
  ASSERT_TRUE(remote.status.ok()) << remote.status.error_message();
  ASSERT_TRUE(remote.result);
  ASSERT_EQ(remote.result->distances_size(), local.distances_size());
  ASSERT_EQ(local.distances_size(), local.report().vertices());
  for (int v = 0; v < local.distances_size(); ++v)
    EXPECT_EQ(remote.result->distances(v), local.distances(v)) << v;
  EXPECT_EQ(local.distances(17), 0.0);
  v1::GeodesicReport a = remote.result->report(), b = local.report();
  for (v1::GeodesicReport* r : {&a, &b}) {
    r->clear_ms_per_source();
    r->clear_reference_ms_per_source();
    r->clear_speedup();
  }
  EXPECT_EQ(to_json(a, false), to_json(b, false));
  EXPECT_EQ(a.reference(), "cgal");
  EXPECT_LE(a.max_rel_diff(), 1e-9);
  // Without `distances` only the report comes back.
  request.set_distances(false);
  const auto brief = testing::call_geodesic(*daemon.stub(), request);
  ASSERT_TRUE(brief.result);
  EXPECT_EQ(brief.result->distances_size(), 0);
}

TEST(Daemon, RemotePatchIsIdenticalToInProcess) {
  TestDaemon daemon;
  const v1::PatchRequest request = testing::patch_request("sphere");
  const FileBundle local = patch_files(run_patch(request));
  const auto remote = testing::call_patch(*daemon.stub(), request);
  ASSERT_TRUE(remote.status.ok()) << remote.status.error_message();
  const FileBundle files = patch_files(*remote.result);
  EXPECT_EQ(files.at("patch.obj"), local.at("patch.obj"));
  auto report = nlohmann::json::parse(files.at("patch.json"));
  auto local_report = nlohmann::json::parse(local.at("patch.json"));
  for (const char* key : {"seconds", "stage_seconds"}) report.erase(key), local_report.erase(key);
  EXPECT_EQ(report, local_report);
}

// Progress is forwarded at most every progress_interval_ms within a stage: with an interval
// longer than the whole request each stage sends its first event (and at most one more, at
// fraction 1); with 0 every event the kernel reports is offered to the stream.
TEST(Daemon, ProgressEventsAreThrottledPerStage) {
  const v1::DesignRequest request = testing::design_request("double-vault", 32);
  auto events = [&](int interval_ms) {
    server::DaemonOptions options = testing::test_options(1);
    options.progress_interval_ms = interval_ms;
    TestDaemon daemon(options);
    auto remote = testing::call_design(*daemon.stub(), request);
    EXPECT_TRUE(remote.status.ok()) << remote.status.error_message();
    return remote.progress;
  };
  const std::vector<v1::Progress> slow = events(60000), all = events(0);
  ASSERT_FALSE(slow.empty());
  std::set<std::string> stages;
  int run = 0;
  for (size_t i = 0; i < slow.size(); ++i) {
    stages.insert(slow[i].stage());
    run = i > 0 && slow[i].stage() == slow[i - 1].stage() ? run + 1 : 1;
    EXPECT_LE(run, 2) << slow[i].stage() << " at event " << i;
    if (run == 2) {
      EXPECT_GE(slow[i].fraction(), 1.0) << slow[i].stage();
    }
  }
  EXPECT_GE(stages.size(), 4u);  // queued, patch, distance maps, ... all still reported
  EXPECT_GT(all.size(), 2 * slow.size());
}

TEST(Daemon, EightConcurrentClientsAllGetCorrectResults) {
  TestDaemon daemon(testing::test_options(2, 8));
  const v1::DesignRequest request = testing::design_request("double-vault", 32);
  const std::string expected = design_files(run_design(request, {}, {1})).at("design.json");
  std::vector<std::thread> clients;
  std::vector<grpc::Status> statuses(8);
  std::vector<std::string> designs(8);
  for (int c = 0; c < 8; ++c)
    clients.emplace_back([&, c] {
      auto stub = daemon.stub();  // a channel per client, as separate processes would have
      const auto result = testing::call_design(*stub, request);
      statuses[c] = result.status;
      if (result.result) designs[c] = design_files(*result.result).at("design.json");
    });
  for (auto& client : clients) client.join();
  for (int c = 0; c < 8; ++c) {
    EXPECT_TRUE(statuses[c].ok()) << c << ": " << statuses[c].error_message();
    EXPECT_EQ(designs[c], expected) << c;
  }
  const auto stats = daemon.daemon().stats();
  EXPECT_EQ(stats.succeeded, 8u);
  EXPECT_EQ(stats.rejected, 0u);
}

TEST(Daemon, CancelledRequestStopsWorkAndTheDaemonKeepsServing) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  {
    BackgroundCall call(*stub, long_request());
    ASSERT_TRUE(call.wait_stage("distance maps"));
    call.cancel();
    EXPECT_EQ(call.finish().error_code(), grpc::StatusCode::CANCELLED);
    EXPECT_FALSE(call.got_result());
  }
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.cancelled == 1 && s.running == 0; }));
  const auto stats = daemon.daemon().stats();
  EXPECT_EQ(stats.succeeded, 0u);                 // the work stopped before completion
  ASSERT_EQ(stats.cancel_latency_ms.size(), 1u);  // a running job was stopped
  std::printf("cancellation latency (server): %.1f ms\n", stats.cancel_latency_ms[0]);
  EXPECT_NE(daemon.log().find("\"status\":\"CANCELLED\""), std::string::npos) << daemon.log();
  EXPECT_TRUE(testing::call_patch(*stub, testing::patch_request("plane")).status.ok());
}

TEST(Daemon, DeadlineStopsWorkAndTheDaemonKeepsServing) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  {
    // waves-bump at a map resolution of 400 takes several seconds: the deadline is passed in
    // the middle of its distance maps.
    v1::DesignRequest request = long_request();
    request.mutable_options()->set_resolution(400);
    BackgroundCall call(*stub, request, std::chrono::milliseconds(700));
    EXPECT_EQ(call.finish().error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  }
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.cancelled == 1 && s.running == 0; }));
  const auto stats = daemon.daemon().stats();
  EXPECT_EQ(stats.succeeded, 0u);
  ASSERT_EQ(stats.cancel_latency_ms.size(), 1u);
  std::printf("deadline stop latency (server): %.1f ms\n", stats.cancel_latency_ms[0]);
  EXPECT_NE(daemon.log().find("\"status\":\"DEADLINE_EXCEEDED\""), std::string::npos);
  EXPECT_TRUE(testing::call_patch(*stub, testing::patch_request("plane")).status.ok());
}

// Cancels a design in each of its stages, at the first progress event of that stage (or of a
// later one, where the daemon's coalescing let that overtake it): the kernel polls its flag in
// every stage, so each cancel stops a running job (the daemon records a stop), with CANCELLED
// and no result. The stop latencies are printed; `gridshell bench service` measures them.
TEST(Daemon, CancellationStopsEveryStage) {
  server::DaemonOptions options = testing::test_options(1, 4);
  options.cache_mib = 0;  // every call does the whole work, the patch stages included
  TestDaemon daemon(options);
  auto stub = daemon.stub();
  v1::DesignRequest request = testing::design_request("archway");
  request.mutable_options()->set_resolution(300);  // every stage lasts a while
  // The stages this design reports, in order (a run to its end).
  std::vector<std::string> stages;
  for (const v1::Progress& p : testing::call_design(*stub, request).progress)
    if (p.stage() != "queued" && (stages.empty() || stages.back() != p.stage()))
      stages.push_back(p.stage());
  ASSERT_GE(stages.size(), 4u);
  size_t stopped = 0, finished = 0;
  for (size_t k = 0; k < stages.size(); ++k) {
    const std::string& stage = stages[k];
    SCOPED_TRACE(stage);
    BackgroundCall call(*stub, request);
    const std::string reached = call.wait_reached(stages, k);  // "": it ended first
    call.cancel();
    const grpc::Status status = call.finish();
    ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.running == 0; }));
    const auto latencies = daemon.daemon().stats().cancel_latency_ms;
    if (latencies.size() == stopped) {  // the design ended first: only in its last stage
      EXPECT_EQ(k, stages.size() - 1);  // (its result may still be lost to the cancel)
      ++finished;
      continue;
    }
    ++stopped;
    ASSERT_EQ(latencies.size(), stopped);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::CANCELLED);
    EXPECT_FALSE(call.got_result());
    std::printf("cancelled in %-24s stopped in %.1f ms\n", (reached + ":").c_str(),
                latencies.back());
  }
  EXPECT_GE(stopped, stages.size() - 1);
  // The first, uncancelled run, and a run whose cancel came as it ended.
  EXPECT_EQ(daemon.daemon().stats().succeeded, 1u + finished);
}

TEST(Daemon, FullQueueAnswersResourceExhaustedAtOnce) {
  TestDaemon daemon(testing::test_options(1, 1));
  auto stub = daemon.stub();
  BackgroundCall running(*stub, long_request());
  ASSERT_TRUE(running.wait_working());
  BackgroundCall waiting(*stub, long_request());
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.running == 1 && s.queued == 1; }));
  const auto refused = testing::call_design(*stub, long_request());
  EXPECT_EQ(refused.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(refused.status.error_message().find("queue is full"), std::string::npos);
  // At once: the answer came while the first job was still running, not after it.
  EXPECT_FALSE(running.done());
  EXPECT_EQ(daemon.daemon().stats().succeeded, 0u);
  // Light requests have a lane of their own: Examples is answered, over gRPC and HTTP, while
  // the design queue is full (it was refused with 429 before issue 33).
  {
    grpc::ClientContext context;
    auto reader = stub->Examples(&context, v1::ExamplesRequest());
    v1::ExamplesEvent event, last;
    while (reader->Read(&event)) last = event;
    EXPECT_TRUE(reader->Finish().ok());
    EXPECT_GT(last.result().examples_size(), 0);
    const auto reply = testing::http_request(daemon.http_port(), "POST", "/v1/examples", "{}");
    EXPECT_EQ(reply.status, 200) << reply.body;
  }
  EXPECT_FALSE(running.done());
  EXPECT_EQ(daemon.daemon().stats().succeeded, 2u);  // the two Examples calls
  // The waiting job is cancelled without ever running.
  waiting.cancel();
  EXPECT_EQ(waiting.finish().error_code(), grpc::StatusCode::CANCELLED);
  running.cancel();
  EXPECT_EQ(running.finish().error_code(), grpc::StatusCode::CANCELLED);
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.running == 0 && s.cancelled == 2; }));
  EXPECT_EQ(daemon.daemon().stats().cancel_latency_ms.size(), 1u);  // only one had started
  EXPECT_EQ(daemon.daemon().stats().rejected, 1u);
}

TEST(Daemon, EveryBadInputIsInvalidArgumentWithItsMessage) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  for (const testing::BadInput& bad : testing::bad_inputs()) {
    SCOPED_TRACE(bad.name);
    grpc::Status status;
    if (bad.method == "Patch") {
      v1::PatchRequest request;
      ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(bad.json, &request).ok());
      status = testing::call_patch(*stub, request).status;
    } else if (bad.method == "Design") {
      v1::DesignRequest request;
      ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(bad.json, &request).ok());
      status = testing::call_design(*stub, request).status;
    } else if (bad.method == "Simulate") {
      v1::SimulateRequest request;
      ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(bad.json, &request).ok());
      status = testing::call_simulate(*stub, request).status;
    } else if (bad.method == "Geodesic") {
      v1::GeodesicRequest request;
      ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(bad.json, &request).ok());
      status = testing::call_geodesic(*stub, request).status;
    } else {
      ASSERT_EQ(bad.method, "Run");
      v1::RunRequest request;
      ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(bad.json, &request).ok());
      status = testing::call_run(*stub, request).status;
    }
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_NE(status.error_message().find(bad.expected), std::string::npos)
        << "'" << bad.expected << "' not in: " << status.error_message();
  }
  // Still serving, and every failure was counted as one.
  EXPECT_TRUE(testing::call_design(*stub, testing::design_request("plane", 16)).status.ok());
  const auto stats = daemon.daemon().stats();
  EXPECT_EQ(stats.failed, testing::bad_inputs().size());
  EXPECT_EQ(stats.succeeded, 1u);
}

// Random but well-formed requests (arbitrary corners, holes punched into meshes, collapsed
// vertices, options anywhere in their ranges): whatever the kernel makes of them, the answer is
// a status of the caller's making (OK, INVALID_ARGUMENT, FAILED_PRECONDITION), never INTERNAL
// and never a crash.
TEST(Daemon, RandomRequestsNeverCrashOrFailInternally) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  std::mt19937 random(20261201);
  auto uniform = [&](int n) { return static_cast<int>(random() % static_cast<unsigned>(n)); };
  std::map<grpc::StatusCode, int> outcomes;
  for (int i = 0; i < 40; ++i) {
    const char* examples[] = {"plane", "hypar", "sphere", "cone"};
    v1::DesignRequest request = testing::design_request(examples[uniform(4)], 12);
    v1::Mesh& mesh = *request.mutable_mesh();
    const int vertices = mesh.positions_size() / 3;
    switch (uniform(4)) {
      case 0:  // holes and pieces
        for (int k = uniform(12) + 1; k > 0; --k) {
          const int f = uniform(mesh.indices_size() / 3);
          mesh.mutable_indices()->erase(mesh.indices().begin() + 3 * f,
                                        mesh.indices().begin() + 3 * f + 3);
        }
        break;
      case 1:  // collapsed vertices
        for (int k = 0; k < 10; ++k) {
          const int a = uniform(vertices), b = uniform(vertices);
          for (int c = 0; c < 3; ++c) mesh.set_positions(3 * a + c, mesh.positions(3 * b + c));
        }
        break;
      default:
        break;
    }
    v1::Corners& corners = *request.mutable_corners();
    if (uniform(2)) {
      for (int c = 0; c < 4; ++c) corners.set_vertices(c, uniform(vertices));
    } else if (uniform(2)) {
      corners.clear_vertices();
      for (int k = 0; k < 12; ++k) corners.add_points(uniform(160) - 80.0);
    }
    auto& options = *request.mutable_options();
    if (uniform(3) == 0)
      options.set_alpha(std::vector<std::string>{"max", "1.0", "45deg"}[uniform(3)]);
    if (uniform(3) == 0) options.set_members_u(uniform(15));
    if (uniform(3) == 0) options.set_lamella_width(std::vector<double>{0.01, 5, 500}[uniform(3)]);
    const grpc::Status status = testing::call_design(*stub, request).status;
    ++outcomes[status.error_code()];
    EXPECT_TRUE(status.error_code() == grpc::StatusCode::OK ||
                status.error_code() == grpc::StatusCode::INVALID_ARGUMENT ||
                status.error_code() == grpc::StatusCode::FAILED_PRECONDITION)
        << i << ": " << status.error_code() << " " << status.error_message();
  }
  for (const auto& [code, count] : outcomes) std::printf("status %d: %d\n", code, count);
  EXPECT_TRUE(testing::call_patch(*stub, testing::patch_request("plane")).status.ok());
}

TEST(Daemon, InfeasibleDesignIsFailedPrecondition) {
  TestDaemon daemon;
  v1::DesignRequest request = testing::design_request("plane", 16);
  request.mutable_corners()->clear_vertices();
  for (double p : {-40.0, -30.0, 0.0, 40.0, -30.0, 0.0, 0.0, -10.0, 0.0, -40.0, 30.0, 0.0})
    request.mutable_corners()->add_points(p);  // a dart: reflex corner at c2
  const auto result = testing::call_design(*daemon.stub(), request);
  EXPECT_EQ(result.status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(result.status.error_message().find("criterion iv"), std::string::npos)
      << result.status.error_message();
}

/// deployment.json without the fields that are wall-clock times.
v1::SimulateRequest simulate_request(const std::string& notches) {
  v1::SimulateRequest request;
  v1::DesignRequest design = testing::design_request("double-vault", 32);
  design.mutable_options()->set_members_u(7);
  design.mutable_options()->set_members_v(7);
  *request.mutable_design() = run_design(design).design();
  request.mutable_options()->set_notches(notches);
  request.mutable_options()->set_unit("cm");
  request.set_design_name("double-vault.json");
  return request;
}

TEST(Daemon, RemoteSimulateEqualsInProcess) {
  TestDaemon daemon;
  const v1::SimulateRequest request = simulate_request("both");
  const FileBundle local = simulate_files(run_simulate(request, {}, {1}));
  const auto remote = testing::call_simulate(*daemon.stub(), request);
  ASSERT_TRUE(remote.status.ok()) << remote.status.error_message();
  ASSERT_TRUE(remote.result);
  EXPECT_FALSE(remote.progress.empty());
  const FileBundle files = simulate_files(*remote.result);
  for (const char* name : {"deployed.obj", "deviation.ply", "deployed_without_notches.obj",
                           "deviation_without_notches.ply"}) {
    ASSERT_TRUE(files.count(name)) << name;
    EXPECT_EQ(files.at(name), local.at(name)) << name;  // results do not depend on threads
  }
  ASSERT_TRUE(files.count("deployment.json"));
  const auto deployment = testing::deployment_without_timings(files.at("deployment.json"));
  EXPECT_EQ(deployment, testing::deployment_without_timings(local.at("deployment.json")));
  EXPECT_TRUE(deployment["converged"].get<bool>());
  EXPECT_LT(deployment["rms_with_notches"].get<double>(),
            deployment["rms_without_notches"].get<double>());
  EXPECT_EQ(deployment["rods"].size(), 7u + 7u + 4u);
  EXPECT_NE(daemon.log().find("\"method\":\"Simulate\""), std::string::npos) << daemon.log();
}

TEST(Daemon, RemoteRunEqualsInProcessDesignThenSimulate) {
  TestDaemon daemon;
  v1::RunRequest request;
  *request.mutable_design() = testing::design_request("hypar", 16);
  request.mutable_simulation()->set_notches("on");
  const v1::RunResult local = run_run(request, {}, {1});
  const auto remote = testing::call_run(*daemon.stub(), request);
  ASSERT_TRUE(remote.status.ok()) << remote.status.error_message();
  ASSERT_TRUE(remote.result);
  // The run's design is the Design call's design; its simulation is Simulate on that design.
  const FileBundle design = design_files(remote.result->design());
  EXPECT_EQ(design.at("design.json"), design_files(local.design()).at("design.json"));
  EXPECT_EQ(design.at("design.json"), design_files(run_design(request.design())).at("design.json"));
  const FileBundle files = run_files(*remote.result);
  for (const char* name : {"design.json", "planar.svg", "deployed.obj", "deviation.ply"})
    EXPECT_TRUE(files.count(name)) << name;
  EXPECT_EQ(testing::deployment_without_timings(files.at("deployment.json")),
            testing::deployment_without_timings(run_files(local).at("deployment.json")));
  std::set<std::string> stages;
  for (const v1::Progress& p : remote.progress) stages.insert(p.stage());
  EXPECT_GE(stages.size(), 3u);  // patch/design stages and the simulation
}

TEST(Daemon, SimulateDeadlineStopsTheSolverAndTheDaemonKeepsServing) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  // A run that outlasts the deadline by far: rods eight times finer than the default (2.1 s
  // here; at the default this small grid now converges in ~0.4 s, the deadline itself).
  v1::SimulateRequest request = simulate_request("both");
  request.mutable_options()->set_edges_per_interval(16);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(400));
  EXPECT_EQ(testing::call_simulate(*stub, request, &context).status.error_code(),
            grpc::StatusCode::DEADLINE_EXCEEDED);
  ASSERT_TRUE(daemon.wait_for([](const auto& s) { return s.cancelled == 1 && s.running == 0; }));
  const auto stats = daemon.daemon().stats();
  EXPECT_EQ(stats.succeeded, 0u);
  ASSERT_EQ(stats.cancel_latency_ms.size(), 1u);
  std::printf("simulate deadline stop latency (server): %.1f ms\n", stats.cancel_latency_ms[0]);
  EXPECT_TRUE(testing::call_patch(*stub, testing::patch_request("plane")).status.ok());
}

TEST(Daemon, HealthCheckAndReflectionListTheService) {
  TestDaemon daemon;
  // grpc.health.v1.Health/Check {service: "gridshell.v1.Gridshell"}; reply {status: SERVING}.
  const std::string service = "gridshell.v1.Gridshell";
  const auto health =
      testing::raw_unary(daemon.channel(), "/grpc.health.v1.Health/Check",
                         std::string("\x0a", 1) + static_cast<char>(service.size()) + service);
  ASSERT_TRUE(health.status.ok()) << health.status.error_message();
  EXPECT_EQ(health.messages, std::vector<std::string>{std::string("\x08\x01", 2)});
  // grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo {list_services: ""}.
  const auto reflection = testing::raw_stream(
      daemon.channel(), "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
      std::string("\x3a\x00", 2));
  ASSERT_TRUE(reflection.status.ok()) << reflection.status.error_message();
  ASSERT_EQ(reflection.messages.size(), 1u);
  EXPECT_NE(reflection.messages[0].find("gridshell.v1.Gridshell"), std::string::npos);
  EXPECT_NE(reflection.messages[0].find("grpc.health.v1.Health"), std::string::npos);
}

TEST(Daemon, OneStructuredLogLinePerRequest) {
  TestDaemon daemon;
  auto stub = daemon.stub();
  ASSERT_TRUE(testing::call_design(*stub, testing::design_request("double-vault", 24)).status.ok());
  v1::PatchRequest bad = testing::patch_request("plane");
  bad.mutable_options()->set_eta_max(0);
  ASSERT_FALSE(testing::call_patch(*stub, bad).status.ok());
  std::vector<nlohmann::json> requests;
  std::istringstream lines(daemon.log());
  for (std::string line; std::getline(lines, line);) {
    const auto entry = nlohmann::json::parse(line);  // every line is JSON
    if (entry.contains("method")) requests.push_back(entry);
  }
  ASSERT_EQ(requests.size(), 2u) << daemon.log();
  const auto& design = requests[0];
  EXPECT_EQ(design["method"], "Design");
  EXPECT_EQ(design["status"], "OK");
  EXPECT_EQ(design["vertices"], 561);
  EXPECT_GT(design["faces"].get<int>(), 0);
  EXPECT_TRUE(design["id"].is_number());
  for (const char* stage : {"patch", "distance maps", "cladding", "grid"})
    EXPECT_TRUE(design["stages_ms"].contains(stage)) << stage << " in " << design.dump();
  EXPECT_EQ(requests[1]["status"], "INVALID_ARGUMENT");
  EXPECT_EQ(requests[1]["field"], "options.eta_max");
  EXPECT_NE(requests[1]["message"].get<std::string>().find("between 1 and 10"), std::string::npos);
}

TEST(Daemon, ShutdownLetsRunningWorkFinishAndRefusesNewCalls) {
  auto options = testing::test_options(1, 4);
  options.shutdown_grace_seconds = 60;
  TestDaemon daemon(options);
  auto stub = daemon.stub();
  BackgroundCall call(*stub, testing::design_request("double-vault", 32));
  ASSERT_TRUE(call.wait_working());
  std::thread stopper([&] { daemon.daemon().shutdown(); });
  ASSERT_TRUE(daemon.wait_for([&](const auto&) { return !daemon.daemon().serving(); }));
  EXPECT_TRUE(call.finish().ok());  // finished within the grace period
  EXPECT_TRUE(call.got_result());
  stopper.join();
  EXPECT_NE(daemon.log().find("\"event\":\"stopped\""), std::string::npos);
}

TEST(Daemon, ShutdownWithoutGraceCancelsRunningWork) {
  TestDaemon daemon(testing::test_options(1, 4));  // grace 0
  auto stub = daemon.stub();
  BackgroundCall call(*stub, long_request());
  ASSERT_TRUE(call.wait_working());
  daemon.daemon().shutdown();
  EXPECT_EQ(call.finish().error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(daemon.daemon().stats().cancel_latency_ms.size(), 1u);
}

}  // namespace
}  // namespace gridshell
