#pragma once
/// @file renderer.hpp
/// VibrationRenderer: the audio callback. render(out) fills any number of
/// interleaved frames: it drains the contact ring (never waits), plays the
/// contact out behind the servo clock (playout.hpp), runs every routed
/// source once per frame and mixes each into its channel, clipped to
/// [-limit, limit]. noexcept and allocation-free: call it from an audio
/// thread, a sink's callback, or by hand in a test.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "hapticfield/vibration/contact_sample.hpp"
#include "hapticfield/vibration/playout.hpp"
#include "hapticfield/vibration/sources.hpp"

namespace hapticfield::vibration {

/// Most output channels (one per actuator).
inline constexpr int max_vibration_channels = 8;
/// Route::channel that sends a source to every channel.
inline constexpr int all_channels = -1;

/// A source and where it plays: only while the touched material matches
/// (any_material: always), into one channel or all of them.
template <VibrationSource S>
struct Route {
  S source;
  std::uint32_t material{any_material};
  int channel{all_channels};
  double gain{1.0};
};

/// route(source[, material, channel, gain])
template <VibrationSource S>
[[nodiscard]] Route<std::remove_cvref_t<S>> route(S&& source, std::uint32_t material = any_material,
                                                  int channel = all_channels, double gain = 1.0) {
  return {std::forward<S>(source), material, channel, gain};
}

struct RendererConfig {
  PlayoutConfig playout{};  ///< sample rate, delay, hold (playout.hpp)
  int channels{1};          ///< interleaved output channels, 1..8
  double limit{1.0};        ///< output clipped to [-limit, limit]

  /// @throws std::invalid_argument naming the bad parameter.
  void validate() const {
    playout.validate();
    if (channels < 1 || channels > max_vibration_channels)
      throw std::invalid_argument("RendererConfig: channels must be within 1..8");
    if (!(limit > 0.0 && std::isfinite(limit))) throw std::invalid_argument("RendererConfig: limit must be > 0");
  }
};

template <std::size_t N, VibrationSource... S>
class VibrationRenderer {
 public:
  /// Prepares every source for the audio rate.
  /// @throws std::invalid_argument for a bad configuration, a route to a
  ///         channel that does not exist, or a source that refuses the rate.
  VibrationRenderer(ContactRing<N>& ring, const RendererConfig& config, Route<S>... routes)
      : config_((config.validate(), config)), playout_(ring, config.playout), routes_(std::move(routes)...) {
    std::apply(
        [this](auto&... r) {
          ((r.channel < all_channels || r.channel >= config_.channels
                ? throw std::invalid_argument("VibrationRenderer: a route's channel is out of range")
                : prepare_if_needed(r.source, config_.playout.sample_rate)),
           ...);
        },
        routes_);
  }

  /// Fills out (interleaved, out.size() / channels() frames; a partial
  /// frame at the end is zeroed).
  void render(std::span<float> out) noexcept {
    const auto channels = static_cast<std::size_t>(config_.channels);
    const std::size_t frames = out.size() / channels;
    playout_.begin_block();
    for (std::size_t i = 0; i < frames; ++i) {
      const ContactState c = playout_.next();
      float* frame = out.data() + i * channels;
      std::array<double, max_vibration_channels> mix{};
      std::apply([&](auto&... r) { (play(r, c, mix), ...); }, routes_);
      for (std::size_t k = 0; k < channels; ++k) {
        double y = mix[k];
        if (std::isnan(y) || std::fabs(y) > config_.limit) {
          ++clipped_;
          y = std::isnan(y) ? 0.0 : std::copysign(config_.limit, y);
        }
        frame[k] = static_cast<float>(y);
      }
    }
    for (std::size_t i = frames * channels; i < out.size(); ++i)
      out[i] = 0.0f;
  }

  [[nodiscard]] int channels() const noexcept { return config_.channels; }
  [[nodiscard]] double sample_rate() const noexcept { return config_.playout.sample_rate; }
  [[nodiscard]] const PlayoutStatistics& statistics() const noexcept { return playout_.statistics(); }
  /// Output values clipped to the limit (or NaN replaced by 0).
  [[nodiscard]] std::uint64_t clipped() const noexcept { return clipped_; }
  [[nodiscard]] const ContactPlayout<N>& playout() const noexcept { return playout_; }
  /// The I-th route (to reach its source).
  template <std::size_t I>
  [[nodiscard]] auto& route() noexcept {
    return std::get<I>(routes_);
  }

 private:
  template <class R>
  void play(R& r, const ContactState& c, std::array<double, max_vibration_channels>& mix) noexcept {
    ContactState mine = c;
    if (r.material != any_material && r.material != c.material) mine.touching = false;
    const double y = r.gain * static_cast<double>(r.source.next(mine));
    if (r.channel == all_channels) {
      for (int k = 0; k < config_.channels; ++k)
        mix[static_cast<std::size_t>(k)] += y;
    } else {
      mix[static_cast<std::size_t>(r.channel)] += y;
    }
  }

  RendererConfig config_;
  ContactPlayout<N> playout_;
  std::tuple<Route<S>...> routes_;
  std::uint64_t clipped_{0};
};

/// renderer(ring, config, route(...), ...)
template <std::size_t N, VibrationSource... S>
[[nodiscard]] VibrationRenderer<N, S...> renderer(ContactRing<N>& ring, const RendererConfig& config,
                                                  Route<S>... routes) {
  return VibrationRenderer<N, S...>(ring, config, std::move(routes)...);
}

}  // namespace hapticfield::vibration
