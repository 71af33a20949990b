// SPDX-License-Identifier: GPL-3.0-or-later
// The strict JSON reader (application/json_read.cpp, from_json) against protobuf's own parser:
// every malformation refused with the field named, every real request and file read back to the
// message it came from. Differential: each refused case records whether protobuf 3.21's
// JsonStringToMessage accepts it (asserted, so the record stays true), and every accepted case is
// asserted to be accepted by protobuf too, to the same message.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>
#include <google/protobuf/dynamic_message.h>
#include <google/protobuf/util/field_comparator.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/example_surfaces.h"
#include "gridshell/foundation/errors.h"
#include "gridshell/v1/service.pb.h"
#include "support.h"

namespace gridshell {
namespace {

namespace pb = google::protobuf;
using FDP = pb::FieldDescriptorProto;

// ---- A message with every kind of field (gridshell's own have no enum, no integer map keys) ----

FDP* add_field(pb::DescriptorProto* m, const std::string& name, int number, FDP::Type type,
               FDP::Label label = FDP::LABEL_OPTIONAL, const std::string& type_name = "") {
  FDP* f = m->add_field();
  f->set_name(name);
  f->set_number(number);
  f->set_type(type);
  f->set_label(label);
  if (!type_name.empty()) f->set_type_name(type_name);
  return f;
}

void add_map(pb::DescriptorProto* m, const std::string& name, const std::string& entry, int number,
             FDP::Type key, FDP::Type value, const std::string& value_type = "") {
  pb::DescriptorProto* e = m->add_nested_type();
  e->set_name(entry);
  e->mutable_options()->set_map_entry(true);
  add_field(e, "key", 1, key);
  add_field(e, "value", 2, value, FDP::LABEL_OPTIONAL, value_type);
  add_field(m, name, number, FDP::TYPE_MESSAGE, FDP::LABEL_REPEATED, ".jsontest.All." + entry);
}

/// jsontest.All: scalars of every type, repeated ones, maps with integer and bool keys, an
/// enum, a oneof, a custom json_name and the well-known types.
class TestTypes {
 public:
  TestTypes() {
    factory_.SetDelegateToGeneratedFactory(true);
    pb::FileDescriptorProto file;
    file.set_name("jsontest/all.proto");
    file.set_package("jsontest");
    file.set_syntax("proto3");
    for (const char* dep : {"google/protobuf/struct.proto", "google/protobuf/wrappers.proto",
                            "google/protobuf/timestamp.proto", "google/protobuf/any.proto"})
      file.add_dependency(dep);
    pb::EnumDescriptorProto* color = file.add_enum_type();
    color->set_name("Color");
    int number = 0;
    for (const char* name : {"COLOR_UNSPECIFIED", "RED", "GREEN"}) {
      auto* v = color->add_value();
      v->set_name(name);
      v->set_number(number++);
    }
    pb::DescriptorProto* m = file.add_message_type();
    m->set_name("All");
    const auto R = FDP::LABEL_REPEATED;
    const auto O = FDP::LABEL_OPTIONAL;
    add_field(m, "i32", 1, FDP::TYPE_INT32);
    add_field(m, "u32", 2, FDP::TYPE_UINT32);
    add_field(m, "i64", 3, FDP::TYPE_INT64);
    add_field(m, "u64", 4, FDP::TYPE_UINT64);
    add_field(m, "s64", 5, FDP::TYPE_SINT64);
    add_field(m, "fl", 6, FDP::TYPE_FLOAT);
    add_field(m, "db", 7, FDP::TYPE_DOUBLE);
    add_field(m, "b", 8, FDP::TYPE_BOOL);
    add_field(m, "s", 9, FDP::TYPE_STRING);
    add_field(m, "by", 10, FDP::TYPE_BYTES);
    add_field(m, "color", 11, FDP::TYPE_ENUM, O, ".jsontest.Color");
    add_field(m, "child", 12, FDP::TYPE_MESSAGE, O, ".jsontest.All");
    add_field(m, "r_i32", 13, FDP::TYPE_INT32, R);
    add_field(m, "r_color", 14, FDP::TYPE_ENUM, R, ".jsontest.Color");
    add_field(m, "r_child", 15, FDP::TYPE_MESSAGE, R, ".jsontest.All");
    add_map(m, "m_i32", "MI32Entry", 16, FDP::TYPE_INT32, FDP::TYPE_STRING);
    add_map(m, "m_bool", "MBoolEntry", 17, FDP::TYPE_BOOL, FDP::TYPE_INT32);
    add_map(m, "m_value", "MValueEntry", 18, FDP::TYPE_STRING, FDP::TYPE_MESSAGE,
            ".google.protobuf.Value");
    m->add_oneof_decl()->set_name("choice");
    add_field(m, "o_s", 20, FDP::TYPE_STRING)->set_oneof_index(0);
    add_field(m, "o_i32", 21, FDP::TYPE_INT32)->set_oneof_index(0);
    add_field(m, "camel_case", 22, FDP::TYPE_INT32)->set_json_name("customName");
    add_field(m, "st", 30, FDP::TYPE_MESSAGE, O, ".google.protobuf.Struct");
    add_field(m, "v", 31, FDP::TYPE_MESSAGE, O, ".google.protobuf.Value");
    add_field(m, "lv", 32, FDP::TYPE_MESSAGE, O, ".google.protobuf.ListValue");
    add_field(m, "r_v", 33, FDP::TYPE_MESSAGE, R, ".google.protobuf.Value");
    add_field(m, "w_i32", 34, FDP::TYPE_MESSAGE, O, ".google.protobuf.Int32Value");
    add_field(m, "w_db", 35, FDP::TYPE_MESSAGE, O, ".google.protobuf.DoubleValue");
    add_field(m, "ts", 36, FDP::TYPE_MESSAGE, O, ".google.protobuf.Timestamp");
    add_field(m, "any", 37, FDP::TYPE_MESSAGE, O, ".google.protobuf.Any");
    const pb::FileDescriptor* built = pool_.BuildFile(file);
    if (built == nullptr) throw std::runtime_error("jsontest/all.proto does not build");
    all_ = built->FindMessageTypeByName("All");
  }
  std::unique_ptr<pb::Message> all() {
    return std::unique_ptr<pb::Message>(factory_.GetPrototype(all_)->New());
  }

