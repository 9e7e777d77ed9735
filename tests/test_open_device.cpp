// The device front door: open_device, parse_device_spec, list_devices and
// AnyDevice; and the device suite (tests/device_suite.hpp) on the simulated
// twin of every family: sim, hid (ForceArm on the simulated HID link),
// serial's reports, WoodenHaptics P1 and P4, Inverse3.
#include <catch2/catch.hpp>

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "common/device_option.hpp"
#include "device_suite.hpp"
#include "hapticfield/devices/open_device.hpp"
#include "hapticfield/servo.hpp"
#include "run_seed.hpp"

using namespace hapticfield;
using test::device_suite::SeverableLink;

namespace {

LoopConfig quiet() {
  LoopConfig c;
  c.realtime = RealTime::off;
  return c;
}

TimeSource on(VirtualClock& clock) {
  return [&clock] { return clock.now(); };
}

// ---- the twins ---------------------------------------------------------------

/// The simulated force arm as "sim" opens it; unplugged and given wild
/// encoder counts by its own link's faults.
struct SimTwin {
  struct Parts {
    SimulatedArm arm;
    SimulatedTransport link;
    ForceArm force_arm;
    explicit Parts(VirtualClock& clock) : arm(SimulatedArmConfig{}), link(arm, on(clock)), force_arm(link) {}
    ForceArm& device() noexcept { return force_arm; }
  };
  Parts* parts;
  AnyDevice any;
  explicit SimTwin(VirtualClock& clock) {
    auto p = std::make_unique<Parts>(clock);
    parts = p.get();
    any = AnyDevice::holding(std::move(p));
  }
  AnyDevice& device() { return any; }
  [[nodiscard]] double effort() const { return glm::length(parts->arm.applied_torque()); }
  void lose() { parts->link.inject(LinkFault::unplug, parts->arm.ticks() + 1); }
  void send_impossible() { parts->link.inject(LinkFault::wild_counts, parts->arm.ticks() + 1, 5); }
};

/// hid's stand-in: ForceArm reading HID reports from the simulated firmware,
/// the cable pulled between them.
struct HidTwin {
  struct Parts {
    SimulatedArm arm;
    SimulatedTransport link;
    SeverableLink cable;
    ForceArm force_arm;
    explicit Parts(VirtualClock& clock)
        : arm(SimulatedArmConfig{}), link(arm, on(clock)), cable(link), force_arm(cable) {}
    ForceArm& device() noexcept { return force_arm; }
  };
  Parts* parts;
  AnyDevice any;
  explicit HidTwin(VirtualClock& clock) {
    auto p = std::make_unique<Parts>(clock);
    parts = p.get();
    any = AnyDevice::holding(std::move(p));
  }
  AnyDevice& device() { return any; }
  [[nodiscard]] double effort() const { return glm::length(parts->arm.applied_torque()); }
  void lose() { parts->cable.sever(); }
  void send_impossible() { parts->link.inject(LinkFault::wild_counts, parts->arm.ticks() + 1, 5); }
};

/// A WoodenHaptics arm of generation G and its simulated firmware.
template <woody::Generation G>
struct WoodyTwin {
  struct Parts {
    SimulatedWoody arm;
    SimulatedWoodyTransport link;
    SeverableLink cable;
    WoodyArm woody_arm;
    static SimulatedWoodyConfig simulated() {
      SimulatedWoodyConfig c;
      c.generation = G;
      c.encoder_sign = woody_encoder_sign(G);
      return c;
    }
    static WoodyArmConfig host(VirtualClock& clock) {
      WoodyArmConfig c = WoodyArmConfig::defaults(G);
      c.now = on(clock);
      return c;
    }
    explicit Parts(VirtualClock& clock)
        : arm(simulated()), link(arm, on(clock)), cable(link), woody_arm(cable, host(clock)) {}
    WoodyArm& device() noexcept { return woody_arm; }
  };
  Parts* parts;
  AnyDevice any;
  explicit WoodyTwin(VirtualClock& clock) {
    auto p = std::make_unique<Parts>(clock);
    parts = p.get();
    any = AnyDevice::holding(std::move(p));
  }
  AnyDevice& device() { return any; }
  [[nodiscard]] double effort() const { return glm::length(parts->arm.applied_current()); }
  void lose() { parts->cable.sever(); }
  void send_impossible() { parts->link.set_wild_counts(true); }
};

/// A Haply Inverse3 and its simulated twin; an impossible pose is a reply
/// cut short, its position made of the next reply's bytes (a jump).
struct Inverse3Twin {
  struct Parts {
    SimulatedInverse3 arm;
    SimulatedInverse3Transport link;
    SeverableLink cable;
    Inverse3 inverse3;
    static Inverse3Config host(VirtualClock& clock) {
      Inverse3Config c;
      c.now = on(clock);
      return c;
    }
    explicit Parts(VirtualClock& clock) : link(arm), cable(link), inverse3(cable, host(clock)) {}
    Inverse3& device() noexcept { return inverse3; }
  };
  Parts* parts;
  AnyDevice any;
  explicit Inverse3Twin(VirtualClock& clock) {
    auto p = std::make_unique<Parts>(clock);
    parts = p.get();
    any = AnyDevice::holding(std::move(p));
  }
  AnyDevice& device() { return any; }
  [[nodiscard]] double effort() const { return glm::length(parts->arm.force()); }
  void lose() { parts->cable.sever(); }
  void send_impossible() { parts->link.truncate_replies(parts->arm.counters().forces + 2, 12, 5); }
};

static_assert(test::device_suite::Twin<SimTwin>);
static_assert(test::device_suite::Twin<Inverse3Twin>);

}  // namespace

