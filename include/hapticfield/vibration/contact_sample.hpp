#pragma once
/// @file contact_sample.hpp
/// What the servo thread hands to the audio side once per tick: the
/// contact state (tangential speed, |Fc|, the touched material, time), and
/// the ring that carries it (rt::SpscRing: try_push / try_pop only).

#include <cstddef>
#include <cstdint>

#include "hapticfield/rt/spsc_ring.hpp"

namespace hapticfield::vibration {

/// Material id that matches every material (Route::material).
inline constexpr std::uint32_t any_material = UINT32_MAX;

/// One tick's contact, pushed by the servo thread.
struct ContactSample {
  double time{0.0};           ///< the tick's time since the loop started (Probe::time) [s]
  double speed{0.0};          ///< tangential speed of the HIP on the surface [m/s]
  double normal_force{0.0};   ///< |Fc| of this tick [N]; 0: no contact
  std::uint32_t material{0};  ///< id of the touched material (the user's numbering)
};

/// The contact as the audio side sees it at one audio frame: interpolated
/// between the two ticks around the frame's play time.
struct ContactState {
  double speed{0.0};          ///< [m/s]
  double normal_force{0.0};   ///< [N]
  std::uint32_t material{0};  ///< the material of the tick at or before the play time
  bool touching{false};       ///< normal_force > 0 and the servo side is still sending
};

/// The servo -> audio handoff. 256 samples hold 256 ms of a 1 kHz loop.
template <std::size_t N = 256>
using ContactRing = rt::SpscRing<ContactSample, N>;

}  // namespace hapticfield::vibration
