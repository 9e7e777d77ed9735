// Tests of the WoodenHaptics family: wire codecs against the byte vectors
// of arm-protocols.md section 3 and hand-assembled reports, the serial woody
// kinematics against finite differences and hand-checked poses, and WoodyArm
// in a ServoLoop against the simulated arm for every generation.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/arms/woody/simulated_woody.hpp"
#include "hapticfield/arms/woody/woody_arm.hpp"
#include "hapticfield/arms/woody/woody_codec.hpp"
#include "hapticfield/arms/woody/woody_kinematics.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/servo.hpp"
#include "test_fields.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;
using testing::Constant;
using testing::Wall;
using woody::Generation;

namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes bytes_of(std::span<const std::uint8_t> s) {
  return Bytes(s.begin(), s.end());
}
std::span<const std::uint8_t> text(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

SimulatedWoodyConfig sim_config(Generation g) {
  SimulatedWoodyConfig c;
  c.generation = g;
  c.encoder_sign = woody_encoder_sign(g);
  return c;
}

/// Simulated woody arm, its link, WoodyArm and the loop on one virtual clock.
struct Rig {
  VirtualClock clock;
  SimulatedWoody arm;
  SimulatedWoodyTransport link;
  WoodyArm device;
  ServoLoop<WoodyArm, VirtualClock> loop;
  static WoodyArmConfig host(Generation g, VirtualClock& clock) {
    WoodyArmConfig c = WoodyArmConfig::defaults(g);
    c.now = [&clock] { return clock.now(); };
    return c;
  }
  static LoopConfig quiet(LoopConfig c) {
    c.realtime = RealTime::off;
    return c;
  }
  explicit Rig(SimulatedWoodyConfig a, LoopConfig c = {})
      : arm(a),
        link(arm, [this] { return clock.now(); }),
        device(link, host(a.generation, clock)),
        loop(device, clock, quiet(c)) {}
};

/// A line Transport over byte queues, for driving WoodyArm by hand.
class ScriptTransport final : public Transport {
 public:
  std::deque<Bytes> incoming;  ///< what read() returns, one element per call
  std::vector<Bytes> written;
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int) noexcept override {
    if (incoming.empty()) return Status::no_data;
    const Bytes b = incoming.front();
    incoming.pop_front();
    if (b.size() > buffer.size()) return Status::short_report;
    std::copy(b.begin(), b.end(), buffer.begin());
    size = b.size();
    return Status::ok;
  }
  Status write(std::span<const std::uint8_t> report) noexcept override {
    written.emplace_back(report.begin(), report.end());
    return Status::ok;
  }
  Status get_feature(std::span<std::uint8_t>, std::size_t&) noexcept override { return Status::unsupported; }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::unsupported; }
};

std::int16_t le16(const Bytes& b, std::size_t at) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(b[at] | (b[at + 1] << 8)));
}

}  // namespace

// ------------------------------------------------------------------- codecs

