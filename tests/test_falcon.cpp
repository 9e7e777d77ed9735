// Tests of the Novint Falcon family: the packet codec and framer, the
// parallel-arm kinematics against the chain written forward, closed forms
// and central differences over thousands of random poses, the firmware
// upload through the simulated boot loader (flaky loads, no file, loss),
// and Falcon in a ServoLoop on simulated time: homing, LEDs, forces, stop,
// impossible poses, a lost device, a stalled link, restart. Also the
// front door's "falcon" line and servo_demo --device falcon as a child.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "alloc_counter.hpp"
#include "child_process.hpp"
#include "hapticfield/arms/falcon.hpp"
#include "hapticfield/arms/falcon/falcon_door.hpp"
#include "hapticfield/devices/open_device.hpp"
#include "hapticfield/servo.hpp"
#include "run_seed.hpp"
#include "test_fields.hpp"
#if HAPTICFIELD_HAS_LIBUSB
#include "hapticfield/arms/falcon/falcon_libusb.hpp"
#endif

using namespace hapticfield;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {

namespace fs = std::filesystem;

using Packet = std::array<std::uint8_t, falcon::packet_size>;

fs::path tmp_dir() {
  const fs::path d = fs::path(HAPTICFIELD_TEST_TMP) / "falcon";
  fs::create_directories(d);
  return d;
}

/// A stand-in firmware file (Novint's cannot be shipped): n pseudo-random bytes.
std::string firmware_file(std::size_t n = 8492, const std::string& name = "firmware.bin") {
  const fs::path p = tmp_dir() / name;
  std::ofstream out(p, std::ios::binary);
  std::mt19937 rng(7);
  for (std::size_t i = 0; i < n; ++i)
    out.put(static_cast<char>(rng() & 0xFF));
  return p.string();
}

double max_abs(const glm::dvec3& v) {
  return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
}

/// A uniformly random point in a box of half-width h about the origin [m].
glm::dvec3 random_point(std::mt19937& rng, double h) {
  std::uniform_real_distribution<double> u(-h, h);
  return {u(rng), u(rng), u(rng)};
}

/// A uniformly random point of the workspace box (falcon.hpp), shrunk by margin [m].
glm::dvec3 random_pose(std::mt19937& rng, double margin = 0.0) {
  glm::dvec3 p{0.0};
  for (int i = 0; i < 3; ++i) {
    std::uniform_real_distribution<double> u(falcon_workspace_min[i] + margin, falcon_workspace_max[i] - margin);
    p[i] = u(rng);
  }
  return p;
}

struct Rig {
  VirtualClock clock;
  SimulatedFalconUsb usb;
  Falcon device;
  ServoLoop<Falcon, VirtualClock> loop;

  static FalconConfig host(VirtualClock& clock, std::string firmware = {}) {
    FalconConfig c;
    c.now = [&clock] { return clock.now(); };
    c.firmware_path = std::move(firmware);
    return c;
  }
  static LoopConfig quiet(LoopConfig c) {
    c.realtime = RealTime::off;
    return c;
  }
  static SimulatedFalconConfig running(SimulatedFalconConfig s = {}) {
    s.firmware_running = true;
    return s;
  }
  explicit Rig(SimulatedFalconConfig s = running(), LoopConfig c = {}, std::string firmware = {})
      : usb(s), device(usb, host(clock, std::move(firmware))), loop(device, clock, quiet(c)) {}
};

}  // namespace

// ------------------------------------------------------------------ codec

TEST_CASE("falcon codec: a hand-assembled command and report, byte for byte") {
  falcon::Command c;
  c.motor = {0x1234, -2, 0};
  c.leds = falcon::led::green | falcon::led::red;
  c.homing = true;
  Packet out{};
  falcon::encode(c, out);
  // '<', nibbles low first (+0x41), LED|homing, 0x41, '>'
  const Packet want{'<', 0x45, 0x44, 0x43, 0x42, 0x4F, 0x50, 0x50, 0x50, 0x41, 0x41, 0x41, 0x41, 0x41 + 0xB, 0x41, '>'};
  CHECK(out == want);

  const Packet report{'<',        0x41 + 5, 0x41,     0x41, 0x41, 0x41 + 0xF,  0x41 + 0xF, 0x41 + 0xF,
                      0x41 + 0xF, 0x41,     0x41 + 1, 0x41, 0x41, 0x41 + 0x79, 0x41,       '>'};
  falcon::Report r;
  REQUIRE(falcon::decode(report, r) == Status::ok);
  CHECK(r.encoder == std::array<std::int16_t, 3>{5, -1, 16});
  CHECK(r.homed == 7);
  CHECK(r.buttons == 9);
}

