// Tests of shapes that move and deform (surface/moving_shape.hpp,
// surface/deforming_mesh.hpp, MeshBvh::refit), all on the virtual clock
// (each tick's Probe::time is i x 1 ms): a plane moving into a still probe
// pushes it with k x overlap (plus b times the surface's speed with
// damping); a sphere sweeping past at up to 1 m/s never takes the proxy
// inside (random passes against the closed form, and an icosphere against
// the brute-force oracle of proxy_check.hpp in the shape's frame); a box
// turning under the probe; a refit tree answers first_hit, closest and
// sweep_sphere like a rebuilt one on random queries over deformed meshes
// (constructed ones, and the real models in ../shared/data when present);
// a refit mesh is felt like a rebuilt one; no allocation in a tick. The
// random cases take a new seed each run unless Catch's --rng-seed gives
// one; the seed is printed.
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/surface.hpp"
#include "hapticfield/surface/deforming_mesh.hpp"
#include "hapticfield/surface/moving_shape.hpp"
#include "hapticfield/surface/proxy_check.hpp"
#if HAPTICFIELD_TEST_HAS_IO
#include "hapticfield/io/load_mesh.hpp"
#endif
#include "run_seed.hpp"
#include "surface_meshes.hpp"

using namespace hapticfield;
using hapticfield::test::probe_at;

// a ball on a moving mesh starts each sweep from the triangle it met last
// (MeshShape::sweep_sphere's hint, forwarded by PosedQueries)
static_assert(requires(const Moving<MeshShape>& m, QueryStats* q) {
  m.sweep_sphere(glm::dvec3{}, glm::dvec3{}, 1.0, q, std::uint32_t{0});
});

namespace {

/// Catch's --rng-seed when given, else a new seed; printed either way.
unsigned run_seed() {
  static const unsigned seed = [] {
    const unsigned s = test::run_seed();
    std::printf("test_moving_shape: random seed %u (repeat with --rng-seed %u)\n", s, s);
    return s;
  }();
  return seed;
}

constexpr double tick = 1e-3;  // [s], the virtual clock's step

/// A probe at `position` at tick i of the virtual clock.
Probe probe_at_tick(int i, glm::dvec3 position, glm::dvec3 velocity = glm::dvec3{0.0}) {
  Probe p = probe_at(position, velocity);
  p.time = i * tick;
  return p;
}

/// A shape moving in a straight line at `velocity` from `start` (time 0).
MovingPose sliding(glm::dvec3 start, glm::dvec3 velocity) {
  MovingPose m;
  m.pose.translation = start;
  m.linear_velocity = velocity;
  return m;
}

/// A random unit vector.
glm::dvec3 random_direction(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  for (;;) {
    const glm::dvec3 v{g(rng), g(rng), g(rng)};
    const double length = glm::length(v);
    if (length > 1e-6) return v / length;
  }
}

/// True when p is behind every face plane of a convex closed mesh by more
/// than `margin` [m]: inside the solid.
bool inside_convex(const TriangleMesh& mesh, const glm::dvec3& p, double margin) {
  for (const TriangleIndices& t : mesh.triangles) {
    const glm::dvec3 a = mesh.positions[t[0]];
    const glm::dvec3 n = glm::normalize(glm::cross(mesh.positions[t[1]] - a, mesh.positions[t[2]] - a));
    if (glm::dot(p - a, n) > -margin) return false;
  }
  return true;
}

/// The path of the last tick in the shape's frame (pose of that tick).
ProxyPath local_path(const ProxyPath& path, const Pose& pose) {
  ProxyPath out = path;
  for (int i = 0; i < path.count; ++i)
    out.points[static_cast<std::size_t>(i)] = pose.point_to_local(path.points[static_cast<std::size_t>(i)]);
  return out;
}

/// A smooth deformation (a function of position, so welded vertices stay
/// welded): p + amplitude sin(wave . p + phase) along `along` [m].
TriangleMesh deformed(TriangleMesh mesh, double amplitude, glm::dvec3 wave, glm::dvec3 along, double phase) {
  for (glm::dvec3& p : mesh.positions)
    p += amplitude * std::sin(glm::dot(wave, p) + phase) * along;
  return mesh;
}

/// A shape of `radius` [m] sweeping past a hand that drifts slowly: its
/// start `lead` [m] before the hand, aimed within 1.2 radii of it (most
/// passes go through it), at 0.05-1 m/s and turning at up to 5 rad/s; run
/// for `ticks`, long enough to cover `span` [m].
struct SweepPast {
  glm::dvec3 hip0{0.0};   ///< the hand at tick 0 [m]
  glm::dvec3 drift{0.0};  ///< the hand's own slow motion [m/s]
  MovingPose shape{};
  double speed{0.0};  ///< [m/s]
  int ticks{0};
};

SweepPast sweep_past(std::mt19937_64& rng, double radius, double lead, double span) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SweepPast p;
  const glm::dvec3 direction = random_direction(rng);
  p.speed = 0.05 + 0.95 * unit(rng);
  glm::dvec3 aside = random_direction(rng);
  aside -= glm::dot(aside, direction) * direction;
  aside = glm::normalize(aside) * (1.2 * radius * unit(rng));
  p.hip0 = glm::dvec3{0.01 * unit(rng), 0.01 * unit(rng), 0.01 * unit(rng)};
  p.drift = 0.05 * random_direction(rng);
  p.shape = sliding(p.hip0 + aside - lead * direction, p.speed * direction);
  p.shape.angular_velocity = 5.0 * unit(rng) * random_direction(rng);
  p.ticks = static_cast<int>(span / (p.speed * tick));
  return p;
}

