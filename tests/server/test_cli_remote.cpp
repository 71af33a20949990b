// SPDX-License-Identifier: GPL-3.0-or-later
// The CLI as a client (`--server`) writes the same files as in-process runs; `gridshell health`;
// the gridshelld executable starts on ephemeral ports and shuts down cleanly on SIGTERM.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <thread>

#include "gridshell/example_surfaces.h"
#include "server_support.h"
#include "support.h"

namespace gridshell {
namespace {

using testing::read_text;
using testing::run_cli;
using testing::TestDaemon;

nlohmann::json without_timings(const std::string& text) {
  auto json = nlohmann::json::parse(text);
  for (const char* key :
       {"seconds", "t_smooth", "t_grid", "stage_seconds", "cpu_seconds", "peak_memory_bytes"})
    json.erase(key);
  return json;
}

TEST(CliRemote, DesignWritesByteIdenticalFiles) {
  TestDaemon daemon;
  const std::string local = testing::temp_dir(), remote = testing::temp_dir();
  const std::string args = "design example:double-vault --quiet --resolution 40 --members-u 9 ";
  auto result = run_cli(args + "--out '" + local + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  result = run_cli(args + "--server " + daemon.grpc_address() + " --out '" + remote + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("on " + daemon.grpc_address()), std::string::npos);
  for (const char* file : {"design.json", "planar.svg", "spatial.obj", "maps.svg"})
    EXPECT_EQ(read_text(remote + "/" + file), read_text(local + "/" + file)) << file;
  EXPECT_EQ(without_timings(read_text(remote + "/report.json")),
            without_timings(read_text(local + "/report.json")));
}

TEST(CliRemote, GeodesicGivesTheSameDistancesAndReport) {
  TestDaemon daemon;
  const std::string local = testing::temp_dir(), remote = testing::temp_dir();
  const std::string args = "geodesic example:waves --source 17 --compare cgal --json --distances ";
  auto result = run_cli(args + "'" + local + "/d.txt'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  auto local_report = nlohmann::json::parse(result.out);
  result = run_cli(args + "'" + remote + "/d.txt' --server " + daemon.grpc_address());
  ASSERT_EQ(result.exit_code, 0) << result.err;
  auto remote_report = nlohmann::json::parse(result.out);
  EXPECT_FALSE(read_text(local + "/d.txt").empty());
  EXPECT_EQ(read_text(remote + "/d.txt"), read_text(local + "/d.txt"));
  for (auto* r : {&local_report, &remote_report})
    for (const char* key : {"ms_per_source", "reference_ms_per_source", "speedup"}) r->erase(key);
  EXPECT_EQ(remote_report, local_report);
  EXPECT_EQ(remote_report["source"], 17);
  // A bad source is the CLI's own message, before any call.
  result = run_cli("geodesic example:waves --source -3 --server " + daemon.grpc_address());
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--source"), std::string::npos) << result.err;
}

TEST(CliRemote, SimulateAndRunWriteTheSameFiles) {
  TestDaemon daemon;
  const std::string design = testing::temp_dir();
  ASSERT_EQ(run_cli("design example:hypar --quiet --resolution 16 --members-u 7 --members-v 7 "
                    "--out '" +
                    design + "'")
                .exit_code,
            0);
  const auto strip = testing::deployment_without_timings;
  for (const std::string& command :
       {"simulate '" + design + "/design.json' --notches on",
        std::string(
            "run example:hypar --resolution 16 --members-u 7 --members-v 7 --notches on")}) {
    SCOPED_TRACE(command);
    const std::string local = testing::temp_dir(), remote = testing::temp_dir();
    auto result = run_cli(command + " --quiet --out '" + local + "'");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    result =
        run_cli(command + " --quiet --server " + daemon.grpc_address() + " --out '" + remote + "'");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(read_text(remote + "/deployed.obj"), read_text(local + "/deployed.obj"));
    EXPECT_EQ(read_text(remote + "/deviation.ply"), read_text(local + "/deviation.ply"));
    EXPECT_EQ(strip(read_text(remote + "/deployment.json")),
              strip(read_text(local + "/deployment.json")));
  }
  // A bad option is found by the daemon and keeps its exit code and its flag name.
  const auto result = run_cli("simulate '" + design + "/design.json' --quiet --young -1 --server " +
                              daemon.grpc_address() + " --out '" + testing::temp_dir() + "'");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--young"), std::string::npos) << result.err;
}

TEST(CliRemote, PatchOfAFileWithRepairsWritesTheSameFiles) {
  // An isolated vertex first: file order and mesh order differ, corners are file indices.
  const ExampleSurface plane = make_example("plane");
  std::string obj = "v 999 999 999\n";
  for (const Vec3& v : plane.mesh.vertices())
    obj += "v " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " +
           std::to_string(v.z()) + "\n";
  for (const Face& f : plane.mesh.faces())
    obj += "f " + std::to_string(f[0] + 2) + " " + std::to_string(f[1] + 2) + " " +
           std::to_string(f[2] + 2) + "\n";
  const std::string mesh = testing::write_text(testing::temp_dir(), "shifted.obj", obj);
  std::string corners;
  for (int c : plane.corners) corners += (corners.empty() ? "" : ",") + std::to_string(c + 1);
  TestDaemon daemon;
  const std::string local = testing::temp_dir(), remote = testing::temp_dir();
  const std::string args = "patch '" + mesh + "' --quiet --corners " + corners + " ";
  auto result = run_cli(args + "--out '" + local + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  result = run_cli(args + "--server " + daemon.grpc_address() + " --out '" + remote + "'");
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(read_text(remote + "/patch.obj"), read_text(local + "/patch.obj"));
  const auto report = without_timings(read_text(remote + "/patch.json"));
  EXPECT_EQ(report, without_timings(read_text(local + "/patch.json")));
  EXPECT_EQ(report["corners"][0]["input_vertex"], plane.corners[0] + 1);  // file order
  EXPECT_NE(report["warnings"].dump().find("isolated"), std::string::npos) << report.dump();
}

TEST(CliRemote, ErrorsKeepTheirExitCodes) {
  TestDaemon daemon;
  const std::string server = " --server " + daemon.grpc_address() + " --out " + testing::temp_dir();
  auto result = run_cli("design example:plane --quiet --eta-max 0.5" + server);
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--eta-max"), std::string::npos) << result.err;
  result = run_cli("design example:plane --quiet --corners '-40,-30,0;40,-30,0;0,-10,0;-40,30,0'" +
                   server);
  EXPECT_EQ(result.exit_code, 3) << result.err;
  EXPECT_NE(result.err.find("criterion iv"), std::string::npos) << result.err;
  result = run_cli("design example:plane --quiet --server 127.0.0.1:1 --timeout 5 --out " +
                   testing::temp_dir());
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_EQ(result.err.rfind("error: gridshelld at 127.0.0.1:1", 0), 0u) << result.err;
}

TEST(CliRemote, HealthCommand) {
  TestDaemon daemon;
  auto result = run_cli("health --server " + daemon.grpc_address());
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("SERVING"), std::string::npos) << result.out;
  result = run_cli("health --server 127.0.0.1:1 --timeout 5");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(result.err.rfind("error:", 0), 0u) << result.err;
}

TEST(CliRemote, TlsAndTokenFromTheCommandLine) {
  const auto certificate = testing::make_self_signed_certificate();
  const std::string dir = testing::temp_dir();
  auto options = testing::test_options();
  options.tls_cert = testing::write_text(dir, "cert.pem", certificate.cert_pem);
  options.tls_key = testing::write_text(dir, "key.pem", certificate.key_pem);
  options.token_file = testing::write_text(dir, "token", "abc123\n");
  TestDaemon daemon(options);
  const std::string tls = " --server " + daemon.grpc_address() + " --tls-ca '" + options.tls_cert +
                          "' --out " + testing::temp_dir();
  auto result = run_cli("patch example:plane --quiet" + tls);
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.err.find("unauthenticated"), std::string::npos) << result.err;
  result = run_cli("patch example:plane --quiet --token-file '" + options.token_file + "'" + tls);
  EXPECT_EQ(result.exit_code, 0) << result.err;
}

/// Runs gridshelld as a process with the given arguments; stderr goes to a file.
struct DaemonProcess {
  pid_t pid = -1;
  std::string log_path = testing::temp_dir() + "/gridshelld.log";
  explicit DaemonProcess(const std::vector<std::string>& arguments) {
    pid = fork();
    if (pid == 0) {
      const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, STDERR_FILENO);
      std::vector<char*> argv{const_cast<char*>(GRIDSHELLD)};
      for (const auto& a : arguments) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(GRIDSHELLD, argv.data());
      _exit(127);
    }
  }
  /// The "listening" line's gRPC address, waiting for it up to 30 s.
  std::string grpc_address() const {
    for (int i = 0; i < 3000; ++i) {
      std::smatch match;
      const std::string log = read_text(log_path);
      if (std::regex_search(log, match, std::regex("\"grpc\":\"([0-9.]+:[0-9]+)\"")))
        return match[1];
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return "";
  }
  int wait() {
    int status = 0;
    for (int i = 0; i < 3000; ++i) {
      if (waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }
  ~DaemonProcess() {
    if (pid > 0) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
  }
};

TEST(Gridshelld, ServesAndStopsCleanlyOnSigterm) {
  DaemonProcess daemon({"--listen", "127.0.0.1:0", "--http", "127.0.0.1:0"});
  const std::string address = daemon.grpc_address();
  ASSERT_FALSE(address.empty()) << read_text(daemon.log_path);
  const auto result = run_cli("health --server " + address);
  EXPECT_EQ(result.exit_code, 0) << result.err;
  const std::string out = testing::temp_dir();
  EXPECT_EQ(run_cli("patch example:plane --quiet --server " + address + " --out " + out).exit_code,
            0);
  kill(daemon.pid, SIGTERM);
  EXPECT_EQ(daemon.wait(), 0);
  const std::string log = read_text(daemon.log_path);
  EXPECT_NE(log.find("\"event\":\"stopped\""), std::string::npos) << log;
  EXPECT_NE(log.find("\"method\":\"Patch\""), std::string::npos) << log;
}

TEST(Gridshelld, RefusesAnExposedAddressWithoutTls) {
  DaemonProcess daemon({"--listen", "0.0.0.0:0", "--no-http"});
  EXPECT_EQ(daemon.wait(), 2);
  const std::string log = read_text(daemon.log_path);
  EXPECT_EQ(log.rfind("error: --listen: 0.0.0.0:0 is not a loopback address", 0), 0u) << log;
}

/// The HTTP port from the "listening" line, waiting for it up to 30 s; 0 if none.
int http_port_of(const DaemonProcess& daemon) {
  for (int i = 0; i < 3000; ++i) {
    std::smatch match;
    const std::string log = read_text(daemon.log_path);
    if (std::regex_search(log, match, std::regex("\"http\":\"[0-9.]+:([0-9]+)\"")))
      return std::stoi(match[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return 0;
}

TEST(Gridshelld, StaticFolderFlagAndNoStatic) {
  const std::string site = testing::temp_dir();
  testing::write_text(site, "index.html", "<!doctype html><title>page</title>");
  {
    DaemonProcess daemon({"--listen", "127.0.0.1:0", "--http", "127.0.0.1:0", "--static", site});
    const int port = http_port_of(daemon);
    ASSERT_GT(port, 0) << read_text(daemon.log_path);
    const auto reply = testing::http_request(port, "GET", "/");
    EXPECT_EQ(reply.status, 200);
    EXPECT_EQ(reply.body, "<!doctype html><title>page</title>");
  }
  {
    DaemonProcess daemon(
        {"--listen", "127.0.0.1:0", "--http", "127.0.0.1:0", "--static", site, "--no-static"});
    const int port = http_port_of(daemon);
    ASSERT_GT(port, 0) << read_text(daemon.log_path);
    EXPECT_EQ(testing::http_request(port, "GET", "/").status, 404);
    EXPECT_EQ(testing::http_request(port, "GET", "/index.html").status, 404);
    EXPECT_EQ(testing::http_request(port, "GET", "/healthz").status, 200);
  }
  // An explicit folder must exist.
  DaemonProcess missing(
      {"--listen", "127.0.0.1:0", "--http", "127.0.0.1:0", "--static", site + "/nothing-here"});
  EXPECT_EQ(missing.wait(), 2);
  EXPECT_NE(read_text(missing.log_path).find("--static"), std::string::npos)
      << read_text(missing.log_path);
}

}  // namespace
}  // namespace gridshell
