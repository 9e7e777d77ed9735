#pragma once
/// @file camera.hpp
/// Pinhole camera intrinsics K and lens distortion for the normals-from-a-
/// picture estimation (Kim & Kwon, World Haptics 2013): from an OpenCV
/// calibration file, from a focal length and principal point, or guessed
/// from a field of view. Setup code: may allocate and throw.

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <glm/vec2.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <pugixml.hpp>

#include "hapticfield/core/error.hpp"

namespace hapticfield {

/// A calibration file that is malformed or holds invalid values; what()
/// names the file (and the line or element).
class CalibrationError : public FileError {
 public:
  using FileError::FileError;
};

/// Largest calibration file read [bytes] (OpenCV's are a few KB).
inline constexpr std::uintmax_t max_calibration_file_bytes = std::uintmax_t{1} << 20;

namespace detail {

/// What a calibration file says, before the values are checked by Camera.
struct CalibrationMatrix {
  bool present{false};
  int rows{0};
  int cols{0};
  std::vector<double> data;
};
struct CalibrationContent {
  CalibrationMatrix k;
  CalibrationMatrix distortion;
  std::string distortion_name;
  std::optional<int> width;
  std::optional<int> height;
};

/// Reads the subset of OpenCV's YAML and XML persistence that calibration
/// files use. Strict: anything it does not understand about a field it
/// needs is an error naming the file and the line (YAML) or element (XML);
/// fields it does not need are skipped unparsed.
class CalibrationReader {
 public:
  CalibrationReader(std::string_view text, std::string_view name) : text_(text), name_(name) {}

  CalibrationContent read() {
    std::string_view t = text_;
    if (t.starts_with("\xEF\xBB\xBF")) t.remove_prefix(3);  // UTF-8 byte order mark
    const std::size_t first = t.find_first_not_of(" \t\r\n");
    if (first == std::string_view::npos) fail("empty file");
    if (t.substr(first).starts_with("%YAML")) {
      read_yaml(t);
    } else if (t[first] == '<') {
      read_xml(t);
    } else if (t[first] == '{') {
      fail("JSON calibration files are not read; save the calibration as YAML or XML");
    } else {
      fail("not an OpenCV calibration file (expected a %YAML:1.0 or <?xml header)");
    }
    if (!out_.k.present) fail("no 'camera_matrix' node");
    return std::move(out_);
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw CalibrationError("calibration file '" + std::string(name_) + "': " + what);
  }

 private:
  static bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
  static std::string_view trim(std::string_view s) noexcept {
    while (!s.empty() && is_space(s.front()))
      s.remove_prefix(1);
    while (!s.empty() && is_space(s.back()))
      s.remove_suffix(1);
    return s;
  }
  static std::string excerpt(std::string_view s) {
    return s.size() <= 32 ? std::string(s) : std::string(s.substr(0, 32)) + "...";
  }

  [[noreturn]] void fail_at(std::size_t line, const std::string& what) const {
    fail("line " + std::to_string(line) + ": " + what);
  }

  /// A number as OpenCV writes it ("1000.", "-1.5e-03"); `where` for messages.
  double number(std::string_view token, const std::string& where) const {
    std::string_view t = trim(token);
    if (!t.empty() && t.front() == '+') t.remove_prefix(1);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v))
      fail(where + ": '" + excerpt(trim(token)) + "' is not a finite number");
    return v;
  }