/// The mesh's bounding-box diagonal [m].
double diagonal(const TriangleMesh& mesh) {
  glm::dvec3 lo{1e300}, hi{-1e300};
  for (const glm::dvec3& p : mesh.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  return glm::length(hi - lo);
}

/// Every real model in ../shared/data this build reads, fitted to 0.2 m.
std::vector<std::pair<std::string, TriangleMesh>> real_models() {
  std::vector<std::pair<std::string, TriangleMesh>> out;
#if HAPTICFIELD_TEST_HAS_IO
  const std::filesystem::path data = std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  if (!std::filesystem::is_directory(data)) return out;
  for (const char* name : {"meshes/spot.obj", "meshes/teapot.obj", "meshes/fandisk.obj", "meshes/rocker-arm.obj",
                           "meshes/stanford-bunny.obj", "gltf/Duck.gltf"}) {
    const std::filesystem::path p = data / name;
    if (!std::filesystem::exists(p)) continue;
    out.emplace_back(name, test::fitted(io::load_mesh(p.string()).mesh));
  }
#endif
  return out;
}

/// A test-only shape that switches, at each advance(), to the next of a list
/// of MeshShapes (each rebuilt over its mesh): the baseline a refit
/// DeformingMesh must feel like.
class RebuiltFrames {
 public:
  static constexpr bool flat_primitives = true;
  explicit RebuiltFrames(const std::vector<MeshShape>* frames) : frames_(frames) {}
  bool advance(double) noexcept {
    if (next_ >= frames_->size()) return false;
    current_ = next_++;
    return current_ > 0;
  }
  [[nodiscard]] Hit closest(const glm::dvec3& p, double r) const noexcept { return at().closest(p, r); }
  [[nodiscard]] Hit closest(const glm::dvec3& p, double r, QueryStats* q) const noexcept {
    return at().closest(p, r, q);
  }
  [[nodiscard]] Hit first_hit(const glm::dvec3& a, const glm::dvec3& b) const noexcept { return at().first_hit(a, b); }
  [[nodiscard]] Hit first_hit(const glm::dvec3& a, const glm::dvec3& b, QueryStats* q) const noexcept {
    return at().first_hit(a, b, q);
  }
  [[nodiscard]] Hit on_primitive(std::uint32_t k, const glm::dvec3& p, double r) const noexcept {
    return at().on_primitive(k, p, r);
  }

 private:
  [[nodiscard]] const MeshShape& at() const noexcept { return (*frames_)[current_]; }
  const std::vector<MeshShape>* frames_;
  std::size_t current_{0};
  std::size_t next_{0};
};

}  // namespace

