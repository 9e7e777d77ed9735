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
  /// Sleep mode with a look-ahead (Pacer::wait(clock, ready)): wake this
  /// long before the deadline to run it, then sleep again [ns]; 0: no
  /// look-ahead in sleep mode. (Hybrid mode runs it in its margin.)
  std::int64_t look_ahead_ns{default_spin_margin_ns};

  /// @throws std::invalid_argument for a margin or look-ahead lead outside
  ///         [0, 1 s].
  void validate() const {
    if (spin_margin_ns < 0 || spin_margin_ns > max_spin_margin_ns)
      throw std::invalid_argument("PacingConfig: spin_margin_ns must be within [0, 1e9] [ns]");
    if (look_ahead_ns < 0 || look_ahead_ns > max_spin_margin_ns)
      throw std::invalid_argument("PacingConfig: look_ahead_ns must be within [0, 1e9] [ns]");
  }
};

/// What the last Pacer::wait(clock, ready) did with ready().
struct LookAhead {
  bool ran{false};          ///< ready() ran
  bool skipped{false};      ///< a late wake left too little slack: it did not run
  bool late{false};         ///< it ran, and ended past the deadline
  std::int64_t took_ns{0};  ///< how long it ran [ns]
};

class Pacer {
 public:
  /// @param period_ns  tick period [ns], > 0
  /// @param pacing     how to wait (the margin and the look-ahead lead are
  ///                   clamped into [0, period / 2])
  explicit Pacer(std::int64_t period_ns, PacingConfig pacing = {}) noexcept : period_ns_(period_ns), pacing_(pacing) {
    if (pacing_.spin_margin_ns < 0) pacing_.spin_margin_ns = 0;
    if (pacing_.spin_margin_ns > period_ns_ / 2) pacing_.spin_margin_ns = period_ns_ / 2;
    if (pacing_.look_ahead_ns < 0) pacing_.look_ahead_ns = 0;
    if (pacing_.look_ahead_ns > period_ns_ / 2) pacing_.look_ahead_ns = period_ns_ / 2;
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
    auto nothing = []() noexcept {};
    return wait_for(clock, nothing, false);
  }

  /// The same, with `ready()` run once in the slack before the deadline
  /// (the servo loop's look-ahead, LoopConfig::anticipate): in hybrid mode
  /// after the sleep, before the spin (out of the margin); in sleep mode the
  /// thread wakes PacingConfig::look_ahead_ns before the deadline to run it,
  /// then sleeps again to the deadline. It runs only while the slack left
  /// is more than a quarter of that stretch (margin or lead, > 0) and more
  /// than it has lately taken (its longest run, forgotten by 1/8 a wait),
  /// so a late wake skips it rather than be made later by it; it can still
  /// end past the deadline when a run takes longer than any recent one
  /// (look_ahead() says what it did). The time returned is the tick's own
  /// wake: ready()'s time counts in the wake latency only where it ran past
  /// the deadline.
  template <ServoClock C, class Ready>
  std::int64_t wait(C& clock, Ready&& ready) noexcept {
    static_assert(std::is_nothrow_invocable_v<Ready&>, "Pacer::wait: ready() must be noexcept");
    return wait_for(clock, ready, true);
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
  /// Waits whose ready() ran (wait(clock, ready)).
  [[nodiscard]] std::uint64_t readied() const noexcept { return readied_; }
  /// What the last wait(clock, ready) did with ready().
  [[nodiscard]] const LookAhead& look_ahead() const noexcept { return look_ahead_; }

 private:
  template <ServoClock C, class Ready>
  std::int64_t wait_for(C& clock, Ready& ready, bool with_ready) noexcept {
    std::int64_t now = clock.now();
    bool hybrid = false;
    if constexpr (SpinningClock<C>) hybrid = pacing_.mode == PacingMode::hybrid;
    // how long before the deadline the first sleep ends [ns]
    const std::int64_t early = hybrid ? pacing_.spin_margin_ns : (with_ready ? pacing_.look_ahead_ns : 0);
    const std::int64_t sleep_to = deadline_ - early;
    while (now < sleep_to) {
      clock.sleep_until(sleep_to);
      now = clock.now();
    }
    look_ahead_ = LookAhead{};
    if (with_ready && early > 0) {
      const std::int64_t left = deadline_ - now;  // the slack [ns]
      if (left > early / 4 && left > ready_high_ns_) {
        ready();
        const std::int64_t after = clock.now();
        look_ahead_.ran = true;
        look_ahead_.took_ns = after - now;
        look_ahead_.late = after > deadline_;
        ready_high_ns_ =
            look_ahead_.took_ns > ready_high_ns_ ? look_ahead_.took_ns : ready_high_ns_ - ready_high_ns_ / 8;
        ++readied_;
        now = after;
      } else {
        look_ahead_.skipped = true;
        ready_high_ns_ -= ready_high_ns_ / 8;  // forgotten while skipped too, or one long run would stop it for good
      }
    }
    if constexpr (SpinningClock<C>) {
      if (hybrid && now < deadline_) {
        clock.spin_until(deadline_);
        const std::int64_t after = clock.now();
        spun_ns_ += after - now;
        ++spins_;
        now = after;
      }
    }
    while (now < deadline_) {
      clock.sleep_until(deadline_);
      now = clock.now();
    }
    previous_wake_ = first_ ? now : wake_;
    first_ = false;
    wake_ = now;
    return now;
  }

  std::int64_t period_ns_;
  PacingConfig pacing_;
  std::int64_t deadline_{0};
  std::int64_t wake_{0};
  std::int64_t previous_wake_{0};
  std::int64_t spun_ns_{0};
  std::uint64_t spins_{0};
  std::uint64_t readied_{0};
  std::int64_t ready_high_ns_{0};  ///< ready()'s recent longest run [ns] (decays by 1/8 a wait)
  LookAhead look_ahead_{};
  bool first_{true};
  bool overran_{false};
};

}  // namespace hapticfield
