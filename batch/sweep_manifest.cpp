// SPDX-License-Identifier: GPL-3.0-or-later
// Sweep manifests: CSV (libcsv) or JSON Lines, one design per row, checked before anything runs:
// ids and columns here, each row's values by the caller's RowChecker (the CLI's: the parsers and
// request checks that `gridshell run` applies to its command line).
#include <csv.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "gridshell/batch/sweep.h"
#include "gridshell/foundation/errors.h"

namespace gridshell::sweep {
namespace fs = std::filesystem;

std::vector<std::string> Row::run_arguments() const {
  std::vector<std::string> arguments{mesh};
  for (const auto& [column, value] : values)
    if (column != "mesh") arguments.push_back("--" + column + "=" + value);
  return arguments;
}

const std::string* Row::value(const std::string& column) const {
  for (const auto& [name, value] : values)
    if (name == column) return &value;
  return nullptr;
}

std::string Problem::describe() const {
  std::string text = "line " + std::to_string(line);
  if (!id.empty()) text += " (id " + id + ")";
  if (!column.empty()) text += ", column " + column;
  return text + ": " + message;
}

namespace {

std::string normalized_column(std::string name) {
  const auto b = name.find_first_not_of(" \t\r\n");
  const auto e = name.find_last_not_of(" \t\r\n");
  name = b == std::string::npos ? "" : name.substr(b, e - b + 1);
  if (name.rfind("--", 0) == 0) name = name.substr(2);
  for (char& c : name) {
    if (c == '_') c = '-';
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return name;
}

std::string trimmed(const std::string& text) {
  const auto b = text.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = text.find_last_not_of(" \t\r\n");
  return text.substr(b, e - b + 1);
}

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> records;
  std::vector<int> lines;  // first line of each record
};

Table read_csv(const std::string& path, const std::string& text) {
  struct State {
    Table table;
    std::vector<std::string> record;
    int line = 0;
    int record_line = 0;
    bool header_done = false;
  } state;
  auto on_field = [](void* data, size_t size, void* user) {
    auto& s = *static_cast<State*>(user);
    if (s.record.empty()) s.record_line = s.line;
    s.record.emplace_back(data ? static_cast<const char*>(data) : "", data ? size : 0);
  };
  auto on_record = [](int, void* user) {
    auto& s = *static_cast<State*>(user);
    const bool blank = s.record.size() <= 1 && (s.record.empty() || trimmed(s.record[0]).empty());
    if (!blank) {
      if (!s.header_done) {
        s.table.header = std::move(s.record);
        s.header_done = true;
      } else {
        s.table.records.push_back(std::move(s.record));
        s.table.lines.push_back(s.record_line);
      }
    }
    s.record.clear();
  };
  csv_parser parser;
  if (csv_init(&parser, CSV_STRICT | CSV_STRICT_FINI) != 0)
    throw std::runtime_error("cannot initialise the CSV parser");
  std::unique_ptr<csv_parser, void (*)(csv_parser*)> guard(&parser, csv_free);
  size_t begin = 0;
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) begin = 3;  // a UTF-8 byte order mark
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    end = end == std::string::npos ? text.size() : end + 1;
    ++state.line;
    if (csv_parse(&parser, text.data() + begin, end - begin, on_field, on_record, &state) !=
        end - begin)
      throw InvalidInput(path, "line " + std::to_string(state.line) + ": " +
                                   csv_strerror(csv_error(&parser)) +
                                   " (a quote inside a quoted field is written twice: \"\")");
    begin = end;
  }
  if (csv_fini(&parser, on_field, on_record, &state) != 0)
    throw InvalidInput(path, "line " + std::to_string(state.line) +
                                 ": a quoted field is not closed at the end of the file");
  if (state.table.header.empty()) throw InvalidInput(path, "empty: no header row");
  return state.table;
}

/// A JSON value as the text of a command-line value: strings as they are, numbers as JSON
/// prints them, arrays of numbers joined by commas and arrays of points by semicolons (corners).
std::string json_value_text(const nlohmann::json& value, bool* ok) {
  *ok = true;
  if (value.is_string()) return value.get<std::string>();
  if (value.is_number()) return value.dump();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_array()) {
    std::string text;
    for (size_t i = 0; i < value.size(); ++i) {
      const auto& item = value[i];
      std::string part;
      if (item.is_number()) {
        part = item.dump();
        if (i) text += ",";
      } else if (item.is_array()) {
        for (size_t k = 0; k < item.size(); ++k) {
          if (!item[k].is_number()) *ok = false;
          part += (k ? "," : "") + item[k].dump();
        }
        if (i) text += ";";
      } else {
        *ok = false;
      }
      text += part;
    }
    return text;
  }
  *ok = false;
  return "";
}

