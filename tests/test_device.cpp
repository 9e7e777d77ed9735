// Tests of the device layer: kinematics, the report protocol, the simulated
// arm and transport with fault injection, ForceArm.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "crc16_reference.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/transport.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;

namespace {

constexpr double pi = std::numbers::pi;

void check_vec(const glm::dvec3& a, const glm::dvec3& b, double tol) {
  CHECK_THAT(a.x, WithinAbs(b.x, tol));
  CHECK_THAT(a.y, WithinAbs(b.y, tol));
  CHECK_THAT(a.z, WithinAbs(b.z, tol));
}

std::span<const std::uint8_t> bytes(const char* s) {
  return {reinterpret_cast<const std::uint8_t*>(s), std::strlen(s)};
}

}  // namespace

// ---------------------------------------------------------------- kinematics

TEST_CASE("forward kinematics matches hand-computed poses") {
  const PhantomKinematics k;  // l1 = l2 = 0.133 m
  const double l = 0.133;
  // Home pose: the origin.
  check_vec(k.forward({0, 0, 0}), {0, 0, 0}, 1e-12);
  // Base turned 90 deg: reach l1 along +x, height -l2 -> (l1, 0, -l1).
  check_vec(k.forward({pi / 2, 0, 0}), {l, 0, -l}, 1e-12);
  // Upper arm vertical: reach 0, height l1 - l2 -> (0, l1, -l1).
  check_vec(k.forward({0, pi / 2, 0}), {0, l, -l}, 1e-12);
  // Forearm horizontal: reach l1 + l2 along +z, height 0 -> (0, l2, l2).
  check_vec(k.forward({0, 0, pi / 2}), {0, l, l}, 1e-12);
  // Unequal links, 30/45/60 deg worked by hand:
  KinematicsConfig c;
  c.l1 = 0.2;
  c.l2 = 0.1;
  const PhantomKinematics k2(c);
  const double r = 0.2 * std::cos(pi / 4) + 0.1 * std::sin(pi / 3);  // 0.2280239
  const double h = 0.2 * std::sin(pi / 4) - 0.1 * std::cos(pi / 3);  // 0.0914214
  check_vec(k2.forward({pi / 6, pi / 4, pi / 3}), {r * 0.5, h + 0.1, r * std::sqrt(3.0) / 2 - 0.2}, 1e-12);
  CHECK_THAT(r, WithinAbs(0.2280239, 1e-7));
}

TEST_CASE("the Jacobian agrees with central finite differences") {
  const PhantomKinematics k;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.2);
  for (int trial = 0; trial < 200; ++trial) {
    const glm::dvec3 q{u(rng), u(rng), u(rng)};
    const glm::dmat3 j = k.jacobian(q);
    for (int c = 0; c < 3; ++c) {
      glm::dvec3 dq{0.0};
      dq[c] = 1e-6;
      const glm::dvec3 fd = (k.forward(q + dq) - k.forward(q - dq)) / 2e-6;
      check_vec(j[c], fd, 1e-8);
    }
  }
}

TEST_CASE("tau = J^T F does the same work as the force (virtual work)") {
  const PhantomKinematics k;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const glm::dvec3 q{u(rng), u(rng), u(rng)}, f{u(rng), u(rng), u(rng)}, qd{u(rng), u(rng), u(rng)};
    const glm::dvec3 tau = k.torques(q, f);
    const glm::dvec3 v = k.velocity(q, qd);
    CHECK_THAT(glm::dot(tau, qd), WithinAbs(glm::dot(f, v), 1e-12));
  }
  // At home, a force along +y loads only the shoulder: tau2 = l1 * Fy.
  check_vec(k.torques({0, 0, 0}, {0, 1, 0}), {0, 0.133, 0}, 1e-12);
}

TEST_CASE("encoder counts map to angles and back") {
  const PhantomKinematics k;  // 15000 counts per turn
  CHECK_THAT(k.angles({15000, -3750, 0})[0], WithinAbs(2 * pi, 1e-12));
  CHECK_THAT(k.angles({15000, -3750, 0})[1], WithinAbs(-pi / 2, 1e-12));
  const auto n = k.counts({0.5, -0.25, 1.0});
  const glm::dvec3 back = k.angles(n);
  check_vec(back, {0.5, -0.25, 1.0}, 2 * pi / 15000);
  CHECK(k.counts({std::numeric_limits<double>::quiet_NaN(), 0, 0})[0] == 0);
}

