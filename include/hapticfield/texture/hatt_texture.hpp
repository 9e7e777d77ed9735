#pragma once
/// @file hatt_texture.hpp
/// A HaTT modelSet rendered as a HapticField (Culbertson, Lopez Delgado &
/// Kuchenbecker, "One hundred data-driven haptic texture models and
/// open-source methods for rendering on 3D objects", IEEE Haptics Symposium
/// 2014). Each tick the renderer locates the current (speed, force) in the
/// triangulation, interpolates the models' LSFs and variance
/// barycentrically (interpolated LSFs stay sorted, so the AR filter stays
/// stable), converts the LSFs to AR coefficients, drives the filter with
/// Gaussian noise of that variance and turns the acceleration into a force
/// through an effective mass; Coulomb friction mu |Fc| opposes the motion.
/// GLM only: reading model files (pugixml) is in hatt_model_file.hpp.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/surface_frame.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/texture/hatt_model_set.hpp"
#include "hapticfield/texture/hatt_triangulation.hpp"
#include "hapticfield/texture/lsf.hpp"
#include "hapticfield/texture/noise.hpp"

namespace hapticfield::texture {

struct HattConfig {
  double effective_mass{0.05};               ///< acceleration [m/s^2] -> force [N] (stylus + hand) [kg]
  glm::dvec3 surface_normal{0.0, 0.0, 1.0};  ///< unit; vibration along it, speed and friction in the tangent plane
  std::uint32_t seed{1};                     ///< noise seed
  int update_every{1};                       ///< ticks between coefficient updates (>= 1)
  double velocity_threshold{1e-3};           ///< silent below this tangential speed [m/s]
  bool friction{true};                       ///< add mu |Fc| Coulomb friction
  /// Run the model at its own sample rate: round(sample rate x tick period)
  /// AR steps per tick (at most max_hatt_steps_per_tick), output the newest,
  /// so a 10 kHz model in a 1 kHz loop keeps its spectrum below the loop's
  /// Nyquist frequency instead of being compressed ten times. false: one
  /// step per tick.
  bool match_sample_rate{true};
};

/// Most AR steps one tick runs when matching the model's sample rate.
inline constexpr int max_hatt_steps_per_tick = 256;

/// A HaTT model set as a HapticField. MaxOrder bounds the AR and MA orders
/// (storage is fixed at construction; force() never allocates). The model
/// runs at its own sample rate (HaTT models are identified at 10 kHz): each
/// tick advances it by the tick's period and renders the newest sample, so
/// content above the loop's Nyquist frequency folds down, as any sampled
/// display of the signal would.
template <std::size_t MaxOrder = 32>
class HattTexture {
 public:
  /// @throws std::invalid_argument for orders above MaxOrder, a bad
  ///         effective mass, normal or update period, or an invalid set.
  HattTexture(const HattModelSet& set, const HattConfig& params)
      : tri_(set.speeds, set.forces, set.triangles),
        config_(params),
        p_order_(set.ar_order),
        q_order_(set.ma_order),
        mu_(set.mu),
        speed_to_file_(set.speed_to_file),
        accel_to_si_(set.acceleration_to_si),
        sample_rate_(set.sample_rate) {
    if (set.ar_order < 1 || set.ar_order > MaxOrder || set.ma_order > MaxOrder)
      throw std::invalid_argument("HattTexture: AR/MA order above MaxOrder");
    if (!std::isfinite(params.effective_mass) || params.effective_mass < 0.0)
      throw std::invalid_argument("HattTexture: effective_mass must be finite and >= 0 [kg]");
    if (std::fabs(glm::length(params.surface_normal) - 1.0) > 1e-9)
      throw std::invalid_argument("HattTexture: surface_normal must be a unit vector");
    if (params.update_every < 1) throw std::invalid_argument("HattTexture: update_every must be >= 1 [ticks]");
    if (!std::isfinite(params.velocity_threshold) || params.velocity_threshold < 0.0)
      throw std::invalid_argument("HattTexture: velocity_threshold must be finite and >= 0 [m/s]");
    if (set.models.size() != set.speeds.size()) throw std::invalid_argument("HattTexture: one model per vertex needed");
    for (const auto& m : set.models) {
      if (m.ar_lsf.size() != p_order_ || m.ma_lsf.size() != q_order_)
        throw std::invalid_argument("HattTexture: every model needs numARCoeff AR and numMACoeff MA LSFs");
      ar_lsf_.insert(ar_lsf_.end(), m.ar_lsf.begin(), m.ar_lsf.end());
      ma_lsf_.insert(ma_lsf_.end(), m.ma_lsf.begin(), m.ma_lsf.end());
      variance_.push_back(m.variance);
      gain_.push_back(m.gain);
    }
    update(0.0, 0.0);
  }

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    if (!is_finite(probe.velocity) || !std::isfinite(probe.normal_force) || !is_finite(probe.surface_normal))
      return glm::dvec3{0.0};
    // The touched surface's normal (contact composition) wins over the configured one.
    const glm::dvec3 n = surface_normal_of(probe, config_.surface_normal);
    const glm::dvec3 vt = probe.velocity - glm::dot(probe.velocity, n) * n;
    const double speed = glm::length(vt);
    if (speed < config_.velocity_threshold) return glm::dvec3{0.0};
    const double fn = std::fabs(probe.normal_force);
    if (++since_update_ >= config_.update_every) {
      since_update_ = 0;
      update(speed * speed_to_file_, fn);
    }
    const int steps = steps_per_tick(probe.period);
    double y = 0.0;
    for (int i = 0; i < steps; ++i)
      y = step();
    acceleration_ = y * accel_to_si_;
    glm::dvec3 f = config_.effective_mass * acceleration_ * n;
    if (config_.friction) f -= (mu_ * fn / speed) * vt;
    return is_finite(f) ? f : glm::dvec3{0.0};
  }

