#pragma once
/// @file scenes.hpp
/// Ready-made compositions: a shape, a proxy and a field built in one call
/// from what io/ reads. picture_relief() (a picture's gray levels as a
/// relief with its tangible-image force laid on it) and textured_model() (a
/// mesh felt with its own base-colour texture; relief_model() adds its gray
/// levels as a relief). Never in a tick but the
/// force() of what they return. Needs hapticfield::io (mesh readers) and
/// OpenCV; not in hapticfield.hpp, which leaves io/ out.

#include "hapticfield/scenes/model_relief.hpp"
#include "hapticfield/scenes/model_texture.hpp"
#include "hapticfield/scenes/picture_relief.hpp"
