#include "pidlab/identify/csv_data.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "pidlab/spec/field.h"

namespace pidlab::identify {
namespace {

std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  for (std::string cell; std::getline(ss, cell, ',');) {
    const auto first = cell.find_first_not_of(" \t\r\"");
    const auto last = cell.find_last_not_of(" \t\r\"");
    cells.push_back(first == std::string::npos ? "" : cell.substr(first, last - first + 1));
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

bool ParseNumber(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  *value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && errno != ERANGE;
}

}  // namespace

Status ReadCsvData(const std::string& path, IdentifyData* data) {
  const std::string file = spec::Quote(path);
  std::ifstream in(path);
  if (!in) return Status::InvalidInput(file + " cannot be read");
  std::string line;
  if (!std::getline(in, line))
    return Status::InvalidInput(file + " is empty: a header naming t, u and y is needed");
  const std::vector<std::string> header = SplitCells(line);
  const char* const kNames[] = {"t", "u", "y"};
  std::size_t column[3];
  for (int c = 0; c < 3; ++c) {
    column[c] = header.size();
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == kNames[c]) column[c] = i;
    if (column[c] == header.size())
      return Status::InvalidInput(file + ": the header " + spec::Quote(line) + " names no column " +
                                  kNames[c] + " (t, u and y are needed)");
  }
  *data = IdentifyData{};
  std::vector<double>* const series[] = {&data->t, &data->u, &data->y};
  for (long row = 2; std::getline(in, line); ++row) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::vector<std::string> cells = SplitCells(line);
    for (int c = 0; c < 3; ++c) {
      const std::string cell = column[c] < cells.size() ? cells[column[c]] : "";
      double value = 0.0;
      if (!ParseNumber(cell, &value))
        return Status::InvalidInput(file + " row " + std::to_string(row) + ", column " + kNames[c] + ": " +
                                    spec::Quote(cell) + " is not a number");
      series[c]->push_back(value);
    }
  }
  return Status::Ok();
}

}  // namespace pidlab::identify
