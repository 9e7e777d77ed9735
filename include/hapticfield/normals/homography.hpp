#pragma once
/// @file homography.hpp
/// Plane-to-image homography from point correspondences: the normalised
/// direct linear transform (Hartley & Zisserman, Multiple View Geometry,
/// 2nd ed., algorithm 4.2) for four or more points, and RANSAC (through
/// cv::findHomography) when more than four noisy points are given. Setup
/// code: may allocate and throw.

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace hapticfield {

/// How estimate_homography() treats more than four correspondences.
struct HomographyConfig {
  bool ransac = true;                ///< RANSAC when more than 4 points are given
  double ransac_threshold_px = 3.0;  ///< inlier threshold on the transfer error [px]
  int ransac_iterations = 2000;      ///< RANSAC iteration limit
  double ransac_confidence = 0.999;  ///< RANSAC confidence
};

/// A homography image ~ H [X Y 1]^T with the correspondences it explains.
struct HomographyEstimate {
  cv::Matx33d H;                 ///< plane -> image, normalised so that ||H||_F = 1 and H(2,2) >= 0
  std::vector<bool> inliers;     ///< per input point (all true without RANSAC)
  std::size_t inlier_count = 0;  ///< number of inliers
  double rms_error_px = 0.0;     ///< RMS transfer error over the inliers [px]
  double max_error_px = 0.0;     ///< largest transfer error over the inliers [px]
};

namespace detail {

inline bool finite_points(std::span<const glm::dvec2> p) noexcept {
  return std::all_of(p.begin(), p.end(), [](glm::dvec2 q) { return std::isfinite(q.x) && std::isfinite(q.y); });
}

/// Twice the triangle area over the squared longest side: 0 for collinear
/// points, about 0.87 for an equilateral triangle (scale free).
inline double triangle_fatness(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) noexcept {
  const glm::dvec2 ab = b - a;
  const glm::dvec2 ac = c - a;
  const glm::dvec2 bc = c - b;
  const double area2 = std::abs(ab.x * ac.y - ab.y * ac.x);
  const double longest = std::max({ab.x * ab.x + ab.y * ab.y, ac.x * ac.x + ac.y * ac.y, bc.x * bc.x + bc.y * bc.y});
  return longest > 0.0 ? area2 / longest : 0.0;
}

/// Collinearity threshold on triangle_fatness().
inline constexpr double collinear_tolerance = 1e-4;

/// Throws std::invalid_argument when a point set cannot define a homography:
/// non-finite values, repeated points, all points on one line, or (with
/// exactly four points) three of them on one line.
inline void check_point_set(std::span<const glm::dvec2> p, const char* who, const char* what) {
  const std::string prefix = std::string(who) + ": " + what;
  if (!finite_points(p)) throw std::invalid_argument(prefix + " must be finite");
  double extent = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const glm::dvec2 d = p[i] - p[j];
      extent = std::max(extent, std::sqrt(d.x * d.x + d.y * d.y));
    }
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const glm::dvec2 d = p[i] - p[j];
      if (std::sqrt(d.x * d.x + d.y * d.y) <= 1e-9 * extent || extent == 0.0)
        throw std::invalid_argument(prefix + " contain repeated points (" + std::to_string(i) + " and " +
                                    std::to_string(j) + ")");
    }
  if (p.size() == 4) {
    for (std::size_t i = 0; i < 4; ++i) {
      const glm::dvec2 a = p[(i + 1) % 4];
      const glm::dvec2 b = p[(i + 2) % 4];
      const glm::dvec2 c = p[(i + 3) % 4];
      if (triangle_fatness(a, b, c) < collinear_tolerance)
        throw std::invalid_argument(prefix + " have three collinear points (all but point " + std::to_string(i) + ")");
    }
    return;
  }
  // More points: they must not all lie on one line (RANSAC copes with
  // collinear triples among them).
  std::size_t fi = 0;
  std::size_t fj = 1;
  double far2 = -1.0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const glm::dvec2 d = p[i] - p[j];
      if (d.x * d.x + d.y * d.y > far2) {
        far2 = d.x * d.x + d.y * d.y;
        fi = i;
        fj = j;
      }
    }
  // the farthest pair spans the line; any point well off it makes the set 2D
  for (std::size_t k = 0; k < p.size(); ++k)
    if (triangle_fatness(p[fi], p[fj], p[k]) >= collinear_tolerance) return;
  throw std::invalid_argument(prefix + " are collinear");
}

/// Hartley normalisation: centroid to the origin, mean distance sqrt(2).
inline cv::Matx33d normalising_transform(std::span<const glm::dvec2> p) noexcept {
  glm::dvec2 c{0.0};
  for (auto q : p)
    c += q;
  c /= static_cast<double>(p.size());
  double mean = 0.0;
  for (auto q : p)
    mean += std::hypot(q.x - c.x, q.y - c.y);
  mean /= static_cast<double>(p.size());
  const double s = mean > 0.0 ? std::sqrt(2.0) / mean : 1.0;
  return {s, 0.0, -s * c.x, 0.0, s, -s * c.y, 0.0, 0.0, 1.0};
}

inline glm::dvec2 apply(const cv::Matx33d& H, glm::dvec2 p) noexcept {
  const cv::Vec3d q = H * cv::Vec3d(p.x, p.y, 1.0);
  return glm::dvec2{q[0] / q[2], q[1] / q[2]};
}

inline cv::Matx33d normalise_homography(cv::Matx33d H) noexcept {
  const double n = cv::norm(H, cv::NORM_L2);
  if (n > 0.0) H *= 1.0 / n;
  if (H(2, 2) < 0.0) H *= -1.0;
  return H;
}

}  // namespace detail