TEST_CASE("falcon codec: random commands and reports round trip; malformed packets are refused") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> i16(-32768, 32767), bits(0, 255);
  for (int n = 0; n < 5000; ++n) {
    falcon::Command c;
    for (auto& m : c.motor)
      m = static_cast<std::int16_t>(i16(rng));
    c.leds = static_cast<std::uint8_t>(bits(rng) & falcon::led::all);
    c.homing = bits(rng) & 1;
    Packet p{};
    falcon::encode(c, p);
    falcon::Command back;
    REQUIRE(falcon::decode(p, back) == Status::ok);
    CHECK(back.motor == c.motor);
    CHECK(back.leds == c.leds);
    CHECK(back.homing == c.homing);
    for (std::size_t k = 1; k < 15; ++k)
      CHECK((p[k] >= 0x41 && p[k] <= 0x50));

    falcon::Report r;
    for (auto& e : r.encoder)
      e = static_cast<std::int16_t>(i16(rng));
    r.homed = static_cast<std::uint8_t>(bits(rng) & 7);
    r.buttons = static_cast<std::uint8_t>(bits(rng) & 15);
    falcon::encode(r, p);
    falcon::Report rb;
    REQUIRE(falcon::decode(p, rb) == Status::ok);
    CHECK(rb.encoder == r.encoder);
    CHECK(rb.homed == r.homed);
    CHECK(rb.buttons == r.buttons);
  }
  Packet good{};
  falcon::encode(falcon::Report{}, good);
  falcon::Report r;
  CHECK(falcon::decode(std::span<const std::uint8_t>(good.data(), 15), r) == Status::short_report);
  Packet bad = good;
  bad[15] = 'x';
  CHECK(falcon::decode(bad, r) == Status::unknown_report);
  bad = good;
  bad[0] = 'x';
  CHECK(falcon::decode(bad, r) == Status::unknown_report);
  bad = good;
  bad[5] = 0x40;  // below 'A'
  CHECK(falcon::decode(bad, r) == Status::bad_value);
  bad[5] = 0x51;  // above 'A' + 15
  CHECK(falcon::decode(bad, r) == Status::bad_value);
  bad = good;
  bad[13] = 0x20;
  CHECK(falcon::decode(bad, r) == Status::bad_value);
}

TEST_CASE("falcon framer: packets split anywhere, with noise and false starts between them, come out whole") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::vector<std::uint8_t> stream;
  std::vector<falcon::Report> sent;
  for (int n = 0; n < 300; ++n) {
    if (rng() % 4 == 0) {  // noise with a false '<' in it
      stream.push_back('<');
      for (int k = 0; k < static_cast<int>(rng() % 20); ++k)
        stream.push_back(static_cast<std::uint8_t>('a' + rng() % 20));
    }
    falcon::Report r;
    r.encoder = {static_cast<std::int16_t>(rng()), static_cast<std::int16_t>(rng()), static_cast<std::int16_t>(n)};
    Packet p{};
    falcon::encode(r, p);
    stream.insert(stream.end(), p.begin(), p.end());
    sent.push_back(r);
  }
  falcon::PacketFramer framer;
  std::vector<falcon::Report> got;
  for (std::size_t at = 0; at < stream.size();) {
    const std::size_t n = std::min<std::size_t>(1 + rng() % 40, stream.size() - at);
    framer.push(std::span<const std::uint8_t>(stream.data() + at, n));
    at += n;
    Packet p{};
    while (framer.pop(p)) {
      falcon::Report r;
      if (falcon::decode(p, r) == Status::ok) got.push_back(r);
    }
  }
  REQUIRE(got.size() == sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i)
    CHECK(got[i].encoder == sent[i].encoder);
}

// ------------------------------------------------------------- kinematics

TEST_CASE("falcon kinematics: on the axis every leg sits alike, as the planar two-link closed form says") {
  const FalconKinematics k;
  const FalconGeometry& g = k.geometry();
  for (const double z : {-0.06, -0.03, 0.0, 0.01}) {
    const glm::dvec3 p{0.0, 0.0, z};
    // Closed form: v = -s fixes theta3; (u + c, w) = (c - r, z + origin) is
    // reached by links a and k: theta1 = atan2(w, u + c) - acos((a^2 + D^2 - k^2) / (2 a D)).
    const double t3 = std::acos((-g.s + g.f) / g.b);
    const double kk = g.d + g.e + g.b * std::sin(t3);
    const double tu = -g.r + g.c, tw = z + g.origin_z, dist = std::hypot(tu, tw);
    const double t1 = std::atan2(tw, tu) - std::acos((g.a * g.a + dist * dist - kk * kk) / (2 * g.a * dist));
    glm::dvec3 theta{0.0};
    REQUIRE(k.inverse(p, theta));
    CHECK_THAT(theta.x, WithinAbs(t1, 1e-12));
    CHECK_THAT(theta.y, WithinAbs(t1, 1e-12));
    CHECK_THAT(theta.z, WithinAbs(t1, 1e-12));
  }
  // At the workspace centre the thighs stand at about 47.2 degrees (encoder 0 is 35 degrees).
  glm::dvec3 theta{0.0};
  REQUIRE(k.inverse(glm::dvec3{0.0}, theta));
  CHECK_THAT(theta.x * 180 / std::numbers::pi, WithinAbs(47.24, 0.01));
  // Pulled toward the user (+z), the thighs turn out (theta1 grows).
  glm::dvec3 nearer{0.0};
  REQUIRE(k.inverse({0.0, 0.0, 0.01}, nearer));
  CHECK(nearer.x > theta.x);
}

