#pragma once
/// @file face_pose.hpp
/// Orientation of a planar face from its homography (Kim & Kwon, World
/// Haptics 2013, section on geometry-based interaction): H = s K [r1 r2 t],
/// so K^-1 H gives r1, r2 and t up to one scale; r3 = r1 x r2, the nearest
/// rotation by SVD, and the face normal n = R e3 in the camera frame
/// (OpenCV: x right, y down, z forward), unit, turned toward the camera.
/// Setup code: may allocate and throw.

#include <cmath>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "hapticfield/normals/camera.hpp"
#include "hapticfield/normals/homography.hpp"

namespace hapticfield {

/// Pose of a planar face relative to the camera.
struct FacePose {
  cv::Matx33d R;                       ///< face plane axes -> camera frame (nearest rotation)
  cv::Vec3d t;                         ///< face-plane origin in the camera frame [plane units]
  glm::dvec3 normal{0.0};              ///< unit normal, camera frame, toward the camera (n . centre < 0)
  cv::Matx33d H;                       ///< plane -> undistorted image homography
  double rms_reprojection_px = 0.0;    ///< RMS reprojection error of K [R|t] with distortion [px]
  double max_reprojection_px = 0.0;    ///< largest reprojection error [px]
  double orthogonality = 0.0;          ///< |cos| of the angle between the columns of K^-1 H before orthogonalisation
  double norm_ratio = 1.0;             ///< |K^-1 h1| / |K^-1 h2| (1 for a consistent K and size)
  double width = 0.0;                  ///< face width [plane units] (rectangles)
  double height = 0.0;                 ///< face height [plane units]; 1 when the aspect was recovered
  bool aspect_recovered = false;       ///< true when the size was unknown and W/H came from K
  double closed_form_rms_px = 0.0;     ///< RMS reprojection error of the closed form before refinement [px]
  glm::dvec3 closed_form_normal{0.0};  ///< normal of the closed form before refinement
  bool refined = false;                ///< true when the Levenberg-Marquardt refinement was applied
  std::vector<bool> inliers;           ///< per correspondence
};

/// How pose_from_homography() finishes the closed form.
struct PoseConfig {
  /// Refine R, t by Levenberg-Marquardt on the reprojection error
  /// (cv::solvePnPRefineLM) starting from the closed form, as Zhang's
  /// calibration does; kept only when it lowers the error.
  bool refine = true;
};

namespace detail {

inline cv::Vec3d col(const cv::Matx33d& m, int c) noexcept {
  return {m(0, c), m(1, c), m(2, c)};
}

}  // namespace detail

/// Rotation and translation from a plane -> undistorted-pixel homography:
/// A = K^-1 H = lambda [r1 r2 t], lambda = 2 / (|a1| + |a2|), its sign chosen
/// so that the centroid of the plane points lies in front of the camera
/// (z > 0); r3 = r1 x r2; R = U V^T from the SVD of [r1 r2 r3] (the
/// nearest rotation in the Frobenius norm). The reprojection error is
/// measured against the given (distorted) pixels through the camera's
/// distortion model. With options.refine (the default) the closed form is
/// then refined by Levenberg-Marquardt on that error; the closed-form
/// normal and error stay available in the result.
/// @throws std::invalid_argument when H is singular or the counts differ.
[[nodiscard]] inline FacePose pose_from_homography(const Camera& camera, const cv::Matx33d& H,
                                                   std::span<const glm::dvec2> plane,
                                                   std::span<const glm::dvec2> pixels, const PoseConfig& options = {}) {
  if (plane.size() != pixels.size() || plane.empty())
    throw std::invalid_argument("pose_from_homography: plane and image point counts differ");
  const cv::Matx33d A = camera.matrix().inv() * H;
  const cv::Vec3d a1 = detail::col(A, 0);
  const cv::Vec3d a2 = detail::col(A, 1);
  const cv::Vec3d a3 = detail::col(A, 2);
  const double n1 = cv::norm(a1);
  const double n2 = cv::norm(a2);
  if (!(n1 > 0.0) || !(n2 > 0.0) || !std::isfinite(n1 + n2))
    throw std::invalid_argument("pose_from_homography: singular homography");
  glm::dvec2 centroid{0.0};
  for (auto p : plane)
    centroid += p;
  centroid /= static_cast<double>(plane.size());
  double lambda = 2.0 / (n1 + n2);
  if ((a1 * centroid.x + a2 * centroid.y + a3)[2] < 0.0) lambda = -lambda;

  const cv::Vec3d r1 = lambda * a1;
  const cv::Vec3d r2 = lambda * a2;
  const cv::Vec3d r3 = r1.cross(r2);
  const cv::Matx33d M(r1[0], r2[0], r3[0], r1[1], r2[1], r3[1], r1[2], r2[2], r3[2]);
  cv::Mat w;
  cv::Mat u;
  cv::Mat vt;
  cv::SVD::compute(cv::Mat(M), w, u, vt, cv::SVD::FULL_UV);
  cv::Matx33d R = cv::Matx33d(u.ptr<double>()) * cv::Matx33d(vt.ptr<double>());
  if (cv::determinant(R) < 0.0) {  // cannot happen for det(M) = |r1 x r2|^2 > 0; kept for safety
    cv::Matx33d U(u.ptr<double>());
    for (int r = 0; r < 3; ++r)
      U(r, 2) = -U(r, 2);
    R = U * cv::Matx33d(vt.ptr<double>());
  }

  FacePose pose;
  pose.R = R;
  pose.t = lambda * a3;
  pose.H = H;
  pose.orthogonality = std::abs(a1.dot(a2)) / (n1 * n2);
  pose.norm_ratio = n1 / n2;
  const cv::Vec3d centre = R * cv::Vec3d(centroid.x, centroid.y, 0.0) + pose.t;
  cv::Vec3d n = detail::col(R, 2);
  if (n.dot(centre) > 0.0) n = -n;
  pose.normal = glm::normalize(glm::dvec3{n[0], n[1], n[2]});

  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  for (std::size_t i = 0; i < plane.size(); ++i) {
    object.emplace_back(plane[i].x, plane[i].y, 0.0);
    image.emplace_back(pixels[i].x, pixels[i].y);
  }
  const cv::Mat K(camera.matrix());
  const cv::Mat dist = camera.has_distortion() ? cv::Mat(camera.distortion()) : cv::Mat();
  const auto reprojection = [&](const cv::Vec3d& rvec, const cv::Vec3d& tvec, double& max_error) {
    std::vector<cv::Point2d> projected;
    cv::projectPoints(object, rvec, tvec, K, dist, projected);
    double sum = 0.0;
    max_error = 0.0;
    for (std::size_t i = 0; i < projected.size(); ++i) {
      const double e = std::hypot(projected[i].x - image[i].x, projected[i].y - image[i].y);
      sum += e * e;
      max_error = std::max(max_error, e);
    }
    return std::sqrt(sum / static_cast<double>(projected.size()));
  };
  cv::Vec3d rvec;
  cv::Rodrigues(R, rvec);
  pose.rms_reprojection_px = reprojection(rvec, pose.t, pose.max_reprojection_px);
  pose.closed_form_rms_px = pose.rms_reprojection_px;
  pose.closed_form_normal = pose.normal;
  if (options.refine && plane.size() >= 4) {
    cv::Mat r(rvec);
    cv::Mat t(pose.t);
    r = r.clone();
    t = t.clone();
    cv::solvePnPRefineLM(object, image, K, dist, r, t,
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-12));
    const cv::Vec3d r2(r.ptr<double>());
    const cv::Vec3d t2(t.ptr<double>());
    double max2 = 0.0;
    const double rms2 = reprojection(r2, t2, max2);
    if (std::isfinite(rms2) && rms2 < pose.rms_reprojection_px && t2[2] > 0.0) {
      cv::Rodrigues(r2, pose.R);
      pose.t = t2;
      pose.rms_reprojection_px = rms2;
      pose.max_reprojection_px = max2;
      pose.refined = true;
      const cv::Vec3d c2 = pose.R * cv::Vec3d(centroid.x, centroid.y, 0.0) + pose.t;
      cv::Vec3d n2 = detail::col(pose.R, 2);
      if (n2.dot(c2) > 0.0) n2 = -n2;
      pose.normal = glm::normalize(glm::dvec3{n2[0], n2[1], n2[2]});
    }
  }
  return pose;
}

