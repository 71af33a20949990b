// SPDX-License-Identifier: GPL-3.0-or-later
// `gridshell sweep collect`: summary.csv, summary.json and summary.svg from the rows' status.json
// files (never from the large result files, so that 10 000 rows collect in well under 2 s).
#include <csv.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "gridshell/batch/sweep.h"
#include "gridshell/mesh/mesh_io.h"

namespace gridshell::sweep {
namespace fs = std::filesystem;

namespace {

const char* const kResultColumns[] = {"alpha_bar",
                                      "members",
                                      "crossings",
                                      "rms_without_notches",
                                      "rms_with_notches",
                                      "max_bending_stress",
                                      "t_grid",
                                      "t1",
                                      "t2",
                                      "coverage",
                                      "patches",
                                      "max_seam_gap",
                                      "max_bolt_force"};

std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  // Shortest text that reads back to the same double.
  for (int precision = 6; precision < 17; ++precision) {
    char shorter[32];
    std::snprintf(shorter, sizeof shorter, "%.*g", precision, value);
    if (std::strtod(shorter, nullptr) == value) return shorter;
  }
  return buffer;
}

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos &&
      (text.empty() || (text.front() != ' ' && text.back() != ' ')))
    return text;
  std::string quoted(text.size() * 2 + 2, '\0');
  quoted.resize(csv_write(quoted.data(), quoted.size(), text.data(), text.size()));
  return quoted;
}

std::optional<double> parse_double(const std::string& text) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
    return std::nullopt;
  return value;
}

std::string escape_xml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string option_of(const RowStatus& status, const std::string& column) {
  for (const auto& [name, value] : status.options)
    if (name == column) return value;
  return "";
}

}  // namespace

std::string summary_svg(const Manifest& manifest, const std::vector<RowStatus>& statuses) {
  // Swept parameters: the option columns whose values differ between rows.
  std::vector<std::string> swept;
  for (const std::string& column : manifest.columns) {
    if (column == "id") continue;
    std::set<std::string> values;
    for (const Row& row : manifest.rows) values.insert(row.value(column) ? *row.value(column) : "");
    if (values.size() > 1) swept.push_back(column);
  }
  // The rows with an RMS, best (lowest RMS with notches) first.
  std::vector<size_t> ranked;
  for (size_t i = 0; i < statuses.size(); ++i)
    if (statuses[i].results.count("rms_with_notches")) ranked.push_back(i);
  std::stable_sort(ranked.begin(), ranked.end(), [&](size_t a, size_t b) {
    return statuses[a].results.at("rms_with_notches") < statuses[b].results.at("rms_with_notches");
  });
  const size_t best = std::min<size_t>(3, ranked.size());
  std::set<size_t> best_rows(ranked.begin(), ranked.begin() + best);

  const int panel_w = 420, panel_h = 300, margin = 60;
  const int panels = std::max<int>(1, static_cast<int>(swept.size()));
  const int width = panels * panel_w + 20, height = panel_h + 110;
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(width) +
                    "\" height=\"" + std::to_string(height) + "\" viewBox=\"0 0 " +
                    std::to_string(width) + " " + std::to_string(height) +
                    "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg += "<text x=\"10\" y=\"18\" font-size=\"14\">RMS2 (deployment with notches) of " +
         std::to_string(ranked.size()) + " of " + std::to_string(statuses.size()) +
         " rows; red: the " + std::to_string(best) + " best</text>\n";
  if (ranked.empty()) {
    svg += "<text x=\"10\" y=\"60\">no row has finished with a result</text>\n</svg>\n";
    return svg;
  }
  double y_min = 1e300, y_max = -1e300;
  for (size_t i : ranked) {
    y_min = std::min(y_min, statuses[i].results.at("rms_with_notches"));
    y_max = std::max(y_max, statuses[i].results.at("rms_with_notches"));
  }
  if (y_max - y_min < 1e-12 * std::max(1.0, std::abs(y_max))) {
    y_min -= 0.5 * std::max(1e-9, std::abs(y_min));
    y_max += 0.5 * std::max(1e-9, std::abs(y_max));
  }
  for (int p = 0; p < panels; ++p) {
    const std::string column = swept.empty() ? "id" : swept[p];
    const int x0 = 10 + p * panel_w + margin, y0 = 40, w = panel_w - margin - 20, h = panel_h - 40;
    // x: the parameter's numbers (alpha: the planar angle the row got, in degrees), or its
    // values in order of appearance.
    std::vector<std::optional<double>> xs(statuses.size());
    bool numeric = true;
    for (size_t i : ranked) {
      if (column == "alpha" && statuses[i].results.count("alpha_bar"))
        xs[i] = statuses[i].results.at("alpha_bar") * 180 / 3.14159265358979323846;
      else
        xs[i] = parse_double(column == "id" ? statuses[i].id : option_of(statuses[i], column));
      if (!xs[i]) numeric = false;
    }
    std::vector<std::string> categories;
    if (!numeric) {
      for (size_t i : ranked) {
        const std::string v = column == "id" ? statuses[i].id : option_of(statuses[i], column);
        if (std::find(categories.begin(), categories.end(), v) == categories.end())
          categories.push_back(v);
      }
      for (size_t i : ranked) {
        const std::string v = column == "id" ? statuses[i].id : option_of(statuses[i], column);
        xs[i] = std::find(categories.begin(), categories.end(), v) - categories.begin();
      }
    }
    double x_min = 1e300, x_max = -1e300;
    for (size_t i : ranked) {
      x_min = std::min(x_min, *xs[i]);
      x_max = std::max(x_max, *xs[i]);
    }
    if (x_max - x_min < 1e-12) {
      x_min -= 1;
      x_max += 1;
    }
    const double pad = 0.05 * (x_max - x_min);
    x_min -= pad;
    x_max += pad;
    auto px = [&](double x) { return x0 + (x - x_min) / (x_max - x_min) * w; };
    auto py = [&](double y) { return y0 + h - (y - y_min) / (y_max - y_min) * h; };
    char buffer[512];
    std::snprintf(buffer, sizeof buffer,
                  "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" "
                  "stroke=\"#888\"/>\n",
                  x0, y0, w, h);
    svg += buffer;
    // Axis labels: the extremes of each axis, the categories.
    for (double y : {y_min, y_max}) {
      std::snprintf(buffer, sizeof buffer,
                    "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%.4g</text>\n", x0 - 4,
                    py(y) + 4, y);
      svg += buffer;
    }
    if (numeric) {
      for (double x : {x_min + pad, x_max - pad}) {
        std::snprintf(buffer, sizeof buffer,
                      "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.4g</text>\n", px(x),
                      y0 + h + 16, x);
        svg += buffer;
      }
    } else if (categories.size() <= 24) {
      for (size_t c = 0; c < categories.size(); ++c) {
        std::snprintf(buffer, sizeof buffer,
                      "<text x=\"%.1f\" y=\"%d\" text-anchor=\"end\" transform=\"rotate(-35 "
                      "%.1f %d)\">",
                      px(static_cast<double>(c)), y0 + h + 14, px(static_cast<double>(c)),
                      y0 + h + 14);
        svg += buffer + escape_xml(categories[c].substr(0, 24)) + "</text>\n";
      }
    }
    std::snprintf(buffer, sizeof buffer,
                  "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\" font-weight=\"bold\">",
                  x0 + w / 2, y0 + h + 46);
    svg += buffer + escape_xml(column == "alpha" ? "alpha (planar angle, degrees)" : column) +
           "</text>\n";
    std::snprintf(buffer, sizeof buffer,
                  "<text x=\"%d\" y=\"%d\" transform=\"rotate(-90 %d %d)\" "
                  "text-anchor=\"middle\">RMS2</text>\n",
                  x0 - 44, y0 + h / 2, x0 - 44, y0 + h / 2);
    svg += buffer;
    for (size_t i : ranked) {
      const bool top = best_rows.count(i) > 0;
      std::snprintf(buffer, sizeof buffer,
                    "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%d\" fill=\"%s\" stroke=\"%s\"><title>",
                    px(*xs[i]), py(statuses[i].results.at("rms_with_notches")), top ? 5 : 3,
                    top ? "#d62728" : "#1f77b4", top ? "black" : "none");
      svg += buffer + escape_xml(statuses[i].id) + ": RMS2 " +
             number(statuses[i].results.at("rms_with_notches")) + "</title></circle>\n";
      if (top) {
        std::snprintf(buffer, sizeof buffer, "<text x=\"%.1f\" y=\"%.1f\" fill=\"#d62728\">",
                      px(*xs[i]) + 7, py(statuses[i].results.at("rms_with_notches")) - 6);
        svg += buffer + escape_xml(statuses[i].id) + "</text>\n";
      }
    }
  }
  svg += "</svg>\n";
  return svg;
}

