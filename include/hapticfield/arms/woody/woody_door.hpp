#pragma once
/// @file woody_door.hpp
/// The WoodenHaptics line of the device front door
/// (hapticfield/devices/open_device.hpp):
/// "woody:GEN[:PRESET][:sim|:PATH]", GEN p1 or p2 (USB HID; needs hidapi,
/// HAPTICFIELD_HAS_HID) or p4 (serial text on the tty PATH), PRESET a
/// woody_presets name (default woody_v2015); ":sim" simulates the arm.

#include <time.h>

#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "hapticfield/arms/woody/simulated_woody.hpp"
#include "hapticfield/arms/woody/woody_arm.hpp"
#include "hapticfield/arms/woody/woody_kinematics.hpp"
#include "hapticfield/device/device_family.hpp"
#include "hapticfield/transport/serial_ports.hpp"
#include "hapticfield/transport/serial_transport.hpp"
#if HAPTICFIELD_HAS_HID
#include "hapticfield/transport/hid_transport.hpp"
#endif

namespace hapticfield {

/// A WoodenHaptics device string, parsed.
struct WoodySpec {
  woody::Generation generation{woody::Generation::p4_text};
  std::string preset{"woody_v2015"};
  bool simulated{false};
  std::string port;  ///< tty of a P4 arm
};

/// USB ids of the mbed firmware of WoodenHaptics P1/P2 (1.5).
inline constexpr std::uint16_t woody_hid_vendor = 0x1234;
inline constexpr std::uint16_t woody_hid_product = 0x0006;

/// The text after "woody:": GEN[:PRESET][:sim|:PATH] (PATH starts with '/').
/// @throws DeviceSpecError naming what is wrong.
[[nodiscard]] inline WoodySpec parse_woody_spec(std::string_view args) {
  WoodySpec spec;
  std::string rest(args);
  if (rest.ends_with(":sim")) {
    spec.simulated = true;
    rest.resize(rest.size() - 4);
  } else if (const auto slash = rest.find(":/"); slash != std::string::npos) {
    spec.port = rest.substr(slash + 1);
    rest.resize(slash);
  }
  const std::size_t colon = rest.find(':');
  const std::string gen = rest.substr(0, colon);
  if (colon != std::string::npos) spec.preset = rest.substr(colon + 1);
  if (gen == "p1")
    spec.generation = woody::Generation::p1_hid8;
  else if (gen == "p2")
    spec.generation = woody::Generation::p2_hid14;
  else if (gen == "p4")
    spec.generation = woody::Generation::p4_text;
  else
    throw DeviceSpecError("woody's generation must be p1, p2 or p4, got '" + gen + "'");
  bool known = false;
  for (const char* name : {"woody_v2015", "woodenhaptics_v2019", "aluhaptics_v2", "vintage"})
    known = known || spec.preset == name;
  if (!known)
    throw DeviceSpecError("woody's preset must be woody_v2015, woodenhaptics_v2019, aluhaptics_v2 or vintage, got '" +
                          spec.preset + "'");
  if (!spec.port.empty() && spec.generation != woody::Generation::p4_text)
    throw DeviceSpecError("woody p1 and p2 are USB HID arms: give no tty PATH (only p4 is serial)");
  if (!spec.simulated && spec.generation == woody::Generation::p4_text && spec.port.empty())
    throw DeviceSpecError("woody:p4 needs the arm's tty, e.g. woody:p4:/dev/ttyACM0, or :sim");
  return spec;
}

namespace woody_door {

struct Parts {
  std::unique_ptr<SimulatedWoody> simulated;
  std::unique_ptr<Transport> link;
  std::unique_ptr<WoodyArm> arm;
  WoodyArm& device() noexcept { return *arm; }
};

inline bool check(std::string_view args) {
  return parse_woody_spec(args).simulated;
}

inline DeviceProbe probe() {
  std::string hid;
#if HAPTICFIELD_HAS_HID
  try {
    const std::size_t n = HidTransport::enumerate(woody_hid_vendor, woody_hid_product).size();
    if (n > 0) return {true, "p1/p2 on USB HID 1234:0006"};
    hid = "no p1/p2 on USB HID 1234:0006";
  } catch (const std::exception& e) {
    hid = e.what();
  }
#else
  hid = "p1/p2 not built in (no hidapi)";
#endif
  bool usable = false;
  const std::string serial = describe_usb_serial_ports(usable);
  if (usable) return {true, "p4 may be on " + serial + "; " + hid};
  return {false, hid + "; p4: " + serial};
}

inline AnyDevice open(const DeviceSpec& spec, const DeviceOptions& options) {
  const WoodySpec ws = parse_woody_spec(spec.args);
  WoodyArmConfig config = WoodyArmConfig::defaults(ws.generation, woody_presets::by_name(ws.preset));
  auto parts = std::make_unique<Parts>();
  if (ws.simulated) {
    SimulatedWoodyConfig sc;
    sc.generation = config.generation;
    sc.kinematics = config.kinematics;
    sc.encoder_sign = config.encoder_sign;
    sc.hand = options.hand;
    TimeSource now = options.now;
    if (!now)
      now = [] {
        timespec ts{};
        clock_gettime(CLOCK_MONOTONIC, &ts);
        return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
      };
    config.now = now;
    parts->simulated = std::make_unique<SimulatedWoody>(sc);
    parts->link = std::make_unique<SimulatedWoodyTransport>(*parts->simulated, now);
  } else if (ws.generation != woody::Generation::p4_text) {
#if HAPTICFIELD_HAS_HID
    parts->link = std::make_unique<HidTransport>(woody_hid_vendor, woody_hid_product);
#else
    throw DeviceError("this build has no hidapi: --device woody:p1|p2 is unavailable");
#endif
  } else {
    parts->link = std::make_unique<SerialTransport>(ws.port, SerialConfig{.framing = Framing::lines});
  }
  parts->arm = std::make_unique<WoodyArm>(*parts->link, config);
  return AnyDevice::holding(std::move(parts));
}

}  // namespace woody_door

/// WoodenHaptics arms.
inline constexpr DeviceFamily woody_family{
    "woody",
    "woody:p1|p2|p4[:PRESET][:sim|:PATH]",
    "a WoodenHaptics arm: p1/p2 USB HID, p4 serial text on PATH; PRESET woody_v2015 (default), "
    "woodenhaptics_v2019, aluhaptics_v2 or vintage; :sim simulates it",
    woody_door::check,
    woody_door::probe,
    woody_door::open};

}  // namespace hapticfield
