#pragma once
/// @file sources.hpp
/// Vibration sources: what the audio side runs once per audio frame, given
/// the interpolated contact state. A source is anything with
/// `double next(const ContactState&) noexcept` (one output sample, nominal
/// range [-1, 1]); one with `void prepare(double sample_rate)` is told the
/// audio rate before the stream starts (setup: may allocate and throw).
/// A source keeps running while the contact is off (touching false) so
/// filters ring down instead of stopping on a click; it should output
/// silence, or decay to it.
///
///   ToneSource      a sine whose amplitude follows the speed (and force)
///   SignalSource    a recorded vibration (e.g. a WAV file) replayed at the
///                   speed of the stroke
///   TextureSource   any HapticField (a texture) sampled at audio rate along
///                   a stroke at the contact's speed
///   HattSource      (hatt_source.hpp) a HaTT model at its own rate

#include <cmath>
#include <concepts>
#include <cstddef>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/vibration/contact_sample.hpp"

namespace hapticfield::vibration {

template <class S>
concept VibrationSource = requires(S& source, const ContactState& contact) {
  { source.next(contact) }
  noexcept->std::convertible_to<double>;
};

/// A source that wants the audio rate before it runs.
template <class S>
concept PreparedSource = VibrationSource<S> && requires(S& source, double rate) {
  source.prepare(rate);
};

/// Calls source.prepare(rate) when the source has it.
template <VibrationSource S>
void prepare_if_needed(S& source, double sample_rate) {
  if constexpr (PreparedSource<S>) source.prepare(sample_rate);
}

namespace detail {
inline void check_rate(double sample_rate, const char* who) {
  if (!(sample_rate >= 1000.0 && sample_rate <= 192000.0))
    throw std::invalid_argument(std::string(who) + ": sample rate must be within [1000, 192000] [Hz]");
}
}  // namespace detail

struct ToneConfig {
  double frequency{250.0};  ///< [Hz] (250 Hz: where the skin's Pacinian channel is most sensitive)
  double amplitude{0.5};    ///< output amplitude at full_speed [-]
  double full_speed{0.1};   ///< speed of full amplitude [m/s]; the amplitude grows linearly up to it
  double full_force{0.0};   ///< > 0: the amplitude also scales with normal_force / full_force [N]
};

/// A sine whose amplitude follows the contact: a simple cue per material.
class ToneSource {
 public:
  /// @throws std::invalid_argument for a non-positive frequency or full_speed.
  explicit ToneSource(ToneConfig config = {}) : config_(config) {
    if (!(config.frequency > 0.0) || !(config.full_speed > 0.0) || !std::isfinite(config.amplitude) ||
        !(config.full_force >= 0.0))
      throw std::invalid_argument("ToneSource: frequency and full_speed must be > 0, full_force >= 0");
  }
  void prepare(double sample_rate) {
    detail::check_rate(sample_rate, "ToneSource");
    step_ = 2.0 * std::numbers::pi * config_.frequency / sample_rate;
  }
  [[nodiscard]] double next(const ContactState& c) noexcept {
    phase_ += step_;
    if (phase_ > 2.0 * std::numbers::pi) phase_ -= 2.0 * std::numbers::pi;
    if (!c.touching) return 0.0;
    double a = config_.amplitude * std::fmin(c.speed / config_.full_speed, 1.0);
    if (config_.full_force > 0.0) a *= std::fmin(c.normal_force / config_.full_force, 1.0);
    return a * std::sin(phase_);
  }

 private:
  ToneConfig config_;
  double step_{0.0};
  double phase_{0.0};
};

struct SignalConfig {
  double sample_rate{48000.0};  ///< rate of the recording [Hz]
  double recorded_speed{0.1};   ///< stroke speed of the recording [m/s]: played at speed / recorded_speed
  double recorded_force{0.0};   ///< > 0: amplitude scales with normal_force / recorded_force [N]
  double gain{1.0};             ///< output per recorded unit [-]
};

/// A recorded vibration (one channel), looped, replayed at the rate of the
/// stroke: a stroke at twice the recorded speed plays it twice as fast
/// (every frequency doubled), as dragging over the same surface would.
class SignalSource {
 public:
  /// @throws std::invalid_argument for an empty signal or a bad configuration.
  SignalSource(std::vector<float> signal, SignalConfig config) : signal_(std::move(signal)), config_(config) {
    if (signal_.size() < 2) throw std::invalid_argument("SignalSource: the signal needs at least 2 samples");
    detail::check_rate(config.sample_rate, "SignalSource");
    if (!(config.recorded_speed > 0.0) || !(config.recorded_force >= 0.0) || !std::isfinite(config.gain))
      throw std::invalid_argument("SignalSource: recorded_speed must be > 0, recorded_force >= 0, gain finite");
  }
  void prepare(double sample_rate) {
    detail::check_rate(sample_rate, "SignalSource");
    ratio_ = config_.sample_rate / sample_rate;
  }
  [[nodiscard]] double next(const ContactState& c) noexcept {
    if (!c.touching || !(c.speed > 0.0)) return 0.0;
    const auto n = static_cast<double>(signal_.size());
    position_ += ratio_ * std::fmin(c.speed / config_.recorded_speed, 16.0);
    if (position_ >= n) position_ = std::fmod(position_, n);
    const auto i = static_cast<std::size_t>(position_);
    const double w = position_ - static_cast<double>(i);
    const double a = signal_[i], b = signal_[i + 1 < signal_.size() ? i + 1 : 0];
    double y = config_.gain * (a + w * (b - a));
    if (config_.recorded_force > 0.0) y *= c.normal_force / config_.recorded_force;
    return y;
  }

 private:
  std::vector<float> signal_;
  SignalConfig config_;
  double ratio_{1.0};
  double position_{0.0};
};

struct TextureSourceConfig {
  glm::dvec3 axis{0.0, 0.0, 1.0};  ///< output = gain x (force . axis)
  double gain{1.0};                ///< output per newton [1/N]
};

/// Any field (a texture) as a vibration: a probe strokes along +x on the
/// plane z = 0 at the contact's speed, with the contact's |Fc| and normal
/// +z, one probe step per audio frame; the output is the force along `axis`.
template <HapticField F>
class TextureSource {
 public:
  explicit TextureSource(F field, TextureSourceConfig config = {}) : field_(std::move(field)), config_(config) {}
  void prepare(double sample_rate) {
    detail::check_rate(sample_rate, "TextureSource");
    probe_.period = 1.0 / sample_rate;
    probe_.surface_normal = {0.0, 0.0, 1.0};
  }
  [[nodiscard]] double next(const ContactState& c) noexcept {
    probe_.time += probe_.period;
    if (!c.touching) return 0.0;
    probe_.velocity = {c.speed, 0.0, 0.0};
    probe_.position.x += c.speed * probe_.period;
    probe_.normal_force = c.normal_force;
    const double y = config_.gain * glm::dot(glm::dvec3(field_.force(probe_)), config_.axis);
    return std::isfinite(y) ? y : 0.0;
  }
  [[nodiscard]] F& field() noexcept { return field_; }

 private:
  F field_;
  TextureSourceConfig config_;
  Probe probe_{};
};

}  // namespace hapticfield::vibration