TEST_CASE("kinematics configuration rejects limits that make no sense") {
  const auto expect_bad = [](auto mutate) {
    KinematicsConfig c;
    mutate(c);
    CHECK_THROWS_AS(PhantomKinematics(c), std::invalid_argument);
  };
  expect_bad([](KinematicsConfig& c) { c.l1 = 0; });
  expect_bad([](KinematicsConfig& c) { c.l2 = -0.1; });
  expect_bad([](KinematicsConfig& c) { c.l1 = std::numeric_limits<double>::quiet_NaN(); });
  expect_bad([](KinematicsConfig& c) { c.q_min[0] = 2.0; });
  expect_bad([](KinematicsConfig& c) { c.counts_per_rev[1] = 0; });
  expect_bad([](KinematicsConfig& c) { c.max_torque[2] = std::numeric_limits<double>::infinity(); });
  DeviceInfo info;
  info.max_force = -1;
  CHECK_THROWS_AS(info.validate(), std::invalid_argument);
  info = DeviceInfo{};
  info.nominal_rate = 0;
  CHECK_THROWS_AS(info.validate(), std::invalid_argument);
  info = DeviceInfo{};
  info.continuous_force = 5.0;  // above max_force
  CHECK_THROWS_AS(info.validate(), std::invalid_argument);
}

// ------------------------------------------------------------------ protocol

TEST_CASE("CRC-16/CCITT-FALSE gives the published check value") {
  CHECK(protocol::crc16(bytes("123456789")) == 0x29B1);
  CHECK(protocol::crc16_bitwise(bytes("123456789")) == 0x29B1);
  CHECK(protocol::crc16({}) == 0xFFFF);  // the initial value, nothing shifted in
  std::mt19937 rng(5);
  std::vector<std::uint8_t> data(300);
  for (int trial = 0; trial < 200; ++trial) {
    for (auto& b : data)
      b = static_cast<std::uint8_t>(rng());
    const std::span<const std::uint8_t> part(data.data(), static_cast<std::size_t>(trial));
    CHECK(protocol::crc16(part) == protocol::crc16_bitwise(part));
  }
  static_assert(protocol::crc16(std::span<const std::uint8_t>{}) == 0xFFFF);
}

TEST_CASE("state report: little-endian layout and round trip") {
  protocol::StateReport r;
  r.sequence = 0x1234;
  r.command_echo = 0xBEEF;
  r.timestamp_us = 0x01020304;
  r.encoder = {-1, 70000, -2147483647};
  r.gimbal = {-300, 0, 32767};
  r.status = status_bits::homed | status_bits::estop;
  r.buttons = 0x3;
  r.torque_mnm = {-450, 0, 451};
  std::array<std::uint8_t, 64> b{};
  REQUIRE(protocol::encode(r, b) == protocol::state_size);
  CHECK(b[0] == 0x01);
  CHECK(b[1] == protocol::version);
  CHECK(b[2] == 0x34);  // low byte first
  CHECK(b[3] == 0x12);
  CHECK(b[6] == 0x04);
  CHECK(b[9] == 0x01);
  CHECK(b[10] == 0xFF);  // -1 as int32 little-endian
  CHECK(b[13] == 0xFF);
  const std::uint16_t crc = protocol::crc16(std::span<const std::uint8_t>(b.data(), 38));
  CHECK(b[38] == (crc & 0xFF));
  CHECK(b[39] == (crc >> 8));
  protocol::StateReport d;
  REQUIRE(protocol::decode(std::span<const std::uint8_t>(b.data(), protocol::state_size), d) == Status::ok);
  CHECK(d.sequence == r.sequence);
  CHECK(d.command_echo == r.command_echo);
  CHECK(d.timestamp_us == r.timestamp_us);
  CHECK(d.encoder == r.encoder);
  CHECK(d.gimbal == r.gimbal);
  CHECK(d.status == r.status);
  CHECK(d.buttons == r.buttons);
  CHECK(d.torque_mnm == r.torque_mnm);
}

