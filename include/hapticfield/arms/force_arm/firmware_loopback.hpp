#pragma once
/// @file firmware_loopback.hpp
/// Deprecated names of the firmware twin: SimulatedArm (simulated_arm.hpp)
/// runs the reference firmware core on the simulated mechanics and
/// SimulatedTransport (simulated_transport.hpp) connects a host to it.
/// FirmwareArm is a SimulatedArm whose watchdog defaults to 5 ms (the
/// firmware's own default) and whose step() is tick(); FirmwareLoopback is
/// SimulatedTransport.

#include <cstdint>

#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/arms/force_arm/simulated_transport.hpp"
#include "hapticfield/firmware/core.hpp"

namespace hapticfield {

/// Deprecated: use SimulatedArm(config, watchdog_us) and tick().
class FirmwareArm : public SimulatedArm {
 public:
  /// @throws std::invalid_argument for a bad arm or firmware configuration.
  explicit FirmwareArm(const SimulatedArmConfig& arm = {}, std::uint16_t watchdog_us = 5000)
      : SimulatedArm(arm, watchdog_us) {}
  FirmwareArm(const SimulatedArmConfig& arm, const firmware::FirmwareConfig& config) : SimulatedArm(arm, config) {}
  /// One firmware period (tick()).
  void step() noexcept { tick(); }
};

/// Deprecated: use SimulatedTransport.
using FirmwareLoopback = SimulatedTransport;

}  // namespace hapticfield
