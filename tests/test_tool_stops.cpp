// Ctrl-C and SIGTERM on the tools that drive an arm: the tool stops through
// the loop's stop (zero force, then disarm) and exits 128 + the signal.
//
// The arms on a serial line (our protocol, WoodenHaptics P4, Inverse3) are
// played by their simulated firmware on the master side of a pseudo-terminal
// in this process; the tool runs as a child on the slave side. Once the arm
// is armed and pushing, the child gets SIGINT, and what the firmware last
// received must be zero force, disarmed. The tools that run simulated arms
// inside themselves are checked by their exit status and their report.
//
// Real time, on a possibly loaded machine: every wait is bounded generously
// (tens of seconds) and nothing here asserts how fast anything happens.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#ifdef HAPTICFIELD_TOOL_TANGIBLE_VIDEO
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#endif

#include "child_process.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/arms/inverse3/simulated_inverse3.hpp"
#include "hapticfield/arms/woody/simulated_woody.hpp"
#include "hapticfield/arms/woody/woody_codec.hpp"
#include "hapticfield/firmware/stream_port.hpp"
#include "pty_pair.hpp"

using namespace hapticfield;
using testing::Child;
namespace fs = std::filesystem;

namespace {

using namespace std::chrono_literals;
constexpr auto patience = 60s;  // the longest any wait here may take, on a loaded machine

const fs::path tmp = fs::path(HAPTICFIELD_TEST_TMP) / "tool_stops";

/// A simulated arm's firmware on the master side of a pty, in its own thread
/// at real-time priority where granted (root): `serve` gets the bytes the
/// host wrote and answers on the pty. It publishes what the tests wait for
/// through atomics (no lock the main thread could hold while preempted);
/// after stop() the main thread reads the firmware directly.
class PtyPeer {
 public:
  using Serve = std::function<void(std::span<const std::uint8_t>, int master)>;
  PtyPeer(testing::Pty& pty, Serve serve) : pty_(pty), serve_(std::move(serve)), thread_([this] { run(); }) {}
  ~PtyPeer() { stop(); }
  void stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  /// Waits until pred holds (it reads atomics the peer sets); false after `patience`.
  static bool wait_for(const std::function<bool()>& pred) {
    const auto give_up = std::chrono::steady_clock::now() + patience;
    while (std::chrono::steady_clock::now() < give_up) {
      if (pred()) return true;
      std::this_thread::sleep_for(2ms);
    }
    return false;
  }

 private:
  void run() {
    sched_param sp{};
    sp.sched_priority = 70;
    (void)pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    std::array<std::uint8_t, 512> rx{};
    while (!stop_.load()) {
      pollfd p{pty_.master, POLLIN, 0};
      (void)::poll(&p, 1, 5);
      for (;;) {
        const ssize_t n = ::read(pty_.master, rx.data(), rx.size());
        if (n <= 0) break;
        serve_(std::span<const std::uint8_t>(rx.data(), static_cast<std::size_t>(n)), pty_.master);
      }
    }
  }

