// The MuJoCo bridge (physics/): a scene felt on the simulated arm, all on a
// virtual clock (the servo's ticks and the simulator's steps interleaved by
// the test, whatever the machine's load).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "alloc_counter.hpp"
#include "hapticfield/arms/force_arm/simulated_arm.hpp"
#include "hapticfield/physics/local_model.hpp"
#include "hapticfield/physics/mujoco_bridge.hpp"
#include "hapticfield/physics/virtual_coupling.hpp"
#include "run_seed.hpp"

using namespace hapticfield;

namespace {

std::string scene_file(const char* name) {
  return std::string(HAPTICFIELD_SOURCE_DIR) + "/examples/data/" + name;
}

std::string write_temp(const std::string& name, const std::string& text) {
  std::filesystem::create_directories(HAPTICFIELD_TEST_TMP);
  const std::string path = std::string(HAPTICFIELD_TEST_TMP) + "/" + name;
  std::ofstream(path) << text;
  return path;
}

/// The simulated arm held by the scripted hand, a 1 kHz servo tick rendering
/// the bridge's field, and the simulator stepped every `ratio` ticks: the
/// virtual clock is the tick count.
struct Rig {
  MujocoBridge bridge;
  LocalModelField field;
  ArmPlant plant;
  int ratio;
  std::uint64_t tick = 0;
  double into_scene = 0.0;       ///< work the HIP did on the rendered scene [J]
  glm::dvec3 hand_impulse{0.0};  ///< impulse of the force the field gave the HIP [N s]
  glm::dvec3 last_force{0.0};
  double worst_passivity = 0.0;  ///< max over time of (energy held - work put in) [J]
  double energy0 = 0.0;
  bool observing = false;

  static constexpr double dt = 1e-3;  // the servo period [s]

  Rig(const std::string& path, const MujocoBridgeConfig& config, const HandPath& path_of_hand)
      : bridge(path, config),
        field(bridge.field()),
        plant(arm_config(path_of_hand)),
        ratio(static_cast<int>(std::lround(1.0 / (config.rate * dt)))) {
    if (config.lockstep) bridge.start();  // the simulator's own thread, stepped by the ticks' time
  }

  static SimulatedArmConfig arm_config(const HandPath& path) {
    SimulatedArmConfig c;
    c.hand.path = path;
    return c;
  }

  /// One servo tick (and a simulator step when it is due).
  void step(bool simulate = true) {
    Probe probe;
    probe.position = plant.position();
    probe.velocity = plant.velocity();
    probe.time = static_cast<double>(tick) * dt;
    probe.period = dt;
    const glm::dvec3 f = field.force(probe);
    last_force = f;
    hand_impulse += f * dt;
    const glm::dvec3 p0 = plant.position();
    plant.period(plant.kinematics().torques(plant.q(), f), probe.time);
    // the force is held over the tick: the work it did on the HIP is exact
    into_scene -= glm::dot(f, plant.position() - p0);
    ++tick;
    if (simulate && !bridge.config().lockstep && tick % static_cast<std::uint64_t>(ratio) == 0) {
      (void)bridge.step_once();
      if (!observing) {  // from the first step on: the scene and the tool have met the HIP
        observing = true;
        energy0 = bridge.scene_energy() + field.spring_energy();
        into_scene = 0.0;
      }
      // the passivity observer at the HIP (Hannaford & Ryu 2002): the scene
      // and the rendered springs never hold more than the HIP put in
      worst_passivity = std::max(worst_passivity, bridge.scene_energy() + field.spring_energy() - energy0 - into_scene);
    }
  }
  void run(double seconds, bool simulate = true) {
    const auto n = static_cast<std::uint64_t>(std::lround(seconds / dt));
    for (std::uint64_t i = 0; i < n; ++i)
      step(simulate);
  }
};

MujocoBridgeConfig config_at(double rate, CouplingMode mode = CouplingMode::local_model) {
  MujocoBridgeConfig c;
  c.rate = rate;
  c.mode = mode;
  c.fade_time = 0.0;
  return c;
}

/// A drawer: a box on a slide joint with a weak return spring, no gravity
/// and no contact but the tool's, so the scene's energy is exact (kinetic +
/// the joint spring's; undamped) and a passivity observer at the HIP sees
/// the rendering alone. The hand pushes it in and lets it come back.
std::string drawer_scene(double damping = 0.0) {
  std::string text = R"(<mujoco model="drawer">
  <option timestep="0.001" gravity="0 0 0"/>
  <worldbody>
    <body name="drawer" pos="0.04 0 0">
      <joint name="slide" type="slide" axis="1 0 0" stiffness="20" damping="DAMPING"/>
      <geom type="box" size="0.02 0.02 0.02" mass="0.1"/>
    </body>
    <body name="tool" pos="0 0 0">
      <freejoint/>
      <geom name="tool" type="sphere" size="0.004" mass="0.05"/>
    </body>
  </worldbody>
</mujoco>)";
  const std::string value = std::to_string(damping);
  text.replace(text.find("DAMPING"), 7, value);
  return write_temp("drawer_" + value + ".xml", text);
}
/// Holding the drawer 1.4 cm in.
HandPath hold_drawer() {
  return HandPath::hold(glm::dvec3{0.03, 0.0, 0.0});
}
HandPath push_drawer() {
  return HandPath::line(glm::dvec3{0.0}, glm::dvec3{0.04, 0.0, 0.0}, 0.04);
}

}  // namespace

