#pragma once
/// @file pacer.hpp
/// Pacer: the absolute-deadline timing of a servo loop, shared by ServoLoop
/// and MultiArmLoop. Tick n is due at start + n T. A wake-up before the
/// deadline (a spurious early return) sleeps again, so no period is cut
/// short and the next one doubled; after an overrun the deadlines that
/// already passed are skipped whole, so there is no burst of catch-up ticks
/// (OverrunPolicy::skip, the default). OverrunPolicy::run_next_late runs the
/// next tick at once, late, when its deadline passed less than a period
/// ago, and skips only deadlines older than that: a tick that ends a little
/// past the next deadline then costs no period, which keeps the mean rate
/// on a host that wakes the loop late now and then (one late tick, never a
/// burst).
///
/// Two ways to wait (PacingConfig):
///   - sleep (the default): clock_nanosleep to the deadline. Costs no CPU;
///     each wake is as late as the scheduler makes it.
///   - hybrid: sleep until spin_margin_ns before the deadline, then
///     busy-wait to it. A wake that the scheduler delays by less than the
///     margin lands on the deadline; the price is up to the margin of CPU
///     time per tick (Pacer::spun_ns() counts it). A wake delayed by more
///     than the margin is late as in sleep mode, and spins nothing. The
///     margin used is at most half the period, so the thread sleeps in
///     every period: a SCHED_FIFO thread that never sleeps is throttled by
///     the kernel (sched_rt_runtime_us: a 50 ms pause every second).

#include <cstdint>
#include <stdexcept>
#include <type_traits>

#include "hapticfield/servo/clock.hpp"

namespace hapticfield {

/// How a Pacer waits for a deadline.
enum class PacingMode : std::uint8_t {
  sleep,   ///< sleep to the deadline
  hybrid,  ///< sleep to (deadline - spin margin), then spin to the deadline
};

/// What the tick after an overrun does.
enum class OverrunPolicy : std::uint8_t {
  skip,           ///< every deadline the overrun passed is skipped: the next tick waits for the grid
  run_next_late,  ///< the next tick runs at once if its deadline passed less than a period ago
};

/// Default spin margin of the hybrid mode [ns].
inline constexpr std::int64_t default_spin_margin_ns = 100'000;
/// Largest spin margin accepted [ns] (a margin of a whole period or more
/// spins through every period).
inline constexpr std::int64_t max_spin_margin_ns = 1'000'000'000;

struct PacingConfig {
  PacingMode mode{PacingMode::sleep};
  std::int64_t spin_margin_ns{default_spin_margin_ns};  ///< hybrid: spin this long before each deadline [ns]
  OverrunPolicy overrun{OverrunPolicy::skip};           ///< what the tick after an overrun does

  /// @throws std::invalid_argument for a margin outside [0, 1 s].
  void validate() const {
    if (spin_margin_ns < 0 || spin_margin_ns > max_spin_margin_ns)
      throw std::invalid_argument("PacingConfig: spin_margin_ns must be within [0, 1e9] [ns]");
  }
};

class Pacer {
 public:
  /// @param period_ns  tick period [ns], > 0
  /// @param pacing     how to wait (the margin is clamped into [0, period / 2])
  explicit Pacer(std::int64_t period_ns, PacingConfig pacing = {}) noexcept : period_ns_(period_ns), pacing_(pacing) {
    if (pacing_.spin_margin_ns < 0) pacing_.spin_margin_ns = 0;
    if (pacing_.spin_margin_ns > period_ns_ / 2) pacing_.spin_margin_ns = period_ns_ / 2;
  }

  /// The first tick is due now.
  void start(std::int64_t now) noexcept {
    deadline_ = now;
    previous_wake_ = now;
    first_ = true;
  }

  /// Waits until the current deadline (sleeping again if woken early; in
  /// hybrid mode spinning the last stretch) and returns the wake time [ns].
  template <ServoClock C>
  std::int64_t wait(C& clock) noexcept {
    return wait(clock, []() noexcept {});
  }

  /// The same, with `ready()` called once when the sleeping is over: in
  /// hybrid mode before the spin (its time comes out of the margin), in
  /// sleep mode after the wake (the wake time returned is after it). The
  /// servo loop's look-ahead (LoopConfig::anticipate) runs there.
  template <ServoClock C, class Ready>
  std::int64_t wait(C& clock, Ready&& ready) noexcept {
    static_assert(std::is_nothrow_invocable_v<Ready&>, "Pacer::wait: ready() must be noexcept");
    std::int64_t now = clock.now();
    bool readied = false;
    if constexpr (SpinningClock<C>) {
      if (pacing_.mode == PacingMode::hybrid) {
        const std::int64_t sleep_to = deadline_ - pacing_.spin_margin_ns;
        while (now < sleep_to) {
          clock.sleep_until(sleep_to);
          now = clock.now();
        }
        ready();
        readied = true;
        now = clock.now();
        if (now < deadline_) {
          clock.spin_until(deadline_);
          const std::int64_t after = clock.now();
          spun_ns_ += after - now;
          ++spins_;
          now = after;
        }
      }
    }
    while (now < deadline_) {
      clock.sleep_until(deadline_);
      now = clock.now();
    }
    if (!readied) {
      ready();
      now = clock.now();
    }
    previous_wake_ = first_ ? now : wake_;
    first_ = false;
    wake_ = now;
    return now;
  }

  /// Ends the tick that finished at end [ns]: moves to the next deadline and
  /// returns how many periods were skipped because the tick overran (0: on
  /// time, or, with OverrunPolicy::run_next_late, an overrun of less than a
  /// period: see overran()).
  std::int64_t finish(std::int64_t end) noexcept {
    deadline_ += period_ns_;
    overran_ = end > deadline_;
    if (!overran_) return 0;
    std::int64_t skipped = (end - deadline_) / period_ns_ + 1;       // every deadline that passed
    if (pacing_.overrun == OverrunPolicy::run_next_late) --skipped;  // the newest one runs, late
    deadline_ += skipped * period_ns_;
    return skipped;
  }
  /// The last tick finished after the next deadline (whatever it skipped).
  [[nodiscard]] bool overran() const noexcept { return overran_; }

  [[nodiscard]] std::int64_t deadline() const noexcept { return deadline_; }
  [[nodiscard]] std::int64_t wake() const noexcept { return wake_; }
  /// Time since the previous wake [ns] (0 on the first tick).
  [[nodiscard]] std::int64_t period_observed() const noexcept { return wake_ - previous_wake_; }
  /// How late this wake was after the deadline it waited for [ns].
  [[nodiscard]] std::int64_t wake_latency(std::int64_t waited_for) const noexcept { return wake_ - waited_for; }
  [[nodiscard]] std::int64_t period_ns() const noexcept { return period_ns_; }
  [[nodiscard]] const PacingConfig& pacing() const noexcept { return pacing_; }
  /// Total time spent spinning since construction [ns]: the hybrid mode's
  /// CPU cost beyond the ticks' own work (0 in sleep mode).
  [[nodiscard]] std::int64_t spun_ns() const noexcept { return spun_ns_; }
  /// Waits that ended with a spin.
  [[nodiscard]] std::uint64_t spins() const noexcept { return spins_; }

 private:
  std::int64_t period_ns_;
  PacingConfig pacing_;
  std::int64_t deadline_{0};
  std::int64_t wake_{0};
  std::int64_t previous_wake_{0};
  std::int64_t spun_ns_{0};
  std::uint64_t spins_{0};
  bool first_{true};
  bool overran_{false};
};

}  // namespace hapticfield
