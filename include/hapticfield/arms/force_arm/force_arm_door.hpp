#pragma once
/// @file force_arm_door.hpp
/// The force arm's lines of the device front door
/// (hapticfield/devices/open_device.hpp): "sim" (the simulated arm), "hid"
/// or "hid:VID:PID" (our protocol over USB HID; needs hidapi: build with
/// hapticfield::hid, which defines HAPTICFIELD_HAS_HID) and "serial:PATH"
/// (our protocol over a tty).

#include <time.h>

#include <charconv>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "hapticfield/arms/force_arm/force_arm.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/arms/force_arm/simulated_transport.hpp"
#include "hapticfield/device/device_family.hpp"
#include "hapticfield/protocol/reports.hpp"
#include "hapticfield/transport/serial_ports.hpp"
#include "hapticfield/transport/serial_transport.hpp"
#if HAPTICFIELD_HAS_HID
#include "hapticfield/transport/hid_transport.hpp"
#endif

namespace hapticfield {

/// USB vendor and product ids of a HID arm.
struct HidIds {
  std::uint16_t vendor{default_vendor_id};
  std::uint16_t product{default_product_id};
};

/// The ids after "hid:" ("" for the protocol's defaults): "VID:PID" with 1
/// to 4 hexadecimal digits each; nothing for any other text.
[[nodiscard]] inline std::optional<HidIds> parse_hid_ids(std::string_view ids) {
  if (ids.empty()) return HidIds{};
  const std::size_t colon = ids.find(':');
  if (colon == std::string_view::npos) return std::nullopt;
  const auto hex = [](std::string_view t, std::uint16_t& out) {
    if (t.empty() || t.size() > 4) return false;
    const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), out, 16);
    return error == std::errc{} && end == t.data() + t.size();
  };
  HidIds result;
  if (!hex(ids.substr(0, colon), result.vendor) || !hex(ids.substr(colon + 1), result.product)) return std::nullopt;
  return result;
}

namespace force_arm_door {

/// A ForceArm with its transport (and simulated arm), at one address.
template <class Link>
struct Parts {
  std::unique_ptr<SimulatedArm> simulated;
  std::unique_ptr<Link> link;
  std::unique_ptr<ForceArm> arm;
  ForceArm& device() noexcept { return *arm; }
};

inline TimeSource time_source(const DeviceOptions& options) {
  if (options.now) return options.now;
  return [] {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);  // as the loop's SteadyClock
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  };
}

inline bool check_sim(std::string_view args) {
  if (!args.empty()) throw DeviceSpecError("sim takes nothing after it");
  return true;
}
inline DeviceProbe probe_sim() {
  return {true, "the simulated arm (a scripted hand holds it)"};
}
inline AnyDevice open_sim(const DeviceSpec&, const DeviceOptions& options) {
  auto parts = std::make_unique<Parts<SimulatedTransport>>();
  SimulatedArmConfig config;
  config.hand = options.hand;
  parts->simulated = std::make_unique<SimulatedArm>(config);
  parts->link = std::make_unique<SimulatedTransport>(*parts->simulated, time_source(options));
  parts->arm = std::make_unique<ForceArm>(*parts->link);
  return AnyDevice::holding(std::move(parts));
}

inline bool check_hid(std::string_view args) {
  if (!parse_hid_ids(args))
    throw DeviceSpecError("hid takes VID:PID, 1 to 4 hexadecimal digits each (e.g. hid:1209:0001)");
  return false;
}
inline DeviceProbe probe_hid() {
#if HAPTICFIELD_HAS_HID
  try {
    const HidIds ids;
    const std::vector<HidDeviceInfo> found = HidTransport::enumerate(ids.vendor, ids.product);
    if (found.empty())
      return {false, "no HID arm with the default ids " + detail::hex4(ids.vendor) + ":" + detail::hex4(ids.product) +
                         " found (" + std::to_string(HidTransport::enumerate().size()) +
                         " HID devices present; other ids: hid:VID:PID)"};
    return {true, found.front().path + (found.front().product.empty() ? "" : " (" + found.front().product + ")")};
  } catch (const std::exception& e) {
    return {false, e.what()};
  }
#else
  return {false, "not built in: this build has no hidapi (libhidapi-dev, then rebuild)"};
#endif
}
inline AnyDevice open_hid([[maybe_unused]] const DeviceSpec& spec, const DeviceOptions&) {
#if HAPTICFIELD_HAS_HID
  const HidIds ids = *parse_hid_ids(spec.args);
  auto parts = std::make_unique<Parts<HidTransport>>();
  parts->link = std::make_unique<HidTransport>(ids.vendor, ids.product);
  parts->arm = std::make_unique<ForceArm>(*parts->link);
  return AnyDevice::holding(std::move(parts));
#else
  throw DeviceError("this build has no hidapi: --device hid is unavailable");
#endif
}

inline bool check_serial(std::string_view args) {
  if (args.empty()) throw DeviceSpecError("serial needs the tty's path, e.g. serial:/dev/ttyACM0");
  return false;
}
inline DeviceProbe probe_serial() {
  bool usable = false;
  std::string line = describe_usb_serial_ports(usable);
  return {usable, std::move(line)};
}
inline AnyDevice open_serial(const DeviceSpec& spec, const DeviceOptions&) {
  auto parts = std::make_unique<Parts<SerialTransport>>();
  parts->link = std::make_unique<SerialTransport>(spec.args);
  parts->arm = std::make_unique<ForceArm>(*parts->link);
  return AnyDevice::holding(std::move(parts));
}

}  // namespace force_arm_door

/// The simulated force arm.
inline constexpr DeviceFamily sim_family{"sim",
                                         "sim",
                                         "the simulated force arm (no hardware)",
                                         force_arm_door::check_sim,
                                         force_arm_door::probe_sim,
                                         force_arm_door::open_sim};
/// Our protocol over USB HID.
inline constexpr DeviceFamily hid_family{"hid",
                                         "hid[:VID:PID]",
                                         "a force arm speaking our protocol over USB HID",
                                         force_arm_door::check_hid,
                                         force_arm_door::probe_hid,
                                         force_arm_door::open_hid};
/// Our protocol over a serial line.
inline constexpr DeviceFamily serial_family{"serial",
                                            "serial:PATH",
                                            "a force arm speaking our protocol over a tty (USB CDC, UART)",
                                            force_arm_door::check_serial,
                                            force_arm_door::probe_serial,
                                            force_arm_door::open_serial};

}  // namespace hapticfield