TEST_CASE("LatestValue hands the newest value across, wait-free", "[mujoco]") {
  LatestValue<int> v;
  CHECK(v.latest() == nullptr);
  v.publish(1);
  v.publish(2);
  REQUIRE(v.latest() != nullptr);
  CHECK(*v.latest() == 2);
  v.publish(3);
  CHECK(*v.latest() == 3);
  CHECK(*v.latest() == 3);
}

TEST_CASE("VirtualCoupling refuses B < T K / 2", "[mujoco]") {
  const VirtualCoupling ok{200.0, 1.0};
  CHECK_NOTHROW(ok.validate(0.01));
  CHECK_THROWS_AS((VirtualCoupling{200.0, 0.99}.validate(0.01)), std::invalid_argument);
  CHECK(coupling_max_stiffness(1.0, 0.01) == Approx(200.0));
  CHECK(glm::length(ok.force(glm::dvec3{0.0}, glm::dvec3{0.0}, glm::dvec3{0.01, 0.0, 0.0}, glm::dvec3{0.0}) -
                    glm::dvec3{2.0, 0.0, 0.0}) < 1e-12);
}

TEST_CASE("hidden: the stiffest passive rendering at each simulator rate", "[.stiffness]") {
  for (const CouplingMode mode : {CouplingMode::local_model, CouplingMode::virtual_coupling}) {
    for (const double rate : {100.0, 200.0, 500.0, 1000.0}) {
      double best = 0.0;
      for (double k = 25.0; k < 60000.0; k *= std::sqrt(2.0)) {
        MujocoBridgeConfig c = config_at(rate, mode);
        c.plane_stiffness = k;
        c.plane_damping = k / rate / 2.0;  // the same B >= T K / 2 on the planes
        c.coupling.stiffness = k;
        c.coupling.damping = k / rate / 2.0;  // B = T K / 2, the least Adams & Hannaford allow
        Rig rig(drawer_scene(), c, push_drawer());
        rig.run(4.0);
        const bool passive = rig.worst_passivity < 1e-4 && rig.bridge.events().non_finite == 0;
        std::printf("%s %5.0f Hz K %8.1f: worst %.2e J %s\n", mode == CouplingMode::local_model ? "local" : "coupling",
                    rate, k, rig.worst_passivity, passive ? "passive" : "ACTIVE");
        if (!passive) break;
        best = k;
      }
      std::printf("=> %s at %.0f Hz: %.0f N/m\n", mode == CouplingMode::local_model ? "local" : "coupling", rate, best);
    }
  }
}

TEST_CASE("momentum the hand gives is momentum the ball gains", "[mujoco]") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> speed(0.05, 0.3), sideways(-0.01, 0.01), rate_pick(0.0, 1.0);
  for (int trial = 0; trial < 24; ++trial) {
    const CouplingMode mode = trial % 2 ? CouplingMode::virtual_coupling : CouplingMode::local_model;
    const double rate = rate_pick(rng) < 0.5 ? 100.0 : 500.0;
    MujocoBridgeConfig c = config_at(rate, mode);
    c.plane_damping = c.plane_stiffness / rate / 2.0;
    c.coupling.damping = std::max(c.coupling.damping, c.coupling.stiffness / rate / 2.0);
    // the ball floats (no gravity) 4 cm to the right; the hand pushes it off-centre
    const glm::dvec3 aim{0.08, sideways(rng), sideways(rng)};
    Rig rig(scene_file("mujoco_ball.xml"), c, HandPath::line(glm::dvec3{0.0}, aim, speed(rng)));
    // the first step puts the coupled tool on the HIP, moving as it moves:
    // momentum is counted from there (no force was rendered before it)
    for (int i = 0; i < rig.ratio; ++i)
      rig.step();
    const BodyState tool0 = rig.bridge.body("tool");
    const BodyState ball0 = rig.bridge.body("ball");
    const glm::dvec3 impulse0 = rig.hand_impulse;
    rig.run(0.6);  // a whole number of simulator periods
    INFO("trial " << trial << (mode == CouplingMode::local_model ? " local" : " coupling") << " at " << rate << " Hz");
    const BodyState ball = rig.bridge.body("ball");
    glm::dvec3 gained = ball.mass * (ball.velocity - ball0.velocity);
    if (mode == CouplingMode::virtual_coupling) {
      const BodyState tool = rig.bridge.body("tool");
      gained += tool.mass * (tool.velocity - tool0.velocity);
    }
    // what the HIP got, the scene lost: the run ends on a simulator step,
    // which took every impulse rendered until then
    const glm::dvec3 given = -(rig.hand_impulse - impulse0);
    REQUIRE(glm::length(given) > 1e-3);  // it was pushed [N s]
    CHECK(glm::length(gained - given) <= 1e-9 + 1e-9 * glm::length(given));
    CHECK(ball.velocity.x > 0.0);
  }
}

