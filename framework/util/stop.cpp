// Cooperative stopping (stop.hpp): one process-wide flag, since one run at a time owns the task
// arena; a deadline read from the clock on every 1024th check.
#include "framework/util/stop.hpp"

#include <atomic>
#include <sstream>

namespace ndc {

namespace {

/// 0: run on; otherwise 1 + StopReason.
std::atomic<int> requested{0};
/// The deadline in steady-clock ticks, or 0 for none.
std::atomic<std::chrono::steady_clock::rep> deadlineTicks{0};
double deadlineSeconds = 0;
std::atomic<unsigned> checks{0};

}  // namespace

void requestStop(StopReason reason) {
  requested.store(1 + static_cast<int>(reason), std::memory_order_relaxed);
}

void setStopDeadline(std::optional<std::chrono::steady_clock::time_point> deadline,
                     double seconds) {
  deadlineSeconds = seconds;
  deadlineTicks.store(deadline ? deadline->time_since_epoch().count() : 0,
                      std::memory_order_relaxed);
}

void clearStop() {
  requested.store(0, std::memory_order_relaxed);
  setStopDeadline(std::nullopt);
}

void checkStop() {
  const auto ticks = deadlineTicks.load(std::memory_order_relaxed);
  if (ticks != 0 && checks.fetch_add(1, std::memory_order_relaxed) % 1024 == 0 &&
      std::chrono::steady_clock::now().time_since_epoch().count() >= ticks)
    requestStop(StopReason::kTimeout);
  const int why = requested.load(std::memory_order_relaxed);
  if (why == 0) return;
  if (why - 1 == static_cast<int>(StopReason::kInterrupt))
    throw Stopped(StopReason::kInterrupt, "interrupted");
  std::ostringstream message;
  message << "stopped by the timeout after " << deadlineSeconds << " s";
  throw Stopped(StopReason::kTimeout, message.str());
}

}  // namespace ndc
