#pragma once
// The live scope's binary frames (docs/live.md, "Frames"), little-endian:
//   bytes 0-3   uint32 magic 0x31564C50 ("PLV1")
//   bytes 4-7   uint32 kind: 1 = view (min/max columns), 2 = full data
//   bytes 8-71  eight float64: episode_id, first_step, steps, columns, dt_s,
//               total_steps, steps_done, dropped_frames
//   kind 1      six float32 arrays of `columns` values: y_min, y_max, u_min,
//               u_max, n_min, n_max (DecimateMinMax)
//   kind 2      three float64 arrays of `steps` values: y, u, n, bit for bit
// Pure functions: the page and the tests read the same bytes.

#include <cstdint>
#include <string>
#include <vector>

namespace pidlab::monitor {

inline constexpr uint32_t kFrameMagic = 0x31564C50;  // "PLV1" in little-endian bytes
inline constexpr uint32_t kViewFrame = 1;
inline constexpr uint32_t kDataFrame = 2;
inline constexpr std::size_t kFrameHeaderBytes = 72;
/// Columns a view may ask for.
inline constexpr int kMinColumns = 16;
inline constexpr int kMaxColumns = 4096;

/// What every frame's header says besides its layout.
struct FrameInfo {
  int64_t episode_id = 0;
  double dt_s = 0.0;
  long total_steps = 0;
  long steps_done = 0;
  long dropped_frames = 0;
};

/// Column j of `columns` covers steps [floor(j steps / columns),
/// floor((j + 1) steps / columns)); if steps <= columns, one column per step.
/// Each column's min and max of its values (NaN skipped; a column without a
/// value is NaN), never an average. *min and *max get the column count.
void DecimateMinMax(const double* values, long steps, int columns, std::vector<float>* min,
                    std::vector<float>* max);

/// A kind-1 frame of steps 0..steps-1 of y, u, n in min(columns, steps) columns.
std::string EncodeViewFrame(const FrameInfo& info, const double* y, const double* u, const double* n,
                            long steps, int columns);
/// A kind-2 frame of steps first_step..first_step+steps-1 (the arrays start
/// at first_step), columns = 0.
std::string EncodeDataFrame(const FrameInfo& info, long first_step, const double* y, const double* u,
                            const double* n, long steps);

}  // namespace pidlab::monitor
