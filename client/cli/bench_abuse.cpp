// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell bench abuse`: gridshelld attacked from loopback as a careless or hostile client
// would (issue 33). Each attack runs against a fresh daemon (so its peak memory is its own):
//   slow-connections  515 connections, each holding a partial request body
//   partial-bodies    30 connections, each sending 30 of a declared 31 MiB and stopping
//   non-readers       8 GETs of a 60 MB static file and 3 designs whose answers nobody reads
//   long-name         a design whose mesh.name is 31 MiB, with files: true
//   slowloris         100 connections trickling a header one byte every half second
//   no-token          gRPC health and the HTTP API without the token (a daemon with one)
//   malformed         unsupported Transfer-Encoding, methods not allowed, strict JSON
// While an attack holds its connections, a new client asks for /healthz and a small design; the
// times of those answers and the daemon's peak resident memory over its idle memory are the
// results. Targets: /healthz within 1 s, the design within 3 s, peak <= 512 MiB over idle.
// Writes a table into docs/benchmarks.md (section "abuse"); `--json FILE` writes the rows for
// the test (tests/server/test_abuse.cpp), which asserts the statuses and the memory, not times.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "bench_daemon.h"
#include "bench_support.h"
#include "cli_support.h"
#include "commands.h"
#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"
#include "remote.h"

namespace gridshell::cli {

#ifdef GRIDSHELL_HAVE_GRPC

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Plain sockets: the attacks need control over every byte and over not reading.

int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

void set_timeouts(int fd, double seconds) {
  timeval tv{static_cast<time_t>(seconds),
             static_cast<suseconds_t>((seconds - std::floor(seconds)) * 1e6)};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
}

bool send_all(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n <= 0) return false;
    data.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

/// Reads until the peer closes or `seconds` pass: the bytes, and whether it closed.
std::pair<std::string, bool> read_until_close(int fd, double seconds) {
  std::string bytes;
  char buffer[65536];
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end) {
    pollfd p{fd, POLLIN, 0};
    const int wait = static_cast<int>(
        std::max(1.0, std::chrono::duration<double, std::milli>(end - Clock::now()).count()));
    if (::poll(&p, 1, wait) <= 0) continue;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) return {bytes, true};  // closed or reset
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
  return {bytes, false};
}

int status_of(const std::string& response) {
  int status = 0;
  return std::sscanf(response.c_str(), "HTTP/1.1 %d", &status) == 1 ? status : 0;
}

struct Answer {
  int status = 0;  ///< 0: no answer
  std::string body;
  double seconds = 0;
};

/// One request on a new connection ("Connection: close"), answered within `timeout` s.
Answer exchange(int port, const std::string& method, const std::string& target,
                const std::string& body = "", const std::string& headers = "",
                double timeout = 30) {
  Answer answer;
  const auto start = Clock::now();
  const int fd = connect_to(port);
  if (fd < 0) return answer;
  set_timeouts(fd, timeout);
  std::string request = method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + headers +
                        "Connection: close\r\n";
  if (!body.empty() || method == "POST")
    request +=
        "Content-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) + "\r\n";
  request += "\r\n" + body;
  send_all(fd, request);
  const auto [response, closed] = read_until_close(fd, timeout);
  ::close(fd);
  answer.seconds = seconds_since(start);
  answer.status = status_of(response);
  const auto split = response.find("\r\n\r\n");
  if (split != std::string::npos) answer.body = response.substr(split + 4);
  return answer;
}

/// A small design request (the plane example, R = 16) in JSON.
v1::DesignRequest small_design_request() {
  const ExampleSurface example = make_example("plane");
  v1::DesignRequest request;
  *request.mutable_mesh() = to_proto(example.mesh, "example:plane");
  *request.mutable_corners() = to_proto(CornerSpec::at_vertices(example.corners), "example");
  request.mutable_options()->set_resolution(16);
  return request;
}

