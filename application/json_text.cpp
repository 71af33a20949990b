// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — messages as JSON text (the format of every JSON file gridshell writes).
//
// protobuf's own printer (util::MessageToJsonString / BinaryToJsonString) serializes the message,
// parses it again through a type resolver and writes through several stream layers: on a
// 59k-vertex design (design.json, 11 MB, about a million numbers) that took 1.23 s, 11 % of the
// whole `gridshell design`, and 0.31 s of a 15k design (docs/decisions.md, issue 17). This writer
// walks the message by reflection and writes numbers with std::to_chars (shortest text that
// reads back to the same double): the same JSON mapping (proto field names, every primitive
// field, 64-bit integers as strings, enums by name, NaN and infinities as strings, Struct /
// Value / ListValue and the wrappers as their JSON values, map keys sorted). Messages with
// other well-known types (Any, Timestamp, Duration, FieldMask) go to protobuf's printer. The test
// (tests/application/test_json_text.cpp) reads its output back with protobuf's JSON parser and
// compares the message field by field.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/reflection.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/type_resolver_util.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "gridshell/application/files.h"

namespace gridshell {
namespace {

namespace pb = google::protobuf;
using FD = pb::FieldDescriptor;

class JsonText {
 public:
  explicit JsonText(bool pretty) : pretty_(pretty) { out_.reserve(1 << 16); }
  std::string take() { return std::move(out_); }

  /// false if the message holds a type this writer leaves to protobuf's printer.
  static bool supported(const pb::Descriptor* type, std::vector<const pb::Descriptor*>& seen) {
    if (std::find(seen.begin(), seen.end(), type) != seen.end()) return true;
    seen.push_back(type);
    const std::string& name = type->full_name();
    if (name == "google.protobuf.Any" || name == "google.protobuf.Timestamp" ||
        name == "google.protobuf.Duration" || name == "google.protobuf.FieldMask" ||
        name == "google.protobuf.Empty")
      return false;
    for (int i = 0; i < type->field_count(); ++i)
      if (type->field(i)->cpp_type() == FD::CPPTYPE_MESSAGE &&
          !supported(type->field(i)->message_type(), seen))
        return false;
    return true;
  }

  void message(const pb::Message& m, int depth) {
    const pb::Descriptor* type = m.GetDescriptor();
    const std::string& name = type->full_name();
    if (name == "google.protobuf.Value") return value(m, depth);
    if (name == "google.protobuf.ListValue") return list_value(m, depth);
    if (name == "google.protobuf.Struct") return struct_value(m, depth);
    if (type->well_known_type() >= pb::Descriptor::WELLKNOWNTYPE_DOUBLEVALUE &&
        type->well_known_type() <= pb::Descriptor::WELLKNOWNTYPE_BYTESVALUE)
      return scalar(m, type->field(0), -1, depth);
    const pb::Reflection* r = m.GetReflection();
    out_ += '{';
    bool first = true;
    for (int i = 0; i < type->field_count(); ++i) {
      const FD* f = type->field(i);
      if (f->is_repeated()) {
        // printed also when empty ([] / {}), as protobuf does with always_print_primitive_fields
      } else if (f->cpp_type() == FD::CPPTYPE_MESSAGE || f->has_presence()) {
        if (!r->HasField(m, f)) continue;
      }
      open_member(first, depth + 1);
      key(f->name());
      if (f->is_map())
        map(m, f, depth + 1);
      else if (f->is_repeated())
        repeated(m, f, depth + 1);
      else
        scalar(m, f, -1, depth + 1);
    }
    close(first, depth, '}');
  }

 private:
  void newline(int depth) {
    if (!pretty_) return;
    out_ += '\n';
    out_.append(static_cast<std::size_t>(depth), ' ');
  }
  void open_member(bool& first, int depth) {
    if (!first) out_ += ',';
    first = false;
    newline(depth);
  }
  void close(bool first, int depth, char bracket) {
    if (!first) newline(depth);
    out_ += bracket;
  }
  void key(const std::string& k) {
    string(k);
    out_ += pretty_ ? ": " : ":";
  }

  void string(const std::string& s) {
    out_ += '"';
    for (const char ch : s) {
      const auto c = static_cast<unsigned char>(ch);
      switch (c) {
        case '"':
          out_ += "\\\"";
          break;
        case '\\':
          out_ += "\\\\";
          break;
        case '\n':
          out_ += "\\n";
          break;
        case '\r':
          out_ += "\\r";
          break;
        case '\t':
          out_ += "\\t";
          break;
        case '\b':
          out_ += "\\b";
          break;
        case '\f':
          out_ += "\\f";
          break;
        default:
          if (c < 0x20) {
            static const char* hex = "0123456789abcdef";
            out_ += "\\u00";
            out_ += hex[c >> 4];
            out_ += hex[c & 15];
          } else {
            out_ += ch;
          }
      }
    }
    out_ += '"';
  }

