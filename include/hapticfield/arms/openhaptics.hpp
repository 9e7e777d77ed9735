#pragma once
/// @file openhaptics.hpp
/// OpenHaptics HD arms (3D Systems Touch, Phantom), loaded at run time:
/// the HDAPI declarations and OpenHapticsDevice.

#include "hapticfield/arms/openhaptics/hd_api.hpp"
#include "hapticfield/arms/openhaptics/openhaptics_device.hpp"
#include "hapticfield/arms/openhaptics/openhaptics_servo.hpp"
