// SPDX-License-Identifier: GPL-3.0-or-later
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

std::string describe(const std::string& field, const std::string& message) {
  return field.empty() ? message : field + ": " + message;
}

}  // namespace

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidInput:
      return "invalid_input";
    case ErrorCode::Infeasible:
      return "infeasible";
    case ErrorCode::Cancelled:
      return "cancelled";
    case ErrorCode::Internal:
      return "internal";
  }
  return "internal";
}

std::string join_field(const std::string& prefix, const std::string& field) {
  if (prefix.empty()) return field;
  if (field.empty()) return prefix;
  if (field.front() == '[') return prefix + field;
  return prefix + "." + field;
}

Error::Error(ErrorCode code, std::string field, std::string message, Reason reason)
    : std::runtime_error(describe(field, message)),
      code_(code),
      reason_(reason),
      field_(std::move(field)),
      message_(std::move(message)) {}

void rethrow_within(const Error& error, const std::string& prefix) {
  const std::string field = join_field(prefix, error.field());
  switch (error.code()) {
    case ErrorCode::InvalidInput:
      throw InvalidInput(field, error.message());
    case ErrorCode::Infeasible:
      throw Infeasible(field, error.message(), error.reason());
    case ErrorCode::Cancelled:
      throw Cancelled();
    case ErrorCode::Internal:
      throw Error(ErrorCode::Internal, field, error.message());
  }
  throw error;
}

}  // namespace gridshell