/// Pose of a plane from four or more correspondences between plane points
/// (any unit, e.g. [mm]) and pixels: the points are undistorted with the
/// camera's distortion, the homography estimated (normalised DLT; RANSAC
/// with more than four points), then pose_from_homography(). The
/// reprojection error covers the inliers only.
/// @throws std::invalid_argument on degenerate input (fewer than 4 points,
///         repeated, collinear or non-finite points).
[[nodiscard]] inline FacePose estimate_plane_pose(const Camera& camera, std::span<const glm::dvec2> plane,
                                                  std::span<const glm::dvec2> pixels,
                                                  const HomographyConfig& options = {},
                                                  const PoseConfig& pose_options = {}) {
  if (plane.size() != pixels.size())
    throw std::invalid_argument("estimate_plane_pose: plane and image point counts differ");
  if (plane.size() < 4)
    throw std::invalid_argument("estimate_plane_pose: at least 4 correspondences are needed, got " +
                                std::to_string(plane.size()));
  if (!detail::finite_points(pixels))
    throw std::invalid_argument("estimate_plane_pose: image points [px] must be finite");
  const std::vector<glm::dvec2> ideal = camera.undistort(pixels);
  const HomographyEstimate est = estimate_homography(plane, ideal, options);
  std::vector<glm::dvec2> in_plane;
  std::vector<glm::dvec2> in_pixels;
  for (std::size_t i = 0; i < plane.size(); ++i)
    if (est.inliers[i]) {
      in_plane.push_back(plane[i]);
      in_pixels.push_back(pixels[i]);
    }
  FacePose pose = pose_from_homography(camera, est.H, in_plane, in_pixels, pose_options);
  pose.inliers = est.inliers;
  return pose;
}

