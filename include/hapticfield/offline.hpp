#pragma once
/// @file offline.hpp
/// Offline tools: code that never runs in a servo tick. Figures of force
/// maps, the tangible-images paper's section 5 laws for choosing a mask,
/// the rotated-box stimulus of the normals paper, the FFT the texture
/// figures and tests use, and the bit-by-bit CRC reference. Everything
/// outside offline/ that a field or the loop calls per tick is noexcept and
/// allocation-free.

#include "hapticfield/offline/box_stimulus.hpp"
#include "hapticfield/offline/crc16_reference.hpp"
#include "hapticfield/offline/fft.hpp"
#include "hapticfield/offline/force_map_render.hpp"
#include "hapticfield/offline/mask_choice.hpp"
