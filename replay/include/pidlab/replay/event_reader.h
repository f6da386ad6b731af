#pragma once
// Reading the events of an LCM log (lcm-logger's file format) without liblcm.
//
// An event on disk, all integers big-endian:
//   uint32 sync word 0xEDA1DA01, int64 eventnum, int64 timestamp (us),
//   int32 channel length, int32 data length, channel bytes, data bytes.
// liblcm's reader trusts the two lengths (a data length of 0x7fffffff makes it
// calloc 2 GiB and read into the result unchecked). This reader checks both
// against sane limits and the bytes left in the file before it allocates
// anything, so its memory is bounded by the largest event it returns plus a
// fixed read buffer. Bytes that are not a whole event are skipped up to the
// next sync word and reported; a cut-off or corrupt end of the file is
// reported as the tail.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pidlab/spec/status.h"

namespace pidlab::replay {

/// One event of the log.
struct LogEvent {
  int64_t eventnum = 0;
  int64_t timestamp = 0;  // microseconds since the epoch
  std::string channel;
  std::vector<uint8_t> data;
  long long offset = 0;  // of its sync word in the file
};

/// A stretch of the file that is not an event: [from, to).
struct SkippedBytes {
  enum class Kind {
    kGarbage,       // bytes without a sync word, between events
    kCorruptEvent,  // a sync word whose header is not a whole, sane event
  };
  Kind kind = Kind::kGarbage;
  long long from = 0, to = 0;
};

class EventReader {
 public:
  static constexpr uint32_t kSyncWord = 0xEDA1DA01u;
  static constexpr int kHeaderBytes = 28;
  /// Longest channel name accepted, bytes (LCM itself allows 63).
  static constexpr int32_t kMaxChannelBytes = 256;
  /// Largest event payload accepted, bytes (a UDP datagram of LCM is at most
  /// 64 KiB; fragmented messages up to a few MiB). Longer data lengths are
  /// taken for corruption and skipped.
  static constexpr int32_t kMaxDataBytes = 64 * 1024 * 1024;

  EventReader() = default;
  ~EventReader();
  EventReader(const EventReader&) = delete;
  EventReader& operator=(const EventReader&) = delete;

  /// Opens the log at `path` (a regular file; once per reader) with
  /// io::OpenRegularFile: a FIFO or a folder is refused at once. A failed
  /// Status (kInvalidInput), a line naming the path, if it cannot be opened.
  Status Open(const std::string& path);

  /// Called for every stretch of bytes skipped while looking for the next
  /// event (optional; the counts below are kept either way).
  void OnSkip(std::function<void(const SkippedBytes&)> handler) { on_skip_ = std::move(handler); }

  /// Reads the next whole event into *event. False at the end of the file,
  /// or at the start of bytes up to the end that hold no whole event (tail()).
  bool Next(LogEvent* event);

  long long file_bytes() const { return file_bytes_; }
  /// Offset up to which the file was read: events and skipped stretches; the
  /// tail's start if there is one.
  long long bytes_read() const { return pos_; }
  long events() const { return events_; }
  /// Events whose eventnum is not the previous one plus one (events lost by
  /// the logger, or corrupt counters).
  long eventnum_gaps() const { return eventnum_gaps_; }
  long skipped_stretches() const { return skipped_stretches_; }
  long long skipped_bytes() const { return skipped_bytes_; }
  /// After Next() returned false: whether the file ends with bytes that are
  /// not a whole event (cut off mid-write, or a corrupt tail), and where.
  bool has_tail() const { return has_tail_; }
  long long tail_offset() const { return has_tail_ ? pos_ : file_bytes_; }
  long long tail_bytes() const { return has_tail_ ? file_bytes_ - pos_ : 0; }
  /// Nothing skipped and no tail (so far).
  bool clean() const { return skipped_stretches_ == 0 && !has_tail_; }

 private:
  struct Header {
    int64_t eventnum = 0, timestamp = 0;
    int32_t channel_bytes = 0, data_bytes = 0;
  };
  bool FindSync(long long from, long long* at);
  bool ReadHeader(long long at, Header* header);
  bool ReadEvent(long long at, LogEvent* event);
  bool Fill(long long at);
  bool Load(long long at);
  bool ReadAt(long long at, std::size_t n, uint8_t* out);
  void Skip(SkippedBytes::Kind kind, long long from, long long to);
  void CountEvent(int64_t eventnum);

  int fd_ = -1;
  long long file_bytes_ = 0;
  long long pos_ = 0;
  std::vector<uint8_t> buffer_;  // bytes of the file from buffer_at_
  long long buffer_at_ = 0;
  std::size_t buffer_bytes_ = 0;
  std::function<void(const SkippedBytes&)> on_skip_;
  long events_ = 0, eventnum_gaps_ = 0, skipped_stretches_ = 0;
  long long skipped_bytes_ = 0;
  bool has_last_eventnum_ = false;
  uint64_t last_eventnum_ = 0;
  bool has_tail_ = false;
};

}  // namespace pidlab::replay
