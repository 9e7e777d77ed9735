// Tests of the pacing modes (servo/pacer.hpp) on the virtual clock: the
// default sleep mode, the hybrid sleep-then-spin mode, early and late wakes
// in both, and the hybrid mode through ServoLoop.
#include <catch2/catch.hpp>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "arm_rig.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"

using namespace hapticfield;

namespace {

constexpr std::int64_t period = 1'000'000;  // [ns], 1 kHz

PacingConfig hybrid(std::int64_t margin) {
  return {.mode = PacingMode::hybrid, .spin_margin_ns = margin};
}

/// Runs n ticks of a pacer on the clock (each tick computes `work` [ns]) and
/// returns the wake times; `before_wait(i)` runs before the i-th wait.
template <class BeforeWait>
std::vector<std::int64_t> run(Pacer& pacer, VirtualClock& clock, int n, std::int64_t work, BeforeWait before_wait) {
  std::vector<std::int64_t> wakes;
  pacer.start(clock.now());
  for (int i = 0; i < n; ++i) {
    before_wait(i);
    wakes.push_back(pacer.wait(clock));
    clock.advance(work);
    pacer.finish(clock.now());
  }
  return wakes;
}
std::vector<std::int64_t> run(Pacer& pacer, VirtualClock& clock, int n, std::int64_t work) {
  return run(pacer, clock, n, work, [](int) {});
}

/// A simulated arm and a loop on one virtual clock.
struct Rig : testing::ArmRig {
  explicit Rig(PacingConfig pacing) : ArmRig(free_arm(), LoopConfig{.pacing = pacing}) {}
};

}  // namespace

