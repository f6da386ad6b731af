// Reading paper_tables.csv: see ReadPaperTables in report.h.

#include <cstddef>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "pidlab/io/files.h"
#include "pidlab/report/report.h"

namespace pidlab::report {
namespace {

// Far more than the paper's tables (under 2 KiB) will ever hold.
constexpr std::size_t kMaxPaperTablesBytes = 1 << 20;

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream is(line);
  while (std::getline(is, cell, ',')) out.push_back(Trim(cell));
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

// Column name -> index in paper_tables.csv.
using Columns = std::map<std::string, std::size_t>;

// The header line's columns; false with *error if a required one is missing.
bool ParseHeader(const std::string& line, const std::string& path, Columns* col, std::string* error) {
  const std::vector<std::string> header = SplitCsv(line);
  for (std::size_t i = 0; i < header.size(); ++i) (*col)[header[i]] = i;
  const char* required[] = {"table",
                            "plant",
                            "method",
                            "disturbance_amplitude",
                            "kp",
                            "ki",
                            "kd",
                            "paper_rise_time_s",
                            "paper_overshoot_pct",
                            "paper_settling_time_s",
                            "paper_iae",
                            "ref_rise_time_s",
                            "ref_overshoot_pct",
                            "ref_settling_time_s",
                            "ref_iae"};
  for (const char* name : required) {
    if (!col->count(name)) {
      *error = path + ": missing column " + name;
      return false;
    }
  }
  return true;
}

// One data line (line `number` of `path`); throws std::invalid_argument
// naming the line and column of a cell that is not a number.
PaperRow ParseRow(const std::vector<std::string>& cells, const Columns& col, const std::string& path,
                  int number) {
  auto text = [&](const char* name) {
    const std::size_t i = col.at(name);
    return i < cells.size() ? cells[i] : std::string();
  };
  auto value = [&](const char* name, double fallback, bool allow_empty) {
    const std::string s = text(name);
    if (s.empty() && allow_empty) return fallback;
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != s.size() || s.empty())
      throw std::invalid_argument(path + " line " + std::to_string(number) + ": column " + name + " = '" + s +
                                  "' is not a number");
    return v;
  };
  PaperRow r;
  r.table = text("table");
  r.plant = text("plant");
  r.method = text("method");
  r.disturbance_amplitude = value("disturbance_amplitude", 0.0, true);
  r.gains = {value("kp", 0, false), value("ki", 0, false), value("kd", 0, false)};
  r.paper_rise_time_s = value("paper_rise_time_s", 0, false);
  r.paper_overshoot_pct = value("paper_overshoot_pct", 0, false);
  r.paper_settling_time_s = value("paper_settling_time_s", 0, false);
  r.paper_iae = value("paper_iae", 0, false);
  r.ref_rise_time_s = value("ref_rise_time_s", 0, false);
  r.ref_overshoot_pct = value("ref_overshoot_pct", 0, false);
  r.ref_settling_time_s = value("ref_settling_time_s", 0, false);
  r.ref_iae = value("ref_iae", 0, false);
  return r;
}

}  // namespace

Status ReadPaperTables(const std::string& path, std::vector<PaperRow>* rows) {
  // A FIFO or a folder is refused before anything waits on it.
  std::string text;
  if (const Status st = io::ReadFile(path, kMaxPaperTablesBytes, &text); !st.ok()) return st;
  return ParsePaperTables(text, path, rows);
}

namespace {

// ParsePaperTables() with the refusal's message in *error.
bool ParsePaperTablesOrExplain(const std::string& csv, const std::string& path, std::vector<PaperRow>* rows,
                               std::string* error) {
  std::istringstream in(csv);
  std::string line;
  if (!std::getline(in, line)) {
    *error = path + " is empty";
    return false;
  }
  Columns col;
  if (!ParseHeader(line, path, &col, error)) return false;
  rows->clear();
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (Trim(line).empty()) continue;
    try {
      rows->push_back(ParseRow(SplitCsv(line), col, path, number));
    } catch (const std::invalid_argument& e) {
      *error = e.what();
      return false;
    }
  }
  if (rows->empty()) {
    *error = path + " has no rows";
    return false;
  }
  return true;
}

}  // namespace

Status ParsePaperTables(const std::string& csv, const std::string& path, std::vector<PaperRow>* rows) {
  std::string why;
  if (!ParsePaperTablesOrExplain(csv, path, rows, &why)) return Status::InvalidInput(why);
  return Status::Ok();
}

}  // namespace pidlab::report