TEST_CASE("MovingPose: extrapolation in closed form; bad poses, velocities and feeds are refused") {
  MovingPose m;
  m.pose = Pose::from_axis_angle({0, 0, 1}, 0.3, {0.1, 0.0, 0.0});
  m.linear_velocity = {0.0, 1.0, 0.0};
  m.angular_velocity = {0.0, 0.0, 2.0};
  m.time = 1.0;
  const Pose p = m.at(1.01);
  CHECK(glm::length(p.translation - glm::dvec3{0.1, 0.01, 0.0}) < 1e-15);
  const Pose expected = Pose::from_axis_angle({0, 0, 1}, 0.3 + 0.02);
  for (int c = 0; c < 3; ++c)
    CHECK(glm::length(p.rotation[c] - expected.rotation[c]) < 1e-14);
  p.validate();
  // before the snapshot: the snapshot; long after: at most moving_max_extrapolation on
  CHECK(m.at(0.5).translation == m.pose.translation);
  CHECK(glm::length(m.at(100.0).translation - m.at(1.0 + moving_max_extrapolation).translation) == 0.0);
  CHECK(m.at(NAN).translation == m.pose.translation);
  // the surface velocity: v + w x (p - origin)
  CHECK(glm::length(m.velocity_at(m.pose, {0.1, 0.5, 0.0}) - glm::dvec3{-1.0, 1.0, 0.0}) < 1e-15);

  MovingPose bad = m;
  bad.linear_velocity.x = NAN;
  CHECK_THROWS_AS(bad.validate(), std::invalid_argument);
  bad = m;
  bad.angular_velocity.z = INFINITY;
  CHECK_THROWS_AS(PoseFeed{bad}, std::invalid_argument);
  bad = m;
  bad.time = NAN;
  CHECK_THROWS_AS(Moving<PlaneShape>(PlaneShape({}), bad), std::invalid_argument);
  bad = m;
  bad.pose.rotation[0][0] = 2.0;  // a scale
  PoseFeed feed(m);
  CHECK_THROWS_AS(feed.publish(bad), std::invalid_argument);
  CHECK(feed.newest().time == 1.0);  // nothing published
  CHECK_THROWS_AS(Moving<PlaneShape>(PlaneShape({}), std::shared_ptr<PoseFeed>{}), std::invalid_argument);
}

TEST_CASE("Moving<S>: a moving plane pushes a still probe with k x overlap; damping sees the surface's velocity") {
  const double k = 1000.0, v = 0.2;  // [N/m], [m/s]
  for (const double b : {0.0, 2.0}) {
    INFO("damping " << b);
    ProxyConstraint proxy(Moving<PlaneShape>(PlaneShape({}), sliding({0, 0, -0.003}, {0, 0, v})),
                          ProxyConfig{.stiffness = k, .damping = b});
    int pushed = 0;
    for (int i = 0; i <= 30; ++i) {
      const Contact c = proxy.contact(probe_at_tick(i, {0.002, -0.001, 0.0}));
      const double overlap = -0.003 + v * i * tick;  // the plane's height over the still probe [m]
      if (overlap <= 1e-9) {
        CHECK(glm::length(c.force) == 0.0);
        continue;
      }
      ++pushed;
      CHECK(c.touching);
      CHECK(c.force.z == Approx(k * overlap + b * v).margin(1e-6));  // relative velocity -v along +z
      CHECK(std::fabs(c.force.x) + std::fabs(c.force.y) < 1e-9);
      CHECK(proxy.proxy().z >= overlap);  // the proxy rides on the surface
    }
    CHECK(pushed == 15);
  }
  // a probe moving with the surface: no damping force
  ProxyConstraint proxy(Moving<PlaneShape>(PlaneShape({}), sliding({0, 0, -0.001}, {0, 0, v})),
                        ProxyConfig{.stiffness = k, .damping = 2.0});
  for (int i = 0; i <= 10; ++i) {
    const double z = i == 0 ? 0.005 : -0.002 + v * i * tick;  // from above, then 1 mm into the plane
    const Contact c = proxy.contact(probe_at_tick(i, {0, 0, z}, {0, 0, v}));
    if (i > 0) CHECK(c.force.z == Approx(k * 0.001).margin(1e-9));
  }
  // a non-finite probe velocity drops the damping, not the contact
  ProxyConstraint still(Moving<PlaneShape>(PlaneShape({}), sliding({0, 0, 0.001}, {0, 0, v})),
                        ProxyConfig{.stiffness = k, .damping = 2.0});
  (void)still.contact(probe_at_tick(0, {0, 0, 0.01}));
  const Contact c = still.contact(probe_at_tick(1, {0, 0, 0.0}, {NAN, 0, 0}));
  CHECK(c.force.z == Approx(k * (0.001 + v * tick)).margin(1e-9));
}

