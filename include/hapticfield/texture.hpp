#pragma once
/// @file texture.hpp
/// Stochastic haptic textures and friction (Fritz & Barner, SPIE 1996) and
/// data-driven texture models in the Penn Haptic Texture Toolkit format.
/// Core only (GLM): the OpenCV helpers for image-driven maps live in
/// hapticfield/texture/image_maps.hpp, and the HaTT model-file reader
/// (pugixml, target hapticfield::hatt) in hapticfield/texture/hatt.hpp;
/// neither is included here.

#include "hapticfield/texture/arma.hpp"
#include "hapticfield/texture/data_texture.hpp"
#include "hapticfield/texture/fft.hpp"
#include "hapticfield/texture/fir.hpp"
#include "hapticfield/texture/friction.hpp"
#include "hapticfield/texture/hatt_model_set.hpp"
#include "hapticfield/texture/hatt_texture.hpp"
#include "hapticfield/texture/hatt_triangulation.hpp"
#include "hapticfield/texture/iir.hpp"
#include "hapticfield/texture/lattice.hpp"
#include "hapticfield/texture/local_sphere.hpp"
#include "hapticfield/texture/lsf.hpp"
#include "hapticfield/texture/noise.hpp"
#include "hapticfield/texture/spectral.hpp"
#include "hapticfield/texture/texture_field.hpp"
