#include "pidlab/episode_client/episode_pool.h"

#include <atomic>
#include <exception>
#include <stdexcept>
#include <thread>

namespace pidlab::episode_client {
namespace {

// The trio of the pool worker running on this thread; -1 off a worker.
thread_local int current_trio = -1;

}  // namespace

struct EpisodePool::Trio {
  std::unique_ptr<EpisodeClient> client;
  std::string url;
  std::mutex busy;  // one episode at a time on a trio
  bool alive = true;
};

std::vector<std::string> SplitUrlList(const std::string& list) {
  std::vector<std::string> urls;
  std::string item;
  for (char c : list + " ") {
    if (c == ' ' || c == ',' || c == '\t' || c == '\n') {
      if (!item.empty()) urls.push_back(item);
      item.clear();
    } else {
      item += c;
    }
  }
  return urls;
}

EpisodePool::EpisodePool(const std::vector<EpisodeClientOptions>& trios) {
  if (trios.empty()) throw std::invalid_argument("an episode pool needs at least one trio");
  on_note_ = trios.front().on_note;
  for (const EpisodeClientOptions& options : trios) {
    auto trio = std::make_unique<Trio>();
    trio->client = std::make_unique<EpisodeClient>(options);
    if (status_.ok() && !trio->client->status().ok()) status_ = trio->client->status();
    trio->url = options.lcm_url;
    trios_.push_back(std::move(trio));
  }
}

EpisodePool::~EpisodePool() = default;

int EpisodePool::Pick(int preferred) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const int n = size();
  if (preferred < 0 || preferred >= n) preferred = 0;
  for (int i = 0; i < n; ++i) {
    const int t = (preferred + i) % n;
    if (trios_[static_cast<std::size_t>(t)]->alive) return t;
  }
  return -1;
}

bool EpisodePool::Run(const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                      const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                      std::vector<evaluation::SampledStep>* trajectory, std::string* error) {
  std::string last_error;
  for (;;) {
    const int t = Pick(current_trio);
    if (t < 0) {
      if (error) *error = "every trio failed; the last: " + last_error;
      return false;
    }
    Trio& trio = *trios_[static_cast<std::size_t>(t)];
    std::lock_guard<std::mutex> busy(trio.busy);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!trio.alive) continue;  // left out while we waited
    }
    const Status ran = trio.client->Run(plant, gains, options, disturbance, y_all, trajectory);
    if (ran.ok()) return true;
    const std::string why = ran.message();
    if (!trio.client->last_failure_retryable()) {
      if (error) *error = why;
      return false;
    }
    last_error = why;
    const std::string line = "trio " + std::to_string(t + 1) + " (" + trio.url + ") left out: " + why;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      trio.alive = false;
      lost_.push_back(line);
    }
    if (on_note_) on_note_(line + "; its episode runs on another trio");
  }
}

evaluation::SampledRunner EpisodePool::AsRunner() {
  return [this](const Plant& plant, const PidGains& gains, const evaluation::LoopOptions& options,
                const DisturbanceOptions& disturbance, std::vector<double>* y_all,
                std::vector<evaluation::SampledStep>* trajectory) {
    std::string why;
    if (!Run(plant, gains, options, disturbance, y_all, trajectory, &why)) return Status::RunnerFailed(why);
    return Status::Ok();
  };
}

optim::ParallelFor EpisodePool::AsParallelFor() {
  return [this](int count, const std::function<void(int)>& body) {
    if (count <= 0) return;
    std::vector<std::exception_ptr> errors(static_cast<std::size_t>(count));
    std::atomic<int> next{0};
    auto work = [&](int trio) {
      current_trio = trio;
      for (int i; (i = next.fetch_add(1)) < count;) {
        try {
          body(i);
        } catch (...) {
          errors[static_cast<std::size_t>(i)] = std::current_exception();
        }
      }
      current_trio = -1;
    };
    std::vector<std::thread> workers;
    for (int t = 0; t < size(); ++t) {
      bool alive;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        alive = trios_[static_cast<std::size_t>(t)]->alive;
      }
      if (alive && static_cast<int>(workers.size()) < count) workers.emplace_back(work, t);
    }
    if (workers.empty()) work(0);  // every trio is out: the runner says so
    for (std::thread& w : workers) w.join();
    for (const std::exception_ptr& e : errors)
      if (e) std::rethrow_exception(e);
  };
}

std::vector<std::string> EpisodePool::lost() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return lost_;
}

EpisodeClientStats EpisodePool::stats() const {
  EpisodeClientStats sum;
  for (const auto& trio : trios_) {
    const EpisodeClientStats& s = trio->client->stats();
    sum.episodes += s.episodes;
    sum.steps += s.steps;
    sum.seconds += s.seconds;
    sum.resend_requests += s.resend_requests;
    sum.reruns += s.reruns;
  }
  return sum;
}

}  // namespace pidlab::episode_client