TEST_CASE("Moving<S>: a plane moving away leaves the proxy free, and a still shape feels like Posed<S>") {
  ProxyConstraint proxy(Moving<PlaneShape>(PlaneShape({}), sliding({0, 0, 0.0}, {0, 0, -0.1})),
                        ProxyConfig{.stiffness = 1000.0});
  (void)proxy.contact(probe_at_tick(0, {0, 0, 0.001}));
  const Contact pressed = proxy.contact(probe_at_tick(1, {0, 0, -0.0002}));  // the plane 0.1 mm lower
  CHECK(pressed.touching);
  CHECK(pressed.force.z == Approx(1000.0 * 0.0001).margin(1e-9));
  for (int i = 3; i < 6; ++i)
    CHECK_FALSE(proxy.contact(probe_at_tick(i, {0, 0, -0.0002})).touching);  // the plane has left the probe

  // a still Moving<S> answers as Posed<S>, tick by tick, on a random walk
  std::mt19937_64 rng(run_seed());
  const TriangleMesh mesh = test::icosphere(3, 0.02);
  MovingPose m;
  m.pose = Pose::from_axis_angle({1, 2, 3}, 0.7, {0.01, 0.0, -0.005});
  ProxyConstraint moving(Moving<MeshShape>(MeshShape(mesh), m), ProxyConfig{.stiffness = 800.0});
  ProxyConstraint posed(Posed<MeshShape>(MeshShape(mesh), m.pose), ProxyConfig{.stiffness = 800.0});
  std::normal_distribution<double> step(0.0, 0.001);
  glm::dvec3 hip = m.pose.translation + glm::dvec3{0, 0, 0.03};
  for (int i = 0; i < 2000; ++i) {
    hip += glm::dvec3{step(rng), step(rng), step(rng)} - 0.02 * (hip - m.pose.translation);
    const Contact a = moving.contact(probe_at_tick(i, hip));
    const Contact b = posed.contact(probe_at_tick(i, hip));
    REQUIRE(glm::length(a.force - b.force) <= 1e-9 * (1.0 + glm::length(b.force)));
  }
}

TEST_CASE(
    "Moving<S>: a sphere sweeping past at up to 1 m/s never takes the proxy inside, nor a ball-shaped tool's centre "
    "nearer than its radius",
    "[invariant][radius]") {
  const unsigned seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937_64 rng(seed);
  const double radius = 0.02;  // [m]
  const TriangleMesh ball = test::icosphere(3, radius);
  const MeshChecker checker(ball);
  for (const double r : {0.0, 0.001}) {  // the tool: a point, a ball [m]
    INFO("tool radius " << r);
    const int passes = r > 0.0 ? 120 : 300;
    int touched = 0;
    double nearest = std::numeric_limits<double>::infinity();  // a ball's centre to the icosphere, / r
    for (int pass = 0; pass < passes; ++pass) {
      const bool mesh = pass % 2 == 1;
      const SweepPast past = sweep_past(rng, radius, 0.03 + 2 * r, 0.06 + 4 * r);
      INFO("pass " << pass << (mesh ? " (icosphere)" : " (sphere)") << " speed " << past.speed);
      const auto run = [&](auto& proxy) {
        bool contact = false;
        for (int i = 0; i <= past.ticks; ++i) {
          const glm::dvec3 hip = past.hip0 + past.drift * (i * tick);
          const Contact c = proxy.contact(probe_at_tick(i, hip, past.drift));
          contact = contact || c.touching;
          const Pose& pose = proxy.shape().pose();
          const glm::dvec3 local = pose.point_to_local(proxy.proxy());
          if (!mesh) {
            REQUIRE(glm::length(local) >= (radius + r) * (1.0 - 1e-9));
            continue;
          }
          const ProxyPath path = local_path(proxy.last_path(), pose);
          if (r == 0.0) {
            REQUIRE_FALSE(inside_convex(ball, local, 1e-9));
            REQUIRE_FALSE(checker.check(path).found());
          }
          for (int q = 0; r > 0.0 && q + 1 < path.count; ++q)
            nearest = std::fmin(nearest, checker.entered(path.points[static_cast<std::size_t>(q)],
                                                         path.points[static_cast<std::size_t>(q + 1)], r) /
                                             r);
        }
        if (contact) ++touched;
      };
      const ProxyConfig config{.stiffness = 1000.0, .radius = r};
      if (mesh) {
        ProxyConstraint proxy(Moving<MeshShape>(MeshShape(ball), past.shape), config);
        run(proxy);
      } else {
        ProxyConstraint proxy(Moving<SphereShape>(SphereShape({.radius = radius}), past.shape), config);
        run(proxy);
      }
    }
    INFO("a ball's nearest " << nearest << " r");
    CHECK(nearest >= 1.0 - 1e-6);  // infinity for the point: not measured
    CHECK(touched > passes / 2);   // most passes met the probe
  }
}