  /// A small non-negative integer (rows, cols, image size) up to `max`.
  int integer(std::string_view token, int max, const std::string& where) const {
    const std::string_view t = trim(token);
    int v = -1;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size() || v < 0 || v > max)
      fail(where + ": '" + excerpt(t) + "' is not an integer in 0.." + std::to_string(max));
    return v;
  }

  /// Which matrix a node name is (nullptr: not one we read).
  CalibrationMatrix* matrix_for(std::string_view key, const std::string& where) {
    if (key == "camera_matrix") {
      if (out_.k.present) fail(where + ": a second 'camera_matrix'");
      return &out_.k;
    }
    if (key == "distortion_coefficients" || key == "dist_coeffs" || key == "distortion") {
      if (out_.distortion.present)
        fail(where + ": '" + std::string(key) + "' after '" + out_.distortion_name + "': give the distortion once");
      out_.distortion_name = std::string(key);
      return &out_.distortion;
    }
    return nullptr;
  }

  /// Checks rows x cols for the matrix before any data is read.
  void check_shape(const CalibrationMatrix& m, std::string_view key, const std::string& where) const {
    if (&m == &out_.k) {
      if (m.rows != 3 || m.cols != 3)
        fail(where + ": 'camera_matrix' must be 3x3, not " + std::to_string(m.rows) + "x" + std::to_string(m.cols));
      return;
    }
    const int n = m.rows * m.cols;
    if ((m.rows != 1 && m.cols != 1) || (n != 4 && n != 5 && n != 8 && n != 12 && n != 14))
      fail(where + ": '" + std::string(key) + "' must be a vector of 4, 5, 8, 12 or 14 coefficients, not " +
           std::to_string(m.rows) + "x" + std::to_string(m.cols));
  }

  void check_dt(std::string_view dt, const std::string& where) const {
    dt = trim(dt);
    if (dt.size() != 1 || std::string_view("ucwsihfd").find(dt[0]) == std::string_view::npos)
      fail(where + ": 'dt' must be one of u c w s i h f d (one channel), not '" + excerpt(dt) + "'");
  }

  void scalar(std::string_view key, std::string_view value, const std::string& where) {
    if (key == "image_width" || key == "image_height") {
      std::optional<int>& slot = key == "image_width" ? out_.width : out_.height;
      if (slot) fail(where + ": a second '" + std::string(key) + "'");
      slot = integer(value, 1 << 20, where + ": '" + std::string(key) + "'");
    } else if (key == "camera_matrix" || key == "distortion_coefficients" || key == "dist_coeffs" ||
               key == "distortion") {
      fail(where + ": '" + std::string(key) + "' must be an opencv-matrix (rows, cols, dt, data)");
    }
  }

  // --- YAML (OpenCV's subset) ----------------------------------------------

  void read_yaml(std::string_view t) {
    std::size_t line_no = 0;
    std::size_t pos = 0;
    const auto next_line = [&](std::string_view& line) {
      if (pos >= t.size()) return false;
      std::size_t end = t.find('\n', pos);
      if (end == std::string_view::npos) end = t.size();
      line = t.substr(pos, end - pos);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      pos = end + 1;
      ++line_no;
      return true;
    };
    std::string_view line;
    // header: %YAML:1.x or %YAML 1.x, then an optional "---"
    while (next_line(line) && trim(line).empty()) {
    }
    {
      const std::string_view h = trim(line);
      const bool ok = h.size() > 8 && h.starts_with("%YAML") && (h[5] == ':' || h[5] == ' ') &&
                      h.substr(6, 2) == "1." && h.find_first_not_of("0123456789", 8) == std::string_view::npos;
      if (!ok) fail_at(line_no, "expected the header %YAML:1.0, found '" + excerpt(h) + "'");
    }
    CalibrationMatrix* matrix = nullptr;  // the matrix whose fields follow
    std::string matrix_key;
    std::size_t matrix_line = 0;
    bool in_data = false;   // inside "data: [ ... ]"
    bool skipping = false;  // indented lines of a node we do not read
    const auto finish_matrix = [&] {
      if (!matrix) return;
      const std::string where = "line " + std::to_string(matrix_line) + ": '" + matrix_key + "'";
      if (in_data) fail(where + ": 'data' is not closed with ']'");
      if (matrix->rows == 0 || matrix->cols == 0) fail(where + ": no 'rows' and 'cols'");
      if (matrix->data.empty()) fail(where + ": no 'data'");
      if (matrix->data.size() != static_cast<std::size_t>(matrix->rows * matrix->cols))
        fail(where + ": " + std::to_string(matrix->data.size()) +
             " values in 'data', rows x cols = " + std::to_string(matrix->rows * matrix->cols));
      matrix = nullptr;
    };
    const auto data_tokens = [&](std::string_view s) {  // values separated by commas and spaces; ']' ends
      const std::string where = "line " + std::to_string(line_no) + ": '" + matrix_key + "' data";
      std::size_t i = 0;
      while (i < s.size()) {
        if (is_space(s[i]) || s[i] == ',') {
          ++i;
          continue;
        }
        if (s[i] == ']') {
          in_data = false;
          if (!trim(s.substr(i + 1)).empty() && trim(s.substr(i + 1)).front() != '#')
            fail_at(line_no, "unexpected text after ']'");
          return;
        }
        std::size_t j = i;
        while (j < s.size() && !is_space(s[j]) && s[j] != ',' && s[j] != ']')
          ++j;
        if (matrix->data.size() >= static_cast<std::size_t>(matrix->rows * matrix->cols))
          fail(where + ": more values than rows x cols = " + std::to_string(matrix->rows * matrix->cols));
        matrix->data.push_back(number(s.substr(i, j - i), where));
        i = j;
      }
    };
    bool seen_document_start = false;
    while (next_line(line)) {
      if (in_data) {
        data_tokens(line);
        continue;
      }
      const std::string_view content = trim(line);
      if (content.empty() || content.front() == '#') continue;
      if (content == "---" && !seen_document_start && !matrix) {
        seen_document_start = true;
        continue;
      }
      if (content == "...") break;  // end of the document
      const bool indented = is_space(line.front());
      const std::size_t colon = content.find(':');
      if (indented) {
        if (skipping) continue;
        if (!matrix) fail_at(line_no, "unexpected indented line '" + excerpt(content) + "'");
        if (colon == std::string_view::npos) fail_at(line_no, "expected 'name: value' in '" + matrix_key + "'");
        const std::string_view field = trim(content.substr(0, colon));
        const std::string_view value = trim(content.substr(colon + 1));
        const std::string where = "line " + std::to_string(line_no) + ": '" + matrix_key + "'";
        if (field == "rows" || field == "cols") {
          if (!matrix->data.empty() || (field == "rows" ? matrix->rows : matrix->cols) != 0)
            fail(where + ": '" + std::string(field) + "' given twice or after 'data'");
          const int v = integer(value, 64, where + ": '" + std::string(field) + "'");
          if (v == 0) fail(where + ": '" + std::string(field) + "' must be positive");
          (field == "rows" ? matrix->rows : matrix->cols) = v;
        } else if (field == "dt") {
          check_dt(value, where);
        } else if (field == "data") {
          if (matrix->rows <= 0 || matrix->cols <= 0) fail(where + ": 'data' before 'rows' and 'cols'");
          check_shape(*matrix, matrix_key, where);
          if (value.empty() || value.front() != '[') fail(where + ": 'data' must be a list [ ... ]");
          in_data = true;
          data_tokens(value.substr(1));
        } else {
          fail(where + ": unknown field '" + excerpt(field) + "' (expected rows, cols, dt, data)");
        }
        continue;
      }
      // a top-level "name: value" line
      finish_matrix();
      skipping = false;
      if (colon == std::string_view::npos || colon == 0)
        fail_at(line_no, "expected 'name: value', found '" + excerpt(content) + "'");
      const std::string_view key = trim(content.substr(0, colon));
      for (char c : key)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
          fail_at(line_no, "'" + excerpt(key) + "' is not a node name");
      std::string_view value = trim(content.substr(colon + 1));
      if (const std::size_t hash = value.find(" #"); hash != std::string_view::npos)
        value = trim(value.substr(0, hash));
      const std::string where = "line " + std::to_string(line_no);
      if (value == "!!opencv-matrix") {
        matrix = matrix_for(key, where);
        if (!matrix) {
          skipping = true;  // another matrix: not read
          continue;
        }
        matrix->present = true;
        matrix_key = std::string(key);
        matrix_line = line_no;
      } else if (value.empty() || value.front() == '!') {
        if (matrix_for(key, where)) fail(where + ": '" + std::string(key) + "' must be an !!opencv-matrix");
        skipping = true;  // a nested node we do not read
      } else {
        scalar(key, value, where);
      }
    }
    finish_matrix();
  }

  // --- XML (through pugixml) -------------------------------------------------

  void read_xml(std::string_view t) {
    pugi::xml_document doc;
    const pugi::xml_parse_result r = doc.load_buffer(t.data(), t.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!r) fail("malformed XML: " + std::string(r.description()) + " (at byte " + std::to_string(r.offset) + ")");
    pugi::xml_node root;
    for (pugi::xml_node n = doc.first_child(); n; n = n.next_sibling()) {
      if (n.type() != pugi::node_element) continue;
      if (root) fail("element <" + std::string(n.name()) + "> after the root element");
      root = n;
    }
    if (!root || std::string_view(root.name()) != "opencv_storage") fail("the root element must be <opencv_storage>");
    for (pugi::xml_node n = root.first_child(); n; n = n.next_sibling()) {
      if (n.type() != pugi::node_element) continue;
      const std::string key = n.name();
      const std::string where = "<" + key + ">";
      const bool is_matrix = std::string_view(n.attribute("type_id").value()) == "opencv-matrix";
      if (!is_matrix) {
        if (n.first_child() && n.first_child().type() == pugi::node_element) {
          if (matrix_for(key, where)) fail(where + ": must be an opencv-matrix (type_id=\"opencv-matrix\")");
          continue;  // a nested node we do not read
        }
        scalar(key, n.text().get(), where);
        continue;
      }
      CalibrationMatrix* m = matrix_for(key, where);
      if (!m) continue;
      m->present = true;
      const auto field = [&](const char* f) {
        const pugi::xml_node c = n.child(f);
        if (!c) fail(where + ": missing <" + f + ">");
        if (c.next_sibling(f)) fail(where + ": <" + f + "> given twice");
        return c;
      };
      m->rows = integer(field("rows").text().get(), 64, where + "<rows>");
      m->cols = integer(field("cols").text().get(), 64, where + "<cols>");
      check_dt(field("dt").text().get(), where + "<dt>");
      check_shape(*m, key, where);
      const std::string_view data = field("data").text().get();
      const std::size_t want = static_cast<std::size_t>(m->rows * m->cols);
      std::size_t i = 0;
      while (i < data.size()) {
        while (i < data.size() && is_space(data[i]))
          ++i;
        std::size_t j = i;
        while (j < data.size() && !is_space(data[j]))
          ++j;
        if (j > i) {
          if (m->data.size() >= want) fail(where + "<data>: more values than rows x cols = " + std::to_string(want));
          m->data.push_back(number(data.substr(i, j - i), where + "<data>"));
        }
        i = j;
      }
      if (m->data.size() != want)
        fail(where + "<data>: " + std::to_string(m->data.size()) + " values, rows x cols = " + std::to_string(want));
    }
  }

  std::string_view text_;
  std::string_view name_;
  CalibrationContent out_;
};

}  // namespace detail

