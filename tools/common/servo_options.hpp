#pragma once
/// @file servo_options.hpp
/// The options of the tools that run a servo loop: --realtime and --clock,
/// and the checks that tie them to the arm and to --seconds.

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>

#include "cli.hpp"
#include "hapticfield/device/device_family.hpp"
#include "hapticfield/servo/loop.hpp"

namespace hapticfield::cli {

/// --realtime off|best_effort|enforce: the servo thread's scheduling.
[[nodiscard]] inline RealTime realtime_option(Parser& p) {
  return p.choice<RealTime>(
      "real-time mode",
      {{"off", RealTime::off}, {"best_effort", RealTime::best_effort}, {"enforce", RealTime::enforce}});
}

/// --clock wall|virtual: true for virtual (simulated time, simulated arms
/// only; see check_clock_fits_arm).
[[nodiscard]] inline bool virtual_clock_option(Parser& p) {
  return p.choice<bool>("clock", {{"wall", false}, {"virtual", true}});
}

/// A real arm moves in real time: --clock virtual with one is a usage error
/// naming the flag that chose it ("--device", or a tool's own such as
/// "--student").
inline void check_clock_fits_arm(bool virtual_clock, const DeviceSpec& arm, std::string_view arm_flag = "--device") {
  if (!virtual_clock || arm.simulated) return;
  const std::string flag(arm_flag);
  throw UsageError("--clock virtual needs a simulated arm (" + flag +
                   " sim, woody:GEN[:PRESET]:sim or inverse3:sim); " + flag + " " + detail::quoted(arm.text) +
                   " is a real arm, which runs on the wall clock");
}

/// The loop's run time rounds to at least one tick at `rate_hz` (0 ticks
/// would mean "no limit" to the loop).
/// @throws UsageError "--seconds 0.0001 is less than one tick at 1000 Hz;
///         the minimum is 0.0005 s".
inline void check_at_least_one_tick(double seconds, double rate_hz) {
  if (std::llround(seconds * rate_hz) >= 1) return;
  char text[160];
  std::snprintf(text, sizeof text, "--seconds %g is less than one tick at %g Hz; the minimum is %g s", seconds, rate_hz,
                0.5 / rate_hz);
  throw UsageError(text);
}

}  // namespace hapticfield::cli