TEST_CASE("Moving<S> with a ball-shaped tool: a moving plane pushes a still ball with k (r + overlap)", "[radius]") {
  const double k = 1000.0, v = 0.2, r = 0.001;  // [N/m], [m/s], [m]
  ProxyConstraint proxy(Moving<PlaneShape>(PlaneShape({}), sliding({0, 0, -0.004}, {0, 0, v})),
                        ProxyConfig{.stiffness = k, .radius = r});
  int pushed = 0;
  for (int i = 0; i <= 30; ++i) {
    const Contact c = proxy.contact(probe_at_tick(i, {0.002, -0.001, 0.0}));
    const double plane = -0.004 + v * i * tick;  // the plane's height [m]; the probe is at z = 0
    const double overlap = plane + r;            // how far the ball's centre would sink [m]
    if (overlap <= 1e-9) {
      CHECK(glm::length(c.force) == 0.0);
      continue;
    }
    ++pushed;
    REQUIRE(c.touching);
    CHECK(c.force.z == Approx(k * overlap).margin(1e-6));
    CHECK(std::fabs(c.force.x) + std::fabs(c.force.y) < 1e-9);
    CHECK(proxy.proxy().z >= plane + r * (1.0 - 1e-9));  // the centre rides r above the surface
  }
  CHECK(pushed == 15);
}

TEST_CASE("Moving<S>: a box turning under the probe") {
  const TriangleMesh box = test::box({-0.02, -0.02, -0.02}, {0.02, 0.02, 0.0}, 2);  // top face at z = 0
  // about the vertical axis: the top face stays put, the force stays k d up
  MovingPose spin;
  spin.angular_velocity = {0.0, 0.0, 4.0};
  ProxyConstraint proxy(Moving<MeshShape>(MeshShape(box), spin), ProxyConfig{.stiffness = 1000.0});
  (void)proxy.contact(probe_at_tick(0, {0.005, 0.003, 0.001}));
  for (int i = 1; i < 400; ++i) {
    const Contact c = proxy.contact(probe_at_tick(i, {0.005, 0.003, -0.001}));
    REQUIRE(c.touching);
    REQUIRE(glm::length(c.force - glm::dvec3{0, 0, 1.0}) < 1e-6);
  }
  // with friction the turning top drags the proxy along and the hand with it:
  // a tangential force along the surface's velocity, up to mu_k times the normal one
  ProxyConstraint rough(Moving<MeshShape>(MeshShape(box), spin),
                        ProxyConfig{.stiffness = 1000.0, .static_friction = 0.6, .dynamic_friction = 0.4});
  (void)rough.contact(probe_at_tick(0, {0.01, 0.0, 0.001}));
  Contact last;
  for (int i = 1; i < 400; ++i)
    last = rough.contact(probe_at_tick(i, {0.01, 0.0, -0.001}));
  CHECK(last.force.y > 0.3);  // the top moves toward +y at x = 1 cm
  CHECK(std::hypot(last.force.x, last.force.y) <= 0.6 * last.force.z + 1e-6);

  // tumbling about a horizontal axis under a still probe: never inside, no path through a face
  MovingPose tumble;
  tumble.pose.translation = {0.0, 0.0, -0.025};
  tumble.angular_velocity = {3.0, 1.0, 0.0};
  const TriangleMesh cube = test::box({-0.02, -0.02, -0.02}, {0.02, 0.02, 0.02}, 2);
  const MeshChecker checker(cube);
  ProxyConstraint turning(Moving<MeshShape>(MeshShape(cube), tumble), ProxyConfig{.stiffness = 1000.0});
  int touching = 0;
  for (int i = 0; i < 3000; ++i) {
    const Contact c = turning.contact(probe_at_tick(i, {0.003, -0.002, 0.0}));
    // the snapshot is extrapolated 0.1 s at most: publish it again each 50 ms
    if (i % 50 == 0) {
      MovingPose now = tumble;
      now.pose = tumble.at(i * tick);
      now.time = i * tick;
      tumble = now;
      turning.shape().feed()->publish(now);
    }
    touching += c.touching ? 1 : 0;
    const Pose& pose = turning.shape().pose();
    REQUIRE_FALSE(inside_convex(cube, pose.point_to_local(turning.proxy()), 1e-9));
    REQUIRE_FALSE(checker.check(local_path(turning.last_path(), pose)).found());
  }
  CHECK(touching > 300);  // the corners swept up through the probe
}

