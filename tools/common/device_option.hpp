#pragma once
/// @file device_option.hpp
/// The tools' "--device D" and "--list-devices", through the device front
/// door (hapticfield/devices/open_device.hpp), and the link counters of
/// whichever arm was opened.

#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>

#include "cli.hpp"
#include "hapticfield/devices/open_device.hpp"

namespace hapticfield::cli {

/// The usage lines of --device and --list-devices, the options in a column
/// of `column` characters: every family of the front door (its device
/// strings and what arm it is), so the help cannot fall behind the table.
/// Lines are wrapped at 100 characters.
[[nodiscard]] inline std::string device_help(std::size_t column = 24) {
  const auto option = [&](const char* name) {
    std::string line = std::string("  ") + name;
    line.append(line.size() < column ? column - line.size() : 1, ' ');
    return line;
  };
  std::string text = option("--device D") + "the arm, one of these (default sim):\n";
  const std::string indent(column + 2, ' '), more(column + 4, ' ');
  for (const DeviceFamily& family : device_families) {
    std::string line = indent + std::string(family.syntax) + ":";
    std::string_view rest = family.summary;
    while (!rest.empty()) {  // word by word, wrapped at 100 columns
      const std::size_t space = rest.find(' ');
      const std::string_view word = rest.substr(0, space);
      if (line.size() + 1 + word.size() > 100 && line.size() > more.size()) {
        text += line + "\n";
        line = more;
      } else {
        line += ' ';
      }
      line += word;
      rest = space == std::string_view::npos ? std::string_view{} : rest.substr(space + 1);
    }
    text += line + "\n";
  }
  return text + option("--list-devices") + "one line per arm family: present, or why not; then exit\n";
}

/// A --device value checked by the front door; a bad one is a usage error
/// ("--device: device 'X': what is wrong").
[[nodiscard]] inline DeviceSpec device_option(const std::string& value) {
  try {
    return parse_device_spec(value);
  } catch (const DeviceSpecError& e) {
    throw UsageError(std::string("--device: ") + e.what());
  }
}

/// --list-devices: one line per family on stdout; exit status 0.
inline int print_device_list() {
  for (const DeviceListing& listing : list_devices())
    std::printf("%s\n", listing.line.c_str());
  std::fflush(stdout);
  return exit_ok;
}

/// The link counters of the arm, whichever protocol it speaks.
inline void print_link(const AnyDevice& device) {
  const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  if (const ForceArm* arm = device.target<ForceArm>()) {
    const LinkCounters& c = arm->counters();
    std::printf("link: %llu reports, %llu dropped, %llu corrupt, %llu resyncs, %llu commands\n", u(c.reports),
                u(c.dropped), u(c.corrupt), u(c.resyncs), u(c.commands));
  } else if (const Inverse3* inverse3 = device.target<Inverse3>()) {
    const Inverse3Counters& c = inverse3->counters();
    std::printf("link: %llu replies, %llu implausible, %llu resyncs, %llu bytes dropped, %llu lost, %llu commands\n",
                u(c.replies), u(c.implausible), u(c.resyncs), u(c.dropped_bytes), u(c.lost_replies), u(c.commands));
  } else if (const WoodyArm* woody = device.target<WoodyArm>()) {
    const WoodyCounters& c = woody->counters();
    std::printf("link: %llu replies, %llu with firmware error bits, %llu malformed, %llu commands\n", u(c.reports),
                u(c.error_replies), u(c.malformed), u(c.commands));
  }
}

}  // namespace hapticfield::cli
