#pragma once
/// @file hatt.hpp
/// Data-driven texture models in the Penn Haptic Texture Toolkit format
/// (Culbertson, Lopez Delgado & Kuchenbecker, "One hundred data-driven haptic
/// texture models and open-source methods for rendering on 3D objects",
/// IEEE Haptics Symposium 2014): everything needed to load a modelSet file
/// and render it. Link hapticfield::hatt (GLM + pugixml).
///
///   texture/lsf.hpp                LSF <-> AR polynomial conversion
///   texture/hatt_model_set.hpp     HattModel, HattModelSet (plain data)
///   texture/hatt_model_file.hpp    parse_hatt_model_set, load_hatt_model_set (pugixml)
///   texture/hatt_triangulation.hpp barycentric point location
///   texture/hatt_texture.hpp       HattTexture, the field (GLM only)
///
/// The toolkit's files cannot ship with this project (their licence forbids
/// redistribution); see docs/textures.md for where to get them.

#include "hapticfield/texture/hatt_model_file.hpp"
#include "hapticfield/texture/hatt_model_set.hpp"
#include "hapticfield/texture/hatt_texture.hpp"
#include "hapticfield/texture/hatt_triangulation.hpp"
#include "hapticfield/texture/lsf.hpp"
