// Progress for stages that can take long before a run starts (issue 26: a size-400 body built
// for over 10 s with nothing shown): a SlowStage names what is being done; if it is still
// running after a threshold (1 s; $GRADEL_PROGRESS_AFTER seconds, for tests) a line goes to
// stderr, then one every 5 s with the time so far, and one when it ends. Nothing is printed for
// a fast stage, and nothing at all unless reports were switched on (the `gradel` program does;
// a library user's stderr stays quiet). The stage's work is not touched: results are the same.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace gradel {

/// Switches the reports on or off for the whole process (off by default).
void setSlowStageReports(bool on);
/// The threshold [s]: $GRADEL_PROGRESS_AFTER if set to a number >= 0, else 1.
double slowStageThreshold();

class SlowStage {
 public:
  explicit SlowStage(std::string what);
  ~SlowStage();
  SlowStage(const SlowStage&) = delete;
  SlowStage& operator=(const SlowStage&) = delete;

 private:
  double seconds() const;
  std::string what_;
  std::chrono::steady_clock::time_point start_;
  bool reported_ = false;  ///< The start line was printed (guarded by mutex_ once the watcher runs).
  std::mutex mutex_;
  std::condition_variable done_;
  bool finished_ = false;
  std::thread watcher_;
};

}  // namespace gradel