TEST_CASE("falcon kinematics: the closed-form inverse reproduces every random pose through the chain written forward") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  const FalconKinematics k;
  int reached = 0;
  for (int n = 0; n < 5000; ++n) {
    const glm::dvec3 p = random_pose(rng);
    for (std::size_t leg = 0; leg < 3; ++leg) {
      FalconLegAngles a;
      REQUIRE(k.leg_inverse(leg, p, a));  // the whole workspace box is reachable
      const glm::dvec3 back = k.leg_chain(leg, a);
      INFO("p " << p.x << " " << p.y << " " << p.z << " leg " << leg);
      REQUIRE(max_abs(back - p) < 1e-12);
      ++reached;
    }
  }
  CHECK(reached == 15000);
  // Out of reach: refused, angles untouched.
  FalconLegAngles a{1.0, 2.0, 3.0};
  CHECK_FALSE(k.leg_inverse(0, {0.0, 0.0, 0.5}, a));
  CHECK(a.theta1 == 1.0);
  glm::dvec3 theta{9.0};
  CHECK_FALSE(k.inverse({0.0, 0.3, 0.0}, theta));
  CHECK(theta == glm::dvec3{9.0});
}

TEST_CASE("falcon kinematics: Newton's forward kinematics round-trips thousands of random poses from a far guess") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  const FalconKinematics k;
  int worst = 0;
  for (int n = 0; n < 3000; ++n) {
    const glm::dvec3 p = random_pose(rng);
    const glm::dvec3 guess = random_pose(rng);
    glm::dvec3 theta{0.0};
    REQUIRE(k.inverse(p, theta));
    const FalconForward f = k.forward(theta, guess);
    INFO("p " << p.x << " " << p.y << " " << p.z << " guess " << guess.x << " " << guess.y << " " << guess.z);
    REQUIRE(f.converged);
    CHECK(max_abs(f.position - p) < 1e-9);
    CHECK(f.iterations <= FalconKinematics::default_max_iterations);
    worst = std::max(worst, f.iterations);
  }
  // From a far guess it takes a few steps; warm-started (as each tick is) one or two.
  CHECK(worst <= 12);
  glm::dvec3 theta{0.0};
  REQUIRE(k.inverse({0.01, -0.02, 0.015}, theta));
  const FalconForward warm = k.forward(theta + glm::dvec3{1e-4}, {0.01, -0.02, 0.015});
  CHECK(warm.converged);
  CHECK(warm.iterations <= 3);
}

TEST_CASE("falcon kinematics: angles no pose gives fail within the iteration bound, never loop") {
  const FalconKinematics k;
  // (0.2, 1.5, 0.2) rad looks odd but is a pose (x -89 mm, beyond the workspace box): Newton finds it.
  for (const glm::dvec3 theta : {glm::dvec3{3.0, 3.0, 3.0}, glm::dvec3{-2.0, -2.0, -2.0}, glm::dvec3{0.2, 2.5, 0.2},
                                 glm::dvec3{0.0, 2.8, 0.0}, glm::dvec3{std::nan(""), 0.8, 0.8}}) {
    const FalconForward f = k.forward(theta, glm::dvec3{0.0}, 25);
    CHECK_FALSE(f.converged);
    CHECK(f.iterations <= 25);
  }
}

