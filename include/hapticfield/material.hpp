#pragma once
/// @file material.hpp
/// Haptic materials: property and index maps over uv, materials sampled at
/// the proxy's uv (MaterialSurface), HaTT taxel maps, and the MPEG-I haptic
/// media model (.hjif) with its synthesis, playback and recording. Needs
/// OpenCV for maps from pictures (material_image.hpp). Not here: a model's
/// own textures (scenes/model_texture.hpp, a composition over what io/
/// reads) and the .hjif reader (io/hjif.hpp, hapticfield::hjif).

#include "hapticfield/material/band_synthesis.hpp"
#include "hapticfield/material/haptic_media.hpp"
#include "hapticfield/material/haptic_playback.hpp"
#include "hapticfield/material/haptic_recording.hpp"
#include "hapticfield/material/material_image.hpp"
#include "hapticfield/material/material_map.hpp"
#include "hapticfield/material/material_surface.hpp"
#include "hapticfield/material/property_map.hpp"
#include "hapticfield/material/taxel_map.hpp"
#include "hapticfield/material/wavelet_synthesis.hpp"
