#pragma once
/// @file image.hpp
/// Gray planes and picture loading (needs OpenCV).

#include "hapticfield/image/gray_image.hpp"
#include "hapticfield/image/grayscale.hpp"
#include "hapticfield/image/load.hpp"
#include "hapticfield/image/picture_size.hpp"
