#pragma once
/// @file serial_ports.hpp
/// Which serial ports a USB arm may sit on (/dev/ttyACM*, /dev/ttyUSB*) and
/// whether this user may open them: for "--list-devices", never in a tick.

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace hapticfield {

/// One serial port and whether it can be opened for reading and writing.
struct SerialPortProbe {
  std::string path;
  bool accessible{false};
  std::string why;  ///< empty when accessible, else e.g. "permission denied (join the dialout group)"
};

/// Whether `path` is a serial port this user may open, and if not, why not.
[[nodiscard]] inline SerialPortProbe probe_serial_port(const std::string& path) {
  SerialPortProbe p{path, false, {}};
  if (::access(path.c_str(), F_OK) != 0) {
    p.why = "no such path";
  } else if (::access(path.c_str(), R_OK | W_OK) != 0) {
    p.why = errno == EACCES || errno == EPERM ? "permission denied (join the dialout group, or a udev rule)"
                                              : std::string(std::strerror(errno));
  } else {
    p.accessible = true;
  }
  return p;
}

/// The USB serial ports present (/dev/ttyACM*, /dev/ttyUSB*), sorted.
[[nodiscard]] inline std::vector<SerialPortProbe> usb_serial_ports(const std::filesystem::path& dev = "/dev") {
  std::vector<SerialPortProbe> ports;
  std::error_code error;
  for (std::filesystem::directory_iterator it(dev, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name.starts_with("ttyACM") || name.starts_with("ttyUSB")) ports.push_back(probe_serial_port(it->path()));
  }
  std::sort(ports.begin(), ports.end(), [](const auto& a, const auto& b) { return a.path < b.path; });
  return ports;
}

/// One line about the USB serial ports: the usable ones, else why none is.
[[nodiscard]] inline std::string describe_usb_serial_ports(bool& any_usable) {
  const std::vector<SerialPortProbe> ports = usb_serial_ports();
  any_usable = false;
  std::string usable, refused;
  for (const SerialPortProbe& p : ports) {
    std::string& list = p.accessible ? usable : refused;
    if (!list.empty()) list += ", ";
    list += p.accessible ? p.path : p.path + ": " + p.why;
    any_usable = any_usable || p.accessible;
  }
  if (ports.empty()) return "no serial port found (/dev/ttyACM*, /dev/ttyUSB*)";
  return any_usable ? "serial port(s) " + usable + (refused.empty() ? "" : "; not usable: " + refused) : refused;
}

}  // namespace hapticfield
