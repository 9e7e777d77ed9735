#pragma once
/// @file kernels.hpp
/// Tangible images: masks, per-pixel kernels, force maps and the field
/// (needs OpenCV for pictures).

#include "hapticfield/image.hpp"
#include "hapticfield/kernels/border.hpp"
#include "hapticfield/kernels/direct_kernel.hpp"
#include "hapticfield/kernels/force_map.hpp"
#include "hapticfield/kernels/force_map_render.hpp"
#include "hapticfield/kernels/image_force.hpp"
#include "hapticfield/kernels/integral_kernel.hpp"
#include "hapticfield/kernels/mask.hpp"
#include "hapticfield/kernels/mask_choice.hpp"
#include "hapticfield/kernels/tangible_field.hpp"
#include "hapticfield/kernels/tangible_image.hpp"