TEST_CASE("woody codecs reproduce the byte vectors of arm-protocols.md section 3") {
  std::array<std::uint8_t, 128> out{};
  SECTION("1: P1 IN") {
    const Bytes v{0xE8, 0x03, 0x30, 0xF8, 0x2C, 0x01, 0x07, 0x00};
    CHECK(bytes_of({out.data(), woody::encode(woody::P1In{{1000, -2000, 300}, 7}, out)}) == v);
    woody::P1In r;
    REQUIRE(woody::decode(v, r) == Status::ok);
    CHECK(r.encoder == std::array<std::int16_t, 3>{1000, -2000, 300});
    CHECK(r.debug == 7);
  }
  SECTION("2: P1 OUT") {
    const Bytes v{0x00, 0x64, 0x00, 0x38, 0xFF, 0x32, 0x00, 0x00, 0x00};
    CHECK(bytes_of({out.data(), woody::encode(woody::P1Out{{100, -200, 50}, 0}, out)}) == v);
    woody::P1Out m;
    REQUIRE(woody::decode(v, m) == Status::ok);
    CHECK(m.milliamps == std::array<std::int16_t, 3>{100, -200, 50});
  }
  SECTION("3: P2 IN") {
    const Bytes v{0xE8, 0x03, 0x30, 0xF8, 0x2C, 0x01, 0, 0, 0, 0, 0, 0, 0x01, 0x00};
    CHECK(bytes_of({out.data(), woody::encode(woody::P2In{{1000, -2000, 300, 0, 0, 0}, 1}, out)}) == v);
    woody::P2In r;
    REQUIRE(woody::decode(v, r) == Status::ok);
    CHECK(r.encoder == std::array<std::int16_t, 6>{1000, -2000, 300, 0, 0, 0});
    CHECK(r.info == 1);
  }
  SECTION("4: P2 OUT") {
    const Bytes v{0x00, 0x64, 0x00, 0x38, 0xFF, 0x32, 0x00, 0, 0, 0, 0, 0, 0, 0, 0};
    CHECK(bytes_of({out.data(), woody::encode(woody::P2Out{{100, -200, 50}, 0, {0, 0, 0}}, out)}) == v);
  }
  SECTION("5: P2 calibrate") {
    const Bytes v{0x00, 0x00, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x01, 0x00, 0x87, 0x20, 0x52, 0xD5, 0x04, 0x6A};
    const woody::P2Out m{{0, 30, 0}, woody::p2_command::calibrate, {8327, -10926, 27140}};
    CHECK(bytes_of({out.data(), woody::encode(m, out)}) == v);
    woody::P2Out back;
    REQUIRE(woody::decode(v, back) == Status::ok);
    CHECK(back.command == 1);
    CHECK(back.attr == std::array<std::int16_t, 3>{8327, -10926, 27140});
    CHECK(back.milliamps == std::array<std::int16_t, 3>{0, 30, 0});
  }
  SECTION("6: P4 both ways") {
    const Bytes v{0x5B, 0x31, 0x30, 0x30, 0x2C, 0x2D, 0x32, 0x30, 0x30, 0x2C, 0x35, 0x30, 0x5D, 0x0A, 0x00, 0x00};
    CHECK(bytes_of({out.data(), woody::encode_p4_command({100, -200, 50}, out)}) == v);
    std::array<std::int32_t, 3> ma{};
    CHECK(woody::parse_p4_command(std::span<const std::uint8_t>(v).first(13), ma) == 0);
    CHECK(ma == std::array<std::int32_t, 3>{100, -200, 50});
    woody::P4Reply r;
    REQUIRE(woody::decode(text("[3,1000,-2000,300,0,0,0,0]\n"), r) == Status::ok);
    CHECK(r.model == woody::p4_model::woody);
    CHECK(r.encoder == std::array<std::int32_t, 6>{1000, -2000, 300, 0, 0, 0});
    CHECK(r.error == 0);
    const std::size_t n = woody::encode(r, out);
    CHECK(std::string(reinterpret_cast<const char*>(out.data()), n) == "[3,1000,-2000,300,0,0,0,0]\n");
  }
}

TEST_CASE("woody codecs: hand-assembled reports, round trips and rejects") {
  std::array<std::uint8_t, 128> out{};
  // P2 IN with every field distinct, assembled byte by byte (little-endian).
  const Bytes p2{0x01, 0x00, 0xFF, 0xFF, 0x00, 0x80, 0xFF, 0x7F, 0x34, 0x12, 0x10, 0x27, 0x00, 0x00};
  woody::P2In r;
  REQUIRE(woody::decode(p2, r) == Status::ok);
  CHECK(r.encoder == std::array<std::int16_t, 6>{1, -1, -32768, 32767, 0x1234, 10000});
  CHECK(r.info == 0);
  CHECK(bytes_of({out.data(), woody::encode(r, out)}) == p2);
  // Sizes are exact; the host's OUT must lead with report id 0.
  woody::P1In p1;
  CHECK(woody::decode(Bytes(7, 0), p1) == Status::short_report);
  CHECK(woody::decode(Bytes(9, 0), p1) == Status::short_report);
  woody::P1Out o1;
  CHECK(woody::decode(Bytes{0x01, 0, 0, 0, 0, 0, 0, 0, 0}, o1) == Status::unknown_report);
  woody::P2In i2;
  CHECK(woody::decode(Bytes(13, 0), i2) == Status::short_report);
  CHECK(woody::encode(woody::P2Out{}, std::span<std::uint8_t>(out.data(), 14)) == 0);

  // Seeded round trips through every encoder/decoder pair.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> d(-32768, 32767);
  for (int k = 0; k < 2000; ++k) {
    woody::P2Out m{
        {static_cast<std::int16_t>(d(rng)), static_cast<std::int16_t>(d(rng)), static_cast<std::int16_t>(d(rng))},
        static_cast<std::int16_t>(d(rng)),
        {static_cast<std::int16_t>(d(rng)), static_cast<std::int16_t>(d(rng)), static_cast<std::int16_t>(d(rng))}};
    woody::P2Out b;
    REQUIRE(woody::decode(std::span<const std::uint8_t>(out.data(), woody::encode(m, out)), b) == Status::ok);
    REQUIRE((b.milliamps == m.milliamps && b.command == m.command && b.attr == m.attr));
    const std::array<std::int16_t, 3> ma{m.milliamps};
    const std::size_t n = woody::encode_p4_command(ma, out);
    REQUIRE(n >= woody::p4_min_command);
    std::size_t line = 0;
    while (out[line] != '\n')
      ++line;
    std::array<std::int32_t, 3> parsed{};
    REQUIRE(woody::parse_p4_command(std::span<const std::uint8_t>(out.data(), line), parsed) == 0);
    REQUIRE(parsed == std::array<std::int32_t, 3>{ma[0], ma[1], ma[2]});
  }
}

