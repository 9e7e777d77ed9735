// The hapticfield Python module: fields built in Python, evaluated in C++.
#include "field.hpp"
#include "material.hpp"

#include <hapticfield/core.hpp>
#include <hapticfield/texture.hpp>
#include <hapticfield/version.hpp>

#include <pybind11/stl.h>

#include <cmath>
#include <cstdlib>

namespace hapticfield::python {

namespace {

/// Evaluates a field at N probes in order (tick i at time i * period), the
/// GIL released. Stateful fields (filters, local spheres) see the probes as
/// consecutive ticks.
py::array_t<double> forces(Field& self, const Array& positions, const std::optional<Array>& velocities,
                           const std::optional<Array>& normal_forces, const std::optional<Array>& surface_normals,
                           double period, double start_time, const std::optional<py::array>& into) {
  if (!(std::isfinite(period) && period > 0.0)) throw py::value_error("forces: period must be finite and > 0 [s]");
  const py::ssize_t n = rows_of(positions, 3, "positions");
  if (velocities && rows_of(*velocities, 3, "velocities") != n)
    throw py::value_error("velocities: must have as many rows as positions");
  if (normal_forces && rows_of(*normal_forces, 0, "normal_forces") != n)
    throw py::value_error("normal_forces: must have as many entries as positions");
  if (surface_normals && rows_of(*surface_normals, 3, "surface_normals") != n)
    throw py::value_error("surface_normals: must have as many rows as positions");
  py::array_t<double> out;
  if (into) {
    const py::array& o = *into;
    if (!o.dtype().is(py::dtype::of<double>()) || o.ndim() != 2 || o.shape(0) != n || o.shape(1) != 3 ||
        !(o.flags() & py::array::c_style) || !o.writeable())
      throw py::value_error("out: expected a writable C-contiguous float64 array of shape N x 3");
    out = py::reinterpret_borrow<py::array_t<double>>(o);
  } else {
    out = matrix(n, 3);
  }
  ProbeArrays a;
  a.positions = positions.data();
  a.velocities = velocities ? velocities->data() : nullptr;
  a.normal_forces = normal_forces ? normal_forces->data() : nullptr;
  a.surface_normals = surface_normals ? surface_normals->data() : nullptr;
  a.forces = out.mutable_data();
  a.n = n;
  a.period = period;
  a.start_time = start_time;
  std::shared_ptr<AnyField> field = self.impl;
  const FieldUse use(self);
  {
    py::gil_scoped_release release;
    if (self.batch)
      self.batch(*field, a);
    else
      evaluate(*field, a);
  }
  return out;
}

Field sum_of(const std::vector<Field>& fields) {
  if (fields.empty()) throw py::value_error("sum: needs at least one field");
  FieldSum s;
  std::string d;
  std::vector<const Field*> parts;
  for (const Field& f : fields) {
    s.parts.push_back({f.impl});
    d += (d.empty() ? "" : " + ") + f.description;
    parts.push_back(&f);
  }
  return make_field(std::move(s), d, parts);
}

/// F = Fc + parts: the constraint first, the parts see |Fc| and the normal.
template <class C>
Field contact_with(C constraint, const std::vector<Field>& parts, const std::string& name) {
  if (parts.size() == 1) {  // one part: no sum in between
    const std::string d = "contact(" + name + " + " + parts[0].description + ")";
    // A stateless part (its force() is const) is copied in: a copy behaves as the shared part would, and
    // the contact calls it directly instead of through a second type-erased field.
    // The copy is the contact's own: it does not take the part's guard.
    if (const auto* friction = parts[0].impl->target<texture::Friction>())
      return make_field(contact(std::move(constraint), texture::Friction(*friction)), d);
    return make_field(contact(std::move(constraint), SharedField{parts[0].impl}), d, {&parts[0]});
  }
  FieldSum s;
  std::string d = name;
  std::vector<const Field*> shared;
  for (const Field& f : parts) {
    s.parts.push_back({f.impl});
    d += " + " + f.description;
    shared.push_back(&f);
  }
  return make_field(contact(std::move(constraint), std::move(s)), "contact(" + d + ")", shared);
}

/// For the allocation proof's own test: allocates and frees on every
/// evaluation, so a counter that misses it is shown to be broken.
struct AllocatingField {
  static inline void* volatile sink = nullptr;
  glm::dvec3 force(const Probe&) noexcept {
    sink = std::malloc(64);
    std::free(sink);
    return glm::dvec3{0.0};
  }
};

}  // namespace

void bind_core(py::module_& m) {
  py::class_<Field>(m, "Field",
                    "A haptic field evaluated in C++: force [N] from probe state (position [m], velocity [m/s], "
                    "normal force [N], surface normal).")
      .def("forces", &forces, py::arg("positions"), py::arg("velocities") = py::none(),
           py::arg("normal_forces") = py::none(), py::arg("surface_normals") = py::none(),
           py::arg("period") = servo_period, py::arg("start_time") = 0.0, py::arg("out") = py::none(),
           "Forces [N] (N x 3) at N probes: positions N x 3 [m], optional velocities N x 3 [m/s], normal forces "
           "N [N] and surface normals N x 3 (unit). The probes are evaluated in order as consecutive ticks "
           "period [s] apart, so stateful fields (filters, local spheres) advance. out: an N x 3 float64 array to "
           "write into (reused between calls). The GIL is released.")
      .def(
          "force",
          [](Field& self, const V3& position, const V3& velocity, double normal_force, const V3& surface_normal) {
            const FieldUse use(self);
            Probe p;
            p.position = glm3(position);
            p.velocity = glm3(velocity);
            p.normal_force = normal_force;
            p.surface_normal = glm3(surface_normal);
            const glm::dvec3 f = self.impl->force(p);
            auto out = py::array_t<double>(3);
            out.mutable_at(0) = f.x, out.mutable_at(1) = f.y, out.mutable_at(2) = f.z;
            return out;
          },
          py::arg("position"), py::arg("velocity") = V3{0.0, 0.0, 0.0}, py::arg("normal_force") = 0.0,
          py::arg("surface_normal") = V3{0.0, 0.0, 0.0},
          "Force [N] (3 numbers) at one probe: position [m], velocity [m/s], normal force [N].")
      .def(
          "reset",
          [](Field& self) {
            const FieldUse use(self);
            self.impl->reset();
          },
          "Resets the state of stateful parts (filters, samplers).")
      .def("__add__",
           [](const Field& a, const Field& b) {
             return sum_of({a, b});
           })
      .def("__repr__", [](const Field& self) { return "<hapticfield.Field " + self.description + ">"; })
      .def_property_readonly("description", [](const Field& self) { return self.description; });

  m.def("sum", &sum_of, py::arg("fields"), "F = sum of the fields' forces [N]. The parts are shared, not copied.");
  m.def(
      "scale",
      [](const Field& f, double k) {
        if (!std::isfinite(k)) throw py::value_error("scale: factor must be finite");
        return make_field(scale(SharedField{f.impl}, k), "scale(" + f.description + ")", {&f});
      },
      py::arg("field"), py::arg("factor"), "F = factor x field [N].");
  m.def(
      "clamp",
      [](const Field& f, double limit) {
        return make_field(clamp(SharedField{f.impl}, limit), "clamp(" + f.description + ")", {&f});
      },
      py::arg("field"), py::arg("limit"),
      "|F| limited to limit [N] keeping the direction; a non-finite force becomes zero.");
  m.def(
      "_allocating_field", [] { return make_field(AllocatingField{}, "allocating (for tests)"); },
      "For tests only: a zero field that allocates and frees 64 bytes on every evaluation (the allocation "
      "proof in python/tests/test_alloc.py shows that it catches such a field).");
  m.def(
      "zero", [] { return make_field(ZeroField{}, "zero"); }, "A field that is always zero.");

  m.def(
      "plane_contact",
      [](const std::vector<Field>& parts, const V3& point, const V3& normal, double stiffness, double damping) {
        return contact_with(PlaneConstraint(PlaneConstraintConfig{glm3(point), glm3(normal), stiffness, damping}),
                            parts, "plane");
      },
      py::arg("parts") = std::vector<Field>{}, py::arg("point") = V3{0.0, 0.0, 0.0},
      py::arg("normal") = V3{0.0, 0.0, 1.0}, py::arg("stiffness") = 1500.0, py::arg("damping") = 0.0,
      "F = Fc + parts: a penalty plane through point [m] with unit normal (toward the user), stiffness [N/m] and "
      "damping [N s/m] gives Fc; while touching, the parts see |Fc| [N] and the plane's normal of the same tick.");
  m.def(
      "sphere_contact",
      [](const std::vector<Field>& parts, const V3& centre, double radius, double stiffness, double damping) {
        return contact_with(SphereConstraint(SphereConstraintConfig{glm3(centre), radius, stiffness, damping}), parts,
                            "sphere");
      },
      py::arg("parts") = std::vector<Field>{}, py::arg("centre") = V3{0.0, 0.0, 0.0}, py::arg("radius") = 0.02,
      py::arg("stiffness") = 1500.0, py::arg("damping") = 0.0,
      "F = Fc + parts on a solid penalty sphere: centre [m], radius [m], stiffness [N/m], damping [N s/m].");
}

#ifdef HAPTICFIELD_PYTHON_HJIF
void bind_hjif(py::module_& m);  // hjif_bindings.cpp: .hjif haptic media (nlohmann-json)
#endif

}  // namespace hapticfield::python

