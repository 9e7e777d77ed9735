#pragma once
/// @file offline.hpp
/// Deprecated forwarding umbrella, kept so that existing includes still
/// build; include the component umbrellas (or the headers) instead. The
/// headers it once gathered now stand with what they are about: force-map
/// figures and the section 5 mask laws in kernels/, the FFT (and the PSD) in
/// texture/, the rotated-box stimulus in normals/. The bit-by-bit CRC
/// reference is a test oracle now (tests/crc16_reference.hpp).

#include "hapticfield/kernels/force_map_render.hpp"
#include "hapticfield/kernels/mask_choice.hpp"
#include "hapticfield/normals/box_stimulus.hpp"
#include "hapticfield/texture/fft.hpp"
