#include "thread_team.h"

#if defined(__linux__) && !defined(__EMSCRIPTEN__)
#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>
#define GRADEL_HAVE_FUTEX 1
#endif

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <thread>

namespace gradel {

namespace {

std::atomic<int> gSleepers{0};  // members of any team asleep in futexWait (skips needless wake calls)

// How long a waiting member spins before it sleeps [us]. Long enough to cover the gap between
// two stages of one step on a quiet machine, short enough that a member waiting for a
// descheduled one soon gives its core away. GRADEL_SPIN_US overrides it (for measurements).
long spinMicros() {
  static const long us = [] {
    const char* s = std::getenv("GRADEL_SPIN_US");
    return s ? std::strtol(s, nullptr, 10) : 50L;
  }();
  return us;
}

inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Returns once word != old: spins for spinMicros(), then sleeps on a futex.
void waitWhileEqual(const std::atomic<uint32_t>& word, uint32_t old) {
  if (word.load(std::memory_order_acquire) != old) return;
  const auto limit = std::chrono::steady_clock::now() + std::chrono::microseconds(spinMicros());
  for (int i = 1;; ++i) {
    cpuRelax();
    if (word.load(std::memory_order_acquire) != old) return;
    if ((i & 63) == 0 && std::chrono::steady_clock::now() > limit) break;
  }
#ifdef GRADEL_HAVE_FUTEX
  gSleepers.fetch_add(1, std::memory_order_seq_cst);
  while (word.load(std::memory_order_seq_cst) == old)
    syscall(SYS_futex, reinterpret_cast<const uint32_t*>(&word), FUTEX_WAIT_PRIVATE, old, nullptr, nullptr, 0);
  gSleepers.fetch_sub(1, std::memory_order_seq_cst);
#else
  while (word.load(std::memory_order_seq_cst) == old) std::this_thread::yield();  // no futex: yield instead
#endif
}

void wakeAll([[maybe_unused]] std::atomic<uint32_t>& word) {
#ifdef GRADEL_HAVE_FUTEX
  if (gSleepers.load(std::memory_order_seq_cst) > 0)
    syscall(SYS_futex, reinterpret_cast<uint32_t*>(&word), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr, nullptr, 0);
#endif
}

}  // namespace

void ChunkQueue::reset(const std::vector<size_t>& split) {
  if (shares_.size() != split.size() - 1) shares_ = std::vector<Share>(split.size() - 1);
  for (size_t t = 0; t + 1 < split.size(); ++t) {
    shares_[t].next.store(split[t], std::memory_order_relaxed);
    shares_[t].end = split[t + 1];
  }
}

bool ChunkQueue::claim(int t, size_t* chunkIndex) {
  const size_t n = shares_.size();
  for (size_t k = 0; k < n; ++k) {
    Share& s = shares_[(size_t(t) + k) % n];
    if (s.next.load(std::memory_order_relaxed) >= s.end) continue;
    const size_t i = s.next.fetch_add(1, std::memory_order_relaxed);
    if (i < s.end) {
      *chunkIndex = i;
      return true;
    }
  }
  return false;
}

ThreadTeam::ThreadTeam(int members) : members_(members < 1 ? 1 : members) {
  workers_.reserve(size_t(members_ - 1));
  for (int t = 1; t < members_; ++t) workers_.emplace_back([this, t] { workerLoop(t); });
}

ThreadTeam::~ThreadTeam() {
  if (workers_.empty()) return;
  stop_ = true;
  jobGeneration_.fetch_add(1, std::memory_order_seq_cst);
  wakeAll(jobGeneration_);
  for (std::thread& w : workers_) w.join();
}

void ThreadTeam::workerLoop(int t) {
  uint32_t seen = 0;
  for (;;) {
    waitWhileEqual(jobGeneration_, seen);
    seen = jobGeneration_.load(std::memory_order_acquire);
    if (stop_) return;
    call_(job_, t);
    doneCount_.fetch_add(1, std::memory_order_seq_cst);
    wakeAll(doneCount_);
  }
}

void ThreadTeam::dispatch(Call call, void* job) {
  call_ = call, job_ = job;
  doneCount_.store(0, std::memory_order_relaxed);
  jobGeneration_.fetch_add(1, std::memory_order_seq_cst);  // publishes call_ and job_
  wakeAll(jobGeneration_);
  call(job, 0);
  const uint32_t all = uint32_t(members_ - 1);
  for (uint32_t done; (done = doneCount_.load(std::memory_order_acquire)) != all;) waitWhileEqual(doneCount_, done);
}

void ThreadTeam::barrier() {
  if (members_ == 1) return;
  const uint32_t generation = barrierGeneration_.load(std::memory_order_acquire);
  if (barrierCount_.fetch_add(1, std::memory_order_acq_rel) + 1 == uint32_t(members_)) {
    barrierCount_.store(0, std::memory_order_relaxed);
    barrierGeneration_.fetch_add(1, std::memory_order_seq_cst);
    wakeAll(barrierGeneration_);
  } else {
    waitWhileEqual(barrierGeneration_, generation);
  }
}

void ThreadGovernor::report(double seconds) {
  time_ += seconds, ++steps_;
  const bool windowDone = time_ >= kWindowSeconds && steps_ >= kWindowSteps;
  switch (phase_) {
    case Phase::MeasureCurrent:
      if (!windowDone) return;
      current_ = time_ / steps_;
      phase_ = Phase::ProbeOther;
      break;
    case Phase::ProbeOther:
      if (!windowDone) return;
      other_ = time_ / steps_;
      phase_ = Phase::MeasureAgain;
      break;
    case Phase::MeasureAgain:
      if (!windowDone) return;
      current_ = std::min(current_, time_ / steps_);
      if (other_ < kMargin * current_) useOne_ = !useOne_;
      phase_ = Phase::Run;
      break;
    case Phase::Run:
      if (time_ < kRunSeconds) return;
      phase_ = Phase::MeasureCurrent;
      break;
  }
  time_ = 0, steps_ = 0;
}

}  // namespace gradel
