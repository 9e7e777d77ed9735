// Tests of the Haply Inverse3 adapter: request and reply bytes assembled by
// hand, the frame mapping, the fixed-size framing, and Inverse3 through a
// real pseudo-terminal against SimulatedInverse3 answering on the master
// side in a thread (a ServoLoop on a virtual clock, unplug, silence,
// garbage). Every blocking wait has a hard timeout.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/arms/inverse3/inverse3.hpp"
#include "hapticfield/arms/inverse3/inverse3_codec.hpp"
#include "hapticfield/arms/inverse3/simulated_inverse3.hpp"
#include "hapticfield/protocol/stream_framer.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport/serial_transport.hpp"
#include "pty_pair.hpp"
#include "test_fields.hpp"

using namespace hapticfield;
using Catch::Matchers::WithinAbs;
using testing::Constant;

namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;
constexpr auto hard_timeout = 5s;  // no wait in these tests lasts longer

using testing::Pty;

/// SimulatedInverse3 on the master side of a pty, in its own thread.
class PtyInverse3 {
 public:
  /// garbage_before_reply: 0xFF x 7 go out before this reply (0 = the
  /// wake-up's); stall_after: replies after this many never go out.
  explicit PtyInverse3(Pty& pty, std::int64_t garbage_before_reply = -1, std::int64_t stall_after = -1)
      : pty_(pty), garbage_before_reply_(garbage_before_reply), stall_after_(stall_after) {
    thread_ = std::thread([this] { run(); });
  }
  ~PtyInverse3() { stop(); }
  void stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  /// Closes the master side at once (an unplugged cable), from the thread.
  void unplug() { unplug_.store(true); }
  SimulatedInverse3& sim() { return sim_; }  // only once stopped

  static constexpr std::array<std::uint8_t, 7> garbage{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};

 private:
  void run() {
    std::array<std::uint8_t, 256> rx{};
    const auto give_up = std::chrono::steady_clock::now() + 4 * hard_timeout;
    while (!stop_.load() && std::chrono::steady_clock::now() < give_up) {
      if (unplug_.load()) {
        if (pty_.master >= 0) {
          ::close(pty_.master);
          pty_.master = -1;
        }
        return;
      }
      pollfd p{pty_.master, POLLIN, 0};
      if (::poll(&p, 1, 5) <= 0) continue;
      const ssize_t n = ::read(pty_.master, rx.data(), rx.size());
      if (n <= 0) continue;
      sim_.feed(std::span<const std::uint8_t>(rx.data(), static_cast<std::size_t>(n)),
                [this](std::span<const std::uint8_t> r) {
                  if (stall_after_ >= 0 && replies_ >= stall_after_) return;
                  if (replies_ == garbage_before_reply_) (void)!::write(pty_.master, garbage.data(), garbage.size());
                  ++replies_;
                  (void)!::write(pty_.master, r.data(), r.size());
                });
    }
  }

  Pty& pty_;
  SimulatedInverse3 sim_{};
  std::int64_t garbage_before_reply_;
  std::int64_t stall_after_;
  std::int64_t replies_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> unplug_{false};
  std::thread thread_;
};

/// SerialTransport in lock step with the device thread: while a reply is
/// owed, a read waits for it (bounded), so a loop on a virtual clock sees
/// every reply on the tick after its request, whatever the machine's load.
class Lockstep final : public Transport {
 public:
  explicit Lockstep(SerialTransport& serial) : serial_(serial) {}
  Status read(std::span<std::uint8_t> b, std::size_t& n, int t) noexcept override {
    if (owed_ > 0 && t == 0) t = 1'000'000;
    const Status s = serial_.read(b, n, t);
    if (s == Status::ok && owed_ > 0) --owed_;
    return s;
  }
  Status write(std::span<const std::uint8_t> r) noexcept override {
    const Status s = serial_.write(r);
    if (s == Status::ok) ++owed_;
    return s;
  }
  Status get_feature(std::span<std::uint8_t> b, std::size_t& n) noexcept override { return serial_.get_feature(b, n); }
  Status send_feature(std::span<const std::uint8_t> r) noexcept override { return serial_.send_feature(r); }
  Status set_frame_size(std::size_t n) noexcept override { return serial_.set_frame_size(n); }
  std::size_t drop_pending() noexcept override { return serial_.drop_pending(); }
  [[nodiscard]] std::size_t pending() const noexcept override { return serial_.pending(); }
  [[nodiscard]] std::string_view where() const noexcept override { return serial_.where(); }

