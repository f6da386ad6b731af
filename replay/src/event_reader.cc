#include "pidlab/replay/event_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "pidlab/io/files.h"

namespace pidlab::replay {
namespace {

constexpr std::size_t kBufferBytes = 64 * 1024;

uint64_t BigEndian(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

// pread until n bytes are in, or the end of the file or an error.
bool ReadFully(int fd, long long at, std::size_t n, uint8_t* out) {
  while (n > 0) {
    const ssize_t got = pread(fd, out, n, static_cast<off_t>(at));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    out += got;
    at += got;
    n -= static_cast<std::size_t>(got);
  }
  return true;
}

}  // namespace

EventReader::~EventReader() {
  if (fd_ >= 0) close(fd_);
}

Status EventReader::Open(const std::string& path) {
  if (fd_ >= 0) {
    return Status::IoFailed("log '" + path + "': this reader already has a file open");
  }
  // A FIFO or a device is refused before anything waits on it.
  if (Status s = io::OpenRegularFile(path, &fd_); !s.ok()) {
    fd_ = -1;
    return Status(s.code(), "log " + s.message());
  }
  struct stat st {};
  if (fstat(fd_, &st) != 0) {
    return Status::IoFailed("log '" + path + "' cannot be opened as an LCM log: " + std::strerror(errno));
  }
  // Only what the file holds now: a logger may still be appending.
  file_bytes_ = static_cast<long long>(st.st_size);
  buffer_.resize(kBufferBytes);
  return Status::Ok();
}

bool EventReader::Next(LogEvent* event) {
  while (fd_ >= 0 && pos_ < file_bytes_) {
    long long at = 0, next = 0;
    if (!FindSync(pos_, &at)) break;
    if (ReadEvent(at, event)) {
      if (at > pos_) Skip(SkippedBytes::Kind::kGarbage, pos_, at);
      pos_ = at + kHeaderBytes + static_cast<long long>(event->channel.size() + event->data.size());
      CountEvent(event->eventnum);
      return true;
    }
    // Not a whole event: resume at the next sync word, if there is one.
    if (!FindSync(at + 1, &next)) break;
    if (at > pos_) Skip(SkippedBytes::Kind::kGarbage, pos_, at);
    Skip(SkippedBytes::Kind::kCorruptEvent, at, next);
    pos_ = next;
  }
  has_tail_ = pos_ < file_bytes_;
  return false;
}

// Offset of the first sync word at or after `from` wholly inside the file.
bool EventReader::FindSync(long long from, long long* at) {
  uint32_t window = 0;
  for (long long pos = from; pos < file_bytes_;) {
    if (!Fill(pos)) return false;
    for (std::size_t i = static_cast<std::size_t>(pos - buffer_at_); i < buffer_bytes_; ++i, ++pos) {
      window = (window << 8) | buffer_[i];
      if (pos - from >= 3 && window == kSyncWord) {
        *at = pos - 3;
        return true;
      }
    }
  }
  return false;
}

// The header at `at` if it is a sync word followed by sane lengths, and the
// whole event lies inside the file.
bool EventReader::ReadHeader(long long at, Header* h) {
  uint8_t b[kHeaderBytes];
  if (file_bytes_ - at < kHeaderBytes || !ReadAt(at, sizeof b, b)) return false;
  if (BigEndian(b, 4) != kSyncWord) return false;
  h->eventnum = static_cast<int64_t>(BigEndian(b + 4, 8));
  h->timestamp = static_cast<int64_t>(BigEndian(b + 12, 8));
  h->channel_bytes = static_cast<int32_t>(static_cast<uint32_t>(BigEndian(b + 20, 4)));
  h->data_bytes = static_cast<int32_t>(static_cast<uint32_t>(BigEndian(b + 24, 4)));
  if (h->channel_bytes < 1 || h->channel_bytes > kMaxChannelBytes) return false;
  if (h->data_bytes < 0 || h->data_bytes > kMaxDataBytes) return false;
  // Each length is below 2^31: no overflow.
  const long long left = file_bytes_ - at - kHeaderBytes;
  return static_cast<long long>(h->channel_bytes) + h->data_bytes <= left;
}

bool EventReader::ReadEvent(long long at, LogEvent* event) {
  Header h;
  if (!ReadHeader(at, &h)) return false;  // before anything is allocated
  event->eventnum = h.eventnum;
  event->timestamp = h.timestamp;
  event->offset = at;
  event->channel.assign(static_cast<std::size_t>(h.channel_bytes), '\0');
  event->data.resize(static_cast<std::size_t>(h.data_bytes));
  const long long channel_at = at + kHeaderBytes;
  return ReadAt(channel_at, event->channel.size(), reinterpret_cast<uint8_t*>(&event->channel[0])) &&
         ReadAt(channel_at + h.channel_bytes, event->data.size(), event->data.data());
}

// Makes the buffer hold the byte at `at` (false at the end of the file).
bool EventReader::Fill(long long at) {
  if (at >= buffer_at_ && at < buffer_at_ + static_cast<long long>(buffer_bytes_)) return true;
  return Load(at);
}

// Reads the buffer's worth of the file from `at`.
bool EventReader::Load(long long at) {
  if (at < 0 || at >= file_bytes_) return false;
  const auto n = static_cast<std::size_t>(std::min<long long>(kBufferBytes, file_bytes_ - at));
  buffer_bytes_ = 0;
  if (!ReadFully(fd_, at, n, buffer_.data())) return false;
  buffer_at_ = at;
  buffer_bytes_ = n;
  return true;
}

// n bytes at `at` (inside the file), through the buffer when they fit in it.
bool EventReader::ReadAt(long long at, std::size_t n, uint8_t* out) {
  if (n == 0) return true;
  if (n > kBufferBytes) return ReadFully(fd_, at, n, out);
  const auto end = at + static_cast<long long>(n);
  if (at < buffer_at_ || end > buffer_at_ + static_cast<long long>(buffer_bytes_)) {
    if (!Load(at) || end > buffer_at_ + static_cast<long long>(buffer_bytes_)) return false;
  }
  std::memcpy(out, buffer_.data() + (at - buffer_at_), n);
  return true;
}

void EventReader::Skip(SkippedBytes::Kind kind, long long from, long long to) {
  ++skipped_stretches_;
  skipped_bytes_ += to - from;
  if (on_skip_) on_skip_(SkippedBytes{kind, from, to});
}

// Gaps in the logger's counter, in unsigned arithmetic: any eventnum, even
// INT64_MAX or a negative one, is compared without overflow.
void EventReader::CountEvent(int64_t eventnum) {
  const auto n = static_cast<uint64_t>(eventnum);
  if (has_last_eventnum_ && n != last_eventnum_ + 1u) ++eventnum_gaps_;
  has_last_eventnum_ = true;
  last_eventnum_ = n;
  ++events_;
}

}  // namespace pidlab::replay