 private:
  pb::DescriptorPool pool_{pb::DescriptorPool::generated_pool()};
  pb::DynamicMessageFactory factory_{&pool_};
  const pb::Descriptor* all_ = nullptr;
};

TestTypes& test_types() {
  static TestTypes types;
  return types;
}

// ---- Helpers ---------------------------------------------------------------------------------

bool protobuf_reads(const std::string& json, pb::Message& message, bool ignore_unknown = false) {
  pb::util::JsonParseOptions options;
  options.ignore_unknown_fields = ignore_unknown;
  return pb::util::JsonStringToMessage(json, &message, options).ok();
}

/// Equal field by field, NaN equal to NaN (maps in any order).
bool same(const pb::Message& a, const pb::Message& b) {
  pb::util::DefaultFieldComparator comparator;
  comparator.set_treat_nan_as_equal(true);
  pb::util::MessageDifferencer differencer;
  differencer.set_field_comparator(&comparator);
  return differencer.Compare(a, b);
}

struct Refusal {
  std::string json;
  std::string field;             ///< the InvalidInput's field, exactly
  std::string words;             ///< a part of its message
  bool protobuf_accepts;         ///< what protobuf 3.21's JsonStringToMessage does with it
  bool protobuf_aborts = false;  ///< protobuf 3.21 aborts the process on it: not asked
};

/// from_json refuses `r.json` for a message like `prototype`, naming r.field; protobuf's parser
/// accepts it or not as recorded.
void expect_refused(const pb::Message& prototype, const Refusal& r, int max_depth = kJsonMaxDepth,
                    UnknownFields unknown = UnknownFields::Refuse) {
  SCOPED_TRACE(r.json.size() > 200 ? r.json.substr(0, 200) + "..." : r.json);
  std::unique_ptr<pb::Message> message(prototype.New());
  try {
    from_json(r.json, *message, max_depth, unknown);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), r.field) << e.what();
    EXPECT_NE(e.message().find(r.words), std::string::npos) << e.what();
    EXPECT_EQ(e.what(), e.field().empty() ? e.message() : e.field() + ": " + e.message());
  }
  if (r.protobuf_aborts) return;
  std::unique_ptr<pb::Message> library(prototype.New());
  EXPECT_EQ(protobuf_reads(r.json, *library, unknown == UnknownFields::Skip), r.protobuf_accepts)
      << "protobuf's parser " << (r.protobuf_accepts ? "refuses" : "accepts") << " it";
}

