#pragma once
/// @file normals.hpp
/// Normals from a picture (Kim & Kwon, World Haptics 2013): camera model,
/// homography, face pose, the synthetic box stimulus and the normal field.
/// Needs OpenCV (link hapticfield::image).

#include "hapticfield/core.hpp"
#include "hapticfield/normals/box_stimulus.hpp"
#include "hapticfield/normals/camera.hpp"
#include "hapticfield/normals/face_pose.hpp"
#include "hapticfield/normals/homography.hpp"
#include "hapticfield/normals/normal_field.hpp"
