// feel_mujoco: a MuJoCo scene felt on the simulated arm, off-line on a
// virtual clock. The scripted hand pushes the arm's handle along a line; the
// servo loop's field (physics/local_model.hpp) renders what the scene's
// tool touches at 1 kHz; the simulator (physics/mujoco_bridge.hpp) steps at
// its own rate in between and takes the hand's force back. Prints what
// happened; writes a trace and a 3D picture of the scene at the end.
//
//   feel_mujoco SCENE.xml [--seconds S] [--rate HZ] [--mode local|coupling]
//               [--stiffness K] [--damping B] [--to X,Y,Z] [--speed V]
//               [--trace OUT.csv] [--snapshot OUT.png] [--view YAW,PITCH] [--distance MM]
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/cli.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/physics/mujoco_bridge.hpp"
#include "view/scene3d.hpp"
#include "view/view_options.hpp"

using namespace hapticfield;

namespace {

constexpr const char* usage_text =
    "usage: feel_mujoco SCENE.xml [options]\n"
    "Feels a MuJoCo scene (MJCF) on the simulated arm, off-line on a virtual clock: the\n"
    "scripted hand pushes the handle from the arm's home along a line; the servo loop renders\n"
    "what the scene's tool touches at 1 kHz and the simulator steps at its own rate, taking\n"
    "the hand's force back. The scene needs a body 'tool' with a free joint and a sphere geom;\n"
    "scene frame z up, the device's origin at the scene's (examples: share/hapticfield/data/\n"
    "mujoco_table.xml, mujoco_door.xml, mujoco_ball.xml).\n"
    "  --seconds S           simulated time [s], in (0, 600] (default 3)\n"
    "  --rate HZ             simulator rate [Hz], in [10, 1000] (default 500)\n"
    "  --mode M              local (default: contact planes rendered at 1 kHz) or coupling\n"
    "                        (a spring-damper to the simulated tool)\n"
    "  --stiffness K         the planes' or the coupling's stiffness [N/m], in (0, 1e5]\n"
    "                        (default 1000 local, 200 coupling)\n"
    "  --damping B           its damping [N s/m] (default T K / 2 at the simulator period T,\n"
    "                        the least that keeps it passive; less is refused)\n"
    "  --to X,Y,Z            where the hand goes, device frame (x right, y up, z toward the\n"
    "                        user) [m], each within [-0.1, 0.1] (default -0.07,-0.02,0.01:\n"
    "                        mujoco_table.xml's box pushed along the table)\n"
    "  --speed V             the hand's speed [m/s], in (0, 1] (default 0.05)\n"
    "  --trace OUT.csv       t, HIP [m], force [N], planes touched, per servo tick\n"
    "  --snapshot OUT.png    the 3D view of the scene at the end: its boxes and spheres, the\n"
    "                        tool's ball at the HIP and the force (800 x 600 px, no display needed)\n"
    "  --view YAW,PITCH      the snapshot's camera orbit [degrees] (default 25,30)\n"
    "  --distance MM         the snapshot camera's distance [mm], in [1, 1e5] (default 300)\n"
    "  -h, --help            this text\n"
    "Exit status: 0 done, 1 bad input or a simulator fault, 2 usage error.\n";

struct Arguments {
  std::string scene;
  double seconds{3.0};
  double rate{500.0};
  CouplingMode mode{CouplingMode::local_model};
  double stiffness{0.0};  ///< 0: the mode's default
  double damping{-1.0};   ///< < 0: T K / 2
  glm::dvec3 to{-0.07, -0.02, 0.01};
  double speed{0.05};
  std::string trace, snapshot;
  view::ViewOptions view{.distance_mm = 300.0};  ///< the snapshot's camera
};

glm::dvec3 parse_point(const std::string& text) {
  std::stringstream in(text);
  std::array<double, 3> v{};
  char comma = 0;
  for (int i = 0; i < 3; ++i) {
    std::string part;
    if (!std::getline(in, part, ',')) throw cli::UsageError("--to needs X,Y,Z [m]");
    v[static_cast<std::size_t>(i)] = cli::parse_real(part, "--to");
    if (!std::isfinite(v[static_cast<std::size_t>(i)]) || std::fabs(v[static_cast<std::size_t>(i)]) > 0.1)
      throw cli::UsageError("--to: each coordinate must be within [-0.1, 0.1] [m]");
  }
  if (in >> comma) throw cli::UsageError("--to needs X,Y,Z [m]");
  return {v[0], v[1], v[2]};
}

Arguments parse(cli::Parser& p) {
  Arguments o;
  cli::Input scene("scene (MJCF .xml)");
  while (p.next()) {
    if (o.view.take(p)) continue;  // --view, --distance
    if (p.is("--seconds")) {
      o.seconds = p.real(cli::open_closed(0.0, 600.0));
    } else if (p.is("--rate")) {
      o.rate = p.real(cli::closed(10.0, 1000.0));
    } else if (p.is("--mode")) {
      o.mode = p.choice<CouplingMode>(
          "mode", {{"local", CouplingMode::local_model}, {"coupling", CouplingMode::virtual_coupling}});
    } else if (p.is("--stiffness")) {
      o.stiffness = p.real(cli::open_closed(0.0, 1e5));
    } else if (p.is("--damping")) {
      o.damping = p.real(cli::closed(0.0, 1e4));
    } else if (p.is("--to")) {
      o.to = parse_point(p.value());
    } else if (p.is("--speed")) {
      o.speed = p.real(cli::open_closed(0.0, 1.0));
    } else if (p.is("--trace")) {
      o.trace = p.output_file();
    } else if (p.is("--snapshot")) {
      o.snapshot = p.output_file();
    } else {
      p.input_or_unknown(scene);
    }
  }
  o.scene = scene.required();
  p.finish();
  return o;
}

// ---- the scene's boxes and spheres as triangles for the 3D view ----------

void add_box(view::DisplayMesh& mesh, const std::array<glm::dvec3, 8>& corner) {
  const auto base = static_cast<std::uint32_t>(mesh.positions.size());
  for (const glm::dvec3& c : corner)
    mesh.positions.emplace_back(c);
  // corners: bit 0 x, bit 1 y, bit 2 z (of the box's own axes); faces counter-clockwise from outside
  static constexpr std::array<std::array<std::uint32_t, 4>, 6> faces{
      {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
  for (const auto& f : faces) {
    mesh.triangles.push_back({base + f[0], base + f[1], base + f[2]});
    mesh.triangles.push_back({base + f[0], base + f[2], base + f[3]});
  }
}

void add_sphere(view::DisplayMesh& mesh, const glm::dvec3& centre, double r) {
  constexpr int rings = 10, segments = 16;
  const auto base = static_cast<std::uint32_t>(mesh.positions.size());
  for (int i = 0; i <= rings; ++i) {
    const double theta = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2.0 * std::numbers::pi * j / segments;
      mesh.positions.emplace_back(
          centre + r * glm::dvec3{std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)});
    }
  }
  const auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      mesh.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
    }
}

