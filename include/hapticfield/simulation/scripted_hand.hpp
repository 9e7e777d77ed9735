#pragma once
/// @file scripted_hand.hpp
/// The scripted hand every simulated arm is held by: a spring-damper
/// pulling the handle toward a point that moves along a path (hold, a line,
/// a circle or a raster scan) at a set speed. Positions in the device frame
/// [m]; the arm computes F_hand from its own handle position and velocity.

#include <cmath>
#include <cstdint>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace hapticfield {

/// Path the scripted hand follows (ping-pong along lines and rasters, loops
/// on circles). Positions in the device frame [m].
struct HandPath {
  enum class Kind : std::uint8_t { hold, line, circle, raster };
  Kind kind{Kind::hold};
  glm::dvec3 a{0.0};             ///< hold point, line start, circle or raster centre [m]
  glm::dvec3 b{0.0};             ///< line end [m]
  glm::dvec3 u{1.0, 0.0, 0.0};   ///< circle / raster first axis (raster rows run along it)
  glm::dvec3 v{0.0, -1.0, 0.0};  ///< circle / raster second axis (rows step along it)
  double radius{0.02};           ///< circle radius [m]
  double width{0.06};            ///< raster extent along u [m]
  double height{0.06};           ///< raster extent along v [m]
  int rows{8};                   ///< raster rows (2..32)
  double speed{0.05};            ///< speed along the path [m/s]

  [[nodiscard]] static HandPath hold(glm::dvec3 p) {
    HandPath h;
    h.a = p;
    return h;
  }
  [[nodiscard]] static HandPath line(glm::dvec3 from, glm::dvec3 to, double speed) {
    HandPath h;
    h.kind = Kind::line;
    h.a = from;
    h.b = to;
    h.speed = speed;
    return h;
  }
  [[nodiscard]] static HandPath circle(glm::dvec3 centre, double radius, double speed) {
    HandPath h;
    h.kind = Kind::circle;
    h.a = centre;
    h.radius = radius;
    h.speed = speed;
    return h;
  }
  [[nodiscard]] static HandPath raster(glm::dvec3 centre, double width, double height, int rows, double speed) {
    HandPath h;
    h.kind = Kind::raster;
    h.a = centre;
    h.width = width;
    h.height = height;
    h.rows = rows;
    h.speed = speed;
    return h;
  }

  /// @throws std::invalid_argument naming the bad parameter.
  void validate() const {
    const auto finite = [](glm::dvec3 p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); };
    if (!finite(a) || !finite(b) || !finite(u) || !finite(v))
      throw std::invalid_argument("HandPath: points must be finite [m]");
    if (!std::isfinite(speed) || speed < 0.0)
      throw std::invalid_argument("HandPath: speed must be finite and >= 0 [m/s]");
    if (kind == Kind::circle && (!std::isfinite(radius) || radius <= 0.0))
      throw std::invalid_argument("HandPath: radius must be finite and > 0 [m]");
    if (kind == Kind::raster) {
      if (rows < 2 || rows > 32) throw std::invalid_argument("HandPath: rows must be 2..32");
      if (!std::isfinite(width) || width <= 0.0 || !std::isfinite(height) || height <= 0.0)
        throw std::invalid_argument("HandPath: raster width and height must be finite and > 0 [m]");
    }
  }

  /// Target point at time t [s].
  [[nodiscard]] glm::dvec3 at(double t) const noexcept {
    const double s = speed * t;  // arc length travelled [m]
    switch (kind) {
      case Kind::hold:
        return a;
      case Kind::line: {
        const double length = glm::length(b - a);
        if (length <= 0.0) return a;
        return a + (b - a) * (ping_pong(s, length) / length);
      }
      case Kind::circle: {
        const double angle = s / radius;
        return a + radius * (std::cos(angle) * u + std::sin(angle) * v);
      }
      case Kind::raster: {
        const double step = height / (rows - 1);
        const double total = rows * width + (rows - 1) * step;
        double d = ping_pong(s, total);
        for (int row = 0; row < rows; ++row) {
          const double y = -height / 2.0 + row * step;
          const bool forward = row % 2 == 0;
          if (d <= width) {
            const double x = forward ? -width / 2.0 + d : width / 2.0 - d;
            return a + x * u + y * v;
          }
          d -= width;
          if (row + 1 < rows && d <= step) {
            const double x = forward ? width / 2.0 : -width / 2.0;
            return a + x * u + (y + d) * v;
          }
          d -= step;
        }
        return a + (rows % 2 ? width / 2.0 : -width / 2.0) * u + height / 2.0 * v;
      }
    }
    return a;
  }

 private:
  static double ping_pong(double s, double length) noexcept {
    const double m = std::fmod(s, 2.0 * length);
    return m <= length ? m : 2.0 * length - m;
  }
};

/// The scripted hand: F_hand = k (target - p) + d (v_target - v).
struct Hand {
  bool holding{true};       ///< false: nobody holds the handle
  double stiffness{300.0};  ///< [N/m]
  double damping{3.0};      ///< [N s/m]
  HandPath path{};
};

}  // namespace hapticfield