TEST_CASE("P4 replies are parsed strictly") {
  woody::P4Reply r;
  CHECK(woody::decode(text("[3,1,2,3,4,5,6,0]\r\n"), r) == Status::ok);
  CHECK(woody::decode(text("[1,-5,0,0,0,30,0,1024]"), r) == Status::ok);
  CHECK(r.error == woody::p4_error::parse_error);
  CHECK(r.model == woody::p4_model::polhem_2022);
  CHECK(woody::decode(text("\n"), r) == Status::short_report);
  for (const char* bad : {"[3,1,2,3,4,5,6]\n", "[3,1,2,3,4,5,6,0,9]\n", "[3, 1,2,3,4,5,6,0]\n", "3,1,2,3,4,5,6,0]\n",
                          "[3,1,2,3,4,5,6,0\n", "[3,1,2,3,4,5,6,0]x\n", "[3,1,,3,4,5,6,0]\n", "[3,+1,2,3,4,5,6,0]\n",
                          "[3,1,2,3,4,5,6,-1]\n", "[-3,1,2,3,4,5,6,0]\n", "[3,99999999999,2,3,4,5,6,0]\n",
                          "[3,1a,2,3,4,5,6,0]\n", "[]\n", "[3,1,2,3,4,5,6,0]\n\n"}) {
    INFO(bad);
    CHECK(woody::decode(text(bad), r) == Status::bad_value);
  }
}

TEST_CASE("the simulated P4 firmware sets the named error bits for malformed PC frames") {
  std::array<std::int32_t, 3> ma{7, 7, 7};
  CHECK(woody::parse_p4_command(text("[1,2,3]"), ma) == 0);
  CHECK(ma == std::array<std::int32_t, 3>{1, 2, 3});
  ma = {7, 7, 7};
  CHECK(woody::parse_p4_command(text("]1,2,3["), ma) == woody::p4_error::close_before_open);
  CHECK(woody::parse_p4_command(text("[1,2]"), ma) == woody::p4_error::comma_count);
  CHECK(woody::parse_p4_command(text("[1,2,3,4]"), ma) == woody::p4_error::comma_count);
  CHECK(woody::parse_p4_command(text("[1,2,3]x"), ma) == woody::p4_error::trailing_characters);
  CHECK(woody::parse_p4_command(text("[1,a,3]"), ma) == woody::p4_error::parse_error);
  CHECK(woody::parse_p4_command(text("[1,2,3"), ma) == woody::p4_error::parse_error);
  CHECK(woody::parse_p4_command(text(std::string(70, '1')), ma) == woody::p4_error::buffer_full);
  CHECK(ma == std::array<std::int32_t, 3>{7, 7, 7});  // untouched on error
}

// -------------------------------------------------------------- kinematics

