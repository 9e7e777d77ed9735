// Tests of the servo layer: clocks, statistics, the safety chain (seeded
// property tests), and the loop against the simulated arm on a virtual clock.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "arm_rig.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"
#include "test_fields.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;
using testing::Constant;
using testing::Wall;

namespace {

constexpr double qnan = std::numeric_limits<double>::quiet_NaN();
constexpr double inf = std::numeric_limits<double>::infinity();

/// Property-test size: HAPTICFIELD_PROPERTY_COUNT overrides (default 1e5).
long property_count() {
  if (const char* s = std::getenv("HAPTICFIELD_PROPERTY_COUNT")) return std::max(1L, std::atol(s));
  return 100000;
}
/// Seed: Catch's --rng-seed when given, else 1.
std::uint32_t property_seed() {
  const unsigned s = Catch::getCurrentContext().getConfig()->rngSeed();
  return s ? s : 1u;
}

/// Simulated arm, link, ForceArm and loop on one virtual clock.
using Rig = testing::ArmRig;
SimulatedArmConfig free_arm() {
  return Rig::free_arm();
}

}  // namespace

// ------------------------------------------------------------------- clocks

TEST_CASE("the virtual clock only moves when told") {
  VirtualClock c(100);
  CHECK(c.now() == 100);
  c.sleep_until(50);  // in the past: no change
  CHECK(c.now() == 100);
  c.sleep_until(1000);
  CHECK(c.now() == 1000);
  c.advance(5);
  CHECK(c.now() == 1005);
  c.set_wake_delay(20);
  c.sleep_until(2000);
  CHECK(c.now() == 2020);
}

