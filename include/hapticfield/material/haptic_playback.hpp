#pragma once
/// @file haptic_playback.hpp
/// Plays a rendered haptic channel (band_synthesis.hpp) on contact or on a
/// trigger. The signal is rendered and resampled before the stream starts;
/// what runs per audio frame or per tick only reads the buffer: no
/// allocation, lock, exception or I/O.
///
///   ClipSource           a vibration source (vibration/sources.hpp's
///                        VibrationSource): the vibration path
///   NormalClipField<F>   a field decorator adding the clip along the surface
///                        normal at servo rate: the force path, for arms with
///                        no vibration actuator

#include <atomic>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/vibration/contact_sample.hpp"

namespace hapticfield::material {

/// When a clip starts.
enum class ClipStart {
  on_contact,  ///< at each touch (the contact's rising edge)
  on_trigger   ///< at each trigger() call, touching or not
};

struct ClipConfig {
  double rate{8000.0};  ///< rate the clip was rendered at [Hz]
  double gain{1.0};     ///< output per clip unit [-] (NormalClipField: [N])
  ClipStart start{ClipStart::on_contact};
  double full_force{0.0};  ///< > 0: the output also scales with min(|Fc| / full_force, 1) [N]
};

namespace detail {

/// The clip resampled (linear interpolation) to `rate` [Hz]. Setup only.
[[nodiscard]] inline std::vector<double> resample_clip(const std::vector<double>& clip, double from, double to) {
  if (clip.empty()) throw std::invalid_argument("clip: the signal is empty");
  if (!(from > 0.0) || !(to > 0.0) || !std::isfinite(from) || !std::isfinite(to))
    throw std::invalid_argument("clip: rates must be > 0 [Hz]");
  const double duration = static_cast<double>(clip.size() - 1) / from;
  const auto n = static_cast<std::size_t>(std::floor(duration * to + 1e-9)) + 1;
  if (n > (std::size_t{1} << 28)) throw std::invalid_argument("clip: longer than 2^28 samples at the output rate");
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(i) * from / to;
    const auto k = static_cast<std::size_t>(x);
    const double w = x - static_cast<double>(k);
    const double a = clip[std::min(k, clip.size() - 1)], b = clip[std::min(k + 1, clip.size() - 1)];
    out[i] = std::isfinite(a + w * (b - a)) ? a + w * (b - a) : 0.0;
  }
  return out;
}

}  // namespace detail

/// A rendered channel played once per touch or per trigger on the vibration path.
class ClipSource {
 public:
  /// @throws std::invalid_argument for an empty clip or a bad rate.
  ClipSource(std::vector<double> clip, ClipConfig config) : clip_(std::move(clip)), config_(config) {
    if (clip_.empty()) throw std::invalid_argument("ClipSource: the clip is empty");
    if (!(config.rate > 0.0) || !std::isfinite(config.gain) || !(config.full_force >= 0.0))
      throw std::invalid_argument("ClipSource: rate must be > 0, gain finite, full_force >= 0");
    played_ = clip_;
  }
  /// Resamples the clip to the audio rate (setup: allocates).
  void prepare(double sample_rate) { played_ = detail::resample_clip(clip_, config_.rate, sample_rate); }
  /// Starts the clip at the next frame (ClipStart::on_trigger); callable from any thread.
  void trigger() noexcept { triggered_.store(true, std::memory_order_release); }

  [[nodiscard]] double next(const vibration::ContactState& c) noexcept {
    const bool start = config_.start == ClipStart::on_contact ? (c.touching && !was_touching_)
                                                              : triggered_.exchange(false, std::memory_order_acq_rel);
    was_touching_ = c.touching;
    if (start) index_ = 0;
    if (index_ >= played_.size()) return 0.0;
    double y = config_.gain * played_[index_++];
    if (config_.full_force > 0.0) y *= std::fmin(c.normal_force / config_.full_force, 1.0);
    return std::isfinite(y) ? y : 0.0;
  }
  [[nodiscard]] bool playing() const noexcept { return index_ < played_.size(); }

 private:
  std::vector<double> clip_;
  std::vector<double> played_;
  ClipConfig config_;
  std::size_t index_{static_cast<std::size_t>(-1)};
  bool was_touching_{false};
  std::atomic<bool> triggered_{false};
};

/// The force path: `field`'s force plus gain x clip(t - touch time) along the
/// surface normal while touching (ClipConfig::start on_contact), or from each
/// trigger(). The clip is read at the probe's time by linear interpolation.
template <HapticField F>
class NormalClipField {
 public:
  /// @throws std::invalid_argument for an empty clip or a bad rate.
  NormalClipField(F field, std::vector<double> clip, ClipConfig config)
      : field_(std::move(field)), clip_(std::move(clip)), config_(config) {
    if (clip_.empty()) throw std::invalid_argument("NormalClipField: the clip is empty");
    if (!(config.rate > 0.0) || !std::isfinite(config.gain) || !(config.full_force >= 0.0))
      throw std::invalid_argument("NormalClipField: rate must be > 0, gain finite, full_force >= 0");
  }
  void trigger() noexcept { triggered_.store(true, std::memory_order_release); }

  [[nodiscard]] glm::dvec3 force(const Probe& p) noexcept {
    const glm::dvec3 base = field_.force(p);
    const bool touching = p.normal_force > 0.0;
    const bool start = config_.start == ClipStart::on_contact ? (touching && !was_touching_)
                                                              : triggered_.exchange(false, std::memory_order_acq_rel);
    was_touching_ = touching;
    if (start) start_time_ = p.time, active_ = true;
    if (!active_ || (config_.start == ClipStart::on_contact && !touching)) return base;
    const double x = (p.time - start_time_) * config_.rate;
    if (!(x >= 0.0) || x > static_cast<double>(clip_.size() - 1)) {
      active_ = false;
      return base;
    }
    const auto k = static_cast<std::size_t>(x);
    const double w = x - static_cast<double>(k);
    const double a = clip_[k], b = clip_[std::min(k + 1, clip_.size() - 1)];
    double y = config_.gain * (a + w * (b - a));
    if (config_.full_force > 0.0) y *= std::fmin(p.normal_force / config_.full_force, 1.0);
    if (!std::isfinite(y)) return base;
    return base + y * p.surface_normal;
  }
  [[nodiscard]] F& field() noexcept { return field_; }

 private:
  F field_;
  std::vector<double> clip_;
  ClipConfig config_;
  double start_time_{0.0};
  bool active_{false};
  bool was_touching_{false};
  std::atomic<bool> triggered_{false};
};

}  // namespace hapticfield::material