  testing::Pty& pty_;
  Serve serve_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

void send(int master, std::span<const std::uint8_t> bytes) {
  (void)!::write(master, bytes.data(), bytes.size());
}

/// Our protocol's firmware core on the simulated arm, paced by the host: one
/// firmware period and one state report per command received, so the host
/// sees a fresh state every tick however this machine schedules the peer.
struct OurArm {
  explicit OurArm(const SimulatedArmConfig& config) : arm(config, 50000) {}  // a 50 ms firmware watchdog
  void serve(std::span<const std::uint8_t> bytes, int master) {
    port.feed(bytes);
    port.service(arm.core(), [master](std::span<const std::uint8_t> r) { send(master, r); });
    while (stepped < arm.core().counters().commands) {
      ++stepped;
      arm.tick();
      send(master, arm.core().report());
    }
    const protocol::CommandReport& c = arm.core().last_command();
    armed.store(arm.core().armed());
    pushing.store(arm.core().armed() && (c.flags & protocol::command_flags::arm) &&
                  (c.torque_mnm[0] != 0 || c.torque_mnm[1] != 0 || c.torque_mnm[2] != 0));
    commands.store(arm.core().counters().commands);
  }
  SimulatedArm arm;
  firmware::StreamPort<256> port;
  std::uint32_t stepped{0};
  std::atomic<bool> armed{false}, pushing{false};
  std::atomic<std::uint32_t> commands{0};
};

/// servo_demo with a centring spring, for a long time, on a serial device,
/// with real-time scheduling as by default (granted to root): with it off, a
/// busy machine wakes the loop late three times in a row, the watchdog
/// latches, and the arm never pushes. At 250 Hz: on a busy 2-core machine a
/// 1 kHz loop over a pty (each byte through a kernel worker) was late about
/// four times a second, so once a stall had latched it, it never saw the
/// 0.5 s of on-time ticks its recovery needs; these tests are about the stop.
std::vector<std::string> demo_args(const std::string& device) {
  return {"--field", "spring", "--seconds", "3000", "--rate", "250", "--realtime", "best_effort", "--device", device};
}

/// The checks every signalled tool passes: it exited by itself, 128 + the
/// signal, and said it stopped through the loop.
void check_stopped(Child& child, int signal) {
  CAPTURE(child.out(), child.err());
  REQUIRE(child.wait());
  CHECK(child.killed_by() == 0);
  CHECK(child.exited_normally());
  CHECK(child.status() == 128 + signal);
  CHECK(child.out().find("stopped by signal " + std::to_string(signal)) != std::string::npos);
}

/// A hand holding the handle 25 mm right of the centre: the spring pushes back.
Hand offset_hand() {
  Hand h;
  h.path = HandPath::hold({0.025, 0.0, 0.0});
  return h;
}

}  // namespace

TEST_CASE("Ctrl-C on servo_demo over our protocol on a pty: the last command is zero force, disarmed") {
  for (const int signal : {SIGINT, SIGTERM}) {
    CAPTURE(signal);
    testing::Pty pty;
    SimulatedArmConfig arm_config;
    arm_config.hand = offset_hand();
    OurArm ours(arm_config);
    PtyPeer peer(pty, [&](std::span<const std::uint8_t> bytes, int master) { ours.serve(bytes, master); });
    Child tool(HAPTICFIELD_TOOL_SERVO_DEMO, demo_args("serial:" + pty.path), tmp, "ours");
    const bool ready = PtyPeer::wait_for([&] { return ours.pushing.load(); });
    INFO(tool.out() << tool.err());
    REQUIRE(ready);  // armed, and the spring pushes
    tool.signal(signal);
    check_stopped(tool, signal);
    peer.stop();
    const protocol::CommandReport& last = ours.arm.core().last_command();
    CHECK(last.torque_mnm == std::array<std::int16_t, 3>{0, 0, 0});
    CHECK((last.flags & protocol::command_flags::arm) == 0);
    CHECK_FALSE(ours.arm.core().armed());
    CHECK((ours.arm.core().faults() & status_bits::watchdog_tripped) == 0);  // the host disarmed, not the watchdog
  }
}

TEST_CASE("Ctrl-C on servo_demo with a WoodenHaptics P4 arm on a pty: the last currents are zero") {
  testing::Pty pty;
  SimulatedWoodyConfig sc;
  sc.generation = woody::Generation::p4_text;
  sc.hand = offset_hand();
  SimulatedWoody firmware(sc);
  std::string line;
  std::array<std::int32_t, 3> last_ma{};
  std::atomic<long> nonzero_frames{0};
  PtyPeer peer(pty, [&](std::span<const std::uint8_t> bytes, int master) {
    for (const std::uint8_t c : bytes) {
      if (c == '\0') continue;
      if (c != '\n') {
        line += static_cast<char>(c);
        continue;
      }
      const std::span<const std::uint8_t> frame(reinterpret_cast<const std::uint8_t*>(line.data()), line.size());
      std::array<std::int32_t, 3> ma{};
      if (woody::parse_p4_command(frame, ma) == 0) {
        last_ma = ma;
        if (ma[0] != 0 || ma[1] != 0 || ma[2] != 0) ++nonzero_frames;
      }
      firmware.tick();
      const woody::P4Reply r = firmware.receive_p4(frame);
      std::array<std::uint8_t, woody::p4_max_line> out{};
      send(master, std::span<const std::uint8_t>(out.data(), woody::encode(r, out)));
      line.clear();
    }
  });
  Child tool(HAPTICFIELD_TOOL_SERVO_DEMO, demo_args("woody:p4:" + pty.path), tmp, "p4");
  const bool ready = PtyPeer::wait_for([&] { return nonzero_frames.load() > 50; });
  INFO(tool.out() << tool.err());
  REQUIRE(ready);  // the spring drives the motors
  tool.signal(SIGINT);
  check_stopped(tool, SIGINT);
  peer.stop();
  CHECK(last_ma == std::array<std::int32_t, 3>{0, 0, 0});
  CHECK(firmware.applied_current() == glm::dvec3{0.0});
}

TEST_CASE("Ctrl-C on servo_demo with an Inverse3 on a pty: the last force request is zero") {
  testing::Pty pty;
  SimulatedInverse3 device;
  std::atomic<bool> pushing{false};
  PtyPeer peer(pty, [&](std::span<const std::uint8_t> bytes, int master) {
    device.feed(bytes, [master](std::span<const std::uint8_t> r) { send(master, r); });
    pushing.store(device.counters().forces > 200 && glm::length(device.force()) > 0.1);
  });
  Child tool(HAPTICFIELD_TOOL_SERVO_DEMO, demo_args("inverse3:" + pty.path), tmp, "inverse3");
  const bool ready = PtyPeer::wait_for([&] { return pushing.load(); });
  INFO(tool.out() << tool.err());
  REQUIRE(ready);
  tool.signal(SIGINT);
  check_stopped(tool, SIGINT);
  peer.stop();
  CHECK(device.force() == glm::dvec3{0.0});
}

TEST_CASE("Ctrl-C before the operator's go-ahead: servo_demo exits without a force command") {
  testing::Pty pty;
  OurArm ours(SimulatedArmConfig{});
  PtyPeer peer(pty, [&](std::span<const std::uint8_t> bytes, int master) { ours.serve(bytes, master); });
  Child tool(HAPTICFIELD_TOOL_SERVO_DEMO, demo_args("serial:" + pty.path), tmp, "prompt", false);
  const bool ready = tool.wait_for_output("Press Enter");
  INFO(tool.out() << tool.err());
  REQUIRE(ready);
  tool.signal(SIGINT);
  CAPTURE(tool.out(), tool.err());
  REQUIRE(tool.wait());
  peer.stop();
  REQUIRE(tool.exited_normally());
  CHECK(tool.status() == 130);
  CHECK(tool.out().find("no force was commanded") != std::string::npos);
  CHECK(ours.arm.core().counters().commands == 0);
  CHECK_FALSE(ours.arm.core().armed());
}

TEST_CASE("Ctrl-C on the tools that run a simulated arm: stopped through the loop, exit 130") {
  // Each would run far longer than the test waits; the signal ends it once
  // the tool says its loop runs (`ready`: its handler is in place by then).
  struct Tool {
    std::string name, path;
    std::vector<std::string> args;
    std::string ready;
  };
  std::vector<Tool> tools = {
      {"servo_demo", HAPTICFIELD_TOOL_SERVO_DEMO, {"--seconds", "3000", "--realtime", "off"}, "Hz"},
      {"two_arms", HAPTICFIELD_TOOL_TWO_ARMS, {"--seconds", "60"}, "Ctrl-C stops"},
  };
#ifdef HAPTICFIELD_TOOL_HAPTICFIELD_VIEW
  tools.push_back({"hapticfield_view",
                   HAPTICFIELD_TOOL_HAPTICFIELD_VIEW,
                   {std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png", "--seconds", "3000",
                    "--realtime", "off", "--screenshot", (tmp / "view.png").string()},
                   "Ctrl-C stops"});
#endif
#ifdef HAPTICFIELD_TOOL_TANGIBLE_VIDEO
  // A short image sequence, looped by nothing: the tool plays it for --seconds.
  fs::create_directories(tmp / "frames");
  for (int i = 0; i < 5; ++i) {
    cv::Mat frame(48, 64, CV_8UC1, cv::Scalar(255));
    frame(cv::Rect(10 + 4 * i, 0, 20, 48)).setTo(cv::Scalar(0));
    REQUIRE(cv::imwrite((tmp / "frames" / ("f" + std::to_string(i) + ".png")).string(), frame));
  }
  tools.push_back({"tangible_video",
                   HAPTICFIELD_TOOL_TANGIBLE_VIDEO,
                   {(tmp / "frames" / "f%d.png").string(), "--size", "9", "--seconds", "3000"},
                   "Ctrl-C stops"});
#endif
  for (Tool& t : tools) {
    CAPTURE(t.name);
    Child tool(t.path, t.args, tmp, t.name);
    const bool ready = tool.wait_for_output(t.ready);
    INFO(tool.out() << tool.err());
    REQUIRE(ready);
    tool.signal(SIGINT);
    check_stopped(tool, SIGINT);
  }
}

TEST_CASE("servo_demo: a serial arm that hangs up mid-run is one line on stderr and exit 1") {
  testing::Pty pty;
  OurArm ours(SimulatedArmConfig{});
  PtyPeer peer(pty, [&](std::span<const std::uint8_t> bytes, int master) { ours.serve(bytes, master); });
  Child tool(HAPTICFIELD_TOOL_SERVO_DEMO, demo_args("serial:" + pty.path), tmp, "hangup");
  const bool ready = tool.wait_for_output("Hz");  // the loop runs (armed or not)
  INFO(tool.out() << tool.err());
  REQUIRE(ready);
  peer.stop();
  pty.close_master();  // the cable is pulled
  CAPTURE(tool.out(), tool.err());
  REQUIRE(tool.wait());
  REQUIRE(tool.exited_normally());
  CHECK(tool.status() == 1);
  const std::string err = tool.err();
  CHECK(err == "servo_demo: the device disconnected during the run; zero force was commanded\n");
  CHECK(tool.out().find("the device disconnected") != std::string::npos);
  CHECK(ours.arm.core().counters().commands > 0);
}

TEST_CASE("Ctrl-C on the tools with every simulated arm family: stopped through the loop, exit 130") {
  struct Tool {
    std::string name, path;
    std::vector<std::string> args;
    std::string ready;
  };
  std::vector<Tool> tools;
  // (sim itself is above; the P4 twin through the viewer below)
  for (const char* device : {"woody:p1:sim", "inverse3:sim"})
    tools.push_back({std::string("servo_demo ") + device,
                     HAPTICFIELD_TOOL_SERVO_DEMO,
                     {"--seconds", "3000", "--realtime", "off", "--device", device},
                     "Hz"});
  tools.push_back({"two_arms woody, inverse3",
                   HAPTICFIELD_TOOL_TWO_ARMS,
                   {"--seconds", "60", "--teacher", "woody:p4:sim", "--student", "inverse3:sim"},
                   "Ctrl-C stops"});
#ifdef HAPTICFIELD_TOOL_HAPTICFIELD_VIEW
  tools.push_back({"hapticfield_view woody:p4:sim",
                   HAPTICFIELD_TOOL_HAPTICFIELD_VIEW,
                   {std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/coffee.png", "--device", "woody:p4:sim",
                    "--seconds", "3000", "--realtime", "off", "--screenshot", (tmp / "view_arm.png").string()},
                   "Ctrl-C stops"});
#endif
  int n = 0;
  for (Tool& t : tools) {
    CAPTURE(t.name);
    Child tool(t.path, t.args, tmp, "families" + std::to_string(n++));
    const bool ready = tool.wait_for_output(t.ready);
    INFO(tool.out() << tool.err());
    REQUIRE(ready);
    tool.signal(SIGINT);
    check_stopped(tool, SIGINT);
    CHECK(tool.out().find("zero force") != std::string::npos);
  }
}

TEST_CASE("--list-devices: every tool that opens arms says, one line a family, which are present; exit 0") {
  std::vector<std::pair<std::string, std::string>> tools = {{"servo_demo", HAPTICFIELD_TOOL_SERVO_DEMO},
                                                            {"two_arms", HAPTICFIELD_TOOL_TWO_ARMS}};
#ifdef HAPTICFIELD_TOOL_HAPTICFIELD_VIEW
  tools.emplace_back("hapticfield_view", HAPTICFIELD_TOOL_HAPTICFIELD_VIEW);
#endif
  std::string first;
  for (const auto& [name, path] : tools) {
    CAPTURE(name);
    Child tool(path, {"--list-devices"}, tmp, "list_" + name);
    REQUIRE(tool.wait());
    const std::string out = tool.out();
    CAPTURE(out, tool.err());
    CHECK(tool.status() == 0);
    CHECK(tool.err().empty());
    CHECK(out.rfind("sim: present: ", 0) == 0);
    CHECK(out.find("hid[:VID:PID]: ") != std::string::npos);
    CHECK(out.find("woody:p1|p2|p4[:PRESET][:sim|:PATH]: ") != std::string::npos);
    CHECK(out.find("inverse3:PATH|sim: ") != std::string::npos);
    if (first.empty()) first = out;
    CHECK(std::count(out.begin(), out.end(), '\n') == std::count(first.begin(), first.end(), '\n'));
  }
}