TEST_CASE("MeshBvh::refit answers like a rebuilt tree on deformed meshes", "[invariant]") {
  const unsigned seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::pair<std::string, TriangleMesh>> models = {
      {"icosphere", test::icosphere(4, 0.05)},
      {"box", test::box({-0.03, -0.02, -0.01}, {0.03, 0.02, 0.01}, 6)},
      {"wavy sheet", test::wavy_sheet(0.1, 40, 0.004, 0.03)}};
  for (auto& model : real_models())
    models.push_back(std::move(model));
  if (models.size() == 3) WARN("real models skipped: ../shared/data is absent or unread by this build");
  for (const auto& [name, mesh] : models) {
    const double size = diagonal(mesh);
    MeshBvh refit = MeshBvh::build(mesh);
    for (int frame = 0; frame < 3; ++frame) {
      // a deformation of up to 5 % of the size, smooth over a quarter of it
      const TriangleMesh moved = deformed(mesh, 0.05 * size * unit(rng), random_direction(rng) * (25.0 / size),
                                          random_direction(rng), 6.3 * unit(rng));
      refit.refit(moved);
      const MeshBvh rebuilt = MeshBvh::build(moved);
      INFO(name << ", frame " << frame);
      REQUIRE(refit.triangle_count() == rebuilt.triangle_count());
      const std::uint32_t n = static_cast<std::uint32_t>(moved.triangles.size());
      std::uniform_int_distribution<std::uint32_t> pick(0, n - 1);
      for (int q = 0; q < 1500; ++q) {
        // around a random triangle's centroid, often from outside toward it
        const TriangleIndices& t = moved.triangles[pick(rng)];
        const glm::dvec3 c = (moved.positions[t[0]] + moved.positions[t[1]] + moved.positions[t[2]]) / 3.0;
        const glm::dvec3 from = c + 0.1 * size * unit(rng) * random_direction(rng);
        const glm::dvec3 to = c + 0.05 * size * unit(rng) * random_direction(rng);
        const BvhHit a = refit.first_hit(from, to), b = rebuilt.first_hit(from, to);
        REQUIRE(a.complete == b.complete);
        REQUIRE(a.found() == b.found());
        if (a.found()) {
          REQUIRE(a.t == b.t);  // the same triangles, the same arithmetic: the same nearest
          REQUIRE(glm::length(a.point - b.point) == 0.0);
        }
        const double r = 0.02 * size * unit(rng);
        const BvhHit ca = refit.closest(from, 0.1 * size), cb = rebuilt.closest(from, 0.1 * size);
        REQUIRE(ca.found() == cb.found());
        if (ca.found()) REQUIRE(ca.distance == cb.distance);
        const BvhHit sa = refit.sweep_sphere(from, to, r), sb = rebuilt.sweep_sphere(from, to, r);
        REQUIRE(sa.found() == sb.found());
        if (sa.found()) REQUIRE(sa.t == Approx(sb.t).margin(1e-12));
      }
    }
  }
  // bad input: a mesh without the tree's triangles or with a non-finite position; the tree is unchanged
  const TriangleMesh ball = test::icosphere(2, 0.05);
  MeshBvh bvh = MeshBvh::build(ball);
  const BvhNode before = bvh.root();
  TriangleMesh fewer = ball;
  fewer.triangles.resize(10);
  CHECK_THROWS_AS(bvh.refit(fewer), std::invalid_argument);
  TriangleMesh nan = deformed(ball, 0.01, {10, 0, 0}, {0, 0, 1}, 0.0);
  nan.positions.back().x = NAN;
  CHECK_THROWS_AS(bvh.refit(nan), std::invalid_argument);
  CHECK(bvh.root().lo == before.lo);
  CHECK(bvh.root().hi == before.hi);
}

