// SPDX-License-Identifier: GPL-3.0-or-later
// Replicated daemons behind a real haproxy (scripts/replicas.sh, deploy/haproxy/haproxy.cfg), all
// on free loopback ports: consistent hashing on the patch key (a key stays on its replica, a
// replica that goes away moves only its own keys), the warm cache hit through the proxy, and the
// fault test: 8 clients designing and a sweep running through the proxy while a replica is
// SIGKILLed and restarted, three times; every request ends with the right result, none hangs,
// none leaves a partial file.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "server_support.h"
#include "support.h"

extern char** environ;

namespace gridshell {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// The replicas and haproxy of one test, stopped by the destructor.
class Replicas {
 public:
  explicit Replicas(int n) : state_(testing::temp_dir() + "/replicas") {
    const std::string out = shell("start " + std::to_string(n) + " -- --workers 2");
    for (const std::string& line : lines(out)) {
      if (line.rfind("GRIDSHELL_PROXY_GRPC=", 0) == 0) grpc_ = line.substr(21);
      if (line.rfind("GRIDSHELL_PROXY_HTTP=", 0) == 0) http_ = line.substr(21);
    }
  }
  ~Replicas() { shell("stop"); }
  bool ok() const { return !grpc_.empty() && !http_.empty(); }
  const std::string& grpc() const { return grpc_; }
  int http_port() const { return std::stoi(http_.substr(http_.rfind(':') + 1)); }
  void kill(int i) { shell("kill " + std::to_string(i)); }
  /// Until haproxy's health checks mark replica i down.
  void wait_down(int i) { shell("wait-down " + std::to_string(i)); }
  void restart(int i) { shell("restart " + std::to_string(i)); }
  std::string log(int i) const {
    return testing::read_text(state_ + "/r" + std::to_string(i) + ".log");
  }
  /// Empties replica i's log (a restarted daemon appends to it).
  void clear_log(int i) const {
    std::ofstream(state_ + "/r" + std::to_string(i) + ".log", std::ios::trunc);
  }

  static std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) out.push_back(line);
    return out;
  }

 private:
  std::string shell(const std::string& arguments) const {
    const std::string out = state_ + ".out";
    const std::string command = "GRIDSHELL_REPLICAS_DIR='" + state_ + "' GRIDSHELLD='" +
                                GRIDSHELLD + "' bash '" + GRIDSHELL_SOURCE_DIR +
                                "/scripts/replicas.sh' " + arguments + " >'" + out + "' 2>&1";
    const int status = std::system(command.c_str());
    const std::string text = testing::read_text(out);
    EXPECT_EQ(status, 0) << arguments << ": " << text;
    return text;
  }
  std::string state_, grpc_, http_;
};

bool haproxy_missing() { return std::system("command -v haproxy >/dev/null 2>&1") != 0; }

#define REQUIRE_HAPROXY()                                                         \
  if (haproxy_missing()) {                                                        \
    if (std::getenv("GRIDSHELL_REQUIRE_CLUSTER")) FAIL() << "haproxy is missing"; \
    GTEST_SKIP() << "haproxy is not installed (scripts/setup.sh installs it)";    \
  }

/// The replica (haproxy's server name) that answers a request with this patch key, over HTTP.
std::string replica_for(int port, const std::string& key) {
  const auto reply =
      testing::http_request(port, "POST", "/v1/examples", "{}", {{"X-Gridshell-Patch-Key", key}});
  if (reply.status != 200) return "status " + std::to_string(reply.status);
  const auto it = reply.headers.find("x-gridshell-replica");
  return it == reply.headers.end() ? "?" : it->second;
}

std::map<std::string, std::string> mapping(int port, const std::vector<std::string>& keys) {
  std::map<std::string, std::string> m;
  for (const std::string& key : keys) m[key] = replica_for(port, key);
  return m;
}