TEST_CASE("histogram percentiles agree with a sorted sample") {
  DurationHistogram h;
  std::mt19937 rng(3);
  std::lognormal_distribution<double> d(13.8, 0.3);  // around 1 ms
  std::vector<std::int64_t> v;
  for (int i = 0; i < 20000; ++i) {
    const auto ns = static_cast<std::int64_t>(d(rng));
    v.push_back(ns);
    h.record(ns);
  }
  std::sort(v.begin(), v.end());
  for (const double p : {0.5, 0.9, 0.99, 0.999}) {
    const std::int64_t exact = v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
    CHECK(std::llabs(h.percentile(p) - exact) <= 1000);  // one 1 us bin
  }
  CHECK(h.max() == v.back());
  CHECK(h.count() == v.size());
  h.record(1'000'000'000);  // 1 s lands in the overflow bin, max stays exact
  CHECK(h.max() == 1'000'000'000);
}

// ------------------------------------------------------------- safety chain

TEST_CASE("safety chain: non-finite force gives zero and a fault event") {
  SafetyConfig cfg;
  cfg.soft_start_enabled = false;
  cfg.slew_enabled = false;
  SafetyChain chain(cfg, 3.3);
  SafetyInput in;
  in.time_since_armed = 1.0;
  for (const glm::dvec3 f : {glm::dvec3{qnan, 0, 0}, glm::dvec3{0, inf, 0}, glm::dvec3{0, 0, -inf}}) {
    in.force = f;
    CHECK(chain.process(in) == glm::dvec3{0.0});
    CHECK((chain.events() & safety_events::non_finite) != 0);
  }
  in.force = {1, 0, 0};
  CHECK(chain.process(in) == glm::dvec3{1, 0, 0});  // not latched: the next finite force passes
}

TEST_CASE("safety chain: magnitude clamp keeps the direction") {
  SafetyConfig cfg;
  cfg.soft_start_enabled = false;
  cfg.slew_enabled = false;
  SafetyChain chain(cfg, 3.3);
  SafetyInput in;
  in.time_since_armed = 1.0;
  in.force = {30.0, -40.0, 0.0};  // |F| = 50 N
  const glm::dvec3 out = chain.process(in);
  CHECK_THAT(glm::length(out), WithinAbs(3.3, 1e-12));
  CHECK_THAT(out.x, WithinAbs(3.3 * 0.6, 1e-12));
  CHECK_THAT(out.y, WithinAbs(-3.3 * 0.8, 1e-12));
  in.force = {1e308, 1e308, -1e308};  // |F| overflows a naive length
  CHECK_THAT(glm::length(chain.process(in)), WithinAbs(3.3, 1e-12));
}

TEST_CASE("safety chain: slew limit and soft start") {
  SafetyConfig cfg;
  cfg.slew_rate = 500.0;  // 0.5 N per 1 ms tick
  cfg.soft_start = 0.1;
  SafetyChain chain(cfg, 3.3);
  SafetyInput in;
  in.force = {0, 3.0, 0};
  in.time_since_armed = 1.0;
  double last = 0.0;
  for (int i = 1; i <= 6; ++i) {
    const double y = chain.process(in).y;
    CHECK_THAT(y, WithinAbs(std::min(3.0, 0.5 * i), 1e-12));
    last = y;
  }
  CHECK(last == 3.0);
  SafetyChain ramp(cfg, 3.3);
  in.force = {0, 3.3, 0};
  in.time_since_armed = 0.05;  // half way through the ramp: limit 1.65 N
  for (int i = 0; i < 10; ++i)
    (void)ramp.process(in);
  CHECK_THAT(ramp.previous().y, WithinAbs(1.65, 1e-12));
  in.time_since_armed = -1.0;  // not armed: zero
  CHECK(ramp.process(in) == glm::dvec3{0.0});
}

TEST_CASE("safety chain: watchdog on missing state, stale state and missed deadlines") {
  SafetyConfig cfg;
  cfg.soft_start_enabled = false;
  SafetyChain chain(cfg, 3.3);
  SafetyInput in;
  in.force = {0, 0.1, 0};
  in.time_since_armed = 1.0;
  CHECK(chain.process(in) != glm::dvec3{0.0});
  in.ticks_without_state = 1;  // one late report: carry on
  CHECK(chain.process(in) != glm::dvec3{0.0});
  in.ticks_without_state = 2;  // two: zero, without latching
  CHECK(chain.process(in) == glm::dvec3{0.0});
  CHECK((chain.events() & safety_events::no_new_state) != 0);
  CHECK(chain.latched() == 0);
  in.ticks_without_state = 0;
  CHECK(chain.process(in) != glm::dvec3{0.0});  // resumes (slew-limited from zero)
  in.state_age = 0.011;                         // older than 10 ms: zero and latch
  CHECK(chain.process(in) == glm::dvec3{0.0});
  CHECK((chain.latched() & safety_events::stale_state) != 0);
  in.state_age = 0.0;
  CHECK(chain.process(in) == glm::dvec3{0.0});  // latched until cleared
  chain.clear();
  CHECK(chain.process(in) != glm::dvec3{0.0});
  in.state_age = qnan;  // an unknown age is stale too
  CHECK(chain.process(in) == glm::dvec3{0.0});
  chain.clear();
  in.state_age = 0.0;
  in.missed_in_a_row = 3;
  CHECK(chain.process(in) == glm::dvec3{0.0});
  CHECK((chain.latched() & safety_events::missed_deadlines) != 0);
}

TEST_CASE("safety configuration rejects limits that make no sense") {
  const auto bad = [](auto mutate, double device_max = 3.3) {
    SafetyConfig c;
    mutate(c);
    CHECK_THROWS_AS(SafetyChain(c, device_max), std::invalid_argument);
  };
  bad([](SafetyConfig& c) { c.max_force = -1; });
  bad([](SafetyConfig& c) { c.max_force = qnan; });
  bad([](SafetyConfig& c) { c.max_force = 10; });  // above the device
  bad([](SafetyConfig& c) { c.slew_rate = 0; });
  bad([](SafetyConfig& c) { c.slew_rate = inf; });
  bad([](SafetyConfig& c) { c.soft_start = -0.1; });
  bad([](SafetyConfig& c) { c.max_state_age = 0; });
  bad([](SafetyConfig& c) { c.max_missed_deadlines = 0; });
  bad([](SafetyConfig& c) {
    c.passivity_enabled = true;
    c.passivity_max_damping = qnan;
  });
  bad([](SafetyConfig&) {}, 0.0);
  bad([](SafetyConfig&) {}, qnan);
  SafetyConfig off;
  off.slew_enabled = false;
  off.watchdog_enabled = false;
  CHECK(off.disabled_stages() == "slew limit, watchdog");
  CHECK(SafetyConfig{}.disabled_stages().empty());
}

TEST_CASE("safety invariants hold over seeded random states, fields and garbage") {
  const long n = property_count();
  std::mt19937_64 rng(property_seed());
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 9);
  const auto value = [&](double scale) {
    switch (pick(rng)) {
      case 0:
        return qnan;
      case 1:
        return unit(rng) < 0 ? -inf : inf;
      case 2:
        return unit(rng) * 1e300;  // huge
      case 3:
        return unit(rng) * 1e-300;
      default:
        return unit(rng) * scale;
    }
  };
  SafetyConfig cfg;
  cfg.passivity_enabled = true;
  SafetyChain chain(cfg, 3.3);
  const double step = cfg.slew_rate * 1e-3;
  long violations = 0, zeroed = 0;
  double armed_for = 0.0;
  glm::dvec3 previous{0.0};
  for (long i = 0; i < n; ++i) {
    if (i % 1000 == 999) chain.clear();
    // Each block of 1000 ticks starts with 300 clean, armed ticks of large
    // forces, so that the force is well above one slew step when the
    // garbage begins: the zeroing branch is reached for any seed.
    const bool clean = i % 1000 < 300;
    SafetyInput in;
    in.force =
        clean ? glm::dvec3{3.0 + unit(rng), unit(rng), unit(rng)} : glm::dvec3{value(5.0), value(5.0), value(5.0)};
    in.velocity = clean ? glm::dvec3{0.1 * unit(rng)} : glm::dvec3{value(0.5), value(0.5), value(0.5)};
    // A broken period (NaN, Inf, zero, negative) must zero the force.
    static constexpr double broken_periods[] = {qnan, inf, -inf, 0.0, -1e-3};
    in.period = clean || pick(rng) != 0 ? 1e-3 : broken_periods[pick(rng) % 5];
    in.state_age = !clean && pick(rng) == 0 ? value(0.02) : 0.0;
    in.ticks_without_state = !clean && pick(rng) == 0 ? 2 : 0;
    in.missed_in_a_row = !clean && pick(rng) == 0 ? 3 : 0;
    // Armed time only grows (the soft-start limit never shrinks) until a
    // random disarm.
    armed_for = !clean && pick(rng) == 0 ? -1.0 : std::fmax(armed_for, 0.0) + 1e-3 * (clean ? 1 : pick(rng));
    in.time_since_armed = armed_for;
    in.device_fault = !clean && pick(rng) == 0 && pick(rng) == 0;
    const glm::dvec3 out = chain.process(in);
    const bool finite = is_finite(out);
    const double magnitude = glm::length(out);
    const bool zeroing = out == glm::dvec3{0.0};
    const bool slew_ok = glm::length(out - previous) <= step * (1.0 + 1e-12) || zeroing;
    if (!finite || magnitude > 3.3 * (1.0 + 1e-12) || !slew_ok) {
      ++violations;
      UNSCOPED_INFO("violation at " << i << ": |out| " << magnitude << ", step " << glm::length(out - previous)
                                    << ", events " << chain.events());
    }
    // A zero after a fault is the only way to break the slew limit, and only
    // when the chain says why.
    if (zeroing && glm::length(previous) > step) {
      ++zeroed;
      if ((chain.events() & (safety_events::zeroing | safety_events::latching)) == 0) ++violations;
    }
    previous = out;
  }
  INFO("seed " << property_seed() << ", " << n << " states");
  CHECK(violations == 0);
  // What the property guarantees: whenever garbage meets a force above one
  // slew step, the chain zeroes it at once and says why. The clean ramps
  // before each block of garbage make that happen for any seed.
  CHECK(zeroed > 0);
}

TEST_CASE("through the whole loop, a garbage field never reaches the arm") {
  // Seeded random fields (NaN, Inf, 1e300, ordinary forces) driving the
  // loop and the simulated arm: every command is finite, within the limit
  // and slew-limited or zero, and the arm's torques stay within saturation.
  Rig rig(SimulatedArmConfig{});
  std::mt19937_64 rng(property_seed() + 17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 19);
  const auto garbage = [&] {
    switch (pick(rng)) {
      case 0:
        return qnan;
      case 1:
        return inf;
      case 2:
        return -1e300;
      default:
        return unit(rng) * 6.0;
    }
  };
  glm::dvec3 previous{0.0};
  long bad = 0;
  auto cb = [&](const TickInput&) {
    const glm::dvec3 c = rig.loop.last_command();
    const bool ok = is_finite(c) && glm::length(c) <= 3.3 * (1 + 1e-12) &&
                    (glm::length(c - previous) <= 1000.0 * 1e-3 * (1 + 1e-9) || c == glm::dvec3{0.0});
    const glm::dvec3 tau = rig.arm.applied_torque();
    if (!ok || std::fabs(tau.x) > 0.45 || std::fabs(tau.y) > 0.45 || std::fabs(tau.z) > 0.45) ++bad;
    previous = c;
    return glm::dvec3{garbage(), garbage(), garbage()};
  };
  rig.loop.run(cb, {.max_ticks = static_cast<std::uint64_t>(std::max(2000L, property_count() / 5))});
  CHECK(bad == 0);
  CHECK(rig.loop.statistics().peak_force > 1.0);  // forces did get through
}

TEST_CASE("passivity controller keeps the observed energy non-negative") {
  SafetyConfig cfg;
  cfg.passivity_enabled = true;
  cfg.soft_start_enabled = false;
  cfg.slew_enabled = false;
  SafetyChain chain(cfg, 3.3);
  // An active element: force along the velocity (negative damping) injects
  // energy; the observer must see it and the controller must cancel it.
  SafetyInput in;
  in.time_since_armed = 1.0;
  int corrected = 0;
  for (int i = 0; i < 1000; ++i) {
    const double t = i * 1e-3;
    in.velocity = {0.05 * std::cos(10 * t), 0.0, 0.0};
    in.force = 20.0 * in.velocity;  // -20 N s/m damping: active
    (void)chain.process(in);
    CHECK(chain.observed_energy() >= -1e-12);
    if (chain.events() & safety_events::passivity) ++corrected;
  }
  CHECK(corrected > 500);
  // A passive damper is left alone.
  SafetyChain calm(cfg, 3.3);
  in.velocity = {0.05, 0.0, 0.0};
  in.force = -10.0 * in.velocity;
  CHECK(calm.process(in) == in.force);
  CHECK((calm.events() & safety_events::passivity) == 0);
}

// ---------------------------------------------------------------- the loop

TEST_CASE("loop configuration rejects rates and priorities out of range") {
  VirtualClock clock;
  SimulatedArm arm(free_arm());
  SimulatedTransport link(arm, [&] { return clock.now(); });
  ForceArm device(link);
  for (const double rate : {0.0, -1000.0, 0.5, 10001.0, qnan, inf}) {
    LoopConfig c;
    c.rate = rate;
    CHECK_THROWS_AS((ServoLoop<ForceArm, VirtualClock>(device, clock, c)), std::invalid_argument);
  }
  LoopConfig c;
  c.priority = 0;
  CHECK_THROWS_AS((ServoLoop<ForceArm, VirtualClock>(device, clock, c)), std::invalid_argument);
  c = LoopConfig{};
  c.rate = 10000.0;
  CHECK_NOTHROW(ServoLoop<ForceArm, VirtualClock>(device, clock, c));
}

TEST_CASE("the loop homes, arms, keeps its rate on the virtual clock and soft-starts") {
  Rig rig(free_arm());
  Constant field{{0.0, 1.0, 0.0}};
  CHECK(rig.loop.run(field, {.max_ticks = 1000}) == StopReason::tick_limit);
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.ticks == 1000);
  CHECK(s.missed_deadlines == 0);
  CHECK_THAT(s.rate, WithinAbs(1000.0, 1e-9));
  CHECK_THAT(s.period_p50, WithinAbs(1e-3, 0.5e-6));
  CHECK_THAT(s.period_max, WithinAbs(1e-3, 1e-12));
  CHECK(s.wake_max == 0.0);
  CHECK(rig.arm.homed());
  CHECK(s.peak_force <= 1.0 + 1e-12);
  CHECK_THAT(s.peak_force, WithinAbs(1.0, 1e-12));  // soft start (0.25 s) finished within 1 s
  CHECK_FALSE(rig.arm.armed());                     // disarmed on exit
  CHECK(rig.arm.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
}

TEST_CASE("the loop runs at 10 kHz on the virtual clock") {
  LoopConfig c;
  c.rate = 10000.0;
  Rig rig(free_arm(), c);
  ZeroField zero;
  rig.loop.run(zero, {.max_ticks = 2000});
  CHECK_THAT(rig.loop.statistics().rate, WithinAbs(10000.0, 1e-6));
  CHECK_THAT(rig.loop.statistics().period_max, WithinAbs(1e-4, 1e-12));
}

TEST_CASE("after an overrun the loop skips whole periods instead of bursting") {
  Rig rig(free_arm());
  std::uint64_t tick = 0;
  std::vector<std::int64_t> wakes;
  wakes.reserve(100);
  auto slow_once = [&](const TickInput&) {
    wakes.push_back(rig.clock.now());
    if (++tick == 10) rig.clock.advance(2'500'000);  // 2.5 ms of work in one tick
    return glm::dvec3{0.0};
  };
  rig.loop.run(slow_once, {.max_ticks = 20});
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.missed_deadlines == 2);  // deadlines at +1 and +2 ms passed: skipped
  REQUIRE(wakes.size() == 20);
  for (std::size_t i = 1; i < wakes.size(); ++i) {
    const std::int64_t d = wakes[i] - wakes[i - 1];
    CHECK(d % 1'000'000 == 0);  // every wake on the absolute grid
    CHECK(d >= 1'000'000);      // never a burst of catch-up ticks
  }
  CHECK(wakes[10] - wakes[9] == 3'000'000);
}