/// Every box and sphere geom but the tool's, in the device frame.
view::DisplayMesh scene_mesh(const MujocoBridge& bridge) {
  const mjModel* m = bridge.model();
  const mjData* d = bridge.data();
  const int tool = bridge.body_id(bridge.config().tool_body);
  view::DisplayMesh mesh;
  const auto to_device = [&](const glm::dvec3& s) { return detail::scene_to_device(s - bridge.config().scene_origin); };
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] == tool) continue;
    const glm::dvec3 centre = detail::vec(d->geom_xpos + 3 * g);
    const mjtNum* r = d->geom_xmat + 9 * g;  // row-major: column k is the geom's axis k
    const glm::dvec3 axis[3] = {{r[0], r[3], r[6]}, {r[1], r[4], r[7]}, {r[2], r[5], r[8]}};
    const mjtNum* size = m->geom_size + 3 * g;
    if (m->geom_type[g] == mjGEOM_BOX) {
      std::array<glm::dvec3, 8> corner{};
      for (int k = 0; k < 8; ++k) {
        glm::dvec3 c = centre;
        for (int a = 0; a < 3; ++a)
          c += ((k >> a) & 1 ? 1.0 : -1.0) * size[a] * axis[a];
        corner[static_cast<std::size_t>(k)] = to_device(c);
      }
      add_box(mesh, corner);
    } else if (m->geom_type[g] == mjGEOM_SPHERE) {
      add_sphere(mesh, to_device(centre), size[0]);
    }
  }
  mesh.source_triangles = mesh.triangles.size();
  mesh.finish();
  return mesh;
}