TEST_CASE("woody kinematics: hand-checked poses and the frame mapping") {
  const WoodyKinematics k(woody_presets::woody_v2015());
  // All angles zero: reach 0, height Ln + Lb - Lc; minus the origin (0.220, 0, 0.080).
  glm::dvec3 s = k.forward_source({0.0, 0.0, 0.0});
  CHECK_THAT(s.x, WithinAbs(-0.220, 1e-12));
  CHECK_THAT(s.y, WithinAbs(0.0, 1e-12));
  CHECK_THAT(s.z, WithinAbs(0.080 + 0.205 - 0.245 - 0.080, 1e-12));
  // tB = 90 deg: the first link points toward the user (+x_S), reach Lb.
  s = k.forward_source({0.0, std::numbers::pi / 2, 0.0});
  CHECK_THAT(s.x, WithinAbs(0.205 - 0.220, 1e-12));
  CHECK_THAT(s.z, WithinAbs(0.080 - 0.245 - 0.080, 1e-12));
  // tA = 90 deg, tB = tC = 90 deg: reach Lb + Lc turned to the user's right (+y_S).
  s = k.forward_source({std::numbers::pi / 2, std::numbers::pi / 2, std::numbers::pi / 2});
  CHECK_THAT(s.x, WithinAbs(-0.220, 1e-12));
  CHECK_THAT(s.y, WithinAbs(0.450, 1e-12));
  CHECK_THAT(s.z, WithinAbs(0.0, 1e-12));
  // Device frame: x right = y_S, y up = z_S, z toward the user = x_S.
  const glm::dvec3 d = k.forward({std::numbers::pi / 2, std::numbers::pi / 2, std::numbers::pi / 2});
  CHECK_THAT(d.x, WithinAbs(0.450, 1e-12));
  CHECK_THAT(d.y, WithinAbs(0.0, 1e-12));
  CHECK_THAT(d.z, WithinAbs(-0.220, 1e-12));
}

TEST_CASE("woody kinematics: encoder counts to angles with dir and capstan/body ratio") {
  const WoodyKinematics k(woody_presets::woody_v2015());
  // Joint C: aligned (dir -1), cpr 2000, 10/120 mm: 6000 counts = 3 motor turns = 1/4 joint turn.
  glm::dvec3 q = k.angles({0, 0, 6000});
  CHECK_THAT(q.z, WithinAbs(-std::numbers::pi / 2, 1e-12));
  // Joint A: not aligned (dir +1), 10/160 mm: 4000 counts = 2 motor turns = 1/8 joint turn.
  q = k.angles({4000, 0, 0});
  CHECK_THAT(q.x, WithinAbs(std::numbers::pi / 4, 1e-12));
  // The home offset -6000 on C puts the power-on pose at tC = +90 deg.
  CHECK_THAT(k.angles(woody_presets::woody_v2015().home_offset).z, WithinAbs(std::numbers::pi / 2, 1e-12));
  // vintage: cpr 4000.
  const WoodyKinematics v(woody_presets::vintage());
  CHECK_THAT(v.angles({0, 4000, 0}).y, WithinAbs(-2.0 * std::numbers::pi / 12, 1e-12));
  // counts() inverts angles().
  for (const std::array<std::int32_t, 3> c :
       {std::array<std::int32_t, 3>{123, -4567, 8901}, std::array<std::int32_t, 3>{0, 1, -1}})
    CHECK(k.counts(k.angles(c)) == c);
}

TEST_CASE("woody kinematics: Jacobian against central differences, virtual work, current round trip") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const auto& preset : {woody_presets::woody_v2015(), woody_presets::woodenhaptics_v2019(),
                             woody_presets::aluhaptics_v2(), woody_presets::vintage()}) {
    const WoodyKinematics k(preset);
    for (int n = 0; n < 200; ++n) {
      const glm::dvec3 q{u(rng), u(rng), u(rng)};
      const glm::dmat3 j = k.jacobian_source(q);
      const double h = 1e-6;
      for (int i = 0; i < 3; ++i) {
        glm::dvec3 dq{0.0};
        dq[i] = h;
        const glm::dvec3 fd = (k.forward_source(q + dq) - k.forward_source(q - dq)) / (2.0 * h);
        for (int r = 0; r < 3; ++r)
          REQUIRE_THAT(j[i][r], WithinAbs(fd[r], 1e-8));
      }
      // Virtual work: tau . dq == F . dp for a small joint motion (device frame).
      const glm::dvec3 f{u(rng), u(rng), u(rng)};
      const glm::dvec3 dq{u(rng) * 1e-6, u(rng) * 1e-6, u(rng) * 1e-6};
      const glm::dvec3 tau = k.torques(q, f);
      const glm::dvec3 dp = k.forward(q + dq) - k.forward(q);
      REQUIRE_THAT(tau.x * dq.x + tau.y * dq.y + tau.z * dq.z, WithinAbs(f.x * dp.x + f.y * dp.y + f.z * dp.z, 1e-11));
      // Torque -> current -> torque; and motor power equals joint power.
      const glm::dvec3 amps = k.currents(tau);
      const glm::dvec3 back = k.joint_torques(amps);
      for (int i = 0; i < 3; ++i) {
        REQUIRE_THAT(back[i], WithinAbs(tau[i], 1e-12));
        const double motor_rate = 1.0 / k.ratio(i);  // motor turns per joint turn (signed)
        REQUIRE_THAT(preset.torque_constant[i] * amps[i] * motor_rate, WithinAbs(tau[i], 1e-12));
      }
    }
  }
  // Hand-checked current: tau_A = 0.1 N m on v2015: I = 0.1 * (10/160) / 0.0259 A.
  const WoodyKinematics k(woody_presets::woody_v2015());
  CHECK_THAT(k.currents({0.1, 0.0, 0.0}).x, WithinAbs(0.1 * 0.0625 / 0.0259, 1e-12));
  CHECK_THAT(k.currents({0.0, 0.1, 0.0}).y, WithinAbs(-0.1 * (10.0 / 120.0) / 0.0259, 1e-12));  // aligned: dir -1
}

