#pragma once
/// @file hapticfield.hpp
/// Umbrella header: every component of the library that is installed.

#include "hapticfield/core.hpp"
#include "hapticfield/device.hpp"
#include "hapticfield/image.hpp"
#include "hapticfield/kernels.hpp"
#include "hapticfield/normals.hpp"
#include "hapticfield/offline.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/surface.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "hapticfield/vibration.hpp"
