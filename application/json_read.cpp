// SPDX-License-Identifier: GPL-3.0-or-later
// gridshell — reading protobuf's JSON mapping strictly (from_json, files.h).
//
// protobuf's parser (util::JsonStringToMessage, 3.21) is lenient: "yes" and "1" for a bool, a
// scalar where a list belongs, nested arrays flattened into a repeated double (100k of them into
// an empty list, after minutes: its time grows with the square of the depth), null elements
// dropped, duplicate members merged, an unknown escape read as the letter, trailing commas, single
// quotes and bare keys. from_json first checks the text against the message's descriptors in one
// pass of nlohmann's SAX parser (strict RFC 8259 syntax, UTF-8 checked; no NUL byte, no byte order
// mark): no DOM, no recursion — an explicit stack of frames, one per open object or array, with
// what its next value must be. Paths are built only when an error is reported. Only then does
// protobuf's parser fill the message, so both agree on every value that passes. The pass costs
// about what nlohmann's parser alone does (0.10 s for an 11.6 MB mesh; protobuf's 0.28 s).
//
// What the pass allows, per field type (protobuf.dev/programming-guides/proto3/#json):
//  - bool: true / false. Integers: a JSON number with an integral value in the type's range (2.0
//    and 1e2 too, as protobuf reads them, when the double holds the integer exactly), or a string
//    holding a decimal integer ("-12"; no "+", no leading zeros, no exponent).
//  - float, double: a number (floats within float range), "NaN", "Infinity", "-Infinity", or a
//    string holding a JSON number.
//  - string: a string. bytes: base64, standard or URL-safe, padded or not, canonical trailing bits.
//  - enum: a value's name or an integer (open enums keep unknown numbers).
//  - message: an object. repeated: an array of element values. map: an object whose keys read as
//    the key type ("true"/"false" for bool keys, decimal integers for integer keys), no key twice.
//  - null: the default of any field (not inside an array, not as a map value), except where
//    google.protobuf.Value (or NullValue) takes null as a value. Not for a repeated Value field,
//    which protobuf would read as [null].
//  - well-known types: Struct an object, ListValue an array, Value anything (their content plain
//    JSON, no member twice), the wrappers their primitive, Timestamp / Duration / FieldMask a
//    string (protobuf checks its syntax), Any an object whose first member is "@type" naming a
//    message type of the pool, the rest checked as that type.
//  - a field by its proto name or its JSON name, once (one spelling, one member of a oneof).
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <unordered_set>
#include <vector>

#include "gridshell/application/files.h"
#include "gridshell/foundation/errors.h"

namespace gridshell {
namespace {

namespace pb = google::protobuf;
using FD = pb::FieldDescriptor;
using json = nlohmann::json;

// ---- Text helpers ------------------------------------------------------------------------------

/// Length of the UTF-8 sequence starting at s[i], or 0 if it is not a valid one.
std::size_t utf8_length(std::string_view s, std::size_t i) {
  const auto c = static_cast<unsigned char>(s[i]);
  if (c < 0x80) return 1;
  std::size_t n = c >= 0xF0 && c <= 0xF4 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c < 0xE0 ? 2 : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if ((static_cast<unsigned char>(s[i + k]) & 0xC0) != 0x80) return 0;
  return n;
}

/// `s` between double quotes, JSON-escaped, cut to about `limit` bytes ("..." marks a cut);
/// bytes that are not UTF-8 become \xNN. For messages: never the whole of a 30 MB string.
std::string quote_text(std::string_view s, std::size_t limit = 40) {
  std::string out = "\"";
  std::size_t i = 0;
  while (i < s.size()) {
    if (i >= limit) {
      out += "...";
      break;
    }
    const auto c = static_cast<unsigned char>(s[i]);
    const std::size_t n = utf8_length(s, i);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || n == 0) {
      static const char* hex = "0123456789abcdef";
      out += c < 0x20 ? "\\u00" : "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    } else {
      out.append(s.substr(i, n));
      i += n;
      continue;
    }
    ++i;
  }
  return out + '"';
}

/// A message of nlohmann's (which quotes what it last read) made printable: invalid UTF-8
/// escaped, a long quotation cut to its end.
std::string printable(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    const std::size_t n = utf8_length(s, i);
    if (n == 0) {
      static const char* hex = "0123456789abcdef";
      const auto c = static_cast<unsigned char>(s[i]);
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
      ++i;
    } else {
      out.append(s.substr(i, n));
      i += n;
    }
  }
  constexpr std::size_t kKeep = 80;
  const std::size_t open = out.find("last read: '");
  if (open != std::string::npos) {
    const std::size_t begin = open + 12;
    const std::size_t end = out.rfind('\'');
    if (end != std::string::npos && end > begin + kKeep) {
      std::size_t cut = end - kKeep;
      while (cut < end && (static_cast<unsigned char>(out[cut]) & 0xC0) == 0x80) ++cut;
      out.replace(begin, cut - begin, "...");
    }
  }
  return out;
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }

/// Exponents are read up to this much: beyond the length of any text, so that comparing one with
/// a count of digits stays exact.
constexpr long long kExponentCap = 1'000'000'000'000LL;