TEST_CASE("decoders reject short, unknown, bad-version and bad-CRC reports") {
  std::array<std::uint8_t, 64> b{};
  protocol::encode(protocol::StateReport{}, b);
  protocol::StateReport d;
  for (std::size_t n = 0; n < protocol::state_size; ++n)
    CHECK(protocol::decode(std::span<const std::uint8_t>(b.data(), n), d) == Status::short_report);
  // Every single-bit flip is caught (by the CRC or, for the id, as unknown).
  for (std::size_t byte = 0; byte < protocol::state_size; ++byte)
    for (int bit = 0; bit < 8; ++bit) {
      auto c = b;
      c[byte] ^= static_cast<std::uint8_t>(1u << bit);
      const Status s = protocol::decode(std::span<const std::uint8_t>(c.data(), protocol::state_size), d);
      CHECK(s != Status::ok);
    }
  auto unknown = b;
  unknown[0] = 0x7E;
  CHECK(protocol::decode(std::span<const std::uint8_t>(unknown.data(), 40), d) == Status::unknown_report);
  auto old = b;
  old[1] = 9;
  protocol::detail::seal(old, protocol::state_size);
  CHECK(protocol::decode(std::span<const std::uint8_t>(old.data(), 40), d) == Status::bad_version);
  auto bad = b;
  bad[39] ^= 1;
  CHECK(protocol::decode(std::span<const std::uint8_t>(bad.data(), 40), d) == Status::bad_crc);
  // The buffer is exactly the report: decoding must not look beyond it (ASan checks).
  std::vector<std::uint8_t> exact(b.begin(), b.begin() + 40);
  CHECK(protocol::decode(std::span<const std::uint8_t>(exact), d) == Status::ok);
  std::vector<std::uint8_t> one{0x01};
  CHECK(protocol::decode(std::span<const std::uint8_t>(one), d) == Status::short_report);
}

TEST_CASE("a report whose reserved bytes are not zero is refused, even with a valid CRC") {
  // The bytes marked "reserved, 0" make a version-1 report; a report that
  // sets them (and seals a matching CRC) is not one, and would not survive
  // a decode / encode round trip.
  std::array<std::uint8_t, 64> b{};
  protocol::StateReport state;
  protocol::encode(protocol::StateReport{}, b);
  b[protocol::offset::state::reserved] = 2;
  protocol::detail::seal(b, protocol::state_size);
  CHECK(protocol::decode(std::span<const std::uint8_t>(b.data(), protocol::state_size), state) == Status::bad_value);
  protocol::CommandReport command;
  for (std::size_t at = protocol::offset::command::reserved; at < protocol::command_size - 2; ++at) {
    b.fill(0);
    protocol::encode(protocol::CommandReport{}, b);
    b[at] = 0x80;
    protocol::detail::seal(b, protocol::command_size);
    CHECK(protocol::decode(std::span<const std::uint8_t>(b.data(), protocol::command_size), command) ==
          Status::bad_value);
  }
  b.fill(0);
  protocol::ConfigurationReport configuration;
  configuration.watchdog_us = 20000;
  protocol::encode(configuration, b);
  b[protocol::offset::configuration::reserved + 1] = 1;
  protocol::detail::seal(b, protocol::configuration_size);
  CHECK(protocol::decode(std::span<const std::uint8_t>(b.data(), protocol::configuration_size), configuration) ==
        Status::bad_value);
}