TEST_CASE("DeformingMesh: a refit mesh is felt like a rebuilt one, frame by frame") {
  const unsigned seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937_64 rng(seed);
  const TriangleMesh sheet = test::wavy_sheet(0.1, 30, 0.003, 0.04);
  // a slow wave: each frame moves the surface a few micrometres
  std::vector<TriangleMesh> frames;
  std::vector<MeshShape> rebuilt;
  for (int f = 0; f < 300; ++f) {
    frames.push_back(deformed(sheet, 0.002, {60.0, 20.0, 0.0}, {0, 0, 1}, 0.003 * f));
    rebuilt.emplace_back(frames.back());
  }
  DeformingMesh deforming(sheet);
  const std::shared_ptr<DeformingMeshFeed> feed = deforming.feed();
  const ProxyConfig config{.stiffness = 900.0, .static_friction = 0.3, .dynamic_friction = 0.2};
  ProxyConstraint felt(std::move(deforming), config);
  ProxyConstraint baseline(RebuiltFrames(&rebuilt), config);
  std::normal_distribution<double> step(0.0, 0.0005);
  glm::dvec3 hip{0.0, 0.0, 0.01};
  int touching = 0;
  for (int f = 0; f < 300; ++f) {
    feed->publish(frames[static_cast<std::size_t>(f)].positions);
    hip += glm::dvec3{step(rng), step(rng), step(rng) - 0.0002};
    hip.x = std::clamp(hip.x, -0.04, 0.04);
    hip.y = std::clamp(hip.y, -0.04, 0.04);
    hip.z = std::max(hip.z, -0.004);
    const Contact a = felt.contact(probe_at_tick(f, hip));
    const Contact b = baseline.contact(probe_at_tick(f, hip));
    touching += a.touching ? 1 : 0;
    REQUIRE(a.touching == b.touching);
    REQUIRE(glm::length(a.force - b.force) <= 1e-9);
  }
  CHECK(touching > 50);
  CHECK(felt.shape().frame().sequence == 300);
  // bad input: wrong counts and non-finite values publish nothing
  std::vector<glm::dvec3> wrong(sheet.positions.size() - 1);
  CHECK_THROWS_AS(feed->publish(wrong), std::invalid_argument);
  std::vector<glm::dvec3> nan = sheet.positions;
  nan[3].y = NAN;
  CHECK_THROWS_AS(feed->publish(nan), std::invalid_argument);
  CHECK_THROWS_AS(feed->publish(sheet.positions, wrong), std::invalid_argument);
  CHECK_THROWS_AS(feed->publish(sheet.positions, sheet.positions), std::invalid_argument);  // the sheet has no normals
  CHECK_THROWS_AS(DeformingMesh(std::shared_ptr<DeformingMeshFeed>{}), std::invalid_argument);
}

