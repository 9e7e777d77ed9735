// Tests of the reference firmware core on its own, and of the host
// (ForceArm, ServoLoop) driving it through SimulatedArm (the core on the
// simulated mechanics) with the firmware's own 5 ms watchdog: the watchdog
// and unplug faults the firmware handles. The other link faults, e-stop,
// reboot and the allocation test run on the same twin in test_servo.cpp.
#include <catch2/catch.hpp>

#include <array>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "alloc_counter.hpp"
#include "arm_rig.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/firmware/board.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"
#include "test_fields.hpp"

using namespace hapticfield;
using firmware::BoardInputs;
using firmware::FirmwareConfig;
using firmware::FirmwareCore;
using testing::Constant;

namespace {

std::vector<std::uint8_t> command(std::uint16_t seq, std::uint8_t flags, std::array<std::int16_t, 3> torque) {
  protocol::CommandReport c;
  c.sequence = seq;
  c.flags = flags;
  c.torque_mnm = torque;
  std::vector<std::uint8_t> b(protocol::command_size);
  protocol::encode(c, b);
  return b;
}

std::vector<std::uint8_t> control(protocol::ControlOp op) {
  std::vector<std::uint8_t> b(protocol::control_size);
  protocol::encode(op, b);
  return b;
}

protocol::StateReport decoded(const FirmwareCore& core) {
  protocol::StateReport r;
  REQUIRE(protocol::decode(core.report(), r) == Status::ok);
  return r;
}

/// Drives a core directly: one tick per ms, a command before each tick.
struct Bench {
  FirmwareCore core;
  BoardInputs in;
  std::uint16_t seq{0};
  explicit Bench(FirmwareConfig c = {}) : core(c) { in.encoder = {1000, -2000, 300}; }
  void tick(std::uint32_t us = 1000) {
    in.now_us += us;
    core.tick(in);
  }
  void send(std::uint8_t flags, std::array<std::int16_t, 3> torque = {}) {
    core.receive(command(++seq, flags, torque));
  }
  void home_and_arm() {
    send(protocol::command_flags::home);
    for (int i = 0; i < 52; ++i)
      tick();
    REQUIRE(core.homed());
    send(protocol::command_flags::arm);
    tick();
    REQUIRE(core.armed());
  }
};

constexpr std::uint8_t arm_flag = protocol::command_flags::arm;

}  // namespace

// --------------------------------------------------------- the core alone

TEST_CASE("firmware: homing before arming; encoders are zero at the home pose once homed") {
  Bench b;
  b.tick();
  protocol::StateReport r = decoded(b.core);
  CHECK(r.sequence == 1);
  CHECK(r.encoder == std::array<std::int32_t, 3>{1000, -2000, 300});  // raw until homed
  b.send(arm_flag, {100, 0, 0});
  b.tick();
  CHECK_FALSE(b.core.armed());  // not homed: arming refused
  CHECK(b.core.set_feature(control(protocol::ControlOp::arm)) == Status::not_homed);
  CHECK(b.core.outputs().torque == std::array<std::int16_t, 3>{0, 0, 0});
  b.in.at_home = false;  // homing waits for the arm to rest at home
  CHECK(b.core.set_feature(control(protocol::ControlOp::home)) == Status::ok);
  for (int i = 0; i < 100; ++i)
    b.tick();
  CHECK_FALSE(b.core.homed());
  b.in.at_home = true;
  for (int i = 0; i < 50; ++i)
    b.tick();
  CHECK_FALSE(b.core.homed());
  b.tick();
  CHECK(b.core.homed());
  r = decoded(b.core);
  CHECK(r.encoder == std::array<std::int32_t, 3>{0, 0, 0});
  b.in.encoder[1] += 25;
  b.tick();
  CHECK(decoded(b.core).encoder[1] == 25);
  CHECK(decoded(b.core).sequence == 154);  // 1 + 1 + 100 + 50 + 1 + 1 ticks
}

