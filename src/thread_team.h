// A persistent team of worker threads for the explicit step (private to the engine).
//
// Why not OpenMP: measured on the 2-core machine (docs/speed.md, "Threads"), libgomp's default waiting
// spins for a long time at every barrier, so with one other busy program on the machine two
// threads ran 3x slower than one; its passive policy can only be chosen by an environment
// variable read when the program loads. This team
//  - waits by spinning briefly (kSpinMicros) and then sleeping on a futex, so a waiting member
//    gives its core back to whoever needs it (another program, or the member it waits for);
//  - hands out work in chunks: each member starts on its own contiguous share (the same share
//    every step, so its part of the arrays stays in its core's cache) and, when done, takes the
//    chunks left in the other members' shares. A member that the OS has descheduled therefore
//    delays a step by at most the chunk it holds, not by its whole share.
// Which member computes which chunk never changes a result: every chunk writes only its own
// items, computed the same way by any member.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

namespace gradel {

/// Chunks of [0, items) of `chunk` items each, shared by `members`: member t owns the contiguous
/// chunk range [split[t], split[t + 1]) and claims from it first.
class ChunkQueue {
 public:
  /// `split` has members + 1 ascending chunk indices, split.front() = 0, split.back() = chunks.
  void reset(const std::vector<size_t>& split);
  /// Claims the next chunk for member t (own share first, then the others' in turn); false when
  /// none is left.
  bool claim(int t, size_t* chunkIndex);

 private:
  struct alignas(64) Share {
    std::atomic<size_t> next{0};
    size_t end = 0;
  };
  std::vector<Share> shares_;
};

class ThreadTeam {
 public:
  /// A team of `members` (>= 1): the calling thread is member 0, members - 1 workers are started.
  explicit ThreadTeam(int members);
  ~ThreadTeam();
  ThreadTeam(const ThreadTeam&) = delete;
  ThreadTeam& operator=(const ThreadTeam&) = delete;

  int members() const { return members_; }
  /// Whether the calling thread is the one that made the team (the only one that may run()).
  bool ownedByCaller() const { return std::this_thread::get_id() == owner_; }

  /// Runs job(t) on every member t in [0, members()) and returns when all have finished. Called
  /// from the thread that made the team, never from inside a job.
  template <class Job>
  void run(Job&& job) {
    if (members_ == 1) return job(0);
    auto call = [](void* j, int t) { (*static_cast<std::remove_reference_t<Job>*>(j))(t); };
    dispatch(call, &job);
  }

  /// Inside a job: waits until every member has arrived.
  void barrier();

 private:
  using Call = void (*)(void*, int);
  void dispatch(Call call, void* job);
  void workerLoop(int t);

  int members_;
  std::thread::id owner_ = std::this_thread::get_id();
  std::vector<std::thread> workers_;
  // The job being run; `jobGeneration` counts dispatches (and is the word workers sleep on).
  Call call_ = nullptr;
  void* job_ = nullptr;
  bool stop_ = false;
  alignas(64) std::atomic<uint32_t> jobGeneration_{0};
  alignas(64) std::atomic<uint32_t> barrierCount_{0};
  alignas(64) std::atomic<uint32_t> barrierGeneration_{0};
  alignas(64) std::atomic<uint32_t> doneCount_{0};
  alignas(64) std::atomic<uint32_t> doneGeneration_{0};
};

/// Runs item(i) for every i in [0, n): on the members of `team` in chunks of `chunk` items
/// claimed in turn, or all on this thread when `team` is null, has one member or is another
/// thread's. `item` writes only what belongs to i, so the result never depends on which.
template <class Item>
void forEachInChunks(ThreadTeam* team, size_t n, size_t chunk, Item&& item) {
  if (!team || team->members() == 1 || n <= chunk || !team->ownedByCaller()) {
    for (size_t i = 0; i < n; ++i) item(i);
    return;
  }
  const size_t chunks = (n + chunk - 1) / chunk;
  std::atomic<size_t> next{0};
  team->run([&](int) {
    for (size_t c; (c = next.fetch_add(1, std::memory_order_relaxed)) < chunks;)
      for (size_t i = c * chunk, end = std::min(n, i + chunk); i < end; ++i) item(i);
  });
}

/// Decides, step after step, whether a team of more than one member is worth it on this machine
/// now, by timing both (results never depend on it). Waiting well (above) is not enough on a
/// machine with other busy programs: with one busy process on 2 cores, 2 members ran 5-25 %
/// slower than 1 (bench/results/*-threads.csv). So the governor times a window of steps with the
/// mode in use, then a window with the other mode (all members or one), then the mode in use
/// again, and switches only when the other beats the better of the two (by more than 5 %); it
/// runs the choice for kRunSeconds and measures again. A window is at least kWindowSeconds and
/// kWindowSteps steps. The probe of the slower mode costs ~2 % of the time. The second window of
/// the mode in use is what keeps one slow window from deciding: the first window of a run is often
/// slow with all members (the new worker still shares its creator's core until the scheduler
/// moves it), which made one run in four of box-realtime step on one thread for a second
/// (0.93 s -> 1.43 s, docs/speed.md "Threads").
class ThreadGovernor {
 public:
  /// Members for the next step: 1 or `full`.
  int choose(int full) const {
    const bool one = phase_ == Phase::ProbeOther ? !useOne_ : useOne_;
    return one ? 1 : full;
  }
  /// The wall time [s] of the step just taken with choose()'s members.
  void report(double seconds);
  bool usingOne() const { return useOne_; }

  static constexpr double kWindowSeconds = 0.03, kRunSeconds = 1.0, kMargin = 0.95;
  static constexpr int kWindowSteps = 8;

 private:
  enum class Phase { MeasureCurrent, ProbeOther, MeasureAgain, Run };
  Phase phase_ = Phase::MeasureCurrent;
  bool useOne_ = false;
  double time_ = 0, current_ = 0, other_ = 0;
  int steps_ = 0;
};

}  // namespace gradel