namespace {
/// One run on the virtual clock: every tick's force and the bodies at the end.
struct LockstepRun {
  std::vector<glm::dvec3> forces;
  BodyState box, ball;
  double hinge = 0.0;
  std::uint64_t steps = 0;
};
LockstepRun table_run(bool lockstep) {
  MujocoBridgeConfig c = config_at(100.0);
  c.plane_damping = 5.0;  // T k / 2 at 100 Hz
  c.lockstep = lockstep;
  // feel_mujoco's push: the box along the table
  Rig rig(scene_file("mujoco_table.xml"), c, HandPath::line(glm::dvec3{0.0}, glm::dvec3{-0.07, -0.02, 0.01}, 0.05));
  LockstepRun out;
  for (int i = 0; i < 3000; ++i) {
    rig.step();
    out.forces.push_back(rig.last_force);
  }
  rig.bridge.stop();  // in lockstep: takes the steps due first
  out.box = rig.bridge.body("box");
  out.ball = rig.bridge.body("ball");
  out.hinge = rig.bridge.joint_position("hinge");
  out.steps = rig.bridge.events().steps;
  return out;
}
bool same(const BodyState& a, const BodyState& b) {
  return a.position == b.position && a.velocity == b.velocity;
}
}  // namespace

TEST_CASE("lockstep: the same run run to run, and the same as stepping by hand", "[mujoco]") {
  const LockstepRun by_hand = table_run(false);
  const LockstepRun first = table_run(true);
  const LockstepRun second = table_run(true);
  REQUIRE(by_hand.steps == 300);  // 3 s at 100 Hz
  CHECK(first.steps == 300);
  CHECK(second.steps == 300);
  double peak = 0.0;
  for (const glm::dvec3& f : by_hand.forces)
    peak = std::max(peak, glm::length(f));
  CHECK(peak > 0.1);  // the hand met the scene [N]
  // bitwise: the same steps with the same samples, whatever the threads' speeds
  CHECK(first.forces == by_hand.forces);
  CHECK(second.forces == first.forces);
  CHECK(same(first.box, by_hand.box));
  CHECK(same(second.box, first.box));
  CHECK(same(first.ball, by_hand.ball));
  CHECK(first.hinge == by_hand.hinge);
}

