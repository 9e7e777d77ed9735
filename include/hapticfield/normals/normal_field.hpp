#pragma once
/// @file normal_field.hpp
/// The geometry-based haptic field of Kim & Kwon (World Haptics 2013): image
/// polygons each carrying a face normal; moving over the picture feels the
/// slopes (F = n . m_hat: uphill resists, downhill assists, level is silent),
/// edges between faces are felt as normal discontinuities, and an optional
/// grid of vertex normals interpolated across each cell gives smooth "force
/// shading".
///
/// Conventions. Normals are in the camera frame (OpenCV: x right, y down,
/// z forward), unit, turned toward the camera (n_z <= 0). The picture's
/// x and y axes are the camera's x and y, so a face seen as a surface whose
/// height h grows toward the viewer (-z) has grad h = (n_x, n_y) / n_z:
/// uphill in the image is -(n_x, n_y), downhill is +(n_x, n_y). With m_hat
/// the unit image-plane direction of motion (x right, y down), the paper's
/// scalar s = n . m_hat = n_x m_x + n_y m_y is negative when climbing and
/// positive when descending, and |s| <= sin(slant) <= 1. The force is
///     F_image = F_max * s * m_hat            (along the motion, the default)
/// i.e. against the motion when climbing, with it when descending, and zero
/// along a level line: the tangential weight of a body of weight F_max on an
/// incline, bounded by F_max (0.6 N in the paper). The Minsky-style gradient
/// variant, direction-free, pushes downhill whatever the motion:
///     F_image = F_max * (n_x, n_y).
/// F_image (x right, y down, [N]) is mapped to the device frame through the
/// PlaneMapping (image y is device -y with the default mapping).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/plane_mapping.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// The paper's force bound [N].
inline constexpr double kim_kwon_max_force = 0.6;

/// A face of the picture: an image polygon (convex or not, vertices in
/// order, [px]) and its unit normal (camera frame, toward the camera).
struct ImageFace {
  std::vector<glm::dvec2> polygon;    ///< vertices [px]
  glm::dvec3 normal{0.0, 0.0, -1.0};  ///< unit normal, n_z <= 0
};

/// Which force law NormalField applies.
enum class NormalForceMode {
  along_motion,  ///< F = F_max (n . m_hat) m_hat (Kim & Kwon)
  gradient,      ///< F = F_max (n_x, n_y): downhill push, no motion needed (Minsky-style)
};

/// Parameters of NormalField.
struct NormalFieldConfig {
  NormalForceMode mode = NormalForceMode::along_motion;
  double max_force = kim_kwon_max_force;  ///< force bound F_max [N]
  double speed_threshold = 0.005;         ///< below this filtered HIP speed no direction, no force [m/s]
  /// Extra first-order low-pass on the HIP velocity [Hz]; 0 (default): none.
  /// ForceArm already low-passes the velocity (100 Hz), and two filters in
  /// a row add their lags; set it for velocity sources that are not filtered.
  double velocity_cutoff_hz = 0.0;
  double shading_cell_px = 0.0;  ///< force-shading grid spacing [px]; 0 = flat faces
};

/// Image of face labels: label_at(pixel) is the index of the face covering
/// that pixel or -1. Built once with cv::fillPoly (later faces paint over
/// earlier ones where they overlap); each lookup is one array read.
class FaceLabels {
 public:
  FaceLabels() = default;

