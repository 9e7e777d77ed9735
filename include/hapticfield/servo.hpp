#pragma once
/// @file servo.hpp
/// The servo loop: clocks, statistics, the safety chain and ServoLoop.
/// Knows only the Device and HapticField concepts.

#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/loop.hpp"
#include "hapticfield/servo/safety.hpp"
#include "hapticfield/servo/statistics.hpp"