TEST_CASE("falcon kinematics: the Jacobian against central differences, and tau = J^T F by virtual work") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  const FalconKinematics k;
  const double h = 1e-6;
  for (int n = 0; n < 2000; ++n) {
    const glm::dvec3 p = random_pose(rng, 0.001);
    glm::dmat3 j{0.0};
    REQUIRE(k.angle_jacobian(p, j));
    // d theta / d p by central differences of the inverse
    for (int col = 0; col < 3; ++col) {
      glm::dvec3 e{0.0};
      e[col] = h;
      glm::dvec3 tp{0.0}, tm{0.0};
      REQUIRE(k.inverse(p + e, tp));
      REQUIRE(k.inverse(p - e, tm));
      const glm::dvec3 numeric = (tp - tm) / (2 * h);
      for (int row = 0; row < 3; ++row)
        CHECK_THAT(j[col][row], WithinAbs(numeric[row], 1e-5 * (1.0 + std::fabs(numeric[row]))));
    }
    // d p / d theta by central differences of the forward kinematics: the inverse matrix
    glm::dvec3 theta{0.0};
    REQUIRE(k.inverse(p, theta));
    const glm::dmat3 jp = glm::inverse(j);
    for (int col = 0; col < 3; ++col) {
      glm::dvec3 e{0.0};
      e[col] = 1e-6;
      const FalconForward fp = k.forward(theta + e, p), fm = k.forward(theta - e, p);
      REQUIRE((fp.converged && fm.converged));
      const glm::dvec3 numeric = (fp.position - fm.position) / 2e-6;
      for (int row = 0; row < 3; ++row)
        CHECK_THAT(jp[col][row], WithinAbs(numeric[row], 1e-6 + 1e-5 * std::fabs(numeric[row])));
    }
    // virtual work: tau . d theta == F . d p for a small motion
    const glm::dvec3 force = random_point(rng, 5.0);
    glm::dvec3 tau{0.0};
    REQUIRE(k.torques(p, force, tau));
    const glm::dvec3 dp = random_point(rng, 1e-7);
    glm::dvec3 t1{0.0}, t0{0.0};
    REQUIRE(k.inverse(p + dp, t1));
    REQUIRE(k.inverse(p - dp, t0));
    CHECK_THAT(glm::dot(tau, (t1 - t0) / 2.0),
               WithinAbs(glm::dot(force, dp), 1e-9 * glm::length(force) * 1e-7 + 1e-15));
  }
}

TEST_CASE("falcon kinematics: the workspace box of DeviceInfo is reachable everywhere, without a singular pose") {
  const FalconKinematics k;
  int n = 0;
  for (int i = 0; i <= 14; ++i)
    for (int j = 0; j <= 14; ++j)
      for (int l = 0; l <= 16; ++l) {
        const glm::dvec3 p{falcon_workspace_min.x + i * 0.005, falcon_workspace_min.y + j * 0.005,
                           falcon_workspace_min.z + l * 0.005};
        glm::dmat3 jac{0.0};
        INFO(p.x << " " << p.y << " " << p.z);
        REQUIRE(k.angle_jacobian(p, jac));
        CHECK(std::fabs(glm::determinant(jac)) > 1.0);
        ++n;
      }
  CHECK(n == 15 * 15 * 17);
}

TEST_CASE("falcon kinematics: encoder counts to theta1 with the capstan over the drum") {
  const FalconKinematics k;
  const double per_count = 2 * std::numbers::pi * (0.01425 / 0.110) / 1280.0;
  CHECK_THAT(k.geometry().radians_per_count(), WithinAbs(per_count, 1e-15));
  CHECK_THAT(k.angle(0), WithinAbs(35.0 * std::numbers::pi / 180.0, 1e-15));
  CHECK_THAT(k.angle(1000) - k.angle(0), WithinAbs(1000 * per_count, 1e-12));
  CHECK_THAT(k.count(k.angle(-1234)), WithinAbs(-1234.0, 1e-9));
  FalconGeometry g;
  g.a = -1.0;
  CHECK_THROWS_AS(FalconKinematics(g), std::invalid_argument);
  g = {};
  g.phi[1] = std::nan("");
  CHECK_THROWS_AS(FalconKinematics(g), std::invalid_argument);
}

// ----------------------------------------------------------- firmware upload

TEST_CASE("Falcon: with a firmware already running, nothing is uploaded") {
  Rig rig;
  CHECK_FALSE(rig.device.uploaded_firmware());
  CHECK(rig.device.counters().firmware_uploads == 0);
  CHECK(rig.usb.counters().uploads_started == 0);
}

TEST_CASE("Falcon: no firmware running and no file given is one clear error") {
  SimulatedFalconUsb usb;
  VirtualClock clock;
  try {
    Falcon f(usb, Rig::host(clock));
    FAIL("no error");
  } catch (const DeviceError& e) {
    CHECK_THAT(e.what(), Contains("firmware file not given"));
    CHECK_THAT(e.what(), Contains("simulated Falcon"));
  }
  CHECK(usb.counters().uploads_started == 0);
  // A file that is not there, or empty: FileError naming it.
  CHECK_THROWS_WITH(Falcon(usb, Rig::host(clock, (tmp_dir() / "absent.bin").string())), Contains("absent.bin"));
  CHECK_THROWS_AS(Falcon(usb, Rig::host(clock, firmware_file(0, "empty.bin"))), FileError);
}