  /// @throws std::invalid_argument for a non-positive size, a polygon with
  ///         fewer than 3 vertices or non-finite vertices.
  FaceLabels(int width, int height, std::span<const ImageFace> faces) : width_(width), height_(height) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("FaceLabels: image size must be positive [px]");
    if (faces.size() > static_cast<std::size_t>(INT32_MAX)) throw std::invalid_argument("FaceLabels: too many faces");
    cv::Mat labels(height, width, CV_32S, cv::Scalar(-1));
    constexpr int shift = 8;  // sub-pixel vertices: 1/256 px
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const auto& poly = faces[i].polygon;
      if (poly.size() < 3)
        throw std::invalid_argument("FaceLabels: face " + std::to_string(i) + " needs at least 3 vertices");
      std::vector<cv::Point> pts;
      pts.reserve(poly.size());
      for (auto p : poly) {
        if (!is_finite(p) || std::abs(p.x) > 1e6 || std::abs(p.y) > 1e6)
          throw std::invalid_argument("FaceLabels: face " + std::to_string(i) +
                                      " has a non-finite or out-of-range vertex [px]");
        pts.emplace_back(cvRound(p.x * (1 << shift)), cvRound(p.y * (1 << shift)));
      }
      const cv::Point* data = pts.data();
      const int count = static_cast<int>(pts.size());
      cv::fillPoly(labels, &data, &count, 1, cv::Scalar(static_cast<double>(i)), cv::LINE_8, shift);
    }
    labels_.assign(labels.begin<std::int32_t>(), labels.end<std::int32_t>());
  }

  /// Index of the face at an image position [px], or -1 (background or
  /// outside the picture). O(1).
  [[nodiscard]] int label_at(glm::dvec2 pixel) const noexcept {
    if (!(pixel.x >= -0.5) || !(pixel.y >= -0.5) || !(pixel.x < width_ - 0.5) || !(pixel.y < height_ - 0.5)) return -1;
    const int x = static_cast<int>(pixel.x + 0.5);
    const int y = static_cast<int>(pixel.y + 0.5);
    return labels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
  }

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  /// Row-major labels, width * height.
  [[nodiscard]] std::span<const std::int32_t> data() const noexcept { return labels_; }

 private:
  int width_ = 0;
  int height_ = 0;
  std::vector<std::int32_t> labels_;
};

/// Force shading: unit normals at the vertices of a regular grid of image
/// points, bilinearly interpolated across each cell and renormalised (the
/// haptic counterpart of Phong shading). A zero vertex normal means "no
/// surface there" and takes no part once the interpolation is renormalised.
class ShadingGrid {
 public:
  ShadingGrid() = default;