TEST_CASE("Moving<S> and DeformingMesh: a tick allocates nothing; poses and frames from another thread") {
  const TriangleMesh ball = test::icosphere(3, 0.02);
  ProxyConstraint moving(Moving<MeshShape>(MeshShape(ball), sliding({0, 0, -0.03}, {0, 0, 0.5})),
                         ProxyConfig{.stiffness = 1000.0, .damping = 1.0});
  DeformingMesh deforming(ball);
  const std::shared_ptr<DeformingMeshFeed> frames = deforming.feed();
  ProxyConstraint deformed_proxy(std::move(deforming), ProxyConfig{.stiffness = 1000.0});
  const std::shared_ptr<PoseFeed> poses = moving.shape().feed();
  long allocations = 0, writer_allocations = 0;
  for (int i = 0; i < 200; ++i) {
    if (i % 10 == 0) {  // the writers' work: no allocation once three frames and poses circulate
      const TriangleMesh now = deformed(ball, 0.001, {0, 0, 100.0}, {1, 0, 0}, 0.1 * i);
      const long n = test::count_allocations([&] {
        poses->publish(sliding({0, 0, -0.03 + 0.5 * i * tick}, {0, 0, 0.5}));
        frames->publish(now.positions, now.normals);
      });
      if (i >= 50) writer_allocations += n;
    }
    const Probe p = probe_at_tick(i, {0.001, 0.0, 0.0}, {0, 0, 0.01});
    allocations += test::count_allocations([&] {
      (void)moving.contact(p);
      (void)deformed_proxy.contact(p);
    });
  }
  if (test::allocations_counted) CHECK(allocations == 0);
  if (test::allocations_counted) CHECK(writer_allocations == 0);

  // MeshShape::refit changes a shape no copy shares, and answers like a rebuilt one
  MeshShape shape(ball);
  const TriangleMesh moved = deformed(ball, 0.002, {0, 80.0, 0}, {0, 0, 1}, 0.5);
  {
    const MeshShape copy = shape;
    CHECK_FALSE(shape.refit(moved.positions));
    CHECK(shape.mesh().positions == ball.positions);
  }
  CHECK(shape.refit(moved.positions, moved.normals));
  const MeshShape rebuilt(moved);
  for (int i = 0; i < 100; ++i) {
    const glm::dvec3 from = 0.03 * glm::dvec3{std::sin(i), std::cos(3.0 * i), std::sin(7.0 * i)};
    CHECK(shape.first_hit(from, -from).t == rebuilt.first_hit(from, -from).t);
    CHECK(glm::length(shape.first_hit(from, -from).normal - rebuilt.first_hit(from, -from).normal) == 0.0);
  }
  std::vector<glm::dvec3> short_list(3);
  CHECK_THROWS_AS(shape.refit(short_list), std::invalid_argument);

  // a writer thread publishing poses while the loop ticks: whatever pose a
  // tick takes, the proxy stays outside the sphere
  ProxyConstraint loop(Moving<SphereShape>(SphereShape({.radius = 0.02}), sliding({0, 0, -0.03}, {0, 0, 0.0})),
                       ProxyConfig{.stiffness = 1000.0});
  const std::shared_ptr<PoseFeed> feed = loop.shape().feed();
  (void)loop.contact(probe_at_tick(0, {0.0, 0.0, 0.0}));  // the proxy starts outside
  std::atomic<bool> stop{false};
  std::thread writer([&] {
    for (int j = 0; !stop.load(); ++j) {
      const double phase = 1e-3 * j;
      feed->publish(sliding({0.01 * std::sin(phase), 0.0, 0.025 * std::sin(3.0 * phase)}, {0, 0, 0}));
      std::this_thread::yield();
    }
  });
  for (int i = 1; i < 20000; ++i) {
    (void)loop.contact(probe_at_tick(i, {0.0, 0.0, 0.0}));
    const glm::dvec3 local = loop.shape().pose().point_to_local(loop.proxy());
    REQUIRE(glm::length(local) >= 0.02 * (1.0 - 1e-9));
  }
  stop = true;
  writer.join();

  // a writer thread publishing deformed frames while the loop presses on the mesh
  DeformingMesh breathing(ball);
  const std::shared_ptr<DeformingMeshFeed> breaths = breathing.feed();
  ProxyConstraint pressed(std::move(breathing), ProxyConfig{.stiffness = 1000.0});
  (void)pressed.contact(probe_at_tick(0, {0.0, 0.0, 0.03}));
  std::atomic<bool> done{false};
  std::thread deformer([&] {
    std::vector<glm::dvec3> positions = ball.positions;
    for (int j = 0; !done.load(); ++j) {
      const double scale = 1.0 + 0.02 * std::sin(1e-2 * j);  // the ball breathes by 2 %
      for (std::size_t v = 0; v < positions.size(); ++v)
        positions[v] = scale * ball.positions[v];
      breaths->publish(positions);
      std::this_thread::yield();
    }
  });
  int touching = 0;
  for (int i = 1; i < 5000; ++i) {
    const Contact c = pressed.contact(probe_at_tick(i, {0.0, 0.0, std::max(0.0185, 0.03 - 3e-4 * i)}));
    REQUIRE(is_finite(c.force));
    touching += c.touching ? 1 : 0;
  }
  done = true;
  deformer.join();
  CHECK(touching > 4000);  // pressed 1.5 mm into a ball of 20 +- 0.4 mm: held on it throughout
}