/// True if `s` is a number in JSON's syntax: -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?
bool json_number_syntax(std::string_view s) {
  std::size_t i = 0;
  if (i < s.size() && s[i] == '-') ++i;
  if (i >= s.size() || !is_digit(s[i])) return false;
  if (s[i] == '0') {
    ++i;
  } else {
    while (i < s.size() && is_digit(s[i])) ++i;
  }
  if (i < s.size() && s[i] == '.') {
    ++i;
    if (i >= s.size() || !is_digit(s[i])) return false;
    while (i < s.size() && is_digit(s[i])) ++i;
  }
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (i >= s.size() || !is_digit(s[i])) return false;
    while (i < s.size() && is_digit(s[i])) ++i;
  }
  return i == s.size();
}

/// An integer read exactly: its sign and magnitude (capped: `too_big` above 10^21).
struct ExactInteger {
  bool integral = false;  ///< the value is an integer
  bool too_big = false;   ///< |value| > 10^21, beyond every integer type
  bool negative = false;
  unsigned __int128 magnitude = 0;
};

/// The exact value of a number in JSON syntax (as nlohmann has already checked it): integral or
/// not, and if so its magnitude. Decimal arithmetic on the text, so 1e-400 is not an integer and
/// 1.00000000000000001 is not 1.
ExactInteger exact_integer(std::string_view s) {
  ExactInteger r;
  std::size_t i = 0;
  if (i < s.size() && s[i] == '-') {
    r.negative = true;
    ++i;
  }
  // Significant digits (without leading zeros) and the power of ten of the last one.
  std::string_view int_part, frac_part;
  const std::size_t int_begin = i;
  while (i < s.size() && is_digit(s[i])) ++i;
  int_part = s.substr(int_begin, i - int_begin);
  if (i < s.size() && s[i] == '.') {
    const std::size_t frac_begin = ++i;
    while (i < s.size() && is_digit(s[i])) ++i;
    frac_part = s.substr(frac_begin, i - frac_begin);
  }
  long long exponent = 0;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    bool negative_exponent = false;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) negative_exponent = s[i++] == '-';
    for (; i < s.size() && is_digit(s[i]); ++i)
      if (exponent < kExponentCap) exponent = exponent * 10 + (s[i] - '0');
    if (negative_exponent) exponent = -exponent;
  }
  // digits = int_part + frac_part, value = digits * 10^(exponent - frac_part.size()).
  std::string digits;
  digits.reserve(int_part.size() + frac_part.size());
  digits.append(int_part).append(frac_part);
  std::size_t first = digits.find_first_not_of('0');
  if (first == std::string::npos) {  // zero
    r.integral = true;
    return r;
  }
  std::size_t last = digits.find_last_not_of('0');
  long long power = exponent - static_cast<long long>(frac_part.size()) +
                    static_cast<long long>(digits.size() - 1 - last);
  if (power < 0) return r;  // a nonzero digit after the decimal point
  r.integral = true;
  const long long count = static_cast<long long>(last - first + 1) + power;  // decimal digits
  if (count > 21) {
    r.too_big = true;
    return r;
  }
  for (std::size_t k = first; k <= last; ++k) r.magnitude = r.magnitude * 10 + (digits[k] - '0');
  for (long long k = 0; k < power; ++k) r.magnitude *= 10;
  return r;
}

/// Base64 as protobuf's parser takes it: the standard or the URL-safe alphabet (not both), no
/// whitespace, padding absent or complete, and canonical (zero) bits at the end.
bool valid_base64(std::string_view s) {
  std::size_t n = s.size();
  std::size_t padding = 0;
  while (n > 0 && s[n - 1] == '=') {
    --n;
    ++padding;
  }
  if (padding > 0 && (s.size() % 4 != 0 || padding > 2)) return false;
  if (n % 4 == 1) return false;
  bool standard = false, url_safe = false;
  int last = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const char c = s[i];
    if (c >= 'A' && c <= 'Z') {
      last = c - 'A';
    } else if (c >= 'a' && c <= 'z') {
      last = c - 'a' + 26;
    } else if (c >= '0' && c <= '9') {
      last = c - '0' + 52;
    } else if (c == '+' || c == '/') {
      standard = true;
      last = c == '+' ? 62 : 63;
    } else if (c == '-' || c == '_') {
      url_safe = true;
      last = c == '-' ? 62 : 63;
    } else {
      return false;
    }
  }
  if (standard && url_safe) return false;
  if (n % 4 == 2) return (last & 0xF) == 0;
  if (n % 4 == 3) return (last & 0x3) == 0;
  return true;
}

// ---- What a value must be ----------------------------------------------------------------------

enum class Type : std::uint8_t {
  Bool,
  Int32,
  UInt32,
  Int64,
  UInt64,
  Float,
  Double,
  String,
  Bytes,
  Enum,
  Message,    // an object with the message's fields
  Struct,     // google.protobuf.Struct: an object of anything
  Value,      // google.protobuf.Value: anything
  ListValue,  // google.protobuf.ListValue: an array of anything
  StringWkt,  // Timestamp, Duration, FieldMask: a string protobuf reads
  Any,        // google.protobuf.Any: an object with "@type"
  Generic,    // any JSON value (inside Struct, Value, ListValue, Any)
  Skip,       // the value of an unknown field that is ignored
};