Table read_jsonl(const std::string& path, const std::string& text) {
  Table table;
  std::map<std::string, size_t> column_index;
  std::vector<std::vector<std::pair<std::string, std::string>>> rows;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (trimmed(line).empty()) continue;
    nlohmann::ordered_json object;
    try {
      object = nlohmann::ordered_json::parse(line);
    } catch (const nlohmann::json::exception& e) {
      throw InvalidInput(
          path, "line " + std::to_string(number) + ": not JSON (" + std::string(e.what()) + ")");
    }
    if (!object.is_object())
      throw InvalidInput(path, "line " + std::to_string(number) + ": expected a JSON object");
    std::vector<std::pair<std::string, std::string>> row;
    for (const auto& [key, value] : object.items()) {
      if (value.is_null()) continue;
      bool ok = true;
      const std::string text_value = json_value_text(value, &ok);
      if (!ok)
        throw InvalidInput(path, "line " + std::to_string(number) + ": \"" + key +
                                     "\": expected a string, a number or a list of numbers");
      if (!column_index.count(key)) {
        column_index[key] = table.header.size();
        table.header.push_back(key);
      }
      row.emplace_back(key, text_value);
    }
    rows.push_back(std::move(row));
    table.lines.push_back(number);
  }
  if (table.header.empty()) throw InvalidInput(path, "empty: no rows");
  for (const auto& row : rows) {
    std::vector<std::string> record(table.header.size());
    for (const auto& [key, value] : row) record[column_index[key]] = value;
    table.records.push_back(std::move(record));
  }
  return table;
}

bool usable_id(const std::string& id) {
  if (id.empty() || id.size() > 100 || id == "." || id == ".." || id[0] == '.' || id[0] == '-')
    return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
  });
}

}  // namespace

Manifest read_manifest(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InvalidInput(path, "no such manifest file");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream contents;
  contents << in.rdbuf();
  if (!in.good() && !in.eof()) throw InvalidInput(path, "cannot read the manifest");
  const std::string text = contents.str();
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  bool jsonl = extension == ".jsonl" || extension == ".ndjson";
  if (extension != ".csv" && !jsonl) {
    const auto first = text.find_first_not_of(" \t\r\n");
    jsonl = first != std::string::npos && text[first] == '{';
  }
  const Table table = jsonl ? read_jsonl(path, text) : read_csv(path, text);

  Manifest manifest;
  manifest.path = fs::absolute(path).lexically_normal().string();
  for (const std::string& name : table.header) manifest.columns.push_back(normalized_column(name));
  const fs::path base = fs::path(manifest.path).parent_path();
  for (size_t r = 0; r < table.records.size(); ++r) {
    const auto& record = table.records[r];
    if (record.size() != table.header.size())
      throw InvalidInput(path, "line " + std::to_string(table.lines[r]) + ": " +
                                   std::to_string(record.size()) + " fields, the header has " +
                                   std::to_string(table.header.size()));
    Row row;
    row.line = table.lines[r];
    for (size_t c = 0; c < record.size(); ++c) {
      const std::string value = trimmed(record[c]);
      const std::string& column = manifest.columns[c];
      if (column == "id") {
        row.id = value;
        continue;
      }
      if (value.empty()) continue;
      row.values.emplace_back(column, value);
      if (column == "mesh")
        row.mesh = value.rfind("example:", 0) == 0 || fs::path(value).is_absolute()
                       ? value
                       : (base / value).lexically_normal().string();
    }
    manifest.rows.push_back(std::move(row));
  }
  if (manifest.rows.empty()) throw InvalidInput(path, "no rows below the header");
  return manifest;
}

std::vector<Problem> validate(const Manifest& manifest, RowChecker& checker) {
  std::vector<Problem> problems;
  std::vector<std::string> known{"id", "mesh"};
  for (const std::string& column : checker.columns()) known.push_back(column);
  std::set<std::string> seen_columns;
  bool header_ok = true;
  for (const std::string& column : manifest.columns) {
    if (std::find(known.begin(), known.end(), column) == known.end()) {
      std::string list;
      for (size_t i = 2; i < known.size(); ++i) list += (i > 2 ? ", " : "") + known[i];
      problems.push_back(
          {1, "", column, "not an option of gridshell run (id, mesh, or one of: " + list + ")"});
      header_ok = false;
    }
    if (!seen_columns.insert(column).second) {
      problems.push_back({1, "", column, "given twice"});
      header_ok = false;
    }
  }
  for (const char* required : {"id", "mesh"})
    if (!seen_columns.count(required)) {
      problems.push_back({1, "", required, "missing: every row needs one"});
      header_ok = false;
    }
  if (!header_ok) return problems;

  std::map<std::string, int> ids;
  for (const Row& row : manifest.rows) {
    auto problem = [&](const std::string& column, const std::string& message) {
      problems.push_back({row.line, row.id, column, message});
    };
    if (row.id.empty()) {
      problem("id", "empty");
    } else if (!usable_id(row.id)) {
      problem("id",
              "'" + row.id +
                  "' cannot name a folder: use letters, digits, '-', '_' and '.' (not first), "
                  "at most 100");
    } else if (ids.count(row.id)) {
      problem("id", "'" + row.id + "' is also the id of line " + std::to_string(ids[row.id]));
    } else {
      ids[row.id] = row.line;
    }
    if (row.mesh.empty()) {
      problem("mesh", "empty");
      continue;
    }
    for (const auto& [column, message] : checker.check(row)) problem(column, message);
  }
  return problems;
}

}  // namespace gridshell::sweep
