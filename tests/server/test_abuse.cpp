// SPDX-License-Identifier: GPL-3.0-or-later
// The abuse suite (issue 33): `gridshell bench abuse --quick` attacks real gridshelld processes on
// loopback (515 slow connections, 30 partial 31 MiB bodies, non-readers, a 31 MiB name,
// slowloris, calls without the token, malformed requests) while a new client asks for /healthz
// and a small design. The bench measures; this test asserts what must hold whatever the
// machine's speed: the new client is answered, every refused request gets its documented
// status, the daemon lets go of what it was sent and stays under its memory budget. Times are
// the bench's business (docs/benchmarks.md, section "abuse"), not this test's.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "support.h"

namespace gridshell {
namespace {

constexpr double kMemoryBudgetMib = 512;  // peak over idle (docs/api.md, "Limits")

TEST(Abuse, TheDaemonKeepsServingEveryoneUnderAttack) {
  const std::string json = testing::temp_dir() + "/abuse.json";
  const std::string command = std::string(GRIDSHELL_CLI) +
                              " bench abuse --quick --repeats 1 --no-write --json " + json +
                              " > /dev/null 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(json);
  const nlohmann::json rows = nlohmann::json::parse(in);
  std::set<std::string> seen;
  for (const auto& row : rows) {
    const std::string attack = row["attack"];
    SCOPED_TRACE(attack + ": " + row.dump());
    seen.insert(attack);
    EXPECT_TRUE(row["alive"].get<bool>());
    EXPECT_EQ(row["health_status"], 200);
    EXPECT_EQ(row["design_status"], 200);
    EXPECT_LE(row["over_idle_mib"].get<double>(), kMemoryBudgetMib);
    const auto& got = row["outcomes"];
    const auto count = [&](const std::string& key) { return got.value(key, 0); };
    if (attack == "slow-connections") {
      // Each either still held, closed to make room, or refused with 503: nothing else.
      EXPECT_EQ(count("closed") + count("open") + count("503"), 515);
      EXPECT_GT(count("closed"), 0);  // the per-client share (128) made room for the newcomer
    } else if (attack == "partial-bodies") {
      EXPECT_EQ(count("closed") + count("open") + count("503") + count("408"), 30);
      EXPECT_GT(count("503"), 0);  // the body budget (128 MiB) holds four of them
    } else if (attack == "non-readers") {
      EXPECT_EQ(count("let go"), 11);
    } else if (attack == "long-name") {
      EXPECT_EQ(count("400 naming mesh.name"), 1);
    } else if (attack == "slowloris") {
      EXPECT_EQ(count("cut"), 100);
    } else if (attack == "no-token") {
      EXPECT_EQ(count("grpc health UNAUTHENTICATED"), 1);
      EXPECT_EQ(count("GET /healthz 401"), 1);
      EXPECT_EQ(count("POST /v1/examples 401"), 1);
      EXPECT_EQ(count("POST /v1/design 401"), 1);
      EXPECT_EQ(count("static 200"), 1);
    } else if (attack == "malformed") {
      EXPECT_EQ(count("gzip body 501"), 1);
      EXPECT_EQ(count("PUT static 405"), 1);
      EXPECT_EQ(count("DELETE api 405"), 1);
      EXPECT_EQ(count("bool as string 400"), 1);
      EXPECT_EQ(count("string for a list 400"), 1);
      EXPECT_EQ(count("unknown escape 400"), 1);
      EXPECT_EQ(count("deep nesting 400"), 1);
      EXPECT_EQ(count("eta_max 1e308 400"), 1);
    }
  }
  EXPECT_EQ(seen.size(), 7u);
}

}  // namespace
}  // namespace gridshell