TEST_CASE("woody presets and configurations reject what makes no sense") {
  CHECK(woody_presets::by_name("woody").name == "woody_v2015");
  CHECK(woody_presets::by_name("woodenhaptics_v2019").torque_constant.x == 0.321);
  CHECK(woody_presets::by_name("aluhaptics_v2").lb == 0.140);
  CHECK(woody_presets::by_name("vintage").model_code == 2);
  CHECK_THROWS_WITH(woody_presets::by_name("polhem_v3"), Catch::Contains("closed-chain linkage is not implemented"));
  CHECK_THROWS_AS(woody_presets::by_name("nope"), std::invalid_argument);
  WoodyKinematicsConfig c;
  c.lb = -1.0;
  CHECK_THROWS_AS(WoodyKinematics(c), std::invalid_argument);
  c = {};
  c.counts_per_rev[1] = 0;
  CHECK_THROWS_AS(WoodyKinematics(c), std::invalid_argument);
  ScriptTransport t;
  WoodyArmConfig a = WoodyArmConfig::defaults(Generation::p1_hid8);
  a.max_current = 4.0;  // above P1's 3 A
  CHECK_THROWS_WITH(WoodyArm(t, a), Catch::Contains("max_current"));
  a = WoodyArmConfig::defaults(Generation::p1_hid8);
  a.encoder_sign[0] = 0;
  CHECK_THROWS_AS(WoodyArm(t, a), std::invalid_argument);
  // P4 wake-up: nothing answers -> a clear error after a bounded number of zero frames.
  a = WoodyArmConfig::defaults(Generation::p4_text);
  a.wake_attempts = 5;
  CHECK_THROWS_AS(WoodyArm(t, a), Error);
  REQUIRE(t.written.size() == 5);
  CHECK(bytes_of(t.written[0]) == Bytes{'[', '0', ',', '0', ',', '0', ']', '\n', 0, 0, 0, 0, 0, 0, 0, 0});
}

// -------------------------------------------------------------- WoodyArm

