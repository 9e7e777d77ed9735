#pragma once
/// @file servo.hpp
/// The servo loop: clocks, pacing, statistics, the safety chain, ServoLoop
/// and MultiArmLoop (several arms on one deadline).
/// Knows only the Device and HapticField concepts.

#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/guidance.hpp"
#include "hapticfield/servo/loop.hpp"
#include "hapticfield/servo/multi_arm_loop.hpp"
#include "hapticfield/servo/pacer.hpp"
#include "hapticfield/servo/safety.hpp"
#include "hapticfield/servo/statistics.hpp"
#include "hapticfield/servo/traced_device.hpp"
