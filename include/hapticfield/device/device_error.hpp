#pragma once
/// @file device_error.hpp
/// DeviceError: a device that cannot be found or opened (HidTransport,
/// SerialTransport); what() names the device or path and the cause.

#include "hapticfield/core/error.hpp"

namespace hapticfield {

/// No device matched, or it could not be opened.
class DeviceError : public Error {
 public:
  using Error::Error;
};

}  // namespace hapticfield
