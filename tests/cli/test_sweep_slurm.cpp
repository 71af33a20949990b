// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell sweep --engine slurm` on a real one-node Slurm (scripts/slurm-local.sh start; CI runs
// these through scripts/test-cluster.sh): a sweep mixing feasible, infeasible and invalid rows,
// one array task SIGKILLed mid-row with scancel, the killed row run again by a second submission,
// failures reported with their exit codes, the same RMS as the local engine; and --no-wait.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "support.h"

namespace gridshell {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::run_cli;

std::string shell(const std::string& command) {
  std::string out;
  if (FILE* pipe = popen((command + " 2>&1").c_str(), "r")) {
    char buffer[4096];
    size_t n;
    while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
    pclose(pipe);
  }
  return out;
}

bool slurm_ready(std::string* why) {
  if (!std::getenv("SLURM_CONF")) {
    *why =
        "SLURM_CONF is not set (bash scripts/slurm-local.sh start; eval \"$(bash "
        "scripts/slurm-local.sh env)\")";
    return false;
  }
  if (std::system("sinfo -h >/dev/null 2>&1") != 0) {
    *why = "sinfo does not answer: no Slurm controller";
    return false;
  }
  return true;
}

#define REQUIRE_SLURM()                                            \
  do {                                                             \
    std::string why;                                               \
    if (!slurm_ready(&why)) {                                      \
      if (std::getenv("GRIDSHELL_REQUIRE_CLUSTER")) FAIL() << why; \
      GTEST_SKIP() << why;                                         \
    }                                                              \
  } while (false)

/// Starts `gridshell ARGS` in the background with its output in files.
pid_t start(const std::vector<std::string>& arguments, const std::string& out,
            const std::string& err) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<std::string> strings{GRIDSHELL_CLI};
    strings.insert(strings.end(), arguments.begin(), arguments.end());
    std::vector<char*> argv;
    for (std::string& s : strings) argv.push_back(s.data());
    argv.push_back(nullptr);
    if (!freopen(out.c_str(), "w", stdout) || !freopen(err.c_str(), "w", stderr)) _exit(126);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

/// Waits up to `seconds` for the process; -1 (and killed) if it is still running.
int wait_bounded(pid_t pid, double seconds) {
  int status = 0;
  for (int i = 0; i < seconds * 10; ++i) {
    if (waitpid(pid, &status, WNOHANG) == pid)
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return -1;
}

const std::string kSmall = ",16,3,3,1\n";

TEST(SweepSlurm, AKilledTaskIsRetriedAndEveryFeasibleRowFinishes) {
  REQUIRE_SLURM();
  const std::string dir = testing::temp_dir();
  const std::string out = dir + "/out";
  // Six feasible rows (one slower, to be caught running), one infeasible angle, one lamella too
  // wide for its patch (invalid, found by the kernel at run time).
  std::string rows =
      "id,mesh,alpha,lamella-width,resolution,members-u,members-v,edges-per-interval\n";
  for (int i = 0; i < 5; ++i)
    rows += "a" + std::to_string(i) + ",example:double-vault," + std::to_string(34 + 4 * i) +
            "deg," + kSmall;
  rows += "slow,example:waves,min,,60,,,\n";
  rows += "steep,example:double-vault,5deg," + kSmall;
  rows += "wide,example:double-vault,min,1000" + kSmall;
  const std::string manifest = testing::write_text(dir, "rows.csv", rows);
  const pid_t sweep =
      start({"sweep", manifest, "--out", out, "--engine", "slurm", "--rows-per-task", "1",
             "--max-parallel", "2", "--retries", "2", "--poll-seconds", "0.5", "--quiet"},
            dir + "/stdout", dir + "/stderr");
  ASSERT_GT(sweep, 0);
  // The task that runs row "slow": its claim names it (JOBID_TASK); kill it once its
  // `gridshell run` is under way.
  const std::string claim = out + "/slurm/claims/1/slow";
  std::string task;
  for (int i = 0; i < 1200 && task.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::ifstream in(claim);
    std::string line;
    if (std::getline(in, line) && fs::exists(out + "/rows/.tmp/slow.1/run.log"))
      task = line.substr(0, line.find(' '));
  }
  ASSERT_FALSE(task.empty()) << "row slow never started\n" << testing::read_text(dir + "/stderr");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const std::string scancel = shell("scancel --signal=KILL " + task);
  const int exit_code = wait_bounded(sweep, 600);
  const std::string err = testing::read_text(dir + "/stderr");
  ASSERT_EQ(exit_code, 0) << scancel << "\n" << err << testing::read_text(dir + "/stdout");

  // The killed task, as sacct saw it (scancel --signal=KILL: CANCELLED, its batch step ended by
  // a signal), with the row it held.
  const auto line_start = err.find("sweep: task " + task + " ");
  ASSERT_NE(line_start, std::string::npos) << err;
  const std::string line = err.substr(line_start, err.find('\n', line_start) - line_start);
  EXPECT_TRUE(line.find("CANCELLED") != std::string::npos ||
              line.find("FAILED") != std::string::npos)
      << line;
  EXPECT_NE(line.find(", signal "), std::string::npos) << line;
  EXPECT_NE(line.find("rows without a result: slow"), std::string::npos) << line;
  // Every feasible row finished; the killed one on its second attempt, in a second submission.
  for (const std::string id : {"a0", "a1", "a2", "a3", "a4", "slow"}) {
    const json status = json::parse(testing::read_text(out + "/rows/" + id + "/status.json"));
    EXPECT_EQ(status["status"], "ok") << id;
    EXPECT_EQ(status["engine"], "slurm");
    EXPECT_FALSE(status["slurm_job"].get<std::string>().empty());
    EXPECT_EQ(status["attempt"], id == "slow" ? 2 : 1) << id;
  }
  EXPECT_NE(json::parse(testing::read_text(out + "/rows/slow/status.json"))["slurm_job"], task);
  const json submission2 = json::parse(testing::read_text(out + "/slurm/submission-2.json"));
  EXPECT_EQ(submission2["rows"], json::array({"slow"}));
  const json steep = json::parse(testing::read_text(out + "/rows/steep/status.json"));
  EXPECT_EQ(steep["status"], "infeasible");
  EXPECT_EQ(steep["exit_code"], 3);
  const json wide = json::parse(testing::read_text(out + "/rows/wide/status.json"));
  EXPECT_EQ(wide["status"], "invalid");
  EXPECT_EQ(wide["exit_code"], 2);
  const std::string summary = testing::read_text(dir + "/stdout");
  EXPECT_NE(summary.find("8: 6 ok, 1 invalid, 1 infeasible"), std::string::npos) << summary;
  EXPECT_NE(summary.find("exit 3"), std::string::npos);
  EXPECT_NE(summary.find("exit 2"), std::string::npos);
  EXPECT_FALSE(fs::exists(out + "/rows/.tmp/slow.1")) << "the killed attempt's folder";

  // The same rows on the local engine: the same RMS, bit for bit.
  std::string local_rows =
      "id,mesh,alpha,lamella-width,resolution,members-u,members-v,edges-per-interval\n";
  for (int i = 0; i < 2; ++i)
    local_rows += "a" + std::to_string(i) + ",example:double-vault," + std::to_string(34 + 4 * i) +
                  "deg," + kSmall;
  const auto local = run_cli("sweep '" + testing::write_text(dir, "local.csv", local_rows) +
                             "' --out '" + dir + "/local' --quiet");
  ASSERT_EQ(local.exit_code, 0) << local.err;
  for (const char* id : {"a0", "a1"}) {
    const json a = json::parse(testing::read_text(out + "/rows/" + id + "/status.json"));
    const json b = json::parse(testing::read_text(dir + "/local/rows/" + id + "/status.json"));
    EXPECT_EQ(a["results"]["rms_with_notches"].get<double>(),
              b["results"]["rms_with_notches"].get<double>());
    EXPECT_EQ(a["results"]["rms_without_notches"].get<double>(),
              b["results"]["rms_without_notches"].get<double>());
  }
}

TEST(SweepSlurm, NoWaitPrintsTheJobAndADependentJobCollects) {
  REQUIRE_SLURM();
  const std::string dir = testing::temp_dir();
  const std::string manifest = testing::write_text(
      dir, "rows.jsonl",
      "{\"id\": \"x\", \"mesh\": \"example:double-vault\", \"resolution\": 16, \"members-u\": 3, "
      "\"members-v\": 3, \"edges-per-interval\": 1}\n"
      "{\"id\": \"y\", \"mesh\": \"example:double-vault\", \"resolution\": 16, \"members-u\": 4, "
      "\"members-v\": 3, \"edges-per-interval\": 1}\n");
  const auto r =
      run_cli("sweep '" + manifest + "' --out '" + dir + "/out' --engine slurm --no-wait");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string job = r.out.substr(0, r.out.find('\n'));
  ASSERT_FALSE(job.empty());
  EXPECT_EQ(job.find_first_not_of("0123456789"), std::string::npos) << r.out;
  // A second start while the job runs is refused (it would run the rows twice).
  const auto twice =
      run_cli("sweep '" + manifest + "' --out '" + dir + "/out' --engine slurm --no-wait");
  const bool still_running = !shell("squeue -h -j " + job).empty();
  if (still_running) {
    EXPECT_EQ(twice.exit_code, 2) << twice.err;
    EXPECT_NE(twice.err.find("still queued or running"), std::string::npos) << twice.err;
  }
  // The dependent job writes the summary after the array.
  bool collected = false;
  for (int i = 0; i < 1200 && !collected; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    collected = fs::exists(dir + "/out/summary.csv") &&
                shell("squeue -h -n gridshell-sweep-collect -o %i").empty();
  }
  ASSERT_TRUE(collected) << shell("squeue; sacct -j " + job);
  const std::string csv = testing::read_text(dir + "/out/summary.csv");
  EXPECT_NE(csv.find("\nx,example:double-vault,16,3,3,1,ok,0,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\ny,example:double-vault,16,4,3,1,ok,0,"), std::string::npos) << csv;
}

}  // namespace
}  // namespace gridshell
