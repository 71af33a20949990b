// SPDX-License-Identifier: GPL-3.0-or-later
#include "bench_daemon.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "gridshell/foundation/errors.h"

namespace gridshell::cli {

namespace fs = std::filesystem;

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

ChildDaemon::ChildDaemon(const std::string& log_path, const std::vector<std::string>& extra)
    : log_path_(log_path) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const std::string binary = (self.parent_path() / "gridshelld").string();
  if (ec || !fs::exists(binary))
    throw InvalidInput("", "bench: gridshelld not found next to " + self.string() +
                               " (build with GRIDSHELL_BUILD_SERVER=ON)");
  pid_ = fork();
  if (pid_ == 0) {
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, STDERR_FILENO);
    std::vector<std::string> args{binary, "--listen", "127.0.0.1:0"};
    args.insert(args.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(binary.c_str(), argv.data());
    _exit(127);
  }
  const std::regex grpc("\"grpc\":\"([0-9.]+:[0-9]+)\""), http("\"http\":\"[0-9.]+:([0-9]+)\"");
  for (int i = 0; i < 3000 && address_.empty() && running(); ++i) {
    std::smatch match;
    const std::string log = read_all(log_path_);
    if (std::regex_search(log, match, grpc)) {
      address_ = match[1];
      if (std::regex_search(log, match, http)) http_port_ = std::stoi(match[1]);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  if (address_.empty())
    throw std::runtime_error("gridshelld did not start: " + read_all(log_path_));
}

ChildDaemon::~ChildDaemon() {
  if (pid_ <= 0) return;
  kill(pid_, SIGTERM);
  int status = 0;
  waitpid(pid_, &status, 0);
}

bool ChildDaemon::running() const {
  int status = 0;
  return pid_ > 0 && waitpid(pid_, &status, WNOHANG) == 0;
}

int ChildDaemon::open_sockets() const {
  int count = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc/" + std::to_string(pid_) + "/fd", ec)) {
    const fs::path target = fs::read_symlink(entry.path(), ec);
    if (!ec && target.string().rfind("socket:", 0) == 0) ++count;
  }
  return count;
}

double ChildDaemon::status_mib(const char* key) const {
  std::ifstream in("/proc/" + std::to_string(pid_) + "/status");
  std::string line;
  const std::size_t n = std::char_traits<char>::length(key);
  while (std::getline(in, line))
    if (line.compare(0, n, key) == 0) return std::stod(line.substr(n)) / 1024;
  return 0;
}

double ChildDaemon::resident_mib() const { return status_mib("VmRSS:"); }
double ChildDaemon::peak_resident_mib() const { return status_mib("VmHWM:"); }

double ChildDaemon::cpu_seconds() const {
  std::istringstream stat(read_all("/proc/" + std::to_string(pid_) + "/stat"));
  std::string field;
  double ticks = 0;
  for (int k = 1; stat >> field && k <= 15; ++k)
    if (k >= 14) ticks += std::stod(field);  // utime, stime (the name has no spaces)
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

}  // namespace gridshell::cli