TEST_CASE("pacing: sleep is the default, and its wakes are as late as the scheduler makes them") {
  CHECK(PacingConfig{}.mode == PacingMode::sleep);
  CHECK(LoopConfig{}.pacing.mode == PacingMode::sleep);
  VirtualClock clock;
  clock.set_wake_delay(30'000);  // every sleep returns 30 us late
  Pacer pacer(period);
  const auto wakes = run(pacer, clock, 50, 200'000);
  for (std::size_t i = 1; i < wakes.size(); ++i)
    CHECK(wakes[i] == static_cast<std::int64_t>(i) * period + 30'000);
  CHECK(pacer.spun_ns() == 0);
  CHECK(pacer.spins() == 0);
}

TEST_CASE("pacing: hybrid lands on the deadline when the sleep wakes late by less than the margin") {
  VirtualClock clock;
  clock.set_wake_delay(30'000);
  Pacer pacer(period, hybrid(100'000));
  const auto wakes = run(pacer, clock, 50, 200'000);
  for (std::size_t i = 1; i < wakes.size(); ++i)
    CHECK(wakes[i] == static_cast<std::int64_t>(i) * period);
  // each wait slept to deadline - 100 us, woke 30 us later, spun the other 70 us
  CHECK(pacer.spins() == 49);
  CHECK(pacer.spun_ns() == 49 * 70'000);
}

TEST_CASE("pacing: hybrid after an early wake sleeps again, then spins: no short period") {
  VirtualClock clock;
  Pacer pacer(period, hybrid(100'000));
  const auto wakes = run(pacer, clock, 40, 100'000, [&](int i) {
    if (i == 20) clock.shift_next_wake(-400'000);  // this sleep returns 0.4 ms before deadline - margin
  });
  for (std::size_t i = 1; i < wakes.size(); ++i)
    CHECK(wakes[i] - wakes[i - 1] == period);
  CHECK(pacer.spun_ns() == 39 * 100'000);  // no wake delay: every spin is the whole margin
}

TEST_CASE("pacing: hybrid after a wake later than the margin is late, spins nothing, and keeps the grid") {
  VirtualClock clock;
  Pacer pacer(period, hybrid(100'000));
  const auto wakes = run(pacer, clock, 40, 100'000, [&](int i) {
    if (i == 20) clock.shift_next_wake(2'700'000);  // woke 2.7 ms after deadline - margin: 2.6 ms late
  });
  CHECK(wakes[20] - wakes[19] == 3'600'000);  // woke late, inside the period of deadline +3 ms
  CHECK(wakes[21] - wakes[20] == 400'000);    // then the next deadline on the grid, not a burst
  for (std::size_t i = 22; i < wakes.size(); ++i)
    CHECK(wakes[i] - wakes[i - 1] == period);
  CHECK(pacer.spins() == 38);  // every wait but the first (due at once) and the late one
}

TEST_CASE("pacing: hybrid with a tick that ends inside the margin spins without sleeping") {
  VirtualClock clock;
  clock.set_wake_delay(50'000);  // would make every sleep 50 us late
  Pacer pacer(period, hybrid(300'000));
  const auto wakes = run(pacer, clock, 20, 800'000);  // the work ends 200 us before the deadline
  for (std::size_t i = 1; i < wakes.size(); ++i)
    CHECK(wakes[i] == static_cast<std::int64_t>(i) * period);
  CHECK(pacer.spun_ns() == 19 * 200'000);
}

TEST_CASE("pacing: hybrid with a zero margin is the sleep mode; a margin above half the period is cut to half") {
  VirtualClock clock;
  clock.set_wake_delay(10'000);
  Pacer zero(period, hybrid(0));
  const auto wakes = run(zero, clock, 10, 100'000);
  for (std::size_t i = 1; i < wakes.size(); ++i)
    CHECK(wakes[i] == static_cast<std::int64_t>(i) * period + 10'000);
  CHECK(zero.spun_ns() == 0);

  VirtualClock clock2;
  Pacer whole(period, hybrid(period));  // would spin the whole period: a SCHED_FIFO thread would be throttled
  CHECK(whole.pacing().spin_margin_ns == period / 2);
  const auto wakes2 = run(whole, clock2, 10, 100'000);
  for (std::size_t i = 1; i < wakes2.size(); ++i)
    CHECK(wakes2[i] == static_cast<std::int64_t>(i) * period);
  CHECK(whole.spun_ns() == 9 * 500'000);
}

TEST_CASE("pacing: configuration limits") {
  CHECK_NOTHROW(hybrid(0).validate());
  CHECK_NOTHROW(hybrid(max_spin_margin_ns).validate());
  CHECK_THROWS_AS(hybrid(-1).validate(), std::invalid_argument);
  CHECK_THROWS_AS(hybrid(max_spin_margin_ns + 1).validate(), std::invalid_argument);
  const Pacer clamped(period, hybrid(-5));
  CHECK(clamped.pacing().spin_margin_ns == 0);
}

TEST_CASE("pacing: a clock without spin_until is paced by sleeping only") {
  struct SleepOnly {  // a ServoClock that cannot spin
    VirtualClock* inner;
    [[nodiscard]] std::int64_t now() const noexcept { return inner->now(); }
    void sleep_until(std::int64_t t) const noexcept { inner->sleep_until(t); }
  };
  static_assert(ServoClock<SleepOnly> && !SpinningClock<SleepOnly>);
  VirtualClock clock;
  clock.set_wake_delay(20'000);
  SleepOnly sleep_only{&clock};
  Pacer pacer(period, hybrid(100'000));
  pacer.start(clock.now());
  pacer.finish(clock.now());
  CHECK(pacer.wait(sleep_only) == period + 20'000);
  CHECK(pacer.spins() == 0);
}

TEST_CASE("pacing: ServoLoop with hybrid pacing wakes on every deadline despite a wake delay") {
  Rig sleeping(PacingConfig{});
  Rig spinning(hybrid(100'000));
  for (Rig* rig : {&sleeping, &spinning}) {
    rig->clock.set_wake_delay(40'000);
    ZeroField zero;
    rig->loop.run(zero, {.max_ticks = 500});
  }
  const LoopSnapshot s = sleeping.loop.statistics();
  const LoopSnapshot h = spinning.loop.statistics();
  CHECK(s.wake_max == Approx(40e-6).margin(1e-12));
  CHECK(h.wake_max == 0.0);
  CHECK(h.period_max == Approx(1e-3).margin(1e-12));
  CHECK(h.missed_deadlines == 0);
}

TEST_CASE("overrun policy: skip (the default) waits for the grid; run_next_late runs the next tick at once, late") {
  CHECK(PacingConfig{}.overrun == OverrunPolicy::skip);
  for (const PacingMode mode : {PacingMode::sleep, PacingMode::hybrid}) {
    for (const OverrunPolicy policy : {OverrunPolicy::skip, OverrunPolicy::run_next_late}) {
      CAPTURE(static_cast<int>(mode), static_cast<int>(policy));
      VirtualClock clock;
      Pacer pacer(period, {.mode = mode, .spin_margin_ns = 100'000, .overrun = policy});
      std::vector<std::int64_t> skipped;
      std::vector<bool> overran;
      std::vector<std::int64_t> wakes;
      pacer.start(clock.now());
      for (int i = 0; i < 12; ++i) {
        wakes.push_back(pacer.wait(clock));
        // tick 3 works 1.5 ms (ends 0.5 ms past the next deadline), tick 7 works 3.5 ms (2.5 ms past)
        clock.advance(i == 3 ? 1'500'000 : i == 7 ? 3'500'000 : 100'000);
        skipped.push_back(pacer.finish(clock.now()));
        overran.push_back(pacer.overran());
      }
      const bool late = policy == OverrunPolicy::run_next_late;
      for (int i = 0; i < 12; ++i)
        CHECK(overran[i] == (i == 3 || i == 7));
      CHECK(skipped[3] == (late ? 0 : 1));
      CHECK(skipped[7] == (late ? 2 : 3));  // deadlines older than a period are skipped either way
      if (late) {
        CHECK(wakes[4] == 4'500'000);   // at once: its deadline (4 ms) passed 0.5 ms ago
        CHECK(wakes[5] == 5'000'000);   // back on the grid, not a burst
        CHECK(wakes[8] == 10'500'000);  // deadline 10 ms passed 0.5 ms ago; 8 and 9 ms skipped
        CHECK(wakes[9] == 11'000'000);
      } else {
        CHECK(wakes[4] == 5'000'000);   // 4 ms skipped
        CHECK(wakes[8] == 12'000'000);  // tick 7 woke at 8 ms, ended at 11.5 ms: 9, 10 and 11 ms skipped
      }
      for (std::size_t i = 1; i < wakes.size(); ++i)
        CHECK(wakes[i] - wakes[i - 1] >= 400'000);  // never two ticks back to back
    }
  }
}

TEST_CASE(
    "overrun policy: run_next_late keeps ServoLoop's tick count after short overruns; the watchdog still counts "
    "each") {
  for (const OverrunPolicy policy : {OverrunPolicy::skip, OverrunPolicy::run_next_late}) {
    CAPTURE(static_cast<int>(policy));
    Rig rig({.mode = PacingMode::hybrid, .spin_margin_ns = 100'000, .overrun = policy});
    std::uint64_t tick = 0;
    auto sometimes_slow = [&](const TickInput&) {
      if (++tick % 100 == 50) rig.clock.advance(1'300'000);  // ten overruns of 0.3 ms past the next deadline
      return glm::dvec3{0.0};
    };
    const std::int64_t t0 = rig.clock.now();
    rig.loop.run(sometimes_slow, {.max_ticks = 1000});
    const LoopSnapshot s = rig.loop.statistics();
    const double elapsed_ms = static_cast<double>(rig.clock.now() - t0) * 1e-6;
    CHECK(s.overruns == 10);
    if (policy == OverrunPolicy::skip) {
      CHECK(s.missed_deadlines == 10);
      CHECK(elapsed_ms >= 1009.0);  // 1000 ticks took 1010 periods
    } else {
      CHECK(s.missed_deadlines == 0);
      CHECK(elapsed_ms < 1001.0);  // 1000 ticks in 1000 periods: the rate kept
    }
    CHECK((rig.loop.safety().latched() & safety_events::missed_deadlines) == 0);  // isolated overruns
  }

  // three overruns in a row still latch the watchdog with run_next_late
  Rig rig({.mode = PacingMode::sleep, .overrun = OverrunPolicy::run_next_late});
  std::uint64_t tick = 0;
  auto slow = [&](const TickInput&) {
    ++tick;
    if (tick >= 400 && tick < 403) rig.clock.advance(1'200'000);
    return glm::dvec3{0.0};
  };
  rig.loop.run(slow, {.max_ticks = 420});
  CHECK((rig.loop.safety().latched() & safety_events::missed_deadlines) != 0);
}