TEST_CASE("K missed deadlines in a row zero the force and disarm") {
  Rig rig(free_arm());
  std::uint64_t tick = 0;
  glm::dvec3 at_trip{1.0};
  auto slow = [&](const TickInput& in) {
    ++tick;
    if (tick >= 400 && tick < 403) rig.clock.advance(1'200'000);  // three overruns
    if (tick == 404) at_trip = rig.loop.last_command();
    (void)in;
    return glm::dvec3{0.0, 0.5, 0.0};
  };
  rig.loop.run(slow, {.max_ticks = 420});
  CHECK((rig.loop.safety().latched() & safety_events::missed_deadlines) != 0);
  CHECK(at_trip == glm::dvec3{0.0});
}

TEST_CASE("stall and unplug: force zero within 2 ticks, no stale command") {
  for (const LinkFault fault : {LinkFault::stall, LinkFault::unplug}) {
    Rig rig(free_arm());
    const std::int64_t fault_tick = 500;
    rig.link.inject(fault, fault_tick, 200);
    std::vector<glm::dvec3> commands;
    commands.reserve(1000);
    std::int64_t first_missing = -1;
    auto cb = [&](const TickInput& in) {
      if (first_missing < 0 && in.read_status != Status::ok && rig.arm.ticks() >= fault_tick)
        first_missing = static_cast<std::int64_t>(in.tick);
      commands.push_back(rig.loop.last_command());
      return glm::dvec3{0.0, 0.8, 0.0};
    };
    const StopReason r = rig.loop.run(cb, {.max_ticks = 800});
    REQUIRE(first_missing > 0);
    commands.push_back(rig.loop.last_command());
    // The command computed on tick first_missing + 1 is already zero.
    const auto k = static_cast<std::size_t>(first_missing);
    CHECK(glm::length(commands[k - 1]) > 0.5);  // full force before the fault
    CHECK(commands[k + 2] == glm::dvec3{0.0});
    for (std::size_t i = k + 2; i < commands.size(); ++i)
      CHECK(commands[i] == glm::dvec3{0.0});
    if (fault == LinkFault::unplug) {
      CHECK(r == StopReason::disconnected);
      CHECK((rig.loop.safety().latched() & safety_events::disconnected) != 0);
    } else {
      CHECK((rig.loop.safety().latched() & safety_events::stale_state) != 0);
      // After the stall the arm gets fresh commands only, all zero force,
      // with increasing sequence numbers.
      CHECK(rig.arm.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
      CHECK(rig.arm.last_command().sequence == rig.device.last_command().sequence);
    }
  }
}

TEST_CASE("drop, duplicate, reorder and corrupt are reported and do not stop the force") {
  Rig rig(free_arm());
  rig.link.inject(LinkFault::drop, 400);
  rig.link.inject(LinkFault::duplicate, 410);
  rig.link.inject(LinkFault::reorder, 420);
  rig.link.inject(LinkFault::corrupt, 430);
  Constant field{{0.0, 0.5, 0.0}};
  rig.loop.run(field, {.max_ticks = 600});
  const LinkCounters& c = rig.device.counters();
  // The held (reordered) and the corrupt report each leave a gap when the
  // newer one is read first, so they count as drops too: 1 + 1 + 1.
  CHECK(c.dropped == 3);
  CHECK(c.duplicates == 1);
  CHECK(c.reordered == 1);
  CHECK(c.corrupt == 1);
  CHECK(rig.loop.safety().latched() == 0);  // single glitches do not trip the watchdog
}

TEST_CASE("a device fault (e-stop) zeroes the force; after release it soft-starts again") {
  Rig rig(free_arm());
  std::vector<double> command;
  command.reserve(1200);
  auto cb = [&](const TickInput& in) {
    if (in.tick == 500) rig.arm.inject_fault(status_bits::estop);
    if (in.tick == 700) rig.arm.release_estop();
    command.push_back(rig.loop.last_command().y);
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  rig.loop.run(cb, {.max_ticks = 1200});
  CHECK_THAT(command[499], WithinAbs(0.6, 1e-12));
  for (std::size_t i = 503; i < 700; ++i)
    CHECK(command[i] == 0.0);  // report latency: 1-2 ticks
  // The soft start ramps the limit from 0 to 3.3 N over 0.25 s, so 0.6 N
  // is reached about 45 ms after re-arming.
  CHECK(command[720] > 0.0);
  CHECK(command[720] < 0.45);
  CHECK_THAT(command[1199], WithinAbs(0.6, 1e-12));
}

TEST_CASE("a throwing callback: zero force first, then ServoError with the last states") {
  Rig rig(free_arm());
  auto cb = [&](const TickInput& in) -> glm::dvec3 {
    if (in.tick == 600) throw std::runtime_error("field failed");
    return {0.0, 0.7, 0.0};
  };
  bool caught = false;
  try {
    rig.loop.run(cb);
  } catch (const ServoError& e) {
    caught = true;
    CHECK(e.last_states().size() == ServoLoop<ForceArm, VirtualClock>::history_size);
    CHECK(e.last_states().back().valid);
    CHECK(std::string(e.what()).find("tick 600") != std::string::npos);
    try {
      std::rethrow_if_nested(e);
      FAIL("no nested exception");
    } catch (const std::runtime_error& inner) {
      CHECK(std::string(inner.what()) == "field failed");
    }
  }
  CHECK(caught);
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});
  CHECK(rig.arm.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
  CHECK_FALSE(rig.arm.last_command().flags & protocol::command_flags::arm);
}

namespace {

/// The hand starts at the home pose and presses 1 cm into a wall 5 mm below
/// it, then comes back out, over and over (2 cm/s).
SimulatedArmConfig pressing_hand() {
  SimulatedArmConfig a;
  a.hand.path = HandPath::line({0.0, 0.0, 0.0}, {0.0, -0.015, 0.0}, 0.02);
  return a;
}
/// The loop for the wall tests: passivity controller on or off, no slew limit to speak of.
LoopConfig wall_loop(bool passivity) {
  LoopConfig c;
  c.safety.passivity_enabled = passivity;
  c.safety.slew_rate = 1e5;
  return c;
}

}  // namespace

TEST_CASE("closed loop: the hand presses a stiff wall; stable, energy bounded with passivity on") {
  for (const bool passivity : {false, true}) {
    Rig rig(pressing_hand(), wall_loop(passivity));
    // 2000 N/m: the stiffest wall this arm renders passively. The board
    // acts on a state one period old (t_d = T = 1 ms) and holds it for a
    // period, so passivity needs b > K (T/2 + t_d) (Colgate & Schenkel
    // 1997 for the hold; the delayed spring K x(t - t_d) ~ K x - K t_d v
    // adds K t_d of negative damping); b is the hand's 3 N s/m plus the
    // joints' 2e-4 N m s/rad / l^2 ~ 0.01 N s/m: K < 3.01 / 1.5e-3 ~ 2000 N/m.
    Wall wall{-0.005, 2000.0};
    double max_ke = 0.0, min_energy = 0.0, min_y = 0.0;
    std::uint64_t n = 0;
    auto cb = [&](const TickInput& in) {
      max_ke = std::max(max_ke, rig.arm.kinetic_energy());
      if (in.trusted) min_y = std::min(min_y, in.probe.position.y);  // where the host, and its wall, see it
      min_energy = std::min(min_energy, rig.loop.safety().observed_energy());
      ++n;
      return wall.force(in.probe);
    };
    rig.loop.run(cb, {.max_ticks = 4000});
    INFO("passivity " << passivity);
    // Stable: the handle never sinks deeper than the static balance of the
    // hand spring (300 N/m, at most 1 cm pull) against the wall (2000 N/m:
    // 1.3 mm deep) allows, and never flies off: kinetic energy stays at the
    // level of the hand's own 2 cm/s motion (1/2 m v^2 ~ 1e-5 J).
    CHECK(min_y > -0.005 - 0.0025);
    CHECK(max_ke < 1e-4);  // [J]
    CHECK(rig.loop.statistics().peak_force <= 3.3 + 1e-12);
    CHECK(rig.loop.statistics().peak_force > 2.0);  // the wall was really pressed (balance ~2.6 N)
    if (passivity) CHECK(min_energy >= -1e-9);
  }
}

/// A wall that sees the handle 10 ticks late: delay makes it an active
/// (energy-generating) environment, the case the passivity controller is for.
/// 2000 N/m, the stiffest wall the arm renders passively without that
/// delay (see the stiff wall above), so the energy comes from the wall's.
struct DelayedWall {
  double wall_y{-0.005};
  double stiffness{2000.0};
  std::array<double, 16> history{};
  std::size_t n{0};
  glm::dvec3 force(const Probe& p) noexcept {
    history[n % history.size()] = p.position.y;
    const double y = n >= 10 ? history[(n - 10) % history.size()] : p.position.y;
    ++n;
    const double depth = wall_y - y;
    return depth > 0.0 ? glm::dvec3{0.0, stiffness * depth, 0.0} : glm::dvec3{0.0};
  }
};

TEST_CASE("closed loop: a delayed wall oscillates; the passivity controller damps it") {
  double mean_ke[2] = {0.0, 0.0}, min_energy = 0.0;
  for (const bool passivity : {false, true}) {
    Rig rig(pressing_hand(), wall_loop(passivity));
    DelayedWall wall;
    double sum = 0.0;
    int n = 0;
    auto cb = [&](const TickInput& in) {
      if (in.probe.time > 0.5) {
        sum += rig.arm.kinetic_energy();
        ++n;
        if (passivity) min_energy = std::min(min_energy, rig.loop.safety().observed_energy());
      }
      return wall.force(in.probe);
    };
    rig.loop.run(cb, {.max_ticks = 4000});
    mean_ke[passivity ? 1 : 0] = sum / n;
  }
  INFO("mean kinetic energy without / with passivity control: " << mean_ke[0] << " / " << mean_ke[1] << " J");
  CHECK(mean_ke[0] > 1e-3);              // without it the contact rattles
  CHECK(mean_ke[1] < mean_ke[0] / 5.0);  // with it the energy is an order smaller
  CHECK(min_energy > -1e-3);             // observed energy stays (nearly) non-negative; the damping cap bounds it
}

TEST_CASE("no heap allocation per tick") {
  if (!test::allocations_counted) return;  // ThreadSanitizer build: see alloc_counter.hpp
  Rig rig(free_arm());
  Wall wall;
  rig.loop.run(wall, {.max_ticks = 100});  // warm up
  const long allocations = test::count_allocations([&] { rig.loop.run(wall, {.max_ticks = 2000}); });
  CHECK(allocations == 0);
  TickInput in;
  const long manual = test::count_allocations([&] {
    for (int i = 0; i < 500; ++i) {
      rig.clock.advance(1'000'000);
      rig.loop.read_once(in);
      rig.loop.write_once(wall.force(in.probe));
    }
  });
  CHECK(manual == 0);
}

TEST_CASE("read_once / write_once for users who own the thread") {
  Rig rig(free_arm());
  TickInput in;
  for (int i = 0; i < 400; ++i) {
    rig.clock.advance(1'000'000);
    rig.loop.read_once(in);
    rig.loop.write_once({0.0, 0.3, 0.0});
  }
  CHECK(in.state.armed());
  CHECK(in.probe.position == in.state.position);
  CHECK_THAT(in.probe.time, WithinAbs(0.399, 1e-9));
  CHECK_THAT(rig.loop.last_command().y, WithinAbs(0.3, 1e-12));
  rig.loop.write_once({qnan, 0.0, 0.0});
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});
}

