#pragma once
/// @file hatt_source.hpp
/// HattSource: a Penn Haptic Texture Toolkit model set (Culbertson, Lopez
/// Delgado & Kuchenbecker, IEEE Haptics Symposium 2014) rendered on the
/// audio side at the model's own rate (10 kHz for the toolkit's models),
/// driven by the interpolated contact state. So the model's spectrum up to
/// its Nyquist frequency reaches the actuator, which a 1 kHz force loop
/// cannot carry (texture/hatt_texture.hpp folds it below 500 Hz).
///
/// Every update_every model steps the (speed, |Fc|) of the contact is
/// located in the set's triangulation; the AR (and MA) LSFs, the variance
/// and the gain are interpolated barycentrically and turned into
/// polynomials (texture/lsf.hpp). Each model step draws Gaussian noise of
/// that variance through the filter. Model samples reach the audio rate by
/// Catmull-Rom interpolation (exact at equal rates: the model's own
/// samples, two model steps late). Off contact, or below the velocity
/// threshold, the noise stops and the filter rings down.
/// At most max_hatt_steps_per_sample model steps run per audio frame, so an
/// audio callback's work is bounded whatever the model's rate: a model
/// faster than that many times the audio rate (never one read from a file,
/// whose rate is at most 100 kHz, at an audio rate of 6.25 kHz or more)
/// runs slower than its own time, its pitch lowered, instead of stalling.
/// Output: gain x acceleration [m/s^2]. GLM only (model files are read by
/// texture/hatt_model_file.hpp, which needs pugixml).

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "hapticfield/texture/hatt_model_set.hpp"
#include "hapticfield/texture/hatt_triangulation.hpp"
#include "hapticfield/texture/lsf.hpp"
#include "hapticfield/texture/noise.hpp"
#include "hapticfield/vibration/contact_sample.hpp"

namespace hapticfield::vibration {

struct HattSourceConfig {
  double gain{0.1};                 ///< output per m/s^2 [s^2/m] (0.1: 10 m/s^2 is full scale)
  double velocity_threshold{1e-3};  ///< silent below this speed [m/s]
  int update_every{10};             ///< model steps between coefficient updates (10: 1 kHz at 10 kHz), >= 1
  std::uint32_t seed{1};            ///< noise seed
};

/// Most model steps HattSource::next() runs for one audio frame.
inline constexpr int max_hatt_steps_per_sample = 16;

template <std::size_t MaxOrder = 32>
class HattSource {
 public:
  /// @throws std::invalid_argument for orders above MaxOrder, an invalid set
  ///         or a bad configuration.
  HattSource(const texture::HattModelSet& set, HattSourceConfig config)
      : tri_(set.speeds, set.forces, set.triangles),
        config_(config),
        p_(set.ar_order),
        q_(set.ma_order),
        speed_to_file_(set.speed_to_file),
        accel_to_si_(set.acceleration_to_si),
        model_rate_(set.sample_rate) {
    if (p_ < 1 || p_ > MaxOrder || q_ > MaxOrder) throw std::invalid_argument("HattSource: AR/MA order above MaxOrder");
    if (config.update_every < 1) throw std::invalid_argument("HattSource: update_every must be >= 1");
    if (!std::isfinite(config.gain) || !(config.velocity_threshold >= 0.0))
      throw std::invalid_argument("HattSource: gain must be finite and velocity_threshold >= 0 [m/s]");
    if (!(set.sample_rate > 0.0) || set.models.size() != set.speeds.size())
      throw std::invalid_argument("HattSource: need a positive sample rate and one model per vertex");
    for (const auto& m : set.models) {
      if (m.ar_lsf.size() != p_ || m.ma_lsf.size() != q_)
        throw std::invalid_argument("HattSource: every model needs numARCoeff AR and numMACoeff MA LSFs");
      ar_lsf_.insert(ar_lsf_.end(), m.ar_lsf.begin(), m.ar_lsf.end());
      ma_lsf_.insert(ma_lsf_.end(), m.ma_lsf.begin(), m.ma_lsf.end());
      variance_.push_back(m.variance);
      gain_.push_back(m.gain);
    }
    update(0.0, 0.0);
  }

  /// The audio rate [Hz]; the model keeps its own.
  void prepare(double sample_rate) {
    if (!(sample_rate >= 1000.0 && sample_rate <= 192000.0))
      throw std::invalid_argument("HattSource: sample rate must be within [1000, 192000] [Hz]");
    advance_ = model_rate_ / sample_rate;
  }