  /// Vertex (i, j) sits at origin + spacing * (i, j) [px], i < cols, j < rows;
  /// normals row-major (cols * rows), each unit (n_z <= 0) or zero.
  /// @throws std::invalid_argument for a bad spacing, size or normal.
  ShadingGrid(glm::dvec2 origin, double spacing_px, int cols, int rows, std::vector<glm::dvec3> normals)
      : origin_(origin), spacing_(spacing_px), cols_(cols), rows_(rows), normals_(std::move(normals)) {
    if (!is_finite(origin)) throw std::invalid_argument("ShadingGrid: origin must be finite [px]");
    if (!std::isfinite(spacing_px) || spacing_px <= 0.0)
      throw std::invalid_argument("ShadingGrid: spacing must be finite and positive [px]");
    if (cols < 2 || rows < 2) throw std::invalid_argument("ShadingGrid: at least 2 x 2 vertices are needed");
    if (normals_.size() != static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows))
      throw std::invalid_argument("ShadingGrid: expected cols * rows vertex normals");
    for (auto& n : normals_) {
      if (!is_finite(n)) throw std::invalid_argument("ShadingGrid: vertex normals must be finite");
      const double len = glm::length(n);
      if (len == 0.0) continue;
      if (std::abs(len - 1.0) > 1e-6) throw std::invalid_argument("ShadingGrid: vertex normals must be unit or zero");
      if (n.z > 1e-9) throw std::invalid_argument("ShadingGrid: vertex normals must face the camera (n_z <= 0)");
    }
  }

  /// Vertex normals from the faces: each vertex takes the area-weighted mean
  /// of the face normals of the pixels within one cell of it (the four cells
  /// around it), renormalised; zero where no face is near. Setup cost
  /// O(pixels), memory O(cells).
  [[nodiscard]] static ShadingGrid from_faces(const FaceLabels& labels, std::span<const glm::dvec3> face_normals,
                                              double spacing_px) {
    if (!std::isfinite(spacing_px) || spacing_px < 1.0)
      throw std::invalid_argument("ShadingGrid::from_faces: spacing must be at least 1 [px]");
    const int w = labels.width();
    const int h = labels.height();
    const int cols = static_cast<int>(std::ceil((w - 1) / spacing_px)) + 1;
    const int rows = static_cast<int>(std::ceil((h - 1) / spacing_px)) + 1;
    // sum of the normals of the labelled pixels in each cell [c s, (c+1) s)
    const std::size_t ucols = static_cast<std::size_t>(cols);
    std::vector<glm::dvec3> cells(ucols * static_cast<std::size_t>(rows), glm::dvec3{0.0});
    const auto data = labels.data();
    for (int y = 0; y < h; ++y) {
      const std::size_t cy = static_cast<std::size_t>(std::min(static_cast<int>(y / spacing_px), rows - 1));
      for (int x = 0; x < w; ++x) {
        const int l = data[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)];
        if (l < 0) continue;
        const std::size_t cx = static_cast<std::size_t>(std::min(static_cast<int>(x / spacing_px), cols - 1));
        cells[cy * ucols + cx] += face_normals[static_cast<std::size_t>(l)];
      }
    }
    std::vector<glm::dvec3> normals(cells.size(), glm::dvec3{0.0});
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) {
        glm::dvec3 sum{0.0};
        for (int dj = -1; dj <= 0; ++dj)
          for (int di = -1; di <= 0; ++di) {
            const int ci = i + di;
            const int cj = j + dj;
            if (ci >= 0 && cj >= 0) sum += cells[static_cast<std::size_t>(cj) * ucols + static_cast<std::size_t>(ci)];
          }
        const double len = glm::length(sum);
        if (len > 1e-9) normals[static_cast<std::size_t>(j) * ucols + static_cast<std::size_t>(i)] = sum / len;
      }
    return ShadingGrid(glm::dvec2{0.0}, spacing_px, cols, rows, std::move(normals));
  }

  /// Interpolated unit normal at an image position [px]; zero outside the
  /// grid or where the surrounding vertices carry no normal. O(1).
  [[nodiscard]] glm::dvec3 normal_at(glm::dvec2 pixel) const noexcept {
    const glm::dvec2 g = (pixel - origin_) / spacing_;
    if (!(g.x >= 0.0) || !(g.y >= 0.0) || !(g.x <= cols_ - 1.0) || !(g.y <= rows_ - 1.0)) return glm::dvec3{0.0};
    const int i = std::min(static_cast<int>(g.x), cols_ - 2);
    const int j = std::min(static_cast<int>(g.y), rows_ - 2);
    const double fx = g.x - i;
    const double fy = g.y - j;
    const std::size_t k = static_cast<std::size_t>(j) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(i);
    const std::size_t c = static_cast<std::size_t>(cols_);
    const glm::dvec3 n = (1.0 - fy) * ((1.0 - fx) * normals_[k] + fx * normals_[k + 1]) +
                         fy * ((1.0 - fx) * normals_[k + c] + fx * normals_[k + c + 1]);
    const double len = glm::length(n);
    return len > 1e-9 ? n / len : glm::dvec3{0.0};
  }

  [[nodiscard]] bool empty() const noexcept { return normals_.empty(); }
  [[nodiscard]] int cols() const noexcept { return cols_; }
  [[nodiscard]] int rows() const noexcept { return rows_; }
  [[nodiscard]] double spacing() const noexcept { return spacing_; }
  [[nodiscard]] glm::dvec2 origin() const noexcept { return origin_; }

 private:
  glm::dvec2 origin_{0.0};
  double spacing_ = 1.0;
  int cols_ = 0;
  int rows_ = 0;
  std::vector<glm::dvec3> normals_;
};

