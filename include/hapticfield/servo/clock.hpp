#pragma once
/// @file clock.hpp
/// Clocks the servo loop runs on: SteadyClock (CLOCK_MONOTONIC, absolute
/// sleeps, and a busy-wait for the last stretch before a deadline) and
/// VirtualClock (tests: time moves only when told, never sleeps).

#include <atomic>
#include <cerrno>
#include <concepts>
#include <cstdint>
#include <ctime>

namespace hapticfield {

/// A monotonic clock in integer nanoseconds that can sleep until an
/// absolute time.
template <class C>
concept ServoClock = requires(C& clock, std::int64_t t) {
  { clock.now() }
  noexcept->std::same_as<std::int64_t>;
  { clock.sleep_until(t) }
  noexcept;
};

/// A ServoClock that can also busy-wait until an absolute time: what the
/// hybrid pacing (servo/pacer.hpp) spins on for the last stretch. A clock
/// without spin_until() is paced by sleeping only.
template <class C>
concept SpinningClock = ServoClock<C> && requires(C& clock, std::int64_t t) {
  { clock.spin_until(t) }
  noexcept;
};

namespace detail {
/// Tells the CPU this is a spin-wait (saves power, frees the sibling
/// hyperthread); a no-op where there is no such instruction.
inline void cpu_relax() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}
}  // namespace detail

/// CLOCK_MONOTONIC with clock_nanosleep(TIMER_ABSTIME): sleeps to absolute
/// deadlines, so per-tick latencies do not accumulate into drift.
struct SteadyClock {
  [[nodiscard]] std::int64_t now() const noexcept {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  }
  void sleep_until(std::int64_t t) const noexcept {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(t / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(t % 1'000'000'000);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
  /// Busy-waits until t [ns]: keeps the CPU for the whole wait.
  void spin_until(std::int64_t t) const noexcept {
    while (now() < t)
      detail::cpu_relax();
  }
};

/// Time that moves only when the loop sleeps or a test advances it [ns].
/// sleep_until jumps to the deadline (plus an optional wake delay, to model
/// scheduling latency); advance() models compute time. Thread-safe.
class VirtualClock {
 public:
  explicit VirtualClock(std::int64_t start = 0) noexcept : now_ns_(start) {}
  [[nodiscard]] std::int64_t now() const noexcept { return now_ns_.load(std::memory_order_acquire); }
  void sleep_until(std::int64_t t) noexcept {
    const std::int64_t once = once_.exchange(0, std::memory_order_relaxed);
    const std::int64_t target = t + wake_delay_.load(std::memory_order_relaxed) + once;
    std::int64_t cur = now_ns_.load(std::memory_order_relaxed);
    while (cur < target && !now_ns_.compare_exchange_weak(cur, target, std::memory_order_acq_rel)) {
    }
  }
  /// A busy-wait is exact: time moves to t (never backwards). Neither the
  /// wake delay nor a shifted wake applies (they model the scheduler, which
  /// a spinning thread does not wait for).
  void spin_until(std::int64_t t) noexcept {
    std::int64_t cur = now_ns_.load(std::memory_order_relaxed);
    while (cur < t && !now_ns_.compare_exchange_weak(cur, t, std::memory_order_acq_rel)) {
    }
  }
  /// Moves time forward by dt [ns] (e.g. to model compute time in a field).
  void advance(std::int64_t dt) noexcept { now_ns_.fetch_add(dt, std::memory_order_acq_rel); }
  /// Every sleep wakes this late [ns] (scheduling latency model).
  void set_wake_delay(std::int64_t dt) noexcept { wake_delay_.store(dt, std::memory_order_relaxed); }
  /// The next sleep only wakes dt [ns] late (dt > 0: a scheduling stall) or
  /// early (dt < 0: a spurious early return, before the deadline).
  void shift_next_wake(std::int64_t dt) noexcept { once_.store(dt, std::memory_order_relaxed); }

 private:
  std::atomic<std::int64_t> now_ns_;
  std::atomic<std::int64_t> wake_delay_{0};
  std::atomic<std::int64_t> once_{0};
};

static_assert(SpinningClock<SteadyClock>);
static_assert(SpinningClock<VirtualClock>);

}  // namespace hapticfield