/// from_json reads `json` into a message equal to what protobuf's parser reads.
std::unique_ptr<pb::Message> expect_read(const pb::Message& prototype, const std::string& json,
                                         UnknownFields unknown = UnknownFields::Refuse) {
  SCOPED_TRACE(json.size() > 200 ? json.substr(0, 200) + "..." : json);
  std::unique_ptr<pb::Message> ours(prototype.New());
  try {
    from_json(json, *ours, kJsonMaxDepth, unknown);
  } catch (const Error& e) {
    ADD_FAILURE() << "refused: " << e.what();
  }
  std::unique_ptr<pb::Message> library(prototype.New());
  EXPECT_TRUE(protobuf_reads(json, *library, unknown == UnknownFields::Skip));
  EXPECT_TRUE(same(*ours, *library));
  return ours;
}

v1::DesignRequest example_request(const std::string& name) {
  const ExampleSurface example = make_example(name);
  v1::DesignRequest request;
  *request.mutable_mesh() = to_proto(example.mesh, "example:" + name);
  for (int v : example.corners) request.mutable_corners()->add_vertices(v);
  return request;
}

/// The message printed by to_json (pretty and not) and by protobuf's printer (JSON names and
/// proto names), each read back by from_json to an equal message.
void expect_round_trip(const pb::Message& message) {
  std::vector<std::string> texts{to_json(message, true), to_json(message, false)};
  for (const bool proto_names : {false, true}) {
    pb::util::JsonPrintOptions options;
    options.preserve_proto_field_names = proto_names;
    options.always_print_primitive_fields = !proto_names;
    std::string text;
    ASSERT_TRUE(pb::util::MessageToJsonString(message, &text, options).ok());
    texts.push_back(text);
  }
  for (const std::string& text : texts) {
    SCOPED_TRACE(message.GetTypeName() + ": " + text.substr(0, 120));
    std::unique_ptr<pb::Message> back(message.New());
    try {
      from_json(text, *back);
    } catch (const Error& e) {
      ADD_FAILURE() << "refused: " << e.what();
      continue;
    }
    EXPECT_TRUE(pb::util::MessageDifferencer::Equals(message, *back));
    std::unique_ptr<pb::Message> library(message.New());
    EXPECT_TRUE(protobuf_reads(text, *library));
  }
}

std::string repeat(const std::string& s, int n) {
  std::string out;
  out.reserve(s.size() * static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) out += s;
  return out;
}

// ---- Refused -----------------------------------------------------------------------------------