HAPTICFIELD_DEVICE_SUITE(SimTwin, "device suite, sim")
HAPTICFIELD_DEVICE_SUITE(HidTwin, "device suite, hid (simulated link)")
HAPTICFIELD_DEVICE_SUITE(WoodyTwin<woody::Generation::p1_hid8>, "device suite, woody p1 (simulated)")
HAPTICFIELD_DEVICE_SUITE(WoodyTwin<woody::Generation::p4_text>, "device suite, woody p4 (simulated)")
HAPTICFIELD_DEVICE_SUITE(Inverse3Twin, "device suite, inverse3 (simulated)")

// ---- the front door ------------------------------------------------------------

TEST_CASE("open_device opens every simulated arm, and one loop type runs each") {
  for (const std::string spec : {"sim", "woody:p1:sim", "woody:p2:sim", "woody:p4:sim", "woody:p4:vintage:sim",
                                 "woody:p2:aluhaptics_v2:sim", "inverse3:sim"}) {
    CAPTURE(spec);
    const DeviceSpec parsed = parse_device_spec(spec);
    CHECK(parsed.simulated);
    CHECK(parsed.text == spec);
    VirtualClock clock;
    DeviceOptions options;
    options.now = on(clock);
    AnyDevice device = open_device(parsed, options);
    REQUIRE(device);
    CHECK_FALSE(device.info().name.empty());
    ServoLoop<AnyDevice, VirtualClock> loop(device, clock, quiet());
    std::uint64_t trusted = 0;
    auto count = [&](const TickInput& in) noexcept {
      trusted += in.trusted ? 1 : 0;
      return glm::dvec3{0.0};
    };
    CHECK(loop.run(count, {.max_ticks = 600}) == StopReason::tick_limit);
    CHECK(trusted > 300);  // homed (where the arm homes) and reporting on time
  }
}

TEST_CASE("open_device: the held arm is reachable by its type, and only by it") {
  VirtualClock clock;
  DeviceOptions options;
  options.now = on(clock);
  AnyDevice sim = open_device("sim", options);
  CHECK(sim.target<ForceArm>() != nullptr);
  CHECK(sim.target<WoodyArm>() == nullptr);
  AnyDevice woody = open_device("woody:p4:sim", options);
  CHECK(woody.target<WoodyArm>() != nullptr);
  CHECK(woody.target<WoodyArm>()->info().name == woody.info().name);
  CHECK(woody.target<Inverse3>() == nullptr);
  AnyDevice inverse3 = open_device("inverse3:sim", options);
  CHECK(inverse3.target<Inverse3>() != nullptr);
  CHECK(inverse3.clear_fault() == Status::unsupported);  // a family without the request says so
}

TEST_CASE("every device string the tools took before still parses, real or simulated as before") {
  struct Case {
    const char* text;
    bool simulated;
  };
  for (const Case c : {Case{"sim", true}, Case{"hid", false}, Case{"hid:1209:0001", false}, Case{"hid:0:f", false},
                       Case{"serial:/dev/ttyACM0", false}, Case{"woody:p4:/dev/ttyACM0", false},
                       Case{"woody:p4:woodenhaptics_v2019:/dev/ttyUSB1", false}, Case{"woody:p1", false},
                       Case{"woody:p2:vintage", false}, Case{"woody:p4:sim", true},
                       Case{"inverse3:/dev/ttyACM0", false}, Case{"inverse3:sim", true}}) {
    CAPTURE(c.text);
    const DeviceSpec spec = parse_device_spec(c.text);
    CHECK(spec.simulated == c.simulated);
    CHECK(find_device_family(spec.family) != nullptr);
  }
}

