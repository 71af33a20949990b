// SPDX-License-Identifier: GPL-3.0-or-later
// Errors as data (gridshell/foundation/errors.h): codes and their names, field paths joined as the
// API's request paths, what() = "field: message", and rethrow_within keeping code and message
// while prefixing the field.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

TEST(Errors, CodeNames) {
  EXPECT_STREQ(to_string(ErrorCode::InvalidInput), "invalid_input");
  EXPECT_STREQ(to_string(ErrorCode::Infeasible), "infeasible");
  EXPECT_STREQ(to_string(ErrorCode::Cancelled), "cancelled");
  EXPECT_STREQ(to_string(ErrorCode::Internal), "internal");
  EXPECT_STREQ(to_string(static_cast<ErrorCode>(99)), "internal");
}

TEST(Errors, JoinFieldBuildsRequestPaths) {
  EXPECT_EQ(join_field("mesh", "faces[3]"), "mesh.faces[3]");
  EXPECT_EQ(join_field("design", "members[4]"), "design.members[4]");
  EXPECT_EQ(join_field("corners", "[2]"), "corners[2]");  // an index joins without a dot
  EXPECT_EQ(join_field("", "corners[2]"), "corners[2]");
  EXPECT_EQ(join_field("options", ""), "options");
  EXPECT_EQ(join_field("", ""), "");
  EXPECT_EQ(join_field(join_field("request", "design"), "corners.points[1]"),
            "request.design.corners.points[1]");
}

TEST(Errors, WhatIsFieldColonMessage) {
  const InvalidInput invalid("corners[2]", "vertex 7 is out of range");
  EXPECT_EQ(invalid.code(), ErrorCode::InvalidInput);
  EXPECT_EQ(invalid.field(), "corners[2]");
  EXPECT_EQ(invalid.message(), "vertex 7 is out of range");
  EXPECT_STREQ(invalid.what(), "corners[2]: vertex 7 is out of range");
  const Infeasible infeasible("", "no feasible planar angle");
  EXPECT_EQ(infeasible.code(), ErrorCode::Infeasible);
  EXPECT_STREQ(infeasible.what(), "no feasible planar angle");  // no field: the message alone
  const Cancelled cancelled;
  EXPECT_EQ(cancelled.code(), ErrorCode::Cancelled);
  EXPECT_EQ(cancelled.field(), "");
  EXPECT_STREQ(cancelled.what(), "cancelled");
  // All are Errors and runtime_errors.
  const Error& base = invalid;
  EXPECT_EQ(base.code(), ErrorCode::InvalidInput);
  const std::runtime_error& runtime = infeasible;
  EXPECT_STREQ(runtime.what(), "no feasible planar angle");
}

/// What rethrow_within(error, prefix) throws; a failure unless it is an `Expected`.
template <class Expected>
Error rethrown(const Error& error, const std::string& prefix) {
  try {
    rethrow_within(error, prefix);
  } catch (const Expected& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "rethrown as the wrong type: " << e.what();
  }
  ADD_FAILURE() << "nothing rethrown";
  return Error(ErrorCode::Internal, "none", "none");
}

TEST(Errors, RethrowWithinPrefixesTheFieldAndKeepsTheKind) {
  const Error invalid = rethrown<InvalidInput>(InvalidInput("faces[3]", "bad"), "mesh");
  EXPECT_EQ(invalid.code(), ErrorCode::InvalidInput);
  EXPECT_EQ(invalid.field(), "mesh.faces[3]");
  EXPECT_EQ(invalid.message(), "bad");
  EXPECT_STREQ(invalid.what(), "mesh.faces[3]: bad");
  const Error infeasible = rethrown<Infeasible>(Infeasible("[1]", "reflex"), "corners");
  EXPECT_EQ(infeasible.code(), ErrorCode::Infeasible);
  EXPECT_EQ(infeasible.field(), "corners[1]");
  EXPECT_EQ(infeasible.message(), "reflex");
  // An error about the whole part names the part.
  EXPECT_EQ(rethrown<Infeasible>(Infeasible("", "no angle"), "design").field(), "design");
  // Cancelled stays as it is.
  const Error cancelled = rethrown<Cancelled>(Cancelled(), "design");
  EXPECT_EQ(cancelled.code(), ErrorCode::Cancelled);
  EXPECT_EQ(cancelled.field(), "");
  EXPECT_STREQ(cancelled.what(), "cancelled");
  // Internal keeps its code.
  const Error internal = rethrown<Error>(Error(ErrorCode::Internal, "grid", "invariant"), "design");
  EXPECT_EQ(internal.code(), ErrorCode::Internal);
  EXPECT_EQ(internal.field(), "design.grid");
  EXPECT_EQ(internal.message(), "invariant");
}

}  // namespace
}  // namespace gridshell
