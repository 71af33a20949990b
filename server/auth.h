// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — the bearer token every call must carry when the daemon has one (--token-file).
#pragma once

#include <string>
#include <string_view>

namespace gridshell::server {

/// True if `authorization` is "Bearer TOKEN" with the daemon's token (compared in constant time,
/// so the time taken does not tell how much of a guess was right). An empty token accepts all.
bool bearer_token_matches(std::string_view authorization, const std::string& token);

/// The token in a token file: its contents without surrounding whitespace. Throws InvalidInput
/// naming the option if the file cannot be read or holds no token.
std::string read_token_file(const std::string& path);

/// A whole file (certificates, keys). Throws InvalidInput naming `option` and the path.
std::string read_secret_file(const std::string& path, const char* option);

}  // namespace gridshell::server