TEST_CASE("statistics are readable from another thread while the loop runs") {
  Rig rig(free_arm());
  Wall wall;
  std::thread servo([&] { rig.loop.run(wall); });
  std::uint64_t seen = 0;
  while (seen < 3000) {
    const LoopSnapshot s = rig.loop.statistics();
    CHECK(s.ticks >= seen);
    seen = s.ticks;
    std::this_thread::yield();
  }
  rig.loop.request_stop();
  servo.join();
  CHECK(rig.loop.statistics().ticks >= 3000);
  CHECK(rig.loop.statistics().missed_deadlines == 0);
}

TEST_CASE("real-time: enforce is granted or refuses to start; best effort runs on and reports the refusal as a value") {
  for (const RealTime mode : {RealTime::enforce, RealTime::best_effort}) {
    LoopConfig c;
    c.realtime = mode;
    c.priority = 10;
    VirtualClock clock;
    SimulatedArm arm(free_arm());
    SimulatedTransport link(arm, [&] { return clock.now(); });
    ForceArm device(link);
    ServoLoop<ForceArm, VirtualClock> loop(device, clock, c);
    ZeroField zero;
    bool threw = false;
    try {
      loop.run(zero, {.max_ticks = 10});
    } catch (const std::runtime_error& e) {
      threw = true;
      CHECK(mode == RealTime::enforce);
      CHECK(std::string(e.what()).find("RealTime::enforce refused") != std::string::npos);
      CHECK(loop.statistics().ticks == 0);  // refused before the first tick
    }
    CHECK(loop.realtime_refused().empty() == loop.realtime_granted());
    if (mode == RealTime::enforce)
      CHECK(threw != loop.realtime_granted());
    else
      CHECK(loop.statistics().ticks == 10);
  }
  const rt::RealTimeGrant grant = rt::request_realtime(10);
  rt::release_realtime(grant.memory_locked);
  CHECK(grant.granted() == grant.refused.empty());
}

// ------------------------------------------------- life cycle (stop, restart)

namespace {
/// Per-run record of the commands the safety chain produced, tick by tick.
struct CommandLog {
  std::vector<glm::dvec3> commands;
  CommandLog() { commands.reserve(4000); }
};

/// Checks that a run's commands start at zero, never step by more than the
/// slew limit and stay under the soft-start ramp measured from the first
/// non-zero command (the arm reported armed just before it).
void check_gentle_start(const std::vector<glm::dvec3>& c, double limit, double slew_step, double soft_start,
                        double period) {
  REQUIRE(!c.empty());
  CHECK(glm::length(c.front()) <= slew_step * (1 + 1e-12));
  std::size_t first = c.size();
  for (std::size_t i = 0; i < c.size() && first == c.size(); ++i)
    if (c[i] != glm::dvec3{0.0}) first = i;
  REQUIRE(first < c.size());
  for (std::size_t i = 1; i < c.size(); ++i)
    CHECK(glm::length(c[i] - c[i - 1]) <= slew_step * (1 + 1e-12));
  for (std::size_t i = first; i < c.size(); ++i) {
    const double ramp = limit * std::min(1.0, static_cast<double>(i - first + 1) * period / soft_start);
    CHECK(glm::length(c[i]) <= ramp * (1 + 1e-9) + 1e-12);
  }
}
}  // namespace

