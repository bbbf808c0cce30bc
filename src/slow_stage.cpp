#include "gradel/slow_stage.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>

namespace gradel {

namespace {
std::atomic<bool> gReports{false};
}

void setSlowStageReports(bool on) { gReports = on; }

double slowStageThreshold() {
  if (const char* s = std::getenv("GRADEL_PROGRESS_AFTER")) {
    char* end = nullptr;
    const double v = std::strtod(s, &end);
    if (end != s && v >= 0 && v < 1e6) return v;
  }
  return 1.0;
}

SlowStage::SlowStage(std::string what) : what_(std::move(what)), start_(std::chrono::steady_clock::now()) {
  if (!gReports) return;
  const double after = slowStageThreshold();
  if (after <= 0) {  // at once (tests): no race with a stage that ends before a thread starts
    std::fprintf(stderr, "gradel: %s ...\n", what_.c_str());
    reported_ = true;
  }
  watcher_ = std::thread([this, after] {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!reported_) {
      if (done_.wait_for(lock, std::chrono::duration<double>(after), [this] { return finished_; })) return;
      std::fprintf(stderr, "gradel: %s ...\n", what_.c_str());
      reported_ = true;
    }
    while (!done_.wait_for(lock, std::chrono::seconds(5), [this] { return finished_; }))
      std::fprintf(stderr, "gradel: %s: %.0f s so far\n", what_.c_str(), seconds());
  });
}

double SlowStage::seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

SlowStage::~SlowStage() {
  if (!watcher_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
  }
  done_.notify_all();
  watcher_.join();
  if (reported_) std::fprintf(stderr, "gradel: %s: done in %.1f s\n", what_.c_str(), seconds());
}

}  // namespace gradel
