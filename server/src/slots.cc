// The server's connection and body budget: see slots.h.

#include "slots.h"

#include <utility>
#include <vector>

namespace pidlab::server::internal {

Slots::Id Slots::Open(const std::string& address) {
  Entry& e = entries_[++last_];
  e.address = address;
  e.since = Clock::now();
  return last_;
}

void Slots::Close(Id id) {
  ReleaseBody(id);
  entries_.erase(id);
}

void Slots::Idle(Id id, std::function<void()> close) {
  const auto e = entries_.find(id);
  if (e == entries_.end()) return;
  e->second.since = Clock::now();
  e->second.close = std::move(close);
}

void Slots::Touch(Id id) {
  const auto e = entries_.find(id);
  if (e != entries_.end()) e->second.since = Clock::now();
}

void Slots::Busy(Id id) {
  const auto e = entries_.find(id);
  if (e != entries_.end()) e->second.close = nullptr;
}

void Slots::OnStop(Id id, std::function<void()> close) {
  const auto e = entries_.find(id);
  if (e != entries_.end()) e->second.stop = std::move(close);
}

void Slots::CloseAll() {
  std::vector<std::function<void()>> stops;
  for (auto& [id, e] : entries_)
    if (e.stop) stops.push_back(std::move(e.stop));
  for (const auto& stop : stops) stop();
}

int Slots::Count(const std::string* address) const {
  if (!address) return static_cast<int>(entries_.size());
  int n = 0;
  for (const auto& [id, e] : entries_) n += e.address == *address;
  return n;
}

bool Slots::EvictIdleLongest(const std::string* address) {
  auto oldest = entries_.end();
  for (auto e = entries_.begin(); e != entries_.end(); ++e)
    if (e->second.close && (!address || e->second.address == *address) &&
        (oldest == entries_.end() || e->second.since < oldest->second.since))
      oldest = e;
  if (oldest == entries_.end()) return false;
  const std::function<void()> close = std::move(oldest->second.close);
  body_bytes_ -= oldest->second.body_bytes;
  entries_.erase(oldest);
  close();
  return true;
}

bool Slots::MakeRoom(const std::string& address, int per_address_cap, int cap, int* evicted) {
  const auto evict = [this, evicted](const std::string* of) {
    if (!EvictIdleLongest(of)) return false;
    ++*evicted;
    return true;
  };
  if (Count(&address) >= per_address_cap && !evict(&address)) return false;
  return Count(nullptr) < cap || evict(nullptr);
}

bool Slots::HoldBody(Id id, std::size_t bytes, std::size_t budget) {
  const auto e = entries_.find(id);
  if (e == entries_.end()) return false;
  const std::size_t others = body_bytes_ - e->second.body_bytes;
  if (bytes > budget || others > budget - bytes) return false;
  body_bytes_ = others + bytes;
  e->second.body_bytes = bytes;
  return true;
}

void Slots::ReleaseBody(Id id) {
  const auto e = entries_.find(id);
  if (e == entries_.end()) return;
  body_bytes_ -= e->second.body_bytes;
  e->second.body_bytes = 0;
}

}  // namespace pidlab::server::internal