TEST_CASE("command, device-info, configuration and control reports round trip") {
  std::array<std::uint8_t, 64> b{};
  protocol::CommandReport c;
  c.sequence = 65535;
  c.flags = protocol::command_flags::arm | protocol::command_flags::home;
  c.torque_mnm = {-32768, 1, 32767};
  REQUIRE(protocol::encode(c, b) == protocol::command_size);
  protocol::CommandReport cd;
  REQUIRE(protocol::decode(std::span<const std::uint8_t>(b.data(), 16), cd) == Status::ok);
  CHECK(cd.sequence == 65535);
  CHECK(cd.flags == c.flags);
  CHECK(cd.torque_mnm == c.torque_mnm);
  b[4] = 0x80;  // undefined flag bit (with a valid CRC)
  protocol::detail::seal(b, protocol::command_size);
  CHECK(protocol::decode(std::span<const std::uint8_t>(b.data(), 16), cd) == Status::bad_value);

  protocol::DeviceInfoReport i;
  i.counts_per_rev = {15000, 16000, 17000};
  i.max_torque_mnm = {450, 460, 470};
  i.l1_um = 133000;
  i.l2_um = 140000;
  i.q_min_mrad = {-1000, -300, -200};
  i.q_max_mrad = {1000, 1300, 1400};
  i.max_force_mn = 3300;
  i.continuous_force_mn = 880;
  i.rate_hz = 1000;
  REQUIRE(protocol::encode(i, b) == protocol::device_info_size);
  protocol::DeviceInfoReport id;
  REQUIRE(protocol::decode(std::span<const std::uint8_t>(b.data(), protocol::device_info_size), id) == Status::ok);
  CHECK(id.counts_per_rev == i.counts_per_rev);
  CHECK(id.max_torque_mnm == i.max_torque_mnm);
  CHECK(id.l2_um == 140000);
  CHECK(id.q_max_mrad == i.q_max_mrad);
  CHECK(id.rate_hz == 1000);
  i.rate_hz = 0;
  protocol::encode(i, b);
  CHECK(protocol::decode(std::span<const std::uint8_t>(b.data(), protocol::device_info_size), id) == Status::bad_value);

  protocol::ConfigurationReport cfg{20000};
  REQUIRE(protocol::encode(cfg, b) == protocol::configuration_size);
  protocol::ConfigurationReport cfgd;
  REQUIRE(protocol::decode(std::span<const std::uint8_t>(b.data(), 8), cfgd) == Status::ok);
  CHECK(cfgd.watchdog_us == 20000);

  REQUIRE(protocol::encode(protocol::ControlOp::clear_fault, b) == protocol::control_size);
  protocol::ControlOp op{};
  REQUIRE(protocol::decode(std::span<const std::uint8_t>(b.data(), 4), op) == Status::ok);
  CHECK(op == protocol::ControlOp::clear_fault);
  b[1] = 9;
  protocol::detail::seal(b, protocol::control_size);
  CHECK(protocol::decode(std::span<const std::uint8_t>(b.data(), 4), op) == Status::bad_value);
  CHECK(protocol::report_size(0x02) == protocol::command_size);
  CHECK(protocol::report_size(0x55) == 0);
}

// ------------------------------------------------------------- simulated arm

namespace {
struct SimRig {
  std::int64_t now{0};
  SimulatedArm arm;
  SimulatedTransport link;
  ForceArm device;
  explicit SimRig(SimulatedArmConfig c = {}) : arm(c), link(arm, [this] { return now; }), device(link) {}
  /// One host tick of 1 ms: advance time, read, write force.
  Status step(glm::dvec3 force, DeviceState& s) {
    now += 1'000'000;
    const Status r = device.read(s);
    device.write(force);
    return r;
  }
};
SimulatedArmConfig still_arm() {
  SimulatedArmConfig c;
  c.hand.holding = false;
  return c;
}
}  // namespace

TEST_CASE("ForceArm takes geometry and limits from the device-info feature report") {
  SimulatedArmConfig c = still_arm();
  c.kinematics.l1 = 0.15;
  c.kinematics.counts_per_rev = {20000, 20000, 4096};
  c.max_force = 2.5;
  c.continuous_force = 0.8;
  SimRig rig(c);
  CHECK_THAT(rig.device.kinematics().config().l1, WithinAbs(0.15, 1e-9));
  CHECK(rig.device.kinematics().config().counts_per_rev[2] == 4096);
  CHECK_THAT(rig.device.info().max_force, WithinAbs(2.5, 1e-9));
  CHECK_THAT(rig.device.info().nominal_rate, WithinAbs(1000.0, 1e-9));
}

TEST_CASE("the simulated arm homes before it arms and reports encoder-derived positions") {
  SimRig rig(still_arm());
  DeviceState s;
  CHECK(rig.step({0, 0, 0}, s) == Status::ok);
  CHECK_FALSE(s.homed());
  CHECK(rig.device.set_armed(true) == Status::not_homed);
  for (int i = 0; i < 5; ++i)
    rig.step({0, 0, 0}, s);
  CHECK_FALSE(rig.arm.armed());  // arm requested but not homed: refused
  rig.device.request_home();
  for (int i = 0; i < 60 && !s.homed(); ++i)
    rig.step({0, 0, 0}, s);
  REQUIRE(s.homed());
  rig.step({0, 0, 0}, s);
  rig.step({0, 0, 0}, s);
  CHECK(s.armed());
  // Position from encoders equals the true position within one count of each joint.
  check_vec(s.position, rig.arm.position(), 0.27 * 2 * pi / 15000 * 3);
}