TEST_CASE("a stop requested before run() ends that run before its first tick") {
  Rig rig(free_arm());
  Constant field{{0.0, 1.0, 0.0}};
  rig.loop.request_stop();
  CHECK(rig.loop.run(field, {.max_ticks = 100000}) == StopReason::requested);
  CHECK(rig.loop.statistics().ticks == 0);
  // The request is consumed by the run it stopped: the next run runs.
  CHECK(rig.loop.run(field, {.max_ticks = 10}) == StopReason::tick_limit);
  CHECK(rig.loop.statistics().ticks == 10);
}

TEST_CASE("the README's pattern: run on a thread, request_stop(), join, never lost") {
  // No tick limit at all: a lost stop would hang here, so the harness's
  // own timeout is the failure. The virtual clock never sleeps, so the loop
  // spins as fast as it can while the stop races its start.
  for (int trial = 0; trial < 200; ++trial) {
    Rig rig(free_arm());
    ZeroField zero;
    StopReason reason = StopReason::tick_limit;
    std::thread servo([&] { reason = rig.loop.run(zero); });
    rig.loop.request_stop();
    servo.join();
    CHECK(reason == StopReason::requested);
    CHECK(rig.arm.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
  }
}

TEST_CASE("run/stop/run/stop: every start ramps from zero through the slew limit and the soft start") {
  for (const bool disarm_on_exit : {false, true}) {
    INFO("disarm_on_exit " << disarm_on_exit);
    LoopConfig c;
    c.disarm_on_exit = disarm_on_exit;
    Rig rig(free_arm(), c);
    const double step = c.safety.slew_rate * 1e-3, limit = 3.3, soft = c.safety.soft_start;
    for (int run = 0; run < 3; ++run) {
      INFO("run " << run);
      CommandLog log;
      auto cb = [&](const TickInput& in) {
        if (in.tick > 0) log.commands.push_back(rig.loop.last_command());
        if (log.commands.size() == 600) rig.loop.request_stop();  // stop from inside, mid-run
        return glm::dvec3{0.0, 3.0, 0.0};
      };
      CHECK(rig.loop.run(cb) == StopReason::requested);
      check_gentle_start(log.commands, limit, step, soft, 1e-3);
      CHECK_THAT(log.commands.back().y, WithinAbs(3.0, 1e-12));  // armed again: full force after the ramp
      CHECK(rig.loop.last_command() == glm::dvec3{0.0});
      CHECK(rig.arm.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
      CHECK(rig.arm.armed() == !disarm_on_exit);
    }
    CHECK(rig.loop.statistics().latches == 0);
  }
}

TEST_CASE("a latched fault from an earlier run: run() refuses to arm with a clear error until clear_fault()") {
  Rig rig(free_arm());
  rig.link.inject(LinkFault::stall, 300, 30);  // 30 ms without reports: stale state latches
  Constant field{{0.0, 0.5, 0.0}};
  rig.loop.run(field, {.max_ticks = 500});
  REQUIRE((rig.loop.safety().latched() & safety_events::stale_state) != 0);
  CHECK(rig.loop.statistics().latches == 1);
  CHECK(rig.loop.statistics().last_latch == safety_events::stale_state);
  try {
    rig.loop.run(field, {.max_ticks = 10});
    FAIL("run() armed over a latched fault");
  } catch (const ServoError& e) {
    CHECK(std::string(e.what()).find("cannot arm") != std::string::npos);
    CHECK(std::string(e.what()).find("stale state") != std::string::npos);
    CHECK(std::string(e.what()).find("clear_fault()") != std::string::npos);
  }
  rig.loop.clear_fault();
  CommandLog log;
  auto cb = [&](const TickInput& in) {
    if (in.tick > 0) log.commands.push_back(rig.loop.last_command());
    return glm::dvec3{0.0, 0.5, 0.0};
  };
  CHECK(rig.loop.run(cb, {.max_ticks = 600}) == StopReason::tick_limit);
  check_gentle_start(log.commands, 3.3, 1.0, 0.25, 1e-3);
  CHECK_THAT(log.commands.back().y, WithinAbs(0.5, 1e-12));
}

TEST_CASE("one late wake-up is one event: no latch, the force carries on") {
  Rig rig(free_arm());
  auto cb = [&](const TickInput& in) {
    if (in.tick == 500) rig.clock.advance(3'200'000);  // the thread is descheduled for 3.2 ms
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  rig.loop.run(cb, {.max_ticks = 1000});
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.missed_deadlines == 3);  // the periods it skipped (deadlines +1, +2, +3 ms) are still counted
  CHECK(s.overruns == 1);          // as one late tick
  CHECK(s.latches == 0);
  CHECK(rig.loop.safety().latched() == 0);
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});  // the run ended, zero commanded
  CHECK_THAT(s.peak_force, WithinAbs(0.6, 1e-12));
}

TEST_CASE("late wakes tick after tick still latch; with recover_after the loop re-arms with the soft start") {
  LoopConfig c;
  c.recover_after = 0.2;
  Rig rig(free_arm(), c);
  CommandLog log;
  auto cb = [&](const TickInput& in) {
    if (in.tick >= 400 && in.tick < 403) rig.clock.advance(1'200'000);  // three overrunning ticks in a row
    log.commands.push_back(rig.loop.last_command());
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  rig.loop.run(cb, {.max_ticks = 1500});
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.latches == 1);
  CHECK(s.last_latch == safety_events::missed_deadlines);
  CHECK(s.recoveries == 1);
  CHECK(rig.loop.safety().latched() == 0);
  // Zero from the latch until recovery (200 ms of fresh, on-time states).
  std::size_t zero_from = 0, back_at = 0;
  for (std::size_t i = 400; i < log.commands.size(); ++i) {
    if (!zero_from && log.commands[i] == glm::dvec3{0.0}) zero_from = i;
    if (zero_from && !back_at && log.commands[i] != glm::dvec3{0.0}) back_at = i;
  }
  REQUIRE(zero_from > 0);
  REQUIRE(back_at > 0);
  CHECK(zero_from <= 404);
  CHECK(back_at >= zero_from + 200);
  // The force comes back under the soft start, from zero.
  const std::vector<glm::dvec3> after(log.commands.begin() + static_cast<long>(back_at) - 1, log.commands.end());
  check_gentle_start(after, 3.3, 1.0, 0.25, 1e-3);
  CHECK_THAT(log.commands.back().y, WithinAbs(0.6, 1e-12));
}

TEST_CASE(
    "recover_after: a stall that trips the firmware watchdog recovers for real, force back through the soft start") {
  LoopConfig c;
  c.recover_after = 0.2;
  Rig rig(free_arm(), c);
  rig.link.inject(LinkFault::stall, 300, 30);  // 30 ms: the loop's state age latches, the arm's 20 ms watchdog trips
  CommandLog log;
  bool tripped = false, armed_at_end = false;
  auto cb = [&](const TickInput& in) {
    log.commands.push_back(rig.loop.last_command());
    tripped = tripped || (in.state.flags & status_bits::watchdog_tripped) != 0;
    armed_at_end = in.state.armed() && !in.state.faulted();
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  rig.loop.run(cb, {.max_ticks = 1200});
  REQUIRE(tripped);  // the device latched a fault of its own
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.latches == 1);
  CHECK(s.last_latch == safety_events::stale_state);
  CHECK(s.recoveries == 1);
  CHECK(armed_at_end);
  CHECK(rig.arm.faults() == 0);                              // the loop cleared the watchdog trip while disarmed
  CHECK_THAT(log.commands.back().y, WithinAbs(0.6, 1e-12));  // force came back
  std::size_t zero_from = 0, back_at = 0;
  for (std::size_t i = 300; i < log.commands.size(); ++i) {
    if (!zero_from && log.commands[i] == glm::dvec3{0.0}) zero_from = i;
    if (zero_from && !back_at && log.commands[i] != glm::dvec3{0.0}) back_at = i;
  }
  REQUIRE(back_at > zero_from + 200);  // recover_after of fresh states first
  const std::vector<glm::dvec3> after(log.commands.begin() + static_cast<long>(back_at) - 1, log.commands.end());
  check_gentle_start(after, 3.3, 1.0, 0.25, 1e-3);
  // The statistics date the latch and the moment force came back.
  CHECK(s.last_latch_time > 0.29);
  CHECK(s.last_latch_time < 0.32);
  CHECK(s.last_recovery_time >= s.last_latch_time + 0.2);
  CHECK_THAT(s.last_recovery_time, WithinAbs(static_cast<double>(back_at - 1) * 1e-3, 1.5e-3));
}

