// SPDX-License-Identifier: GPL-3.0-or-later
// gridshelld — call outcome, independent of the transport. The codes are gRPC's (same numbers), so
// the gRPC layer casts them and the HTTP gateway maps them to HTTP statuses (docs/api.md).
#pragma once

#include <string>
#include <vector>

#include "gridshell/v1/requests.pb.h"

namespace gridshell::server {

enum class StatusCode {
  Ok = 0,
  Cancelled = 1,
  Unknown = 2,
  InvalidArgument = 3,
  DeadlineExceeded = 4,
  NotFound = 5,
  AlreadyExists = 6,
  PermissionDenied = 7,
  ResourceExhausted = 8,
  FailedPrecondition = 9,
  Aborted = 10,
  OutOfRange = 11,
  Unimplemented = 12,
  Internal = 13,
  Unavailable = 14,
  DataLoss = 15,
  Unauthenticated = 16,
};

struct Status {
  StatusCode code = StatusCode::Ok;
  std::string message;  ///< plain text, without the field
  std::string field{};  ///< the request field it concerns (kernel errors), or ""
  /// An infeasible design's ranked feasible suggestions (v1::ErrorDetail.suggestions).
  std::vector<v1::Suggestion> suggestions{};
  bool ok() const { return code == StatusCode::Ok; }
  /// "field: message", or the message alone: the gRPC status message and the log's.
  std::string text() const { return field.empty() ? message : field + ": " + message; }
};

/// "INVALID_ARGUMENT", ...
const char* code_name(StatusCode code);

/// The kernel's name of the error class a status code stands for: "invalid_input",
/// "infeasible", "cancelled", "internal" (v1::ErrorDetail.code), or the lower-case status name.
std::string error_code_name(StatusCode code);

/// The HTTP status the gateway answers for a code: 400 invalid argument, 422 failed precondition,
/// 499 cancelled, 504 deadline exceeded, 429 resource exhausted, 401 unauthenticated, 501
/// unimplemented, 503 unavailable, 500 internal and everything else.
int http_status(StatusCode code);

}  // namespace gridshell::server