TEST(JsonRead, RefusesWhatTheMappingDoesNotAllowNamingTheField) {
  const v1::DesignRequest design;
  const std::vector<Refusal> refusals{
      // bool: only true / false. protobuf reads "yes", "true", "1", "t" ... as true.
      {R"({"files":"yes"})", "files", "expected true or false, got the string \"yes\"", true},
      {R"({"files":"true"})", "files", "true or false", true},
      {R"({"files":1})", "files", "true or false", false},
      // repeated: an array. protobuf reads a scalar as a list of one.
      {R"({"mesh":{"positions":"1.5"}})", "mesh.positions", "expected an array", true},
      {R"({"mesh":{"positions":1.5}})", "mesh.positions", "expected an array", true},
      {R"({"mesh":{"warnings":"a"}})", "mesh.warnings", "expected an array", true},
      // ... of elements: protobuf flattens nested arrays and drops null elements.
      {R"({"mesh":{"positions":[1,[2]]}})", "mesh.positions[1]", "got an array", true},
      {R"({"mesh":{"positions":[0,1,null]}})", "mesh.positions[2]", "got null", true},
      {R"({"options":{"auto_corner_angles":[[]]}})", "options.auto_corner_angles[0]",
       "expected a number, got an array", true},
      // syntax: nlohmann's parser; protobuf reads \q as q, and takes trailing commas, single
      // quotes and bare keys.
      {R"({"mesh":{"name":"a\qb"}})", "", "not valid JSON", true},
      {R"({"mesh":{"positions":[1,]}})", "", "not valid JSON", true},
      {R"({"mesh":{}, })", "", "not valid JSON", true},
      {R"({'mesh':{}})", "", "not valid JSON", true},
      {R"({mesh:{}})", "", "not valid JSON", true},
      {R"({"mesh":{}} x)", "", "not valid JSON", false},
      {R"({"mesh":{"positions":[Infinity]}})", "", "not valid JSON", false},
      {R"({"mesh":{"positions":[NaN]}})", "", "not valid JSON", false},
      {R"({"mesh":{"positions":[1e999]}})", "", "not valid JSON", false},
      {R"({"mesh":{"positions":[01]}})", "", "not valid JSON", false},
      {"{\"mesh\":{\"name\":\"\xff\"}}", "", "not valid JSON", false},
      {"\xEF\xBB\xBF{}", "", "byte order mark", false},
      // nlohmann's lexer stops at a NUL byte: what follows must not go unread.
      {std::string("{\"files\":true}\0{\"mesh\":1}", 25), "", "NUL byte, at byte 15", false},
      {"", "", "not valid JSON", false},
      // the root: an object
      {"[]", "", "expected an object (gridshell.v1.DesignRequest), got an array", false},
      {"null", "", "got null", false},
      // fields: each by its proto or JSON name, once. protobuf merges duplicates (last wins).
      {R"({"mesh":{"nmae":"x"}})", "mesh.nmae", "unknown field", false},
      {R"({"options":{"LamellaWidth":1}})", "options.LamellaWidth", "unknown field", false},
      {R"({"design":{}})", "design", "unknown field", false},
      {R"({"mesh":{"name":"a","name":"b"}})", "mesh.name", "given twice", true},
      {R"({"options":{"lamellaWidth":1,"lamella_width":2}})", "options.lamella_width",
       "given twice", true},
      {R"({"mesh":{"name":"a"},"mesh":{"example":"b"}})", "mesh", "given twice", true},
      // integers: integral numbers in range, or decimal strings
      {R"({"mesh":{"indices":[1.5]}})", "mesh.indices[0]", "expected an integer (int32), got 1.5",
       false},
      {R"({"mesh":{"indices":[0,2147483648]}})", "mesh.indices[1]",
       "from -2147483648 to 2147483647", false},
      {R"({"mesh":{"indices":[-2147483649]}})", "mesh.indices[0]", "from -2147483648", false},
      {R"({"mesh":{"indices":["2147483648"]}})", "mesh.indices[0]", "from -2147483648", false},
      {R"({"mesh":{"indices":["1.0"]}})", "mesh.indices[0]", "expected an integer", false},
      {R"({"mesh":{"indices":[true]}})", "mesh.indices[0]", "expected an integer", false},
      {R"({"mesh":{"indices":["+1"]}})", "mesh.indices[0]", "expected an integer", true},
      {R"({"mesh":{"indices":["012"]}})", "mesh.indices[0]", "expected an integer", true},
      {R"({"mesh":{"indices":[1e-400]}})", "mesh.indices[0]", "expected an integer", true},
      // double: a number, or a string holding one or NaN / Infinity / -Infinity
      {R"({"options":{"lamella_width":"abc"}})", "options.lamella_width", "expected a number",
       false},
      {R"({"options":{"lamella_width":"nan"}})", "options.lamella_width", "expected a number",
       false},
      {R"({"options":{"lamella_width":"1e999"}})", "options.lamella_width", "double range", false},
      {R"({"options":{"lamella_width":"0x10"}})", "options.lamella_width", "expected a number",
       true},
      {R"({"options":{"lamella_width":".5"}})", "options.lamella_width", "expected a number", true},
      {R"({"options":{"lamella_width":true}})", "options.lamella_width", "got true", false},
      // string, bytes, message
      {R"({"mesh":{"name":1}})", "mesh.name", "expected a string, got 1", false},
      {R"({"mesh":{"file":"a b"}})", "mesh.file", "base64", false},
      {R"({"mesh":{"file":"AAF="}})", "mesh.file", "base64", false},  // bits beyond the byte
      {R"({"mesh":{"file":"A-_+"}})", "mesh.file", "base64", false},  // both alphabets
      {R"({"mesh":"x"})", "mesh", "expected an object (gridshell.v1.Mesh)", false},
      {R"({"mesh":[]})", "mesh", "got an array", false},
  };
  for (const Refusal& r : refusals) expect_refused(design, r);

  // A field deeper in: design.files of a RunRequest.
  expect_refused(v1::RunRequest(), {R"({"design":{"files":"yes"}})", "design.files",
                                    "expected true or false, got the string", true});
  // Maps: values not null (protobuf reads null as 0), keys once.
  expect_refused(v1::DesignReport(),
                 {R"({"stage_seconds":{"grid":null}})", "stage_seconds[\"grid\"]",
                  "expected a number, got null", true});
  expect_refused(v1::DesignReport(), {R"({"stage_seconds":{"a":1,"a":2}})", "stage_seconds[\"a\"]",
                                      "given twice", false});
  expect_refused(v1::DesignReport(),
                 {R"({"stage_seconds":[]})", "stage_seconds", "expected an object", false});
  // int64: "9223372036854775808" out of range; a fraction the double cannot hold exactly
  // (protobuf reads 9007199254740993.0 as ...992).
  expect_refused(v1::DesignReport(), {R"({"peak_memory_bytes":"9223372036854775808"})",
                                      "peak_memory_bytes", "from -9223372036854775808", false});
  expect_refused(v1::DesignReport(), {R"({"peak_memory_bytes":9007199254740993.0})",
                                      "peak_memory_bytes", "exactly", true});
  // A oneof: one member (protobuf refuses two as well, but takes a null one beside another).
  expect_refused(v1::DesignEvent(), {R"({"progress":{},"result":{}})", "result",
                                     "only one member of oneof event", false});
  expect_refused(v1::DesignEvent(), {R"({"progress":null,"result":{}})", "result",
                                     "only one member of oneof event", true});
  // google.protobuf.ListValue: an array (protobuf takes an object as an empty list).
  expect_refused(v1::Design(), {R"({"planar_corners":{}})", "planar_corners",
                                "expected an array (google.protobuf.ListValue)", true});
  expect_refused(v1::Design(), {R"({"planar_corners":[[0,0],[1,0],[1,1],[0,1]],"patch":{)"
                                R"("vertices":[[0,0,0]],"faces":[[0,1,2]],"corners":[0.5]}})",
                                "patch.corners[0]", "expected an integer", false});
}