TEST_CASE("WoodyArm P1: decodes signs and offsets, zero current without state, for NaN and when disarmed") {
  ScriptTransport t;
  WoodyArm arm(t, WoodyArmConfig::defaults(Generation::p1_hid8));
  CHECK(t.written.empty());  // P1 has no wake-up
  REQUIRE(arm.set_armed(true) == Status::ok);
  REQUIRE(arm.write({0.0, 1.0, 0.0}) == Status::ok);  // no state yet
  CHECK(t.written.back() == Bytes(9, 0));
  // Two reports queued: the newest wins. Raw enc_a 400 is negated by the host (section 1, P1).
  t.incoming.push_back({0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00});
  t.incoming.push_back({0x90, 0x01, 0xE8, 0x03, 0x00, 0x00, 0x02, 0x00});  // (400, 1000, 0)
  DeviceState s;
  REQUIRE(arm.read(s) == Status::ok);
  CHECK(s.encoder == std::array<std::int32_t, 3>{-400, 1000, -6000});
  const glm::dvec3 q = arm.kinematics().angles({-400, 1000, -6000});
  CHECK(s.joint_angles == q);
  CHECK(s.position == arm.kinematics().forward(q));
  CHECK(arm.read(s) == Status::no_data);
  // A force: the bytes carry round(1000 * I) with I = currents(J^T F), clamped at 3 A.
  REQUIRE(arm.write({0.3, -0.2, 0.1}) == Status::ok);
  const glm::dvec3 amps = arm.kinematics().currents(arm.kinematics().torques(q, {0.3, -0.2, 0.1}));
  const Bytes& w = t.written.back();
  REQUIRE(w.size() == 9);
  CHECK(w[0] == 0x00);
  for (int i = 0; i < 3; ++i)
    CHECK(le16(w, 1 + 2 * static_cast<std::size_t>(i)) == std::lround(std::clamp(amps[i], -3.0, 3.0) * 1000.0));
  REQUIRE(arm.write({0.0, 500.0, 0.0}) == Status::ok);  // far beyond the limit
  bool saturated = false;
  for (int i = 0; i < 3; ++i) {
    const int v = le16(t.written.back(), 1 + 2 * static_cast<std::size_t>(i));
    CHECK(std::abs(v) <= 3000);
    saturated = saturated || std::abs(v) == 3000;
  }
  CHECK(saturated);
  REQUIRE(arm.write({std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}) == Status::ok);
  CHECK(t.written.back() == Bytes(9, 0));
  REQUIRE(arm.write({0.3, -0.2, 0.1}) == Status::ok);
  CHECK(t.written.back() != Bytes(9, 0));
  const std::size_t before = t.written.size();
  REQUIRE(arm.set_armed(false) == Status::ok);
  REQUIRE(t.written.size() == before + 1);  // sent at once
  CHECK(t.written.back() == Bytes(9, 0));
  REQUIRE(arm.write({0.3, -0.2, 0.1}) == Status::ok);
  CHECK(t.written.back() == Bytes(9, 0));
  // A short report is counted, not decoded.
  t.incoming.push_back({0x01, 0x02});
  CHECK(arm.read(s) == Status::no_data);
  CHECK(arm.counters().malformed == 1);
  CHECK(arm.request_home() == Status::unsupported);
}

TEST_CASE("WoodyArm P4: an error reply is counted, its encoders ignored, the state kept") {
  ScriptTransport t;
  t.incoming.push_back(
      Bytes{'[', '3', ',', '1', '0', ',', '2', '0', ',', '3', '0', ',', '0', ',', '0', ',', '0', ',', '0', ']', '\n'});
  WoodyArm arm(t, WoodyArmConfig::defaults(Generation::p4_text));
  REQUIRE(t.written.size() == 1);  // one wake-up frame was enough
  DeviceState s;
  REQUIRE(arm.read(s) == Status::ok);  // the wake-up reply
  CHECK(s.encoder == std::array<std::int32_t, 3>{10, 20, 30 - 6000});
  CHECK(arm.model() == woody::p4_model::woody);
  const DeviceState kept = s;
  const std::string err = "[3,999,999,999,0,0,0," + std::to_string(woody::p4_error::comma_count) + "]\n";
  t.incoming.emplace_back(err.begin(), err.end());
  CHECK(arm.read(s) == Status::no_data);
  CHECK(arm.counters().error_replies == 1);
  CHECK(arm.last_error() == woody::p4_error::comma_count);
  CHECK(s.encoder == kept.encoder);
  CHECK(s.position == kept.position);
  t.incoming.push_back(Bytes{'g', 'a', 'r', 'b', 'a', 'g', 'e', '\n'});
  CHECK(arm.read(s) == Status::no_data);
  CHECK(arm.counters().malformed == 1);
  CHECK(arm.request_home() == Status::unsupported);
}

TEST_CASE("WoodyArm read and write do not allocate, for every generation") {
  if (!test::allocations_counted) return;  // operator new is not counted under ThreadSanitizer
  for (const Generation g : {Generation::p1_hid8, Generation::p2_hid14, Generation::p4_text}) {
    Rig rig(sim_config(g));
    DeviceState s;
    rig.device.set_armed(true);
    for (int i = 0; i < 50; ++i) {
      rig.clock.advance(1'000'000);
      rig.device.read(s);
      rig.device.write({0.0, 0.5, 0.0});
    }
    const long n = test::count_allocations([&] {
      for (int i = 0; i < 2000; ++i) {
        rig.clock.advance(1'000'000);
        (void)rig.device.read(s);
        (void)rig.device.write({0.1, 0.5, -0.2});
      }
    });
    INFO(woody::to_string(g));
    CHECK(n == 0);
    CHECK(s.valid);
  }
}

// ------------------------------------------------------------- end to end