int run(const Arguments& o) {
  MujocoBridgeConfig config;
  config.mode = o.mode;
  config.rate = o.rate;
  const double k = o.stiffness > 0.0 ? o.stiffness : (o.mode == CouplingMode::local_model ? 1000.0 : 200.0);
  const double b = o.damping >= 0.0 ? o.damping : k / o.rate / 2.0;
  config.plane_stiffness = config.coupling.stiffness = k;
  config.plane_damping = config.coupling.damping = b;
  if (b < k / o.rate / 2.0) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "--damping %g is below T K / 2 = %g N s/m at %g Hz: that rendering would not be passive", b,
                  k / o.rate / 2.0, o.rate);
    throw cli::UsageError(text);
  }
  long tick = 0;
  config.clock = [&tick] { return tick * 1'000'000; };  // overruns on the virtual clock: the servo's ticks [ns]
  MujocoBridge bridge(o.scene, config);
  LocalModelField field = bridge.field();
  SimulatedArmConfig arm;
  arm.hand.path = HandPath::line(glm::dvec3{0.0}, o.to, o.speed);
  ArmPlant plant(arm);

  constexpr double dt = 1e-3;  // the servo's tick [s]
  const auto ticks = static_cast<long>(std::lround(o.seconds / dt));
  const long ratio = std::max(1L, std::lround(1.0 / (o.rate * dt)));
  std::vector<std::array<double, 8>> rows;
  if (!o.trace.empty()) rows.reserve(static_cast<std::size_t>(ticks));
  glm::dvec3 force{0.0};
  double peak = 0.0, into_scene = 0.0, worst = 0.0, energy0 = 0.0;
  long touching_ticks = 0;
  for (; tick < ticks; ++tick) {
    Probe probe;
    probe.position = plant.position();
    probe.velocity = plant.velocity();
    probe.time = static_cast<double>(tick) * dt;
    probe.period = dt;
    force = field.force(probe);
    peak = std::max(peak, glm::length(force));
    if (field.touching() > 0) ++touching_ticks;
    const glm::dvec3 before = plant.position();
    plant.period(plant.kinematics().torques(plant.q(), force), probe.time);
    into_scene -= glm::dot(force, plant.position() - before);
    if (!o.trace.empty())
      rows.push_back({probe.time, probe.position.x, probe.position.y, probe.position.z, force.x, force.y, force.z,
                      static_cast<double>(field.touching())});
    if ((tick + 1) % ratio == 0) {  // the simulator's step, between two servo ticks
      (void)bridge.step_once();
      if (tick + 1 == ratio) {
        energy0 = bridge.scene_energy() + field.spring_energy();
        into_scene = 0.0;
      }
      worst = std::max(worst, bridge.scene_energy() + field.spring_energy() - energy0 - into_scene);
    }
  }
  const MujocoEvents events = bridge.events();
  std::printf("scene: %s, tool radius %.1f mm, %s mode at %g Hz, k %g N/m, b %g N s/m\n", o.scene.c_str(),
              bridge.tool_radius() * 1e3, o.mode == CouplingMode::local_model ? "local model" : "virtual coupling",
              o.rate, k, b);
  std::printf("%ld servo ticks, %llu simulator steps; touching %ld ticks, peak force %.3f N\n", ticks,
              static_cast<unsigned long long>(events.steps), touching_ticks, peak);
  std::printf("passivity observer at the HIP: worst %.2e J (energy the scene held beyond what the HIP put in)\n",
              worst);
  std::printf("events: %llu overruns, %llu non-finite, %llu MuJoCo errors, %llu warnings, %llu stalls\n",
              static_cast<unsigned long long>(events.overruns), static_cast<unsigned long long>(events.non_finite),
              static_cast<unsigned long long>(events.mujoco_errors), static_cast<unsigned long long>(events.warnings),
              static_cast<unsigned long long>(bridge.link().stalls.load()));
  std::string moved;
  for (int body = 1; body < bridge.model()->nbody; ++body) {
    const char* name = mj_id2name(bridge.model(), mjOBJ_BODY, body);
    if (name == nullptr || bridge.model()->body_weldid[body] == 0 || name == bridge.config().tool_body) continue;
    const glm::dvec3 p = bridge.body(name).position * 1e3;
    char text[160];
    std::snprintf(text, sizeof text, "%s%s at %.1f,%.1f,%.1f", moved.empty() ? "" : ", ", name, p.x, p.y, p.z);
    moved += text;
  }
  if (!moved.empty()) std::printf("bodies (centres of mass, device frame [mm]): %s\n", moved.c_str());
  if (!o.trace.empty()) {
    std::ofstream f(o.trace);
    f << "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,planes\n";
    for (const auto& r : rows)
      f << r[0] << ',' << r[1] << ',' << r[2] << ',' << r[3] << ',' << r[4] << ',' << r[5] << ',' << r[6] << ',' << r[7]
        << '\n';
    if (!f) throw FileError("--trace: cannot write '" + o.trace + "'");
    std::printf("trace: %s (%zu rows)\n", o.trace.c_str(), rows.size());
  }
  if (!o.snapshot.empty()) {
    const view::DisplayMesh mesh = scene_mesh(bridge);
    view::OrbitCamera camera;
    camera.target = glm::dvec3{0.0, -0.02, 0.0};
    o.view.aim(camera);
    view::Sample3d now;
    now.hip = now.proxy = plant.position();
    now.force = force;
    now.touching = field.touching() > 0;
    view::Scene3dConfig look;
    look.tip_radius = bridge.tool_radius();
    view::RenderTarget target;
    const view::Scene3dMarks marks = view::draw_scene3d(target, mesh, camera, now, look);
    if (!cv::imwrite(o.snapshot, target.image)) throw FileError("--snapshot: cannot write '" + o.snapshot + "'");
    std::printf("snapshot: %s, the tool at %d,%d px, %zu triangles drawn\n", o.snapshot.c_str(), marks.proxy.x,
                marks.proxy.y, marks.stats.drawn);
  }
  if (bridge.faulted()) throw MujocoError("the simulator stopped: " + bridge.fault_message());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return cli::main("feel_mujoco", usage_text, argc, argv, [](cli::Parser& p) { return run(parse(p)); });
}
