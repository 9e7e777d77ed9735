#pragma once
/// @file local_sphere.hpp
/// The local circle / sphere method (Fritz & Barner 1996, section 4.2): a new
/// noise sample is drawn each time the HIP leaves the ball of radius r around
/// the point where the last sample was drawn; in between, the texture value
/// moves from the previous sample to the new one in proportion to the
/// distance travelled (so the output is continuous). With a surface normal,
/// displacements are projected on the tangent plane (the local circle): the
/// probe's surface normal when it has one (inside a ContactField), otherwise
/// the configured one.

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/surface_frame.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/texture/noise.hpp"

namespace hapticfield::texture {

template <NoiseSource Noise>
class LocalSphere {
 public:
  /// @param radius  ball radius r [m] (> 0)
  /// @param surface_normal  unit normal of the surface for the local-circle
  ///        variant; zero vector for the sphere (free space)
  /// @throws std::invalid_argument for a bad radius or a normal that is
  ///         neither zero nor unit length.
  LocalSphere(Noise noise, std::uint32_t seed, double radius, glm::dvec3 surface_normal = glm::dvec3{0.0})
      : noise_(std::move(noise)), seed_(seed), radius_(radius), normal_(surface_normal) {
    if (!std::isfinite(radius) || radius <= 0.0)
      throw std::invalid_argument("LocalSphere: radius must be finite and > 0 [m]");
    const double n = glm::length(surface_normal);
    if (!std::isfinite(n) || (n != 0.0 && std::fabs(n - 1.0) > 1e-9))
      throw std::invalid_argument("LocalSphere: surface_normal must be zero or a unit vector");
  }

  /// Texture value at the HIP position [m] (advances the state).
  [[nodiscard]] glm::dvec3 sample(const glm::dvec3& position) noexcept { return advance(position, normal_); }

  /// Same, from a Probe (TextureSource interface): in the tangent plane of
  /// the probe's surface normal when it has one.
  [[nodiscard]] glm::dvec3 sample(const Probe& probe) noexcept {
    if (!is_finite(probe.surface_normal)) return glm::dvec3{0.0};
    return advance(probe.position, surface_normal_of(probe, normal_));
  }

  void reset() noexcept {
    started_ = false;
    count_ = 0;
  }

  /// Number of samples drawn since reset.
  [[nodiscard]] std::uint32_t samples_drawn() const noexcept { return count_; }

 private:
  glm::dvec3 advance(const glm::dvec3& position, const glm::dvec3& normal) noexcept {
    if (!is_finite(position)) return glm::dvec3{0.0};
    if (!started_) {
      started_ = true;
      centre_ = position;
      from_ = noise_.sample(seed_, Cell{0, 0, 0});
      to_ = noise_.sample(seed_, Cell{1, 0, 0});
      count_ = 2;
    }
    glm::dvec3 d = position - centre_;
    d -= glm::dot(d, normal) * normal;  // tangent plane (no-op for the sphere)
    double distance = glm::length(d);
    if (distance >= radius_) {
      // Left the ball: the value has reached the new sample; it becomes the
      // start of the next segment, whose centre is the exit point (on the
      // tangent plane through the previous centre).
      from_ = to_;
      to_ = noise_.sample(seed_, Cell{count_++, 0, 0});
      centre_ += d;
      distance = 0.0;
    }
    return from_ + (distance / radius_) * (to_ - from_);
  }

  Noise noise_;
  std::uint32_t seed_;
  double radius_;
  glm::dvec3 normal_{0.0};
  glm::dvec3 centre_{0.0};
  glm::dvec3 from_{0.0};
  glm::dvec3 to_{0.0};
  std::uint32_t count_{0};
  bool started_{false};
};

}  // namespace hapticfield::texture