TEST_CASE("Falcon: the firmware goes through the boot loader; flaky loads are retried") {
  const std::string file = firmware_file();
  for (const bool leading_zero : {false, true}) {
    for (const int flaky : {0, 1, 3, 9}) {
      SimulatedFalconConfig s;
      s.flaky_loads = flaky;
      s.leading_zero_in_check_reply = leading_zero;
      s.expected_firmware_size = 8492;
      SimulatedFalconUsb usb(s);
      VirtualClock clock;
      Falcon f(usb, Rig::host(clock, file));
      INFO("flaky " << flaky << " leading zero " << leading_zero);
      CHECK(f.uploaded_firmware());
      CHECK(usb.firmware_running());
      CHECK(f.counters().firmware_uploads == static_cast<std::uint64_t>(flaky + 1));
      CHECK(usb.counters().uploads_started == static_cast<std::uint64_t>(flaky + 1));
    }
  }
  // More flaky loads than attempts: one error naming the file and the count.
  SimulatedFalconConfig s;
  s.flaky_loads = 50;
  SimulatedFalconUsb usb(s);
  VirtualClock clock;
  FalconConfig c = Rig::host(clock, file);
  c.firmware_attempts = 4;
  try {
    Falcon f(usb, c);
    FAIL("no error");
  } catch (const DeviceError& e) {
    CHECK_THAT(e.what(), Contains("did not load after 4 attempt(s)"));
    CHECK_THAT(e.what(), Contains("the echo differs at byte 100"));
    CHECK_THAT(e.what(), Contains("firmware.bin"));
  }
  // A firmware the boot loader takes but that never answers (a wrong file).
  SimulatedFalconConfig wrong;
  wrong.expected_firmware_size = 7914;
  SimulatedFalconUsb usb2(wrong);
  c.firmware_attempts = 2;
  CHECK_THROWS_WITH(Falcon(usb2, c), Contains("the firmware was sent but does not answer"));
  // The device lost during the upload: no more attempts.
  SimulatedFalconUsb usb3;
  usb3.lose();
  CHECK_THROWS_AS(Falcon(usb3, c), DeviceError);
}

TEST_CASE("Falcon: configurations that make no sense are refused") {
  VirtualClock clock;
  SimulatedFalconUsb usb(Rig::running());
  const auto bad = [&](auto edit) {
    FalconConfig c = Rig::host(clock);
    edit(c);
    CHECK_THROWS_AS(Falcon(usb, c), std::invalid_argument);
  };
  bad([](FalconConfig& c) { c.firmware_attempts = 0; });
  bad([](FalconConfig& c) { c.max_force = std::nan(""); });
  bad([](FalconConfig& c) { c.max_motor_count = 40000; });
  bad([](FalconConfig& c) { c.reach = 0.0; });
  bad([](FalconConfig& c) { c.newton_iterations = 0; });
  SimulatedFalconConfig s;
  s.initial_position = {0.0, 0.0, 0.2};
  CHECK_THROWS_AS(SimulatedFalconUsb(s), std::invalid_argument);
}

// --------------------------------------------------------------- the device

TEST_CASE("Falcon: homing mode until the encoders report homed; LEDs red, then blue, then green") {
  Rig rig;
  DeviceState s;
  rig.device.write(glm::dvec3{0.0});
  REQUIRE(rig.device.read(s) == Status::ok);
  CHECK_FALSE(s.homed());
  CHECK(rig.usb.last_command().leds == falcon::led::red);
  CHECK_FALSE(rig.usb.last_command().homing);  // not asked yet
  // Unhomed, the counts carry the power-on offset: the pose is off.
  CHECK(glm::length(s.position - rig.usb.position()) > 1e-3);
  rig.device.request_home();
  int sent = 0;
  while (!s.homed() && sent < 200) {
    rig.device.write(glm::dvec3{1.0, 0.0, 0.0});  // not homed: zero force whatever is asked
    CHECK(rig.usb.last_command().motor == std::array<std::int16_t, 3>{0, 0, 0});
    CHECK(rig.usb.last_command().homing);
    ++sent;
    rig.clock.advance(1'000'000);
    rig.device.read(s);
  }
  REQUIRE(s.homed());
  CHECK(sent == 50);
  CHECK(max_abs(s.position - rig.usb.position()) < 2e-4);  // one count is about 0.06 mm at the handle
  rig.device.write(glm::dvec3{0.0});
  CHECK_FALSE(rig.usb.last_command().homing);
  CHECK(rig.usb.last_command().leds == falcon::led::blue);
  rig.device.set_armed(true);
  rig.device.write(glm::dvec3{0.0});
  CHECK(rig.usb.last_command().leds == falcon::led::green);
  rig.device.set_leds(falcon::led::red | falcon::led::blue);
  rig.device.write(glm::dvec3{0.0});
  CHECK(rig.usb.last_command().leds == (falcon::led::red | falcon::led::blue));
  rig.device.set_automatic_leds();
  rig.device.write(glm::dvec3{0.0});
  CHECK(rig.usb.last_command().leds == falcon::led::green);
  rig.usb.set_buttons(0x5);
  rig.device.write(glm::dvec3{0.0});
  rig.clock.advance(1'000'000);
  REQUIRE(rig.device.read(s) == Status::ok);
  CHECK(s.buttons == 0x5);
}

