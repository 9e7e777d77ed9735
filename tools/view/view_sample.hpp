#pragma once
/// @file view_sample.hpp
/// What the servo thread tells the viewer each tick. The viewer hands these
/// from the servo thread to its own through rt::SpscRing
/// (hapticfield/rt/spsc_ring.hpp): a full ring refuses the newest sample
/// (the viewer is behind); the servo thread never waits.

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hapticfield::view {

/// One servo tick as the viewer draws it.
struct ViewSample {
  double t{0.0};          ///< loop time [s]
  glm::dvec2 pixel{0.0};  ///< probe in the picture [px] (x right, y down)
  glm::dvec3 force{0.0};  ///< commanded force, device frame [N]
};

}  // namespace hapticfield::view