TEST_CASE("recover_after claims no recovery while the device's fault cannot be cleared (e-stop held)") {
  LoopConfig c;
  c.recover_after = 0.2;
  Rig rig(free_arm(), c);
  rig.link.inject(LinkFault::stall, 300, 30);
  CommandLog log;
  auto cb = [&](const TickInput& in) {
    if (in.tick == 310) rig.arm.inject_fault(status_bits::estop);  // pressed during the stall, and held
    log.commands.push_back(rig.loop.last_command());
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  rig.loop.run(cb, {.max_ticks = 1200});
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.latches == 1);
  CHECK(s.recoveries == 0);
  CHECK(s.last_recovery_time < 0.0);
  CHECK((rig.loop.safety().latched() & safety_events::stale_state) != 0);  // still latched, and says so
  for (std::size_t i = 320; i < log.commands.size(); ++i)
    CHECK(log.commands[i] == glm::dvec3{0.0});
}

TEST_CASE("a stall longer than the state age limit still latches, and is reported") {
  Rig rig(free_arm());
  rig.link.inject(LinkFault::stall, 300, 15);
  Constant field{{0.0, 0.5, 0.0}};
  rig.loop.run(field, {.max_ticks = 600});
  CHECK(rig.loop.statistics().latches == 1);
  CHECK(rig.loop.statistics().last_latch == safety_events::stale_state);
  CHECK(safety_events::names(rig.loop.statistics().last_latch) == "stale state");
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});
}

TEST_CASE("a device that reboots is taken up again within a few ticks, force zero meanwhile") {
  Rig rig(free_arm());
  rig.link.inject(LinkFault::reboot, 500);
  CommandLog log;
  std::vector<Status> reads;
  reads.reserve(3000);
  auto cb = [&](const TickInput& in) {
    log.commands.push_back(rig.loop.last_command());
    reads.push_back(in.read_status);
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  rig.loop.run(cb, {.max_ticks = 2000});
  CHECK(rig.arm.boots() == 1);
  CHECK(rig.device.counters().resyncs == 1);
  // The first ticks after the reboot are held back (Status::resync) and
  // command zero; a fresh stream is accepted after 3 consistent reports.
  const auto first_resync = std::find(reads.begin(), reads.end(), Status::resync);
  REQUIRE(first_resync != reads.end());
  const auto k = static_cast<std::size_t>(first_resync - reads.begin());
  CHECK(std::count(reads.begin(), reads.end(), Status::resync) == 2);
  CHECK(reads[k + 2] == Status::ok);
  for (std::size_t i = k + 1; i < k + 50; ++i)
    CHECK(log.commands[i] == glm::dvec3{0.0});  // then homing (50 ticks)
  // The arm homes and arms again and the force ramps back up from zero.
  CHECK(rig.arm.homed());
  const std::vector<glm::dvec3> after(log.commands.begin() + static_cast<long>(k) + 1, log.commands.end());
  check_gentle_start(after, 3.3, 1.0, 0.25, 1e-3);
  CHECK_THAT(log.commands.back().y, WithinAbs(0.6, 1e-12));
  CHECK(rig.loop.statistics().latches == 0);
}

TEST_CASE("an impossible pose with a valid CRC latches: zero force from that tick on, and the latch says why") {
  Rig rig(free_arm());
  rig.link.inject(LinkFault::wild_counts, 600, 40);  // encoders at +-2^31 for 40 ms, CRC valid
  CommandLog log;
  std::vector<Status> reads;
  reads.reserve(1000);
  auto cb = [&](const TickInput& in) {
    log.commands.push_back(rig.loop.last_command());  // the command of the tick before
    reads.push_back(in.read_status);
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  rig.loop.run(cb, {.max_ticks = 900});
  const auto first = std::find(reads.begin(), reads.end(), Status::impossible);
  REQUIRE(first != reads.end());
  const auto k = static_cast<std::size_t>(first - reads.begin());
  CHECK(k >= 598);
  CHECK(k <= 602);
  CHECK_THAT(log.commands[k].y, WithinAbs(0.6, 1e-12));  // full force on the tick before
  for (std::size_t i = k + 1; i < log.commands.size(); ++i)
    CHECK(log.commands[i] == glm::dvec3{0.0});  // zero from that tick on, after the fault too
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});
  CHECK((rig.loop.safety().latched() & safety_events::impossible_state) != 0);
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.latches == 1);
  CHECK(s.last_latch == safety_events::impossible_state);
  CHECK(safety_events::names(s.last_latch) == "impossible state");
  CHECK_FALSE(rig.arm.armed());  // the latch disarmed the arm
  // The wild pose never became the loop's state.
  CHECK(std::abs(rig.loop.state().joint_angles.x) < 2.0);
}

TEST_CASE("a non-finite position from a device latches as an impossible state") {
  /// A device that reports a NaN position from tick 300 on.
  struct NanDevice {
    DeviceInfo info_{};
    std::uint64_t reads{0};
    glm::dvec3 commanded{0.0};
    Status read(DeviceState& s) noexcept {
      ++reads;
      s.valid = true;
      s.flags = status_bits::homed | status_bits::armed;
      s.position = reads >= 300 ? glm::dvec3{std::nan(""), 0.0, 0.0} : glm::dvec3{0.0};
      return Status::ok;
    }
    Status write(const glm::dvec3& f) noexcept {
      commanded = f;
      return Status::ok;
    }
    Status set_armed(bool) noexcept { return Status::ok; }
    Status request_home() noexcept { return Status::ok; }
    const DeviceInfo& info() const noexcept { return info_; }
  } device;
  VirtualClock clock;
  ServoLoop<NanDevice, VirtualClock> loop(device, clock, Rig::quiet({}));
  std::vector<glm::dvec3> commands;
  commands.reserve(600);
  auto cb = [&](const TickInput&) {
    commands.push_back(device.commanded);
    return glm::dvec3{0.0, 0.6, 0.0};
  };
  loop.run(cb, {.max_ticks = 500});
  REQUIRE(commands.size() == 500);
  CHECK_THAT(commands[299].y, WithinAbs(0.6, 1e-12));
  for (std::size_t i = 300; i < commands.size(); ++i)
    CHECK(commands[i] == glm::dvec3{0.0});
  CHECK(loop.statistics().last_latch == safety_events::impossible_state);
}

TEST_CASE("max_ticks = 0 is an error, not 'no limit'") {
  Rig rig(free_arm());
  ZeroField zero;
  CHECK_THROWS_AS(rig.loop.run(zero, {.max_ticks = 0}), std::invalid_argument);
  CHECK(rig.loop.statistics().ticks == 0);
  CHECK(RunLimits{}.max_ticks == no_tick_limit);
}