/// Where the value stands, which decides what null means and whether an array is the field's.
enum class Shape : std::uint8_t {
  Field,     // a singular field: null is its default
  Repeated,  // the whole of a repeated field: an array, or null
  Map,       // the whole of a map field: an object, or null
  Element,   // an element of a repeated field: null only where it is a value
  MapValue,  // a map's value: null only where it is a value
  Root,      // the message itself
};

struct Slot {
  Type type = Type::Generic;
  Shape shape = Shape::Field;
  bool null_is_value = false;               // google.protobuf.Value, NullValue
  const FD* field = nullptr;                // the field (a wrapper's: its `value` field)
  const pb::Descriptor* message = nullptr;  // message and well-known types
};

void classify_message(Slot& s, const pb::Descriptor* d) {
  s.message = d;
  switch (d->well_known_type()) {
    case pb::Descriptor::WELLKNOWNTYPE_DOUBLEVALUE:
    case pb::Descriptor::WELLKNOWNTYPE_FLOATVALUE:
    case pb::Descriptor::WELLKNOWNTYPE_INT64VALUE:
    case pb::Descriptor::WELLKNOWNTYPE_UINT64VALUE:
    case pb::Descriptor::WELLKNOWNTYPE_INT32VALUE:
    case pb::Descriptor::WELLKNOWNTYPE_UINT32VALUE:
    case pb::Descriptor::WELLKNOWNTYPE_STRINGVALUE:
    case pb::Descriptor::WELLKNOWNTYPE_BYTESVALUE:
    case pb::Descriptor::WELLKNOWNTYPE_BOOLVALUE: {
      const FD* value = d->field(0);
      switch (value->cpp_type()) {
        case FD::CPPTYPE_DOUBLE:
          s.type = Type::Double;
          break;
        case FD::CPPTYPE_FLOAT:
          s.type = Type::Float;
          break;
        case FD::CPPTYPE_INT64:
          s.type = Type::Int64;
          break;
        case FD::CPPTYPE_UINT64:
          s.type = Type::UInt64;
          break;
        case FD::CPPTYPE_INT32:
          s.type = Type::Int32;
          break;
        case FD::CPPTYPE_UINT32:
          s.type = Type::UInt32;
          break;
        case FD::CPPTYPE_BOOL:
          s.type = Type::Bool;
          break;
        default:
          s.type = value->type() == FD::TYPE_BYTES ? Type::Bytes : Type::String;
      }
      s.field = value;
      return;
    }
    case pb::Descriptor::WELLKNOWNTYPE_STRUCT:
      s.type = Type::Struct;
      return;
    case pb::Descriptor::WELLKNOWNTYPE_VALUE:
      s.type = Type::Value;
      s.null_is_value = true;
      return;
    case pb::Descriptor::WELLKNOWNTYPE_LISTVALUE:
      s.type = Type::ListValue;
      return;
    case pb::Descriptor::WELLKNOWNTYPE_TIMESTAMP:
    case pb::Descriptor::WELLKNOWNTYPE_DURATION:
    case pb::Descriptor::WELLKNOWNTYPE_FIELDMASK:
      s.type = Type::StringWkt;
      return;
    case pb::Descriptor::WELLKNOWNTYPE_ANY:
      s.type = Type::Any;
      return;
    default:
      s.type = Type::Message;
  }
}

/// What a value of field `f` (one element of it, if repeated) must be.
Slot slot_of(const FD* f, Shape shape) {
  Slot s;
  s.shape = shape;
  s.field = f;
  switch (f->cpp_type()) {
    case FD::CPPTYPE_BOOL:
      s.type = Type::Bool;
      break;
    case FD::CPPTYPE_INT32:
      s.type = Type::Int32;
      break;
    case FD::CPPTYPE_UINT32:
      s.type = Type::UInt32;
      break;
    case FD::CPPTYPE_INT64:
      s.type = Type::Int64;
      break;
    case FD::CPPTYPE_UINT64:
      s.type = Type::UInt64;
      break;
    case FD::CPPTYPE_FLOAT:
      s.type = Type::Float;
      break;
    case FD::CPPTYPE_DOUBLE:
      s.type = Type::Double;
      break;
    case FD::CPPTYPE_STRING:
      s.type = f->type() == FD::TYPE_BYTES ? Type::Bytes : Type::String;
      break;
    case FD::CPPTYPE_ENUM:
      s.type = Type::Enum;
      s.null_is_value = f->enum_type()->full_name() == "google.protobuf.NullValue";
      break;
    case FD::CPPTYPE_MESSAGE:
      classify_message(s, f->message_type());
      break;
  }
  return s;
}

/// The slot of a message field given as a member of its object.
Slot slot_of_member(const FD* f) {
  if (f->is_map()) return slot_of(f, Shape::Map);
  return slot_of(f, f->is_repeated() ? Shape::Repeated : Shape::Field);
}