/// The results of one attack.
struct Row {
  std::string attack, what;
  int count = 0;
  std::map<std::string, int> outcomes;  ///< what the attacking connections got
  Answer health, design;                ///< the new client's answers during the attack
  double idle_mib = 0, peak_mib = 0;
  bool alive = true;
  Row(std::string a, std::string w, int n) : attack(std::move(a)), what(std::move(w)), count(n) {}
  nlohmann::json to_json() const {
    return {{"attack", attack},
            {"what", what},
            {"count", count},
            {"outcomes", outcomes},
            {"health_status", health.status},
            {"health_seconds", health.seconds},
            {"design_status", design.status},
            {"design_seconds", design.seconds},
            {"idle_mib", idle_mib},
            {"peak_mib", peak_mib},
            {"over_idle_mib", peak_mib - idle_mib},
            {"alive", alive}};
  }
};

class Bench {
 public:
  Bench(std::string dir, bool quick) : dir_(std::move(dir)), quick_(quick) {
    design_json_ = to_json(small_design_request(), false);
    fs::create_directories(dir_ + "/static");
    std::ofstream big(dir_ + "/static/big.bin", std::ios::binary);
    const std::string block(1 << 20, 'b');
    for (int k = 0; k < 60; ++k) big << block;
  }

  double stall() const { return quick_ ? 2 : 10; }