TEST_CASE("safety chain: a NaN, Inf, non-positive or absurd period is zero force and a counted event") {
  SafetyChain chain(SafetyConfig{}, 3.3);
  SafetyInput in;
  in.force = {0, 1.0, 0};
  in.time_since_armed = 1.0;
  for (int i = 0; i < 5; ++i)
    (void)chain.process(in);
  REQUIRE(chain.previous().y == 1.0);
  for (const double bad : {qnan, inf, -inf, 0.0, -1e-3, 1e-9, 5.0}) {
    in.period = bad;
    in.force = {0, 3.3, 0};
    CHECK(chain.process(in) == glm::dvec3{0.0});
    CHECK((chain.events() & safety_events::bad_period) != 0);
  }
  in.period = 1e-3;
  CHECK_THAT(chain.process(in).y, WithinAbs(1.0, 1e-12));  // slew-limited from the zero it commanded
}

TEST_CASE("safety chain: an extreme velocity cannot disable the passivity observer") {
  SafetyConfig cfg;
  cfg.passivity_enabled = true;
  cfg.soft_start_enabled = false;
  SafetyChain chain(cfg, 3.3);
  SafetyInput in;
  in.force = {0, 1.0, 0};
  in.time_since_armed = 1.0;
  in.velocity = {0, 1e300, 0};
  CHECK(chain.process(in) == glm::dvec3{0.0});
  CHECK((chain.events() & safety_events::energy_overflow) != 0);
  CHECK(std::isfinite(chain.observed_energy()));
  in.velocity = {0, -1e308, 0};
  in.force = {0, 1e308, 0};
  CHECK(chain.process(in) == glm::dvec3{0.0});
  CHECK(std::isfinite(chain.observed_energy()));
  // Ordinary motion afterwards: the observer still works (damping added
  // when the field would generate energy).
  in.velocity = {0, -0.1, 0};
  in.force = {0, 1.0, 0};
  for (int i = 0; i < 50; ++i)
    (void)chain.process(in);
  CHECK(std::isfinite(chain.observed_energy()));
  CHECK(chain.observed_energy() >= -1e-12);
}

// ------------------------------------------------------- pacing: early, late

