#pragma once
/// @file hapticfield.hpp
/// Umbrella header: every component of the library that is installed.

#include "hapticfield/arms.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/device.hpp"
#include "hapticfield/image.hpp"
#include "hapticfield/kernels.hpp"
#include "hapticfield/material.hpp"
#include "hapticfield/normals.hpp"
#include "hapticfield/physics.hpp"
#include "hapticfield/protocol.hpp"
#include "hapticfield/servo.hpp"
#include "hapticfield/simulation.hpp"
#include "hapticfield/surface.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "hapticfield/transport.hpp"
#include "hapticfield/vibration.hpp"