  template <class T>
  void integer(T v, bool quoted) {
    char buffer[32];
    const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
    if (quoted) out_ += '"';
    out_.append(buffer, end);
    if (quoted) out_ += '"';
  }

  template <class T>
  void real(T v) {
    if (std::isnan(v)) {
      out_ += "\"NaN\"";
    } else if (std::isinf(v)) {
      out_ += v > 0 ? "\"Infinity\"" : "\"-Infinity\"";
    } else {
      char buffer[64];
      const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
      out_.append(buffer, end);
    }
  }

  static std::string base64(const std::string& bytes) {
    static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
      const unsigned n = (static_cast<unsigned char>(bytes[i]) << 16) |
                         (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                         static_cast<unsigned char>(bytes[i + 2]);
      for (int s : {18, 12, 6, 0}) out += table[(n >> s) & 63];
    }
    if (i < bytes.size()) {
      unsigned n = static_cast<unsigned char>(bytes[i]) << 16;
      if (i + 1 < bytes.size()) n |= static_cast<unsigned char>(bytes[i + 1]) << 8;
      out += table[(n >> 18) & 63];
      out += table[(n >> 12) & 63];
      out += i + 1 < bytes.size() ? table[(n >> 6) & 63] : '=';
      out += '=';
    }
    return out;
  }

  /// Field f of m (element `index` of a repeated field, or -1 for a singular one).
  void scalar(const pb::Message& m, const FD* f, int index, int depth) {
    const pb::Reflection* r = m.GetReflection();
    const bool rep = index >= 0;
    switch (f->cpp_type()) {
      case FD::CPPTYPE_DOUBLE:
        return real(rep ? r->GetRepeatedDouble(m, f, index) : r->GetDouble(m, f));
      case FD::CPPTYPE_FLOAT:
        return real(rep ? r->GetRepeatedFloat(m, f, index) : r->GetFloat(m, f));
      case FD::CPPTYPE_INT32:
        return integer(rep ? r->GetRepeatedInt32(m, f, index) : r->GetInt32(m, f), false);
      case FD::CPPTYPE_UINT32:
        return integer(rep ? r->GetRepeatedUInt32(m, f, index) : r->GetUInt32(m, f), false);
      case FD::CPPTYPE_INT64:
        return integer(rep ? r->GetRepeatedInt64(m, f, index) : r->GetInt64(m, f), true);
      case FD::CPPTYPE_UINT64:
        return integer(rep ? r->GetRepeatedUInt64(m, f, index) : r->GetUInt64(m, f), true);
      case FD::CPPTYPE_BOOL:
        out_ += (rep ? r->GetRepeatedBool(m, f, index) : r->GetBool(m, f)) ? "true" : "false";
        return;
      case FD::CPPTYPE_ENUM: {
        const int number = rep ? r->GetRepeatedEnumValue(m, f, index) : r->GetEnumValue(m, f);
        if (const pb::EnumValueDescriptor* e = f->enum_type()->FindValueByNumber(number))
          string(e->name());
        else
          integer(number, false);
        return;
      }
      case FD::CPPTYPE_STRING: {
        std::string scratch;
        const std::string& s = rep ? r->GetRepeatedStringReference(m, f, index, &scratch)
                                   : r->GetStringReference(m, f, &scratch);
        if (f->type() == FD::TYPE_BYTES)
          string(base64(s));
        else
          string(s);
        return;
      }
      case FD::CPPTYPE_MESSAGE:
        return message(rep ? r->GetRepeatedMessage(m, f, index) : r->GetMessage(m, f), depth);
    }
  }

  void repeated(const pb::Message& m, const FD* f, int depth) {
    const int n = m.GetReflection()->FieldSize(m, f);
    out_ += '[';
    bool first = true;
    for (int i = 0; i < n; ++i) {
      open_member(first, depth + 1);
      scalar(m, f, i, depth + 1);
    }
    close(first, depth, ']');
  }

