// A MuJoCo scene from Python (physics/mujoco_bridge.hpp), when the module is built with MuJoCo: a Field that
// run_servo feels, the simulator stepped in lockstep with the loop's virtual clock or in real time on the wall
// clock, on a thread of its own either way (never on the loop's).
#include "field.hpp"

#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>

#if HAPTICFIELD_PYTHON_MUJOCO
#include <hapticfield/physics/mujoco_bridge.hpp>
#endif

namespace hapticfield::python {

#if HAPTICFIELD_PYTHON_MUJOCO

namespace {

/// The servo's side of a scene: the bridge's field, the bridge kept alive with it.
struct SceneField {
  std::shared_ptr<MujocoBridge> bridge;
  LocalModelField field;
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept { return field.force(probe); }
  void reset() noexcept { field.reset(); }
};

/// A MuJoCo scene as Python holds it: a Field (run_servo, forces, sums) and the bridge to step and inspect.
struct MujocoScene : Field {
  std::shared_ptr<MujocoBridge> bridge;
};

V3 v3(const glm::dvec3& v) {
  return V3{v.x, v.y, v.z};
}

MujocoScene mujoco_scene(const py::object& path, double rate, const std::string& mode, double stiffness,
                         std::optional<double> damping, double static_friction, double dynamic_friction,
                         double coupling_stiffness, std::optional<double> coupling_damping,
                         const std::string& tool_body, const V3& scene_origin, double detect_distance,
                         double stall_time, double fade_time) {
  MujocoBridgeConfig c;
  c.mode = choose<CouplingMode>(
      "mode", mode, {{"local_model", CouplingMode::local_model}, {"virtual_coupling", CouplingMode::virtual_coupling}});
  c.rate = rate;
  c.plane_stiffness = stiffness;
  // the least damping Adams & Hannaford allow, B = T K / 2, unless given
  const double period = std::isfinite(rate) && rate > 0.0 ? 1.0 / rate : 0.0;
  c.plane_damping = damping.value_or(period * stiffness / 2.0);
  c.plane_static_friction = static_friction;
  c.plane_dynamic_friction = dynamic_friction;
  c.coupling.stiffness = coupling_stiffness;
  c.coupling.damping = coupling_damping.value_or(std::fmax(2.0, period * coupling_stiffness / 2.0));
  c.tool_body = tool_body;
  c.scene_origin = glm3(scene_origin);
  c.detect_distance = detect_distance;
  c.stall_time = stall_time;
  c.fade_time = fade_time;
  const std::string p = py::str(py::module_::import("os").attr("fspath")(path));
  std::shared_ptr<MujocoBridge> bridge;
  {
    py::gil_scoped_release release;
    bridge = std::make_shared<MujocoBridge>(p, c);
  }
  MujocoScene scene;
  static_cast<Field&>(scene) = make_field(SceneField{bridge, bridge->field()},
                                          "MuJoCo scene " + p + " at " + std::to_string(std::lround(rate)) + " Hz");
  scene.bridge = bridge;
  const std::weak_ptr<MujocoBridge> weak = bridge;
  // run_servo on the virtual clock: the simulator steps in lockstep with the loop's time, on its own thread
  scene.guards.front()->lockstep = [weak](bool on) {
    if (const auto b = weak.lock()) {
      b->stop();
      if (on) b->start(true);
    }
  };
  // run_servo on the wall clock: at its rate in real time, on its own thread
  scene.guards.front()->real_time = [weak](bool on) {
    if (const auto b = weak.lock()) {
      b->stop();
      if (on) b->start(false);
    }
  };
  return scene;
}

const char* fault_name(SimulatorFault f) {
  switch (f) {
    case SimulatorFault::non_finite:
      return "non_finite";
    case SimulatorFault::mujoco_error:
      return "mujoco_error";
    case SimulatorFault::none:
      break;
  }
  return "none";
}

}  // namespace

void bind_mujoco(py::module_& m) {
  m.attr("has_mujoco") = true;
  py::class_<MujocoScene, Field>(
      m, "MujocoScene",
      "A MuJoCo scene felt through the servo loop (mujoco_scene()): a Field, and the simulator behind it. "
      "The scene's inspection (body, joint_position, step, ...) waits for no run: it raises RuntimeError while a "
      "run_servo loop or a forces() call uses the field.")
      .def(
          "step",
          [](MujocoScene& s, int n) {
            if (n < 0) throw py::value_error("step: n must be >= 0");
            const FieldUse use(s);
            bool ok = true;
            py::gil_scoped_release release;
            for (int i = 0; i < n; ++i)
              ok = s.bridge->step_once() && ok;
            return ok;
          },
          py::arg("n") = 1,
          "Takes n simulator steps on the calling thread, with the newest handle sample (for forces() "
          "evaluations between steps; run_servo steps the scene by itself). False when the simulator is faulted.")
      .def(
          "body",
          [](MujocoScene& s, const std::string& name) {
            const FieldUse use(s);
            const BodyState b = s.bridge->body(name);
            py::dict d;
            d["position"] = v3(b.position);
            d["velocity"] = v3(b.velocity);
            d["mass"] = b.mass;
            return d;
          },
          py::arg("name"),
          "A body's centre of mass position [m], its velocity [m/s] (device frame) and mass [kg] as a dict. "
          "ValueError for an unknown body.")
      .def(
          "joint_position",
          [](MujocoScene& s, const std::string& name) {
            const FieldUse use(s);
            return s.bridge->joint_position(name);
          },
          py::arg("name"),
          "A joint's position (a hinge's angle [rad], a slide's [m]). ValueError for an unknown joint.")
      .def_property_readonly(
          "simulated_time",
          [](MujocoScene& s) {
            const FieldUse use(s);
            return s.bridge->simulated_time();
          },
          "Simulated time since the scene started [s].")
      .def_property_readonly(
          "scene_energy",
          [](MujocoScene& s) {
            const FieldUse use(s);
            return s.bridge->scene_energy();
          },
          "Kinetic and gravity's potential energy of the moving bodies, and the joint springs' [J].")
      .def_property_readonly(
          "tool_radius", [](MujocoScene& s) { return s.bridge->tool_radius(); }, "The tool's sphere radius [m].")
      .def_property_readonly(
          "rate", [](MujocoScene& s) { return 1.0 / s.bridge->period(); }, "Simulator steps per second [Hz].")
      .def_property_readonly(
          "events",
          [](MujocoScene& s) {
            const MujocoEvents e = s.bridge->events();
            const LocalModelLink& link = s.bridge->link();
            py::dict d;
            d["steps"] = e.steps;
            d["overruns"] = e.overruns;
            d["non_finite"] = e.non_finite;
            d["mujoco_errors"] = e.mujoco_errors;
            d["warnings"] = e.warnings;
            d["scene_changes"] = e.scene_changes;
            d["stalls"] = link.stalls.load();
            d["faults_seen"] = link.faults_seen.load();
            d["zeroed_ticks"] = link.zeroed_ticks.load();
            return d;
          },
          "Counts: simulator steps, overruns (real time only), non-finite states, MuJoCo errors and warnings, "
          "scene changes; and the loop's side: stalls, faulty models seen, ticks zeroed for a stall or a fault.")
      .def_property_readonly(
          "fault", [](MujocoScene& s) { return std::string(fault_name(s.bridge->fault())); },
          "none, non_finite or mujoco_error: why the simulator stopped (the field gives zero force).")
      .def_property_readonly(
          "fault_message", [](MujocoScene& s) { return s.bridge->fault_message(); }, "One line saying why, or ''.")
      .def(
          "clear_fault",
          [](MujocoScene& s) {
            const FieldUse use(s);
            s.bridge->clear_fault();
          },
          "Starts the scene again from its initial state after a fault; the force fades back in.")
      .def(
          "load",
          [](MujocoScene& s, const py::object& path) {
            const std::string p = py::str(py::module_::import("os").attr("fspath")(path));
            const FieldUse use(s);
            py::gil_scoped_release release;
            s.bridge->load(p);
          },
          py::arg("path"),
          "Changes the scene (MJCF): the new one fades in. FileError / Error as mujoco_scene; the old scene stays "
          "on failure.");
  m.def("mujoco_scene", &mujoco_scene, py::arg("path"), py::arg("rate") = 500.0, py::arg("mode") = "local_model",
        py::arg("stiffness") = 1000.0, py::arg("damping") = py::none(), py::arg("static_friction") = 0.0,
        py::arg("dynamic_friction") = 0.0, py::arg("coupling_stiffness") = 200.0,
        py::arg("coupling_damping") = py::none(), py::arg("tool_body") = "tool",
        py::arg("scene_origin") = V3{0.0, 0.0, 0.0}, py::arg("detect_distance") = 0.01, py::arg("stall_time") = 0.05,
        py::arg("fade_time") = 0.2,
        "A MuJoCo scene (an MJCF file with a tool: a free body named tool_body with a sphere geom, the tool's "
        "radius) felt as a field (a MujocoScene): the simulator steps at rate [Hz] (10..10000) on a thread of its "
        "own, never on the servo loop's. In run_servo on the virtual clock (the default for the simulated arm) it "
        "steps in lockstep with the loop's time (step j at j / rate, the loop waiting for it), so a run is the same "
        "on any machine; on the wall clock it steps in real time. mode: local_model (default: the touched surfaces "
        "as planes rendered at the loop's rate,  stiffness [N/m] and damping [N s/m] on them, "
        "Coulomb friction 0 <= dynamic_friction <= static_friction on each: a proxy on the plane sticks in the static "
        "cone, slides in the dynamic one) or virtual_coupling (a "
        "spring-damper coupling_stiffness [N/m], coupling_damping [N s/m] to the simulated tool). A damping left "
        "None is the least Adams & Hannaford's bound allows, T K / 2 at T = 1 / rate (the coupling's at least 2 N "
        "s/m); a smaller one is a ValueError. Device frame (y up) to MuJoCo's z up: (x, y, z) -> (x, -z, y), plus "
        "scene_origin [m] (scene frame). detect_distance [m]: contacts published within it; stall_time [s]: no "
        "step for this long gives zero force; fade_time [s]: the force fades in after a change or a fault. A "
        "missing file or MJCF MuJoCo refuses raises FileError, a scene without a usable tool Error.");
}

#else  // no MuJoCo in this build

void bind_mujoco(py::module_& m) {
  m.attr("has_mujoco") = false;
  m.def(
      "mujoco_scene",
      [](const py::args&, const py::kwargs&) -> py::object {
        throw hapticfield::Error(
            "mujoco_scene: this build of the module has no MuJoCo (libmujoco-dev was not found when it was built; "
            "scripts/deps.sh installs it)");
      },
      "Unavailable: this build of the module has no MuJoCo (raises hapticfield.Error).");
}

#endif

}  // namespace hapticfield::python
