#pragma once
/// @file falcon_door.hpp
/// The Novint Falcon's line of the device front door
/// (hapticfield/devices/open_device.hpp): "falcon[:INDEX[:FIRMWARE]]" (the
/// INDEX-th Falcon on USB, 0 the first; needs libusb-1.0: build with
/// hapticfield::falcon_usb, which defines HAPTICFIELD_HAS_LIBUSB; never run
/// on a real one) or "falcon:sim" (the simulated Falcon). FIRMWARE is the
/// firmware file to upload when none runs; without it the environment
/// variable HAPTICFIELD_FALCON_FIRMWARE names it.

#include <charconv>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "hapticfield/arms/falcon/falcon.hpp"
#include "hapticfield/arms/falcon/simulated_falcon.hpp"
#include "hapticfield/device/device_family.hpp"
#if HAPTICFIELD_HAS_LIBUSB
#include "hapticfield/arms/falcon/falcon_libusb.hpp"
#endif

namespace hapticfield::falcon_door {

/// The environment variable naming the firmware file when the device string does not.
inline constexpr const char* firmware_variable = "HAPTICFIELD_FALCON_FIRMWARE";

/// A checked "falcon" string: which Falcon, which firmware file.
struct Where {
  unsigned index{0};
  std::string firmware;  ///< "" when the string gives none
  bool simulated{false};
};

/// Parses the text after "falcon:" ("" for the first Falcon).
/// @throws DeviceSpecError naming what is wrong.
inline Where parse(std::string_view args) {
  Where w;
  if (args == "sim") {
    w.simulated = true;
    return w;
  }
  if (args.empty()) return w;
  const std::size_t colon = args.find(':');
  const std::string_view index = args.substr(0, colon);
  const auto [end, error] = std::from_chars(index.data(), index.data() + index.size(), w.index);
  if (index.empty() || error != std::errc{} || end != index.data() + index.size() || w.index > 15)
    throw DeviceSpecError("falcon takes an index 0..15 (falcon:0), then optionally :FIRMWARE, or :sim");
  if (colon != std::string_view::npos) {
    w.firmware = std::string(args.substr(colon + 1));
    if (w.firmware.empty()) throw DeviceSpecError("falcon:INDEX: takes the firmware file's path after the ':'");
  }
  return w;
}

inline bool check(std::string_view args) {
  return parse(args).simulated;
}

inline DeviceProbe probe() {
#if HAPTICFIELD_HAS_LIBUSB
  try {
    const unsigned n = LibusbFalconUsb::count();
    if (n == 0) return {false, "no Falcon found (USB 0403:cb48)"};
    return {true, std::to_string(n) + " Falcon(s) on USB (falcon:0 .. falcon:" + std::to_string(n - 1) + ")"};
  } catch (const std::exception& e) {
    return {false, e.what()};
  }
#else
  return {false, "not built in: this build has no libusb-1.0 (libusb-1.0-0-dev, then rebuild); falcon:sim works"};
#endif
}

template <class Link>
struct Parts {
  std::unique_ptr<Link> link;
  std::unique_ptr<Falcon> arm;
  Falcon& device() noexcept { return *arm; }
};

inline AnyDevice open(const DeviceSpec& spec, const DeviceOptions& options) {
  Where w = parse(spec.args);
  FalconConfig config;
  config.now = options.now;
  if (w.simulated) {
    auto parts = std::make_unique<Parts<SimulatedFalconUsb>>();
    SimulatedFalconConfig sim;
    sim.firmware_running = true;  // as after an upload: the twin needs no firmware file
    sim.hand = options.hand;
    parts->link = std::make_unique<SimulatedFalconUsb>(sim);
    parts->arm = std::make_unique<Falcon>(*parts->link, config);
    return AnyDevice::holding(std::move(parts));
  }
#if HAPTICFIELD_HAS_LIBUSB
  if (w.firmware.empty())
    if (const char* path = std::getenv(firmware_variable)) w.firmware = path;
  config.firmware_path = w.firmware;
  auto parts = std::make_unique<Parts<LibusbFalconUsb>>();
  parts->link = std::make_unique<LibusbFalconUsb>(w.index);
  try {
    parts->arm = std::make_unique<Falcon>(*parts->link, config);
  } catch (const DeviceError& e) {
    if (!w.firmware.empty()) throw;
    throw DeviceError(std::string(e.what()) + "; give the file as falcon:" + std::to_string(w.index) +
                      ":FIRMWARE or in $" + firmware_variable);
  }
  return AnyDevice::holding(std::move(parts));
#else
  throw DeviceError("this build has no libusb-1.0: --device falcon is unavailable (falcon:sim works)");
#endif
}

}  // namespace hapticfield::falcon_door

namespace hapticfield {

/// Novint Falcons over libusb-1.0, and the simulated Falcon.
inline constexpr DeviceFamily falcon_family{
    "falcon",
    "falcon[:INDEX[:FIRMWARE]]|falcon:sim",
    "a Novint Falcon on USB (never run on a real one; firmware from $HAPTICFIELD_FALCON_FIRMWARE or :FIRMWARE); "
    ":sim simulates it",
    falcon_door::check,
    falcon_door::probe,
    falcon_door::open};

}  // namespace hapticfield