TEST(JsonRead, RefusesEveryKindOfTypeMismatchInTheFullTestMessage) {
  const auto all = test_types().all();
  const std::vector<Refusal> refusals{
      // enums: a name or a number (protobuf also takes the number as a string)
      {R"({"color":"BLUE"})", "color", "unknown value \"BLUE\" of enum jsontest.Color", false},
      {R"({"color":"red"})", "color", "unknown value", false},
      {R"({"color":"1"})", "color", "unknown value", true},
      {R"({"color":true})", "color", "expected a value of jsontest.Color", false},
      {R"({"color":2147483648})", "color", "from -2147483648", false},
      {R"({"r_color":["RED",null]})", "r_color[1]", "got null", true},
      // unsigned, 64-bit, float
      {R"({"u32":-1})", "u32", "from 0 to 4294967295", false},
      {R"({"u64":"-0"})", "u64", "expected an integer (uint64)", false},
      {R"({"u64":18446744073709551616})", "u64", "from 0 to 18446744073709551615", false},
      {R"({"s64":"1e3"})", "s64", "expected an integer (sint64)", false},
      {R"({"fl":3.5e38})", "fl", "float range", false},
      {R"({"fl":"3.4028235e38"})", "fl", "float range", false},         // as protobuf's string rule
      {R"({"fl":3.4028235677973366e38})", "fl", "float range", false},  // rounds to infinity
      // maps: keys that read as the key type, written canonically
      {R"({"m_i32":{"x":"a"}})", "m_i32[\"x\"]", "map key of type int32", false},
      {R"({"m_i32":{"01":"a"}})", "m_i32[\"01\"]", "map key of type int32", true},
      {R"({"m_i32":{"-0":"a"}})", "m_i32[\"-0\"]", "map key of type int32", true},
      {R"({"m_i32":{"2147483648":"a"}})", "m_i32[\"2147483648\"]", "map key", false},
      {R"({"m_bool":{"True":1}})", "m_bool[\"True\"]", "map key of type bool", true},
      {R"({"m_bool":{"1":1}})", "m_bool[\"1\"]", "map key of type bool", true},
      {R"({"m_i32":{"1":null}})", "m_i32[\"1\"]", "expected a string, got null", true},
      // oneof, json_name
      {R"({"o_s":"a","o_i32":1})", "o_i32", "only one member of oneof choice", false},
      {R"({"o_s":"a","o_s":"b"})", "o_s", "given twice", false},
      {R"({"customName":1,"camel_case":2})", "camel_case", "given twice", true},
      {R"({"camelCase":1})", "camelCase", "unknown field", false},  // not its JSON name
      {R"({"child":{"":1}})", "child", "empty name", false},
      // well-known types: the JSON kind of the type
      {R"({"st":{"a":1,"a":2}})", "st[\"a\"]", "given twice", false},
      {R"({"st":[]})", "st", "expected an object (google.protobuf.Struct)", false},
      {R"({"lv":{}})", "lv", "expected an array (google.protobuf.ListValue)", true},
      {R"({"w_i32":{"value":5}})", "w_i32", "expected an integer (int32), got an object", true},
      {R"({"w_i32":1.5})", "w_i32", "expected an integer", false},
      {R"({"w_db":"x"})", "w_db", "expected a number", false},
      {R"({"ts":{}})", "ts", "expected a string (google.protobuf.Timestamp)", true},
      {R"({"ts":1})", "ts", "expected a string (google.protobuf.Timestamp)", false},
      {R"({"any":"x"})", "any", "expected an object (google.protobuf.Any)", false},
      // Any: "@type" first, naming a message type; the rest is checked as that type.
      {R"({"any":{"i32":1}})", "any[\"i32\"]", "first member must be \"@type\"", false},
      {R"({"any":{"i32":1,"@type":"type.googleapis.com/jsontest.All"}})", "any[\"i32\"]",
       "first member must be \"@type\"", true},
      {R"({"any":{"@type":"type.googleapis.com/jsontest.All","i32":"x"}})", "any.i32",
       "expected an integer (int32)", false},
      {R"({"any":{"@type":"example.com/jsontest.All"}})", "any[\"@type\"]", "type.googleapis.com",
       false},
      {R"({"any":{"@type":"type.googleapis.com/jsontest.Nope"}})", "any[\"@type\"]",
       "the name of a message type", false},
      {R"({"any":{"@type":null}})", "any[\"@type\"]", "expected a string, got null", false},
      {R"({"any":{"@type":"type.googleapis.com/google.protobuf.Struct","a":1}})", "any[\"a\"]",
       "holds its JSON in \"value\"", false},
      // protobuf 3.21 aborts the process on this one (CHECK failed: !done_): not asked.
      {R"({"any":{"@type":"type.googleapis.com/google.protobuf.Int32Value","l":1,"e":{}}})",
       "any[\"l\"]", "holds its JSON in \"value\"", false, true},
      // null: a repeated Value's null would be read by protobuf as [null]
      {R"({"r_v":null})", "r_v", "expected an array, got null", true},
      {R"({"r_child":[{},null]})", "r_child[1]", "got null", true},
      {R"({"r_child":[{"child":{"r_i32":[1,"x"]}}]})", "r_child[0].child.r_i32[1]",
       "expected an integer (int32), got the string \"x\"", false},
  };
  for (const Refusal& r : refusals) expect_refused(*all, r);
}

