// gridshell — the error types every kernel function may throw.
//
// They map one-to-one onto the CLI's exit codes and the daemon's gRPC status codes
// (docs/decisions.md): InvalidInput -> exit 2 / INVALID_ARGUMENT, Infeasible -> exit 3 /
// FAILED_PRECONDITION, Cancelled -> CANCELLED; anything else is a bug (exit 1 / INTERNAL).
#pragma once

#include <stdexcept>
#include <string>

namespace gridshell {

/// The input is malformed: an unreadable or invalid mesh, bad corners, a bad option.
/// The message names the file, line, element or field and the problem.
class InvalidInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The input is well-formed but the requested design is impossible: reflex corner, crossing
/// boundary geodesics, a patch that smoothing cannot make coverable, no feasible angle.
class Infeasible : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The caller asked to stop (Progress cancellation flag).
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("cancelled") {}
};

}  // namespace gridshell