/// Camera intrinsics: K = [fx s cx; 0 fy cy; 0 0 1] [px] and OpenCV
/// distortion coefficients (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tx ty]]]]).
/// Pixel convention as OpenCV: x right, y down, integer coordinates are
/// pixel centres.
class Camera {
 public:
  /// From focal lengths and principal point [px].
  /// @throws std::invalid_argument for a non-positive or non-finite focal
  ///         length or a non-finite principal point.
  Camera(double fx, double fy, glm::dvec2 centre, std::vector<double> distortion = {})
      : Camera(cv::Matx33d(fx, 0.0, centre.x, 0.0, fy, centre.y, 0.0, 0.0, 1.0), std::move(distortion)) {}

  /// From a full 3x3 camera matrix and optional distortion coefficients.
  /// @throws std::invalid_argument when K is not finite, not upper
  ///         triangular with K(2,2) = 1, or a focal length is not positive,
  ///         or the number of distortion coefficients is not 4, 5, 8, 12 or 14.
  explicit Camera(const cv::Matx33d& K, std::vector<double> distortion = {})
      : K_(K), distortion_(std::move(distortion)) {
    for (int i = 0; i < 9; ++i)
      if (!std::isfinite(K.val[i])) throw std::invalid_argument("Camera: camera matrix entries must be finite");
    if (!(K(0, 0) > 0.0) || !(K(1, 1) > 0.0)) throw std::invalid_argument("Camera: focal length must be positive [px]");
    if (K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0)
      throw std::invalid_argument("Camera: camera matrix must be [fx s cx; 0 fy cy; 0 0 1]");
    const std::size_t n = distortion_.size();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
      throw std::invalid_argument("Camera: distortion_coefficients must have 4, 5, 8, 12 or 14 entries");
    for (double d : distortion_)
      if (!std::isfinite(d)) throw std::invalid_argument("Camera: distortion coefficients must be finite");
    bool any = false;
    for (double d : distortion_)
      any = any || d != 0.0;
    if (!any) distortion_.clear();
  }

