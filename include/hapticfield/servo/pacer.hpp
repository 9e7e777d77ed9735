#pragma once
/// @file pacer.hpp
/// Pacer: the absolute-deadline timing of a servo loop, shared by ServoLoop
/// and MultiArmLoop. Tick n is due at start + n T. A wake-up before the
/// deadline (a spurious early return) sleeps again, so no period is cut
/// short and the next one doubled; after an overrun the deadlines that
/// already passed are skipped whole, so there is no burst of catch-up ticks.

#include <cstdint>

#include "hapticfield/servo/clock.hpp"

namespace hapticfield {

class Pacer {
 public:
  /// @param period_ns  tick period [ns], > 0
  explicit Pacer(std::int64_t period_ns) noexcept : period_ns_(period_ns) {}

  /// The first tick is due now.
  void start(std::int64_t now) noexcept {
    deadline_ = now;
    previous_wake_ = now;
    first_ = true;
  }

  /// Sleeps until the current deadline (again if woken early) and returns
  /// the wake time [ns].
  template <ServoClock C>
  std::int64_t wait(C& clock) noexcept {
    std::int64_t now = clock.now();
    while (now < deadline_) {
      clock.sleep_until(deadline_);
      now = clock.now();
    }
    previous_wake_ = first_ ? now : wake_;
    first_ = false;
    wake_ = now;
    return now;
  }

  /// Ends the tick that finished at end [ns]: moves to the next deadline and
  /// returns how many periods were skipped because the tick overran (0: on
  /// time).
  std::int64_t finish(std::int64_t end) noexcept {
    deadline_ += period_ns_;
    if (end <= deadline_) return 0;
    const std::int64_t skipped = (end - deadline_) / period_ns_ + 1;
    deadline_ += skipped * period_ns_;
    return skipped;
  }

  [[nodiscard]] std::int64_t deadline() const noexcept { return deadline_; }
  [[nodiscard]] std::int64_t wake() const noexcept { return wake_; }
  /// Time since the previous wake [ns] (0 on the first tick).
  [[nodiscard]] std::int64_t period_observed() const noexcept { return wake_ - previous_wake_; }
  /// How late this wake was after the deadline it waited for [ns].
  [[nodiscard]] std::int64_t wake_latency(std::int64_t waited_for) const noexcept { return wake_ - waited_for; }
  [[nodiscard]] std::int64_t period_ns() const noexcept { return period_ns_; }

 private:
  std::int64_t period_ns_;
  std::int64_t deadline_{0};
  std::int64_t wake_{0};
  std::int64_t previous_wake_{0};
  bool first_{true};
};

}  // namespace hapticfield