/// Pose of a rectangular face from its four corners in order around the
/// face: the first maps to (0, 0) on the face, then (W, 0), (W, H), (0, H).
///
/// With size = (W, H) [mm] the correspondences are those four. Without a
/// size the rectangle's aspect ratio is unknown and is recovered with K:
/// the corners are matched to the unit square, giving H0 = H diag(W, H, 1),
/// so K^-1 H0 = lambda [W r1, H r2, t]; since |r1| = |r2| = 1 (the equal-norm
/// constraint) W / H = |a1| / |a2|. The face is then taken as W/H x 1. The
/// orthogonality constraint r1 . r2 = 0 is not used for the aspect; its
/// residual (FacePose::orthogonality) says how well K fits the picture (see
/// focal_from_rectangle() to estimate f from it).
/// @throws std::invalid_argument for a corner count other than 4, a
///         non-finite or non-positive size, or degenerate corners (repeated,
///         collinear, non-finite, or not in order around a convex face).
[[nodiscard]] inline FacePose estimate_rectangle_pose(const Camera& camera, std::span<const glm::dvec2> corners,
                                                      std::optional<glm::dvec2> size = std::nullopt,
                                                      const PoseConfig& pose_options = {}) {
  if (corners.size() != 4)
    throw std::invalid_argument("estimate_rectangle_pose: a rectangle needs exactly 4 corners, got " +
                                std::to_string(corners.size()));
  if (size && (!std::isfinite(size->x) || !std::isfinite(size->y) || size->x <= 0.0 || size->y <= 0.0))
    throw std::invalid_argument("estimate_rectangle_pose: size must be finite and positive [mm]");
  if (!detail::finite_points(corners))
    throw std::invalid_argument("estimate_rectangle_pose: image points [px] must be finite");
  detail::check_point_set(corners, "estimate_rectangle_pose", "image points [px]");
  {
    // A rectangle in front of the camera images as a convex quadrilateral
    // with its corners in order: a crossing (bow-tie) or non-convex order
    // means the corners were not given around the face.
    const std::vector<glm::dvec2> ideal = camera.undistort(corners);
    int positive = 0;
    for (std::size_t i = 0; i < 4; ++i) {
      const glm::dvec2 a = ideal[(i + 1) % 4] - ideal[i];
      const glm::dvec2 b = ideal[(i + 2) % 4] - ideal[(i + 1) % 4];
      if (a.x * b.y - a.y * b.x > 0.0) ++positive;
    }
    if (positive != 0 && positive != 4)
      throw std::invalid_argument(
          "estimate_rectangle_pose: the 4 corners must go around the face in order (they form a "
          "crossed or non-convex quadrilateral)");
  }
  double w = 1.0;
  double h = 1.0;
  bool recovered = false;
  if (size) {
    w = size->x;
    h = size->y;
  } else {
    if (!detail::finite_points(corners))
      throw std::invalid_argument("estimate_rectangle_pose: image points [px] must be finite");
    const std::vector<glm::dvec2> unit{{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}};
    const cv::Matx33d H0 = homography_dlt(unit, camera.undistort(corners));
    const cv::Matx33d A = camera.matrix().inv() * H0;
    w = cv::norm(detail::col(A, 0)) / cv::norm(detail::col(A, 1));
    recovered = true;
  }
  const std::vector<glm::dvec2> plane{{0.0, 0.0}, {w, 0.0}, {w, h}, {0.0, h}};
  FacePose pose = estimate_plane_pose(camera, plane, corners, {}, pose_options);
  pose.width = w;
  pose.height = h;
  pose.aspect_recovered = recovered;
  return pose;
}