TEST_CASE("Falcon: the motors get the force the host asked for, through J^T and back") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  SimulatedFalconConfig sc = Rig::running();
  sc.homing_packets = 1;
  Rig rig(sc);
  DeviceState s;
  rig.device.request_home();
  rig.device.set_armed(true);
  for (int i = 0; i < 5; ++i) {
    rig.device.write(glm::dvec3{0.0});
    rig.device.read(s);
  }
  REQUIRE(s.armed());
  for (int n = 0; n < 200; ++n) {
    const glm::dvec3 f = random_point(rng, 2.0);
    rig.device.write(f);
    // The simulated arm turns the counts back into a handle force: equal to
    // what was asked, within the counts' rounding (at most 0.5 count a motor).
    CHECK(glm::length(rig.usb.motor_force() - f) < 0.02);
    rig.clock.advance(1'000'000);
    rig.device.read(s);
  }
  // A force beyond the motors: all three counts scaled together, direction kept.
  const glm::dvec3 big{0.0, -40.0, 10.0};
  rig.device.write(big);
  const auto& m = rig.usb.last_command().motor;
  CHECK(std::max({std::abs(m[0]), std::abs(m[1]), std::abs(m[2])}) == 4096);
  CHECK(glm::dot(glm::normalize(rig.usb.motor_force()), glm::normalize(big)) > 0.9999);
  // Non-finite: zero.
  rig.device.write({std::nan(""), 0.0, 0.0});
  CHECK(rig.usb.last_command().motor == std::array<std::int16_t, 3>{0, 0, 0});
}

TEST_CASE("Falcon read and write do not allocate") {
  if (!test::allocations_counted) return;  // operator new is not counted under ThreadSanitizer
  SimulatedFalconConfig sc = Rig::running();
  sc.homing_packets = 1;
  Rig rig(sc);
  DeviceState s;
  rig.device.request_home();
  rig.device.set_armed(true);
  for (int i = 0; i < 20; ++i) {
    rig.device.write(glm::dvec3{0.0});
    rig.device.read(s);
  }
  const long n = test::count_allocations([&] {
    for (int i = 0; i < 3000; ++i) {
      rig.clock.advance(1'000'000);
      (void)rig.device.read(s);
      (void)rig.device.write({0.3, -0.5, 0.2});
    }
  });
  CHECK(n == 0);
  CHECK(s.valid);
  CHECK(s.armed());
}

// ----------------------------------------------------------------- end to end

TEST_CASE("end to end: ServoLoop homes the Falcon, then a constant force moves the handle that way") {
  LoopConfig c;
  c.safety.slew_rate = 1e5;
  Rig rig(Rig::running(), c);
  testing::Constant push{{0.0, 0.0, 1.0}};  // toward the user [N]
  rig.loop.run(push, {.max_ticks = 600});
  CHECK(rig.usb.homed());
  CHECK(rig.loop.state().homed());
  CHECK(rig.usb.position().z > 0.005);  // at the simulated wall, 1 cm in front of the centre
  CHECK(std::fabs(rig.usb.position().x) < 0.2 * rig.usb.position().z);
  CHECK(glm::length(rig.loop.state().position - rig.usb.position()) < 1e-3);
  CHECK(rig.device.counters().impossible == 0);
  CHECK(rig.device.counters().malformed == 0);
  // Stop gives zero force: the last command after run() returns is zero.
  CHECK(rig.usb.last_command().motor == std::array<std::int16_t, 3>{0, 0, 0});
  CHECK(rig.usb.motor_force() == glm::dvec3{0.0});
  // The Newton solve, warm-started each tick, takes few steps.
  CHECK(rig.device.counters().newton_worst <= 6);
}

TEST_CASE("end to end: the scripted hand presses into a wall the Falcon renders, and the wall holds") {
  SimulatedFalconConfig sc = Rig::running();
  sc.hand.holding = true;
  sc.hand.stiffness = 200.0;
  sc.hand.path = HandPath::line({0.0, 0.0, 0.0}, {0.0, -0.03, 0.0}, 0.02);
  LoopConfig c;
  c.safety.slew_rate = 1e5;
  Rig rig(sc, c);
  testing::Wall wall{-0.01, 2000.0};
  double min_y = 1.0;
  auto cb = [&](const TickInput& in) {
    if (rig.usb.homed()) min_y = std::min(min_y, rig.usb.position().y);
    return wall.force(in.probe);
  };
  rig.loop.run(cb, {.max_ticks = 3000});
  CHECK(min_y < -0.01);           // touched
  CHECK(min_y > -0.01 - 0.0045);  // held: 200 N/m against 2000 N/m over 2 cm is 1.8 mm in
  CHECK(rig.loop.statistics().peak_force > 1.0);
}

