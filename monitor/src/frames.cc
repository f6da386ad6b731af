#include "pidlab/monitor/frames.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace pidlab::monitor {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the frames are written in the host's byte order");

template <typename T>
void Append(std::string* out, const T* values, std::size_t count) {
  const std::size_t at = out->size();
  out->resize(at + count * sizeof(T));
  if (count > 0) std::memcpy(out->data() + at, values, count * sizeof(T));
}

std::string Header(uint32_t kind, const FrameInfo& info, long first_step, long steps, long columns) {
  std::string out;
  const uint32_t words[2] = {kFrameMagic, kind};
  Append(&out, words, 2);
  const double fields[8] = {static_cast<double>(info.episode_id),
                            static_cast<double>(first_step),
                            static_cast<double>(steps),
                            static_cast<double>(columns),
                            info.dt_s,
                            static_cast<double>(info.total_steps),
                            static_cast<double>(info.steps_done),
                            static_cast<double>(info.dropped_frames)};
  Append(&out, fields, 8);
  return out;
}

}  // namespace

void DecimateMinMax(const double* values, long steps, int columns, std::vector<float>* min,
                    std::vector<float>* max) {
  const long n = steps <= 0 ? 0 : std::min<long>(steps, std::max(columns, 0));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  min->assign(static_cast<std::size_t>(n), nan);
  max->assign(static_cast<std::size_t>(n), nan);
  for (long j = 0; j < n; ++j) {
    const long first = static_cast<long>(static_cast<int64_t>(j) * steps / n);
    const long end = static_cast<long>(static_cast<int64_t>(j + 1) * steps / n);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    bool any = false;
    for (long k = first; k < end; ++k) {
      const double v = values[k];
      if (std::isnan(v)) continue;
      any = true;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (!any) continue;
    (*min)[static_cast<std::size_t>(j)] = static_cast<float>(lo);
    (*max)[static_cast<std::size_t>(j)] = static_cast<float>(hi);
  }
}

std::string EncodeViewFrame(const FrameInfo& info, const double* y, const double* u, const double* n,
                            long steps, int columns) {
  std::vector<float> lo, hi;
  DecimateMinMax(y, steps, columns, &lo, &hi);
  std::string out = Header(kViewFrame, info, 0, std::max(steps, 0L), static_cast<long>(lo.size()));
  out.reserve(kFrameHeaderBytes + 6 * lo.size() * sizeof(float));
  Append(&out, lo.data(), lo.size());
  Append(&out, hi.data(), hi.size());
  for (const double* series : {u, n}) {
    DecimateMinMax(series, steps, columns, &lo, &hi);
    Append(&out, lo.data(), lo.size());
    Append(&out, hi.data(), hi.size());
  }
  return out;
}

std::string EncodeDataFrame(const FrameInfo& info, long first_step, const double* y, const double* u,
                            const double* n, long steps) {
  const std::size_t count = static_cast<std::size_t>(std::max(steps, 0L));
  std::string out = Header(kDataFrame, info, first_step, static_cast<long>(count), 0);
  out.reserve(kFrameHeaderBytes + 3 * count * sizeof(double));
  for (const double* series : {y, u, n}) Append(&out, series, count);
  return out;
}

}  // namespace pidlab::monitor
