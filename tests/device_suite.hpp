#pragma once
// The device test suite every arm family passes, on its simulated twin or
// stand-in, through AnyDevice and one ServoLoop<AnyDevice, VirtualClock>:
//   - a stop (the tick limit, or request_stop() as Ctrl-C does) leaves the
//     last command zero and the twin's motors applying nothing;
//   - an impossible pose latches: zero force from then on, the latch named;
//   - a lost device latches: run() returns disconnected, zero force;
//   - a restart (run() again after a stop) comes back through the soft
//     start and the slew limit, never a step;
//   - read() and write() through AnyDevice never allocate.
//
// A family plugs in a Twin (see the concept below) and one line:
//   HAPTICFIELD_DEVICE_SUITE(MyTwin, "my family")
// which defines the suite's test cases for it. Include alloc_counter.hpp
// exactly once in the test program (before or after this header).

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/device/any_device.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/servo.hpp"

namespace hapticfield::test::device_suite {

/// A Transport that forwards to another until sever(); from then on every
/// call says the device is gone (an unplugged cable, a dead hub). Twins
/// whose own link cannot be unplugged put it between link and arm.
class SeverableLink final : public Transport {
 public:
  explicit SeverableLink(Transport& inner) : inner_(&inner) {}
  void sever() noexcept { severed_ = true; }
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept override {
    return severed_ ? Status::disconnected : inner_->read(buffer, size, timeout_us);
  }
  Status write(std::span<const std::uint8_t> report) noexcept override {
    return severed_ ? Status::disconnected : inner_->write(report);
  }
  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept override {
    return severed_ ? Status::disconnected : inner_->get_feature(buffer, size);
  }
  Status send_feature(std::span<const std::uint8_t> report) noexcept override {
    return severed_ ? Status::disconnected : inner_->send_feature(report);
  }
  Status set_frame_size(std::size_t n) noexcept override { return inner_->set_frame_size(n); }
  std::size_t drop_pending() noexcept override { return inner_->drop_pending(); }
  [[nodiscard]] std::size_t pending() const noexcept override { return inner_->pending(); }
  [[nodiscard]] std::string_view where() const noexcept override { return inner_->where(); }

