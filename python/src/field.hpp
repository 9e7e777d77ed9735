#pragma once
/// @file field.hpp
/// The Python-side field handle: a shared, type-erased HapticField, and the
/// helpers that turn numpy arrays into probes and back.

#include <hapticfield/core.hpp>
#include <hapticfield/kernels.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hapticfield::python {

namespace py = pybind11;

/// A field built in Python. Fields made of fields share their parts.
struct Field {
  std::shared_ptr<AnyField> impl;
  std::string description;
};

/// A part held by a composed field: forwards to the shared field.
struct SharedField {
  std::shared_ptr<AnyField> field;
  glm::dvec3 force(const Probe& probe) noexcept { return field->force(probe); }
  void reset() noexcept { field->reset(); }
};

/// F = sum of the parts; the vector is filled at construction only.
struct FieldSum {
  std::vector<SharedField> parts;
  glm::dvec3 force(const Probe& probe) noexcept {
    glm::dvec3 f{0.0};
    for (auto& p : parts)
      f += p.force(probe);
    return f;
  }
  void reset() noexcept {
    for (auto& p : parts)
      p.reset();
  }
};

template <HapticField F>
Field make_field(F&& f, std::string description) {
  return Field{std::make_shared<AnyField>(std::forward<F>(f)), std::move(description)};
}

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// Checks an N x cols array (cols = 0: a 1-D array of N) and returns N.
inline py::ssize_t rows_of(const Array& a, py::ssize_t cols, const char* what) {
  if (cols == 0) {
    if (a.ndim() != 1) throw py::value_error(std::string(what) + ": expected a 1-D array");
    return a.shape(0);
  }
  if (a.ndim() != 2 || a.shape(1) != cols)
    throw py::value_error(
        std::string(what) + ": expected an N x " + std::to_string(cols) + " array, got shape " +
        std::string(py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()))))));
  return a.shape(0);
}

/// The option called `name` among `options`; a ValueError naming them all otherwise.
template <class E>
inline E choose(const std::string& what, const std::string& name, const std::map<std::string, E>& options) {
  const auto it = options.find(name);
  if (it != options.end()) return it->second;
  std::string names;
  for (const auto& [k, v] : options)
    names += (names.empty() ? "" : ", ") + k;
  throw py::value_error(what + ": unknown '" + name + "' (choose " + names + ")");
}

/// Mask, border and tangible options as tangible_forces() takes them (image.cpp).
MaskKind mask_kind(const std::string& name);
Border border_kind(const std::string& name);
TangibleConfig tangible_options(const std::string& mask, std::optional<int> size, const std::string& border,
                                double sigma);
/// The picture centred on the origin at px_per_mm [px/mm] (default Kim & Kwon's 6.4) or fitted so that its
/// longer side spans workspace_mm [mm].
PlaneMapping mapping_for(int width, int height, std::optional<double> px_per_mm, std::optional<double> workspace_mm);

using V3 = std::array<double, 3>;
inline glm::dvec3 glm3(const V3& a) {
  return {a[0], a[1], a[2]};
}

/// An N x 3 (or N x cols) result array.
inline py::array_t<double> matrix(py::ssize_t n, py::ssize_t cols) {
  return py::array_t<double>({n, cols});
}

void bind_core(py::module_& m);
void bind_image(py::module_& m);
void bind_texture(py::module_& m);
void bind_servo(py::module_& m);
void bind_video(py::module_& m);

}  // namespace hapticfield::python
