#pragma once
/// @file loop_thread.hpp
/// What the tools that drive an arm share: the operator's go-ahead before a
/// real arm moves, and a servo loop's run() on a thread of its own while
/// the calling thread shows its status.

#include <atomic>
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>
#include <thread>

#include "hapticfield/rt/realtime_thread.hpp"
#include "hapticfield/servo/loop.hpp"

namespace hapticfield::cli {

/// Warns that a real arm will move and waits for Enter (Ctrl-C aborts).
inline void wait_for_operator() {
  std::printf(
      "WARNING: a real arm will move and push. Hold the handle, keep the workspace clear.\n"
      "Press Enter to start (Ctrl-C to abort)... ");
  std::fflush(stdout);
  std::string line;
  std::getline(std::cin, line);
}

/// loop.run(callback, limits) on a thread of its own. The loop and the
/// callback must outlive it; the destructor joins.
class LoopThread {
 public:
  /// The library prints nothing: what the loop reports (safety stages the
  /// configuration turned off, real-time scheduling refused under
  /// RealTime::best_effort) goes to stderr here, one line each.
  template <class Loop, class Callback>
  LoopThread(Loop& loop, Callback& callback, RunLimits limits)
      : thread_([this, &loop, &callback, limits] {
          if (const std::string off = loop.config().safety.disabled_stages(); !off.empty())
            std::fprintf(stderr, "hapticfield: safety stages disabled by configuration: %s\n", off.c_str());
          try {
            reason_ = loop.run(callback, limits);
          } catch (...) {
            failure_ = std::current_exception();
          }
          if (!loop.realtime_refused().empty())
            std::fprintf(stderr, "hapticfield: real-time scheduling not granted (%s); ran best-effort. %s\n",
                         loop.realtime_refused().c_str(), rt::realtime_advice);
          ran_for_ = std::chrono::steady_clock::now() - started_;
          done_.store(true, std::memory_order_release);
        }) {}
  LoopThread(const LoopThread&) = delete;
  LoopThread& operator=(const LoopThread&) = delete;
  ~LoopThread() {
    if (thread_.joinable()) thread_.join();
  }

  /// True once run() has returned or thrown.
  [[nodiscard]] bool done() const noexcept { return done_.load(std::memory_order_acquire); }
  /// Waits for run() to end.
  void join() {
    if (thread_.joinable()) thread_.join();
  }
  /// After join(): how long run() took on the wall clock [s].
  [[nodiscard]] double wall_seconds() const noexcept { return std::chrono::duration<double>(ran_for_).count(); }
  /// After join(): why run() returned. @throws what run() threw.
  [[nodiscard]] StopReason outcome() const {
    if (failure_) std::rethrow_exception(failure_);
    return reason_;
  }

 private:
  std::atomic<bool> done_{false};
  const std::chrono::steady_clock::time_point started_{std::chrono::steady_clock::now()};
  std::chrono::steady_clock::duration ran_for_{};
  StopReason reason_{StopReason::requested};
  std::exception_ptr failure_;
  std::thread thread_;  ///< last: starts once the members above exist
};

}  // namespace hapticfield::cli