/// "an integer (int32)", "a number", ...: what a slot takes, for messages.
std::string expected(const Slot& s) {
  if (s.shape == Shape::Repeated) return "an array";
  if (s.shape == Shape::Map) return "an object (a map)";
  const std::string type_name = s.field != nullptr ? s.field->type_name() : "";
  switch (s.type) {
    case Type::Bool:
      return "true or false";
    case Type::Int32:
    case Type::UInt32:
    case Type::Int64:
    case Type::UInt64:
      return "an integer (" + type_name + ")";
    case Type::Float:
    case Type::Double:
      return "a number";
    case Type::String:
      return "a string";
    case Type::Bytes:
      return "a base64 string";
    case Type::Enum:
      return "a value of " + s.field->enum_type()->full_name() + " (its name or its number)";
    case Type::Message:
    case Type::Struct:
    case Type::Any:
      return "an object (" + s.message->full_name() + ")";
    case Type::ListValue:
      return "an array (" + s.message->full_name() + ")";
    case Type::StringWkt:
      return "a string (" + s.message->full_name() + ")";
    case Type::Value:
    case Type::Generic:
    case Type::Skip:
      return "a value";
  }
  return "a value";
}

// ---- The validating pass -----------------------------------------------------------------------

enum class Kind : std::uint8_t {
  Message,   // an object filling a message: members are fields
  Repeated,  // an array filling a repeated field
  Map,       // an object filling a map field: members are entries
  Object,    // an object inside Struct / Value: any members, each once
  Any,       // google.protobuf.Any's object before its "@type"
  AnyValue,  // ... after an "@type" naming a well-known type: its JSON in "value"
  Array,     // an array inside Value / ListValue
  Skip,      // an object or array inside an ignored unknown field
};

struct Frame {
  Kind kind = Kind::Message;
  bool is_array = false;
  Slot slot;                // the next value: a member's (set by key()) or an element's
  std::size_t index = 0;    // arrays: elements begun (the current one is index - 1)
  std::size_t members = 0;  // objects: members begun
  std::size_t seen = 0;     // Message: offset of its marks in Checker::seen_
  const pb::Descriptor* message = nullptr;  // Message: its type
  const FD* member = nullptr;               // Message: the current member's field (else `key`)
  const FD* map_key = nullptr;              // Map: the key field
  std::string key;                          // objects: the current key, as given
  std::unordered_set<std::string> keys;     // Map / Object / Any: the keys given
};

/// Numbers as they appear in messages: nlohmann's text, cut to 40 characters.
std::string number_text(const std::string& text) {
  return text.size() > 40 ? text.substr(0, 40) + "..." : text;
}

std::string got_string(std::string_view value) { return "the string " + quote_text(value); }

bool is_integer(Type t) {
  return t == Type::Int32 || t == Type::UInt32 || t == Type::Int64 || t == Type::UInt64;
}

/// -?(0|[1-9][0-9]*): an integer in a string as protobuf writes it (no "+", no leading zeros,
/// no fraction or exponent).
bool decimal_integer(std::string_view text, ExactInteger& e) {
  std::size_t i = 0;
  if (i < text.size() && text[i] == '-') {
    e.negative = true;
    ++i;
  }
  if (i >= text.size()) return false;
  if (text[i] == '0' && i + 1 != text.size()) return false;
  for (; i < text.size(); ++i) {
    if (!is_digit(text[i])) return false;
    if (e.magnitude > (static_cast<unsigned __int128>(1) << 100))
      e.too_big = true;
    else
      e.magnitude = e.magnitude * 10 + static_cast<unsigned>(text[i] - '0');
  }
  e.integral = true;
  return true;
}

/// Whether an integral value fits the integer type (enums: int32).
bool in_range(Type type, const ExactInteger& e) {
  if (!e.integral || e.too_big) return false;
  unsigned __int128 max_positive = 0, max_negative = 0;
  switch (type) {
    case Type::Int32:
    case Type::Enum:
      max_positive = std::numeric_limits<std::int32_t>::max();
      max_negative = max_positive + 1;
      break;
    case Type::UInt32:
      max_positive = std::numeric_limits<std::uint32_t>::max();
      break;
    case Type::Int64:
      max_positive = std::numeric_limits<std::int64_t>::max();
      max_negative = max_positive + 1;
      break;
    case Type::UInt64:
      max_positive = std::numeric_limits<std::uint64_t>::max();
      break;
    default:
      return false;
  }
  return e.negative && e.magnitude != 0 ? e.magnitude <= max_negative : e.magnitude <= max_positive;
}

const char* range_text(Type t) {
  switch (t) {
    case Type::Int32:
    case Type::Enum:
      return "-2147483648 to 2147483647";
    case Type::UInt32:
      return "0 to 4294967295";
    case Type::Int64:
      return "-9223372036854775808 to 9223372036854775807";
    default:
      return "0 to 18446744073709551615";
  }
}

/// For a number in JSON syntax that from_chars found out of range: true if it is tiny (it then
/// reads as 0, as in protobuf), false if it is huge.
bool underflows(std::string_view s) {
  std::size_t i = s[0] == '-' ? 1 : 0;
  long long position = 0;  // the power of ten of the first significant digit
  bool found = false;
  for (; i < s.size() && is_digit(s[i]); ++i) {
    if (found)
      ++position;
    else if (s[i] != '0')
      found = true;
  }
  if (i < s.size() && s[i] == '.') {
    long long after = 0;
    for (++i; i < s.size() && is_digit(s[i]); ++i) {
      ++after;
      if (!found && s[i] != '0') {
        found = true;
        position = -after;
      }
    }
  }
  if (!found) return true;
  long long exponent = 0;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    bool negative = false;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) negative = s[i++] == '-';
    for (; i < s.size() && is_digit(s[i]); ++i)
      if (exponent < kExponentCap) exponent = exponent * 10 + (s[i] - '0');
    if (negative) exponent = -exponent;
  }
  return position + exponent < 0;
}