TEST(JsonRead, StopsAtTheFirstLevelTooDeep) {
  // 100000 nested arrays where nesting is allowed (a google.protobuf.ListValue): refused at the
  // 33rd level, the first one too deep, naming its path (so the rest was never read). protobuf's
  // parser needs minutes for this text (quadratic in the depth); it is not asked here.
  const int n = 100000;
  const std::string deep =
      R"({"design":{"patch":{"vertices":)" + repeat("[", n) + repeat("]", n) + "}}}";
  v1::SimulateRequest simulate;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    from_json(deep, simulate);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    // Levels: the request, design, patch, vertices' array, then 28 more arrays inside it.
    EXPECT_EQ(e.field(), "design.patch.vertices" + repeat("[0]", 29));
    EXPECT_EQ(e.message(), "too deep: more than 32 levels of nested objects and arrays");
  }
  std::printf("100000 nested arrays refused in %.6f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());

  // The same inside mesh.positions (a repeated double): the first nested array is no number,
  // refused at once by type. protobuf reads this text as an empty list.
  const std::string positions = R"({"mesh":{"positions":)" + repeat("[", n) + repeat("]", n) + "}}";
  v1::DesignRequest design;
  try {
    from_json(positions, design);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "mesh.positions[0]");
    EXPECT_EQ(e.message(), "expected a number, got an array");
  }
  // With a lower limit the depth is found first, at the same place.
  try {
    from_json(positions, design, 3);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "mesh.positions[0]");
    EXPECT_EQ(e.message(), "too deep: more than 3 levels of nested objects and arrays");
  }

  // Objects count as much as arrays; exactly 32 levels pass.
  const auto all = test_types().all();
  expect_read(*all, repeat(R"({"child":)", 31) + "{}" + repeat("}", 31));
  expect_refused(*all, {repeat(R"({"child":)", 32) + "{}" + repeat("}", 32),
                        repeat("child.", 31) + "child", "too deep", true});
  expect_read(*all, R"({"v":)" + repeat("[", 31) + repeat("]", 31) + "}");
  expect_refused(*all, {R"({"st":)" + repeat(R"({"a":)", 32) + "1" + repeat("}", 33),
                        "st" + repeat("[\"a\"]", 31), "too deep", true});
}

