// SPDX-License-Identifier: GPL-3.0-or-later
// Sweep rows on disk: one `gridshell run` per row in a child process, into a temporary folder
// that becomes rows/<id> in one rename; status.json; the sweep's own file and lock.
#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "gridshell/application/files.h"
#include "gridshell/batch/sweep.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/mesh/mesh_io.h"
#include "gridshell/v1/deployment.pb.h"
#include "gridshell/v1/design.pb.h"
#include "gridshell/v1/layout.pb.h"

namespace gridshell::sweep {
namespace fs = std::filesystem;
using ordered_json = nlohmann::ordered_json;

namespace {

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string host_name() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

/// argv as the NUL-terminated array execv wants (built before fork: no allocation after it).
struct Argv {
  std::vector<std::string> strings;
  std::vector<char*> pointers;
  explicit Argv(std::vector<std::string> arguments) : strings(std::move(arguments)) {
    for (std::string& s : strings) pointers.push_back(s.data());
    pointers.push_back(nullptr);
  }
};

int exit_code_of(int wait_status) {
  if (WIFEXITED(wait_status)) return WEXITSTATUS(wait_status);
  if (WIFSIGNALED(wait_status)) return 128 + WTERMSIG(wait_status);
  return 1;
}

/// The last "error: ..." line of a run's output, without the prefix.
std::string error_line(const std::string& log) {
  std::string last;
  std::istringstream in(log);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("error: ", 0) == 0) last = line.substr(7);
  return last;
}

/// A run's result file. Unknown fields (and enum value names) are skipped, as they were with
/// protobuf's ignore_unknown_fields: a file written by a newer gridshell still gives its numbers.
template <class Message>
bool parse_json_file(const fs::path& path, Message* message, std::string* error) {
  try {
    from_json(read_file(path), *message, kJsonMaxDepth, UnknownFields::Skip);
  } catch (const InvalidInput& e) {
    *error = path.filename().string() + ": " + e.what();
    return false;
  }
  return true;
}

/// The summary numbers of a finished run, from its design.json, report.json, deployment.json.
bool read_results(const fs::path& folder, std::map<std::string, double>* results,
                  std::string* error) {
  auto& r = *results;
  std::error_code ec;
  if (fs::is_directory(folder / "patches", ec)) {
    // A layout run (--layout): the whole's design.json and deployment.json.
    v1::LayoutDesign layout;
    v1::LayoutDeployment whole;
    if (!parse_json_file(folder / "design.json", &layout, error) ||
        !parse_json_file(folder / "deployment.json", &whole, error))
      return false;
    r["coverage"] = layout.layout().coverage();
    r["patches"] = whole.patches_size();
    if (whole.has_rms_without_notches()) r["rms_without_notches"] = whole.rms_without_notches();
    if (whole.has_rms_with_notches()) r["rms_with_notches"] = whole.rms_with_notches();
    r["max_seam_gap"] = whole.max_seam_gap();
    // Joined in one equilibrium: the largest force a seam bolt carries (force_unit).
    if (whole.seams_joined()) r["max_bolt_force"] = whole.max_bolt_force();
    return true;
  }
  v1::Design design;
  v1::DesignReport report;
  v1::Deployment deployment;
  if (!parse_json_file(folder / "design.json", &design, error) ||
      !parse_json_file(folder / "report.json", &report, error) ||
      !parse_json_file(folder / "deployment.json", &deployment, error))
    return false;
  r["alpha_bar"] = design.alpha_bar();
  r["members"] = report.members_g() + report.members_h();
  r["crossings"] = report.crossings();
  if (deployment.has_rms_without_notches())
    r["rms_without_notches"] = deployment.rms_without_notches();
  if (deployment.has_rms_with_notches()) r["rms_with_notches"] = deployment.rms_with_notches();
  const auto& rods = deployment.rods_size() ? deployment.rods() : deployment.rods_without_notches();
  if (!rods.empty()) {
    double stress = 0;
    for (const v1::Lamella& lamella : rods) stress = std::max(stress, lamella.max_bending_stress());
    r["max_bending_stress"] = stress;
  }
  r["t_grid"] = report.t_grid();
  if (deployment.has_seconds_without_notches()) r["t1"] = deployment.seconds_without_notches();
  if (deployment.has_seconds_with_notches()) r["t2"] = deployment.seconds_with_notches();
  return true;
}

/// Attempt numbers of the row's earlier runs: the finished folder's and any left-over
/// temporary folders (.tmp/<id>.<n>).
int last_attempt(const fs::path& rows, const std::string& id) {
  int last = 0;
  if (auto status = read_status((rows / id / "status.json").string()))
    last = std::max(last, status->attempt);
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(rows / ".tmp", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > id.size() + 1 && name.compare(0, id.size() + 1, id + ".") == 0) {
      const std::string number = name.substr(id.size() + 1);
      if (number.find_first_not_of("0123456789") == std::string::npos && number.size() < 9)
        last = std::max(last, std::stoi(number));
    }
  }
  return last;
}