/// The SAX handler of the validating pass. Every event either fits what the top frame expects
/// or records the error (field path and message) and returns false, which stops nlohmann's parser
/// at once.
class Checker {
 public:
  Checker(const pb::Descriptor* root, int max_depth, UnknownFields unknown,
          std::size_t max_string_bytes)
      : pool_(root->file()->pool()),
        max_depth_(static_cast<std::size_t>(std::max(max_depth, 0))),
        max_string_bytes_(max_string_bytes),
        skip_unknown_(unknown == UnknownFields::Skip) {
    classify_message(root_, root);
    root_.shape = Shape::Root;
    frames_.reserve(std::min<std::size_t>(max_depth_, 64));
  }

  bool failed() const { return failed_; }
  const std::string& error_field() const { return error_field_; }
  const std::string& error_message() const { return error_message_; }

  // nlohmann's SAX interface ------------------------------------------------------------------

  bool null() {
    const Slot& s = begin_value();
    switch (s.shape) {
      case Shape::Repeated:
        // protobuf reads null for a repeated Value as a list holding one null value.
        if (s.type == Type::Value) return fail_got(s, "null");
        return true;
      case Shape::Field:
      case Shape::Map:
        return true;  // the field's default (a Value's null value)
      default:        // Element, MapValue, Root
        if (s.null_is_value || s.type == Type::Value || s.type == Type::Generic ||
            s.type == Type::Skip)
          return true;
        return fail_got(s, "null");
    }
  }

  bool boolean(bool value) {
    const Slot& s = begin_value();
    if (!whole(s) && (s.type == Type::Bool || takes_anything(s.type))) return true;
    return fail_got(s, value ? "true" : "false");
  }

  bool number_integer(json::number_integer_t value) {
    ExactInteger e;
    e.integral = true;
    e.negative = value < 0;
    e.magnitude = value < 0 ? static_cast<unsigned __int128>(-(value + 1)) + 1
                            : static_cast<unsigned __int128>(value);
    return number(e, static_cast<double>(value), nullptr);
  }

  bool number_unsigned(json::number_unsigned_t value) {
    ExactInteger e;
    e.integral = true;
    e.magnitude = value;
    return number(e, static_cast<double>(value), nullptr);
  }

  bool number_float(json::number_float_t value, const json::string_t& text) {
    ExactInteger e;
    const Type type = peek_value().type;
    if (is_integer(type) || type == Type::Enum) e = exact_integer(text);
    return number(e, value, &text);
  }

  bool string(json::string_t& value) {
    const Slot& s = begin_value();
    if (depth_ > 0 && frames_[depth_ - 1].kind == Kind::Any) return any_type(value);
    if (whole(s)) return fail_got(s, got_string(value));
    switch (s.type) {
      case Type::String:
        if (max_string_bytes_ > 0 && value.size() > max_string_bytes_)
          return fail(path(true), "too long: " + std::to_string(value.size()) + " bytes, at most " +
                                      std::to_string(max_string_bytes_));
        return true;
      case Type::StringWkt:
      case Type::Value:
      case Type::Generic:
      case Type::Skip:
        return true;
      case Type::Bytes:
        if (valid_base64(value)) return true;
        return fail(path(true),
                    "expected base64 (the standard or the URL-safe alphabet, padded or not), got " +
                        got_string(value));
      case Type::Int32:
      case Type::UInt32:
      case Type::Int64:
      case Type::UInt64:
        return integer_string(s, value);
      case Type::Float:
      case Type::Double:
        return real_string(s, value);
      case Type::Enum:
        if (s.field->enum_type()->FindValueByName(value) != nullptr || skip_unknown_) return true;
        return fail(path(true), "unknown value " + quote_text(value) + " of enum " +
                                    s.field->enum_type()->full_name());
      default:
        return fail_got(s, got_string(value));
    }
  }

  bool binary(json::binary_t& /*value*/) { return true; }  // never produced by JSON text

  bool start_object(std::size_t /*elements*/) {
    const Slot s = begin_value();  // a copy: push() may move the frames
    if (!deeper()) return false;
    if (s.shape == Shape::Map) {
      const pb::Descriptor* entry = s.field->message_type();
      Frame& f = push(Kind::Map, false);
      f.map_key = entry->map_key();
      f.slot = slot_of(entry->map_value(), Shape::MapValue);
      return true;
    }
    if (s.shape == Shape::Repeated) return fail_got(s, "an object");
    switch (s.type) {
      case Type::Message:
        become_message(push(Kind::Message, false), s.message);
        return true;
      case Type::Struct:
      case Type::Value:
      case Type::Generic:
        push(Kind::Object, false);
        return true;
      case Type::Any:
        push(Kind::Any, false);
        return true;
      case Type::Skip:
        push(Kind::Skip, false).slot.type = Type::Skip;
        return true;
      default:
        return fail_got(s, "an object");
    }
  }

