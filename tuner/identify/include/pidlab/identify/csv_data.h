#pragma once
// A record for Identify() read from a CSV file whose header names the
// columns t, u and y (any order, other columns ignored).

#include <string>

#include "pidlab/identify/identify.h"
#include "pidlab/spec/status.h"

namespace pidlab::identify {

/// kInvalidInput with one line naming the file, and the column, row (the
/// file's line number) and value where one is at fault.
Status ReadCsvData(const std::string& path, IdentifyData* data);

}  // namespace pidlab::identify