TEST(JsonRead, SkipsUnknownFieldsOnlyWhenAsked) {
  const auto all = test_types().all();
  const std::string text = R"({"i32":1,"later":{"x":[1,{"y":null}]},"r_color":["RED","PURPLE"]})";
  expect_refused(*all, {text, "later", "unknown field of jsontest.All", false});
  // As protobuf's ignore_unknown_fields: the member and unknown enum names are skipped ...
  const auto read = expect_read(*all, text, UnknownFields::Skip);
  EXPECT_EQ(read->GetReflection()->GetInt32(*read, read->GetDescriptor()->FindFieldByName("i32")),
            1);
  // ... but known fields are still checked, and so is the depth inside the skipped value.
  expect_refused(*all, {R"({"later":1,"i32":"x"})", "i32", "expected an integer", false},
                 kJsonMaxDepth, UnknownFields::Skip);
  expect_refused(*all, {R"({"":1})", "", "empty name", false}, kJsonMaxDepth, UnknownFields::Skip);
  expect_refused(*all,
                 {R"({"later":)" + repeat("[", 40) + repeat("]", 40) + "}",
                  "later" + repeat("[0]", 31), "too deep", true},
                 kJsonMaxDepth, UnknownFields::Skip);
}

// The daemon's text limit, checked in the pass before protobuf copies the string: string fields
// (repeated ones by element) longer than the limit are refused naming the field; bytes fields
// (whole mesh files) and strings exactly at the limit are not.
TEST(JsonRead, RefusesStringsLongerThanTheLimitWhenGiven) {
  const auto read = [](const std::string& json, std::size_t limit) {
    v1::DesignRequest request;
    from_json(json, request, kJsonMaxDepth, UnknownFields::Refuse, limit);
    return request;
  };
  const std::string name(1025, 'n');
  EXPECT_EQ(read(R"({"mesh":{"name":")" + name + R"("}})", 0).mesh().name(), name);  // no limit
  EXPECT_EQ(read(R"({"mesh":{"name":")" + name.substr(1) + R"("}})", 1024).mesh().name().size(),
            1024u);
  try {
    read(R"({"mesh":{"name":")" + name + R"("}})", 1024);
    ADD_FAILURE() << "accepted a 1025-byte name";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "mesh.name");
    EXPECT_EQ(e.message(), "too long: 1025 bytes, at most 1024");
  }
  try {
    read(R"({"mesh":{"warnings":["ok",")" + name + R"("]}})", 1024);
    ADD_FAILURE() << "accepted a 1025-byte warning";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.field(), "mesh.warnings[1]");
  }
  const std::string file(4000, 'A');  // base64 of 3000 bytes: a bytes field, not text
  EXPECT_EQ(read(R"({"mesh":{"file":")" + file + R"("}})", 1024).mesh().file().size(), 3000u);
}

// ---- Accepted ----------------------------------------------------------------------------------

TEST(JsonRead, ReadsRealRequestsAndFilesBack) {
  v1::DesignRequest design = example_request("double-vault");
  design.mutable_options()->set_alpha("70deg");
  design.mutable_options()->set_members_u(4);
  design.mutable_options()->set_eta_max(1.01);
  design.mutable_options()->add_auto_corner_angles(0.5);
  design.set_files(true);
  expect_round_trip(design);

  v1::PatchRequest patch;
  *patch.mutable_mesh() = design.mesh();
  patch.mutable_mesh()->set_file(std::string("v 0 0 0\n\0\xff", 10));
  patch.mutable_mesh()->set_format("obj");
  patch.mutable_options()->set_max_smoothing_iterations(0);
  expect_round_trip(patch);

  v1::GeodesicRequest geodesic;
  geodesic.mutable_mesh()->set_example("sphere");
  geodesic.set_source(3);
  geodesic.set_distances(true);
  expect_round_trip(geodesic);

  // design.json and report.json of a real design (ListValues, maps, int64), then a simulation
  // request and a run request holding them.
  const v1::DesignResult result = run_design(example_request("waves-bump"), {}, {1});
  expect_round_trip(result.design());
  expect_round_trip(result.report());
  v1::SimulateRequest simulate;
  *simulate.mutable_design() = result.design();
  simulate.mutable_options()->set_notches("both");
  simulate.mutable_options()->set_anchor_goal(0.001);
  expect_round_trip(simulate);
  v1::RunRequest run;
  *run.mutable_design() = design;
  run.mutable_simulation()->set_max_iterations(10);
  expect_round_trip(run);
  v1::DesignEvent event;
  event.mutable_progress()->set_stage("queued");
  expect_round_trip(event);
}