  [[nodiscard]] double next(const ContactState& c) noexcept {
    const bool active =
        c.touching && c.speed >= config_.velocity_threshold && std::isfinite(c.speed) && std::isfinite(c.normal_force);
    position_ += advance_;
    if (position_ >= static_cast<double>(max_hatt_steps_per_sample))  // bounded work: drop the model time beyond
      position_ = static_cast<double>(max_hatt_steps_per_sample) + (position_ - std::floor(position_));
    while (position_ >= 1.0) {
      position_ -= 1.0;
      if (active && (!was_active_ || ++since_update_ >= config_.update_every)) {
        since_update_ = 0;
        update(c.speed * speed_to_file_, c.normal_force);
      }
      was_active_ = active;
      h_[0] = h_[1];
      h_[1] = h_[2];
      h_[2] = h_[3];
      h_[3] = step(active);
    }
    // Catmull-Rom between h_[1] and h_[2]
    const double t = position_;
    const double y =
        h_[1] +
        0.5 * t *
            (h_[2] - h_[0] +
             t * (2.0 * h_[0] - 5.0 * h_[1] + 4.0 * h_[2] - h_[3] + t * (3.0 * (h_[1] - h_[2]) + h_[3] - h_[0])));
    const double out = config_.gain * accel_to_si_ * y;
    return std::isfinite(out) ? out : 0.0;
  }

  /// Recomputes the filter for (speed [file unit], force [N]); noexcept and
  /// allocation-free.
  void update(double speed_file_units, double force) noexcept {
    where_ = tri_.locate(speed_file_units, force, where_.triangle);
    std::array<double, MaxOrder> lsf{}, mlsf{};
    variance_now_ = 0.0;
    gain_now_ = 0.0;
    for (std::size_t k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(where_.vertex[k]);
      const double w = where_.weight[k];
      for (std::size_t i = 0; i < p_; ++i)
        lsf[i] += w * ar_lsf_[v * p_ + i];
      for (std::size_t i = 0; i < q_; ++i)
        mlsf[i] += w * ma_lsf_[v * q_ + i];
      variance_now_ += w * variance_[v];
      gain_now_ += w * gain_[v];
    }
    (void)texture::lsf_to_ar<MaxOrder>(std::span<const double>(lsf.data(), p_), std::span<double>(ar_.data(), p_ + 1));
    if (q_ > 0)
      (void)texture::lsf_to_ar<MaxOrder>(std::span<const double>(mlsf.data(), q_),
                                         std::span<double>(ma_.data(), q_ + 1));
  }

  /// Current AR polynomial 1, a_1..a_p.
  [[nodiscard]] std::span<const double> ar_coefficients() const noexcept { return {ar_.data(), p_ + 1}; }
  [[nodiscard]] double variance() const noexcept { return variance_now_; }
  [[nodiscard]] double model_rate() const noexcept { return model_rate_; }
  /// Model steps run so far (at most max_hatt_steps_per_sample per next()).
  [[nodiscard]] std::uint64_t model_steps() const noexcept { return count_; }

 private:
  double step(bool active) noexcept {
    const std::uint64_t n = count_++;
    const double x = active ? std::sqrt(variance_now_) *
                                  texture::gaussian(config_.seed, texture::Cell{static_cast<std::uint32_t>(n),
                                                                                static_cast<std::uint32_t>(n >> 32), 1})
                            : 0.0;
    double y = x;
    if (q_ > 0) {
      y = ma_[0] * x;
      for (std::size_t k = 1; k <= q_; ++k)
        y += ma_[k] * x_hist_[k - 1];
      y *= gain_now_;
      for (std::size_t k = q_; k-- > 1;)
        x_hist_[k] = x_hist_[k - 1];
      x_hist_[0] = x;
    }
    for (std::size_t k = 1; k <= p_; ++k)
      y -= ar_[k] * y_hist_[k - 1];
    for (std::size_t k = p_; k-- > 1;)
      y_hist_[k] = y_hist_[k - 1];
    y_hist_[0] = y;
    return y;
  }

  texture::HattTriangulation tri_;
  HattSourceConfig config_;
  std::size_t p_;
  std::size_t q_;
  double speed_to_file_;
  double accel_to_si_;
  double model_rate_;  // [Hz]
  std::vector<double> ar_lsf_, ma_lsf_, variance_, gain_;
  texture::Barycentric where_{};
  std::array<double, MaxOrder + 1> ar_{};
  std::array<double, MaxOrder + 1> ma_{};
  std::array<double, MaxOrder> x_hist_{};
  std::array<double, MaxOrder> y_hist_{};
  std::array<double, 4> h_{};  // the last four model samples, oldest first
  double variance_now_{0.0};
  double gain_now_{1.0};
  double advance_{1.0};   // model steps per audio frame
  double position_{0.0};  // fraction of a model step since h_[1]
  std::uint64_t count_{0};
  int since_update_{0};
  bool was_active_{false};
};

}  // namespace hapticfield::vibration
