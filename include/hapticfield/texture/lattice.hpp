#pragma once
/// @file lattice.hpp
/// Noise sampled on a 2D or 3D lattice with per-axis spacing (grain) and
/// nearest, linear or cubic interpolation (Fritz & Barner 1996, section 4.1:
/// "lattice textures"). The value at a point is a pure function of (seed,
/// position): stroking the same spot twice feels the same.

#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include <glm/vec3.hpp>

#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/texture/noise.hpp"

namespace hapticfield::texture {

/// How lattice values are blended between lattice points.
enum class Interpolation {
  nearest,  ///< value of the nearest lattice point (piecewise constant)
  linear,   ///< (bi/tri)linear: continuous, first derivative jumps at cell edges
  cubic,    ///< Catmull-Rom (tensor product): continuous first derivative
};

namespace detail {

/// Offsets and weights along one axis for coordinate u [cells].
struct AxisWeights {
  std::int64_t first{0};  ///< first lattice index used
  int count{1};           ///< 1, 2 or 4 lattice points
  std::array<double, 4> w{1.0, 0.0, 0.0, 0.0};
};

/// Catmull-Rom weights at fraction t in [0, 1) (Catmull & Rom 1974; the
/// cardinal spline with tension 0.5; C1 across lattice points).
[[nodiscard]] inline std::array<double, 4> catmull_rom(double t) noexcept {
  const double t2 = t * t;
  const double t3 = t2 * t;
  return {0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t),
          0.5 * (t3 - t2)};
}

[[nodiscard]] inline AxisWeights axis_weights(double u, Interpolation mode) noexcept {
  AxisWeights a;
  switch (mode) {
    case Interpolation::nearest:
      a.first = static_cast<std::int64_t>(std::floor(u + 0.5));
      break;
    case Interpolation::linear: {
      const double f = std::floor(u);
      const double t = u - f;
      a.first = static_cast<std::int64_t>(f);
      a.count = 2;
      a.w = {1.0 - t, t, 0.0, 0.0};
      break;
    }
    case Interpolation::cubic: {
      const double f = std::floor(u);
      a.first = static_cast<std::int64_t>(f) - 1;
      a.count = 4;
      a.w = catmull_rom(u - f);
      break;
    }
  }
  return a;
}

/// Largest |coordinate| [cells] the lattice accepts; beyond it the value is
/// zero (keeps the int64 conversion defined).
inline constexpr double max_cells = 1e15;

}  // namespace detail

/// Vector noise on a lattice of spacing `grain` [m] per axis. Dim = 2 uses the
/// x-y plane (z ignored); Dim = 3 the volume. Output range: that of the noise
/// for nearest and linear (convex weights); cubic may overshoot it: per axis
/// the Catmull-Rom weights sum to 1 with sum |w| <= 1.25, so |value| <=
/// 1.25^Dim max |sample|.
template <NoiseSource Noise, int Dim = 3>
requires(Dim == 2 || Dim == 3) class NoiseLattice {
 public:
  /// @param grain  lattice spacing per axis [m] (> 0; z unused when Dim = 2)
  /// @throws std::invalid_argument for a non-positive or non-finite grain.
  NoiseLattice(Noise noise, std::uint32_t seed, glm::dvec3 grain, Interpolation mode = Interpolation::linear)
      : noise_(std::move(noise)), seed_(seed), inv_grain_(1.0 / grain), mode_(mode) {
    const int axes = Dim;
    for (int i = 0; i < axes; ++i)
      if (!std::isfinite(grain[i]) || grain[i] <= 0.0)
        throw std::invalid_argument("NoiseLattice: grain must be finite and > 0 [m] on every axis");
    if (Dim == 2) inv_grain_.z = 0.0;
  }

  /// Interpolated value at a position [m]; zero for a non-finite position.
  [[nodiscard]] glm::dvec3 operator()(const glm::dvec3& position) const noexcept { return at(position, seed_); }

  /// Same lattice with another seed (used by fBm octaves).
  [[nodiscard]] glm::dvec3 at(const glm::dvec3& position, std::uint32_t seed) const noexcept {
    const glm::dvec3 u = position * inv_grain_;
    if (!is_finite(u) || std::fabs(u.x) > detail::max_cells || std::fabs(u.y) > detail::max_cells ||
        std::fabs(u.z) > detail::max_cells)
      return glm::dvec3{0.0};
    const detail::AxisWeights ax = detail::axis_weights(u.x, mode_);
    const detail::AxisWeights ay = detail::axis_weights(u.y, mode_);
    const detail::AxisWeights az = Dim == 3 ? detail::axis_weights(u.z, mode_) : detail::AxisWeights{};
    glm::dvec3 sum{0.0};
    for (int k = 0; k < az.count; ++k) {
      const auto cz = static_cast<std::uint32_t>(static_cast<std::uint64_t>(az.first + k));
      for (int j = 0; j < ay.count; ++j) {
        const auto cy = static_cast<std::uint32_t>(static_cast<std::uint64_t>(ay.first + j));
        const double wyz = ay.w[static_cast<std::size_t>(j)] * az.w[static_cast<std::size_t>(k)];
        for (int i = 0; i < ax.count; ++i) {
          const auto cx = static_cast<std::uint32_t>(static_cast<std::uint64_t>(ax.first + i));
          sum += (wyz * ax.w[static_cast<std::size_t>(i)]) * noise_.sample(seed, Cell{cx, cy, cz});
        }
      }
    }
    return sum;
  }

  [[nodiscard]] const Noise& noise() const noexcept { return noise_; }
  [[nodiscard]] std::uint32_t seed() const noexcept { return seed_; }
  [[nodiscard]] Interpolation interpolation() const noexcept { return mode_; }

 private:
  Noise noise_;
  std::uint32_t seed_;
  glm::dvec3 inv_grain_{1.0};
  Interpolation mode_;
};

/// A spatial texture generator: a const, noexcept map position [m] -> vector.
template <class G>
concept SpatialGenerator = requires(const G& g, const glm::dvec3& p) {
  { g(p) }
  noexcept->std::convertible_to<glm::dvec3>;
};

static_assert(SpatialGenerator<NoiseLattice<GaussianNoise, 2>>);

}  // namespace hapticfield::texture