TEST(JsonRead, ReadsWhatTheMappingAllows) {
  const v1::DesignRequest design;
  // null: a field's default (a message, a scalar, a repeated field)
  expect_read(design, R"({"mesh":null,"files":null,"options":{"eta_max":null,"alpha":null}})");
  expect_read(design, R"({"mesh":{"positions":null,"warnings":null}})");
  // Non-finite doubles as strings, numbers as strings, integers written as whole doubles.
  const auto mesh = expect_read(
      design, R"({"mesh":{"positions":["NaN","Infinity","-Infinity","1.5","-0",1e-400,1E2],)"
              R"("indices":["12",2.0,1e2,-0,2147483647,-2147483648]}})");
  const auto& positions = static_cast<const v1::DesignRequest&>(*mesh).mesh().positions();
  ASSERT_EQ(positions.size(), 7);
  EXPECT_TRUE(std::isnan(positions[0]));
  EXPECT_EQ(positions[1], std::numeric_limits<double>::infinity());
  EXPECT_EQ(positions[2], -std::numeric_limits<double>::infinity());
  EXPECT_EQ(positions[3], 1.5);
  const auto& indices = static_cast<const v1::DesignRequest&>(*mesh).mesh().indices();
  EXPECT_EQ(std::vector<int>(indices.begin(), indices.end()),
            (std::vector<int>{12, 2, 100, 0, 2147483647, -2147483648}));
  // int64 as a string or a number; JSON names; UTF-8 and escapes; base64 of both alphabets.
  expect_read(v1::DesignReport(),
              R"({"peakMemoryBytes":"9223372036854775807","stage_seconds":{"a":1,"b":"2"}})");
  expect_read(v1::DesignReport(), R"({"peak_memory_bytes":-9223372036854775808})");
  expect_read(design, R"({"mesh":{"name":"\u00e9\ud83d\ude00 \"q\" \u0000 é","file":"-_8="}})");
  expect_read(design, R"({"mesh":{"file":"+/8="}})");
  expect_read(design, R"({"mesh":{"file":"AAE"}})");
  expect_read(v1::DesignEvent(), R"({"progress":{"fraction":0.5}})");

  const auto all = test_types().all();
  expect_read(*all, R"({"color":"RED","r_color":["GREEN",1,7],"u64":"18446744073709551615",)"
                    R"("i64":-9223372036854775808,"fl":3.4028235e38,"s64":"-12","b":false})");
  expect_read(*all, R"({"m_i32":{"-5":"a","0":"b"},"m_bool":{"true":1,"false":2},)"
                    R"("customName":3,"o_i32":4})");
  expect_read(*all,
              R"({"st":{"a":[1,null,{"b":"c"}],"":true},"v":null,"lv":[1,[2],{"x":null}],)"
              R"("r_v":[null,1,"a",[],{}],"m_value":{"n":null},"w_i32":"5","w_db":"NaN",)"
              R"("ts":"2020-01-01T00:00:00Z",)"
              R"("any":{"@type":"type.googleapis.com/google.protobuf.Int32Value","value":5}})");
  expect_read(*all, R"({"any":{},"r_child":[{},{"i32":1}],"child":{"child":null}})");
  expect_read(*all, R"({"any":{"@type":"type.googleapis.com/google.protobuf.Struct",)"
                    R"("value":{"a":[1,{"@type":"x"}]}}})");
  expect_read(*all, R"({"any":{"@type":"type.googleapis.com/jsontest.All","i32":5,"any":{)"
                    R"("@type":"type.googleapis.com/google.protobuf.Int32Value","value":3}}})");
  expect_read(*all,
              R"({"any":{"@type":"type.googleapis.com/google.protobuf.Value","value":null}})");
  expect_read(*all, R"({"any":{"@type":"type.googleapis.com/google.protobuf.Empty"}})");
}

TEST(JsonRead, TimesALargeRequest) {
  // A mesh of 250k triangles as to_json writes it (about 10 MB), read by from_json and by
  // protobuf's parser alone. Times printed, not asserted (docs/testing.md).
  v1::DesignRequest request;
  *request.mutable_mesh() = to_proto(testing::bump(354), "bump");
  for (int v : {0, 354, 355 * 355 - 1, 355 * 354}) request.mutable_corners()->add_vertices(v);
  ASSERT_GE(request.mesh().indices_size(), 3 * 250000);
  const std::string text = to_json(request, false);
  auto seconds = [](auto since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
  };
  v1::DesignRequest ours, library;
  const auto t0 = std::chrono::steady_clock::now();
  from_json(text, ours);
  const double t_ours = seconds(t0);
  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_TRUE(protobuf_reads(text, library));
  const double t_library = seconds(t1);
  EXPECT_TRUE(pb::util::MessageDifferencer::Equals(request, ours));
  std::printf("%zu bytes, %d triangles: from_json %.3f s, JsonStringToMessage alone %.3f s\n",
              text.size(), request.mesh().indices_size() / 3, t_ours, t_library);
}

}  // namespace
}  // namespace gridshell