  bool key(json::string_t& name) {
    Frame& f = frames_[depth_ - 1];
    ++f.members;
    switch (f.kind) {
      case Kind::Message:
        return member(f, name);
      case Kind::Map:
        f.key = name;
        if (!valid_map_key(f.map_key, name))
          return fail(
              path(true),
              "expected a map key of type " + std::string(f.map_key->type_name()) +
                  (f.map_key->cpp_type() == FD::CPPTYPE_BOOL ? " (\"true\" or \"false\")"
                                                             : " (a decimal integer in range)") +
                  ", got " + quote_text(name));
        if (!f.keys.insert(name).second) return fail(path(true), "map key given twice");
        return true;
      case Kind::Object:
        f.key = name;
        if (!f.keys.insert(name).second) return fail(path(true), "given twice");
        return true;
      case Kind::Any:
        // "@type" first (as every printer writes it): the rest is then checked as that type.
        f.key = name;
        if (name != "@type")
          return fail(
              path(true),
              "an Any's first member must be \"@type\" (the URL of its type), not this one");
        f.slot = Slot{};
        f.slot.type = Type::String;
        f.slot.shape = Shape::Element;  // not null either
        return true;
      case Kind::AnyValue:
        f.key = name;
        if (name != "value")
          return fail(path(true), "an Any of " + f.message->full_name() +
                                      " holds its JSON in \"value\" (beside \"@type\") only");
        if (!f.keys.insert(name).second) return fail(path(true), "given twice");
        return true;
      default:  // Skip
        f.key = name;
        return true;
    }
  }

  bool end_object() {
    const Frame& f = frames_[depth_ - 1];
    if (f.kind == Kind::Message) seen_top_ = f.seen;
    --depth_;
    return true;
  }

  bool start_array(std::size_t /*elements*/) {
    const Slot s = begin_value();  // a copy: push() may move the frames
    if (!deeper()) return false;
    if (s.shape == Shape::Repeated) {
      // (A repeated wrapper's slot holds the wrapper's value field: its elements are read as
      // that primitive, which is the wrapper's JSON.)
      push(Kind::Repeated, true).slot = slot_of(s.field, Shape::Element);
      return true;
    }
    if (s.shape == Shape::Map) return fail_got(s, "an array");
    switch (s.type) {
      case Type::ListValue:
      case Type::Value:
      case Type::Generic:
        push(Kind::Array, true);
        return true;
      case Type::Skip:
        push(Kind::Skip, true).slot.type = Type::Skip;
        return true;
      default:
        return fail_got(s, "an array");
    }
  }

  bool end_array() {
    --depth_;
    return true;
  }

  bool parse_error(std::size_t position, const std::string& /*last_token*/,
                   const nlohmann::detail::exception& error) {
    // "[json.exception.parse_error.101] parse error at line 1, column 9: syntax error ..."
    std::string what = error.what();
    const std::size_t bracket = what.find("] ");
    if (bracket != std::string::npos) what.erase(0, bracket + 2);
    std::string where = "at byte " + std::to_string(position);
    constexpr std::string_view kAt = "parse error at ";
    if (what.rfind(kAt, 0) == 0) {
      const std::size_t colon = what.find(": ");
      if (colon != std::string::npos) {
        where += " (" + what.substr(kAt.size(), colon - kAt.size()) + ")";
        what.erase(0, colon + 2);
      }
    }
    return fail("", "not valid JSON: " + printable(what) + ", " + where);
  }

 private:
  static bool takes_anything(Type t) {
    return t == Type::Value || t == Type::Generic || t == Type::Skip;
  }
  /// The slot is a whole repeated or map field: only an array / object (or null) fits.
  static bool whole(const Slot& s) { return s.shape == Shape::Repeated || s.shape == Shape::Map; }

  /// The slot the next value fills, without counting it.
  const Slot& peek_value() const { return depth_ == 0 ? root_ : frames_[depth_ - 1].slot; }

  /// The slot the next value fills; counts an array's element.
  const Slot& begin_value() {
    if (depth_ == 0) return root_;
    Frame& f = frames_[depth_ - 1];
    if (f.is_array) ++f.index;
    return f.slot;
  }

  bool deeper() {
    if (depth_ < max_depth_) return true;
    return fail(path(true), "too deep: more than " + std::to_string(max_depth_) +
                                " levels of nested objects and arrays");
  }

  Frame& push(Kind kind, bool is_array) {
    if (frames_.size() <= depth_) frames_.emplace_back();
    Frame& f = frames_[depth_++];
    f.kind = kind;
    f.is_array = is_array;
    f.slot = Slot{};
    f.index = 0;
    f.members = 0;
    f.message = nullptr;
    f.member = nullptr;
    f.map_key = nullptr;
    f.key.clear();
    f.keys.clear();
    return f;
  }

  /// Makes `f` the frame of an object of message type `type`: its fields' and oneofs' marks.
  void become_message(Frame& f, const pb::Descriptor* type) {
    const std::size_t marks =
        static_cast<std::size_t>(type->field_count() + type->oneof_decl_count());
    if (seen_.size() < seen_top_ + marks) seen_.resize(seen_top_ + marks);
    std::fill_n(seen_.begin() + static_cast<std::ptrdiff_t>(seen_top_), marks, 0);
    f.kind = Kind::Message;
    f.message = type;
    f.member = nullptr;
    f.seen = seen_top_;
    seen_top_ += marks;
  }