TEST_CASE("a bad device string is one DeviceSpecError naming the string and what is wrong") {
  struct Case {
    std::string text, says;
  };
  std::vector<Case> cases = {
      {"", "unknown device"},
      {"usb", "unknown device"},
      {"SIM", "unknown device"},
      {"sim:", "nothing after 'sim:'"},
      {"sim:fast", "sim takes nothing"},
      {"hid:", "nothing after 'hid:'"},
      {"hid:12345:1", "hexadecimal"},
      {"hid:1209", "hexadecimal"},
      {"hid:12g9:0001", "hexadecimal"},
      {"serial:", "nothing after"},
      {"inverse3:", "nothing after"},
      {"woody:", "nothing after"},
      {"woody:p9:sim", "generation must be p1, p2 or p4"},
      {"woody:p4:polhem_v3:sim", "preset must be"},
      {"woody:p1:/dev/ttyACM0", "USB HID"},
      {"woody:p4", "needs the arm's tty"},
  };
  for (const std::string_view planned : planned_device_families) {
    cases.push_back({std::string(planned), "not built in this version"});
    cases.push_back({std::string(planned) + ":0", "not built in this version"});
  }
  for (const Case& c : cases) {
    CAPTURE(c.text);
    try {
      (void)open_device(c.text);
      FAIL("opened '" << c.text << "'");
    } catch (const DeviceSpecError& e) {
      const std::string what = e.what();
      CHECK(what.rfind("device '" + c.text + "': ", 0) == 0);
      CHECK(what.find(c.says) != std::string::npos);
      CHECK(what.find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("open_device: an arm that is not there is a DeviceError naming it") {
  for (const char* spec : {"serial:/no/such/tty", "inverse3:/no/such/tty", "woody:p4:/no/such/tty"}) {
    CAPTURE(spec);
    CHECK_THROWS_AS(open_device(spec), DeviceError);
    CHECK_THROWS_WITH(open_device(spec), Catch::Matchers::Contains("no serial port at /no/such/tty"));
  }
}

TEST_CASE("parse_device_spec on random text: a spec of a known family that parses again the same, or one error") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  const std::vector<std::string> pieces = {
      "sim", "hid",  "serial", "woody",   "inverse3",     "falcon",     "dhd",  ":",   ":",
      "p1",  "p2",   "p4",     "vintage", "/dev/ttyACM0", "1209",       "0001", "sim", "x",
      "",    "\x01", "::",     "/",       "ffff",         "woody_v2015"};
  std::uniform_int_distribution<std::size_t> pick(0, pieces.size() - 1), count(0, 6);
  int parsed = 0, refused = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string text;
    for (std::size_t k = count(rng); k > 0; --k)
      text += pieces[pick(rng)];
    CAPTURE(text);
    try {
      const DeviceSpec spec = parse_device_spec(text);
      REQUIRE(find_device_family(spec.family) != nullptr);
      const DeviceSpec again = parse_device_spec(spec.text);
      REQUIRE(again.family == spec.family);
      REQUIRE(again.args == spec.args);
      REQUIRE(again.simulated == spec.simulated);
      REQUIRE(spec.text == (spec.args.empty() ? spec.family : spec.family + ":" + spec.args));
      ++parsed;
    } catch (const DeviceSpecError& e) {
      REQUIRE(std::string(e.what()).rfind("device '" + text + "': ", 0) == 0);
      ++refused;
    }
  }
  CHECK(parsed > 100);
  CHECK(refused > 100);
}

TEST_CASE("list_devices: one line per family, present or why not; the simulated arm always present") {
  const std::vector<DeviceListing> all = list_devices();
  REQUIRE(all.size() == device_families.size() + planned_device_families.size());
  for (std::size_t i = 0; i < device_families.size(); ++i) {
    CAPTURE(all[i].line);
    CHECK(all[i].family == std::string(device_families[i].name));
    CHECK(all[i].line.rfind(std::string(device_families[i].syntax) + ": ", 0) == 0);
    CHECK(all[i].line.find(all[i].present ? ": present: " : ": not present: ") != std::string::npos);
    CHECK(all[i].line.find('\n') == std::string::npos);
  }
  CHECK(all.front().family == "sim");
  CHECK(all.front().present);
  for (std::size_t i = device_families.size(); i < all.size(); ++i) {
    CHECK_FALSE(all[i].present);
    CHECK(all[i].line.find("not built in this version") != std::string::npos);
  }
}

TEST_CASE("an empty AnyDevice is a device that is gone: the loop stops at once with zero force") {
  AnyDevice none;
  CHECK_FALSE(none);
  DeviceState s;
  CHECK(none.read(s) == Status::disconnected);
  CHECK(none.write(glm::dvec3{1.0}) == Status::disconnected);
  CHECK(none.info().name == "no device");
  VirtualClock clock;
  ServoLoop<AnyDevice, VirtualClock> loop(none, clock, quiet());
  auto push = [](const TickInput&) noexcept { return glm::dvec3{1.0, 0.0, 0.0}; };
  CHECK(loop.run(push, {.max_ticks = 100}) == StopReason::disconnected);
  CHECK(loop.last_command() == glm::dvec3{0.0});
}

TEST_CASE("the tools' --device help names every family's device strings, in lines of at most 100 characters") {
  const std::string help = cli::device_help();
  for (const DeviceFamily& family : device_families) {
    const std::string name(family.name);  // Catch2 2.13 built by clang has no StringMaker for string_view
    CAPTURE(name);
    CHECK(help.find(std::string(family.syntax) + ":") != std::string::npos);
  }
  std::size_t start = 0, lines = 0;
  for (std::size_t end = help.find('\n'); end != std::string::npos; start = end + 1, end = help.find('\n', start)) {
    CAPTURE(help.substr(start, end - start));
    CHECK(end - start <= 100);
    ++lines;
  }
  CHECK(start == help.size());  // ends with a newline
  CHECK(lines >= device_families.size() + 2);
}
