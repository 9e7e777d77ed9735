// A material map held by Python (material(), load_haptic_material()), given to surface_contact(material=...).
#pragma once

#include <memory>
#include <string>

#include <pybind11/pybind11.h>

#include <hapticfield/material/material_map.hpp>

namespace hapticfield::python {

struct Material {
  std::shared_ptr<const material::MaterialMap> map;
  std::string description;
};

void bind_material(pybind11::module_& m);  // material_bindings.cpp

}  // namespace hapticfield::python