/// The normals-from-a-picture field (see the file comment for the force
/// law and conventions). Stateful (the velocity low-pass): reset() before
/// reuse. force() is O(1) in the number of faces, noexcept, allocation-free.
///
/// @code
///   const FacePose pose = estimate_rectangle_pose(camera, corners_px);
///   NormalField field(picture.cols, picture.rows, {{corners_px, pose.normal}});
///   glm::dvec3 f = field.force(probe);  // [N], device frame
/// @endcode
class NormalField {
 public:
  /// @param width, height  picture size [px]
  /// @param faces  polygons and normals (normals are normalised here)
  /// @param options  force law, bound, speed threshold, filter, shading
  /// @param mapping  device <-> image; default PlaneMapping::kim_kwon(width, height)
  /// @param shading  explicit vertex normals; when empty and
  ///        options.shading_cell_px > 0 the grid is built from the faces
  /// @throws std::invalid_argument for a bad size, polygon, normal (non-finite,
  ///         zero, or facing away: n_z > 0) or option.
  NormalField(int width, int height, std::vector<ImageFace> faces, NormalFieldConfig options = {},
              std::optional<PlaneMapping> mapping = std::nullopt, ShadingGrid shading = {})
      : options_(options),
        mapping_(mapping ? *mapping : PlaneMapping::kim_kwon(width, height)),
        labels_(width, height, faces),
        shading_(std::move(shading)) {
    if (!std::isfinite(options.max_force) || options.max_force <= 0.0)
      throw std::invalid_argument("NormalField: max_force must be finite and positive [N]");
    if (!std::isfinite(options.speed_threshold) || options.speed_threshold < 0.0)
      throw std::invalid_argument("NormalField: speed_threshold must be finite and non-negative [m/s]");
    if (!std::isfinite(options.velocity_cutoff_hz) || options.velocity_cutoff_hz < 0.0)
      throw std::invalid_argument("NormalField: velocity_cutoff_hz must be finite and >= 0 (0: no filter) [Hz]");
    if (!std::isfinite(options.shading_cell_px) || options.shading_cell_px < 0.0)
      throw std::invalid_argument("NormalField: shading_cell_px must be finite and non-negative [px]");
    normals_.reserve(faces.size());
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const glm::dvec3 n = faces[i].normal;
      const double len = is_finite(n) ? glm::length(n) : 0.0;
      if (!(len > 1e-12) || !std::isfinite(len))
        throw std::invalid_argument("NormalField: face " + std::to_string(i) + " needs a finite non-zero normal");
      if (n.z / len > 1e-9)
        throw std::invalid_argument("NormalField: face " + std::to_string(i) +
                                    " normal must face the camera (n_z <= 0, camera frame)");
      normals_.push_back(n / len);
    }
    if (shading_.empty() && options.shading_cell_px > 0.0)
      shading_ = ShadingGrid::from_faces(labels_, normals_, options.shading_cell_px);
    threshold_px_ = options.speed_threshold * mapping_.px_per_mm() * 1000.0;
    update_alpha(servo_period);
  }

  /// Force on the HIP [N], device frame. Zero for a non-finite probe, off
  /// the faces, or (along_motion) below the speed threshold.
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    if (!is_finite(probe.position) || !is_finite(probe.velocity)) return glm::dvec3{0.0};
    const glm::dvec2 pixel = mapping_.to_image(probe.position);
    const glm::dvec2 velocity = mapping_.velocity_to_image(probe.velocity);
    if (!is_finite(pixel) || !is_finite(velocity)) return glm::dvec3{0.0};
    if (probe.period != period_ && std::isfinite(probe.period) && probe.period > 0.0) update_alpha(probe.period);
    if (primed_) {
      velocity_ += alpha_ * (velocity - velocity_);
    } else {
      velocity_ = velocity;
      primed_ = true;
    }
    return mapping_.vector_to_device(image_force(pixel, velocity_));
  }

  /// Forgets the filtered velocity (the next tick starts from its own).
  void reset() noexcept {
    velocity_ = glm::dvec2{0.0};
    primed_ = false;
  }

  /// The force law itself in image axes (x right, y down) [N] at an image
  /// position [px] for an image velocity [px/s] (no filtering).
  [[nodiscard]] glm::dvec2 image_force(glm::dvec2 pixel, glm::dvec2 velocity_px) const noexcept {
    const glm::dvec3 n = normal_at(pixel);
    if (options_.mode == NormalForceMode::gradient) return options_.max_force * glm::dvec2{n.x, n.y};
    const double speed = glm::length(velocity_px);
    if (!(speed > threshold_px_) || !(speed > 0.0) || !std::isfinite(speed)) return glm::dvec2{0.0};
    const glm::dvec2 m = velocity_px / speed;
    const double s = n.x * m.x + n.y * m.y;  // Kim & Kwon: F = n . m_hat
    return options_.max_force * s * m;
  }

  /// The normal felt at an image position [px]: the face's, or the shaded
  /// one inside a face when force shading is on; zero off the faces.
  [[nodiscard]] glm::dvec3 normal_at(glm::dvec2 pixel) const noexcept {
    const int label = labels_.label_at(pixel);
    if (label < 0) return glm::dvec3{0.0};
    if (!shading_.empty()) return shading_.normal_at(pixel);
    return normals_[static_cast<std::size_t>(label)];
  }

  /// A probe at an image position [px] moving at an image velocity [px/s].
  [[nodiscard]] Probe probe_at(glm::dvec2 pixel, glm::dvec2 velocity_px = glm::dvec2{0.0}) const noexcept {
    Probe p;
    p.position = mapping_.to_device(pixel);
    p.velocity = mapping_.vector_to_device(velocity_px) / (mapping_.px_per_mm() * 1000.0);
    return p;
  }

  /// A device-frame force [N] in image axes (x right, y down) [N].
  [[nodiscard]] glm::dvec2 to_image_axes(const glm::dvec3& force) const noexcept {
    return glm::dvec2{glm::dot(force, mapping_.vector_to_device({1.0, 0.0})),
                      glm::dot(force, mapping_.vector_to_device({0.0, 1.0}))};
  }

  [[nodiscard]] const FaceLabels& labels() const noexcept { return labels_; }
  [[nodiscard]] const ShadingGrid& shading() const noexcept { return shading_; }
  [[nodiscard]] const PlaneMapping& mapping() const noexcept { return mapping_; }
  [[nodiscard]] const NormalFieldConfig& options() const noexcept { return options_; }
  [[nodiscard]] std::span<const glm::dvec3> normals() const noexcept { return normals_; }
  /// Filtered image velocity [px/s].
  [[nodiscard]] glm::dvec2 filtered_velocity() const noexcept { return velocity_; }

 private:
  void update_alpha(double period) noexcept {
    period_ = period;
    // first-order low-pass, exact discretisation: alpha = 1 - exp(-2 pi fc dt);
    // no cutoff: alpha = 1, the velocity passes unchanged
    alpha_ = options_.velocity_cutoff_hz > 0.0
                 ? 1.0 - std::exp(-2.0 * std::numbers::pi * options_.velocity_cutoff_hz * period)
                 : 1.0;
  }

  NormalFieldConfig options_;
  PlaneMapping mapping_;
  FaceLabels labels_;
  ShadingGrid shading_;
  std::vector<glm::dvec3> normals_;
  double threshold_px_ = 0.0;
  double period_ = servo_period;
  double alpha_ = 1.0;
  glm::dvec2 velocity_{0.0};
  bool primed_ = false;
};

static_assert(ResettableField<NormalField>);

}  // namespace hapticfield