  /// A map field: entries sorted by key (protobuf's deterministic order: numeric for integer
  /// keys, bytewise for strings).
  void map(const pb::Message& m, const FD* f, int depth) {
    const pb::Reflection* r = m.GetReflection();
    const int n = r->FieldSize(m, f);
    std::vector<const pb::Message*> entries;
    for (int i = 0; i < n; ++i) entries.push_back(&r->GetRepeatedMessage(m, f, i));
    const FD* key_field = f->message_type()->map_key();
    const FD* value_field = f->message_type()->map_value();
    auto key_text = [&](const pb::Message& e) {
      const pb::Reflection* er = e.GetReflection();
      switch (key_field->cpp_type()) {
        case FD::CPPTYPE_STRING:
          return er->GetString(e, key_field);
        case FD::CPPTYPE_INT32:
          return std::to_string(er->GetInt32(e, key_field));
        case FD::CPPTYPE_UINT32:
          return std::to_string(er->GetUInt32(e, key_field));
        case FD::CPPTYPE_INT64:
          return std::to_string(er->GetInt64(e, key_field));
        case FD::CPPTYPE_UINT64:
          return std::to_string(er->GetUInt64(e, key_field));
        case FD::CPPTYPE_BOOL:
          return std::string(er->GetBool(e, key_field) ? "true" : "false");
        default:
          throw std::runtime_error("JSON conversion: unsupported map key type");
      }
    };
    auto numeric = [&](const pb::Message& e) -> long double {
      const pb::Reflection* er = e.GetReflection();
      switch (key_field->cpp_type()) {
        case FD::CPPTYPE_INT32:
          return er->GetInt32(e, key_field);
        case FD::CPPTYPE_UINT32:
          return er->GetUInt32(e, key_field);
        case FD::CPPTYPE_INT64:
          return er->GetInt64(e, key_field);
        case FD::CPPTYPE_UINT64:
          return er->GetUInt64(e, key_field);
        case FD::CPPTYPE_BOOL:
          return er->GetBool(e, key_field);
        default:
          return 0;
      }
    };
    const bool by_text = key_field->cpp_type() == FD::CPPTYPE_STRING;
    std::stable_sort(entries.begin(), entries.end(),
                     [&](const pb::Message* a, const pb::Message* b) {
                       return by_text ? key_text(*a) < key_text(*b) : numeric(*a) < numeric(*b);
                     });
    out_ += '{';
    bool first = true;
    for (const pb::Message* e : entries) {
      open_member(first, depth + 1);
      key(key_text(*e));
      scalar(*e, value_field, -1, depth + 1);
    }
    close(first, depth, '}');
  }

  void value(const pb::Message& m, int depth) {
    const pb::Descriptor* type = m.GetDescriptor();
    const pb::Reflection* r = m.GetReflection();
    const pb::OneofDescriptor* kind = type->oneof_decl(0);
    const FD* f = r->GetOneofFieldDescriptor(m, kind);
    if (f == nullptr || f->name() == "null_value") {
      out_ += "null";
    } else if (f->name() == "number_value") {
      const double v = r->GetDouble(m, f);
      if (!std::isfinite(v))
        throw std::runtime_error("JSON conversion: a Value holds a number that is not finite");
      real(v);
    } else if (f->name() == "string_value") {
      string(r->GetString(m, f));
    } else if (f->name() == "bool_value") {
      out_ += r->GetBool(m, f) ? "true" : "false";
    } else {
      message(r->GetMessage(m, f), depth);  // struct_value / list_value
    }
  }

  void list_value(const pb::Message& m, int depth) {
    const FD* values = m.GetDescriptor()->FindFieldByName("values");
    repeated(m, values, depth);
  }

  void struct_value(const pb::Message& m, int depth) {
    map(m, m.GetDescriptor()->FindFieldByName("fields"), depth);
  }

  bool pretty_;
  std::string out_;
};

std::string library_json(const pb::Message& message, bool pretty) {
  pb::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.add_whitespace = pretty;
  options.always_print_primitive_fields = true;
  // MessageToJsonString serializes the message first without the deterministic flag, so maps
  // (energies, stage_seconds) came out in the hash order of the process: a file's bytes changed
  // from run to run. The same conversion over a deterministic serialization sorts map keys.
  std::string binary;
  {
    pb::io::StringOutputStream stream(&binary);
    pb::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    if (!message.SerializeToCodedStream(&coded))
      throw std::runtime_error("JSON conversion failed: cannot serialize " + message.GetTypeName());
  }
  static const std::unique_ptr<pb::util::TypeResolver> resolver(
      pb::util::NewTypeResolverForDescriptorPool("type.googleapis.com",
                                                 pb::DescriptorPool::generated_pool()));
  std::string json;
  const auto status = pb::util::BinaryToJsonString(
      resolver.get(), "type.googleapis.com/" + message.GetDescriptor()->full_name(), binary, &json,
      options);
  if (!status.ok()) throw std::runtime_error("JSON conversion failed: " + status.ToString());
  return json;
}

}  // namespace

std::string to_json(const google::protobuf::Message& message, bool pretty) {
  std::vector<const pb::Descriptor*> seen;
  if (!JsonText::supported(message.GetDescriptor(), seen)) return library_json(message, pretty);
  JsonText text(pretty);
  text.message(message, 0);
  return text.take();
}

std::string to_json_library(const google::protobuf::Message& message, bool pretty) {
  return library_json(message, pretty);
}

}  // namespace gridshell