/// Focal length [px] of a square-pixel camera with known principal point
/// from one imaged rectangle of unknown size: the corners give H0 (unit
/// square -> pixels shifted by the principal point) and r1 . r2 = 0 gives
/// f^2 = -(g1x g2x + g1y g2y) / (g1z g2z) with g_i the columns of H0
/// (Zhang-style orthogonality constraint). Empty when the constraint is
/// degenerate (a vanishing point at infinity, e.g. a fronto-parallel face)
/// or gives no positive f^2.
[[nodiscard]] inline std::optional<double> focal_from_rectangle(std::span<const glm::dvec2> corners,
                                                                glm::dvec2 principal_point) {
  if (corners.size() != 4) throw std::invalid_argument("focal_from_rectangle: a rectangle needs exactly 4 corners");
  std::vector<glm::dvec2> shifted;
  for (auto c : corners)
    shifted.push_back(c - principal_point);
  const std::vector<glm::dvec2> unit{{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}};
  const cv::Matx33d G = homography_dlt(unit, shifted);
  const cv::Vec3d g1 = detail::col(G, 0);
  const cv::Vec3d g2 = detail::col(G, 1);
  const double scale = cv::norm(g1) * cv::norm(g2);
  const double denom = g1[2] * g2[2];
  // vanishing points farther than ~1e4 focal lengths: no information
  if (std::abs(denom) < 1e-12 * scale) return std::nullopt;
  const double f2 = -(g1[0] * g2[0] + g1[1] * g2[1]) / denom;
  if (!std::isfinite(f2) || f2 <= 0.0) return std::nullopt;
  return std::sqrt(f2);
}

}  // namespace hapticfield