TEST_CASE("a commanded force reaches the handle as tau = J^T F, quantised and saturated") {
  SimRig rig(still_arm());
  DeviceState s;
  rig.device.request_home();
  rig.device.set_armed(true);
  for (int i = 0; i < 60; ++i)
    rig.step({0, 0, 0}, s);
  REQUIRE(s.armed());
  rig.step({0.0, 1.0, 0.0}, s);
  rig.step({0.0, 1.0, 0.0}, s);
  const glm::dvec3 tau = rig.arm.kinematics().torques(s.joint_angles, {0, 1, 0});
  check_vec(rig.arm.applied_torque(), tau, 0.5e-3 + 1e-12);  // 1 mN m wire unit
  check_vec(s.applied_torque, rig.arm.applied_torque(), 1e-12);
  rig.step({0.0, 1e3, 0.0}, s);  // far beyond the motors
  rig.step({0.0, 1e3, 0.0}, s);
  CHECK(std::abs(rig.arm.applied_torque().y) <= 0.45 + 1e-12);
  rig.step({std::nan(""), 0.0, 0.0}, s);
  rig.step({0.0, 0.0, 0.0}, s);
  CHECK(rig.arm.last_command().torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
}

TEST_CASE("the firmware watchdog zeroes torque and latches until cleared while disarmed") {
  SimRig rig(still_arm());
  DeviceState s;
  rig.device.request_home();
  rig.device.set_armed(true);
  for (int i = 0; i < 60; ++i)
    rig.step({0, 0.5, 0}, s);
  REQUIRE(rig.arm.armed());
  rig.now += 25'000'000;  // 25 ms without a command (watchdog 20 ms)
  rig.device.read(s);
  CHECK_FALSE(rig.arm.armed());
  CHECK(rig.arm.applied_torque() == glm::dvec3{0.0});
  CHECK((s.flags & status_bits::watchdog_tripped) != 0);
  for (int i = 0; i < 5; ++i)
    rig.step({0, 0.5, 0}, s);  // arm requested again: refused while latched
  CHECK_FALSE(rig.arm.armed());
  CHECK(rig.device.clear_fault() == Status::ok);
  for (int i = 0; i < 3; ++i)
    rig.step({0, 0.5, 0}, s);
  CHECK(rig.arm.armed());
  CHECK(rig.arm.send_feature(std::array<std::uint8_t, 4>{0x12, 3, 0, 0}) == Status::bad_crc);
  // Clearing while armed is refused.
  std::array<std::uint8_t, 4> clear{};
  protocol::encode(protocol::ControlOp::clear_fault, clear);
  CHECK(rig.arm.send_feature(clear) == Status::bad_value);
}

TEST_CASE("the watchdog period is configurable through the configuration feature report") {
  SimRig rig(still_arm());
  CHECK(rig.device.configure_watchdog(0.005) == Status::ok);
  CHECK(rig.device.configure_watchdog(0.0) == Status::bad_value);
  CHECK(rig.device.configure_watchdog(std::nan("")) == Status::bad_value);
  std::array<std::uint8_t, 64> b{};
  b[0] = 0x11;
  std::size_t n = 0;
  REQUIRE(rig.link.get_feature(b, n) == Status::ok);
  protocol::ConfigurationReport r;
  REQUIRE(protocol::decode(std::span<const std::uint8_t>(b.data(), n), r) == Status::ok);
  CHECK(r.watchdog_us == 5000);
}

TEST_CASE("injected link faults are detected and reported") {
  SimRig rig(still_arm());
  DeviceState s;
  rig.link.inject(LinkFault::drop, 5, 2);
  rig.link.inject(LinkFault::duplicate, 10);
  rig.link.inject(LinkFault::reorder, 15);
  rig.link.inject(LinkFault::corrupt, 20);
  rig.link.inject(LinkFault::stall, 25, 3);
  rig.link.inject(LinkFault::unplug, 40);
  std::uint32_t seen = 0;
  int no_data = 0;
  Status last = Status::ok;
  for (int i = 0; i < 45; ++i) {
    last = rig.step({0, 0, 0}, s);
    seen |= rig.device.last_events();
    if (last == Status::no_data) ++no_data;
  }
  const LinkCounters& c = rig.device.counters();
  CHECK(c.dropped >= 2);
  CHECK(c.duplicates == 1);
  CHECK(c.reordered == 1);
  CHECK(c.corrupt == 1);
  CHECK((seen & link_events::dropped) != 0);
  CHECK((seen & link_events::corrupt) != 0);
  CHECK(no_data >= 3);  // the stall (and the drop and held report) left ticks without news
  CHECK(last == Status::disconnected);
  CHECK(rig.device.write({0, 0, 0}) == Status::disconnected);
}

TEST_CASE("ForceArm resynchronises after a device restart or a long loss within a few reports") {
  SECTION("restart: the sequence falls back to 1") {
    SimRig rig(still_arm());
    rig.link.inject(LinkFault::reboot, 100);
    DeviceState s;
    std::vector<Status> reads;
    for (int i = 0; i < 110; ++i)
      reads.push_back(rig.step({0, 0, 0}, s));
    // Before the fix every report of the new stream counted as reordered
    // (behind the last sequence) for up to 65535 reports.
    const auto first = std::find(reads.begin(), reads.end(), Status::resync);
    REQUIRE(first != reads.end());
    CHECK(first - reads.begin() == 99);
    CHECK(reads[100] == Status::resync);
    CHECK(reads[101] == Status::ok);  // the third consistent report is taken
    CHECK(rig.device.counters().resyncs == 1);
    CHECK(s.sequence == 3 + 8);
    CHECK_FALSE(s.homed());  // the new stream's state: unhomed after the restart
    CHECK(s.velocity == glm::dvec3{0.0});
  }
  SECTION("a long loss: the sequence jumps ahead by more than max_sequence_gap") {
    SimRig rig(still_arm());
    rig.link.inject(LinkFault::drop, 50, 1500);  // 1.5 s of reports lost, the device counts on
    DeviceState s;
    int resync = 0, ok_after = 0;
    for (int i = 0; i < 1560; ++i) {
      const Status r = rig.step({0, 0, 0}, s);
      if (i >= 1549) {
        resync += r == Status::resync;
        ok_after += r == Status::ok;
      }
    }
    CHECK(resync == 2);
    CHECK(ok_after >= 8);
    CHECK(rig.device.counters().resyncs == 1);
  }
  SECTION("one stale report is not a new stream") {
    SimRig rig(still_arm());
    rig.link.inject(LinkFault::reorder, 30);
    DeviceState s;
    for (int i = 0; i < 60; ++i)
      CHECK(rig.step({0, 0, 0}, s) != Status::resync);
    CHECK(rig.device.counters().reordered == 1);
    CHECK(rig.device.counters().resyncs == 0);
  }
}

namespace {
/// The device-info report of a default SimulatedArm, then the state reports
/// a test puts in `reports` (CRC valid).
class CraftedReports final : public Transport {
 public:
  SimulatedArm arm{};
  std::vector<protocol::StateReport> reports;
  std::size_t next{0};
  Status read(std::span<std::uint8_t> b, std::size_t& n, int) noexcept override {
    if (next == reports.size()) return Status::no_data;
    n = protocol::encode(reports[next++], b);
    return Status::ok;
  }
  Status write(std::span<const std::uint8_t>) noexcept override { return Status::ok; }
  Status get_feature(std::span<std::uint8_t> b, std::size_t& n) noexcept override { return arm.get_feature(b, n); }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::ok; }
};
protocol::StateReport crafted(std::uint16_t sequence, glm::dvec3 q, bool homed) {
  protocol::StateReport r;
  r.sequence = sequence;
  r.timestamp_us = sequence * 1000u;
  r.encoder = PhantomKinematics{}.counts(q);
  r.status = homed ? status_bits::homed : 0;
  return r;
}
}  // namespace