 private:
  SerialTransport& serial_;
  int owed_{0};
};

SerialConfig fixed_framing() {
  SerialConfig c;
  c.framing = Framing::fixed;
  return c;
}

/// The frame these tests use: our y is the device's z, our z is minus its y.
Inverse3Frame test_frame() {
  return Inverse3Frame::axes({1, 3, -2}, glm::dvec3{0.0, 0.1, 0.05});
}

LoopConfig quiet() {
  LoopConfig c;
  c.realtime = RealTime::off;
  return c;
}

/// Everything on one virtual clock: pty, device thread, serial, Inverse3, loop.
struct Rig {
  explicit Rig(std::int64_t garbage_at = -1) : pty(), device_thread(pty, garbage_at) {}
  Pty pty;
  PtyInverse3 device_thread;
  VirtualClock clock;
  SerialTransport serial{pty.path, fixed_framing()};
  Lockstep link{serial};
  Inverse3 arm{link, config()};
  ServoLoop<Inverse3, VirtualClock> loop{arm, clock, quiet()};
  Inverse3Config config() {
    Inverse3Config c;
    c.frame = test_frame();
    c.reply_timeout_us = 2'000'000;  // a loaded machine may be slow to run the device thread
    c.now = [this] { return clock.now(); };
    return c;
  }
};

}  // namespace

