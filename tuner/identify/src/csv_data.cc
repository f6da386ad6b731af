#include "pidlab/identify/csv_data.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "pidlab/io/files.h"
#include "pidlab/spec/field.h"

namespace pidlab::identify {
namespace {

// The cells of one CSV line (RFC 4180): commas split, a field in double
// quotes may hold commas, and "" inside it is one quote; blanks around a
// cell and a line's CR (a CRLF file) are dropped.
std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cells.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cells.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.emplace_back();
    } else {
      cells.back() += c;
    }
  }
  for (std::string& cell : cells) {
    const auto first = cell.find_first_not_of(" \t\r");
    const auto last = cell.find_last_not_of(" \t\r");
    cell = first == std::string::npos ? "" : cell.substr(first, last - first + 1);
  }
  return cells;
}

bool ParseNumber(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  *value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && errno != ERANGE;
}

// A value as a message shows it: quoted, at most kMaxEchoedChars, and every
// byte that would not be seen (a BOM, a CR, a control or non-ASCII byte)
// written as \xHH.
std::string Visible(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (out.size() >= spec::kMaxEchoedChars) {
      out += "...";
      break;
    }
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  return "'" + out + "'";
}

constexpr char kUtf8Bom[] = "\xef\xbb\xbf";

}  // namespace

Status ReadCsvData(const std::string& path, IdentifyData* data, std::vector<long>* rows) {
  const std::string file = spec::Quote(path);
  std::string text;
  if (Status s = io::ReadFile(path, kMaxCsvBytes, &text); !s.ok()) return s;
  if (text.compare(0, 3, kUtf8Bom) == 0) text.erase(0, 3);  // what Excel writes first
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line.find_first_not_of(" \t\r") == std::string::npos)
    return Status::InvalidInput(file + " is empty: a header naming t, u and y is needed");
  const std::vector<std::string> header = SplitCells(line);
  const char* const kNames[] = {"t", "u", "y"};
  std::size_t column[3];
  for (int c = 0; c < 3; ++c) {
    column[c] = header.size();
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == kNames[c]) column[c] = i;
    if (column[c] == header.size())
      return Status::InvalidInput(file + ": the header " + Visible(line) + " names no column " + kNames[c] +
                                  " (t, u and y are needed)");
  }
  *data = IdentifyData{};
  if (rows) rows->clear();
  std::vector<double>* const series[] = {&data->t, &data->u, &data->y};
  for (long row = 2; std::getline(in, line); ++row) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::vector<std::string> cells = SplitCells(line);
    for (int c = 0; c < 3; ++c) {
      const std::string cell = column[c] < cells.size() ? cells[column[c]] : "";
      double value = 0.0;
      if (!ParseNumber(cell, &value))
        return Status::InvalidInput(file + " row " + std::to_string(row) + ", column " + kNames[c] + ": " +
                                    Visible(cell) + " is not a number");
      series[c]->push_back(value);
    }
    if (rows) rows->push_back(row);
  }
  return Status::Ok();
}

}  // namespace pidlab::identify