TEST_CASE("ForceArm holds back a state beyond the device's joint limits (with the margin) and says so") {
  CraftedReports link;
  ForceArm device(link);
  const KinematicsConfig& k = device.kinematics().config();  // from the device-info report
  REQUIRE(device.joint_margin() > 0.0);
  const double m = device.joint_margin();
  DeviceState s;
  // Homed: the joint limits the device reports, widened by the margin.
  link.reports = {crafted(1, {0.1, 0.2, 0.3}, true), crafted(2, {k.q_max.x + 0.5 * m, 0.2, 0.3}, true),
                  crafted(3, {0.1, k.q_min.y - 2.0 * m, 0.3}, true)};
  CHECK(device.read(s) == Status::impossible);  // one impossible report among the drained ones is enough
  CHECK(device.counters().impossible == 1);
  CHECK((device.last_events() & link_events::impossible) != 0);
  CHECK_FALSE(s.valid);  // untouched
  // Encoder counts of +-2^31 (valid CRC): thousands of radians.
  protocol::StateReport wild = crafted(4, {0.0, 0.0, 0.0}, true);
  wild.encoder = {INT32_MAX, INT32_MIN, INT32_MAX};
  link.reports.push_back(wild);
  CHECK(device.read(s) == Status::impossible);
  CHECK(device.counters().impossible == 2);
  // Unhomed counts are relative to an unknown pose inside the limits: up to
  // the span of each joint (plus the margin) either way is possible.
  link.reports.push_back(crafted(5, {k.q_min.x - k.q_max.x + 0.5 * m, 0.0, 0.0}, false));
  CHECK(device.read(s) == Status::ok);
  link.reports.push_back(crafted(6, {0.0, k.q_max.y - k.q_min.y + 2.0 * m, 0.0}, false));
  CHECK(device.read(s) == Status::impossible);
  link.reports.push_back(crafted(7, {0.0, 0.3, 0.2}, true));
  CHECK(device.read(s) == Status::ok);
  CHECK(s.joint_angles.y == Approx(0.3).margin(1e-3));
  CHECK(device.counters().impossible == 3);
  CHECK((device.last_events() & link_events::impossible) == 0);
}

