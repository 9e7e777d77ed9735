#pragma once
/// @file device.hpp
/// The device seam, what every arm and every loop agrees on: DeviceState,
/// DeviceInfo and the Device concept, Status, the Transport interface and
/// DeviceError. The arms themselves: hapticfield/arms.hpp; the transports:
/// hapticfield/transport.hpp.

#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"
#include "hapticfield/device/transport.hpp"