  /// AR steps one tick of `period` [s] runs (see HattConfig::match_sample_rate).
  [[nodiscard]] int steps_per_tick(double period) const noexcept {
    if (!config_.match_sample_rate) return 1;
    const double steps = std::round(sample_rate_ * period);
    if (!std::isfinite(steps) || steps < 1.0) return 1;
    return steps > max_hatt_steps_per_tick ? max_hatt_steps_per_tick : static_cast<int>(steps);
  }

  void reset() noexcept {
    x_hist_.fill(0.0);
    y_hist_.fill(0.0);
    tick_ = 0;
    since_update_ = 0;
    acceleration_ = 0.0;
  }

  /// Recomputes the filter for (speed [file unit], force [N]): locate,
  /// interpolate LSFs, variance and gain, convert to AR / MA polynomials.
  /// noexcept and allocation-free; called from force() every update_every
  /// ticks, or by the user from another place in the loop.
  void update(double speed_file_units, double force) noexcept {
    where_ = tri_.locate(speed_file_units, force, where_.triangle);
    std::array<double, MaxOrder> lsf{};
    cur_variance_ = 0.0;
    cur_gain_ = 0.0;
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(where_.vertex[static_cast<std::size_t>(k)]);
      const double w = where_.weight[static_cast<std::size_t>(k)];
      for (std::size_t i = 0; i < p_order_; ++i)
        lsf[i] += w * ar_lsf_[v * p_order_ + i];
      cur_variance_ += w * variance_[v];
      cur_gain_ += w * gain_[v];
    }
    (void)lsf_to_ar<MaxOrder>(std::span<const double>(lsf.data(), p_order_),
                              std::span<double>(ar_.data(), p_order_ + 1));
    if (q_order_ > 0) {
      std::array<double, MaxOrder> mlsf{};
      for (int k = 0; k < 3; ++k) {
        const auto v = static_cast<std::size_t>(where_.vertex[static_cast<std::size_t>(k)]);
        const double w = where_.weight[static_cast<std::size_t>(k)];
        for (std::size_t i = 0; i < q_order_; ++i)
          mlsf[i] += w * ma_lsf_[v * q_order_ + i];
      }
      (void)lsf_to_ar<MaxOrder>(std::span<const double>(mlsf.data(), q_order_),
                                std::span<double>(ma_.data(), q_order_ + 1));
    }
  }

  /// Current AR polynomial a_0 = 1, a_1..a_p.
  [[nodiscard]] std::span<const double> ar_coefficients() const noexcept { return {ar_.data(), p_order_ + 1}; }
  /// Current MA polynomial b_0..b_q (empty for AR models).
  [[nodiscard]] std::span<const double> ma_coefficients() const noexcept {
    return {ma_.data(), q_order_ > 0 ? q_order_ + 1 : 0};
  }
  [[nodiscard]] double variance() const noexcept { return cur_variance_; }
  [[nodiscard]] const Barycentric& location() const noexcept { return where_; }
  /// Last synthesised acceleration [m/s^2].
  [[nodiscard]] double acceleration() const noexcept { return acceleration_; }

 private:
  /// One AR / ARMA step at the model's sample rate: returns y [file units].
  double step() noexcept {
    const double x = std::sqrt(cur_variance_) * gaussian(config_.seed, Cell{tick_++, 0, 0});
    double y = x;
    if (q_order_ > 0) {
      y = ma_[0] * x;
      for (std::size_t k = 1; k <= q_order_; ++k)
        y += ma_[k] * x_hist_[k - 1];
      y *= cur_gain_;
      for (std::size_t k = q_order_; k-- > 1;)
        x_hist_[k] = x_hist_[k - 1];
      x_hist_[0] = x;
    }
    for (std::size_t k = 1; k <= p_order_; ++k)
      y -= ar_[k] * y_hist_[k - 1];
    for (std::size_t k = p_order_; k-- > 1;)
      y_hist_[k] = y_hist_[k - 1];
    y_hist_[0] = y;
    return y;
  }

  HattTriangulation tri_;
  HattConfig config_;
  std::size_t p_order_;
  std::size_t q_order_;
  double mu_;
  double speed_to_file_;
  double accel_to_si_;
  double sample_rate_;          ///< [Hz]
  std::vector<double> ar_lsf_;  // models x p
  std::vector<double> ma_lsf_;  // models x q
  std::vector<double> variance_;
  std::vector<double> gain_;
  Barycentric where_{};
  std::array<double, MaxOrder + 1> ar_{};
  std::array<double, MaxOrder + 1> ma_{};
  std::array<double, MaxOrder> x_hist_{};
  std::array<double, MaxOrder> y_hist_{};
  double cur_variance_{0.0};
  double cur_gain_{1.0};
  double acceleration_{0.0};
  std::uint32_t tick_{0};
  int since_update_{0};
};

}  // namespace hapticfield::texture