PYBIND11_MODULE(hapticfield, m) {
  namespace hp = hapticfield::python;
  namespace py = pybind11;
  m.doc() =
      "hapticfield: haptic fields (tangible images, stochastic textures, friction, HaTT models, normals from a "
      "picture, contact composition, surfaces: height fields, meshes and pictures as reliefs felt through a proxy) "
      "built in Python and evaluated in C++, and a servo loop on a simulated or real arm. Units: [m], [m/s], [N], "
      "[s], [px].";
  m.attr("__version__") = std::to_string(HAPTICFIELD_VERSION_MAJOR) + "." + std::to_string(HAPTICFIELD_VERSION_MINOR) +
                          "." + std::to_string(HAPTICFIELD_VERSION_PATCH);
  static py::exception<hapticfield::Error> error(m, "Error", PyExc_RuntimeError);
  // A FileError is also an OSError, so `except OSError` catches a missing or unreadable file.
  static py::exception<hapticfield::FileError> file_error(m, "FileError",
                                                          py::make_tuple(error, py::handle(PyExc_OSError)));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const hapticfield::FileError& e) {
      file_error(e.what());
    } catch (const hapticfield::Error& e) {
      error(e.what());
    }
  });
  hp::bind_core(m);
  hp::bind_image(m);
  hp::bind_texture(m);
  hp::bind_servo(m);
  hp::bind_video(m);
  hp::bind_budget(m);
  hp::bind_material(m);  // before surface_contact, which takes a Material
  hp::bind_surface(m);
#ifdef HAPTICFIELD_PYTHON_HJIF
  hp::bind_hjif(m);
#endif
  hp::bind_relief_map(m);
  hp::bind_mujoco(m);
}