TEST_CASE("lockstep keeps the bridge's laws: momentum given is momentum gained, the door turns about its hinge",
          "[mujoco]") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> speed(0.05, 0.3), sideways(-0.01, 0.01);
  for (int trial = 0; trial < 6; ++trial) {
    const CouplingMode mode = trial % 2 ? CouplingMode::virtual_coupling : CouplingMode::local_model;
    const double rate = trial < 3 ? 100.0 : 500.0;
    MujocoBridgeConfig c = config_at(rate, mode);
    c.plane_damping = c.plane_stiffness / rate / 2.0;
    c.coupling.damping = std::max(c.coupling.damping, c.coupling.stiffness / rate / 2.0);
    c.lockstep = true;
    const glm::dvec3 aim{0.08, sideways(rng), sideways(rng)};
    Rig rig(scene_file("mujoco_ball.xml"), c, HandPath::line(glm::dvec3{0.0}, aim, speed(rng)));
    for (int i = 0; i < rig.ratio; ++i)
      rig.step();
    rig.bridge.stop();  // inspected between steps; started again where the servo's time is
    const BodyState tool0 = rig.bridge.body("tool");
    const BodyState ball0 = rig.bridge.body("ball");
    const glm::dvec3 impulse0 = rig.hand_impulse;
    rig.bridge.start();
    rig.run(0.6);
    rig.bridge.stop();
    INFO("trial " << trial << (mode == CouplingMode::local_model ? " local" : " coupling") << " at " << rate << " Hz");
    const BodyState ball = rig.bridge.body("ball");
    glm::dvec3 gained = ball.mass * (ball.velocity - ball0.velocity);
    if (mode == CouplingMode::virtual_coupling) {
      const BodyState tool = rig.bridge.body("tool");
      gained += tool.mass * (tool.velocity - tool0.velocity);
    }
    const glm::dvec3 given = -(rig.hand_impulse - impulse0);
    REQUIRE(glm::length(given) > 1e-3);  // [N s]
    CHECK(glm::length(gained - given) <= 1e-9 + 1e-9 * glm::length(given));
    CHECK(rig.bridge.events().steps == static_cast<std::uint64_t>(std::lround(0.6 * rate)) + 1);
  }
  MujocoBridgeConfig c = config_at(200.0);
  c.plane_damping = c.plane_stiffness / 200.0 / 2.0;
  c.lockstep = true;
  Rig rig(scene_file("mujoco_door.xml"), c,
          HandPath::line(glm::dvec3{-0.03, 0.0, 0.0}, glm::dvec3{-0.03, 0.0, -0.06}, 0.05));
  double radius_error = 0.0;
  for (int i = 0; i < 30; ++i) {
    rig.run(0.05);
    rig.bridge.stop();
    const BodyState door = rig.bridge.body("door");
    radius_error = std::max(radius_error, std::fabs(std::hypot(door.position.x - 0.05, door.position.z + 0.03) - 0.05));
    rig.bridge.start();
  }
  rig.bridge.stop();
  CHECK(rig.bridge.joint_position("hinge") < -0.2);  // [rad]
  CHECK(radius_error < 1e-3);                        // [m]
  CHECK(rig.bridge.events().steps == 300);           // 1.5 s at 200 Hz
}

TEST_CASE("lockstep without a servo: the runner waits, and stops at once", "[mujoco]") {
  MujocoBridgeConfig c = config_at(500.0);
  c.lockstep = true;
  MujocoBridge bridge(scene_file("mujoco_ball.xml"), c);
  bridge.start();
  CHECK(bridge.lockstep_running());
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  bridge.stop();
  CHECK_FALSE(bridge.lockstep_running());
  CHECK(bridge.events().steps == 0);  // no servo time, no step
  // a field ticking with no runner never waits
  LocalModelField field = bridge.field();
  Probe probe;
  for (int i = 0; i < 10; ++i)
    (void)field.force(probe);
  CHECK(field.touching() == 0);
}

namespace {
/// A local model of one static plane, published once, never stale.
LocalModel one_plane(const ContactPlane& plane, double tool_radius) {
  LocalModel m;
  m.sequence = 1;
  m.scene = 1;
  m.tool_radius = tool_radius;
  m.stall_time = 1e9;
  m.fade_time = 0.0;
  m.planes[0] = plane;
  m.plane_count = 1;
  return m;
}
glm::dvec3 any_perpendicular(const glm::dvec3& n) {
  const glm::dvec3 a = std::fabs(n.x) < 0.9 ? glm::dvec3{1.0, 0.0, 0.0} : glm::dvec3{0.0, 1.0, 0.0};
  return glm::normalize(glm::cross(n, a));
}
}  // namespace

