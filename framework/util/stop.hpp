/// \file stop.hpp
/// Cooperative stopping of a run: a caller on another thread (the Python module's wait loop on
/// Ctrl-C, or a deadline) asks the run to stop, and the run's loops notice at their next work
/// item and throw Stopped. Every parallel loop checks (framework/numeric/parallel.hpp), so a run
/// stops within one work item of any stage. The command line does not need it: its SIGINT and
/// `--timeout` end the process (framework/io/io.hpp).
#pragma once

#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>

namespace ndc {

/// Why a run stopped early.
enum class StopReason { kInterrupt, kTimeout };

/// Thrown by checkStop in the run's thread (or a worker, whence it reaches the run's caller).
class Stopped : public std::runtime_error {
 public:
  Stopped(StopReason reason, const std::string& message)
      : std::runtime_error(message), reason_(reason) {}
  StopReason reason() const { return reason_; }

 private:
  StopReason reason_;
};

/// Asks the current run to stop (thread-safe; async-signal-safe). The next checkStop throws.
void requestStop(StopReason reason);

/// Sets (or with nullopt clears) the deadline after which checkStop throws a kTimeout Stopped;
/// `seconds` is what the message names. Call before a run, not during one.
void setStopDeadline(std::optional<std::chrono::steady_clock::time_point> deadline,
                     double seconds = 0);

/// Clears a requested stop and the deadline (before a new run).
void clearStop();

/// Throws Stopped when a stop was requested or the deadline has passed; otherwise costs one
/// relaxed atomic load (and a clock read every 1024th call while a deadline is set).
void checkStop();

}  // namespace ndc