TEST_CASE("firmware: the watchdog disarms and latches after its period; clear_fault only while disarmed") {
  FirmwareConfig c;
  c.watchdog_us = 5000;
  Bench b(c);
  b.home_and_arm();
  b.send(arm_flag, {200, 0, 0});
  b.tick();
  CHECK(b.core.outputs().torque[0] == 200);
  CHECK(b.core.outputs().enable);
  for (int i = 0; i < 5; ++i)
    b.tick();  // 5 ms since the last command: still within the period
  CHECK(b.core.armed());
  b.tick();  // 6 ms: tripped
  CHECK_FALSE(b.core.armed());
  CHECK_FALSE(b.core.outputs().enable);
  CHECK(b.core.outputs().torque == std::array<std::int16_t, 3>{0, 0, 0});
  CHECK((decoded(b.core).status & status_bits::watchdog_tripped) != 0);
  CHECK(b.core.counters().watchdog_trips == 1);
  b.send(arm_flag, {200, 0, 0});  // arming again is refused while latched
  b.tick();
  CHECK_FALSE(b.core.armed());
  CHECK(b.core.set_feature(control(protocol::ControlOp::arm)) == Status::fault);
  b.send(0);
  b.tick();
  CHECK(b.core.set_feature(control(protocol::ControlOp::clear_fault)) == Status::ok);
  b.send(arm_flag, {200, 0, 0});
  b.tick();
  CHECK(b.core.armed());
  CHECK(b.core.set_feature(control(protocol::ControlOp::clear_fault)) == Status::bad_value);  // armed: refused
  // The period is configurable (and a period shorter than a tick is refused).
  protocol::ConfigurationReport cfg{2000};
  std::array<std::uint8_t, protocol::configuration_size> bytes{};
  protocol::encode(cfg, bytes);
  CHECK(b.core.set_feature(bytes) == Status::ok);
  CHECK(b.core.watchdog_us() == 2000);
  for (int i = 0; i < 3; ++i)
    b.tick();
  CHECK_FALSE(b.core.armed());
  cfg.watchdog_us = 500;
  protocol::encode(cfg, bytes);
  CHECK(b.core.set_feature(bytes) == Status::bad_value);
  CHECK(b.core.watchdog_us() == 2000);
}

TEST_CASE("firmware: torque saturation and the current limit; the report returns what was applied") {
  FirmwareConfig c;
  c.max_torque_mnm = {450, 450, 450};
  c.torque_constant = {100, 50, 100};     // [uN m/mA]
  c.max_current_ma = {4500, 4500, 1000};  // joint 3: 1 A -> 100 mN m
  Bench b(c);
  b.home_and_arm();
  b.send(arm_flag, {-900, 300, 250});
  b.tick();
  const auto& out = b.core.outputs();
  CHECK(out.torque[0] == -450);       // saturation
  CHECK(out.current_ma[0] == -4500);  // 450 mN m / 0.1 N m/A
  CHECK(out.torque[1] == 225);        // 300 -> 6 A > 4.5 A: 4.5 A x 0.05 N m/A
  CHECK(out.current_ma[1] == 4500);
  CHECK(out.torque[2] == 100);
  CHECK(out.current_ma[2] == 1000);
  CHECK(decoded(b.core).torque_mnm == std::array<std::int16_t, 3>{-450, 225, 100});
  b.send(arm_flag, {-32768, 32767, 0});  // extremes do not overflow
  b.tick();
  CHECK(b.core.outputs().torque[0] == -450);
}

TEST_CASE("firmware: driver faults latch, e-stop holds; both forbid torque") {
  Bench b;
  b.home_and_arm();
  b.in.over_current = true;
  b.send(arm_flag, {100, 0, 0});
  b.tick();
  b.in.over_current = false;
  CHECK_FALSE(b.core.armed());
  CHECK((b.core.faults() & status_bits::over_current) != 0);
  b.send(arm_flag, {100, 0, 0});
  b.tick();
  CHECK(b.core.outputs().torque[0] == 0);
  b.send(0);
  b.tick();
  REQUIRE(b.core.set_feature(control(protocol::ControlOp::clear_fault)) == Status::ok);
  b.in.estop = true;
  b.send(arm_flag, {100, 0, 0});
  b.tick();
  CHECK_FALSE(b.core.armed());
  CHECK((decoded(b.core).status & status_bits::estop) != 0);
  b.in.estop = false;  // released: not latched
  b.send(arm_flag, {100, 0, 0});
  b.tick();
  CHECK(b.core.armed());
  CHECK(b.core.outputs().torque[0] == 100);
}