 private:
  Transport* inner_;
  bool severed_{false};
};

/// What a family's twin offers the suite. Constructed on the loop's clock
/// (T(VirtualClock&)), it holds the arm and its simulated other end.
template <class T>
concept Twin = std::constructible_from<T, VirtualClock&> && requires(T& t, const T& ct) {
  { t.device() } -> std::same_as<AnyDevice&>;
  /// What the twin's motors apply now, as a magnitude in the family's own
  /// unit (N, A, N m): 0 means no force.
  { ct.effort() } -> std::convertible_to<double>;
  t.lose();             // the link is gone from now on
  t.send_impossible();  // the states from now on (or the next few) are ones the arm cannot be in
};

/// The loop every case runs: simulated time, no real-time scheduling, no
/// recovery (a latch holds).
[[nodiscard]] inline LoopConfig quiet_loop() {
  LoopConfig c;
  c.realtime = RealTime::off;
  c.recover_after = 0.0;
  return c;
}

/// A spring toward where the handle was on the first trusted tick, offset
/// 5 mm along x (k = 100 N/m: 0.5 N there), so every arm pushes.
struct Pull {
  bool anchored{false};
  glm::dvec3 anchor{0.0};
  glm::dvec3 operator()(const TickInput& in) noexcept {
    if (!in.trusted) return glm::dvec3{0.0};
    if (!anchored) {
      anchor = in.probe.position + glm::dvec3{0.005, 0.0, 0.0};
      anchored = true;
    }
    return 100.0 * (anchor - in.probe.position);
  }
};

/// Reads the twin for `ms` more simulated milliseconds without commanding
/// anything (what the arm does after the loop let go of it).
template <Twin T>
void settle(T& twin, VirtualClock& clock, int ms) {
  DeviceState s;
  for (int i = 0; i < ms; ++i) {
    clock.advance(1'000'000);
    (void)twin.device().read(s);
  }
}

template <Twin T>
void stop_gives_zero_force() {
  for (const bool by_request : {false, true}) {
    CAPTURE(by_request);
    VirtualClock clock;
    T twin(clock);
    ServoLoop<AnyDevice, VirtualClock> loop(twin.device(), clock, quiet_loop());
    Pull pull;
    double peak_command = 0.0, peak_effort = 0.0;
    auto tick = [&](const TickInput& in) noexcept {
      peak_command = std::fmax(peak_command, glm::length(loop.last_command()));
      peak_effort = std::fmax(peak_effort, twin.effort());
      if (by_request && in.tick == 1500) loop.request_stop();  // what Ctrl-C does (cli::StopOnSignal)
      return pull(in);
    };
    const StopReason why = loop.run(tick, {.max_ticks = by_request ? 3000u : 1500u});
    CHECK(why == (by_request ? StopReason::requested : StopReason::tick_limit));
    REQUIRE(peak_command > 0.1);  // it pushed [N]
    REQUIRE(peak_effort > 0.0);
    CHECK(loop.last_command() == glm::dvec3{0.0});
    settle(twin, clock, 20);
    CHECK(twin.effort() == 0.0);
  }
}

template <Twin T>
void impossible_pose_latches() {
  VirtualClock clock;
  T twin(clock);
  ServoLoop<AnyDevice, VirtualClock> loop(twin.device(), clock, quiet_loop());
  Pull pull;
  std::vector<double> commands;
  commands.reserve(2100);
  bool sent = false;
  auto tick = [&](const TickInput& in) noexcept {
    commands.push_back(glm::length(loop.last_command()));
    if (in.tick == 1000) {
      twin.send_impossible();
      sent = true;
    }
    return pull(in);
  };
  loop.run(tick, {.max_ticks = 2000});
  REQUIRE(sent);
  REQUIRE(*std::max_element(commands.begin(), commands.begin() + 1000) > 0.1);
  CHECK((loop.safety().latched() & safety_events::impossible_state) != 0);
  CHECK((loop.statistics().last_latch & safety_events::impossible_state) != 0);
  // within a few ticks of the impossible states, and zero from then on
  for (std::size_t i = 1010; i < commands.size(); ++i) {
    CAPTURE(i);
    REQUIRE(commands[i] == 0.0);
  }
  CHECK(loop.last_command() == glm::dvec3{0.0});
  settle(twin, clock, 20);
  CHECK(twin.effort() == 0.0);
}

template <Twin T>
void lost_device_latches() {
  VirtualClock clock;
  T twin(clock);
  ServoLoop<AnyDevice, VirtualClock> loop(twin.device(), clock, quiet_loop());
  Pull pull;
  double peak = 0.0;
  auto tick = [&](const TickInput& in) noexcept {
    peak = std::fmax(peak, glm::length(loop.last_command()));
    if (in.tick == 1000) twin.lose();
    return pull(in);
  };
  const StopReason why = loop.run(tick, {.max_ticks = 3000});
  REQUIRE(peak > 0.1);
  CHECK(why == StopReason::disconnected);
  CHECK(loop.statistics().ticks < 1010);
  CHECK((loop.safety().latched() & safety_events::disconnected) != 0);
  CHECK(loop.last_command() == glm::dvec3{0.0});
}

template <Twin T>
void restart_slews() {
  VirtualClock clock;
  T twin(clock);
  LoopConfig config = quiet_loop();
  ServoLoop<AnyDevice, VirtualClock> loop(twin.device(), clock, config);
  Pull pull;
  loop.run(pull, {.max_ticks = 1500});
  REQUIRE(loop.last_command() == glm::dvec3{0.0});
  settle(twin, clock, 50);
  // Again, after the stop: the soft start and the slew limit bring the force
  // back, never a step.
  // (a new anchor: an arm no hand holds rests where the first pull left it)
  std::vector<glm::dvec3> commands, wanted;
  commands.reserve(1600);
  wanted.reserve(1600);
  Pull again;
  auto tick = [&](const TickInput& in) noexcept {
    commands.push_back(loop.last_command());  // the command of the tick before (the stop's own zero excluded)
    const glm::dvec3 f = again(in);
    wanted.push_back(f);
    return f;
  };
  loop.run(tick, {.max_ticks = 1500});
  const double period = loop.period();
  const double step_limit = config.safety.slew_rate * period + 1e-9;  // [N] per tick
  double peak = 0.0;
  std::size_t first = commands.size();
  for (std::size_t i = 1; i < commands.size(); ++i) {
    CAPTURE(i);
    REQUIRE(glm::length(commands[i] - commands[i - 1]) <= step_limit);
    peak = std::fmax(peak, glm::length(commands[i]));
    if (first == commands.size() && glm::length(commands[i]) > 0.0) first = i;
  }
  REQUIRE(peak > 0.1);  // the force came back
  REQUIRE(first < commands.size());
  // The first force after the restart is a sliver of what the field asked
  // for: the soft start ramps the limit from zero.
  const double asked = glm::length(wanted[first - 1]);
  CHECK(glm::length(commands[first]) <= 0.1 * std::fmax(asked, 0.1));
}

template <Twin T>
void read_and_write_never_allocate() {
  if (!allocations_counted) {
    WARN("allocations are not counted under ThreadSanitizer");
    return;
  }
  VirtualClock clock;
  T twin(clock);
  AnyDevice& device = twin.device();
  DeviceState s;
  (void)device.set_armed(true);
  for (int i = 0; i < 50; ++i) {  // warm up
    clock.advance(1'000'000);
    (void)device.read(s);
    (void)device.write(glm::dvec3{0.1, 0.0, 0.0});
  }
  const long n = count_allocations([&] {
    for (int i = 0; i < 2000; ++i) {
      clock.advance(1'000'000);
      (void)device.read(s);
      (void)device.write(glm::dvec3{0.2 * std::sin(i * 0.01), 0.1, 0.0});
    }
  });
  CHECK(n == 0);
}

}  // namespace hapticfield::test::device_suite

/// The suite's test cases for one twin type, named after `family`.
#define HAPTICFIELD_DEVICE_SUITE(TwinType, family)                                                   \
  TEST_CASE(family ": a stop (tick limit or request) leaves zero force", "[device_suite]") {         \
    hapticfield::test::device_suite::stop_gives_zero_force<TwinType>();                              \
  }                                                                                                  \
  TEST_CASE(family ": an impossible pose latches, zero force from then on", "[device_suite]") {      \
    hapticfield::test::device_suite::impossible_pose_latches<TwinType>();                            \
  }                                                                                                  \
  TEST_CASE(family ": a lost device latches and stops the loop with zero force", "[device_suite]") { \
    hapticfield::test::device_suite::lost_device_latches<TwinType>();                                \
  }                                                                                                  \
  TEST_CASE(family ": a restart comes back through the soft start and the slew", "[device_suite]") { \
    hapticfield::test::device_suite::restart_slews<TwinType>();                                      \
  }                                                                                                  \
  TEST_CASE(family ": read and write through AnyDevice never allocate", "[device_suite]") {          \
    hapticfield::test::device_suite::read_and_write_never_allocate<TwinType>();                      \
  }
