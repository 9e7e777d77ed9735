// Materials over uv for Python: material() from numbers and numpy pictures (material/material_map.hpp), and the
// glTF extension MPEG_haptic_material read and written (io/gltf_haptic_material.hpp, where the library has the
// mesh readers and the .hjif reader).
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "field.hpp"
#include "material.hpp"

#include <hapticfield/material/uv_relief.hpp>

#if HAPTICFIELD_PYTHON_GLTF_MATERIAL
#include <hapticfield/io/gltf_haptic_material.hpp>
#endif

namespace hapticfield::python {

namespace {

using Picture = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Ids = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
using PropertyArg = std::variant<double, Picture>;
using IdArg = std::variant<std::int64_t, Ids>;

material::UvLayout layout_of(bool clamp) {
  return material::UvLayout{clamp ? material::UvWrap::clamp : material::UvWrap::repeat};
}

material::PropertyMap property_of(const PropertyArg& arg, const char* what, bool clamp) {
  if (const double* c = std::get_if<double>(&arg)) {
    if (!std::isfinite(*c)) throw py::value_error(std::string(what) + ": must be finite");
    return material::PropertyMap(*c);
  }
  const Picture& p = std::get<Picture>(arg);
  if (p.ndim() != 2 || p.shape(0) < 1 || p.shape(1) < 1)
    throw py::value_error(std::string(what) + ": expected a number or an H x W array (row 0 the picture's top, v = 1)");
  std::vector<float> values(static_cast<std::size_t>(p.size()));
  for (py::ssize_t i = 0; i < p.size(); ++i) {
    const double v = p.data()[i];
    if (!std::isfinite(v))
      throw py::value_error(std::string(what) + ": value " + std::to_string(i) + " is not finite (NaN or infinite)");
    values[static_cast<std::size_t>(i)] = static_cast<float>(v);
  }
  return material::PropertyMap(static_cast<int>(p.shape(1)), static_cast<int>(p.shape(0)), std::move(values),
                               layout_of(clamp));
}

material::IndexMap ids_of(const IdArg& arg, bool clamp) {
  if (const std::int64_t* c = std::get_if<std::int64_t>(&arg)) {
    if (*c < 0 || *c > 0xFFFFFFFDll) throw py::value_error("vibration: an id must be in [0, 4294967293]");
    return material::IndexMap(static_cast<std::uint32_t>(*c));
  }
  const Ids& p = std::get<Ids>(arg);
  if (p.ndim() != 2 || p.shape(0) < 1 || p.shape(1) < 1)
    throw py::value_error("vibration: expected an id or an H x W integer array");
  std::vector<std::uint32_t> ids(static_cast<std::size_t>(p.size()));
  for (py::ssize_t i = 0; i < p.size(); ++i) {
    const std::int64_t v = p.data()[i];
    if (v < 0 || v > 0xFFFFFFFDll) throw py::value_error("vibration: id " + std::to_string(i) + " is out of range");
    ids[static_cast<std::size_t>(i)] = static_cast<std::uint32_t>(v);
  }
  return material::IndexMap(static_cast<int>(p.shape(1)), static_cast<int>(p.shape(0)), std::move(ids),
                            layout_of(clamp));
}

Material make_material(const PropertyArg& stiffness, const PropertyArg& damping, const PropertyArg& static_friction,
                       const std::optional<PropertyArg>& dynamic_friction, const PropertyArg& texture_gain,
                       const IdArg& vibration, bool clamp) {
  material::MaterialMaps maps;
  maps.stiffness = property_of(stiffness, "stiffness", clamp);
  maps.damping = property_of(damping, "damping", clamp);
  maps.static_friction = property_of(static_friction, "static_friction", clamp);
  maps.dynamic_friction = property_of(dynamic_friction.value_or(static_friction), "dynamic_friction", clamp);
  maps.texture_gain = property_of(texture_gain, "texture_gain", clamp);
  maps.vibration = ids_of(vibration, clamp);
  try {
    return Material{std::make_shared<const material::MaterialMap>(std::move(maps)), "material"};
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}

py::dict sample(const Material& m, double u, double v) {
  const material::MaterialSample s = m.map->sample({u, v});
  py::dict d;
  d["stiffness"] = s.stiffness;
  d["damping"] = s.damping;
  d["static_friction"] = s.static_friction;
  d["dynamic_friction"] = s.dynamic_friction;
  d["texture_gain"] = s.texture_gain;
  d["vibration"] = s.vibration;
  return d;
}

Field uv_relief(const PropertyArg& heights, double stiffness, double metres_per_uv, bool clamp) {
  material::PropertyMap h = property_of(heights, "heights", clamp);
  try {
    return make_field(material::UvRelief(std::move(h), stiffness, metres_per_uv), "uv relief");
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}

#if HAPTICFIELD_PYTHON_GLTF_MATERIAL
std::string path_text(const py::object& o) {
  return py::str(py::module_::import("os").attr("fspath")(o));
}

Material load_haptic_material(const py::object& path, std::size_t index) {
  const std::string p = path_text(path);
  io::GltfHapticModel model;
  io::HapticMaterialLayers layers;
  {
    py::gil_scoped_release release;
    model = io::load_gltf_haptic(p);
    if (index >= model.haptics.materials.size())
      throw py::value_error("load_haptic_material: '" + p + "' has " + std::to_string(model.haptics.materials.size()) +
                            " haptic materials, no " + std::to_string(index));
    layers = io::haptic_material_layers(model.haptics.materials[index]);
  }
  const std::string name = model.haptics.materials[index].name;
  return Material{std::make_shared<const material::MaterialMap>(std::move(layers.maps)),
                  "haptic material '" + name + "' of " + p};
}

/// An 8- or 16-bit one-channel picture from an H x W array of levels.
cv::Mat picture_of(const py::array& a, const char* what) {
  const auto levels = py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!levels || levels.ndim() != 2 || levels.shape(0) < 1 || levels.shape(1) < 1)
    throw py::value_error(std::string(what) + ": expected an H x W array of 8- or 16-bit levels");
  const bool wide = py::dtype::of<std::uint16_t>().is(a.dtype()) || a.dtype().itemsize() > 1;
  cv::Mat out(static_cast<int>(levels.shape(0)), static_cast<int>(levels.shape(1)), wide ? CV_16UC1 : CV_8UC1);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const std::uint16_t v = levels.at(y, x);
      if (wide)
        out.at<std::uint16_t>(y, x) = v;
      else
        out.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(v);
    }
  return out;
}

using Ranged = std::tuple<py::array, double, double>;

io::HapticPicture ranged(const std::optional<Ranged>& r, const char* what) {
  if (!r) return {};
  return io::HapticPicture{picture_of(std::get<0>(*r), what), std::get<1>(*r), std::get<2>(*r)};
}

void save_haptic_material(const py::object& base, const py::object& out, const std::optional<Ranged>& stiffness,
                          const std::optional<Ranged>& friction,
                          const std::optional<std::tuple<py::array, double>>& texture,
                          const std::optional<py::array>& vibration, const std::string& name) {
  io::HapticMaterialPictures p;
  p.name = name;
  p.stiffness = ranged(stiffness, "stiffness");
  p.friction = ranged(friction, "friction");
  if (texture) p.texture = io::HapticPicture{picture_of(std::get<0>(*texture), "texture"), 0.0, std::get<1>(*texture)};
  if (vibration) p.vibration_ids = picture_of(*vibration, "vibration");
  if (p.stiffness.picture.empty() && p.friction.picture.empty() && p.texture.picture.empty() && p.vibration_ids.empty())
    throw py::value_error("save_haptic_material: give at least one of stiffness, friction, texture, vibration");
  const std::string from = path_text(base);
  const std::string to = path_text(out);
  try {
    py::gil_scoped_release release;
    io::save_gltf_with_haptic_material(from, p, to);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}
#endif

}  // namespace

void bind_material(py::module_& m) {
  py::class_<Material>(
      m, "Material",
      "A material over a surface's uv (material(), load_haptic_material()): stiffness [N/m], damping "
      "[N s/m], static and dynamic friction, texture gain and a vibration id, each a constant or a "
      "picture read bilinearly (ids at the nearest texel). surface_contact(..., material=...) reads it "
      "at the touched uv every tick.")
      .def("sample", &sample, py::arg("u"), py::arg("v"),
           "The material at uv (u right, v up) as a dict: stiffness, damping, static_friction, dynamic_friction, "
           "texture_gain, vibration.")
      .def_property_readonly("description", [](const Material& self) { return self.description; })
      .def("__repr__", [](const Material& self) { return "<hapticfield.Material " + self.description + ">"; });
  m.def("material", &make_material, py::arg("stiffness") = 1500.0, py::arg("damping") = 0.0,
        py::arg("static_friction") = 0.0, py::arg("dynamic_friction") = py::none(), py::arg("texture_gain") = 1.0,
        py::arg("vibration") = 0, py::arg("clamp") = false,
        "A Material: each property a number or an H x W array over uv [0, 1]^2 (row 0 the picture's top, v = 1; "
        "bilinear between texel centres), repeated outside (clamp=True: edges extended). stiffness [N/m] > 0, "
        "damping [N s/m], friction and texture_gain >= 0 everywhere (ValueError otherwise); dynamic_friction "
        "defaults to static_friction; vibration: an id or an H x W integer array of ids for the vibration tap.");
  m.def("uv_relief", &uv_relief, py::arg("heights"), py::arg("stiffness") = 1500.0, py::arg("metres_per_uv") = 1.0,
        py::arg("clamp") = false,
        "A relief of small height over a surface's uv, felt by haptic bump mapping (Ho, Basdogan & Srinivasan "
        "1999): heights [m] >= 0, a number or an H x W array over uv as material(); lay it with on_surface() as a "
        "part of surface_contact() of the same stiffness [N/m]. While touching it adds k h(uv) along the normal and "
        "-(|Fc| + k h) grad h along the surface, grad h in m per m with metres_per_uv [m] the surface's size of "
        "one uv unit. ValueError for a negative height or a stiffness or scale not finite and > 0.");
#if HAPTICFIELD_PYTHON_GLTF_MATERIAL
  m.def("load_haptic_material", &load_haptic_material, py::arg("path"), py::arg("index") = 0,
        "The Material of haptic material `index` of a glTF file's MPEG_haptic_material extension (stiffness, "
        "friction and vibration ids; docs/materials.md lists every field). FileError for a file the reader "
        "refuses, ValueError for an index past the last.");
  m.def("save_haptic_material", &save_haptic_material, py::arg("base"), py::arg("out"),
        py::arg("stiffness") = py::none(), py::arg("friction") = py::none(), py::arg("texture") = py::none(),
        py::arg("vibration") = py::none(), py::arg("name") = "",
        "Writes the glTF `base` again as `out` (.gltf self-contained, or .glb) with an MPEG_haptic_material for "
        "every mesh: stiffness and friction as (levels, low, high) with levels an H x W uint8 or uint16 array "
        "(black = low, white = high), texture as (levels, force [N] at a black/white edge), vibration an id array. "
        "The extension is in extensionsUsed only: any glTF viewer still opens the model.");
#endif
}

}  // namespace hapticfield::python
