// hapticfield.relief_map(image, ...): the heights a picture relief is made of (io/height_map.hpp) and their
// normals, as arrays: what an off-line corpus job (hapticfield.batch) writes to disk for every picture.
#include "field.hpp"

#include <hapticfield/io/height_map.hpp>

#include <pybind11/stl.h>

#include <glm/geometric.hpp>

#include <cstddef>
#include <optional>
#include <string>

namespace hapticfield::python {

namespace {

/// (heights, normals): H x W heights [m] and H x W x 3 unit normals, both in picture order (row 0 is the
/// picture's top row). The normal at a sample is that of HeightFieldShape's force shading: central differences
/// of the heights, one-sided at the border, in the relief's frame (x right, y up the picture, z toward the user).
py::tuple relief_map(const py::object& image, double pixel_size, double mm_per_level, double blur, bool dark_is_high,
                     const std::string& gray, const std::string& channels, std::optional<double> levels) {
  io::PictureHeightConfig c;
  c.pixel_size = pixel_size;
  c.mm_per_level = mm_per_level;
  c.blur_sigma = blur;
  c.dark_is_high = dark_is_high;
  c.weights = gray_weights(gray);
  const bool from_file = py::isinstance<py::str>(image) || py::hasattr(image, "__fspath__");
  io::HeightGrid grid;
  if (from_file) {
    const std::string path = py::str(py::module_::import("os").attr("fspath")(image));
    py::gil_scoped_release release;
    grid = io::load_height_picture(path, c);
  } else {
    const GrayImage g = gray_from(image, c.weights, channels, levels);
    py::gil_scoped_release release;
    grid = io::height_grid_from_gray(g, c);
  }
  const py::ssize_t w = grid.width, h = grid.height;
  py::array_t<double> heights({h, w});
  py::array_t<double> normals({h, w, py::ssize_t{3}});
  double* z = heights.mutable_data();
  double* n = normals.mutable_data();
  {
    py::gil_scoped_release release;
    for (int j = 0; j < grid.height; ++j) {
      const std::size_t row = static_cast<std::size_t>(grid.height - 1 - j) * static_cast<std::size_t>(w);
      const int j0 = j > 0 ? j - 1 : j, j1 = j + 1 < grid.height ? j + 1 : j;
      for (int i = 0; i < grid.width; ++i) {
        const int i0 = i > 0 ? i - 1 : i, i1 = i + 1 < grid.width ? i + 1 : i;
        const double hx = (grid.at(i1, j) - grid.at(i0, j)) / ((i1 - i0) * grid.spacing_x);  // slope along x [-]
        const double hy = (grid.at(i, j1) - grid.at(i, j0)) / ((j1 - j0) * grid.spacing_y);  // slope along y [-]
        const glm::dvec3 normal = glm::normalize(glm::dvec3{-hx, -hy, 1.0});
        z[row + static_cast<std::size_t>(i)] = grid.at(i, j);
        double* out = n + 3 * (row + static_cast<std::size_t>(i));
        out[0] = normal.x, out[1] = normal.y, out[2] = normal.z;
      }
    }
  }
  return py::make_tuple(heights, normals);
}

}  // namespace

void bind_relief_map(py::module_& m) {
  m.def("relief_map", &relief_map, py::arg("image"), py::arg("pixel_size") = 1e-4, py::arg("mm_per_level") = 0.01,
        py::arg("blur") = 0.0, py::arg("dark_is_high") = false, py::arg("gray") = "paper", py::arg("channels") = "rgb",
        py::arg("levels") = py::none(),
        (std::string("The relief of a picture as arrays, as height_field_from_picture() builds it: (heights, "
                     "normals), H x W heights [m] (gray level x mm_per_level [mm], dark_is_high: 255 - level, after "
                     "a Gaussian blur of blur [px]) and H x W x 3 unit normals (central differences over pixel_size "
                     "[m], one-sided at the border; x right, y up the picture, z toward the user), row 0 the "
                     "picture's top row. A missing or undecodable file, or one under 2 x 2 px, raises FileError.\n\n") +
         picture_argument_doc)
            .c_str());
}

}  // namespace hapticfield::python
