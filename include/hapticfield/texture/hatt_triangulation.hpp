#pragma once
/// @file hatt_triangulation.hpp
/// Point location with barycentric weights in the (speed, force) Delaunay
/// triangulation of a HaTT modelSet. locate() is noexcept and
/// allocation-free (servo path); construction is setup code.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <vector>

namespace hapticfield::texture {

/// Barycentric location of a point in the triangulation.
struct Barycentric {
  std::array<int, 3> vertex{0, 0, 0};           ///< model indices
  std::array<double, 3> weight{1.0, 0.0, 0.0};  ///< >= 0, sum 1
  bool inside{true};                            ///< false: projected from outside the hull
  std::size_t triangle{0};                      ///< index of the triangle used
};

/// Point location in the (speed, force) Delaunay triangulation.
class HattTriangulation {
 public:
  HattTriangulation() = default;
  /// @throws std::invalid_argument for an index out of range or a degenerate triangle.
  HattTriangulation(std::vector<double> speeds, std::vector<double> forces,
                    const std::vector<std::array<int, 3>>& triangles)
      : speeds_(std::move(speeds)), forces_(std::move(forces)) {
    if (speeds_.size() != forces_.size() || speeds_.empty())
      throw std::invalid_argument("HattTriangulation: need as many speeds as forces (>= 1)");
    for (const auto& t : triangles) {
      for (int v : t)
        if (v < 0 || static_cast<std::size_t>(v) >= speeds_.size())
          throw std::invalid_argument("HattTriangulation: vertex index out of range");
      Tri tri;
      tri.v = t;
      tri.s0 = speeds_[static_cast<std::size_t>(t[0])];
      tri.f0 = forces_[static_cast<std::size_t>(t[0])];
      const double a = speeds_[static_cast<std::size_t>(t[1])] - tri.s0,
                   b = speeds_[static_cast<std::size_t>(t[2])] - tri.s0;
      const double c = forces_[static_cast<std::size_t>(t[1])] - tri.f0,
                   d = forces_[static_cast<std::size_t>(t[2])] - tri.f0;
      const double det = a * d - b * c;
      if (!(std::fabs(det) > 0.0) || !std::isfinite(det))
        throw std::invalid_argument("HattTriangulation: degenerate triangle");
      tri.inv = {d / det, -b / det, -c / det, a / det};
      tris_.push_back(tri);
    }
  }

  /// Locates (speed, force); outside the hull the weights of the nearest
  /// triangle (largest smallest weight) are clipped to >= 0 and
  /// renormalised. With no triangle (fewer than 3 models) the first model.
  /// `hint`: a triangle to try first (the previous answer: strokes move
  /// slowly through the triangulation).
  [[nodiscard]] Barycentric locate(double speed, double force, std::size_t hint = 0) const noexcept {
    Barycentric out;
    if (tris_.empty()) return out;
    double best = -std::numeric_limits<double>::infinity();
    std::size_t best_i = 0;
    std::array<double, 3> best_w{1.0, 0.0, 0.0};
    const std::size_t n = tris_.size();
    const std::size_t first = hint < n ? hint : 0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = k == 0 ? first : (k <= first ? k - 1 : k);  // hint, then the others in order
      const auto w = weights(tris_[i], speed, force);
      const double m = std::min(w[0], std::min(w[1], w[2]));
      if (m > best) best = m, best_i = i, best_w = w;
      if (m >= -1e-12) break;
    }
    out.vertex = tris_[best_i].v;
    out.triangle = best_i;
    out.inside = best >= -1e-12;
    double total = 0.0;
    for (double& w : best_w)
      total += (w = std::max(w, 0.0));
    if (!(total > 0.0)) best_w = {1.0, 0.0, 0.0}, total = 1.0;
    for (int k = 0; k < 3; ++k)
      out.weight[static_cast<std::size_t>(k)] = best_w[static_cast<std::size_t>(k)] / total;
    return out;
  }

  [[nodiscard]] std::size_t size() const noexcept { return tris_.size(); }

 private:
  struct Tri {
    std::array<int, 3> v{};
    double s0{0}, f0{0};
    std::array<double, 4> inv{};  // inverse of [[a b][c d]]
  };
  static std::array<double, 3> weights(const Tri& t, double s, double f) noexcept {
    const double ds = s - t.s0, df = f - t.f0;
    const double w1 = t.inv[0] * ds + t.inv[1] * df;
    const double w2 = t.inv[2] * ds + t.inv[3] * df;
    return {1.0 - w1 - w2, w1, w2};
  }
  std::vector<double> speeds_;
  std::vector<double> forces_;
  std::vector<Tri> tris_;
};

}  // namespace hapticfield::texture