  /// The "@type" of an Any: "type.googleapis.com/" and a message type protobuf's parser finds.
  /// The Any's other members are then checked as that type's: its fields, or the JSON of a
  /// well-known type in "value" (protobuf 3.21 aborts the process — CHECK failed: !done_ — on
  /// some other members beside a well-known type's "@type").
  bool any_type(const std::string& url) {
    constexpr std::string_view kPrefix = "type.googleapis.com/";
    const pb::Descriptor* type = url.rfind(kPrefix, 0) == 0
                                     ? pool_->FindMessageTypeByName(url.substr(kPrefix.size()))
                                     : nullptr;
    if (type == nullptr)
      return fail(path(true),
                  "expected \"type.googleapis.com/\" and the name of a message type, got " +
                      got_string(url));
    Frame& f = frames_[depth_ - 1];
    Slot inner;
    classify_message(inner, type);
    if (inner.type == Type::Message) {
      become_message(f, type);
    } else {
      f.kind = Kind::AnyValue;
      f.message = type;
      f.slot = inner;
      f.slot.shape = Shape::Field;
    }
    return true;
  }

  /// A member of a message's object: a field by its proto or its JSON name, once; one member of
  /// a oneof.
  bool member(Frame& f, const std::string& name) {
    const pb::Descriptor* type = f.message;
    // protobuf refuses an empty name even when it skips unknown fields.
    if (name.empty())
      return fail(path(false), "a member with an empty name in " + type->full_name());
    const FD* field = type->FindFieldByName(name);
    for (int i = 0; field == nullptr && i < type->field_count(); ++i)
      if (type->field(i)->json_name() == name) field = type->field(i);
    f.member = field;
    if (field == nullptr) {
      f.key = name;
      if (!skip_unknown_) return fail(path(true), "unknown field of " + type->full_name());
      f.slot = Slot{};
      f.slot.type = Type::Skip;
      return true;
    }
    f.slot = slot_of_member(field);
    int& given = seen_[f.seen + static_cast<std::size_t>(field->index())];
    if (given != 0) return fail(path(true), "given twice (by its name or its JSON name)");
    given = 1;
    if (const pb::OneofDescriptor* oneof = field->real_containing_oneof()) {
      int& set = seen_[f.seen + static_cast<std::size_t>(type->field_count() + oneof->index())];
      if (set != 0)
        return fail(path(true), "only one member of oneof " + oneof->name() +
                                    " may be given, and " + type->field(set - 1)->name() +
                                    " is given too");
      set = field->index() + 1;
    }
    return true;
  }

  static bool valid_map_key(const FD* key, const std::string& text) {
    switch (key->cpp_type()) {
      case FD::CPPTYPE_STRING:
        return true;
      case FD::CPPTYPE_BOOL:
        return text == "true" || text == "false";
      default: {
        Slot s = slot_of(key, Shape::Field);
        ExactInteger e;  // canonical: not "-0" either, so that no key is given twice
        return decimal_integer(text, e) && in_range(s.type, e) &&
               !(e.negative && e.magnitude == 0) &&
               !((s.type == Type::UInt32 || s.type == Type::UInt64) && e.negative);
      }
    }
  }

  /// A JSON number: `e` its exact value where the slot is an integer or enum, `value` as a
  /// double, `text` nlohmann's text of a number with a fraction or exponent (else null).
  bool number(const ExactInteger& e, double value, const std::string* text) {
    const Slot& s = begin_value();
    auto shown = [&] {
      if (text != nullptr) return number_text(*text);
      if (e.negative) return "-" + std::to_string(static_cast<std::uint64_t>(e.magnitude));
      return std::to_string(static_cast<std::uint64_t>(e.magnitude));
    };
    if (whole(s)) return fail_got(s, shown());
    switch (s.type) {
      case Type::Double:
      case Type::Value:
      case Type::Generic:
      case Type::Skip:
        return true;
      case Type::Float:
        // protobuf refuses a double that rounds to infinity as a float (2^128 - 2^103 and up).
        if (std::fabs(value) < 0x1.ffffffp+127) return true;
        return fail(path(true), "expected a number within float range, got " + shown());
      case Type::Int32:
      case Type::UInt32:
      case Type::Int64:
      case Type::UInt64:
      case Type::Enum: {
        const std::string type_name = s.type == Type::Enum
                                          ? "enum " + s.field->enum_type()->full_name()
                                          : std::string(s.field->type_name());
        if (!e.integral)
          return fail(path(true), "expected an integer (" + type_name + "), got " + shown());
        if (!in_range(s.type, e))
          return fail(path(true), std::string("expected an integer from ") + range_text(s.type) +
                                      " (" + type_name + "), got " + shown());
        // protobuf reads a number with a fraction or exponent as a double, which must hold the
        // integer exactly (9007199254740993.0 would become ...992).
        if (text != nullptr && static_cast<unsigned __int128>(std::fabs(value)) != e.magnitude)
          return fail(path(true), "expected an integer (" + type_name + "), got " + shown() +
                                      ", which a double does not hold exactly: write its digits");
        return true;
      }
      default:
        return fail_got(s, shown());
    }
  }