TEST_CASE("firmware: bad CRC, short, unknown and bad-version reports are ignored and counted") {
  Bench b;
  b.home_and_arm();
  auto good = command(++b.seq, arm_flag, {100, 0, 0});
  auto bad_crc = good;
  bad_crc[5] ^= 1;
  b.core.receive(bad_crc);
  b.core.receive(std::span<const std::uint8_t>(good.data(), 7));
  const std::array<std::uint8_t, 3> unknown{0x7E, 1, 2};
  b.core.receive(unknown);
  auto bad_version = good;
  bad_version[1] = 9;
  protocol::detail::seal(bad_version, protocol::command_size);
  b.core.receive(bad_version);
  auto bad_flags = command(++b.seq, 0x80, {});
  b.core.receive(bad_flags);
  b.core.receive({});
  CHECK(b.core.counters().bad_crc == 1);
  CHECK(b.core.counters().short_report == 2);
  CHECK(b.core.counters().unknown == 1);
  CHECK(b.core.counters().bad_version == 1);
  CHECK(b.core.counters().bad_value == 1);
  // None of them fed the watchdog: 6 ms later it trips.
  for (int i = 0; i < 7; ++i)
    b.tick();
  CHECK_FALSE(b.core.armed());
  std::size_t n = 0;
  std::array<std::uint8_t, 64> out{};
  CHECK(b.core.get_feature(0x55, out, n) == Status::unknown_report);
  CHECK(b.core.get_feature(0x10, std::span<std::uint8_t>(out.data(), 10), n) == Status::short_report);
}

TEST_CASE("firmware: a configuration that makes no sense never homes, arms or describes itself") {
  FirmwareConfig c;
  c.torque_constant[1] = 0;
  FirmwareCore core(c);
  REQUIRE(core.config_error() != nullptr);
  CHECK(std::string(core.config_error()).find("torque_constant") != std::string::npos);
  CHECK(core.set_feature(control(protocol::ControlOp::home)) == Status::ok);
  BoardInputs in;
  for (int i = 0; i < 100; ++i) {
    in.now_us += 1000;
    core.tick(in);
  }
  CHECK_FALSE(core.homed());
  std::array<std::uint8_t, 64> out{};
  std::size_t n = 0;
  CHECK(core.get_feature(0x10, out, n) == Status::bad_value);
  CHECK_THROWS_AS(SimulatedArm({}, c), std::invalid_argument);
  SimulatedArmConfig a;
  CHECK_THROWS_AS(firmware_config_for(a, 100), std::invalid_argument);  // watchdog below one period
}

TEST_CASE("firmware: stream frames carry commands and in-band feature requests and replies") {
  FirmwareCore core;
  firmware::StreamPort<256> port;
  std::vector<std::vector<std::uint8_t>> sent;
  auto sink = [&](std::span<const std::uint8_t> b) { sent.emplace_back(b.begin(), b.end()); };
  std::array<std::uint8_t, protocol::feature_request_size> req{};
  protocol::encode_feature_request(0x10, req);
  const std::array<std::uint8_t, 5> garbage{0xFF, 0x01, 0x00, 0x13, 0x42};
  port.feed(garbage);
  port.feed(std::span<const std::uint8_t>(req.data(), 2));  // a partial frame waits
  port.service(core, sink);
  CHECK(sent.empty());
  port.feed(std::span<const std::uint8_t>(req.data() + 2, 2));
  port.service(core, sink);
  REQUIRE(sent.size() == 1);
  protocol::DeviceInfoReport info;
  CHECK(protocol::decode(sent[0], info) == Status::ok);
  CHECK(info.rate_hz == 1000);
  port.feed(control(protocol::ControlOp::arm));
  port.service(core, sink);
  REQUIRE(sent.size() == 2);
  protocol::FeatureReply reply;
  REQUIRE(protocol::decode(sent[1], reply) == Status::ok);
  CHECK(reply.report == 0x12);
  CHECK(reply.status == Status::not_homed);
  CHECK(port.counters().skipped == garbage.size());
}