  /// A fresh daemon with the gateway (and the static folder), as a user would start it, but
  /// with a shorter stall timeout when quick.
  std::unique_ptr<ChildDaemon> start(std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"--http",         "127.0.0.1:0", "--static",
                                  dir_ + "/static", "--workers",   "2"};
    // Only when quick: otherwise the daemon's own default applies, and an older gridshelld
    // (measured side by side: this gridshell copied next to it) starts too.
    if (quick_) args.insert(args.end(), {"--http-stall-timeout", std::to_string(stall())});
    args.insert(args.end(), extra.begin(), extra.end());
    auto daemon = std::make_unique<ChildDaemon>(
        dir_ + "/gridshelld-" + std::to_string(++runs_) + ".log", args);
    // Warm: one design, so the idle memory includes what every design needs.
    exchange(daemon->http_port(), "POST", "/v1/design", design_json_);
    return daemon;
  }

  /// The new client: /healthz, then a small design.
  void probe(const ChildDaemon& daemon, Row& row) {
    row.health = exchange(daemon.http_port(), "GET", "/healthz", "", "", 10);
    row.design = exchange(daemon.http_port(), "POST", "/v1/design", design_json_, "", 30);
  }

  void finish(const ChildDaemon& daemon, Row& row, const std::string& headers = "") {
    row.peak_mib = daemon.peak_resident_mib();
    row.alive = daemon.running() &&
                exchange(daemon.http_port(), "GET", "/healthz", "", headers).status == 200;
    std::cerr << "bench abuse: " << row.to_json().dump() << "\n";
  }

  /// `count` new connections to the daemon, each sent `first` (and `then`, if given).
  static std::vector<int> open_connections(const ChildDaemon& daemon, int count, double timeout,
                                           const std::string& first, const std::string& then = "",
                                           int receive_buffer = 0) {
    std::vector<int> fds;
    for (int k = 0; k < count; ++k) {
      const int fd = connect_to(daemon.http_port());
      if (fd < 0) continue;
      set_timeouts(fd, timeout);
      if (receive_buffer > 0)
        setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
      send_all(fd, first);
      if (!then.empty()) send_all(fd, then);
      fds.push_back(fd);
    }
    return fds;
  }

  /// What each held connection got: an HTTP status, closed without one, or still open.
  static void tally(std::vector<int>& fds, Row& row, double wait) {
    for (int fd : fds) {
      const auto [bytes, closed] = read_until_close(fd, wait / static_cast<double>(fds.size()));
      const int status = status_of(bytes);
      ++row.outcomes[status ? std::to_string(status) : closed ? "closed" : "open"];
      ::close(fd);
    }
    fds.clear();
  }

  Row slow_connections() {
    Row row{"slow-connections", "515 connections, each holding a partial body of 1 MiB", 515};
    auto daemon = start();
    row.idle_mib = daemon->resident_mib();
    std::vector<int> fds =
        open_connections(*daemon, row.count, 5,
                         "POST /v1/design HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                         "Content-Length: 1048576\r\n\r\n{\"mesh\": {\"name\": \"");
    probe(*daemon, row);
    tally(fds, row, 2);
    finish(*daemon, row);
    return row;
  }

  Row partial_bodies() {
    Row row{"partial-bodies", "30 connections, each sending 30 of a declared 31 MiB", 30};
    auto daemon = start();
    row.idle_mib = daemon->resident_mib();
    std::vector<int> fds =
        open_connections(*daemon, row.count, 5,
                         "POST /v1/design HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                         "Content-Length: " +
                             std::to_string(31u << 20) + "\r\n\r\n",
                         std::string(30u << 20, ' '));
    probe(*daemon, row);
    tally(fds, row, 2);
    finish(*daemon, row);
    return row;
  }

  Row non_readers() {
    Row row{"non-readers",
            "8 GETs of a 60 MB static file and 3 designs (files: true), never read; cut after "
            "the stall timeout",
            11};
    auto daemon = start();
    row.idle_mib = daemon->resident_mib();
    v1::DesignRequest request = small_design_request();
    request.set_files(true);
    const std::string design = to_json(request, false);
    const int baseline = daemon->open_sockets();
    // A client that never reads: a small window that stays closed.
    std::vector<int> fds =
        open_connections(*daemon, 8, 5, "GET /big.bin HTTP/1.1\r\nHost: x\r\n\r\n", "", 4096);
    for (int fd : open_connections(*daemon, 3, 5,
                                   "POST /v1/design HTTP/1.1\r\nHost: x\r\nContent-Type: "
                                   "application/json\r\nContent-Length: " +
                                       std::to_string(design.size()) + "\r\n\r\n" + design,
                                   "", 4096))
      fds.push_back(fd);
    probe(*daemon, row);
    // Past the stall timeout (and the 5 s a finished answer's connection may drain) the daemon
    // must have let go of every one of them, read or not.
    const int before = baseline;
    std::this_thread::sleep_for(std::chrono::duration<double>(stall() + 6));
    const int held = std::max(0, daemon->open_sockets() - before);
    row.outcomes["let go"] = row.count - held;
    if (held > 0) row.outcomes["held"] = held;
    for (int fd : fds) ::close(fd);
    finish(*daemon, row);
    return row;
  }

  Row long_name() {
    Row row{"long-name", "a design whose mesh.name is 31 MiB, files: true", 1};
    auto daemon = start();
    row.idle_mib = daemon->resident_mib();
    v1::DesignRequest request = small_design_request();
    request.mutable_mesh()->set_name(std::string(31u << 20, 'n'));
    request.set_files(true);
    const std::string body = to_json(request, false);
    Answer attack;
    std::thread attacker(
        [&] { attack = exchange(daemon->http_port(), "POST", "/v1/design", body, "", 60); });
    probe(*daemon, row);
    attacker.join();
    ++row.outcomes[std::to_string(attack.status) +
                   (attack.body.find("mesh.name") != std::string::npos ? " naming mesh.name" : "")];
    finish(*daemon, row);
    return row;
  }

  Row slowloris() {
    Row row{"slowloris", "100 connections trickling a header, a byte every 0.5 s", 100};
    auto daemon = start();
    row.idle_mib = daemon->resident_mib();
    std::vector<int> fds = open_connections(*daemon, row.count, 1, "GET /healthz HTTP/1.1\r\n");
    std::atomic<bool> done{false};
    std::vector<bool> cut(fds.size(), false);
    std::thread trickle([&] {
      const auto end = Clock::now() + std::chrono::duration<double>(stall() + 5);
      while (!done && Clock::now() < end) {
        for (std::size_t k = 0; k < fds.size(); ++k)
          if (!cut[k] && !send_all(fds[k], "X")) cut[k] = true;
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
      }
    });
    probe(*daemon, row);
    trickle.join();
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if (!cut[k]) cut[k] = read_until_close(fds[k], 0.05).second;
      ++row.outcomes[cut[k] ? "cut" : "open"];
      ::close(fds[k]);
    }
    finish(*daemon, row);
    return row;
  }

  Row no_token() {
    Row row{"no-token", "gRPC health, HTTP /healthz and API without the token; static files", 5};
    const std::string token_file = dir_ + "/token";
    std::ofstream(token_file) << "bench-token-1234\n";
    auto daemon = start({"--token-file", token_file});
    row.idle_mib = daemon->resident_mib();
    RemoteOptions options;
    options.server = daemon->address();
    RemoteClient anonymous(options);
    try {
      ++row.outcomes["grpc health " + anonymous.health()];
    } catch (const std::exception& e) {
      const std::string text = e.what();
      const bool refused = text.find("UNAUTHENTICATED") != std::string::npos ||
                           text.find("unauthenticated") != std::string::npos;
      ++row.outcomes[refused ? "grpc health UNAUTHENTICATED" : "grpc health: " + text];
    }
    for (const auto& [method, target] :
         {std::pair{"GET", "/healthz"}, {"POST", "/v1/examples"}, {"POST", "/v1/design"}})
      ++row.outcomes[std::string(method) + " " + target + " " +
                     std::to_string(exchange(daemon->http_port(), method, target, "{}").status)];
    ++row.outcomes["static " +
                   std::to_string(
                       exchange(daemon->http_port(), "HEAD", "/big.bin", "", "", 10).status)];
    // The new client has the token.
    const std::string bearer = "Authorization: Bearer bench-token-1234\r\n";
    row.health = exchange(daemon->http_port(), "GET", "/healthz", "", bearer, 10);
    row.design = exchange(daemon->http_port(), "POST", "/v1/design", design_json_, bearer, 30);
    finish(*daemon, row, bearer);
    return row;
  }

  Row malformed() {
    Row row{"malformed", "bad framing, methods and JSON", 0};
    auto daemon = start();
    row.idle_mib = daemon->resident_mib();
    const int port = daemon->http_port();
    const auto count = [&](const std::string& name, const Answer& answer,
                           const std::string& field = "") {
      ++row.count;
      ++row.outcomes[name + " " + std::to_string(answer.status) +
                     (field.empty() || answer.body.find("\"field\":\"" + field) != std::string::npos
                          ? ""
                          : " (field not named)")];
    };
    count("gzip body", exchange(port, "POST", "/v1/design", "", "Transfer-Encoding: gzip\r\n", 10));
    count("PUT static", exchange(port, "PUT", "/index.html", "x"));
    count("DELETE api", exchange(port, "DELETE", "/v1/design"));
    count("bool as string", exchange(port, "POST", "/v1/design", R"({"files": "yes"})"), "files");
    count("string for a list",
          exchange(port, "POST", "/v1/design", R"({"mesh": {"positions": "0 0 0"}})"),
          "mesh.positions");
    count("unknown escape", exchange(port, "POST", "/v1/design", R"({"mesh": {"name": "\q"}})"));
    count("deep nesting",
          exchange(port, "POST", "/v1/design",
                   R"({"mesh": {"positions": )" + std::string(100000, '[') +
                       std::string(100000, ']') + "}}"),
          "mesh.positions");
    v1::DesignRequest huge_eta = small_design_request();
    huge_eta.mutable_options()->set_eta_max(1e308);
    count("eta_max 1e308", exchange(port, "POST", "/v1/design", to_json(huge_eta, false)),
          "options.eta_max");
    probe(*daemon, row);
    finish(*daemon, row);
    return row;
  }

 private:
  std::string dir_;
  bool quick_;
  std::string design_json_;
  int runs_ = 0;
};

