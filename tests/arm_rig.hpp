#pragma once
// The simulated arm (the firmware twin), its link, ForceArm and a servo
// loop on one virtual clock: the rig the servo, pacer and firmware tests
// drive.
#include <cstdint>

#include "hapticfield/arms/force_arm/force_arm.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/arms/force_arm/simulated_transport.hpp"
#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/loop.hpp"

namespace hapticfield::testing {

struct ArmRig {
  VirtualClock clock;
  SimulatedArm arm;
  SimulatedTransport link;
  ForceArm device;
  ServoLoop<ForceArm, VirtualClock> loop;

  /// The loop without real-time scheduling (tests run on any machine).
  static LoopConfig quiet(LoopConfig c = {}) {
    c.realtime = RealTime::off;
    return c;
  }
  /// Nobody holds the handle.
  static SimulatedArmConfig free_arm() {
    SimulatedArmConfig c;
    c.hand.holding = false;
    return c;
  }

  /// The firmware watchdog is a.watchdog.
  explicit ArmRig(const SimulatedArmConfig& a = {}, const LoopConfig& c = {})
      : arm(a), link(arm, [this] { return clock.now(); }), device(link), loop(device, clock, quiet(c)) {}
  /// The firmware watchdog is watchdog_us [us].
  ArmRig(const SimulatedArmConfig& a, std::uint16_t watchdog_us, const LoopConfig& c = {})
      : arm(a, watchdog_us), link(arm, [this] { return clock.now(); }), device(link), loop(device, clock, quiet(c)) {}
};

}  // namespace hapticfield::testing