TEST_CASE("inverse3 codec: requests and replies, byte by byte") {
  std::array<std::uint8_t, 32> out{};
  REQUIRE(inverse3::encode_wake(out) == 1);
  CHECK(out[0] == 0x0A);
  REQUIRE(inverse3::encode_command(inverse3::code::force, {1.0f, -2.0f, 0.5f}, out) == 13);
  CHECK(Bytes(out.begin(), out.begin() + 13) ==
        Bytes{0x2A, 0x00, 0x00, 0x80, 0x3F, 0x00, 0x00, 0x00, 0xC0, 0x00, 0x00, 0x00, 0x3F});
  REQUIRE(inverse3::encode_command(inverse3::code::joint_torques, {20.0f, 0.0f, -0.25f}, out) == 13);
  CHECK(Bytes(out.begin(), out.begin() + 13) ==
        Bytes{0x1A, 0x00, 0x00, 0xA0, 0x41, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0xBE});
  CHECK(inverse3::encode_command(0x3A, {0.0f, 0.0f, 0.0f}, out) == 0);
  CHECK(inverse3::encode_command(inverse3::code::force, {0.0f, 0.0f, 0.0f}, std::span<std::uint8_t>(out.data(), 12)) ==
        0);

  // Wake-up reply: header 0x55, id 0x1234, model 3, hardware 2, firmware 7, 16 bytes 0xA0..0xAF.
  Bytes wake{0x55, 0x34, 0x12, 0x03, 0x02, 0x07};
  for (std::uint8_t i = 0; i < 16; ++i)
    wake.push_back(static_cast<std::uint8_t>(0xA0 + i));
  inverse3::Identity id;
  REQUIRE(inverse3::decode_wake_reply(wake, id) == Status::ok);
  CHECK(id.header == 0x55);
  CHECK(id.device_id == 0x1234);
  CHECK(id.model == 3);
  CHECK(id.hardware_version == 2);
  CHECK(id.firmware_version == 7);
  CHECK(id.extra[0] == 0xA0);
  CHECK(id.extra[15] == 0xAF);
  CHECK(inverse3::decode_wake_reply(std::span<const std::uint8_t>(wake.data(), 21), id) == Status::short_report);
  CHECK(Bytes(out.begin(), out.begin() + static_cast<long>(inverse3::encode_wake_reply(id, out))) == wake);

  // State reply: position (0.25, -0.5, 1) m, velocity (0, 2, -0.125) m/s.
  const Bytes state{0x77, 0x00, 0x00, 0x80, 0x3E, 0x00, 0x00, 0x00, 0xBF, 0x00, 0x00, 0x80, 0x3F,
                    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40, 0x00, 0x00, 0x00, 0xBE};
  inverse3::StateReply r;
  REQUIRE(inverse3::decode_state_reply(state, r) == Status::ok);
  CHECK(r.header == 0x77);
  CHECK(r.first == std::array<float, 3>{0.25f, -0.5f, 1.0f});
  CHECK(r.second == std::array<float, 3>{0.0f, 2.0f, -0.125f});
  CHECK(Bytes(out.begin(), out.begin() + static_cast<long>(inverse3::encode_state_reply(r, out))) == state);
  Bytes nan = state;
  nan[4] = 0x7F;
  nan[3] = 0xC0;  // 0x7FC00000: a quiet NaN
  CHECK(inverse3::decode_state_reply(nan, r) == Status::bad_value);
  Bytes inf = state;
  inf[16] = 0x7F;
  inf[15] = 0x80;  // 0x7F800000: +inf
  CHECK(inverse3::decode_state_reply(inf, r) == Status::bad_value);
  CHECK(inverse3::decode_state_reply(std::span<const std::uint8_t>(state.data(), 24), r) == Status::short_report);

  std::array<float, 3> v{};
  CHECK(inverse3::decode_command(std::span<const std::uint8_t>(out.data(), 13), v) == Status::unknown_report);
  REQUIRE(inverse3::encode_command(inverse3::code::force, {1.0f, -2.0f, 0.5f}, out) == 13);
  REQUIRE(inverse3::decode_command(std::span<const std::uint8_t>(out.data(), 13), v) == Status::ok);
  CHECK(v == std::array<float, 3>{1.0f, -2.0f, 0.5f});
}