  /// Square pixels: fx = fy = focal [px], principal point centre [px].
  [[nodiscard]] static Camera from_focal(double focal, glm::dvec2 centre) {
    if (!std::isfinite(focal) || focal <= 0.0)
      throw std::invalid_argument("Camera::from_focal: focal length must be finite and positive [px]");
    if (!std::isfinite(centre.x) || !std::isfinite(centre.y))
      throw std::invalid_argument("Camera::from_focal: principal point must be finite [px]");
    return Camera(focal, focal, centre);
  }

  /// A guess for an uncalibrated picture: square pixels, principal point at
  /// the image centre ((w-1)/2, (h-1)/2), focal length from the horizontal
  /// field of view: f = (w/2) / tan(hfov/2) [px].
  [[nodiscard]] static Camera from_field_of_view(double horizontal_fov_deg, int width, int height) {
    if (width <= 0 || height <= 0)
      throw std::invalid_argument("Camera::from_field_of_view: image size must be positive [px]");
    if (!std::isfinite(horizontal_fov_deg) || horizontal_fov_deg <= 0.0 || horizontal_fov_deg >= 180.0)
      throw std::invalid_argument("Camera::from_field_of_view: horizontal field of view must be in (0, 180) [deg]");
    const double half = horizontal_fov_deg * std::numbers::pi / 360.0;
    return from_focal(0.5 * width / std::tan(half), image_centre(width, height));
  }

