// Pictures in: tangible images, force maps, normals from a picture.
#include "field.hpp"

#include <hapticfield/kernels.hpp>
#include <hapticfield/normals.hpp>

#include <pybind11/stl.h>

#include <cmath>
#include <map>

namespace hapticfield::python {

namespace {

/// Largest picture accepted as an array [px] (int sizes, 8 bytes a pixel: 2 GiB).
constexpr py::ssize_t max_array_pixels = py::ssize_t{1} << 28;

/// A number as Python prints it (255.0, 0.5, nan).
std::string number(double v) {
  return py::str(py::float_(v));
}

}  // namespace

GrayWeights gray_weights(const std::string& name) {
  return choose<GrayWeights>("gray", name, {{"paper", GrayWeights::paper}, {"bt601", GrayWeights::bt601}});
}

/// A picture from a path (any format OpenCV reads; 16-bit files are scaled by 255 / 65535) or a numpy array:
/// H x W gray levels, or H x W x 3 / 4 colour in the order `channels` names ("rgb": R, G, B (, A), as numpy
/// and PIL hold pictures; "bgr": B, G, R (, A), as cv2.imread returns them). An array's white level: 255 for
/// uint8 and other integer arrays, 65535 for uint16 (as 16-bit files), and `levels` for float or bool
/// arrays, which have no scale of their own and are refused without it (1.0 for pictures in [0, 1]).
GrayImage gray_from(const py::object& image, GrayWeights weights, const std::string& channels,
                    std::optional<double> levels) {
  const bool bgr = choose<bool>("channels", channels, {{"rgb", false}, {"bgr", true}});
  if (levels && !(std::isfinite(*levels) && *levels > 0.0))
    throw py::value_error("levels: the array's white level must be finite and > 0, e.g. 1.0 or 255");
  if (py::isinstance<py::str>(image) || py::hasattr(image, "__fspath__")) {
    const std::string path = py::str(py::module_::import("os").attr("fspath")(image));
    return load_gray(path, weights);
  }
  const py::array raw = py::array::ensure(image);
  if (!raw) throw py::type_error("image: expected a path or a numpy array");
  const char kind = raw.dtype().kind();
  if (kind != 'u' && kind != 'i' && kind != 'f' && kind != 'b')
    throw py::type_error("image: expected a numeric array, got dtype " + std::string(py::str(raw.dtype())));
  double white = gray_full_scale;
  if (levels)
    white = *levels;
  else if (kind == 'f' || kind == 'b')
    throw py::value_error(
        "image: a " + std::string(py::str(raw.dtype())) +
        " array has no gray scale of its own: give levels= (its white level: 1.0 for a picture in [0, 1], 255 for "
        "[0, 255]), or pass uint8 / uint16");
  else if (kind == 'u' && raw.itemsize() == 2)
    white = 65535.0;
  const Array a = Array::ensure(raw);
  if (!a) throw py::type_error("image: expected a path or a numpy array");
  if (a.ndim() != 2 && !(a.ndim() == 3 && (a.shape(2) == 3 || a.shape(2) == 4)))
    throw py::value_error("image: expected an H x W gray array or an H x W x 3 / x 4 colour array (see channels=)");
  if (a.shape(0) < 1 || a.shape(1) < 1) throw py::value_error("image: the array is empty (0 x 0 px)");
  if (a.shape(0) * a.shape(1) > max_array_pixels)
    throw py::value_error("image: more than " + std::to_string(max_array_pixels) + " pixels");
  GrayImage gray(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
  const LumaWeights w = luma_weights(weights);
  const py::ssize_t c = a.ndim() == 3 ? a.shape(2) : 1;
  const int r_at = bgr ? 2 : 0, b_at = bgr ? 0 : 2;
  // The same arithmetic as a file's pixels (to_gray): scale * (wb B + wg G + wr R).
  const double scale = gray_full_scale / white;
  const double* src = a.data();
  for (int y = 0; y < gray.height(); ++y)
    for (int x = 0; x < gray.width(); ++x, src += c) {
      for (py::ssize_t k = 0; k < std::min<py::ssize_t>(c, 3); ++k)
        if (!(std::isfinite(src[k]) && src[k] >= 0.0 && src[k] <= white))
          throw py::value_error("image: values must be finite and within [0, " + number(white) + "], got " +
                                number(src[k]) + " at (" + std::to_string(x) + ", " + std::to_string(y) + ")" +
                                (levels ? "" : " (give levels= for another scale)"));
      gray.at(x, y) = c == 1 ? scale * src[0] : scale * (w.b * src[b_at] + w.g * src[1] + w.r * src[r_at]);
    }
  return gray;
}

namespace {

py::array_t<double> tangible_forces(const py::object& image, const Array& xy, const std::string& mask,
                                    std::optional<int> size, const std::string& border, double sigma,
                                    const std::string& gray, const std::string& channels,
                                    std::optional<double> levels) {
  const py::ssize_t n = rows_of(xy, 2, "xy");
  const TangibleImage tangible(gray_from(image, gray_weights(gray), channels, levels),
                               tangible_options(mask, size, border, sigma));
  auto out = matrix(n, 2);
  const double* p = xy.data();
  double* f = out.mutable_data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) {
      const glm::dvec2 r = tangible.at(p[2 * i], p[2 * i + 1]);
      f[2 * i] = r.x, f[2 * i + 1] = r.y;
    }
  }
  return out;
}

py::dict pose_dict(const FacePose& pose) {
  py::dict d;
  d["normal"] = std::array<double, 3>{pose.normal.x, pose.normal.y, pose.normal.z};
  std::array<std::array<double, 3>, 3> R{}, H{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      R[r][c] = pose.R(r, c), H[r][c] = pose.H(r, c);
  d["R"] = py::array(py::cast(R));
  d["H"] = py::array(py::cast(H));
  d["t"] = std::array<double, 3>{pose.t[0], pose.t[1], pose.t[2]};
  d["rms_reprojection_px"] = pose.rms_reprojection_px;
  d["max_reprojection_px"] = pose.max_reprojection_px;
  d["width"] = pose.width;
  d["height"] = pose.height;
  d["aspect_recovered"] = pose.aspect_recovered;
  return d;
}

std::vector<glm::dvec2> points_of(const Array& a, const char* what) {
  const py::ssize_t n = rows_of(a, 2, what);
  std::vector<glm::dvec2> p;
  for (py::ssize_t i = 0; i < n; ++i)
    p.emplace_back(a.at(i, 0), a.at(i, 1));
  return p;
}

Camera camera_of(const Array& K) {
  if (K.ndim() != 2 || K.shape(0) != 3 || K.shape(1) != 3)
    throw py::value_error("K: expected a 3 x 3 camera matrix [px]");
  cv::Matx33d k;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      k(r, c) = K.at(r, c);
  return Camera(k);
}

}  // namespace

MaskKind mask_kind(const std::string& name) {
  return choose<MaskKind>("mask", name,
                          {{"prewitt", MaskKind::prewitt},
                           {"sobel", MaskKind::sobel},
                           {"scharr", MaskKind::scharr},
                           {"roberts", MaskKind::roberts},
                           {"gauss", MaskKind::gaussian},
                           {"emboss", MaskKind::emboss}});
}

Border border_kind(const std::string& name) {
  return choose<Border>(
      "border", name,
      {{"suspend", Border::suspend}, {"clamp", Border::clamp}, {"reflect", Border::reflect}, {"fade", Border::fade}});
}

TangibleConfig tangible_options(const std::string& mask, std::optional<int> size, const std::string& border,
                                double sigma) {
  TangibleConfig o;
  o.mask = mask_kind(mask);
  o.size = size                                                        ? *size
           : o.mask == MaskKind::roberts                               ? 2
           : (o.mask == MaskKind::scharr || o.mask == MaskKind::sobel) ? 3
                                                                       : 17;
  o.border = border_kind(border);
  if (!(std::isfinite(sigma) && sigma >= 0.0))
    throw py::value_error("sigma: must be finite and >= 0 [px] (0: size / 6)");
  o.sigma = sigma;
  return o;
}

PlaneMapping mapping_for(int width, int height, std::optional<double> px_per_mm, std::optional<double> workspace_mm) {
  if (px_per_mm && workspace_mm) throw py::value_error("give px_per_mm or workspace_mm, not both");
  if (workspace_mm) return PlaneMapping::fit(width, height, *workspace_mm);
  if (px_per_mm) return PlaneMapping(*px_per_mm, glm::dvec2{(width - 1) / 2.0, (height - 1) / 2.0});
  return PlaneMapping::kim_kwon(width, height);
}

void bind_image(py::module_& m) {
  m.def("tangible_forces", &tangible_forces, py::arg("image"), py::arg("xy"), py::arg("mask") = "prewitt",
        py::arg("size") = py::none(), py::arg("border") = "suspend", py::arg("sigma") = 0.0, py::arg("gray") = "paper",
        py::arg("channels") = "rgb", py::arg("levels") = py::none(),
        (std::string("Tangible-image forces (Vasudevan & Manivannan 2008) at N pixel positions. ") +
         picture_argument_doc +
         " xy N x 2 [px] (x right, y down, integer = pixel centre). "
         "Returns N x 2: the normalised force (1 = a black/white edge) before any gain, fy positive downward; the "
         "same numbers as `tangible_image --probes`. mask prewitt|sobel|scharr|roberts|gauss|emboss, size [px] "
         "(default 17; sobel/scharr 3, roberts 2), border suspend|clamp|reflect|fade, sigma [px] (gauss; 0: size/6), "
         "gray paper|bt601 (luma weights).")
            .c_str());
  m.def(
      "force_map",
      [](const py::object& image, const std::string& mask, std::optional<int> size, const std::string& border,
         double sigma, const std::string& gray, const std::string& channels, std::optional<double> levels) {
        const TangibleConfig o = tangible_options(mask, size, border, sigma);
        const GrayImage g = gray_from(image, gray_weights(gray), channels, levels);
        ForceMap map;
        {
          py::gil_scoped_release release;
          if (o.mask == MaskKind::prewitt)
            map = prewitt_force_map(g, o.size, o.border, o.fade_px);
          else
            map = force_map(TangibleImage(g, o));
        }
        py::array_t<float> fx({map.height, map.width}), fy({map.height, map.width});
        std::copy(map.fx.begin(), map.fx.end(), fx.mutable_data());
        std::copy(map.fy.begin(), map.fy.end(), fy.mutable_data());
        return py::make_tuple(fx, fy);
      },
      py::arg("image"), py::arg("mask") = "prewitt", py::arg("size") = py::none(), py::arg("border") = "suspend",
      py::arg("sigma") = 0.0, py::arg("gray") = "paper", py::arg("channels") = "rgb", py::arg("levels") = py::none(),
      (std::string("The tangible-image force at every pixel centre: (fx, fy), two H x W float32 arrays, normalised "
                   "(1 = a black/white edge), fy positive downward. ") +
       picture_argument_doc + " Other options as tangible_forces().")
          .c_str());
  m.def(
      "tangible_field",
      [](const py::object& image, const std::string& mask, std::optional<int> size, const std::string& border,
         double sigma, double gain, std::optional<double> px_per_mm, std::optional<double> workspace_mm,
         const std::string& gray, const std::string& channels, std::optional<double> levels) {
        const GrayImage g = gray_from(image, gray_weights(gray), channels, levels);
        const PlaneMapping mapping = mapping_for(g.width(), g.height(), px_per_mm, workspace_mm);
        return make_field(
            TangibleImageField(TangibleImage(g, tangible_options(mask, size, border, sigma)), mapping, gain),
            "tangible image " + std::to_string(g.width()) + " x " + std::to_string(g.height()) + " px");
      },
      py::arg("image"), py::arg("mask") = "prewitt", py::arg("size") = py::none(), py::arg("border") = "suspend",
      py::arg("sigma") = 0.0, py::arg("gain") = 1.0, py::arg("px_per_mm") = py::none(),
      py::arg("workspace_mm") = py::none(), py::arg("gray") = "paper", py::arg("channels") = "rgb",
      py::arg("levels") = py::none(),
      (std::string("A tangible-image field in the device's x-y plane: the picture centred on the origin at px_per_mm "
                   "[px/mm] (default 6.4, Kim & Kwon's) or fitted so its longer side spans workspace_mm [mm]; gain [N] "
                   "at a black/white edge. Device frame x right, y up. ") +
       picture_argument_doc + " Other options as tangible_forces().")
          .c_str());

  m.def(
      "estimate_normal",
      [](const Array& corners, const Array& K, std::optional<std::array<double, 2>> size, bool refine) {
        const std::vector<glm::dvec2> c = points_of(corners, "corners");
        std::optional<glm::dvec2> s;
        if (size) s = glm::dvec2{(*size)[0], (*size)[1]};
        return pose_dict(estimate_rectangle_pose(camera_of(K), c, s, PoseConfig{refine}));
      },
      py::arg("corners"), py::arg("K"), py::arg("size") = py::none(), py::arg("refine") = true,
      "Normal of a rectangular face from its 4 image corners (4 x 2 [px], in order around the face) and the 3 x 3 "
      "camera matrix K [px] (Kim & Kwon 2013): the homography H = s K [r1 r2 t], the rotation R and "
      "n = R [0 0 1]^T (camera frame, toward the camera). size (W, H) [mm] if known, else the aspect is recovered. "
      "Returns a dict: normal, R, t, H, rms_reprojection_px, max_reprojection_px, width, height, aspect_recovered.");
  m.def(
      "estimate_plane_normal",
      [](const Array& plane, const Array& pixels, const Array& K) {
        return pose_dict(estimate_plane_pose(camera_of(K), points_of(plane, "plane"), points_of(pixels, "pixels")));
      },
      py::arg("plane"), py::arg("pixels"), py::arg("K"),
      "Pose and normal of a planar face from N >= 4 correspondences: plane points N x 2 (any unit, e.g. [mm]) and "
      "their pixels N x 2 [px]; K the 3 x 3 camera matrix [px]. Returns the same dict as estimate_normal().");
  m.def(
      "normal_field",
      [](int width, int height, const std::vector<std::pair<Array, std::array<double, 3>>>& faces,
         const std::string& mode, double max_force, double speed_threshold, double shading_cell_px,
         std::optional<double> px_per_mm) {
        std::vector<ImageFace> f;
        for (const auto& [polygon, normal] : faces)
          f.push_back({points_of(polygon, "face polygon"), glm3(normal)});
        NormalFieldConfig o;
        o.mode = choose<NormalForceMode>(
            "mode", mode, {{"along_motion", NormalForceMode::along_motion}, {"gradient", NormalForceMode::gradient}});
        o.max_force = max_force;
        o.speed_threshold = speed_threshold;
        o.shading_cell_px = shading_cell_px;
        std::optional<PlaneMapping> mapping;
        if (px_per_mm) mapping = mapping_for(width, height, px_per_mm, std::nullopt);
        return make_field(NormalField(width, height, std::move(f), o, mapping),
                          "normals " + std::to_string(faces.size()) + " faces");
      },
      py::arg("width"), py::arg("height"), py::arg("faces"), py::arg("mode") = "along_motion",
      py::arg("max_force") = kim_kwon_max_force, py::arg("speed_threshold") = 0.005, py::arg("shading_cell_px") = 0.0,
      py::arg("px_per_mm") = py::none(),
      "Normals from a picture as a field (Kim & Kwon 2013): faces a list of (polygon K x 2 [px], unit normal "
      "(camera frame, n_z <= 0)); F = max_force (n . m) m along the HIP's motion m (mode along_motion) or "
      "max_force (n_x, n_y) (gradient). max_force [N], speed_threshold [m/s], shading_cell_px [px] (0: flat faces); "
      "picture centred at px_per_mm [px/mm] (default 6.4).");
}

}  // namespace hapticfield::python
