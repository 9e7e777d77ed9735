#pragma once
/// @file transport.hpp
/// Transports that need no system library: RecordingTransport and
/// ReplayTransport. For real hardware include
/// hapticfield/transport/hid_transport.hpp (link hapticfield::hid) or
/// hapticfield/transport/serial_transport.hpp (POSIX). Each arm family's
/// simulated transport stands with that family (hapticfield/arms.hpp).

#include "hapticfield/transport/recording.hpp"
