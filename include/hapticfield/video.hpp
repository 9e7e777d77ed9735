#pragma once
/// @file video.hpp
/// Tangible video: a video felt at 1 kHz (needs OpenCV with videoio).

#include "hapticfield/kernels.hpp"
#include "hapticfield/video/denoise.hpp"
#include "hapticfield/video/frame_preparer.hpp"
#include "hapticfield/video/frame_window.hpp"
#include "hapticfield/video/playback_clock.hpp"
#include "hapticfield/video/scene_cut.hpp"
#include "hapticfield/video/sequence_pattern.hpp"
#include "hapticfield/video/video_field.hpp"
#include "hapticfield/video/video_source.hpp"
#include "hapticfield/video/video_timeline.hpp"
