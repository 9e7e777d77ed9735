// Tests of SerialTransport through a real pseudo-terminal: the reference
// firmware core (SimulatedArm, the firmware twin) answers on the master side in a thread,
// stepped to the servo loop's virtual clock; ForceArm and ServoLoop run on
// the slave side. Every blocking wait has a hard timeout.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/arms.hpp"
#include "hapticfield/firmware/stream_port.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/transport.hpp"
#include "hapticfield/transport/serial_transport.hpp"
#include "pty_pair.hpp"
#include "test_fields.hpp"

using namespace hapticfield;
using testing::Constant;

namespace {

using namespace std::chrono_literals;
constexpr auto hard_timeout = 5s;  // no wait in these tests lasts longer

using testing::Pty;

/// The firmware on the master side of the pty, in its own thread: it serves
/// feature requests as they come and runs firmware ticks up to a target the
/// host sets from its virtual clock (so the run is repeatable).
class PtyFirmware {
 public:
  PtyFirmware(Pty& pty, const SimulatedArmConfig& arm) : pty_(pty), arm_(arm, 5000) {
    REQUIRE(::pipe(wake_) == 0);
    thread_ = std::thread([this] { run(); });
  }
  ~PtyFirmware() {
    stop();
    ::close(wake_[0]);
    ::close(wake_[1]);
  }
  void stop() {
    if (!thread_.joinable()) return;
    stop_.store(true);
    wake();
    thread_.join();
  }
  [[nodiscard]] bool running() const { return thread_.joinable(); }

  /// Runs the firmware up to tick `target` and waits for it (hard timeout).
  bool advance_to(std::int64_t target) {
    if (!running() || target <= target_.load()) return true;
    target_.store(target, std::memory_order_release);
    wake();
    const auto deadline = std::chrono::steady_clock::now() + hard_timeout;
    while (done_.load(std::memory_order_acquire) < target)
      if (std::chrono::steady_clock::now() > deadline)
        return false;
      else
        std::this_thread::yield();
    return true;
  }

  // Stream faults made by the firmware side, set before the run.
  std::int64_t garbage_at{-1};  ///< garbage bytes before the report of this tick
  std::int64_t split_at{-1};    ///< the report of this tick goes out in two writes, one tick apart
  static constexpr std::array<std::uint8_t, 7> garbage{0x01, 0x10, 0xFF, 0x02, 0x00, 0x7E, 0x13};

  SimulatedArm& arm() { return arm_; }  // only once stopped, or between advance_to() calls
  const firmware::StreamPort<256>& port() const { return port_; }

 private:
  void wake() const {
    const char c = 1;
    (void)!::write(wake_[1], &c, 1);
  }

  void send(std::span<const std::uint8_t> b) {
    if (pty_.master >= 0) (void)!::write(pty_.master, b.data(), b.size());
  }

  void run() {
    std::array<std::uint8_t, 256> rx{};
    std::array<std::uint8_t, protocol::max_report_size> rest{};
    std::size_t rest_size = 0;
    while (!stop_.load()) {
      pollfd p[2] = {{pty_.master, POLLIN, 0}, {wake_[0], POLLIN, 0}};
      ::poll(p, 2, 100);
      char sink[64];
      while (p[1].revents & POLLIN && ::read(wake_[0], sink, sizeof sink) == static_cast<ssize_t>(sizeof sink)) {
      }
      const std::int64_t target = target_.load(std::memory_order_acquire);
      for (;;) {  // every byte the host wrote before setting the target
        const ssize_t n = ::read(pty_.master, rx.data(), rx.size());
        if (n <= 0) break;
        port_.feed(std::span<const std::uint8_t>(rx.data(), static_cast<std::size_t>(n)));
      }
      port_.service(arm_.core(), [this](std::span<const std::uint8_t> reply) { send(reply); });
      while (arm_.ticks() < target) {
        arm_.tick();
        const std::int64_t k = arm_.ticks();
        if (rest_size) {
          send(std::span<const std::uint8_t>(rest.data(), rest_size));
          rest_size = 0;
        }
        if (k == garbage_at) send(garbage);
        const std::span<const std::uint8_t> report = arm_.core().report();
        if (k == split_at) {
          send(report.first(10));
          rest_size = report.size() - 10;
          std::memcpy(rest.data(), report.data() + 10, rest_size);
        } else {
          send(report);
        }
      }
      done_.store(arm_.ticks(), std::memory_order_release);
    }
  }

