#pragma once
/// @file falcon.hpp
/// Novint Falcon: the codec, the kinematics, the USB seam, Falcon and the
/// simulated Falcon. The libusb link is arms/falcon/falcon_libusb.hpp (its
/// own target, hapticfield::falcon_usb), not included here.

#include "hapticfield/arms/falcon/falcon.hpp"
#include "hapticfield/arms/falcon/falcon_codec.hpp"
#include "hapticfield/arms/falcon/falcon_kinematics.hpp"
#include "hapticfield/arms/falcon/falcon_usb.hpp"
#include "hapticfield/arms/falcon/simulated_falcon.hpp"