TEST_CASE("the wild_counts link fault sends encoders of +-2^31 with a valid CRC; ForceArm refuses them") {
  SimRig rig(still_arm());
  rig.link.inject(LinkFault::wild_counts, 30, 2);
  DeviceState s;
  std::vector<Status> reads;
  for (int i = 0; i < 40; ++i)
    reads.push_back(rig.step({0, 0, 0}, s));
  CHECK(std::count(reads.begin(), reads.end(), Status::impossible) == 2);
  CHECK(rig.device.counters().corrupt == 0);  // the CRC was right
  CHECK(rig.device.counters().impossible == 2);
  CHECK(reads.back() == Status::ok);
}

TEST_CASE("the scripted hand follows its paths") {
  const HandPath line = HandPath::line({0, 0, 0}, {0.1, 0, 0}, 0.05);
  check_vec(line.at(1.0), {0.05, 0, 0}, 1e-12);
  check_vec(line.at(3.0), {0.05, 0, 0}, 1e-12);                              // ping-pong: back at the middle
  const HandPath circle = HandPath::circle({0, 0, 0}, 0.02, 0.02 * pi / 2);  // quarter turn per second
  check_vec(circle.at(1.0), {0, -0.02, 0}, 1e-12);                           // along v = -y
  const HandPath raster = HandPath::raster({0, 0, 0}, 0.04, 0.02, 3, 0.01);
  check_vec(raster.at(0.0), {-0.02, 0.01, 0}, 1e-12);  // first row at v = -height/2 -> y = +0.01
  check_vec(raster.at(4.0), {0.02, 0.01, 0}, 1e-12);   // end of row 0
  check_vec(raster.at(5.0), {0.02, 0.0, 0}, 1e-12);    // stepped to row 1
  check_vec(raster.at(6.0), {0.01, 0.0, 0}, 1e-12);    // row 1 runs back
  HandPath bad = raster;
  bad.rows = 1;
  CHECK_THROWS_AS(bad.validate(), std::invalid_argument);
  bad = line;
  bad.speed = -1;
  CHECK_THROWS_AS(bad.validate(), std::invalid_argument);
}

TEST_CASE("the simulated hand drags the free arm toward its target") {
  SimulatedArmConfig c;
  c.hand.path = HandPath::hold({0.01, 0.0, 0.0});
  SimRig rig(c);
  DeviceState s;
  for (int i = 0; i < 2000; ++i)
    rig.step({0, 0, 0}, s);
  // Equilibrium: hand spring vs Coulomb friction; within a millimetre.
  check_vec(rig.arm.position(), {0.01, 0.0, 0.0}, 1e-3);
  CHECK(glm::length(rig.arm.velocity()) < 1e-3);
}

TEST_CASE("simulated arm configuration rejects values that make no sense") {
  SimulatedArmConfig c;
  c.inertia.x = 0;
  CHECK_THROWS_AS(SimulatedArm(c), std::invalid_argument);
  c = SimulatedArmConfig{};
  c.rate = std::nan("");
  CHECK_THROWS_AS(SimulatedArm(c), std::invalid_argument);
  c = SimulatedArmConfig{};
  c.watchdog = -1;
  CHECK_THROWS_AS(SimulatedArm(c), std::invalid_argument);
  SimulatedArm arm;
  CHECK_THROWS_AS(SimulatedTransport(arm, TimeSource{}), std::invalid_argument);
}