void remove_leftovers(const fs::path& rows, const std::string& id) {
  std::error_code ec;
  std::vector<fs::path> old;
  for (const auto& entry : fs::directory_iterator(rows / ".tmp", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > id.size() + 1 && name.compare(0, id.size() + 1, id + ".") == 0 &&
        name.find_first_not_of("0123456789", id.size() + 1) == std::string::npos)
      old.push_back(entry.path());
  }
  for (const fs::path& path : old) fs::remove_all(path, ec);
}

/// Moves the finished attempt to rows/<id>: one rename when the row has no folder yet, else an
/// atomic exchange with the old folder (renameat2 RENAME_EXCHANGE), which is then removed.
void install(const fs::path& attempt, const fs::path& final_dir) {
  if (::rename(attempt.c_str(), final_dir.c_str()) == 0) return;
  if (errno != ENOTEMPTY && errno != EEXIST)
    throw std::runtime_error("cannot move " + attempt.string() + " to " + final_dir.string() +
                             ": " + std::strerror(errno));
  if (::renameat2(AT_FDCWD, attempt.c_str(), AT_FDCWD, final_dir.c_str(), RENAME_EXCHANGE) != 0)
    throw std::runtime_error("cannot replace " + final_dir.string() + ": " + std::strerror(errno));
  std::error_code ec;
  fs::remove_all(attempt, ec);  // now the previous folder
}

}  // namespace

std::string now_iso8601() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const int millis = static_cast<int>(
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buffer[96];  // room for any int the format could see (-Wformat-truncation)
  std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, millis);
  return buffer;
}

std::string status_of_exit_code(int exit_code) {
  switch (exit_code) {
    case 0:
      return "ok";
    case 2:
      return "invalid";
    case 3:
      return "infeasible";
    case 4:
      return "unconverged";  // files kept for diagnosis, not a result
    case 130:
      return "cancelled";
    default:
      return exit_code > 128 ? "killed" : "failed";
  }
}

std::string to_json(const RowStatus& s) {
  ordered_json j;
  j["id"] = s.id;
  j["status"] = s.status;
  j["exit_code"] = s.exit_code;
  j["error"] = s.error;
  j["attempt"] = s.attempt;
  j["host"] = s.host;
  j["engine"] = s.engine;
  if (!s.slurm_job.empty()) j["slurm_job"] = s.slurm_job;
  j["started"] = s.started;
  j["finished"] = s.finished;
  j["seconds"] = s.seconds;
  ordered_json options = ordered_json::object();
  for (const auto& [column, value] : s.options) options[column] = value;
  j["options"] = options;
  ordered_json results = ordered_json::object();
  for (const auto& [name, value] : s.results) results[name] = value;
  j["results"] = results;
  return j.dump(2) + "\n";
}