TEST_CASE("Coulomb friction on the local model's planes: sticks within mu_s F_n, slides at mu_k F_n", "[mujoco]") {
  const std::uint32_t seed = test::run_seed();
  INFO("seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), u01(0.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    INFO("trial " << trial);
    glm::dvec3 n{unit(rng), unit(rng), unit(rng)};
    if (glm::length(n) < 0.1) n = {0.0, 1.0, 0.0};
    n = glm::normalize(n);
    const double angle = 6.3 * u01(rng);  // of the slide in the plane [rad]
    const glm::dvec3 t = std::cos(angle) * any_perpendicular(n) + std::sin(angle) * glm::cross(n, any_perpendicular(n));
    ContactPlane plane;
    plane.point = 0.05 * glm::dvec3{unit(rng), unit(rng), unit(rng)};
    plane.normal = n;
    plane.stiffness = 200.0 + 2800.0 * u01(rng);   // [N/m]
    plane.static_friction = 0.1 + 0.9 * u01(rng);  // [-]
    plane.dynamic_friction = plane.static_friction * u01(rng);
    const double k = plane.stiffness, mu_s = plane.static_friction, mu_k = plane.dynamic_friction;
    const double r = 0.005 * u01(rng), d = 0.0005 + 0.0025 * u01(rng);  // tool radius, depth [m]
    LocalModelLink link;
    link.model.publish(one_plane(plane, r));
    LocalModelField field(link);
    Probe probe;
    probe.period = 1e-3;
    const glm::dvec3 x0 = plane.point + (r - d) * n;  // pressed d in, still
    const double scale = k * d;                       // the normal force [N]
    probe.position = x0;
    CHECK(glm::length(field.force(probe) - scale * n) <= 1e-9 * scale);  // a new touch: no tangential force
    // a straight slide along t: F_t = -k s t while k s <= mu_s F_n; once it broke, -mu_k F_n t
    const double step = mu_s * d / (5.0 + 10.0 * u01(rng));
    bool broke = false;
    glm::dvec3 last{0.0};
    for (int i = 1; i <= 30; ++i) {
      const double s = i * step;
      probe.position = x0 + s * t;
      broke = broke || s > mu_s * d * (1.0 + 1e-12);
      const glm::dvec3 expected = scale * n - (broke ? mu_k * scale : k * s) * t;
      const glm::dvec3 f = field.force(probe);
      REQUIRE(glm::length(f - expected) <= 1e-9 * scale);
      last = probe.position;
    }
    REQUIRE(broke);
    // back by delta: the proxy trails mu_k d behind, so the slip is mu_k d - delta: it sticks again within the
    // dynamic cone, |mu_k d - delta| <= mu_k d, and slides back at mu_k F_n beyond
    const double delta = (2.0 * mu_k + 0.5 * mu_s) * d * u01(rng);
    probe.position = last - delta * t;
    const glm::dvec3 back = field.force(probe);
    const double slip = std::fabs(mu_k * d - delta) <= mu_k * d * (1.0 + 1e-12) ? mu_k * d - delta : -mu_k * d;
    CHECK(glm::length(back - (scale * n - k * slip * t)) <= 1e-9 * scale);
    CHECK(field.spring_energy() == Approx(0.5 * k * (d * d + slip * slip)));
  }
}

TEST_CASE("friction drags a still hand along a plane moving under it, up to mu_s F_n, then mu_k F_n", "[mujoco]") {
  ContactPlane plane;
  plane.velocity = {0.021, 0.0, 0.0};  // sliding along x under the hand [m/s]
  plane.normal = {0.0, 1.0, 0.0};
  plane.stiffness = 1000.0;
  plane.static_friction = 0.6;
  plane.dynamic_friction = 0.4;
  plane.body = 3;
  LocalModelLink link;
  link.model.publish(one_plane(plane, 0.0));
  LocalModelField field(link);
  Probe probe;
  probe.period = 1e-3;
  probe.position = {0.0, -0.002, 0.0};  // 2 mm in: F_n = 2 N
  (void)field.force(probe);
  for (int i = 1; i <= 100; ++i) {
    const glm::dvec3 f = field.force(probe);
    const double dragged = 1000.0 * 0.021 * i * 1e-3;  // k v t while it sticks [N]
    const double expected = dragged <= 0.6 * 2.0 * (1.0 + 1e-12) ? dragged : 0.4 * 2.0;
    INFO("tick " << i);
    REQUIRE(f.x == Approx(expected).margin(1e-12));
    REQUIRE(f.y == Approx(2.0).margin(1e-12));
  }
  // the plane's body got the opposite of everything the hand got
  const HandleSample* h = link.handle.latest();
  REQUIRE(h != nullptr);
  CHECK(h->impulse[3].x < 0.0);
}

TEST_CASE("energy does not grow over 10 s of pushing at 100 Hz", "[mujoco]") {
  MujocoBridgeConfig c = config_at(100.0);
  c.plane_stiffness = 1000.0;
  c.plane_damping = 5.0;  // T k / 2 at 100 Hz
  SECTION("the drawer: the passivity observer at the HIP never goes negative") {
    Rig rig(drawer_scene(), c, push_drawer());
    rig.run(10.0);
    CHECK(rig.worst_passivity < 1e-4);  // [J]
    CHECK(rig.bridge.events().non_finite == 0);
  }
  // the table: box, ball and door pushed about for 10 s
  const auto table_stays_calm = [](const MujocoBridgeConfig& config) {
    Rig rig(scene_file("mujoco_table.xml"), config, HandPath::raster(glm::dvec3{0.0, -0.01, 0.0}, 0.1, 0.06, 4, 0.05));
    double peak = 0.0, late = 0.0, touched = 0.0;
    for (int i = 0; i < 10000; ++i) {
      rig.step();
      const double kinetic = rig.bridge.scene_energy();
      touched = std::max(touched, glm::length(rig.last_force));
      peak = std::max(peak, kinetic);
      if (i >= 8000) late = std::max(late, kinetic);
    }
    CHECK(rig.bridge.events().non_finite == 0);
    CHECK(rig.bridge.events().mujoco_errors == 0);
    CHECK(late <= peak);
    // pushing at 5 cm/s can give a 0.1 kg box ~1e-4 J of motion, far
    // below what a growing oscillation reaches
    CHECK(peak - rig.bridge.scene_energy() < 0.05);
    CHECK(touched > 0.5);  // the hand met the scene [N]
  };
  SECTION("the table: box, ball and door pushed about stay calm") {
    table_stays_calm(c);
  }
  SECTION("the table with Coulomb friction on the planes stays calm too") {
    c.plane_static_friction = 0.6;
    c.plane_dynamic_friction = 0.4;
    table_stays_calm(c);
  }
}