std::string outcomes_text(const std::map<std::string, int>& outcomes) {
  std::string text;
  for (const auto& [what, n] : outcomes)
    text += (text.empty() ? "" : ", ") + std::to_string(n) + " × " + what;
  return text;
}

}  // namespace

int bench_abuse(const std::string& out, bool no_write, int repeats, bool quick,
                const std::string& json_path) {
  const std::string dir =
      (fs::temp_directory_path() / ("gridshell-abuse-" + std::to_string(getpid()))).string();
  Bench bench(dir, quick);
  nlohmann::json rows = nlohmann::json::array();
  std::vector<std::vector<Row>> rounds;
  for (int round = 0; round < repeats; ++round) {
    std::vector<Row> results;
    for (const auto& attack : std::vector<std::function<Row()>>{
             [&] { return bench.slow_connections(); }, [&] { return bench.partial_bodies(); },
             [&] { return bench.non_readers(); }, [&] { return bench.long_name(); },
             [&] { return bench.slowloris(); }, [&] { return bench.no_token(); },
             [&] { return bench.malformed(); }}) {
      results.push_back(attack());
      nlohmann::json row = results.back().to_json();
      row["round"] = round;
      rows.push_back(std::move(row));
    }
    rounds.push_back(std::move(results));
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (!json_path.empty()) write_file_atomically(json_path, rows.dump(1) + "\n");

  // The table: per attack, the worst over the rounds.
  std::ostringstream table;
  table << "## Abuse: gridshelld attacked from loopback (issue 33)\n\n"
        << "Each attack against a fresh daemon (defaults, 2 workers, "
        << (quick ? "--http-stall-timeout 2" : "the default stall timeout of 10 s")
        << "); meanwhile a new client asks for /healthz and a small design "
        << "(plane, R = 16). Worst of " << repeats << " round(s); targets: /healthz <= 1 s, "
        << "design <= 3 s, peak resident memory <= 512 MiB over idle.\n\n"
        << "| attack | what the attackers got | /healthz | design | idle MiB | peak over idle "
           "MiB |\n|---|---|---|---|---|---|\n";
  char line[512];
  for (std::size_t a = 0; a < rounds.front().size(); ++a) {
    Row worst = rounds.front()[a];
    for (const auto& round : rounds) {
      const Row& r = round[a];
      if (r.health.seconds > worst.health.seconds || r.health.status != 200)
        worst.health = r.health;
      if (r.design.seconds > worst.design.seconds || r.design.status != 200)
        worst.design = r.design;
      worst.peak_mib = std::max(worst.peak_mib, r.peak_mib - r.idle_mib + worst.idle_mib);
    }
    std::snprintf(line, sizeof line,
                  "| %s: %s | %s | %d in %.3f s | %d in %.3f s | %.0f | %.0f |\n",
                  worst.attack.c_str(), worst.what.c_str(), outcomes_text(worst.outcomes).c_str(),
                  worst.health.status, worst.health.seconds, worst.design.status,
                  worst.design.seconds, worst.idle_mib, worst.peak_mib - worst.idle_mib);
    table << line;
  }
  table << "\nMachine: " << cpu_name() << ", " << std::thread::hardware_concurrency()
        << " hardware threads; " << today() << ". Command: `gridshell bench abuse"
        << (quick ? " --quick" : "") << " --repeats " << repeats << "`\n";
  publish_section(out, "abuse", table.str(), no_write);
  return 0;
}

#else

int bench_abuse(const std::string&, bool, int, bool, const std::string&) {
  throw InvalidInput("", "bench abuse needs the daemon (build with GRIDSHELL_BUILD_SERVER=ON)");
}

#endif

}  // namespace gridshell::cli