std::optional<RowStatus> read_status(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  try {
    const ordered_json j = ordered_json::parse(in);
    RowStatus s;
    s.id = j.at("id").get<std::string>();
    s.status = j.at("status").get<std::string>();
    s.exit_code = j.at("exit_code").get<int>();
    s.error = j.value("error", "");
    s.attempt = j.value("attempt", 0);
    s.host = j.value("host", "");
    s.engine = j.value("engine", "");
    s.slurm_job = j.value("slurm_job", "");
    s.started = j.value("started", "");
    s.finished = j.value("finished", "");
    s.seconds = j.value("seconds", 0.0);
    if (j.contains("options"))
      for (const auto& [column, value] : j["options"].items())
        s.options.emplace_back(column, value.get<std::string>());
    if (j.contains("results"))
      for (const auto& [name, value] : j["results"].items()) s.results[name] = value.get<double>();
    return s;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string row_dir(const std::string& dir, const std::string& id) {
  return (fs::path(dir) / "rows" / id).string();
}

CommandOutput run_command(const std::vector<std::string>& arguments) {
  CommandOutput output;
  int out_pipe[2], err_pipe[2];
  if (pipe2(out_pipe, O_CLOEXEC) != 0) return output;
  if (pipe2(err_pipe, O_CLOEXEC) != 0) {
    close(out_pipe[0]);
    close(out_pipe[1]);
    return output;
  }
  Argv argv(arguments);
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = open("/dev/null", O_RDONLY);
    if (null >= 0) dup2(null, 0);
    dup2(out_pipe[1], 1);
    dup2(err_pipe[1], 2);
    execvp(argv.pointers[0], argv.pointers.data());
    const char* message = "cannot run the command\n";
    (void)!write(2, message, std::strlen(message));
    _exit(127);
  }
  close(out_pipe[1]);
  close(err_pipe[1]);
  if (pid < 0) {
    close(out_pipe[0]);
    close(err_pipe[0]);
    output.err = std::string("fork: ") + std::strerror(errno);
    return output;
  }
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&output.out, &output.err};
  int open_count = 2;
  char buffer[65536];
  while (open_count > 0) {
    if (poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t n = read(fds[i].fd, buffer, sizeof buffer);
      if (n > 0) {
        sinks[i]->append(buffer, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_count;
      }
    }
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  output.exit_code = exit_code_of(status);
  return output;
}

RowStatus run_row(const std::string& dir, const Row& row, const RowSettings& settings,
                  const std::atomic<bool>* cancel) {
  const fs::path rows = fs::path(dir) / "rows";
  const fs::path temporary = rows / ".tmp";
  fs::create_directories(temporary);
  RowStatus status;
  status.id = row.id;
  status.options = row.values;
  status.host = host_name();
  status.engine = settings.engine;
  status.slurm_job = settings.slurm_job;
  // The attempt's folder, made with mkdir: the first to make it owns it.
  fs::path attempt_dir;
  for (int attempt = last_attempt(rows, row.id) + 1;; ++attempt) {
    attempt_dir = temporary / (row.id + "." + std::to_string(attempt));
    if (::mkdir(attempt_dir.c_str(), 0777) == 0) {
      status.attempt = attempt;
      break;
    }
    if (errno != EEXIST || attempt > 10000)
      throw std::runtime_error("cannot create " + attempt_dir.string() + ": " +
                               std::strerror(errno));
  }

  std::vector<std::string> arguments{settings.gridshell, "run"};
  for (const std::string& a : row.run_arguments()) arguments.push_back(a);
  for (const std::string& a : {std::string("--out"), attempt_dir.string(), std::string("--quiet"),
                               std::string("--threads"), std::to_string(settings.threads)})
    arguments.push_back(a);
  const RemoteOptions& remote = settings.remote;
  if (remote.remote()) {
    arguments.push_back("--server=" + remote.server);
    if (remote.tls) arguments.push_back("--tls");
    if (!remote.tls_ca.empty()) arguments.push_back("--tls-ca=" + remote.tls_ca);
    if (!remote.token_file.empty()) arguments.push_back("--token-file=" + remote.token_file);
    if (remote.timeout > 0) arguments.push_back("--timeout=" + std::to_string(remote.timeout));
  }
  Argv argv(arguments);
  const fs::path log_path = attempt_dir / "run.log";
  const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (log < 0) throw std::runtime_error("cannot create " + log_path.string());

  status.started = now_iso8601();
  const auto start = std::chrono::steady_clock::now();
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {
    // The run dies with the process that runs the row (a killed Slurm task takes its row
    // with it), and reads nothing.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(137);
    // A session of its own, as slurmstepd gives each array task: the terminal's Ctrl-C reaches
    // the sweep only (which stops its rows with SIGTERM), and with the kernel's autogroup
    // scheduling each row competes for the CPUs as one group, as a Slurm task does (sharing one
    // group, the local engine's rows got a third of the Slurm tasks' CPU on a busy machine).
    setsid();
    const int null = open("/dev/null", O_RDONLY);
    if (null >= 0) dup2(null, 0);
    dup2(log, 1);
    dup2(log, 2);
    execv(argv.pointers[0], argv.pointers.data());
    const char* message = "error: internal: cannot start gridshell run\n";
    (void)!write(2, message, std::strlen(message));
    _exit(127);
  }
  ::close(log);
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  int wait_status = 0;
  bool terminated = false;
  auto terminated_at = start;
  for (;;) {
    const pid_t done = waitpid(pid, &wait_status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) break;
    if (cancel && cancel->load() && !terminated) {
      kill(pid, SIGTERM);  // gridshell run cancels its work and exits 130
      terminated = true;
      terminated_at = std::chrono::steady_clock::now();
    }
    if (terminated && std::chrono::steady_clock::now() - terminated_at > std::chrono::seconds(10))
      kill(pid, SIGKILL);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  status.exit_code = exit_code_of(wait_status);
  status.finished = now_iso8601();
  status.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  status.status = status_of_exit_code(status.exit_code);
  const std::string log_text = read_file(log_path);
  status.error = error_line(log_text);
  if (status.status == "killed" && status.error.empty())
    status.error = "killed by signal " + std::to_string(status.exit_code - 128);
  if (status.status == "cancelled" || status.status == "killed") return status;  // not a result

  if (status.status == "ok") {
    std::string problem;
    if (!read_results(attempt_dir, &status.results, &problem)) {
      status.status = "failed";
      status.exit_code = 1;
      status.error = "internal: cannot read the run's results: " + problem;
    }
  }
  write_file_atomically((attempt_dir / "status.json").string(), to_json(status));
  install(attempt_dir, rows / row.id);
  remove_leftovers(rows, row.id);
  return status;
}

// sweep.json ------------------------------------------------------------------------------------

void write_sweep_file(const std::string& dir, const Manifest& manifest) {
  ordered_json j;
  j["manifest"] = manifest.path;
  j["columns"] = manifest.columns;
  ordered_json rows = ordered_json::array();
  for (const Row& row : manifest.rows) {
    ordered_json r;
    r["id"] = row.id;
    r["line"] = row.line;
    r["mesh"] = row.mesh;
    ordered_json values = ordered_json::object();
    for (const auto& [column, value] : row.values) values[column] = value;
    r["values"] = values;
    rows.push_back(r);
  }
  j["rows"] = rows;
  write_file_atomically((fs::path(dir) / "sweep.json").string(), j.dump(1) + "\n");
}

Manifest read_sweep_file(const std::string& dir) {
  const fs::path path = fs::path(dir) / "sweep.json";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(dir, "not a sweep folder (no sweep.json)");
  try {
    const ordered_json j = ordered_json::parse(in);
    Manifest manifest;
    manifest.path = j.at("manifest").get<std::string>();
    manifest.columns = j.at("columns").get<std::vector<std::string>>();
    for (const auto& r : j.at("rows")) {
      Row row;
      row.id = r.at("id").get<std::string>();
      row.line = r.value("line", 0);
      row.mesh = r.at("mesh").get<std::string>();
      for (const auto& [column, value] : r.at("values").items())
        row.values.emplace_back(column, value.get<std::string>());
      manifest.rows.push_back(std::move(row));
    }
    return manifest;
  } catch (const std::exception& e) {
    throw InvalidInput(path.string(), std::string("unreadable: ") + e.what());
  }
}

std::vector<RowStatus> row_statuses(const std::string& dir, const Manifest& manifest) {
  std::vector<RowStatus> statuses;
  statuses.reserve(manifest.rows.size());
  const fs::path rows = fs::path(dir) / "rows";
  for (const Row& row : manifest.rows) {
    std::optional<RowStatus> status = read_status((rows / row.id / "status.json").string());
    if (!status) {
      status.emplace();
      status->id = row.id;
      status->status = "pending";
      status->options = row.values;
      const int attempts = last_attempt(rows, row.id);
      if (attempts > 0) {
        status->attempt = attempts;
        status->error = "attempt " + std::to_string(attempts) +
                        " running or interrupted (rows/.tmp/" + row.id + "." +
                        std::to_string(attempts) + ")";
      }
    }
    statuses.push_back(std::move(*status));
  }
  return statuses;
}

FolderLock::FolderLock(const std::string& dir) {
  const std::string path = (fs::path(dir) / ".lock").string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0) throw InvalidInput("--out", "cannot create " + path + ": " + std::strerror(errno));
  if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const std::string holder = read_file(path);
    ::close(fd_);
    fd_ = -1;
    throw InvalidInput("--out", "another gridshell sweep is running in " + dir +
                                    (holder.empty() ? "" : " (" + holder + ")"));
  }
  const std::string me = "pid " + std::to_string(getpid()) + " on " + host_name();
  if (ftruncate(fd_, 0) == 0) (void)!pwrite(fd_, me.data(), me.size(), 0);
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace gridshell::sweep