TEST_CASE("the door turns about its hinge", "[mujoco]") {
  MujocoBridgeConfig c = config_at(200.0);
  c.plane_damping = c.plane_stiffness / 200.0 / 2.0;
  // the door's face is 2.7 cm beyond the origin; the hand pushes 8 cm off the hinge
  Rig rig(scene_file("mujoco_door.xml"), c,
          HandPath::line(glm::dvec3{-0.03, 0.0, 0.0}, glm::dvec3{-0.03, 0.0, -0.06}, 0.05));
  double radius_error = 0.0;
  for (int i = 0; i < 1500; ++i) {
    rig.step();
    const BodyState door = rig.bridge.body("door");
    // the hinge: x 0.05, z -0.03 in the device frame, vertical
    radius_error = std::max(radius_error, std::fabs(std::hypot(door.position.x - 0.05, door.position.z + 0.03) - 0.05));
  }
  CHECK(rig.bridge.joint_position("hinge") < -0.2);  // pushed away at its left: turns clockwise seen from above [rad]
  CHECK(radius_error < 1e-3);                        // about its hinge [m]
}

TEST_CASE("a stalled simulator gives zero force within its stall time, and fades back in", "[mujoco]") {
  MujocoBridgeConfig c = config_at(500.0);
  c.fade_time = 0.1;
  Rig rig(drawer_scene(2.0), c, hold_drawer());
  rig.run(1.0);
  REQUIRE(glm::length(rig.last_force) > 0.05);  // pushing the drawer [N]
  int ticks = 0;
  while (glm::length(rig.last_force) > 0.0 && ticks < 1000) {
    rig.step(false);  // the simulator stops
    ++ticks;
  }
  // the last model may be a period old when the simulator stops
  CHECK(ticks <= static_cast<int>(c.stall_time / Rig::dt) + rig.ratio + 1);
  CHECK(rig.bridge.link().stalls.load() == 1);
  CHECK(rig.field.zeroed());
  double largest_step = 0.0, peak = 0.0;
  glm::dvec3 previous = rig.last_force;
  for (int i = 0; i < 300; ++i) {
    rig.step();
    largest_step = std::max(largest_step, glm::length(rig.last_force - previous));
    peak = std::max(peak, glm::length(rig.last_force));
    previous = rig.last_force;
  }
  CHECK_FALSE(rig.field.zeroed());
  CHECK(glm::length(rig.last_force) > 0.05);
  // faded in over 100 ticks: at most 50 N/s, a twentieth of the safety chain's default slew limit
  CHECK(largest_step < 0.05);  // [N per tick]
}

TEST_CASE("NaN in the simulator and MuJoCo's error hook give zero force on the next tick", "[mujoco]") {
  bool poison = false, fail = false;
  MujocoBridgeConfig c = config_at(500.0);
  c.before_step = [&](const mjModel*, mjData* d) {
    if (poison) d->qvel[0] = std::nan("");  // the drawer's slide
    if (fail) mju_error("injected failure");
  };
  Rig rig(drawer_scene(2.0), c, hold_drawer());
  rig.run(1.0);
  REQUIRE(glm::length(rig.last_force) > 0.05);
  SECTION("NaN") {
    poison = true;
    while (rig.bridge.events().non_finite == 0 && rig.tick < 2000)
      rig.step();
    CHECK(rig.bridge.fault() == SimulatorFault::non_finite);
  }
  SECTION("the error hook (it never returns to MuJoCo)") {
    fail = true;
    while (rig.bridge.events().mujoco_errors == 0 && rig.tick < 2000)
      rig.step();
    CHECK(rig.bridge.fault() == SimulatorFault::mujoco_error);
    CHECK(rig.bridge.fault_message().find("injected failure") != std::string::npos);
  }
  CHECK(rig.bridge.faulted());
  rig.step(false);  // the next servo tick
  CHECK(rig.last_force == glm::dvec3{0.0});
  CHECK(rig.field.zeroed());
  CHECK_FALSE(rig.bridge.step_once());  // latched
  CHECK(rig.bridge.link().faults_seen.load() == 1);
  // cleared: the scene starts again and the force fades in
  poison = fail = false;
  rig.bridge.clear_fault();
  rig.run(0.5);
  CHECK_FALSE(rig.bridge.faulted());
  CHECK_FALSE(rig.field.zeroed());
}

