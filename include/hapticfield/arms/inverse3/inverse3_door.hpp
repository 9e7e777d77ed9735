#pragma once
/// @file inverse3_door.hpp
/// The Haply Inverse3 line of the device front door
/// (hapticfield/devices/open_device.hpp): "inverse3:PATH" (the arm on the
/// tty PATH; never run on a real one) or "inverse3:sim" (its simulated twin).

#include <time.h>

#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "hapticfield/arms/inverse3/inverse3.hpp"
#include "hapticfield/arms/inverse3/simulated_inverse3.hpp"
#include "hapticfield/device/device_family.hpp"
#include "hapticfield/transport/serial_ports.hpp"
#include "hapticfield/transport/serial_transport.hpp"

namespace hapticfield::inverse3_door {

struct Parts {
  std::unique_ptr<SimulatedInverse3> simulated;
  std::unique_ptr<Transport> link;
  std::unique_ptr<Inverse3> arm;
  Inverse3& device() noexcept { return *arm; }
};

inline bool check(std::string_view args) {
  if (args.empty()) throw DeviceSpecError("inverse3 needs the arm's tty, e.g. inverse3:/dev/ttyACM0, or :sim");
  return args == "sim";
}

inline DeviceProbe probe() {
  bool usable = false;
  std::string line = describe_usb_serial_ports(usable);
  return {usable, usable ? "may be on " + line : std::move(line)};
}

inline AnyDevice open(const DeviceSpec& spec, const DeviceOptions& options) {
  auto parts = std::make_unique<Parts>();
  Inverse3Config config;
  if (spec.args == "sim") {
    // The twin answers each request at once: it keeps no clock of its own.
    config.now = options.now;
    config.port = "the simulated Inverse3";
    parts->simulated = std::make_unique<SimulatedInverse3>();
    parts->link = std::make_unique<SimulatedInverse3Transport>(*parts->simulated);
  } else {
    parts->link = std::make_unique<SerialTransport>(spec.args, SerialConfig{.framing = Framing::fixed});
  }
  parts->arm = std::make_unique<Inverse3>(*parts->link, config);
  return AnyDevice::holding(std::move(parts));
}

}  // namespace hapticfield::inverse3_door

namespace hapticfield {

/// Haply Inverse3 arms.
inline constexpr DeviceFamily inverse3_family{
    "inverse3",
    "inverse3:PATH|sim",
    "a Haply Inverse3 on the tty PATH (never run on a real one: check its frame); :sim simulates it",
    inverse3_door::check,
    inverse3_door::probe,
    inverse3_door::open};

}  // namespace hapticfield
