/// \file parallel.hpp
/// The task scheduler of `--threads` (oneTBB; docs/performance.md, "Threads"). Every parallel
/// loop of the pipeline has one shape: work item i writes its result into slot i of a vector
/// sized before the loop, and the caller then merges the slots sequentially in index order, so
/// the outputs are the same, bit for bit, whatever the number of threads and however the
/// scheduler splits and steals the work. No loop takes a lock; the slots are the only shared
/// state written, each by one task.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <cstddef>
#include <optional>
#include <type_traits>
#include <utility>

#include "framework/numeric/scalar.hpp"
#include "framework/util/stop.hpp"

namespace ndc {

/// The worker threads a run with `requested` threads uses: `requested`, or every hardware
/// thread for 0.
inline int effectiveThreads(int requested) {
  return requested > 0 ? requested : tbb::info::default_concurrency();
}

/// Keeps a worker thread's MPFR default precision at the caller's for the duration of a task.
/// Boost 1.74 keeps it in one process-wide variable (then this only reads it); later Boost
/// versions keep it per thread, and then a worker set it here.
class WorkerPrecision {
 public:
  explicit WorkerPrecision(unsigned bits) : saved_(mpfrPrecision()) {
    if (saved_ != bits) setMpfrPrecision(bits);
  }
  ~WorkerPrecision() {
    if (mpfrPrecision() != saved_) setMpfrPrecision(saved_);
  }
  WorkerPrecision(const WorkerPrecision&) = delete;
  WorkerPrecision& operator=(const WorkerPrecision&) = delete;

 private:
  unsigned saved_;
};

/// parallelFor over blocks: `body(begin, end)` for disjoint ranges covering [0, count), so a
/// task can keep its scratch for a whole block. `body` must only read shared state and write
/// what belongs to its items; worker threads see the caller's MPFR precision; exceptions reach
/// the caller (oneTBB cancels the rest of the loop), and so does Stopped when a stop is
/// requested (stop.hpp). `grain`: the fewest items of one task.
template <class Body>
void parallelForBlocks(std::size_t count, Body&& body, std::size_t grain = 1) {
  if (count == 0) return;
  const unsigned bits = mpfrPrecision();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      checkStop();
                      const WorkerPrecision precision(bits);
                      body(range.begin(), range.end());
                    });
}

/// Calls `body(i)` for every i in [0, count) on the current task arena (the run's, sized by
/// `--threads`), in any order and on any thread (the rules of parallelForBlocks).
template <class Body>
void parallelFor(std::size_t count, Body&& body, std::size_t grain = 1) {
  if (count == 1) {
    checkStop();
    return body(std::size_t{0});
  }
  parallelForBlocks(
      count,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i != end; ++i) {
          checkStop();  // a stop requested meanwhile ends the loop within one item
          body(i);
        }
      },
      grain);
}

/// One task run beside the calling thread on the current task arena: start(work) returns at
/// once and wait() when `work` is done, rethrowing what it threw. Meanwhile the caller may do
/// sequential work that `work` neither reads nor writes, so the outputs do not depend on the
/// thread count (with one thread, wait() runs `work` itself). `work` may run parallel loops and
/// sees the caller's MPFR precision; it is called as const. The destructor cancels and waits: an
/// exception in the caller never leaves the task running.
class TaskBeside {
 public:
  TaskBeside() = default;
  TaskBeside(const TaskBeside&) = delete;
  TaskBeside& operator=(const TaskBeside&) = delete;
  ~TaskBeside() {
    if (!running_) return;
    group_.cancel();
    try {
      group_.wait();
    } catch (...) {  // the caller's exception is the one that propagates
    }
  }

  template <class Work>
  void start(Work&& work) {
    wait();
    running_ = true;
    group_.run([bits = mpfrPrecision(), work = std::forward<Work>(work)] {
      const WorkerPrecision precision(bits);
      work();
    });
  }

  void wait() {
    if (!running_) return;
    running_ = false;
    group_.wait();
  }

 private:
  tbb::task_group group_;
  bool running_ = false;
};

/// Sorts [first, last) by `less` on the current task arena. `less` must be a strict total
/// order on the elements' values (two elements compare equal only when they are equal), so
/// that the result is the one std::sort gives, whatever the number of threads.
template <class It, class Less>
void parallelSort(It first, It last, Less less) {
  tbb::parallel_sort(first, last, less);
}

/// The calling thread's working storage of type T for user `Tag`, kept across calls so that its
/// vectors keep their capacity: a hot loop allocates nothing once warm. Two users that may be
/// active at once on one thread need different tags; a user must not run a parallel loop while
/// it holds its storage (the thread could start another task with the same user meanwhile).
/// In MPFR, whose numbers keep the precision they were made with, it returns a new T made in
/// `fresh` (the caller's, empty: in double nothing is constructed).
template <class S, class Tag, class T>
T& threadScratch(std::optional<T>& fresh) {
  if constexpr (std::is_same_v<S, double>) {
    thread_local T scratch;
    return scratch;
  } else {
    return fresh.emplace();
  }
}

/// Runs `f()` on a task arena of `threads` worker threads (0: every hardware thread), so that
/// every parallelFor inside it uses at most that many; returns what `f` returns.
template <class F>
decltype(auto) withThreads(int threads, F&& f) {
  const int count = effectiveThreads(threads);
  // More threads than oneTBB's default (the hardware's) need its limit raised, or the arena
  // gets fewer workers (and oneTBB prints a warning).
  std::optional<tbb::global_control> limit;
  if (count > tbb::info::default_concurrency())
    limit.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(count));
  tbb::task_arena arena(count);
  return arena.execute(std::forward<F>(f));
}

}  // namespace ndc