TEST_CASE("an early wake-up sleeps again: no short period and no double-length one after it") {
  Rig rig(free_arm());
  std::vector<std::int64_t> wakes;
  wakes.reserve(100);
  auto cb = [&](const TickInput& in) {
    wakes.push_back(rig.clock.now());
    if (in.tick == 20) rig.clock.shift_next_wake(-400'000);  // the next sleep returns 0.4 ms early
    return glm::dvec3{0.0};
  };
  rig.loop.run(cb, {.max_ticks = 40});
  REQUIRE(wakes.size() == 40);
  for (std::size_t i = 1; i < wakes.size(); ++i)
    CHECK(wakes[i] - wakes[i - 1] == 1'000'000);
  CHECK(rig.loop.statistics().overruns == 0);
}

TEST_CASE("a late wake-up is followed by the next deadline on the grid, not a burst") {
  Rig rig(free_arm());
  std::vector<std::int64_t> wakes;
  wakes.reserve(100);
  auto cb = [&](const TickInput& in) {
    wakes.push_back(rig.clock.now());
    if (in.tick == 20) rig.clock.shift_next_wake(2'600'000);  // the next wake is 2.6 ms late
    return glm::dvec3{0.0};
  };
  rig.loop.run(cb, {.max_ticks = 40});
  REQUIRE(wakes.size() == 40);
  CHECK(wakes[21] - wakes[20] == 3'600'000);  // woke late, inside the period of deadline +3 ms
  CHECK(wakes[22] - wakes[21] == 400'000);    // the next deadline on the grid: +4 ms (not at once, not +1 ms later)
  for (std::size_t i = 23; i < wakes.size(); ++i)
    CHECK(wakes[i] - wakes[i - 1] == 1'000'000);
  CHECK(rig.loop.statistics().wake_max == Approx(2.6e-3).margin(1e-12));
  CHECK(rig.loop.statistics().latches == 0);
}

// ----------------------------------------------------------- two arms, one loop

namespace {
/// Two simulated arms with their links on one virtual clock.
struct TwoArms {
  VirtualClock clock;
  SimulatedArm arm_a, arm_b;
  SimulatedTransport link_a, link_b;
  ForceArm device_a, device_b;
  MultiArmLoop<ForceArm, 2, VirtualClock> loop;
  explicit TwoArms(ArmFaultPolicy policy = ArmFaultPolicy::isolate)
      : arm_a(free_arm()),
        arm_b(free_arm()),
        link_a(arm_a, [this] { return clock.now(); }),
        link_b(
            arm_b, [this] { return clock.now(); }, 0.25),
        device_a(link_a),
        device_b(link_b),
        loop({&device_a, &device_b}, clock, Rig::quiet({}), policy) {}
};
}  // namespace

TEST_CASE("two arms on one deadline: each its own field, soft start and statistics") {
  TwoArms rig;
  Constant push_a{{0.0, 0.8, 0.0}}, push_b{{0.5, 0.0, 0.0}};
  CHECK(rig.loop.run({.max_ticks = 1000}, push_a, push_b) == StopReason::tick_limit);
  const LoopSnapshot s = rig.loop.statistics();
  CHECK(s.ticks == 1000);
  CHECK_THAT(s.rate, WithinAbs(1000.0, 1e-9));
  CHECK(s.overruns == 0);
  CHECK_THAT(rig.loop.arm(0).statistics().peak_force, WithinAbs(0.8, 1e-12));
  CHECK_THAT(rig.loop.arm(1).statistics().peak_force, WithinAbs(0.5, 1e-12));
  CHECK(rig.arm_a.homed());
  CHECK(rig.arm_b.homed());
  CHECK(rig.arm_a.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
  CHECK(rig.arm_b.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
}

TEST_CASE("two arms: a fault on one zeroes that arm only (isolate) or both (stop_all)") {
  for (const ArmFaultPolicy policy : {ArmFaultPolicy::isolate, ArmFaultPolicy::stop_all}) {
    INFO("policy " << static_cast<int>(policy));
    TwoArms rig(policy);
    rig.link_b.inject(LinkFault::stall, 500, 30);  // arm b's link stalls for 30 ms: stale state latches b
    Constant push_a{{0.0, 0.8, 0.0}}, push_b{{0.0, 0.8, 0.0}};
    rig.loop.run({.max_ticks = 900}, push_a, push_b);
    CHECK((rig.loop.arm(1).safety().latched() & safety_events::stale_state) != 0);
    if (policy == ArmFaultPolicy::isolate) {
      CHECK(rig.loop.arm(0).safety().latched() == 0);
      CHECK(rig.loop.arm(0).statistics().latches == 0);
    } else {
      CHECK(rig.loop.arm(0).safety().latched() == safety_events::other_arm);
      CHECK(rig.loop.arm(0).statistics().latches == 1);
    }
    CHECK(rig.loop.arm(1).statistics().latches == 1);
  }
}

TEST_CASE("two arms: forces while a fault holds, tick by tick") {
  TwoArms rig(ArmFaultPolicy::isolate);
  rig.link_b.inject(LinkFault::unplug, 600);
  std::vector<glm::dvec3> a, b;
  a.reserve(1000);
  b.reserve(1000);
  struct Recorder {
    const ServoLoop<ForceArm, VirtualClock>* loop;
    std::vector<glm::dvec3>* log;
    glm::dvec3 push;
    glm::dvec3 force(const Probe&) const noexcept {
      if (log->size() < log->capacity()) log->push_back(loop->last_command());
      return push;
    }
  };
  Recorder ra{&rig.loop.arm(0), &a, {0.0, 0.8, 0.0}}, rb{&rig.loop.arm(1), &b, {0.0, 0.8, 0.0}};
  CHECK(rig.loop.run({.max_ticks = 900}, ra, rb) == StopReason::tick_limit);  // isolate: a carries on alone
  REQUIRE(a.size() == 900);
  REQUIRE(b.size() == 900);
  CHECK_THAT(a.back().y, WithinAbs(0.8, 1e-12));
  for (std::size_t i = 603; i < b.size(); ++i)
    CHECK(b[i] == glm::dvec3{0.0});
  CHECK((rig.loop.arm(1).safety().latched() & safety_events::disconnected) != 0);
}

TEST_CASE("two arms: a run refuses to start over a latched arm; the README's stop pattern works") {
  TwoArms rig;
  rig.link_b.inject(LinkFault::stall, 100, 30);
  Constant push{{0.0, 0.5, 0.0}};
  rig.loop.run({.max_ticks = 300}, push, push);
  CHECK_THROWS_AS(rig.loop.run({.max_ticks = 10}, push, push), ServoError);
  rig.loop.clear_fault(1);
  rig.loop.request_stop();
  CHECK(rig.loop.run({}, push, push) == StopReason::requested);
  CHECK(rig.loop.statistics().ticks == 300);  // the stopped run ran no tick
}

TEST_CASE("two arms: no heap allocation per tick") {
  TwoArms rig;
  Wall wall;
  rig.loop.run({.max_ticks = 100}, wall, wall);  // warm up
  const long allocations = test::count_allocations([&] { rig.loop.run({.max_ticks = 2000}, wall, wall); });
  CHECK(allocations == 0);
}

// ------------------------------------------------- two arms: trusted poses

namespace {
using ArmLoop = ServoLoop<ForceArm, VirtualClock>;

/// A teacher whose hand holds its handle at the home pose and a free
/// student guided toward the teacher's handle, on one virtual clock.
struct TeacherStudent {
  VirtualClock clock;
  SimulatedArm teacher_arm, student_arm;
  SimulatedTransport teacher_link, student_link;
  ForceArm teacher, student;
  MultiArmLoop<ForceArm, 2, VirtualClock> loop;
  TeacherStudent(SimulatedArmConfig teacher_config, ArmFaultPolicy policy)
      : teacher_arm(teacher_config),
        student_arm(free_arm()),
        teacher_link(teacher_arm, [this] { return clock.now(); }),
        student_link(
            student_arm, [this] { return clock.now(); }, 0.25),
        teacher(teacher_link),
        student(student_link),
        loop({&teacher, &student}, clock, Rig::quiet({}), policy) {}
};

/// The student's field: GuidanceField, recording each tick whether the
/// teacher was trusted and homed, and the student's command of the tick before.
struct RecordedGuidance {
  GuidanceField<ArmLoop> guidance;
  const ArmLoop* student;
  const SimulatedArm* teacher_arm;
  std::vector<glm::dvec3> commands;
  std::vector<char> trusted, homed;
  RecordedGuidance(const ArmLoop& t, const ArmLoop& s, const SimulatedArm& a)
      : guidance{&t, 150.0, 1.0}, student(&s), teacher_arm(&a) {
    commands.reserve(3000);
    trusted.reserve(3000);
    homed.reserve(3000);
  }
  glm::dvec3 force(const Probe& p) noexcept {
    if (commands.size() < commands.capacity()) {
      commands.push_back(student->last_command());
      trusted.push_back(guidance.leader->trusted() ? 1 : 0);
      homed.push_back(teacher_arm->homed() ? 1 : 0);
    }
    return guidance.force(p);
  }
  /// The student's command on tick i.
  [[nodiscard]] glm::dvec3 command(std::size_t i) const { return commands.at(i + 1); }
};

SimulatedArmConfig holding_teacher() {
  SimulatedArmConfig c;
  c.hand.path = HandPath::hold({0.0, 0.0, 0.0});  // the teacher's hand holds the handle at home
  return c;
}
}  // namespace

TEST_CASE("ServoLoop::trusted(): false until homed and armed as asked, false while resynchronising or latched") {
  Rig rig(free_arm());
  std::vector<char> trusted;
  std::vector<char> homed_armed;
  trusted.reserve(700);
  homed_armed.reserve(700);
  rig.link.inject(LinkFault::reboot, 400);
  auto cb = [&](const TickInput& in) {
    trusted.push_back(in.trusted ? 1 : 0);
    CHECK(in.trusted == rig.loop.trusted());
    homed_armed.push_back(in.state.homed() && in.state.armed() ? 1 : 0);
    return glm::dvec3{0.0};
  };
  rig.loop.run(cb, {.max_ticks = 700});
  CHECK(trusted[0] == 0);
  CHECK(trusted[30] == 0);  // homing: the pose is offset by whatever the encoders held
  for (std::size_t i = 0; i < trusted.size(); ++i) {
    INFO("tick " << i);
    if (trusted[i]) CHECK(homed_armed[i]);  // never an unhomed or unarmed pose
  }
  CHECK(trusted[300] == 1);
  CHECK(std::count(trusted.begin() + 395, trusted.begin() + 460, 0) >= 50);  // the reboot: resync, homing
  CHECK(trusted.back() == 1);
  CHECK_FALSE(rig.loop.trusted());  // the run ended: disarmed
}

TEST_CASE(
    "two arms: the student feels nothing while the teacher's pose is not trusted, at start-up and after a reboot") {
  for (const ArmFaultPolicy policy : {ArmFaultPolicy::isolate, ArmFaultPolicy::stop_all}) {
    INFO("policy " << static_cast<int>(policy));
    SECTION("start-up: the teacher homes for 300 ms while the student is armed") {
      SimulatedArmConfig t = holding_teacher();
      t.homing_ticks = 300;
      TeacherStudent rig(t, policy);
      RecordedGuidance guided(rig.loop.arm(0), rig.loop.arm(1), rig.teacher_arm);
      Constant none{{0.0, 0.0, 0.0}};
      rig.loop.run({.max_ticks = 800}, none, guided);
      const std::size_t n = guided.commands.size() - 1;
      std::size_t homed_at = 0;
      while (homed_at < n && !guided.homed[homed_at])
        ++homed_at;
      REQUIRE(homed_at >= 290);
      REQUIRE(homed_at < 320);
      for (std::size_t i = 0; i < n; ++i) {
        INFO("tick " << i);
        if (!guided.trusted[i]) CHECK(guided.command(i) == glm::dvec3{0.0});
        if (i < homed_at) CHECK_FALSE(guided.trusted[i]);
      }
      CHECK(rig.loop.arm(1).statistics().latches == 0);
      CHECK(rig.loop.arm(1).statistics().peak_force < 0.2);  // never pulled toward the unhomed (bogus) pose
    }
    SECTION("a reboot of the teacher mid-run") {
      TeacherStudent rig(holding_teacher(), policy);
      rig.teacher_link.inject(LinkFault::reboot, 1000);
      RecordedGuidance guided(rig.loop.arm(0), rig.loop.arm(1), rig.teacher_arm);
      Constant none{{0.0, 0.0, 0.0}};
      rig.loop.run({.max_ticks = 1600}, none, guided);
      CHECK(rig.teacher_arm.boots() == 1);
      const std::size_t n = guided.commands.size() - 1;
      std::size_t untrusted_after_start = 0;
      for (std::size_t i = 0; i < n; ++i) {
        INFO("tick " << i);
        if (!guided.trusted[i]) CHECK(guided.command(i) == glm::dvec3{0.0});
        if (i > 900 && i < 1100) untrusted_after_start += guided.trusted[i] ? 0 : 1;
        if (i > 900 && !guided.homed[i]) CHECK_FALSE(guided.trusted[i]);
      }
      CHECK(untrusted_after_start >= 50);  // resynchronising, then homing
      CHECK(guided.trusted[n - 1] == 1);   // and trusted again
      CHECK(rig.loop.arm(1).statistics().peak_force < 0.2);
      CHECK(rig.loop.arm(1).statistics().latches == 0);
    }
  }
}

TEST_CASE("GuidanceField: a spring toward a trusted leader, nothing from an untrusted one") {
  struct Leader {
    DeviceState s{};
    bool ok{true};
    bool trusted() const noexcept { return ok; }
    const DeviceState& state() const noexcept { return s; }
  } leader;
  leader.s.position = {0.01, 0.0, 0.0};
  GuidanceField<Leader> g{&leader, 100.0, 2.0};
  Probe p;
  p.velocity = {0.0, 0.1, 0.0};
  const glm::dvec3 f = g.force(p);
  CHECK_THAT(f.x, WithinAbs(1.0, 1e-12));
  CHECK_THAT(f.y, WithinAbs(-0.2, 1e-12));
  leader.ok = false;
  CHECK(g.force(p) == glm::dvec3{0.0});
  GuidanceField<Leader> none{};
  CHECK(none.force(p) == glm::dvec3{0.0});
}