// ------------------------------------------------------- record and replay

TEST_CASE("a recorded session replays the same states at the same times") {
  std::int64_t now = 0;
  SimulatedArmConfig c;
  c.hand.path = HandPath::circle({0.0, 0.0, 0.0}, 0.01, 0.05);
  SimulatedArm arm(c);
  SimulatedTransport link(arm, [&] { return now; });
  RecordingTransport recorder(
      link, [&] { return now; }, 10000);
  ForceArm device(recorder);
  std::vector<DeviceState> original;
  DeviceState s;
  for (int i = 0; i < 300; ++i) {
    now += 1'000'000;
    if (device.read(s) == Status::ok) original.push_back(s);
    device.write({0.0, 0.2, 0.0});
  }
  REQUIRE(original.size() > 250);
  CHECK(recorder.dropped() == 0);
  const std::string path = std::string(HAPTICFIELD_TEST_TMP) + "/session.hfrec";
  std::filesystem::create_directories(HAPTICFIELD_TEST_TMP);
  recorder.save(path);

  std::int64_t replay_now = 5'000'000'000;  // any start time
  ReplayTransport replay(path, [&] { return replay_now; });
  ForceArm again(replay);  // device info comes from the recorded feature reply
  CHECK_THAT(again.kinematics().config().l1, WithinAbs(0.133, 1e-9));
  std::vector<DeviceState> replayed;
  Status r = Status::ok;
  for (int i = 0; i < 400 && r != Status::disconnected; ++i) {
    replay_now += 1'000'000;
    r = again.read(s);
    // The read that meets the end still delivers what arrived before it.
    if (r == Status::ok || (r == Status::disconnected && s.sequence != replayed.back().sequence)) replayed.push_back(s);
  }
  CHECK(r == Status::disconnected);  // the session ended
  REQUIRE(replayed.size() == original.size());
  for (std::size_t i = 0; i < original.size(); ++i) {
    CHECK(replayed[i].sequence == original[i].sequence);
    CHECK(replayed[i].position == original[i].position);
  }
}

TEST_CASE("replay rejects files that are not recordings") {
  const auto now = [] { return std::int64_t{0}; };
  CHECK_THROWS_AS(ReplayTransport("/nonexistent/session.hfrec", now), std::runtime_error);
  const std::string path = std::string(HAPTICFIELD_TEST_TMP) + "/garbage.hfrec";
  std::filesystem::create_directories(HAPTICFIELD_TEST_TMP);
  {
    std::ofstream f(path, std::ios::binary);
    f << "not a recording at all";
  }
  CHECK_THROWS_AS(ReplayTransport(path, now), std::runtime_error);
  {
    std::ofstream f(path, std::ios::binary);
    f << "hapticfield-recording 1\n" << 'I' << "\x01\x02";  // truncated record
  }
  CHECK_THROWS_AS(ReplayTransport(path, now), std::runtime_error);
}

TEST_CASE("ForceArm rejects bad options and a device that does not describe itself") {
  std::int64_t now = 0;
  SimulatedArm arm(still_arm());
  SimulatedTransport link(arm, [&] { return now; });
  ForceArmConfig o;
  o.velocity_cutoff = std::nan("");
  CHECK_THROWS_AS(ForceArm(link, o), std::invalid_argument);
  o = ForceArmConfig{};
  o.query_device = false;  // else the device's own unit replaces it
  o.torque_unit = 0.0;
  CHECK_THROWS_AS(ForceArm(link, o), std::invalid_argument);
  o = ForceArmConfig{};
  o.query_device = false;
  o.info.max_force = -3.0;
  CHECK_THROWS_AS(ForceArm(link, o), std::invalid_argument);
  // A recording without the device-info reply: the error names the report.
  const std::string path = std::string(HAPTICFIELD_TEST_TMP) + "/no_info.hfrec";
  std::filesystem::create_directories(HAPTICFIELD_TEST_TMP);
  {
    std::ofstream f(path, std::ios::binary);
    f << "hapticfield-recording 1\n";
  }
  ReplayTransport empty(path, [] { return std::int64_t{0}; });
  try {
    ForceArm device(empty);
    FAIL("built a ForceArm without device info");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("device-info feature report") != std::string::npos);
  }
}