TEST_CASE("inverse3 frame: signed axes map both ways, and bad matrices are rejected") {
  const Inverse3Frame f = test_frame();
  // Device (1, 2, 3) is ours (1, 3, -2); the origin is removed first.
  CHECK(f.vector_to_ours({1.0, 2.0, 3.0}) == glm::dvec3{1.0, 3.0, -2.0});
  CHECK(f.position_to_ours({0.0, 0.1, 0.05}) == glm::dvec3{0.0});
  CHECK(f.vector_to_device({1.0, 3.0, -2.0}) == glm::dvec3{1.0, 2.0, 3.0});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double a = 0.3, b = -1.1;  // a general rotation: about z by a, then about x by b
  Inverse3Frame g;
  g.rotation = glm::dmat3(1, 0, 0, 0, std::cos(b), std::sin(b), 0, -std::sin(b), std::cos(b)) *
               glm::dmat3(std::cos(a), std::sin(a), 0, -std::sin(a), std::cos(a), 0, 0, 0, 1);
  CHECK_NOTHROW(g.validate());
  for (int i = 0; i < 200; ++i) {
    const glm::dvec3 v{u(rng), u(rng), u(rng)};
    for (const Inverse3Frame* fr : std::array<const Inverse3Frame*, 2>{&f, &g}) {
      const glm::dvec3 back = fr->vector_to_device(fr->vector_to_ours(v));
      CHECK(glm::length(back - v) < 1e-15);
      CHECK_THAT(glm::length(fr->vector_to_ours(v)), WithinAbs(glm::length(v), 1e-15));
    }
  }
  CHECK(Inverse3Frame::axes({1, 2, 3}).rotation == glm::dmat3(1.0));
  CHECK(Inverse3Frame::axes({-1, -2, 3}).vector_to_ours({1, 2, 3}) == glm::dvec3{-1, -2, 3});

  const auto message = [](auto&& make) {
    try {
      make();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(message([] { (void)Inverse3Frame::axes({1, 1, 3}); }).find("orthonormal") != std::string::npos);
  CHECK(message([] { (void)Inverse3Frame::axes({1, 2, 4}); }).find("+-3") != std::string::npos);
  CHECK(message([] { (void)Inverse3Frame::axes({0, 2, 3}); }).find("+-3") != std::string::npos);
  CHECK(message([] { (void)Inverse3Frame::axes({1, 2, -3}); }).find("reflection") != std::string::npos);
  CHECK(message([] { (void)Inverse3Frame::axes({2, 1, 3}); }).find("reflection") != std::string::npos);
  Inverse3Frame scaled;
  scaled.rotation = glm::dmat3(1.01);
  CHECK(message([&] { scaled.validate(); }).find("orthonormal") != std::string::npos);
  Inverse3Frame sheared;
  sheared.rotation[1][0] = 1e-6;
  CHECK(message([&] { sheared.validate(); }).find("orthonormal") != std::string::npos);
  Inverse3Frame nan;
  nan.rotation[2][2] = std::nan("");
  CHECK(message([&] { nan.validate(); }).find("finite") != std::string::npos);
  Inverse3Frame far;
  far.origin.y = INFINITY;
  CHECK(message([&] { far.validate(); }).find("origin") != std::string::npos);
  Inverse3Config c;
  c.frame = scaled;
  CHECK_THROWS_AS(c.validate(), std::invalid_argument);
  c = {};
  c.max_force = -1.0;
  CHECK_THROWS_AS(c.validate(), std::invalid_argument);
  c = {};
  c.max_outstanding = 33;
  CHECK_THROWS_AS(c.validate(), std::invalid_argument);
}

TEST_CASE("fixed framing: frames of N bytes across splits; N changes between exchanges and drops the rest") {
  StreamFramer<512> framer(Framing::fixed);
  std::array<std::uint8_t, 64> out{};
  std::size_t n = 0;
  const Bytes a{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  framer.push(a);
  CHECK(framer.next(out, n) == Status::no_data);  // no size set yet
  REQUIRE(framer.set_frame_size(4));
  CHECK(framer.counters().skipped == 10);  // the bytes of before
  framer.push(std::span<const std::uint8_t>(a.data(), 3));
  CHECK(framer.next(out, n) == Status::no_data);  // a partial frame waits
  framer.push(std::span<const std::uint8_t>(a.data() + 3, 6));
  REQUIRE(framer.next(out, n) == Status::ok);
  CHECK(Bytes(out.begin(), out.begin() + static_cast<long>(n)) == Bytes{1, 2, 3, 4});
  REQUIRE(framer.next(out, n) == Status::ok);
  CHECK(Bytes(out.begin(), out.begin() + static_cast<long>(n)) == Bytes{5, 6, 7, 8});
  CHECK(framer.next(out, n) == Status::no_data);
  CHECK(framer.pending() == 1);
  CHECK(framer.drop_pending() == 1);
  CHECK(framer.counters().skipped == 11);
  CHECK_FALSE(framer.set_frame_size(257));  // over half the capacity
  CHECK(framer.frame_size() == 4);
  REQUIRE(framer.set_frame_size(25));
  framer.push(Bytes(60, 0x33));
  CHECK(framer.next(out, n) == Status::ok);
  CHECK(n == 25);
  std::array<std::uint8_t, 8> small{};
  CHECK(framer.next(small, n) == Status::no_data);  // a frame larger than the caller's buffer is dropped
  CHECK(framer.counters().overflow == 25);
}

TEST_CASE("inverse3: ServoLoop through a pty against the simulated device, in the configured frame") {
  Rig rig;
  CHECK(rig.arm.identity().device_id == 0x1234);
  CHECK(rig.arm.identity().model == 3);
  CHECK(rig.arm.identity().firmware_version == 7);
  CHECK(rig.arm.info().max_force == 3.0);
  Constant field{{0.0, 0.8, 0.0}};  // ours: up, which is the device's +z in the test frame
  CHECK(rig.loop.run(field, {.max_ticks = 600}) == StopReason::tick_limit);
  DeviceState last;
  REQUIRE(rig.arm.read(last) == Status::ok);  // the reply to the loop's last request
  CHECK(rig.arm.outstanding() == 0);
  rig.device_thread.stop();
  const SimulatedInverse3& sim = rig.device_thread.sim();
  CHECK(sim.counters().wakes == 1);
  CHECK(sim.counters().forces >= 601);
  CHECK(sim.peak_force().x == 0.0);
  CHECK(sim.peak_force().y == 0.0);
  CHECK_THAT(sim.peak_force().z, WithinAbs(0.8, 1e-6));  // ours -> device through R^T
  CHECK(sim.force() == glm::dvec3{0.0});                 // the loop's stop sent zero last
  CHECK(sim.position().z > 0.06);                        // the force moved the handle along device +z
  const glm::dvec3 expected = test_frame().position_to_ours(glm::dvec3(glm::vec3(sim.position())));
  CHECK(glm::length(last.position - expected) < 1e-9);
  CHECK(last.position.y > 0.01);  // ours: up
  CHECK(glm::length(last.velocity - test_frame().vector_to_ours(glm::dvec3(glm::vec3(sim.velocity())))) < 1e-9);
  const Inverse3Counters& c = rig.arm.counters();
  CHECK(c.implausible == 0);
  CHECK(c.resyncs == 0);
  CHECK(c.unexpected == 0);
  CHECK(c.lost_replies == 0);
  CHECK(c.headers[0x0B] == 1);          // the wake-up reply's header, counted by value
  CHECK(c.headers[0x2B] == c.replies);  // every state reply's
  CHECK(c.replies == sim.counters().forces);
  CHECK(rig.loop.safety().latched() == 0);
  CHECK_THAT(rig.loop.statistics().peak_force, WithinAbs(0.8, 1e-12));
}

TEST_CASE("inverse3: no heap allocation per servo tick") {
  if (!test::allocations_counted) return;
  Rig rig;
  Constant field{{0.0, 0.3, 0.0}};
  rig.loop.run(field, {.max_ticks = 100});
  const long n = test::count_allocations([&] { rig.loop.run(field, {.max_ticks = 500}); });
  CHECK(n == 0);
}

TEST_CASE("inverse3: zero force when disarmed, for a non-finite force, and the clamp") {
  Rig rig;
  DeviceState s;
  const auto sent = [&](const glm::dvec3& f) {
    CHECK(rig.arm.write(f) == Status::ok);
    return rig.arm.last_device_force();
  };
  CHECK(sent({0.0, 1.0, 0.0}) == glm::dvec3{0.0});  // not armed yet
  CHECK(rig.arm.set_armed(true) == Status::ok);
  CHECK(sent({0.0, 1.0, 0.0}) == glm::dvec3{0.0, 0.0, 1.0});
  CHECK(sent({NAN, 1.0, 0.0}) == glm::dvec3{0.0});
  CHECK(sent({0.0, INFINITY, 0.0}) == glm::dvec3{0.0});
  const glm::dvec3 big = sent({0.0, 0.0, -30.0});  // clamped to 3 N, direction kept
  CHECK(big == glm::dvec3{0.0, 3.0, 0.0});
  CHECK(rig.arm.set_armed(false) == Status::ok);  // sends a zero at once
  CHECK(rig.arm.last_device_force() == glm::dvec3{0.0});
  CHECK(sent({0.0, 1.0, 0.0}) == glm::dvec3{0.0});
  for (int i = 0; i < 50 && rig.arm.outstanding() > 0; ++i)
    (void)rig.arm.read(s);
  CHECK(rig.arm.outstanding() == 0);
  rig.device_thread.stop();
  CHECK(rig.device_thread.sim().force() == glm::dvec3{0.0});  // the last request the device served
  CHECK(rig.device_thread.sim().counters().forces == 8);      // 1 at setup + 7 here
}

TEST_CASE("inverse3: joint torques (0x1A) come back as joint angles, in radians") {
  Rig rig;
  DeviceState s;
  (void)rig.arm.read(s);
  const glm::dvec3 p0 = s.position;
  CHECK(rig.arm.set_armed(true) == Status::ok);
  for (int i = 0; i < 20; ++i) {
    CHECK(rig.arm.write_joint_torques({10.0, -5.0, 1e9}) == Status::ok);  // the last is clamped to 100 N mm
    const Status st = rig.arm.read(s);
    CHECK((st == Status::no_data || st == Status::ok));
  }
  CHECK(rig.arm.write_joint_torques({NAN, 1.0, 1.0}) == Status::ok);  // a non-finite torque: all zero
  for (int i = 0; i < 50 && rig.arm.outstanding() > 0; ++i)
    (void)rig.arm.read(s);
  rig.arm.set_armed(false);
  for (int i = 0; i < 50 && rig.arm.outstanding() > 0; ++i)
    (void)rig.arm.read(s);
  rig.device_thread.stop();
  const SimulatedInverse3& sim = rig.device_thread.sim();
  CHECK(sim.counters().torques == 21);
  CHECK(sim.torque() == glm::dvec3{0.0});
  constexpr double rad = 3.14159265358979323846 / 180.0;
  for (int i = 0; i < 3; ++i) {
    CHECK_THAT(s.joint_angles[i],
               WithinAbs(static_cast<double>(static_cast<float>(sim.joint_angles_deg()[i])) * rad, 1e-9));
  }
  CHECK(s.joint_angles.x > 0.0);
  CHECK(s.joint_angles.y < 0.0);
  CHECK(s.position == p0);  // joint replies leave the end-effector state alone
  CHECK(rig.arm.counters().headers[0x1B] == 21);
  CHECK(rig.arm.counters().implausible == 0);
}

TEST_CASE("inverse3: unplug (the other side closes) is disconnected and zero force") {
  Rig rig;
  Constant field{{0.0, 0.8, 0.0}};
  std::uint64_t tick = 0;
  auto cb = [&](const TickInput& in) {
    if (++tick == 300) rig.device_thread.unplug();
    return field.force(in.probe);
  };
  CHECK(rig.loop.run(cb, {.max_ticks = 2000}) == StopReason::disconnected);
  CHECK(tick < 320);
  CHECK(rig.serial.disconnected());
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});
  CHECK((rig.loop.safety().latched() & safety_events::disconnected) != 0);
  DeviceState s;
  CHECK(rig.arm.read(s) == Status::disconnected);
  CHECK(rig.arm.write({0.0, 1.0, 0.0}) == Status::disconnected);
}

TEST_CASE("inverse3: a device that never answers the wake-up is a clear error within the bound") {
  Pty pty;  // nobody on the master side
  SerialTransport serial(pty.path, fixed_framing());
  Inverse3Config c;
  c.wake_attempts = 2;
  c.reply_timeout_us = 50'000;
  const auto t0 = std::chrono::steady_clock::now();
  std::string what = "no error";
  try {
    Inverse3 arm(serial, c);
  } catch (const Error& e) {
    what = e.what();
  }
  const auto took = std::chrono::steady_clock::now() - t0;
  CHECK(what.find("no reply to the wake-up (0x0A)") != std::string::npos);
  CHECK(what.find(pty.path) != std::string::npos);  // names the port
  CHECK(took >= 100ms);
  CHECK(took < 10s);  // a hang guard
  // The device wrote 0x0A twice and nothing else.
  std::array<std::uint8_t, 16> rx{};
  CHECK(::read(pty.master, rx.data(), rx.size()) == 2);
  CHECK(rx[0] == 0x0A);
  CHECK(rx[1] == 0x0A);
}

TEST_CASE("inverse3: a short wake-up reply is dropped when the wait ends mid-frame") {
  Pty pty;
  SerialTransport serial(pty.path, fixed_framing());
  const Bytes partial(10, 0x42);
  pty.write_master(partial);  // bytes before the wake-up are dropped too
  std::thread answer([&] {
    // Answer every wake-up with only 10 of its 22 bytes.
    pollfd p{pty.master, POLLIN, 0};
    std::array<std::uint8_t, 16> rx{};
    for (int answered = 0; answered < 2;) {
      if (::poll(&p, 1, 2000) <= 0) return;
      const ssize_t n = ::read(pty.master, rx.data(), rx.size());
      for (ssize_t i = 0; i < n; ++i, ++answered)
        (void)!::write(pty.master, partial.data(), partial.size());
    }
  });
  Inverse3Config c;
  c.wake_attempts = 2;
  c.reply_timeout_us = 100'000;
  c.port = "the test port";
  std::string what = "no error";
  try {
    Inverse3 arm(serial, c);
  } catch (const Error& e) {
    what = e.what();
  }
  answer.join();
  CHECK(what.find("the test port") != std::string::npos);
  CHECK(serial.framer_counters().skipped >= 20);  // two partial frames dropped
  CHECK(serial.framer_counters().frames == 0);
}

TEST_CASE("inverse3: a transport without fixed framing is refused at construction") {
  Pty pty;
  SerialConfig lines;
  lines.framing = Framing::lines;
  SerialTransport serial(pty.path, lines);
  CHECK_THROWS_AS(Inverse3(serial), std::invalid_argument);
  SerialTransport fixed(pty.path, fixed_framing());
  CHECK(fixed.set_frame_size(0) == Status::bad_value);
  CHECK(fixed.set_frame_size(513) == Status::bad_value);
  CHECK(fixed.set_frame_size(25) == Status::ok);
  CHECK(serial.set_frame_size(25) == Status::unsupported);
}

TEST_CASE("inverse3: garbage bytes before a reply cost one state, then the stream is back in line") {
  Rig rig(300);  // 7 x 0xFF before reply 300
  Constant field{{0.0, 0.5, 0.0}};
  CHECK(rig.loop.run(field, {.max_ticks = 600}) == StopReason::tick_limit);
  DeviceState last;
  REQUIRE(rig.arm.read(last) == Status::ok);
  rig.device_thread.stop();
  const Inverse3Counters& c = rig.arm.counters();
  CHECK(c.implausible == 1);  // the misaligned frame: it starts with 0xFF x 4, a NaN
  CHECK(c.resyncs == 1);
  CHECK(c.dropped_bytes == 7);  // the tail of the reply it swallowed
  CHECK(c.replies + c.implausible == rig.device_thread.sim().counters().forces);
  const SimulatedInverse3& sim = rig.device_thread.sim();
  CHECK(glm::length(last.position - test_frame().position_to_ours(glm::dvec3(glm::vec3(sim.position())))) < 1e-9);
  CHECK(rig.loop.safety().latched() == 0);
}

TEST_CASE("inverse3: a device that stops answering: replies given up on after max_outstanding, no crash") {
  Pty pty;
  PtyInverse3 device_thread(pty, -1, 40);  // the wake-up, the first state, then 38 more replies
  SerialTransport serial(pty.path, fixed_framing());
  Inverse3Config c;
  c.reply_timeout_us = 2'000'000;
  Inverse3 arm(serial, c);
  DeviceState s;
  CHECK(arm.set_armed(true) == Status::ok);
  int fresh = 0;
  std::size_t most = 0;
  for (int i = 0; i < 150; ++i) {
    CHECK(arm.write({0.0, 0.2, 0.0}) == Status::ok);
    std::this_thread::sleep_for(1ms);
    if (arm.read(s) == Status::ok) ++fresh;
    most = std::max(most, arm.outstanding());
  }
  CHECK(fresh >= 1);
  CHECK(fresh <= 40);
  CHECK(most <= 16);
  CHECK(arm.counters().lost_replies >= 80);
  CHECK(arm.counters().implausible == 0);
}

TEST_CASE("inverse3: replies cut short are never re-assembled into a pose: no force in a wrong direction, a latch") {
  // The reply of one request loses its tail on the wire; fixed-size framing
  // would glue the next reply's head onto it and misalign every later frame.
  for (const std::size_t keep : {std::size_t{12}, std::size_t{1}, std::size_t{13}, std::size_t{24}}) {
    INFO("reply cut to " << keep << " of 25 bytes");
    SimulatedInverse3 sim;
    SimulatedInverse3Transport link(sim);
    VirtualClock clock;
    Inverse3Config c;
    c.now = [&clock] { return clock.now(); };
    Inverse3 arm(link, c);  // identity frame: ours = the device's
    ServoLoop<Inverse3, VirtualClock> loop(arm, clock, quiet());
    link.truncate_replies(400, keep);
    const glm::dvec3 target{0.05, 0.1, 0.05};  // 5 cm from the start along x [m]
    const auto spring = [&target](const glm::dvec3& p) { return 40.0 * (target - p); };
    std::vector<glm::dvec3> expected, commands;  // per tick: the field at the true pose, the command sent
    std::vector<std::uint64_t> truncated;
    std::vector<Status> reads;
    expected.reserve(1000);
    commands.reserve(1000);
    truncated.reserve(1000);
    reads.reserve(1000);
    auto cb = [&](const TickInput& in) {
      if (!expected.empty()) commands.push_back(loop.last_command());
      expected.push_back(spring(sim.position()));  // the pose the last reply should have carried
      truncated.push_back(link.truncated());
      reads.push_back(in.read_status);
      return spring(in.probe.position);
    };
    loop.run(cb, {.max_ticks = 800});
    commands.push_back(loop.last_command());
    REQUIRE(commands.size() == expected.size());
    const auto cut = static_cast<std::size_t>(std::find(truncated.begin(), truncated.end(), 1u) - truncated.begin());
    REQUIRE(cut < truncated.size());
    int wrong = 0, nonzero_after = 0;
    for (std::size_t i = 0; i < commands.size(); ++i) {
      const double f = glm::length(commands[i]), e = glm::length(expected[i]);
      if (f == 0.0 || e < 0.1) continue;
      if (glm::dot(commands[i], expected[i]) < std::cos(0.25 * 3.14159265358979) * f * e) ++wrong;  // > 45 deg off
      if (i > cut) ++nonzero_after;
    }
    CHECK(wrong == 0);
    // Within a few ticks the loop knew: a latch (impossible motion) or a
    // resynchronisation (zero force that tick), and it says which.
    const auto noticed = std::find_if(reads.begin() + static_cast<long>(cut), reads.end(),
                                      [](Status s) { return s == Status::impossible || s == Status::resync; });
    REQUIRE(noticed != reads.end());
    CHECK(noticed - reads.begin() <= static_cast<long>(cut) + 4);
    const Inverse3Counters& n = arm.counters();
    CHECK(n.impossible + n.wrong_header + n.implausible >= 1);
    CHECK(n.resyncs >= 1);
    if (keep == 12) {  // the header byte is right, the position jumps: latched, and named
      CHECK(n.impossible >= 1);
      CHECK(loop.statistics().last_latch == safety_events::impossible_state);
      CHECK(nonzero_after == 0);
    }
  }
}