  Pty& pty_;
  SimulatedArm arm_;
  firmware::StreamPort<256> port_;
  int wake_[2]{-1, -1};
  std::atomic<std::int64_t> target_{0};
  std::atomic<std::int64_t> done_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// SerialTransport that first lets the firmware catch up with the virtual clock.
class SteppedSerial final : public Transport {
 public:
  SteppedSerial(SerialTransport& serial, PtyFirmware& fw, VirtualClock& clock)
      : serial_(serial), fw_(fw), clock_(clock), start_(clock.now() + 500'000) {}
  Status read(std::span<std::uint8_t> b, std::size_t& n, int t) noexcept override {
    const std::int64_t due = clock_.now() >= start_ ? (clock_.now() - start_) / 1'000'000 + 1 : 0;
    if (!fw_.advance_to(due)) {
      stuck_ = true;
      return Status::timeout;
    }
    return serial_.read(b, n, t);
  }
  Status write(std::span<const std::uint8_t> r) noexcept override { return serial_.write(r); }
  Status get_feature(std::span<std::uint8_t> b, std::size_t& n) noexcept override { return serial_.get_feature(b, n); }
  Status send_feature(std::span<const std::uint8_t> r) noexcept override { return serial_.send_feature(r); }
  bool stuck_{false};

 private:
  SerialTransport& serial_;
  PtyFirmware& fw_;
  VirtualClock& clock_;
  std::int64_t start_;
};

SimulatedArmConfig free_arm() {
  SimulatedArmConfig c;
  c.hand.holding = false;
  return c;
}

SerialConfig test_serial() {
  SerialConfig c;
  c.feature_timeout_us = 2'000'000;  // a loaded machine may take long to schedule the firmware thread
  return c;
}

/// Everything on one virtual clock: pty, firmware thread, serial transport, ForceArm, loop.
struct Rig {
  Pty pty;
  VirtualClock clock;
  PtyFirmware fw{pty, free_arm()};
  SerialTransport serial{pty.path, test_serial()};
  SteppedSerial link{serial, fw, clock};
  ForceArm device{link};
  ServoLoop<ForceArm, VirtualClock> loop{device, clock, quiet()};
  static LoopConfig quiet() {
    LoopConfig c;
    c.realtime = RealTime::off;
    return c;
  }
};

}  // namespace

TEST_CASE("serial: ForceArm over a pty drives the firmware core; garbage and split frames are survived") {
  Rig rig;
  rig.fw.garbage_at = 300;
  rig.fw.split_at = 400;
  CHECK(rig.device.info().nominal_rate == 1000.0);  // device info came through the in-band feature request
  CHECK(rig.device.configure_watchdog(0.008) == Status::ok);
  Constant field{{0.0, 0.8, 0.0}};
  CHECK(rig.loop.run(field, {.max_ticks = 800}) == StopReason::tick_limit);
  CHECK_FALSE(rig.link.stuck_);
  rig.fw.stop();
  CHECK(rig.fw.arm().core().homed());
  CHECK(rig.fw.arm().core().watchdog_us() == 8000);
  CHECK(rig.fw.arm().core().counters().commands >= 790);
  CHECK(rig.fw.arm().plant().q().y > 0.02);  // the force moved the arm
  CHECK(rig.serial.framer_counters().skipped == PtyFirmware::garbage.size());
  const LinkCounters& c = rig.device.counters();
  CHECK(c.corrupt == 0);
  CHECK(c.dropped == 0);
  CHECK(rig.loop.safety().latched() == 0);
  CHECK_THAT(rig.loop.statistics().peak_force, Catch::Matchers::WithinAbs(0.8, 1e-12));
}

TEST_CASE("serial: unplug (the other side closes) is disconnected and zero force") {
  Rig rig;
  Constant field{{0.0, 0.8, 0.0}};
  std::uint64_t tick = 0;
  auto cb = [&](const TickInput& in) {
    if (++tick == 400) {
      rig.fw.stop();
      rig.pty.close_master();
    }
    return field.force(in.probe);
  };
  CHECK(rig.loop.run(cb, {.max_ticks = 800}) == StopReason::disconnected);
  CHECK(tick < 405);
  CHECK(rig.serial.disconnected());
  CHECK(rig.loop.last_command() == glm::dvec3{0.0});
  CHECK((rig.loop.safety().latched() & safety_events::disconnected) != 0);
  std::array<std::uint8_t, 64> b{};
  std::size_t n = 0;
  CHECK(rig.serial.read(b, n, 0) == Status::disconnected);
  CHECK(rig.serial.write(std::span<const std::uint8_t>(b.data(), 16)) == Status::disconnected);
  b[0] = 0x10;
  CHECK(rig.serial.get_feature(b, n) == Status::disconnected);
}

TEST_CASE("serial: a set feature refused by the firmware returns its status; clear_fault only while disarmed") {
  Rig rig;
  CHECK(rig.device.control(protocol::ControlOp::arm) == Status::not_homed);
  CHECK(rig.device.configure_watchdog(0.0005) == Status::bad_value);  // below one period: refused by the device
  CHECK(rig.device.clear_fault() == Status::ok);
}

TEST_CASE("serial: no heap allocation per servo tick") {
  if (!test::allocations_counted) return;
  Rig rig;
  Constant field{{0.0, 0.3, 0.0}};
  rig.loop.run(field, {.max_ticks = 100});
  const long n = test::count_allocations([&] { rig.loop.run(field, {.max_ticks = 500}); });
  CHECK(n == 0);
}

TEST_CASE("serial: a feature request nobody answers times out within the bound") {
  Pty pty;
  SerialConfig c;
  c.feature_timeout_us = 50'000;
  SerialTransport serial(pty.path, c);
  std::array<std::uint8_t, 64> b{};
  b[0] = 0x10;
  std::size_t n = 0;
  const auto t0 = std::chrono::steady_clock::now();
  CHECK(serial.get_feature(b, n) == Status::timeout);
  CHECK(std::chrono::steady_clock::now() - t0 < hard_timeout);
}

TEST_CASE("serial: a ForceArm whose device never answers the device-info request names the port") {
  Pty pty;  // nobody on the master side
  SerialConfig c;
  c.feature_timeout_us = 50'000;
  SerialTransport serial(pty.path, c);
  std::string what = "no error";
  try {
    ForceArm arm(serial);
  } catch (const std::exception& e) {
    what = e.what();
  }
  CHECK(what == "ForceArm: reading the device-info feature report from " + pty.path + " failed: timeout");
}

TEST_CASE("serial: line framing returns text lines, strips NUL padding, drops over-long lines") {
  Pty pty;
  SerialConfig c;
  c.framing = Framing::lines;
  c.max_line = 32;
  SerialTransport serial(pty.path, c);
  std::array<std::uint8_t, 64> b{};
  std::size_t n = 0;
  const auto line = [&]() -> std::string {
    const auto deadline = std::chrono::steady_clock::now() + hard_timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      const Status s = serial.read(b, n, 1000);
      if (s == Status::ok) return std::string(reinterpret_cast<const char*>(b.data()), n);
      if (s != Status::no_data) return "<" + std::string(to_string(s)) + ">";
    }
    return "<timeout>";
  };
  pty.write_master(std::string("[3,1000,-2000,300,0,0,0,0]\n"));
  CHECK(line() == "[3,1000,-2000,300,0,0,0,0]");
  pty.write_master(std::string("[1,2,", 5));  // a partial line waits
  CHECK(serial.read(b, n, 0) == Status::no_data);
  pty.write_master(std::string("3]\n\0\0\0", 6));
  CHECK(line() == "[1,2,3]");
  pty.write_master(std::string(40, 'x') + "\nok\n");
  CHECK(line() == "ok");
  CHECK(serial.framer_counters().overflow >= 40);
  CHECK(serial.get_feature(b, n) == Status::unsupported);
  pty.close_master();
  CHECK(line() == "<disconnected>");
}

TEST_CASE("serial: opening errors name the path") {
  const auto message = [](const std::string& path) {
    try {
      SerialTransport s(path);
    } catch (const DeviceError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string missing = "/dev/hapticfield-no-such-port";
  CHECK(message(missing).find(missing) != std::string::npos);
  CHECK(message(missing).find("no serial port") != std::string::npos);
  std::filesystem::create_directories(HAPTICFIELD_TEST_TMP);
  const std::string file = std::string(HAPTICFIELD_TEST_TMP) + "/not_a_tty";
  std::ofstream(file) << "x";
  CHECK(message(file).find("not a serial port") != std::string::npos);
  CHECK(message(file).find(file) != std::string::npos);
  Pty pty;
  SerialConfig c;
  c.baud = 12345;
  CHECK_THROWS_AS(SerialTransport(pty.path, c), std::invalid_argument);
}

TEST_CASE("serial: a WoodenHaptics P4 arm over a pty, through line framing, with the simulated P4 firmware") {
  Pty pty;
  SimulatedWoodyConfig sc;
  sc.generation = woody::Generation::p4_text;
  sc.hand.holding = false;
  SimulatedWoody firmware(sc);
  std::atomic<bool> stop{false};
  std::atomic<int> replies{0};
  // The P4 firmware on the master side: one reply per '\n'-terminated frame
  // (NUL padding ignored), the arm's mechanics stepping one tick per frame.
  std::thread peer([&] {
    std::string line;
    std::array<char, 256> rx{};
    const auto give_up = std::chrono::steady_clock::now() + 12 * hard_timeout;  // the whole test, on a loaded machine
    while (!stop.load() && std::chrono::steady_clock::now() < give_up) {
      pollfd p{pty.master, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      const ssize_t n = ::read(pty.master, rx.data(), rx.size());
      for (ssize_t i = 0; i < n; ++i) {
        const char c = rx[static_cast<std::size_t>(i)];
        if (c == '\0') continue;
        if (c != '\n') {
          line += c;
          continue;
        }
        firmware.tick();  // the frame without its '\n', as the firmware's parser sees it
        const woody::P4Reply r = firmware.receive_p4(
            std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(line.data()), line.size()));
        std::array<std::uint8_t, woody::p4_max_line> out{};
        pty.write_master(std::span<const std::uint8_t>(out.data(), woody::encode(r, out)));
        line.clear();
        ++replies;
      }
    }
  });
  struct JoinOnExit {
    std::atomic<bool>& stop;
    std::thread& peer;
    ~JoinOnExit() {
      stop.store(true);
      if (peer.joinable()) peer.join();
    }
  } join_on_exit{stop, peer};
  {
    SerialConfig config;
    config.framing = Framing::lines;
    SerialTransport serial(pty.path, config);
    WoodyArmConfig wc = WoodyArmConfig::defaults(woody::Generation::p4_text);
    wc.wake_timeout_us = 1000000;  // the peer thread may be slow to get the processor on a loaded machine
    WoodyArm arm(serial, wc);      // the wake-up: zero frames until the first reply
    DeviceState s;
    // Lock-step: each command gets one reply; wait for it (bounded), however
    // slowly the peer thread is scheduled.
    const auto exchange = [&] {
      arm.write(glm::dvec3{0.0});
      const auto give_up = std::chrono::steady_clock::now() + hard_timeout;
      while (std::chrono::steady_clock::now() < give_up) {
        if (arm.read(s) == Status::ok) return true;
        std::this_thread::sleep_for(200us);
      }
      return false;
    };
    int fresh = 0;
    for (int i = 0; i < 50; ++i)
      fresh += exchange() ? 1 : 0;
    CHECK(fresh == 50);
    CHECK(s.valid);
    CHECK(arm.counters().error_replies == 0);
    CHECK(arm.counters().malformed == 0);
    // The position the host computes from the P4 encoders is the simulated arm's own.
    CHECK(glm::length(s.position - firmware.position()) < 1e-3);
    // A malformed frame written by hand gets an error reply, which the host counts.
    serial.write(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>("[1,2]\n"), 6));
    const auto give_up = std::chrono::steady_clock::now() + hard_timeout;
    while (arm.counters().error_replies == 0 && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(200us);
      (void)arm.read(s);
    }
    CHECK(arm.counters().error_replies == 1);
    CHECK((arm.last_error() & woody::p4_error::comma_count) != 0);
  }
  stop.store(true);
  peer.join();
  CHECK(replies.load() >= 50);
}
