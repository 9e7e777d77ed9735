#pragma once
/// @file stop_signal.hpp
/// Ctrl-C (SIGINT) and SIGTERM stop a servo loop through its own stop
/// (request_stop(): zero force, then disarm) instead of killing the process
/// with the last command, armed and non-zero, still on the wire.
///
///   ServoLoop loop(device, clock, config);
///   cli::StopOnSignal stop(loop);          // before the operator's prompt
///   if (hardware) cli::wait_for_operator();
///   if (stop.caught()) return stop.exit_status();
///   ... run the loop ...
///   return stop.caught() ? stop.exit_status() : 0;
///
/// The first signal asks the loop to stop (the handler only stores two
/// atomics, which is async-signal-safe); the handler then removes itself
/// (SA_RESETHAND), so a second Ctrl-C kills a tool that does not stop.

#include <signal.h>

#include <atomic>
#include <stdexcept>

namespace hapticfield::cli {

class StopOnSignal {
 public:
  /// Installs the handlers for SIGINT and SIGTERM; `loop` has request_stop()
  /// (ServoLoop, MultiArmLoop) and must outlive this object. One at a time.
  /// @throws std::logic_error when another StopOnSignal is installed.
  template <class Loop>
  explicit StopOnSignal(Loop& loop) {
    if (target().exchange(&loop) != nullptr) throw std::logic_error("StopOnSignal: one loop at a time");
    stopper().store([](void* l) noexcept { static_cast<Loop*>(l)->request_stop(); });
    caught_signal().store(0);
    struct sigaction action {};
    action.sa_handler = &handle;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;  // no SA_RESTART: a blocking read (the operator's prompt) returns
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;
  /// Restores the handlers found at construction.
  ~StopOnSignal() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
    stopper().store(nullptr);
    target().store(nullptr);
  }

  /// The signal that asked the loop to stop (0: none yet).
  [[nodiscard]] int caught() const noexcept { return caught_signal().load(); }
  /// What a tool stopped by a signal exits with: 128 + the signal (130 for Ctrl-C).
  [[nodiscard]] int exit_status() const noexcept { return 128 + caught(); }

 private:
  using Stopper = void (*)(void*) noexcept;
  static std::atomic<void*>& target() noexcept {
    static std::atomic<void*> t{nullptr};
    return t;
  }
  static std::atomic<Stopper>& stopper() noexcept {
    static std::atomic<Stopper> s{nullptr};
    return s;
  }
  static std::atomic<int>& caught_signal() noexcept {
    static std::atomic<int> c{0};
    return c;
  }
  static_assert(std::atomic<void*>::is_always_lock_free && std::atomic<Stopper>::is_always_lock_free &&
                    std::atomic<int>::is_always_lock_free,
                "the signal handler uses lock-free atomics only");

  static void handle(int signal) noexcept {
    caught_signal().store(signal);
    if (const Stopper s = stopper().load()) s(target().load());
  }

  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

}  // namespace hapticfield::cli
