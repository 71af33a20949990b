// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — errors as data: what every kernel function may throw.
//
// An error is a code, the field it concerns as a path into the caller's input, and a plain
// message without any client's syntax. The field paths are those of the API's request
// messages (proto/gridshell/v1/requests.proto), which the kernel's option structs mirror:
// "corners[2]", "mesh.faces[31]", "options.lamella_width", "design.members[4]". Each client
// renders them in its own terms: the CLI with its flag names (--corners, --lamella-width), the
// daemon as a gRPC status and a JSON body {code, field, message} (docs/api.md). Nothing rewrites
// message text.
//
// The codes map one-to-one onto the CLI's exit codes and the daemon's status codes
// (docs/decisions.md): InvalidInput -> exit 2 / INVALID_ARGUMENT, Infeasible -> exit 3 /
// FAILED_PRECONDITION, Cancelled -> exit 130 / CANCELLED, Internal -> exit 1 / INTERNAL. Any
// other exception escaping the kernel is a bug and is reported as Internal.
#pragma once

#include <stdexcept>
#include <string>

namespace gridshell {

enum class ErrorCode {
  InvalidInput,  ///< malformed input: unreadable or invalid mesh, bad corners, a bad option
  Infeasible,    ///< well-formed input, impossible design: reflex corner, no feasible angle, ...
  Cancelled,     ///< the caller asked to stop (Progress cancellation flag)
  Internal,      ///< a bug: an invariant the kernel relies on does not hold
};

/// What made a design infeasible, in the kernel's terms, for a caller that acts on it (the
/// suggestions search): it never needs to read the field or the message.
enum class Reason {
  Unspecified,
  LamellasTooWide,   ///< the automatic member count cannot reach its minimum at this width
  GMembersDoNotFit,  ///< the g-members (their count, or one of them) cannot be placed
  HMembersDoNotFit,  ///< ... the h-members
};

/// "invalid_input" | "infeasible" | "cancelled" | "internal".
const char* to_string(ErrorCode code);

/// Joins field paths: join_field("mesh", "faces[3]") = "mesh.faces[3]"; either may be empty.
std::string join_field(const std::string& prefix, const std::string& field);

/// The error every kernel function throws. what() is "field: message" (or the message alone).
class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, std::string field, std::string message,
        Reason reason = Reason::Unspecified);

  ErrorCode code() const { return code_; }
  /// Why, where the kernel says (Infeasible designs); Unspecified otherwise.
  Reason reason() const { return reason_; }
  /// Path of the input element concerned ("corners[2]"), empty if the whole input is.
  const std::string& field() const { return field_; }
  /// Plain description of the problem, without the field.
  const std::string& message() const { return message_; }

 private:
  ErrorCode code_;
  Reason reason_;
  std::string field_;
  std::string message_;
};

/// The input is malformed; the field names the file, element or option.
class InvalidInput : public Error {
 public:
  InvalidInput(std::string field, std::string message)
      : Error(ErrorCode::InvalidInput, std::move(field), std::move(message)) {}
};

/// The input is well-formed but the requested design is impossible (the field names the input
/// that makes it so, where one does: "corners[1]" for a reflex corner, "options.alpha").
class Infeasible : public Error {
 public:
  Infeasible(std::string field, std::string message, Reason reason = Reason::Unspecified)
      : Error(ErrorCode::Infeasible, std::move(field), std::move(message), reason) {}
};

/// The caller asked to stop.
class Cancelled : public Error {
 public:
  Cancelled() : Error(ErrorCode::Cancelled, "", "cancelled") {}
};

/// The same error with `prefix` joined in front of its field (Cancelled stays as it is): for
/// a caller that hands a part of its input to a function, e.g. the "design" of a request.
[[noreturn]] void rethrow_within(const Error& error, const std::string& prefix);

}  // namespace gridshell