  /// Reads an OpenCV calibration file (YAML or XML as written by
  /// cv::FileStorage, e.g. after cv::calibrateCamera): the 3x3
  /// !!opencv-matrix `camera_matrix` and optionally
  /// `distortion_coefficients` (also accepted: `dist_coeffs`, `distortion`)
  /// with 4, 5, 8, 12 or 14 entries, `image_width`, `image_height`.
  /// The file is read and checked by the library's own strict reader
  /// (pugixml for XML); OpenCV never parses it.
  /// @throws FileError when the file is missing, not a regular file,
  ///         unreadable or larger than max_calibration_file_bytes;
  ///         CalibrationError (a FileError) naming the file when it is
  ///         malformed or its values are invalid.
  [[nodiscard]] static Camera from_file(const std::string& path) {
    return from_text(read_file(path, max_calibration_file_bytes), path);
  }

  /// Parses calibration text held in memory (as from_file(); `name` names
  /// it in messages).
  /// @throws CalibrationError naming `name` when the text is malformed or
  ///         its values are invalid.
  [[nodiscard]] static Camera from_text(std::string_view text, std::string_view name);

  /// Writes K and the distortion in the layout from_file() reads (YAML or
  /// XML by the file's extension, through cv::FileStorage).
  /// @throws FileError when the file cannot be written.
  void save(const std::string& path) const {
    try {
      cv::FileStorage fs(path, cv::FileStorage::WRITE);
      if (!fs.isOpened()) throw FileError("cannot write '" + path + "'");
      if (width_ > 0) fs << "image_width" << width_;
      if (height_ > 0) fs << "image_height" << height_;
      fs << "camera_matrix" << cv::Mat(K_);
      fs << "distortion_coefficients" << cv::Mat(distortion_.empty() ? std::vector<double>(5, 0.0) : distortion_);
    } catch (const cv::Exception& e) {
      throw FileError("cannot write '" + path + "': " + e.what());
    }
  }

