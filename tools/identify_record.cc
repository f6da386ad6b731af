#include "identify_record.h"

#include <vector>

#include "pidlab/identify/csv_data.h"

namespace pidlab::cli {

Status ReadCsvRecord(const std::string& path, const std::string& source, identify::IdentifyData* data) {
  std::vector<long> rows;
  if (Status st = identify::ReadCsvData(path, data, &rows); !st.ok()) return st;
  identify::Sampling sampling;
  if (Status st = identify::CheckData(*data, &sampling, &rows); !st.ok())
    return Status(st.code(), source + ": " + st.message());
  return Status::Ok();
}

bool EpisodeInputVaries(const replay::Episode& e) {
  for (long k = 1; k < e.total_steps; ++k) {
    const auto i = static_cast<std::size_t>(k);
    if (e.u[i] + e.n[i] != e.u[0] + e.n[0]) return true;
  }
  return false;
}

identify::IdentifyData EpisodeRecord(const replay::Episode& e) {
  identify::IdentifyData data;
  for (long k = 0; k < e.total_steps; ++k) {
    const auto i = static_cast<std::size_t>(k);
    data.t.push_back(static_cast<double>(k) * e.spec.dt_s);
    data.u.push_back(e.u[i] + e.n[i]);
    data.y.push_back(e.y[i]);
  }
  return data;
}

}  // namespace pidlab::cli