TEST_CASE("end to end: ServoLoop over each generation holds a wall against the scripted hand") {
  for (const Generation g : {Generation::p1_hid8, Generation::p2_hid14, Generation::p4_text}) {
    SimulatedWoodyConfig a = sim_config(g);
    SimulatedWoody probe(a);
    const glm::dvec3 home = probe.position();
    // The hand presses 2 cm down from the power-on pose, into a wall 5 mm below it.
    a.hand.path = HandPath::line(home, home + glm::dvec3{0.0, -0.02, 0.0}, 0.02);
    a.hand.stiffness = 200.0;
    LoopConfig c;
    c.safety.slew_rate = 1e5;
    Rig rig(a, c);
    Wall wall{home.y - 0.005, 2000.0};
    double min_y = 1.0, max_ke = 0.0;
    auto cb = [&](const TickInput& in) {
      min_y = std::min(min_y, rig.arm.position().y);
      max_ke = std::max(max_ke, rig.arm.kinetic_energy());
      return wall.force(in.probe);
    };
    rig.loop.run(cb, {.max_ticks = 4000});
    INFO(woody::to_string(g));
    // The host sees the simulated arm where it is.
    CHECK(glm::length(rig.loop.state().position - rig.arm.position()) < 1e-3);
    // Without the wall the hand would reach home.y - 0.02; the wall holds it
    // near its surface (balance of 200 N/m against 2000 N/m: 1.4 mm in).
    CHECK(min_y > home.y - 0.005 - 0.004);
    CHECK(min_y < home.y - 0.005);  // the wall was really touched
    CHECK(rig.loop.statistics().peak_force > 1.5);
    CHECK(max_ke < 1e-3);  // [J]
    CHECK(rig.device.counters().malformed == 0);
    CHECK(rig.arm.watchdog_trips() == 0);
  }
}

TEST_CASE("end to end: with the hand away, a constant force moves the handle that way") {
  for (const Generation g : {Generation::p1_hid8, Generation::p2_hid14, Generation::p4_text}) {
    SimulatedWoodyConfig a = sim_config(g);
    a.hand.holding = false;
    LoopConfig c;
    c.safety.slew_rate = 1e5;
    Rig rig(a, c);
    const glm::dvec3 start = rig.arm.position();
    Constant push{{0.0, 0.0, 0.5}};  // toward the user [N]
    rig.loop.run(push, {.max_ticks = 400});
    INFO(woody::to_string(g));
    const glm::dvec3 moved = rig.arm.position() - start;
    CHECK(moved.z > 0.005);
    CHECK(std::abs(moved.x) < 0.5 * moved.z);
  }
}

TEST_CASE("end to end: the firmware watchdog zeroes the output when the host stops writing") {
  for (const Generation g : {Generation::p1_hid8, Generation::p2_hid14, Generation::p4_text}) {
    SimulatedWoodyConfig a = sim_config(g);
    LoopConfig c;
    c.safety.slew_rate = 1e5;
    Rig rig(a, c);
    Constant push{{0.0, 1.0, 0.0}};
    rig.loop.run(push, {.max_ticks = 500});
    rig.device.set_armed(true);
    rig.device.write({0.0, 1.0, 0.0});  // the loop disarmed on exit; command a force once more by hand
    INFO(woody::to_string(g));
    rig.link.advance();
    REQUIRE(rig.arm.enabled());
    const double period = g == Generation::p4_text ? SimulatedWoody::text_watchdog : SimulatedWoody::hid_watchdog;
    // The host goes silent: still driving just before the period, zero after it.
    rig.clock.advance(static_cast<std::int64_t>((period - 0.01) * 1e9));
    rig.link.advance();
    CHECK(rig.arm.enabled());
    CHECK(glm::length(rig.arm.applied_current()) > 0.0);
    rig.clock.advance(static_cast<std::int64_t>(0.02 * 1e9));
    rig.link.advance();
    CHECK_FALSE(rig.arm.enabled());
    CHECK(rig.arm.applied_current() == glm::dvec3{0.0});
    CHECK(rig.arm.watchdog_trips() == 1);
  }
}