/// Normalised DLT (Hartley & Zisserman, algorithm 4.2): the least-squares
/// homography with image_i ~ H plane_i, exact for four points. Both point
/// sets are translated to their centroid and scaled to mean distance
/// sqrt(2) before the 2n x 9 system is solved by SVD.
/// @throws std::invalid_argument for fewer than 4 points, different counts,
///         non-finite, repeated or collinear points.
[[nodiscard]] inline cv::Matx33d homography_dlt(std::span<const glm::dvec2> plane, std::span<const glm::dvec2> image) {
  if (plane.size() != image.size()) throw std::invalid_argument("homography_dlt: plane and image point counts differ");
  if (plane.size() < 4)
    throw std::invalid_argument("homography_dlt: at least 4 correspondences are needed, got " +
                                std::to_string(plane.size()));
  detail::check_point_set(plane, "homography_dlt", "plane points");
  detail::check_point_set(image, "homography_dlt", "image points [px]");
  const cv::Matx33d Tp = detail::normalising_transform(plane);
  const cv::Matx33d Ti = detail::normalising_transform(image);
  const int n = static_cast<int>(plane.size());
  cv::Mat A = cv::Mat::zeros(2 * n, 9, CV_64F);
  for (int i = 0; i < n; ++i) {
    const glm::dvec2 X = detail::apply(Tp, plane[static_cast<std::size_t>(i)]);
    const glm::dvec2 x = detail::apply(Ti, image[static_cast<std::size_t>(i)]);
    double* r0 = A.ptr<double>(2 * i);
    double* r1 = A.ptr<double>(2 * i + 1);
    // [0^T, -X^T, y X^T] and [X^T, 0^T, -x X^T] with X = (X, Y, 1)
    r0[3] = -X.x;
    r0[4] = -X.y;
    r0[5] = -1.0;
    r0[6] = x.y * X.x;
    r0[7] = x.y * X.y;
    r0[8] = x.y;
    r1[0] = X.x;
    r1[1] = X.y;
    r1[2] = 1.0;
    r1[6] = -x.x * X.x;
    r1[7] = -x.x * X.y;
    r1[8] = -x.x;
  }
  cv::Mat w;
  cv::Mat u;
  cv::Mat vt;
  cv::SVD::compute(A, w, u, vt, cv::SVD::FULL_UV);
  const double* h = vt.ptr<double>(8);
  const cv::Matx33d Hn(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
  const cv::Matx33d H = Ti.inv() * Hn * Tp;
  if (!std::isfinite(cv::norm(H)) || std::abs(cv::determinant(detail::normalise_homography(H))) < 1e-300)
    throw std::invalid_argument("homography_dlt: degenerate configuration (singular homography)");
  return detail::normalise_homography(H);
}

/// Homography from four or more correspondences: the normalised DLT for
/// four points (or when RANSAC is off); with more than four, RANSAC through
/// cv::findHomography (then a Levenberg-Marquardt refinement on the inliers).
/// @throws std::invalid_argument on degenerate input (see homography_dlt) or
///         when RANSAC finds fewer than 4 inliers.
[[nodiscard]] inline HomographyEstimate estimate_homography(std::span<const glm::dvec2> plane,
                                                            std::span<const glm::dvec2> image,
                                                            const HomographyConfig& options = {}) {
  if (plane.size() != image.size())
    throw std::invalid_argument("estimate_homography: plane and image point counts differ");
  if (plane.size() < 4)
    throw std::invalid_argument("estimate_homography: at least 4 correspondences are needed, got " +
                                std::to_string(plane.size()));
  detail::check_point_set(plane, "estimate_homography", "plane points");
  detail::check_point_set(image, "estimate_homography", "image points [px]");
  if (!std::isfinite(options.ransac_threshold_px) || options.ransac_threshold_px <= 0.0)
    throw std::invalid_argument("estimate_homography: ransac_threshold_px must be positive [px]");

  HomographyEstimate est;
  est.inliers.assign(plane.size(), true);
  if (plane.size() == 4 || !options.ransac) {
    est.H = homography_dlt(plane, image);
  } else {
    std::vector<cv::Point2d> src;
    std::vector<cv::Point2d> dst;
    for (std::size_t i = 0; i < plane.size(); ++i) {
      src.emplace_back(plane[i].x, plane[i].y);
      dst.emplace_back(image[i].x, image[i].y);
    }
    std::vector<unsigned char> mask;
    const cv::Mat H = cv::findHomography(src, dst, cv::RANSAC, options.ransac_threshold_px, mask,
                                         options.ransac_iterations, options.ransac_confidence);
    if (H.empty()) throw std::invalid_argument("estimate_homography: RANSAC found no consistent homography");
    for (std::size_t i = 0; i < mask.size(); ++i)
      est.inliers[i] = mask[i] != 0;
    est.H = detail::normalise_homography(cv::Matx33d(H.ptr<double>()));
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < plane.size(); ++i) {
    if (!est.inliers[i]) continue;
    const glm::dvec2 d = detail::apply(est.H, plane[i]) - image[i];
    const double e = std::hypot(d.x, d.y);
    sum += e * e;
    est.max_error_px = std::max(est.max_error_px, e);
    ++est.inlier_count;
  }
  if (est.inlier_count < 4) throw std::invalid_argument("estimate_homography: fewer than 4 inliers after RANSAC");
  est.rms_error_px = std::sqrt(sum / static_cast<double>(est.inlier_count));
  return est;
}

}  // namespace hapticfield
