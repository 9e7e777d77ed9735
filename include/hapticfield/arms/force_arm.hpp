#pragma once
/// @file force_arm.hpp
/// The force arm (Phantom-class kinematics, our report protocol): ForceArm,
/// the simulated arm and its transport with link faults, and the loopback
/// to the reference firmware core.

#include "hapticfield/arms/force_arm/firmware_loopback.hpp"
#include "hapticfield/arms/force_arm/force_arm.hpp"
#include "hapticfield/arms/force_arm/kinematics.hpp"
#include "hapticfield/arms/force_arm/link_faults.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/arms/force_arm/simulated_transport.hpp"
