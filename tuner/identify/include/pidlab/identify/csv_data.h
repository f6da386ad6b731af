#pragma once
// A record for Identify() read from a CSV file whose header names the
// columns t, u and y (any order, other columns ignored).

#include <cstddef>
#include <string>
#include <vector>

#include "pidlab/identify/identify.h"
#include "pidlab/spec/status.h"

namespace pidlab::identify {

/// The most a CSV record may hold (about 10^7 rows).
inline constexpr std::size_t kMaxCsvBytes = std::size_t{512} << 20;

/// kInvalidInput with one line naming the file, and the column, row (the
/// file's line number) and value where one is at fault; invisible bytes in
/// an echoed value are written as \xHH. A UTF-8 BOM is skipped, CRLF line
/// ends and RFC 4180 quoted fields are read. `rows` (if given): each
/// sample's line in the file, for CheckData's messages.
Status ReadCsvData(const std::string& path, IdentifyData* data, std::vector<long>* rows = nullptr);

}  // namespace pidlab::identify