std::vector<RowStatus> collect(const std::string& dir) {
  const Manifest manifest = read_sweep_file(dir);
  const std::vector<RowStatus> statuses = row_statuses(dir, manifest);
  std::vector<std::string> options;  // the manifest's option columns (id first in the files)
  for (const std::string& column : manifest.columns)
    if (column != "id") options.push_back(column);

  std::string csv = "id";
  for (const std::string& column : options) csv += "," + csv_field(column);
  csv += ",status,exit_code,error";
  for (const char* column : kResultColumns) csv += std::string(",") + column;
  csv += ",attempt,seconds,host\n";
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const RowStatus& s : statuses) {
    csv += csv_field(s.id);
    nlohmann::ordered_json row;
    row["id"] = s.id;
    for (const std::string& column : options) {
      const std::string value = option_of(s, column);
      csv += "," + csv_field(value);
      row[column] = value;
    }
    const bool ran = s.status != "pending";
    csv +=
        "," + s.status + "," + (ran ? std::to_string(s.exit_code) : "") + "," + csv_field(s.error);
    row["status"] = s.status;
    row["exit_code"] = ran ? nlohmann::ordered_json(s.exit_code) : nlohmann::ordered_json();
    row["error"] = s.error;
    for (const char* column : kResultColumns) {
      const auto it = s.results.find(column);
      csv += "," + (it == s.results.end() ? std::string() : number(it->second));
      row[column] =
          it == s.results.end() ? nlohmann::ordered_json() : nlohmann::ordered_json(it->second);
    }
    csv += "," + (s.attempt ? std::to_string(s.attempt) : std::string()) + "," +
           (ran ? number(s.seconds) : std::string()) + "," + csv_field(s.host) + "\n";
    row["attempt"] = s.attempt;
    row["seconds"] = ran ? nlohmann::ordered_json(s.seconds) : nlohmann::ordered_json();
    row["host"] = s.host;
    rows.push_back(std::move(row));
  }
  std::string json = "[\n";
  for (size_t i = 0; i < rows.size(); ++i)
    json += "  " + rows[i].dump() + (i + 1 < rows.size() ? ",\n" : "\n");
  json += "]\n";
  write_file_atomically((fs::path(dir) / "summary.csv").string(), csv);
  write_file_atomically((fs::path(dir) / "summary.json").string(), json);
  write_file_atomically((fs::path(dir) / "summary.svg").string(), summary_svg(manifest, statuses));
  return statuses;
}

}  // namespace gridshell::sweep