  bool integer_string(const Slot& s, const std::string& value) {
    ExactInteger e;
    const bool is_unsigned = s.type == Type::UInt32 || s.type == Type::UInt64;
    if (!decimal_integer(value, e) || (is_unsigned && e.negative))
      return fail(path(true), "expected an integer (" + std::string(s.field->type_name()) +
                                  "), got " + got_string(value));
    if (!in_range(s.type, e))
      return fail(path(true), std::string("expected an integer from ") + range_text(s.type) + " (" +
                                  s.field->type_name() + "), got " + got_string(value));
    return true;
  }

  bool real_string(const Slot& s, const std::string& value) {
    if (value == "NaN" || value == "Infinity" || value == "-Infinity") return true;
    if (!json_number_syntax(value))
      return fail(path(true), "expected a number (or \"NaN\", \"Infinity\", \"-Infinity\"), got " +
                                  got_string(value));
    double d = 0;
    const auto result = std::from_chars(value.data(), value.data() + value.size(), d);
    const char* range = s.type == Type::Float ? "float" : "double";
    if (result.ec == std::errc::result_out_of_range) {
      if (underflows(value)) return true;  // reads as 0, as in protobuf
      return fail(path(true), std::string("expected a number within ") + range + " range, got " +
                                  got_string(value));
    }
    if (result.ec != std::errc() || result.ptr != value.data() + value.size())
      return fail(path(true), "expected a number, got " + got_string(value));
    // protobuf's float from a string: at most FLT_MAX (a number may round down to it).
    if (s.type == Type::Float && std::fabs(d) > std::numeric_limits<float>::max())
      return fail(path(true), std::string("expected a number within ") + range + " range, got " +
                                  got_string(value));
    return true;
  }

  bool fail_got(const Slot& s, const std::string& got) {
    return fail(path(true), "expected " + expected(s) + ", got " + got);
  }

  bool fail(std::string field, std::string message) {
    failed_ = true;
    error_field_ = std::move(field);
    error_message_ = std::move(message);
    return false;
  }

  /// The path in proto field names of the top frame's current member or element (`child`) or
  /// of the top frame's own value: "mesh.positions[12]", "report.stage_seconds[\"grid\"]".
  std::string path(bool child) const {
    std::string out;
    const std::size_t n = child || depth_ == 0 ? depth_ : depth_ - 1;
    for (std::size_t i = 0; i < n; ++i) {
      const Frame& f = frames_[i];
      if (f.is_array) {
        out += '[';
        out += std::to_string(f.index - 1);
        out += ']';
      } else if (f.kind == Kind::Message) {
        if (!out.empty()) out += '.';
        if (f.member != nullptr) {
          out += f.member->name();
        } else {
          const std::string key = quote_text(f.key, 64);  // an unknown member, as given
          out.append(key, 1, key.size() - 2);
        }
      } else {
        out += '[';
        out += quote_text(f.key, 64);
        out += ']';
      }
    }
    return out;
  }

  const pb::DescriptorPool* pool_;  // the root message's: where an Any's "@type" is looked up
  const std::size_t max_depth_;
  const std::size_t max_string_bytes_;  // 0 = no limit
  const bool skip_unknown_;
  Slot root_;
  std::vector<Frame> frames_;  // [0, depth_) are open; the rest are kept for reuse
  std::size_t depth_ = 0;
  std::vector<int> seen_;  // per open message: its fields given (1), its oneofs' (field index + 1)
  std::size_t seen_top_ = 0;
  bool failed_ = false;
  std::string error_field_;
  std::string error_message_;
};

}  // namespace

void from_json(std::string_view text, google::protobuf::Message& message, int max_depth,
               UnknownFields unknown, std::size_t max_string_bytes) {
  message.Clear();
  // nlohmann skips a byte order mark, protobuf's parser does not: refused, as before.
  if (text.substr(0, 3) == "\xEF\xBB\xBF")
    throw InvalidInput("", "not valid JSON: it starts with a byte order mark (U+FEFF)");
  // nlohmann's lexer ends the input at a NUL byte, so what follows one would go unread. JSON has
  // no raw NUL anywhere (in a string it must be escaped): refused wherever it is.
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    throw InvalidInput("", "not valid JSON: a NUL byte, at byte " + std::to_string(nul + 1));
  Checker checker(message.GetDescriptor(), max_depth, unknown, max_string_bytes);
  const bool valid = json::sax_parse(text.data(), text.data() + text.size(), &checker);
  if (checker.failed()) throw InvalidInput(checker.error_field(), checker.error_message());
  if (!valid) throw InvalidInput("", "not valid JSON");
  pb::util::JsonParseOptions options;
  options.ignore_unknown_fields = unknown == UnknownFields::Skip;
  const auto status =
      pb::util::JsonStringToMessage(pb::StringPiece(text.data(), text.size()), &message, options);
  if (!status.ok())
    throw InvalidInput("", "not read by protobuf's JSON parser: " + std::string(status.message()));
}

}  // namespace gridshell