TEST_CASE("a MuJoCo engine error while loading is a FileError naming it, not an exit", "[mujoco]") {
  const std::string path = write_temp("tiny_stack.xml", R"(<mujoco>
  <size nstack="16"/>
  <worldbody>
    <body name="tool"><freejoint/><geom type="sphere" size="0.004" mass="0.05"/></body>
  </worldbody>
</mujoco>)");
  CHECK_THROWS_WITH(MujocoBridge(path), Catch::Contains("Stack overflow"));
}

TEST_CASE("a changed scene never jerks the arm", "[mujoco]") {
  MujocoBridgeConfig c = config_at(500.0);
  c.fade_time = 0.2;
  Rig rig(drawer_scene(2.0), c, hold_drawer());
  rig.run(1.0);
  REQUIRE(glm::length(rig.last_force) > 0.05);
  // the new scene puts a fixed block around the handle: the tool is deep inside it
  const std::string inside = write_temp("block.xml", R"(<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <geom type="box" pos="0.03 0 0" size="0.02 0.02 0.02"/>
    <body name="tool"><freejoint/><geom type="sphere" size="0.004" mass="0.05"/></body>
  </worldbody>
</mujoco>)");
  rig.bridge.load(inside);
  CHECK(rig.bridge.events().scene_changes == 1);
  double largest_step = 0.0, peak = 0.0;
  glm::dvec3 previous = rig.last_force;
  for (int i = 0; i < 400; ++i) {
    rig.step();
    largest_step = std::max(largest_step, glm::length(rig.last_force - previous));
    peak = std::max(peak, glm::length(rig.last_force));
    previous = rig.last_force;
  }
  CHECK(peak > 1.0);  // the block pushes the HIP out [N]
  // the old scene fades out as the new one fades in over 200 ticks: the
  // block's full 24 N (1000 N/m, 24 mm deep) comes in steps of ~0.12 N
  CHECK(largest_step < 0.18);  // [N per tick]
}

TEST_CASE("the field renders without allocating", "[mujoco]") {
  Rig rig(drawer_scene(2.0), config_at(500.0), hold_drawer());
  rig.run(1.0);
  REQUIRE(glm::length(rig.last_force) > 0.05);
  Probe probe;
  probe.position = rig.plant.position();
  const long n = test::count_allocations([&] {
    for (int i = 0; i < 1000; ++i)
      (void)rig.field.force(probe);
  });
  if (test::allocations_counted) CHECK(n == 0);
}

TEST_CASE("overruns are counted on the bridge's clock", "[mujoco]") {
  std::int64_t now = 0;
  MujocoBridgeConfig c = config_at(500.0);
  c.clock = [&now] { return now; };
  bool slow = false;
  c.before_step = [&](const mjModel*, mjData*) {
    if (slow) now += 5'000'000;  // 5 ms in a 2 ms period
  };
  MujocoBridge bridge(scene_file("mujoco_ball.xml"), c);
  (void)bridge.step_once();
  CHECK(bridge.events().overruns == 0);
  slow = true;
  (void)bridge.step_once();
  CHECK(bridge.events().overruns == 1);
  CHECK_FALSE(bridge.faulted());  // late is not wrong: a stall, if it lasts, is the field's to see
}

