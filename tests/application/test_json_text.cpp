// SPDX-License-Identifier: GPL-3.0-or-later
// The JSON writer of every file gridshell writes (application/json_text.cpp) against protobuf's
// own JSON printer and parser: its text must read back (protobuf's parser) to exactly the message
// it came from, and hold the same JSON value as protobuf's printer writes.
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <google/protobuf/wrappers.pb.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"

namespace gridshell {
namespace {

namespace pb = google::protobuf;

void expect_same_json(const pb::Message& message) {
  for (const bool pretty : {true, false}) {
    SCOPED_TRACE(message.GetTypeName() + (pretty ? " pretty" : " compact"));
    const std::string ours = to_json(message, pretty);
    const std::string library = to_json_library(message, pretty);
    std::unique_ptr<pb::Message> back(message.New());
    const auto status = pb::util::JsonStringToMessage(ours, back.get());
    ASSERT_TRUE(status.ok()) << status.ToString() << "\n" << ours.substr(0, 400);
    EXPECT_TRUE(pb::util::MessageDifferencer::Equals(message, *back));
    EXPECT_EQ(nlohmann::json::parse(ours), nlohmann::json::parse(library));
    if (ours.size() > 2 && ours.front() == '{') {  // an object with members, not a wrapper's value
      EXPECT_EQ(ours.find('\n') != std::string::npos, pretty);
    }
  }
}

v1::DesignRequest example_request(const std::string& name) {
  const ExampleSurface example = make_example(name);
  v1::DesignRequest request;
  *request.mutable_mesh() = to_proto(example.mesh, "example:" + name);
  for (int v : example.corners) request.mutable_corners()->add_vertices(v);
  return request;
}

TEST(JsonText, DesignResultsReadBackExactly) {
  // A whole design (members as nested ListValues, the patch, maps of stage times, 64-bit
  // integers, optional fields) and its report.
  const v1::DesignResult result = run_design(example_request("waves-bump"), {}, {1});
  expect_same_json(result.design());
  expect_same_json(result.report());
  expect_same_json(result);  // views: bytes fields
}

TEST(JsonText, EdgeCasesOfTheMapping) {
  // Doubles that need all 17 digits, subnormals, huge and negative zero; strings that need
  // escapes and UTF-8; bytes of every value; empty repeated fields; unset optional fields.
  v1::Mesh mesh;
  mesh.set_name("quote \" backslash \\ tab \t newline \n bell \x07 \xc3\xa9 \xe2\x82\xac");
  for (double v : {0.1, 1.0 / 3.0, -0.0, 5e-324, 1.7976931348623157e308, 1e21, 1e-7, 123456789.0,
                   54.652211872083271, -2.5})
    mesh.add_positions(v);
  std::string bytes;
  for (int c = 0; c < 256; ++c) bytes += static_cast<char>(c);
  for (const std::string& b : {bytes, std::string("a"), std::string("ab"), std::string()}) {
    mesh.set_file(b);
    expect_same_json(mesh);
  }
  v1::DesignRequest request = example_request("sphere");
  request.mutable_options()->set_eta_max(1.01);  // optional with presence: printed when set
  request.mutable_options()->set_alpha("70deg");
  expect_same_json(request);
  request.mutable_options()->clear_eta_max();
  expect_same_json(request);

  pb::Struct s;
  (*s.mutable_fields())["b"].set_number_value(2.5);
  (*s.mutable_fields())["a"].set_string_value("x");
  (*s.mutable_fields())["n"].set_null_value(pb::NULL_VALUE);
  (*s.mutable_fields())["t"].set_bool_value(true);
  pb::ListValue* list = (*s.mutable_fields())["l"].mutable_list_value();
  list->add_values()->set_number_value(1e-300);
  list->add_values()->mutable_struct_value();
  list->add_values()->mutable_list_value();
  expect_same_json(s);
  pb::DoubleValue wrapped;
  wrapped.set_value(0.30000000000000004);
  expect_same_json(wrapped);
  pb::Int64Value big;
  big.set_value(std::numeric_limits<std::int64_t>::min());
  expect_same_json(big);
}

TEST(JsonText, NonFiniteDoublesAreStringsAsInProtobuf) {
  v1::Mesh mesh;
  mesh.add_positions(std::numeric_limits<double>::quiet_NaN());
  mesh.add_positions(std::numeric_limits<double>::infinity());
  mesh.add_positions(-std::numeric_limits<double>::infinity());
  const std::string ours = to_json(mesh, false);
  EXPECT_EQ(nlohmann::json::parse(ours), nlohmann::json::parse(to_json_library(mesh, false)));
  v1::Mesh back;
  ASSERT_TRUE(pb::util::JsonStringToMessage(ours, &back).ok());
  ASSERT_EQ(back.positions_size(), 3);
  EXPECT_TRUE(std::isnan(back.positions(0)));
  EXPECT_EQ(back.positions(1), std::numeric_limits<double>::infinity());
  EXPECT_EQ(back.positions(2), -std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace gridshell