/// Runs the gridshell CLI with `arguments`, stdout and stderr into files of `dir`; returns the
/// exit code, or -1 if it did not end within `seconds` (then it is killed: a hung request).
struct Outcome {
  int exit_code = -1;
  std::string err;
};
Outcome run_bounded(const std::vector<std::string>& arguments, const std::string& dir,
                    double seconds) {
  fs::create_directories(dir);
  std::vector<std::string> argv_strings{GRIDSHELL_CLI};
  argv_strings.insert(argv_strings.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, (dir + "/stdout").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, (dir + "/stderr").c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  Outcome outcome;
  if (rc != 0) return outcome;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(static_cast<long long>(seconds * 1000));
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) {
      outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      break;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      break;  // -1: hung
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  outcome.err = testing::read_text(dir + "/stderr");
  return outcome;
}

TEST(Replicas, AKeyStaysOnItsReplicaOnlyTheLostReplicasKeysMoveRedesignsFindTheCache) {
  REQUIRE_HAPROXY();
  Replicas replicas(3);
  ASSERT_TRUE(replicas.ok());
  std::vector<std::string> keys;
  for (int i = 0; i < 60; ++i) keys.push_back("key-" + std::to_string(i * 7919));
  const auto before = mapping(replicas.http_port(), keys);
  std::map<std::string, int> load;
  for (const auto& [key, replica] : before) ++load[replica];
  EXPECT_EQ(load.size(), 3u) << "every replica holds keys";
  for (const auto& [replica, count] : load) {
    EXPECT_TRUE(replica == "r1" || replica == "r2" || replica == "r3") << replica;
    EXPECT_GE(count, 8) << replica;  // 20 on average
  }
  EXPECT_EQ(mapping(replicas.http_port(), keys), before) << "the same key, another replica";
  // gRPC: the same replica as HTTP for the same key (both backends hash the same server ids).
  auto channel = grpc::CreateChannel(replicas.grpc(), grpc::InsecureChannelCredentials());
  auto stub = v1::Gridshell::NewStub(channel);
  for (int i = 0; i < 6; ++i) {
    grpc::ClientContext context;
    context.AddMetadata("x-gridshell-patch-key", keys[i]);
    auto reader = stub->Examples(&context, v1::ExamplesRequest());
    v1::ExamplesEvent event;
    while (reader->Read(&event)) {
    }
    ASSERT_TRUE(reader->Finish().ok());
    const auto& metadata = context.GetServerInitialMetadata();
    const auto it = metadata.find("x-gridshell-replica");
    ASSERT_NE(it, metadata.end());
    EXPECT_EQ(std::string(it->second.data(), it->second.size()), before.at(keys[i])) << keys[i];
  }

  replicas.kill(2);
  // haproxy notices within two failed checks (0.5 s apart); until then a request to r2's keys is
  // redispatched on every retry (option redispatch 1), a state in which a request's choice also
  // depends on the streams still open. The mapping is taken once haproxy has marked r2 down.
  replicas.wait_down(2);
  std::map<std::string, std::string> during;
  for (int attempt = 0; attempt < 100; ++attempt) {
    during = mapping(replicas.http_port(), keys);
    // Until then a request can also meet r2's dead pooled connection (502, which clients
    // retry): wait until every answer is an answer from r1 or r3.
    bool settled = true;
    for (const auto& [key, replica] : during)
      settled = settled && (replica == "r1" || replica == "r3");
    if (settled) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  int moved = 0;
  for (const std::string& key : keys) {
    if (before.at(key) == "r2") {
      EXPECT_TRUE(during.at(key) == "r1" || during.at(key) == "r3") << key << " " << during.at(key);
      ++moved;
    } else {
      // One answer off the ring can come from haproxy's bounded load (hash-balance-factor) if a
      // stream of the previous request is still counted: a key has moved only if it stays moved.
      for (int again = 0; again < 3 && during.at(key) != before.at(key); ++again) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        during[key] = replica_for(replicas.http_port(), key);
      }
      EXPECT_EQ(during.at(key), before.at(key)) << key << " moved though its replica is up";
    }
  }
  EXPECT_EQ(moved, load["r2"]);
  replicas.restart(2);
  std::map<std::string, std::string> after;
  for (int attempt = 0; attempt < 100; ++attempt) {
    after = mapping(replicas.http_port(), keys);
    if (after == before) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(after, before) << "r2's keys return to it";

  // Redesigns through the proxy find their patch cached: the key the daemon computed from the
  // request, the one the CLI sent (the same function), and the cache of the replica that key
  // leads to: cold first, warm after.
  const std::string dir = testing::temp_dir();
  std::string key;
  for (const char* alpha : {"min", "40deg", "45deg", "max"}) {
    const auto out =
        run_bounded({"design", "example:double-vault", "--resolution", "24", "--alpha", alpha,
                     "--server", replicas.grpc(), "--out", dir + "/" + alpha, "--quiet"},
                    dir + "/" + alpha, 120);
    ASSERT_EQ(out.exit_code, 0) << out.err;
    const json report = json::parse(testing::read_text(dir + "/" + alpha + "/report.json"));
    if (key.empty()) key = report["patch_key"];
    EXPECT_EQ(report["patch_key"], key);
    EXPECT_EQ(report["distance_maps_cached"].get<bool>(), std::string(alpha) != "min") << alpha;
  }
  EXPECT_EQ(key.size(), 32u);
}

TEST(Replicas, FaultTestAKilledReplicaLosesNoRequestAndNoRow) {
  REQUIRE_HAPROXY();
  const std::string dir = testing::temp_dir();
  // The designs: 8 patches (resolutions), so that their keys spread over the replicas. Their
  // reference files come from in-process runs.
  const int kClients = 8, kDesigns = 3;
  std::map<int, std::string> reference;
  for (int c = 0; c < kClients; ++c) {
    const int resolution = 16 + c;
    const std::string out = dir + "/reference/" + std::to_string(resolution);
    const auto r =
        run_bounded({"design", "example:double-vault", "--resolution", std::to_string(resolution),
                     "--members-u", "3", "--members-v", "3", "--out", out, "--quiet"},
                    out, 120);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    reference[resolution] = testing::read_text(out + "/design.json");
  }
  // The sweep's rows: small ones, their RMS compared with a local run of the same rows.
  std::string manifest = "id,mesh,alpha,resolution,members-u,members-v,edges-per-interval\n";
  for (int i = 0; i < 6; ++i)
    manifest += "s" + std::to_string(i) + ",example:double-vault," + std::to_string(32 + 3 * i) +
                "deg,16,3,3,1\n";
  const std::string manifest_path = testing::write_text(dir, "rows.csv", manifest);
  const auto local = run_bounded(
      {"sweep", manifest_path, "--out", dir + "/local-sweep", "--quiet", "--workers", "2"},
      dir + "/local-sweep-log", 300);
  ASSERT_EQ(local.exit_code, 0) << local.err;
  const json local_summary = json::parse(testing::read_text(dir + "/local-sweep/summary.json"));

  // One set of replicas for the three repetitions (each kills and restarts another replica).
  Replicas replicas(3);
  ASSERT_TRUE(replicas.ok());
  for (int repetition = 1; repetition <= 3; ++repetition) {
    SCOPED_TRACE("repetition " + std::to_string(repetition));
    const std::string base = dir + "/rep" + std::to_string(repetition);
    std::atomic<int> finished{0};
    std::mutex mutex;
    std::vector<std::string> failures;
    int hung = 0, corrupted = 0;
    std::vector<std::thread> clients;
    for (int c = 0; c < kClients; ++c)
      clients.emplace_back([&, c] {
        const int resolution = 16 + c;
        for (int k = 0; k < kDesigns; ++k) {
          const std::string out = base + "/c" + std::to_string(c) + "-" + std::to_string(k);
          const auto r = run_bounded(
              {"design", "example:double-vault", "--resolution", std::to_string(resolution),
               "--members-u", "3", "--members-v", "3", "--server", replicas.grpc(), "--out", out,
               "--quiet", "--timeout", "100"},
              out, 120);
          std::lock_guard lock(mutex);
          ++finished;
          if (r.exit_code == -1) {
            ++hung;
          } else if (r.exit_code != 0) {
            failures.push_back(out + ": exit " + std::to_string(r.exit_code) + ": " + r.err);
          } else if (testing::read_text(out + "/design.json") != reference[resolution]) {
            ++corrupted;
          }
          // No partial files: every file gridshell writes is whole (written under a temporary
          // name, then renamed); none of those temporary names may be left.
          for (const auto& entry : fs::directory_iterator(out))
            if (entry.path().filename().string().find(".tmp") != std::string::npos) ++corrupted;
        }
      });
    // The sweep's local engine pointed at the proxy, at the same time.
    Outcome sweep;
    std::thread sweeper([&] {
      sweep = run_bounded({"sweep", manifest_path, "--out", base + "/sweep", "--quiet", "--workers",
                           "2", "--server", replicas.grpc(), "--timeout", "100"},
                          base + "/sweep-log", 300);
    });
    // Mid-load: a third of the designs done, then one replica killed, and restarted once
    // haproxy has noticed (the requests meanwhile go to the others).
    for (int i = 0; i < 1200 && finished < kClients * kDesigns / 3; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const int victim = 1 + (repetition - 1) % 3;
    replicas.kill(victim);
    replicas.wait_down(victim);
    replicas.restart(victim);
    for (auto& t : clients) t.join();
    sweeper.join();
    EXPECT_EQ(hung, 0);
    EXPECT_EQ(corrupted, 0);
    EXPECT_TRUE(failures.empty()) << failures.size() << " requests failed, the first: "
                                  << (failures.empty() ? "" : failures[0]);
    // Every row of the sweep finished, with the RMS of the local run.
    ASSERT_EQ(sweep.exit_code, 0) << sweep.err;
    const json summary = json::parse(testing::read_text(base + "/sweep/summary.json"));
    ASSERT_EQ(summary.size(), local_summary.size());
    for (size_t i = 0; i < summary.size(); ++i) {
      EXPECT_EQ(summary[i]["status"], "ok") << summary[i];
      EXPECT_EQ(summary[i]["rms_with_notches"], local_summary[i]["rms_with_notches"]) << i;
      EXPECT_EQ(summary[i]["rms_without_notches"], local_summary[i]["rms_without_notches"]) << i;
    }
    // The victim really died mid-load and came back: its log has two starts.
    const std::string log = replicas.log(victim);
    size_t starts = 0;
    for (size_t at = log.find("\"listening\""); at != std::string::npos;
         at = log.find("\"listening\"", at + 1))
      ++starts;
    EXPECT_EQ(starts, 2u) << log;
    replicas.clear_log(victim);
  }
}

}  // namespace
}  // namespace gridshell
