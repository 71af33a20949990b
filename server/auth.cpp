// SPDX-License-Identifier: GPL-3.0-or-later
#include "auth.h"

#include <cctype>
#include <fstream>
#include <sstream>

#include "gridshell/foundation/errors.h"

namespace gridshell::server {

bool bearer_token_matches(std::string_view authorization, const std::string& token) {
  if (token.empty()) return true;
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization.size() < kScheme.size()) return false;
  for (size_t i = 0; i < kScheme.size(); ++i)  // the scheme is case-insensitive (RFC 7235)
    if (std::tolower(static_cast<unsigned char>(authorization[i])) !=
        std::tolower(static_cast<unsigned char>(kScheme[i])))
      return false;
  const std::string_view given = authorization.substr(kScheme.size());
  unsigned difference = given.size() != token.size();
  for (size_t i = 0; i < token.size(); ++i)
    difference |= static_cast<unsigned char>(i < given.size() ? given[i] : 0) ^
                  static_cast<unsigned char>(token[i]);
  return difference == 0;
}

std::string read_secret_file(const std::string& path, const char* option) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(option, "cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string read_token_file(const std::string& path) {
  std::string text = read_secret_file(path, "--token-file");
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  if (first == std::string::npos) throw InvalidInput("--token-file", "" + path + " is empty");
  text = text.substr(first, last - first + 1);
  if (text.find_first_of(" \t\r\n") != std::string::npos)
    throw InvalidInput("--token-file", "" + path + ": the token must be one word");
  return text;
}

}  // namespace gridshell::server
