#pragma once
/// @file haptic_recording.hpp
/// A run recorded from the servo loop (force, contact force, vibration) as a
/// haptic media (haptic_media.hpp), ready for io/hjif.hpp's save_hjif:
///   perception 0 "Force"        channels x, y, z: the commanded force
///   perception 1 "Pressure"     channel 0: the contact (constraint) force |Fc|
///   perception 2 "Vibrotactile" channel 0: the vibration (omitted when empty)
/// Each channel is one Curve band (curve_type Linear) with one effect at
/// position 0 and one keyframe per sample, amplitudes in [-1, 1] of the
/// channel's gain (the full-scale force [N] for force and contact, 1 for the
/// vibration), so render_channel gives newtons back. The timescale is the
/// vibration rate when the servo rate divides it, else 1,000,000 ticks/s;
/// sample times become the nearest tick. Setup-side code.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/material/haptic_media.hpp"

namespace hapticfield::material {

struct RecordedRun {
  double servo_rate{1000.0};      ///< ticks per second of force and contact [Hz]
  std::vector<glm::dvec3> force;  ///< commanded force per tick [N]
  std::vector<double> contact;    ///< |Fc| per tick [N] (empty: not recorded)
  double vibration_rate{8000.0};  ///< [Hz]
  std::vector<double> vibration;  ///< vibration output, nominal [-1, 1] (empty: not recorded)
  double full_scale_force{0.0};   ///< [N]; 0: the largest |component| recorded (at least 1e-9)
  std::string description{"recorded run"};
};

namespace detail {
[[nodiscard]] inline Channel curve_channel(std::int64_t id, std::string description, const std::vector<double>& v,
                                           double scale, double rate, std::int64_t timescale) {
  Channel c;
  c.id = id;
  c.description = std::move(description);
  c.gain = scale;
  Band b;
  b.type = BandType::curve;
  b.curve_type = CurveType::linear;
  b.has_curve_type = true;
  b.lower_frequency_limit = 0.0;
  b.upper_frequency_limit = std::floor(rate / 2.0);
  Effect e;
  e.keyframes.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double a = std::isfinite(v[i]) ? std::clamp(v[i] / scale, -1.0, 1.0) : 0.0;
    const auto t =
        static_cast<std::int64_t>(std::llround(static_cast<double>(i) * static_cast<double>(timescale) / rate));
    e.keyframes.push_back({t, a, std::nullopt});
  }
  b.effects.push_back(std::move(e));
  c.bands.push_back(std::move(b));
  return c;
}
}  // namespace detail

/// The run as a haptic media (see the file comment for its layout).
/// @throws std::invalid_argument for non-positive rates or nothing recorded.
[[nodiscard]] inline HapticMedia media_from_run(const RecordedRun& run) {
  if (!(run.servo_rate > 0.0) || !(run.vibration_rate > 0.0) || !std::isfinite(run.servo_rate) ||
      !std::isfinite(run.vibration_rate))
    throw std::invalid_argument("media_from_run: rates must be > 0 [Hz]");
  if (run.force.empty() && run.contact.empty() && run.vibration.empty())
    throw std::invalid_argument("media_from_run: nothing recorded");
  HapticMedia m;
  m.description = run.description;
  const double ratio = run.vibration_rate / run.servo_rate;
  m.timescale = (std::floor(run.vibration_rate) == run.vibration_rate && std::floor(ratio) == ratio)
                    ? static_cast<std::int64_t>(run.vibration_rate)
                    : 1'000'000;
  double full = run.full_scale_force;
  if (!(full > 0.0)) {
    full = 1e-9;
    for (const glm::dvec3& f : run.force)
      for (int a = 0; a < 3; ++a)
        if (std::isfinite(f[a])) full = std::max(full, std::abs(f[a]));
    for (double c : run.contact)
      if (std::isfinite(c)) full = std::max(full, std::abs(c));
  }
  if (!run.force.empty()) {
    Perception p;
    p.id = 0;
    p.description = "commanded force [N]";
    p.modality = "Force";
    const char* axis[] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      std::vector<double> v(run.force.size());
      for (std::size_t i = 0; i < v.size(); ++i)
        v[i] = run.force[i][a];
      p.channels.push_back(
          detail::curve_channel(a, std::string("force ") + axis[a] + " [N]", v, full, run.servo_rate, m.timescale));
    }
    m.perceptions.push_back(std::move(p));
  }
  if (!run.contact.empty()) {
    Perception p;
    p.id = static_cast<std::int64_t>(m.perceptions.size());
    p.description = "contact force |Fc| [N]";
    p.modality = "Pressure";
    p.channels.push_back(detail::curve_channel(0, "contact |Fc| [N]", run.contact, full, run.servo_rate, m.timescale));
    m.perceptions.push_back(std::move(p));
  }
  if (!run.vibration.empty()) {
    Perception p;
    p.id = static_cast<std::int64_t>(m.perceptions.size());
    p.description = "vibration";
    p.modality = "Vibrotactile";
    p.channels.push_back(detail::curve_channel(0, "vibration", run.vibration, 1.0, run.vibration_rate, m.timescale));
    m.perceptions.push_back(std::move(p));
  }
  return m;
}

}  // namespace hapticfield::material