TEST_CASE("the threaded runner steps on its own and stops", "[mujoco]") {
  MujocoBridge bridge(scene_file("mujoco_table.xml"), config_at(500.0));
  bridge.start();
  CHECK(bridge.running());
  for (int i = 0; i < 1000 && bridge.events().steps < 20; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  bridge.stop();
  const std::uint64_t steps = bridge.events().steps;
  CHECK(steps >= 20);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(bridge.events().steps == steps);
  CHECK_FALSE(bridge.running());
}

TEST_CASE("bad scenes and settings: one clear error each", "[mujoco]") {
  CHECK_THROWS_AS(MujocoBridge(std::string(HAPTICFIELD_TEST_TMP) + "/no_such_scene.xml"), FileError);
  CHECK_THROWS_AS(MujocoBridge(write_temp("broken.xml", "<mujoco><worldbody><body>")), FileError);
  CHECK_THROWS_AS(MujocoBridge(write_temp("no_tool.xml", "<mujoco><worldbody/></mujoco>")), MujocoError);
  CHECK_THROWS_AS(MujocoBridge(write_temp("fixed_tool.xml", R"(<mujoco><worldbody>
    <body name="tool"><geom type="sphere" size="0.004" mass="0.05"/></body></worldbody></mujoco>)")),
                  MujocoError);
  CHECK_THROWS_AS(MujocoBridge(write_temp("box_tool.xml", R"(<mujoco><worldbody>
    <body name="tool"><freejoint/><geom type="box" size="0.004 0.004 0.004" mass="0.05"/></body></worldbody></mujoco>)")),
                  MujocoError);
  const std::string ball = scene_file("mujoco_ball.xml");
  MujocoBridgeConfig c;
  c.rate = 5.0;
  CHECK_THROWS_AS(MujocoBridge(ball, c), std::invalid_argument);
  c = {};
  c.rate = 100.0;  // k 1000 N/m needs b >= 5 N s/m at 100 Hz
  CHECK_THROWS_AS(MujocoBridge(ball, c), std::invalid_argument);
  c = {};
  c.mode = CouplingMode::virtual_coupling;
  c.coupling = {2000.0, 1.0};  // B < T K / 2 at 500 Hz
  CHECK_THROWS_AS(MujocoBridge(ball, c), std::invalid_argument);
  c = {};
  c.plane_static_friction = 0.3;
  c.plane_dynamic_friction = 0.5;  // mu_k > mu_s
  CHECK_THROWS_AS(MujocoBridge(ball, c), std::invalid_argument);
  c = {};
  c.tool_body = "ball";  // a free body without a sphere? the ball has one: fine
  CHECK_NOTHROW(MujocoBridge(ball, c));
}

#ifdef HAPTICFIELD_TOOL_FEEL_MUJOCO
#include "child_process.hpp"

namespace {
struct ToolRun {
  int status;
  std::string out, err;
};
ToolRun feel_mujoco(const std::vector<std::string>& args, const std::string& name) {
  testing::Child child(HAPTICFIELD_TOOL_FEEL_MUJOCO, args, std::string(HAPTICFIELD_TEST_TMP) + "/feel_mujoco", name);
  REQUIRE(child.wait());
  REQUIRE(child.exited_normally());
  return {child.status(), child.out(), child.err()};
}
std::size_t lines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}
}  // namespace

TEST_CASE("feel_mujoco: the table scene felt as a user runs it", "[mujoco][tool]") {
  const std::string dir = std::string(HAPTICFIELD_TEST_TMP) + "/feel_mujoco";
  std::filesystem::create_directories(dir);
  const ToolRun help = feel_mujoco({"--help"}, "help");
  CHECK(help.status == 0);
  CHECK(help.out.find("usage: feel_mujoco") == 0);
  const ToolRun run = feel_mujoco({scene_file("mujoco_table.xml"), "--seconds", "2", "--rate", "100", "--trace",
                                   dir + "/trace.csv", "--snapshot", dir + "/table.png"},
                                  "table");
  CAPTURE(run.out, run.err);
  CHECK(run.status == 0);
  CHECK(run.out.find("100 Hz") != std::string::npos);
  CHECK(run.out.find("0 non-finite, 0 MuJoCo errors") != std::string::npos);
  CHECK(run.out.find("touching 0 ticks") == std::string::npos);  // the hand meets the ball
  CHECK(lines(testing::slurp(dir + "/trace.csv")) == 2001);
  CHECK(std::filesystem::file_size(dir + "/table.png") > 5000);
}

TEST_CASE("feel_mujoco: bad input is one line on stderr", "[mujoco][tool]") {
  const ToolRun missing = feel_mujoco({"no_such_scene.xml"}, "missing");
  CHECK(missing.status == 1);
  CHECK(lines(missing.err) == 1);
  CHECK(missing.err.find("no_such_scene.xml") != std::string::npos);
  const ToolRun no_tool = feel_mujoco({write_temp("toolless.xml", "<mujoco><worldbody/></mujoco>")}, "toolless");
  CHECK(no_tool.status == 1);
  CHECK(no_tool.err.find("no tool body") != std::string::npos);
  const ToolRun too_soft = feel_mujoco({scene_file("mujoco_ball.xml"), "--rate", "100", "--damping", "1"}, "soft");
  CHECK(too_soft.status == 2);
  CHECK(too_soft.err.find("T K / 2") != std::string::npos);
  const ToolRun bad_to = feel_mujoco({scene_file("mujoco_ball.xml"), "--to", "1,0,0"}, "far");
  CHECK(bad_to.status == 2);
  CHECK(lines(bad_to.err) == 1);
  const ToolRun unknown = feel_mujoco({scene_file("mujoco_ball.xml"), "--frobnicate"}, "unknown");
  CHECK(unknown.status == 2);
}
#endif
