// SPDX-License-Identifier: GPL-3.0-or-later
#include "status.h"

#include <cctype>

namespace gridshell::server {

const char* code_name(StatusCode code) {
  switch (code) {
    case StatusCode::Ok:
      return "OK";
    case StatusCode::Cancelled:
      return "CANCELLED";
    case StatusCode::Unknown:
      return "UNKNOWN";
    case StatusCode::InvalidArgument:
      return "INVALID_ARGUMENT";
    case StatusCode::DeadlineExceeded:
      return "DEADLINE_EXCEEDED";
    case StatusCode::NotFound:
      return "NOT_FOUND";
    case StatusCode::AlreadyExists:
      return "ALREADY_EXISTS";
    case StatusCode::PermissionDenied:
      return "PERMISSION_DENIED";
    case StatusCode::ResourceExhausted:
      return "RESOURCE_EXHAUSTED";
    case StatusCode::FailedPrecondition:
      return "FAILED_PRECONDITION";
    case StatusCode::Aborted:
      return "ABORTED";
    case StatusCode::OutOfRange:
      return "OUT_OF_RANGE";
    case StatusCode::Unimplemented:
      return "UNIMPLEMENTED";
    case StatusCode::Internal:
      return "INTERNAL";
    case StatusCode::Unavailable:
      return "UNAVAILABLE";
    case StatusCode::DataLoss:
      return "DATA_LOSS";
    case StatusCode::Unauthenticated:
      return "UNAUTHENTICATED";
  }
  return "UNKNOWN";
}

std::string error_code_name(StatusCode code) {
  switch (code) {
    case StatusCode::InvalidArgument:
      return "invalid_input";
    case StatusCode::FailedPrecondition:
      return "infeasible";
    case StatusCode::Cancelled:
      return "cancelled";
    case StatusCode::Internal:
      return "internal";
    default: {
      std::string name = code_name(code);
      for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return name;
    }
  }
}

int http_status(StatusCode code) {
  switch (code) {
    case StatusCode::Ok:
      return 200;
    case StatusCode::InvalidArgument:
      return 400;
    case StatusCode::OutOfRange:
      return 400;
    case StatusCode::FailedPrecondition:
      return 422;
    case StatusCode::Cancelled:
      return 499;
    case StatusCode::DeadlineExceeded:
      return 504;
    case StatusCode::ResourceExhausted:
      return 429;
    case StatusCode::Unauthenticated:
      return 401;
    case StatusCode::PermissionDenied:
      return 403;
    case StatusCode::NotFound:
      return 404;
    case StatusCode::Unimplemented:
      return 501;
    case StatusCode::Unavailable:
      return 503;
    default:
      return 500;
  }
}

}  // namespace gridshell::server
