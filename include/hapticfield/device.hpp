#pragma once
/// @file device.hpp
/// The device layer without hidapi: Device concept, Phantom-class
/// kinematics, the report protocol, transports (simulated, replay,
/// recording) and the simulated arm. For real hardware include
/// hapticfield/device/hid_transport.hpp and link hapticfield::hid.

#include "hapticfield/device/firmware_loopback.hpp"
#include "hapticfield/device/force_arm.hpp"
#include "hapticfield/device/inverse3.hpp"
#include "hapticfield/device/inverse3_codec.hpp"
#include "hapticfield/device/kinematics.hpp"
#include "hapticfield/device/link_faults.hpp"
#include "hapticfield/device/protocol.hpp"
#include "hapticfield/device/recording.hpp"
#include "hapticfield/device/simulated_arm.hpp"
#include "hapticfield/device/simulated_inverse3.hpp"
#include "hapticfield/device/simulated_transport.hpp"
#include "hapticfield/device/simulated_woody.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"
#include "hapticfield/device/stream_framer.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/device/woody_arm.hpp"
#include "hapticfield/device/woody_codec.hpp"
#include "hapticfield/device/woody_kinematics.hpp"