  /// The same camera for the picture resized by (sx, sy): focal lengths and
  /// skew scale, the principal point maps pixel centres
  /// (c' = (c + 0.5) s - 0.5); distortion is unchanged (it acts on
  /// normalised coordinates). The recorded image size scales too.
  /// @throws std::invalid_argument for a non-finite or non-positive factor.
  [[nodiscard]] Camera scaled(double sx, double sy) const {
    if (!std::isfinite(sx) || !std::isfinite(sy) || sx <= 0.0 || sy <= 0.0)
      throw std::invalid_argument("Camera::scaled: scale factors must be finite and positive");
    cv::Matx33d k = K_;
    k(0, 0) *= sx;
    k(0, 1) *= sx;
    k(0, 2) = (k(0, 2) + 0.5) * sx - 0.5;
    k(1, 1) *= sy;
    k(1, 2) = (k(1, 2) + 0.5) * sy - 0.5;
    Camera c(k, distortion_);
    c.width_ = static_cast<int>(std::lround(width_ * sx));
    c.height_ = static_cast<int>(std::lround(height_ * sy));
    return c;
  }

  /// The camera matrix K [px].
  [[nodiscard]] const cv::Matx33d& matrix() const noexcept { return K_; }
  /// Distortion coefficients (empty when the lens is ideal).
  [[nodiscard]] const std::vector<double>& distortion() const noexcept { return distortion_; }
  [[nodiscard]] bool has_distortion() const noexcept { return !distortion_.empty(); }
  /// Image size recorded in the calibration file [px] (0 when unknown).
  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }

  /// Distorted pixel positions -> ideal (undistorted) pixel positions seen
  /// through the same K. Returns the points unchanged without distortion.
  [[nodiscard]] std::vector<glm::dvec2> undistort(std::span<const glm::dvec2> pixels) const {
    std::vector<glm::dvec2> out(pixels.begin(), pixels.end());
    if (distortion_.empty() || out.empty()) return out;
    std::vector<cv::Point2d> src;
    src.reserve(out.size());
    for (auto p : out)
      src.emplace_back(p.x, p.y);
    std::vector<cv::Point2d> dst;
    cv::undistortPoints(src, dst, cv::Mat(K_), cv::Mat(distortion_), cv::noArray(), cv::Mat(K_));
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i] = glm::dvec2{dst[i].x, dst[i].y};
    return out;
  }

  /// The centre of a width x height image in the pixel-centre convention [px].
  [[nodiscard]] static glm::dvec2 image_centre(int width, int height) noexcept {
    return glm::dvec2{(width - 1) / 2.0, (height - 1) / 2.0};
  }

 private:
  cv::Matx33d K_;
  std::vector<double> distortion_;
  int width_ = 0;
  int height_ = 0;
};

inline Camera Camera::from_text(std::string_view text, std::string_view name) {
  detail::CalibrationReader reader(text, name);
  detail::CalibrationContent c = reader.read();
  if (c.k.data.size() != 9)
    reader.fail("'camera_matrix' must hold 9 values");  // checked by read(); never trust it here
  try {
    Camera camera(cv::Matx33d(c.k.data.data()), std::move(c.distortion.data));
    camera.width_ = c.width.value_or(0);
    camera.height_ = c.height.value_or(0);
    return camera;
  } catch (const std::invalid_argument& e) {
    reader.fail(e.what());
  }
}

}  // namespace hapticfield