TEST_CASE("end to end: encoder counts no pose gives latch the loop (impossible state); zero force from then on") {
  Rig rig;
  std::vector<std::array<std::int16_t, 3>> sent;
  std::vector<Status> reads;
  sent.reserve(1000);
  reads.reserve(1000);
  auto cb = [&](const TickInput& in) {
    sent.push_back(rig.usb.last_command().motor);
    reads.push_back(in.read_status);
    if (in.tick == 500) rig.usb.impossible_report({32000, -32000, 32000});
    return glm::dvec3{0.0, 0.0, 1.0};
  };
  rig.loop.run(cb, {.max_ticks = 800});
  const auto first = std::find(reads.begin(), reads.end(), Status::impossible);
  REQUIRE(first != reads.end());
  const auto k = static_cast<std::size_t>(first - reads.begin());
  CHECK(k >= 500);
  CHECK(k <= 502);
  CHECK(sent[k] != std::array<std::int16_t, 3>{0, 0, 0});  // driving until then
  for (std::size_t i = k + 1; i < sent.size(); ++i)
    CHECK(sent[i] == std::array<std::int16_t, 3>{0, 0, 0});
  CHECK(rig.loop.statistics().last_latch == safety_events::impossible_state);
  CHECK(rig.device.counters().impossible == 1);
}

TEST_CASE("end to end: a lost Falcon ends the run (disconnected); a stalled link latches; zero force either way") {
  {
    Rig rig;
    auto cb = [&](const TickInput& in) {
      if (in.tick == 400) rig.usb.lose();
      return glm::dvec3{0.0, 0.0, 1.0};
    };
    const StopReason why = rig.loop.run(cb, {.max_ticks = 800});
    CHECK(why == StopReason::disconnected);
    CHECK(rig.loop.statistics().ticks < 420);
    CHECK(rig.device.last_command().motor == std::array<std::int16_t, 3>{0, 0, 0});  // nothing gets through now
    CHECK((rig.loop.statistics().last_latch & safety_events::disconnected) != 0);
  }
  {
    Rig rig;
    std::vector<std::array<std::int16_t, 3>> sent;
    sent.reserve(1000);
    auto cb = [&](const TickInput& in) {
      sent.push_back(rig.usb.last_command().motor);
      if (in.tick == 400) rig.usb.stall(true);
      return glm::dvec3{0.0, 0.0, 1.0};
    };
    rig.loop.run(cb, {.max_ticks = 800});
    CHECK(rig.loop.statistics().latches == 1);
    CHECK((rig.loop.statistics().last_latch & (safety_events::stale_state | safety_events::no_new_state)) != 0);
    CHECK(sent[390] != std::array<std::int16_t, 3>{0, 0, 0});
    CHECK(sent.back() == std::array<std::int16_t, 3>{0, 0, 0});
  }
}

TEST_CASE("end to end: after a latch is cleared the force comes back through the slew limit and soft start") {
  LoopConfig c;
  c.safety.slew_rate = 50.0;  // [N/s]
  Rig rig(Rig::running(), c);
  auto cb = [&](const TickInput& in) {
    if (in.tick == 500) rig.usb.stall(true);
    if (in.tick == 520) rig.usb.stall(false);
    return glm::dvec3{0.0, 0.0, 1.5};
  };
  rig.loop.run(cb, {.max_ticks = 700});
  REQUIRE(rig.loop.statistics().latches == 1);
  rig.loop.clear_fault();
  std::vector<double> forces;
  forces.reserve(400);
  auto again = [&](const TickInput&) {
    forces.push_back(glm::length(rig.usb.motor_force()));
    return glm::dvec3{0.0, 0.0, 1.5};
  };
  rig.loop.run(again, {.max_ticks = 400});
  INFO("latches " << rig.loop.statistics().latches << " last " << rig.loop.statistics().last_latch << " trusted "
                  << rig.loop.trusted() << " armed " << rig.loop.state().armed() << " homed "
                  << rig.loop.state().homed() << " valid " << rig.loop.state().valid);
  REQUIRE(forces.size() == 400);
  CHECK(forces[0] == 0.0);
  // rises no faster than the slew limit allows (50 N/s: 0.05 N a tick), within the counts' rounding
  for (std::size_t i = 1; i < forces.size(); ++i)
    CHECK(forces[i] - forces[i - 1] < 0.05 + 0.02);
  CHECK(forces.back() > 1.4);
}

// ------------------------------------------------------- front door and tools