TEST_CASE(
    "end to end: encoder counts far beyond the joints' range latch (impossible state), zero current from then on") {
  for (const Generation g : {Generation::p1_hid8, Generation::p2_hid14, Generation::p4_text}) {
    INFO(woody::to_string(g));
    SimulatedWoodyConfig a = sim_config(g);
    a.hand.holding = false;
    Rig rig(a);
    std::vector<std::array<std::int16_t, 3>> sent;  // currents written by the tick before
    std::vector<Status> reads;
    sent.reserve(1000);
    reads.reserve(1000);
    auto cb = [&](const TickInput& in) {
      sent.push_back(rig.device.last_milliamps());
      reads.push_back(in.read_status);
      if (in.tick == 600) rig.link.set_wild_counts(true);  // P4: +-2^31, P1/P2: +-32767 counts
      return glm::dvec3{0.0, 0.0, 0.5};
    };
    rig.loop.run(cb, {.max_ticks = 800});
    const auto first = std::find(reads.begin(), reads.end(), Status::impossible);
    REQUIRE(first != reads.end());
    const auto k = static_cast<std::size_t>(first - reads.begin());
    CHECK(k >= 600);
    CHECK(k <= 602);
    CHECK(sent[k] != std::array<std::int16_t, 3>{0, 0, 0});  // driving until then
    for (std::size_t i = k + 1; i < sent.size(); ++i)
      CHECK(sent[i] == std::array<std::int16_t, 3>{0, 0, 0});
    CHECK(rig.loop.statistics().last_latch == safety_events::impossible_state);
    CHECK(safety_events::names(rig.loop.statistics().last_latch) == "impossible state");
    CHECK(rig.device.counters().impossible >= 1);
  }
}

TEST_CASE("end to end P4: a malformed frame gets the error reply; WoodyArm counts it, keeps its state and sends zero") {
  Rig rig(sim_config(Generation::p4_text));
  DeviceState s;
  rig.clock.advance(1'000'000);
  REQUIRE(rig.device.read(s) == Status::ok);
  const DeviceState before = s;
  // A frame with two values reaches the firmware (a corrupted line).
  const std::string bad = "[100,-200]\n";
  REQUIRE(rig.link.write(text(bad)) == Status::ok);
  CHECK(rig.arm.rejected() == 1);
  rig.clock.advance(1'000'000);
  CHECK(rig.device.read(s) == Status::no_data);
  CHECK(rig.device.counters().error_replies == 1);
  CHECK(rig.device.last_error() == woody::p4_error::comma_count);
  CHECK(s.encoder == before.encoder);
  CHECK(rig.arm.applied_current() == glm::dvec3{0.0});  // nothing was ever commanded
  // A frame with |mA| > 6000: the firmware outputs zero on that joint.
  REQUIRE(rig.link.write(text("[7000,100,0]\n")) == Status::ok);
  rig.clock.advance(1'000'000);
  rig.link.advance();
  CHECK(rig.arm.applied_current().x == 0.0);
  CHECK_THAT(rig.arm.applied_current().y, WithinAbs(0.1, 1e-12));
  // An overlong frame: buffer full.
  REQUIRE(rig.link.write(text(std::string(100, '1') + "\n")) == Status::ok);
  REQUIRE(rig.device.read(s) == Status::ok);  // the valid reply to [7000,100,0]
  CHECK(rig.device.counters().error_replies == 2);
  CHECK(rig.device.last_error() == woody::p4_error::buffer_full);
}

TEST_CASE(
    "P2: request_home sends the calibrate command while the button flag is set; counters jump to the attributes") {
  SimulatedWoodyConfig a = sim_config(Generation::p2_hid14);
  a.hand.holding = false;
  Rig rig(a);
  WoodyArmConfig hc = Rig::host(Generation::p2_hid14, rig.clock);
  DeviceState s;
  rig.clock.advance(1'000'000);
  REQUIRE(rig.device.read(s) == Status::ok);
  CHECK(rig.device.request_home() == Status::ok);  // no button flag: nothing happens
  rig.device.write({0.0, 0.0, 0.0});
  CHECK(rig.arm.calibrations() == 0);
  rig.arm.press_calibration_button();
  rig.device.write({0.0, 0.0, 0.0});
  rig.clock.advance(1'000'000);
  REQUIRE(rig.device.read(s) == Status::ok);
  CHECK(s.buttons == 1);
  REQUIRE(rig.device.request_home() == Status::ok);
  rig.device.write({0.0, 0.0, 0.0});
  CHECK(rig.arm.calibrations() == 1);
  CHECK(rig.device.counters().calibrations == 1);
  // The default calibration counts are zero: raw counters now read zero.
  CHECK(rig.arm.raw_counts() == std::array<std::int32_t, 3>{0, 0, 0});
  rig.clock.advance(1'000'000);
  REQUIRE(rig.device.read(s) == Status::ok);
  CHECK(s.buttons == 0);
  CHECK(s.encoder == hc.kinematics.home_offset);
}
