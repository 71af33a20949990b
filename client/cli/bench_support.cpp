// SPDX-License-Identifier: GPL-3.0-or-later
#include "bench_support.h"

#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "gridshell/mesh/mesh_io.h"

namespace gridshell::cli {

std::string cpu_name() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

std::string today() {
  const std::time_t now = std::time(nullptr);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d", std::gmtime(&now));
  return buffer;
}

// Replaces the text between the section's markers (or appends the section).
void write_section(const std::string& path, const std::string& name, const std::string& body) {
  const std::string begin = "<!-- bench " + name + " begin -->";
  const std::string end = "<!-- bench " + name + " end -->";
  std::string text;
  if (std::filesystem::exists(path)) {
    std::ifstream in(path);
    std::ostringstream all;
    all << in.rdbuf();
    text = all.str();
  } else {
    text =
        "# Benchmarks\n\nWritten by `gridshell bench`; do not edit the marked sections by hand.\n";
  }
  const std::string section = begin + "\n" + body + end;
  const auto b = text.find(begin), e = text.find(end);
  if (b != std::string::npos && e != std::string::npos && e > b)
    text.replace(b, e + end.size() - b, section);
  else
    text += "\n" + section + "\n";
  write_file_atomically(path, text);
}

void publish_section(const std::string& path, const std::string& name, const std::string& table,
                     bool no_write) {
  std::cout << table;
  if (no_write) return;
  write_section(path, name, table);
  std::cerr << "wrote " << path << "\n";
}

}  // namespace gridshell::cli