TEST_CASE("firmware: a tick does not allocate") {
  if (!test::allocations_counted) return;
  Bench b;
  b.home_and_arm();
  const auto cmd = command(1000, arm_flag, {10, 20, 30});
  const long n = test::count_allocations([&] {
    for (int i = 0; i < 1000; ++i) {
      b.core.receive(cmd);
      b.tick();
    }
  });
  CHECK(n == 0);
}

// ------------------------------------------ the host over the firmware twin

namespace {

SimulatedArmConfig free_arm() {
  return testing::ArmRig::free_arm();
}

/// ForceArm -> SimulatedTransport -> FirmwareCore on ArmPlant, ServoLoop on
/// one virtual clock, with the firmware's own 5 ms watchdog.
struct Rig : testing::ArmRig {
  explicit Rig(const SimulatedArmConfig& a = free_arm()) : ArmRig(a, 5000) {}
};

}  // namespace

TEST_CASE("loopback: ForceArm homes, arms and pushes the mechanics through the firmware core") {
  Rig rig;
  CHECK(rig.device.info().nominal_rate == 1000.0);
  CHECK(rig.device.kinematics().config().counts_per_rev[0] == 15000);
  Constant field{{0.0, 1.0, 0.0}};
  CHECK(rig.loop.run(field, {.max_ticks = 1000}) == StopReason::tick_limit);
  CHECK(rig.arm.core().homed());
  CHECK_THAT(rig.loop.statistics().peak_force, Catch::Matchers::WithinAbs(1.0, 1e-12));
  CHECK(rig.arm.core().counters().commands >= 999);
  CHECK(rig.arm.core().counters().bad_crc == 0);
  CHECK(rig.arm.plant().q().y > 0.05);  // +y at home loads the shoulder: it lifted
  CHECK_FALSE(rig.arm.core().armed());  // disarmed on exit
}

TEST_CASE("loopback: a stall trips the firmware watchdog, which latches until cleared while disarmed") {
  Rig rig;
  rig.link.inject(LinkFault::stall, 500, 20);  // 20 ms: longer than the 5 ms firmware watchdog
  Constant field{{0.0, 0.8, 0.0}};
  rig.loop.run(field, {.max_ticks = 800});
  CHECK((rig.arm.core().faults() & status_bits::watchdog_tripped) != 0);
  CHECK(rig.arm.core().counters().watchdog_trips == 1);
  CHECK(rig.arm.applied_torque() == glm::dvec3{0.0});
  CHECK(rig.arm.core().last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
  // The host clears it between runs (the firmware is disarmed), then runs again.
  rig.loop.clear_fault();
  CHECK(rig.loop.run(field, {.max_ticks = 600}) == StopReason::tick_limit);
  CHECK((rig.arm.core().faults() & status_bits::watchdog_tripped) == 0);
  CHECK(rig.loop.statistics().peak_force > 0.7);
}

TEST_CASE("loopback: unplug stops the loop with zero force") {
  Rig rig;
  rig.link.inject(LinkFault::unplug, 500);
  Constant field{{0.0, 0.8, 0.0}};
  CHECK(rig.loop.run(field, {.max_ticks = 800}) == StopReason::disconnected);
  CHECK((rig.loop.safety().latched() & safety_events::disconnected) != 0);
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});
  // Nothing reaches the firmware any more: its watchdog zeroes the motors.
  for (int i = 0; i < 10; ++i) {
    rig.clock.advance(1'000'000);
    rig.link.advance();
  }
  CHECK(rig.arm.applied_torque() == glm::dvec3{0.0});
}

TEST_CASE("the twin's old names: FirmwareArm (5 ms watchdog, step()) and FirmwareLoopback still work") {
  static_assert(std::is_same_v<FirmwareLoopback, SimulatedTransport>);
  static_assert(std::is_base_of_v<SimulatedArm, FirmwareArm>);
  VirtualClock clock;
  FirmwareArm arm(free_arm());
  FirmwareLoopback link(arm, [&] { return clock.now(); });
  CHECK(arm.core().watchdog_us() == 5000);
  CHECK(SimulatedArm(free_arm()).core().watchdog_us() == 20000);  // SimulatedArmConfig::watchdog
  arm.step();
  CHECK(arm.ticks() == 1);
  clock.advance(5'000'000);
  link.advance();  // ticks at 1.5, 2.5, 3.5 and 4.5 ms
  CHECK(arm.ticks() == 5);
}