TEST_CASE("front door: falcon strings are checked, falcon:sim opens, and a real Falcon says why not") {
  CHECK(parse_device_spec("falcon:sim").simulated);
  CHECK_FALSE(parse_device_spec("falcon").simulated);
  CHECK_FALSE(parse_device_spec("falcon:1").simulated);
  CHECK(falcon_door::parse("2:/tmp/nVent_firmware.bin").firmware == "/tmp/nVent_firmware.bin");
  CHECK(falcon_door::parse("2:/tmp/nVent_firmware.bin").index == 2);
  CHECK_THROWS_WITH(parse_device_spec("falcon:x"), Contains("falcon takes an index"));
  CHECK_THROWS_WITH(parse_device_spec("falcon:99"), Contains("0..15"));
  CHECK_THROWS_WITH(parse_device_spec("falcon:0:"), Contains("firmware file"));

  VirtualClock clock;
  DeviceOptions options;
  options.now = [&clock] { return clock.now(); };
  AnyDevice any = open_device("falcon:sim", options);
  REQUIRE(any);
  CHECK(any.info().name == "Novint Falcon");
  REQUIRE(any.target<Falcon>() != nullptr);
  ServoLoop<AnyDevice, VirtualClock> loop(any, clock, Rig::quiet({}));
  testing::Constant push{{0.5, 0.0, 0.0}};
  loop.run(push, {.max_ticks = 300});
  CHECK(loop.state().homed());
  CHECK(loop.state().position.x > 0.001);

  bool listed = false;
  for (const DeviceListing& l : list_devices())
    if (l.family == "falcon") {
      listed = true;
      CHECK_THAT(l.line, Contains("falcon"));
#if !HAPTICFIELD_HAS_LIBUSB
      CHECK_THAT(l.line, Contains("no libusb-1.0"));
#endif
    }
  CHECK(listed);

#if HAPTICFIELD_HAS_LIBUSB
  // No Falcon on this machine (or no USB at all): one clear error.
  if (LibusbFalconUsb::count() == 0) {
    try {
      (void)open_device("falcon");
      FAIL("opened a Falcon that is not there");
    } catch (const DeviceError& e) {
      CHECK_THAT(e.what(), Contains("no Falcon found") || Contains("libusb_init failed"));
    }
  }
#else
  CHECK_THROWS_AS(open_device("falcon"), DeviceError);
#endif
}

#ifdef HAPTICFIELD_SERVO_DEMO
TEST_CASE("servo_demo --device falcon:sim runs on simulated time; --device falcon without a Falcon is one line") {
  const fs::path dir = tmp_dir() / "servo_demo";
  {
    testing::Child tool(
        HAPTICFIELD_SERVO_DEMO,
        {"--device", "falcon:sim", "--clock", "virtual", "--seconds", "2", "--field", "spring", "--realtime", "off"},
        dir, "sim");
    REQUIRE(tool.wait());
    INFO(tool.out() << tool.err());
    CHECK(tool.exited_normally());
    CHECK(tool.status() == 0);
    CHECK(tool.err().empty());
  }
  {
    testing::Child tool(HAPTICFIELD_SERVO_DEMO, {"--device", "falcon", "--realtime", "off", "--seconds", "1"}, dir,
                        "real");
    REQUIRE(tool.wait());
    INFO(tool.out() << tool.err());
    CHECK(tool.exited_normally());
    CHECK(tool.status() != 0);
    const std::string err = tool.err();
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    CHECK((err.find("no Falcon found") != std::string::npos || err.find("no libusb-1.0") != std::string::npos ||
           err.find("libusb_init failed") != std::string::npos));
  }
}

TEST_CASE("Ctrl-C on servo_demo --device falcon:sim: stopped through the loop, exit 130") {
  testing::Child tool(HAPTICFIELD_SERVO_DEMO,
                      {"--device", "falcon:sim", "--seconds", "3000", "--field", "spring", "--realtime", "off"},
                      tmp_dir() / "servo_demo", "sigint");
  REQUIRE(tool.wait_for_output("Hz"));
  tool.signal(SIGINT);
  REQUIRE(tool.wait());
  INFO(tool.out() << tool.err());
  CHECK(tool.exited_normally());
  CHECK(tool.status() == 130);
  CHECK(tool.out().find("stopped by signal 2") != std::string::npos);
}
#endif

// ------------------------------------------------- the shared device suite

#if __has_include("device_suite.hpp")
#include "device_suite.hpp"

namespace {

/// The Falcon behind the front door's AnyDevice, on the fake USB link.
class FalconTwin {
 public:
  explicit FalconTwin(VirtualClock& clock) {
    auto parts = std::make_unique<Parts>();
    parts->usb = std::make_unique<SimulatedFalconUsb>(Rig::running());
    parts->arm = std::make_unique<Falcon>(*parts->usb, Rig::host(clock));
    usb_ = parts->usb.get();
    any_ = AnyDevice::holding(std::move(parts));
  }
  AnyDevice& device() noexcept { return any_; }
  /// The handle force the last command's motor counts apply [N].
  [[nodiscard]] double effort() const noexcept { return glm::length(usb_->motor_force()); }
  void lose() noexcept { usb_->lose(); }
  void send_impossible() noexcept { usb_->impossible_report({32000, -32000, 32000}); }

 private:
  struct Parts {
    std::unique_ptr<SimulatedFalconUsb> usb;
    std::unique_ptr<Falcon> arm;
    Falcon& device() noexcept { return *arm; }
  };
  SimulatedFalconUsb* usb_{nullptr};
  AnyDevice any_;
};
static_assert(test::device_suite::Twin<FalconTwin>);

}  // namespace

HAPTICFIELD_DEVICE_SUITE(FalconTwin, "falcon")
#endif
