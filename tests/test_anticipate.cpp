// The look-ahead (anticipate(), core/field.hpp): a proxy anticipated before
// every tick makes the same ticks bit for bit as one that is not, whatever
// it is asked to anticipate (random paths with a new seed each run, printed
// on failure; constructed meshes, a height field and every real model in
// ../shared/data), without allocating; every field wrapper passes it on; and
// the servo loops call it once a tick, in the slack before the deadline, on
// the last HIP moved one period by its velocity, and only for a field whose
// look-ahead does something.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "alloc_counter.hpp"
#include "arm_rig.hpp"
#include "hapticfield/core/any_field.hpp"
#include "hapticfield/core/compose.hpp"
#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/field.hpp"
#include "hapticfield/core/live_field.hpp"
#include "hapticfield/material/material_surface.hpp"
#include "hapticfield/servo/multi_arm_loop.hpp"
#include "hapticfield/servo/pacer.hpp"
#include "hapticfield/surface/height_field.hpp"
#include "hapticfield/surface/mesh_shape.hpp"
#include "hapticfield/surface/moving_shape.hpp"
#include "hapticfield/surface/posed_shape.hpp"
#include "hapticfield/surface/proxy.hpp"
#include "run_seed.hpp"
#include "surface_meshes.hpp"
#if HAPTICFIELD_TEST_HAS_IO
#include "hapticfield/io/load_mesh.hpp"
#endif

using namespace hapticfield;
using test::run_seed;

namespace {

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();

/// Equal bit for bit (NaN equal to NaN): what two identical ticks give.
bool same(double a, double b) {
  return a == b || (std::isnan(a) && std::isnan(b));
}
bool same(const glm::dvec3& a, const glm::dvec3& b) {
  return same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z);
}

struct Named {
  std::string name;
  TriangleMesh mesh;
};

/// Constructed meshes, then every real model in ../shared/data this build
/// reads (fitted to a 0.2 m diagonal).
std::vector<Named> meshes() {
  std::vector<Named> out;
  out.push_back({"icosphere", test::icosphere(4, 0.05)});
  out.push_back({"wavy sheet", test::wavy_sheet(0.1, 120, 0.004, 0.03)});
  out.push_back({"box", test::box(glm::dvec3{-0.02}, glm::dvec3{0.02}, 4)});
#if HAPTICFIELD_TEST_HAS_IO
  const std::filesystem::path data = std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data";
  if (std::filesystem::is_directory(data))
    for (const char* name : {"gltf/Duck.gltf", "meshes/spot.obj", "meshes/teapot.obj", "meshes/fandisk.obj",
                             "meshes/rocker-arm.obj", "meshes/stanford-bunny.obj"}) {
      const std::filesystem::path p = data / name;
      if (std::filesystem::exists(p)) out.push_back({name, test::fitted(io::load_mesh(p.string()).mesh)});
    }
  else
    WARN("real models skipped: " << data << " is absent");
#endif
  return out;
}

/// A press onto a random front-facing triangle and a slide along it, at a
/// random speed (26 mm/s to 2 m/s) and depth (up to 3 mm), 1 kHz.
std::vector<Probe> press_and_slide(const TriangleMesh& m, std::mt19937& rng) {
  std::uniform_int_distribution<std::size_t> pick(0, m.triangles.size() - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  glm::dvec3 c{0.0}, n{0.0};
  for (int tries = 0; tries < 100 && glm::length(n) == 0.0; ++tries) {
    const auto& t = m.triangles[pick(rng)];
    const glm::dvec3 a = m.positions[t[0]], b = m.positions[t[1]], d = m.positions[t[2]];
    const glm::dvec3 cross = glm::cross(b - a, d - a);
    if (glm::length(cross) > 0.0) {
      n = glm::normalize(cross);
      c = (a + b + d) / 3.0;
    }
  }
  glm::dvec3 side = glm::cross(n, glm::dvec3{unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5});
  side = glm::length(side) > 0.0 ? glm::normalize(side) : glm::dvec3{1.0, 0.0, 0.0};
  const double speed = 0.026 * std::pow(2.0 / 0.026, unit(rng));  // [m/s]
  const double depth = 3e-3 * unit(rng);                          // [m]
  std::vector<Probe> path;
  glm::dvec3 last = c + 0.003 * n;
  for (int i = 0; i < 120; ++i) {
    const double t = i * 1e-3;                                                    // [s]
    const double press = i < 20 ? 0.003 - (0.003 + depth) * (i / 20.0) : -depth;  // [m] along n
    Probe p;
    p.position = c + press * n + (i < 20 ? 0.0 : speed * (t - 0.02)) * side;
    p.velocity = (p.position - last) / 1e-3;
    p.time = t;
    last = p.position;
    path.push_back(p);
  }
  return path;
}

/// What a proxy is asked to anticipate before tick i: the tick itself, the
/// next one, the predicted one, somewhere far, or a non-finite HIP.
Probe something_to_anticipate(const std::vector<Probe>& path, std::size_t i, std::mt19937& rng) {
  std::uniform_int_distribution<int> kind(0, 6);
  Probe p = path[i];
  switch (kind(rng)) {
    case 0:
      return p;
    case 1:
      return path[std::min(i + 1, path.size() - 1)];
    case 2:
      return i > 0 ? predicted_probe(path[i - 1], 1e-3) : p;
    case 3:
      p.position += glm::dvec3{0.05, -0.03, 0.02};
      return p;
    case 4:
      p.position.x = not_a_number;
      return p;
    case 5:
      p.velocity.y = not_a_number;
      return p;
    default:
      p.position = glm::dvec3{std::numeric_limits<double>::infinity(), 0.0, 0.0};
      return p;
  }
}

/// What compare_on() saw.
struct Compared {
  long allocations{0};  ///< made by the look-ahead
  long ticks{0};
  long touching{0};
  Compared& operator+=(const Compared& o) {
    allocations += o.allocations;
    ticks += o.ticks;
    touching += o.touching;
    return *this;
  }
};

/// Runs `path` on two equal proxies, the second anticipating something
/// before every tick: the same contacts, proxies and tick records, bit for
/// bit (but for a ball's tree nodes).
template <class S>
Compared compare_on(const S& one, const S& other, const ProxyConfig& config, const std::vector<Probe>& path,
                    std::mt19937& rng) {
  ProxyConstraint<S> plain(one, config), ahead(other, config);  // shapes built apart: nothing shared
  Compared out;
  long& allocations = out.allocations;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Probe next = something_to_anticipate(path, i, rng);
    allocations += test::count_allocations([&] { ahead.anticipate(next); });
    const Contact a = plain.contact(path[i]);
    const Contact b = ahead.contact(path[i]);
    INFO("tick " << i);
    REQUIRE(a.touching == b.touching);
    REQUIRE(same(a.force, b.force));
    REQUIRE(same(a.normal, b.normal));
    REQUIRE(same(a.depth, b.depth));
    REQUIRE(a.primitive == b.primitive);
    REQUIRE(same(plain.proxy(), ahead.proxy()));
    REQUIRE(plain.last_tick().moves == ahead.last_tick().moves);
    // a ball keeps the region of the tree its look-ahead gathered (a cache:
    // the answers are the same with any region), so its tick may count
    // other nodes; a point's are the same
    if (!(config.radius > 0.0)) REQUIRE(plain.last_tick().nodes == ahead.last_tick().nodes);
    REQUIRE(plain.last_tick().sliding == ahead.last_tick().sliding);
    REQUIRE(plain.last_tick().planes == ahead.last_tick().planes);
    REQUIRE(plain.last_tick().blocked == ahead.last_tick().blocked);
    REQUIRE(plain.last_tick().held_first == ahead.last_tick().held_first);
    REQUIRE(plain.last_tick().embedded == ahead.last_tick().embedded);
    REQUIRE(same(a.surface_uv.x, b.surface_uv.x));
    REQUIRE(same(a.surface_uv.y, b.surface_uv.y));
    REQUIRE(same(a.surface_tangent, b.surface_tangent));
    REQUIRE(same(a.surface_bitangent, b.surface_bitangent));
    REQUIRE(a.material == b.material);
    REQUIRE(plain.last_path().count == ahead.last_path().count);
    for (int k = 0; k < plain.last_path().count; ++k)
      REQUIRE(same(plain.last_path().points[static_cast<std::size_t>(k)],
                   ahead.last_path().points[static_cast<std::size_t>(k)]));
    ++out.ticks;
    out.touching += a.touching ? 1 : 0;
  }
  return out;
}

}  // namespace

TEST_CASE("a proxy anticipated before every tick makes the same ticks bit for bit, without allocating",
          "[anticipate]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  Compared seen;
  int paths = 0;
  for (const Named& m : meshes()) {
    INFO(m.name);
    const MeshShape shape(m.mesh), apart(m.mesh);
    for (const double radius : {0.0, 5e-4, 2e-3}) {
      INFO("radius " << radius);
      for (const bool stick_first : {true, false}) {
        ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
        config.radius = radius;
        config.stick_first = stick_first;
        for (int k = 0; k < 4; ++k, ++paths)
          seen += compare_on(shape, apart, config, press_and_slide(m.mesh, rng), rng);
      }
    }
  }
  // a height field (a bumpy grid): the point proxy and a ball
  std::vector<double> heights(64 * 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      heights[static_cast<std::size_t>(y * 64 + x)] = 0.002 * std::sin(0.4 * x) * std::cos(0.3 * y);
  const HeightFieldShape field(64, 64, 0.1 / 63, 0.1 / 63, heights), field_apart(64, 64, 0.1 / 63, 0.1 / 63, heights);
  const TriangleMesh as_mesh = test::wavy_sheet(0.1, 64, 0.002, 0.03);
  for (const double radius : {0.0, 1e-3}) {
    ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
    config.radius = radius;
    for (int k = 0; k < 8; ++k, ++paths) {
      std::vector<Probe> path = press_and_slide(as_mesh, rng);
      for (Probe& p : path)
        p.position += glm::dvec3{0.05, 0.05, 0.0};  // over the grid, which starts at the origin
      seen += compare_on(field, field_apart, config, path, rng);
    }
  }
  CHECK(paths > 0);
  CHECK(seen.touching > seen.ticks / 2);  // most ticks press on the surface
  if (test::allocations_counted) CHECK(seen.allocations == 0);
#if HAPTICFIELD_TEST_HAS_IO
  if (std::filesystem::is_directory(std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / ".." / "shared" / "data"))
    CHECK(meshes().size() == 9);  // the three constructed, and the six real models read
#endif
}

TEST_CASE("a ball's look-ahead leaves the region of the tree it gathered to the tick: fewer nodes, the same forces",
          "[anticipate]") {
  // A 0.5 mm ball pressed 1 mm into a fine wavy sheet (0.14 mm triangles)
  // and slid round a circle of 10 mm at 5 cm/s: its sweeps gather a new
  // region every few ticks. Anticipated with the very tick that follows,
  // the tick finds the region gathered and counts none of that gathering.
  const MeshShape shape(test::wavy_sheet(0.1, 707, 0.002, 0.03)), apart(test::wavy_sheet(0.1, 707, 0.002, 0.03));
  ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
  config.radius = 5e-4;
  ProxyConstraint plain(shape, config), ahead(apart, config);
  std::uint64_t plain_nodes = 0, ahead_nodes = 0;
  long touching = 0;
  for (int i = 0; i < 1500; ++i) {
    const double angle = 0.05 / 0.01 * i * 1e-3, sink = std::fmin(1.0, i / 100.0) * 0.001 + 0.002;  // [rad], [m]
    Probe p;
    p.time = i * 1e-3;
    p.position = glm::dvec3{0.01 * std::cos(angle), 0.01 * std::sin(angle), 0.0};
    p.position.z = test::wavy_height(p.position.x, p.position.y, 0.002, 0.03) + 0.003 -
                   sink;  // from 1 mm above the sheet to 1 mm into it
    ahead.anticipate(p);
    const Contact a = plain.contact(p), b = ahead.contact(p);
    INFO("tick " << i);
    REQUIRE(same(a.force, b.force));
    REQUIRE(same(plain.proxy(), ahead.proxy()));
    touching += a.touching ? 1 : 0;
    plain_nodes += plain.last_tick().nodes;
    ahead_nodes += ahead.last_tick().nodes;
  }
  INFO(touching << " ticks touching; tree nodes " << plain_nodes << " without the look-ahead, " << ahead_nodes
                << " with it");
  CHECK(touching > 1000);
  CHECK(static_cast<double>(ahead_nodes) < 0.95 * static_cast<double>(plain_nodes));  // 0.86x when written
}

TEST_CASE("a shape that moves is not anticipated (advance() would take its feed's newest pose): nothing is done",
          "[anticipate]") {
  ProxyConstraint proxy(Moving<MeshShape>(MeshShape(test::icosphere(3, 0.05)), MovingPose{}), ProxyConfig{});
  Probe p;
  p.position = glm::dvec3{0.0, 0.0, 0.049};
  const long allocations = test::count_allocations([&] { proxy.anticipate(p); });
  if (test::allocations_counted) CHECK(allocations == 0);
  // the first tick after a look-ahead still puts the proxy at the HIP
  (void)proxy.contact(p);
  CHECK(same(proxy.proxy(), p.position));
}

namespace {

/// A mesh that counts its queries through a pointer: not pure (the count is
/// a side effect), unless Pure, which the test uses to see the look-ahead's
/// queries.
template <bool Pure>
struct CountingMesh {
  static constexpr bool pure_queries = Pure;
  MeshShape mesh;
  long* queries;
  Hit closest(const glm::dvec3& p, double d) const noexcept { return ++*queries, mesh.closest(p, d); }
  Hit first_hit(const glm::dvec3& a, const glm::dvec3& b) const noexcept { return ++*queries, mesh.first_hit(a, b); }
  Hit sweep_sphere(const glm::dvec3& a, const glm::dvec3& b, double r) const noexcept {
    return ++*queries, mesh.sweep_sphere(a, b, r);
  }
};

}  // namespace

TEST_CASE("the look-ahead makes the queries of the tick it anticipates; a shape that is not pure gets none",
          "[anticipate]") {
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  const TriangleMesh sheet = test::wavy_sheet(0.1, 80, 0.004, 0.03);
  static_assert(PureQueries<MeshShape> && PureQueries<HeightFieldShape> && PureQueries<PlaneShape> &&
                PureQueries<SphereShape> && PureQueries<Posed<MeshShape>>);
  static_assert(!PureQueries<CountingMesh<false>> && !PureQueries<Moving<MeshShape>>);
  long queries = 0, ahead_queries = 0, impure_queries = 0;
  for (const double radius : {0.0, 5e-4}) {
    ProxyConfig config{1500.0, 1.0, 0.5, 0.4};
    config.radius = radius;
    ProxyConstraint pure(CountingMesh<true>{MeshShape(sheet), &queries}, config);
    ProxyConstraint impure(CountingMesh<false>{MeshShape(sheet), &impure_queries}, config);
    long queried_ticks = 0;
    for (int k = 0; k < 6; ++k) {
      const std::vector<Probe> path = press_and_slide(sheet, rng);
      for (const Probe& p : path) {
        const long before = queries;
        pure.anticipate(p);  // the very tick that follows
        ahead_queries = queries - before;
        (void)pure.contact(p);
        INFO("t " << p.time);
        REQUIRE(ahead_queries == queries - before - ahead_queries);
        queried_ticks += ahead_queries > 0 ? 1 : 0;
        const long impure_before = impure_queries;
        impure.anticipate(p);
        REQUIRE(impure_queries == impure_before);
        (void)impure.contact(p);
      }
    }
    CHECK(queried_ticks > 100);  // the look-ahead did query, on most ticks
  }
}

TEST_CASE(
    "a material surface's look-ahead makes the queries of the tick it anticipates, with the material that "
    "tick reads",
    "[anticipate]") {
  // Friction stripes 1 cm wide (mu_s 0.1 and 1.0, mu_k 0.05 and 0.9) across
  // a wavy sheet: each tick first takes the material at the uv where the
  // proxy is held, the last tick's contact. A look-ahead run with the
  // material of the tick before sticks where the tick slides (or slides
  // where it sticks) as the proxy crosses a stripe's edge, and makes
  // other queries than the tick it stands for.
  const std::uint32_t seed = run_seed();
  INFO("seed " << seed << " (replay: --rng-seed " << seed << ")");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const TriangleMesh sheet = test::wavy_sheet(0.1, 80, 0.004, 0.03);  // uv over its 10 cm: a stripe 1 cm
  material::MaterialMaps maps;
  const auto stripes = [](float a, float b) {
    return material::PropertyMap(10, 1, {a, b, a, b, a, b, a, b, a, b}, material::UvLayout{material::UvWrap::clamp});
  };
  maps.static_friction = stripes(0.1F, 1.0F);
  maps.dynamic_friction = stripes(0.05F, 0.9F);
  long queries = 0, queried_ticks = 0;
  for (const double radius : {0.0, 5e-4}) {
    ProxyConfig config;
    config.radius = radius;
    auto surface =
        material::material_surface(CountingMesh<true>{MeshShape(sheet), &queries}, config, material::MaterialMap(maps));
    static_assert(AnticipatingField<decltype(surface)>);
    for (int k = 0; k < 6; ++k) {
      surface.reset();
      const double y = 0.03 * (2.0 * unit(rng) - 1.0), speed = 0.02 + 0.1 * unit(rng);  // [m], [m/s]
      // (up to 7 cm across x: seven stripes' edges at 0.12 m/s)
      for (int i = 0; i < 600; ++i) {  // 5 mm over the sheet, pressed 1.5 mm in over 40 ms, then across x
        const double x = -0.04 + speed * 1e-3 * std::max(0, i - 40);
        Probe p;
        p.position = {x, y, test::wavy_height(x, y, 0.004, 0.03) + 0.005 - 0.0065 * std::min(i, 40) / 40.0};
        p.velocity = {i > 40 ? speed : 0.0, 0.0, 0.0};
        p.time = i * 1e-3;
        const long before = queries;
        surface.anticipate(p);  // the very tick that follows
        const long ahead = queries - before;
        (void)surface.force(p);
        INFO("radius " << radius << ", slide " << k << ", tick " << i);
        REQUIRE(ahead == queries - before - ahead);
        queried_ticks += ahead > 0 ? 1 : 0;
      }
    }
  }
  CHECK(queried_ticks > 1000);
}

// --- every wrapper passes the look-ahead on -------------------------------------

namespace {

/// A constraint that records what it is asked to anticipate.
struct Recorder {
  std::vector<Probe>* seen;
  Contact contact(const Probe&) noexcept { return Contact{}; }
  void anticipate(const Probe& next) const noexcept { seen->push_back(next); }
  [[nodiscard]] bool looks_ahead() const noexcept { return true; }
};

/// A field that records its look-ahead calls and each tick's probe, in
/// order (for the loops): 'a' then the probe anticipated, 'f' then the
/// probe forced.
struct Logged {
  struct Entry {
    char what;
    Probe probe;
    std::int64_t at;  ///< clock time [ns]
  };
  std::vector<Entry>* log;
  const VirtualClock* clock;
  glm::dvec3 push{0.3, 0.0, 0.0};  ///< [N], so that the free arm moves
  bool ahead{true};                ///< what looks_ahead() says
  glm::dvec3 force(const Probe& p) noexcept {
    log->push_back({'f', p, clock->now()});
    return push;
  }
  void anticipate(const Probe& next) const noexcept { log->push_back({'a', next, clock->now()}); }
  [[nodiscard]] bool looks_ahead() const noexcept { return ahead; }
};

}  // namespace

TEST_CASE("ContactField, sums, scales, clamps, AnyField and LiveField pass the look-ahead on; others are left alone",
          "[anticipate]") {
  std::vector<Probe> seen;
  seen.reserve(64);
  Probe p;
  p.position = glm::dvec3{0.01, 0.02, 0.03};
  p.velocity = glm::dvec3{0.1, not_a_number, 0.0};
  auto contact_field = contact(Recorder{&seen});
  static_assert(AnticipatingField<decltype(contact_field)>);
  contact_field.anticipate(p);
  REQUIRE(seen.size() == 1);
  CHECK(same(seen[0].position, p.position));
  CHECK(seen[0].velocity == glm::dvec3{0.0});  // as force() gives the constraint a non-finite velocity
  Probe lost = p;
  lost.position.z = not_a_number;
  contact_field.anticipate(lost);  // no HIP: nothing to anticipate
  CHECK(seen.size() == 1);

  SumField sum(contact(Recorder{&seen}), ZeroField{}, contact(Recorder{&seen}));
  sum.anticipate(p);
  CHECK(seen.size() == 3);
  ScaledField scaled(contact(Recorder{&seen}), 2.0);
  scaled.anticipate(p);
  ClampedField clamped(contact(Recorder{&seen}), 2.0);
  clamped.anticipate(p);
  CHECK(seen.size() == 5);
  AnyField any(ClampedField(contact(Recorder{&seen}), 1.0));
  const long allocations = test::count_allocations([&] { any.anticipate(p); });
  CHECK(seen.size() == 6);
  if (test::allocations_counted) CHECK(allocations == 0);
  std::vector<Probe> first, second;
  first.reserve(8);
  second.reserve(8);
  LiveField<decltype(contact_field)> live(contact(Recorder{&first}));
  static_assert(AnticipatingField<LiveField<decltype(contact_field)>>);
  CHECK(live.looks_ahead());
  live.anticipate(p);
  CHECK(first.size() == 1);
  live.publish(contact(Recorder{&second}));  // a newer field: not looked at before a tick has taken it
  live.anticipate(p);
  CHECK(first.size() == 2);
  CHECK(second.empty());
  (void)live.force(p);
  live.anticipate(p);
  CHECK(first.size() == 2);
  CHECK(second.size() == 1);
  CHECK(seen.size() == 6);
  AnyField empty;
  empty.anticipate(p);
  AnyField zero(ZeroField{});
  zero.anticipate(p);
  anticipate_if_able(ZeroField{}, p);
  CHECK(seen.size() == 6);
  // looks_ahead(): what the parts say
  CHECK(any.looks_ahead());
  CHECK(sum.looks_ahead());
  CHECK_FALSE(empty.looks_ahead());
  CHECK_FALSE(zero.looks_ahead());
  CHECK_FALSE(field_looks_ahead(ZeroField{}));
  CHECK_FALSE(SumField(ZeroField{}, ZeroField{}).looks_ahead());
  CHECK(contact(ProxyConstraint(MeshShape(test::icosphere(1, 0.01)), ProxyConfig{})).looks_ahead());
  CHECK_FALSE(
      contact(ProxyConstraint(Moving<MeshShape>(MeshShape(test::icosphere(1, 0.01)), MovingPose{}), ProxyConfig{}))
          .looks_ahead());
}

TEST_CASE("predicted_probe: the HIP moved by its velocity, time on; a non-finite move keeps the position",
          "[anticipate]") {
  Probe p;
  p.position = glm::dvec3{0.01, 0.02, 0.03};
  p.velocity = glm::dvec3{0.5, -0.25, 0.0};
  p.time = 2.0;
  const Probe next = predicted_probe(p, 1e-3);
  CHECK(next.position == p.position + 1e-3 * p.velocity);
  CHECK(next.time == 2.0 + 1e-3);
  CHECK(next.velocity == p.velocity);
  p.velocity.z = not_a_number;
  CHECK(predicted_probe(p, 1e-3).position == p.position);
  p.velocity.z = 1e308;
  CHECK(predicted_probe(p, 1e300).position == p.position);
}

// --- the loops call it -------------------------------------------------------------

TEST_CASE("Pacer::wait runs ready() in the slack before the deadline, never when a late wake leaves too little",
          "[anticipate]") {
  constexpr std::int64_t period = 1'000'000;  // [ns]
  for (const PacingMode mode : {PacingMode::sleep, PacingMode::hybrid}) {
    CAPTURE(static_cast<int>(mode));
    // the margin (hybrid) and the look-ahead lead (sleep) differ: each mode uses its own
    const std::int64_t early = mode == PacingMode::hybrid ? 80'000 : 120'000;
    VirtualClock clock;
    clock.set_wake_delay(20'000);  // every sleep returns 20 us late
    PacingConfig pacing{mode, 80'000};
    pacing.look_ahead_ns = 120'000;
    Pacer pacer(period, pacing);
    pacer.start(clock.now());
    for (int tick = 0; tick < 20; ++tick) {
      CAPTURE(tick);
      const std::int64_t deadline = pacer.deadline();
      if (tick == 10) clock.shift_next_wake(early - 20'000 - early / 4);  // a quarter of the stretch left: too little
      if (tick == 12) clock.shift_next_wake(early - 20'000 - early / 4 - 1'000);  // 1 us more: enough
      int calls = 0;
      std::int64_t called_at = -1;
      const std::int64_t wake = pacer.wait(clock, [&]() noexcept {
        ++calls;
        called_at = clock.now();
      });
      if (tick == 0 || tick == 10) {  // the first deadline is now; the late wake leaves too little
        CHECK(calls == 0);
        CHECK(pacer.look_ahead().skipped);
      } else {
        CHECK(calls == 1);
        CHECK(called_at == deadline - (tick == 12 ? early / 4 + 1'000 : early - 20'000));
        CHECK(pacer.look_ahead().ran);
        CHECK_FALSE(pacer.look_ahead().late);
      }
      // the tick's own wake: on the deadline after the spin, 20 us late after the second sleep
      if (tick > 0) CHECK(wake == (mode == PacingMode::hybrid ? deadline : deadline + 20'000));
      pacer.finish(wake);
    }
    CHECK(pacer.readied() == 18);
  }
}

TEST_CASE("Pacer::wait: ready()'s own time comes out of the slack; a run past the deadline makes the wake late",
          "[anticipate]") {
  constexpr std::int64_t period = 1'000'000;  // [ns]
  for (const PacingMode mode : {PacingMode::sleep, PacingMode::hybrid}) {
    CAPTURE(static_cast<int>(mode));
    VirtualClock clock;
    PacingConfig pacing{mode, 100'000};
    pacing.look_ahead_ns = 100'000;
    Pacer pacer(period, pacing);
    pacer.start(clock.now());
    pacer.finish(clock.now());   // the first deadline now one period on
    std::int64_t cost = 30'000;  // [ns] what ready() takes
    auto ready = [&clock, &cost]() noexcept { clock.advance(cost); };
    // 30 us: inside the slack; the tick wakes on its deadline
    std::int64_t deadline = pacer.deadline();
    std::int64_t wake = pacer.wait(clock, ready);
    CHECK(wake == deadline);
    CHECK(pacer.look_ahead().took_ns == 30'000);
    if (mode == PacingMode::hybrid) CHECK(pacer.spun_ns() == 70'000);  // the spin is what is left
    pacer.finish(wake);
    // 150 us: it runs (it has not taken that long before) and ends 50 us past the deadline
    cost = 150'000;
    deadline = pacer.deadline();
    wake = pacer.wait(clock, ready);
    CHECK(pacer.look_ahead().ran);
    CHECK(pacer.look_ahead().late);
    CHECK(wake == deadline + 50'000);
    pacer.finish(wake);
    // next period: it took 150 us lately and only 100 us are left: skipped, the tick on time
    cost = 1'000;
    deadline = pacer.deadline();
    wake = pacer.wait(clock, ready);
    CHECK(pacer.look_ahead().skipped);
    CHECK(wake == deadline);
    pacer.finish(wake);
    // the memory of the long run fades (1/8 a period): it runs again within a few periods
    int skipped = 1;
    for (int k = 0; k < 200 && pacer.look_ahead().skipped; ++k) {
      wake = pacer.wait(clock, ready);
      pacer.finish(wake);
      skipped += pacer.look_ahead().skipped ? 1 : 0;
    }
    CHECK(pacer.look_ahead().ran);
    CHECK(skipped <= 6);
  }
}

TEST_CASE("Pacer::wait: no slack, no ready() (a lead or margin of 0, the plain wait)", "[anticipate]") {
  constexpr std::int64_t period = 1'000'000;  // [ns]
  for (const PacingMode mode : {PacingMode::sleep, PacingMode::hybrid}) {
    VirtualClock clock;
    PacingConfig none{mode, 0};
    none.look_ahead_ns = mode == PacingMode::hybrid ? 100'000 : 0;  // hybrid uses its margin only
    Pacer pacer(period, none);
    pacer.start(clock.now());
    for (int tick = 0; tick < 5; ++tick) {
      const std::int64_t wake = pacer.wait(clock, []() noexcept { FAIL("ready() with no slack"); });
      CHECK(wake == static_cast<std::int64_t>(tick) * period);
      pacer.finish(wake);
    }
    CHECK(pacer.readied() == 0);
  }
  // the lead is clamped to half a period
  VirtualClock clock;
  PacingConfig wide;
  wide.look_ahead_ns = 900'000;
  Pacer pacer(period, wide);
  pacer.start(clock.now());
  pacer.finish(clock.now());
  std::int64_t called_at = -1;
  (void)pacer.wait(clock, [&]() noexcept { called_at = clock.now(); });
  CHECK(called_at == period / 2);
  PacingConfig bad;
  bad.look_ahead_ns = -1;
  CHECK_THROWS_AS(bad.validate(), std::invalid_argument);
  LoopConfig with_bad;  // the loop refuses it at construction
  with_bad.pacing = bad;
  CHECK_THROWS_AS(with_bad.validate(), std::invalid_argument);
}

TEST_CASE("ServoLoop anticipates every tick but the first, before its deadline, on the last HIP moved one period",
          "[anticipate]") {
  for (const PacingMode mode : {PacingMode::sleep, PacingMode::hybrid}) {
    CAPTURE(static_cast<int>(mode));
    LoopConfig config;
    config.pacing.mode = mode;
    config.pacing.spin_margin_ns = 70'000;
    config.pacing.look_ahead_ns = 130'000;
    const std::int64_t early = mode == PacingMode::hybrid ? 70'000 : 130'000;
    testing::ArmRig rig(testing::ArmRig::free_arm(), config);
    std::vector<Logged::Entry> log;
    log.reserve(1000);
    Logged field{&log, &rig.clock};
    REQUIRE(rig.loop.run(field, {.max_ticks = 300}) == StopReason::tick_limit);
    const LoopSnapshot st = rig.loop.statistics();
    CHECK(st.look_aheads == 299);
    CHECK(st.look_aheads_skipped == 0);
    CHECK(st.look_aheads_late == 0);
    REQUIRE(log.size() == 2 * 300 - 1);
    CHECK(log[0].what == 'f');
    bool moved = false;
    for (std::size_t i = 1; i + 1 < log.size(); i += 2) {
      INFO("entry " << i);
      REQUIRE(log[i].what == 'a');
      REQUIRE(log[i + 1].what == 'f');
      const Probe expected = predicted_probe(log[i - 1].probe, 1e-3);
      CHECK(log[i].probe.position == expected.position);
      CHECK(log[i].probe.time == expected.time);
      CHECK(log[i + 1].at - log[i].at == early);  // in the slack before the deadline
      moved = moved || glm::length(log[i].probe.velocity) > 0.0;
    }
    CHECK(moved);  // the prediction had a velocity to go by
  }
  // off, or a field whose look-ahead does nothing: never, and one plain sleep a period
  for (const bool off : {true, false}) {
    LoopConfig config;
    config.anticipate = !off;
    testing::ArmRig rig(testing::ArmRig::free_arm(), config);
    std::vector<Logged::Entry> log;
    log.reserve(100);
    Logged field{&log, &rig.clock};
    field.ahead = off;                     // (off: the field would; not off: the field says it does nothing)
    rig.clock.shift_next_wake(3'000'000);  // a 3 ms stall in the sleep before tick 1
    rig.loop.run(field, {.max_ticks = 40});
    CHECK(log.size() == 40);
    const LoopSnapshot st = rig.loop.statistics();
    CHECK(st.look_aheads + st.look_aheads_skipped == 0);
    CHECK(st.missed_deadlines == 3);  // the whole stall, seen by the tick's own sleep
  }
}

TEST_CASE("a callback is anticipated only when made with with_anticipation()", "[anticipate]") {
  testing::ArmRig rig(testing::ArmRig::free_arm());
  std::vector<Logged::Entry> log;
  log.reserve(200);
  Logged field{&log, &rig.clock};
  auto callback = [&field](const TickInput& in) noexcept { return field.force(in.probe); };
  rig.loop.run(callback, {.max_ticks = 30});
  CHECK(log.size() == 30);
  log.clear();
  auto ahead = with_anticipation(callback, field);
  rig.loop.run(ahead, {.max_ticks = 30});
  CHECK(log.size() == 59);
  // through AnyField, as the tools and Python pass their fields
  AnyField any(field);
  log.clear();
  auto through_any = [&any](const TickInput& in) noexcept { return any.force(in.probe); };
  auto any_ahead = with_anticipation(through_any, any);
  rig.loop.run(any_ahead, {.max_ticks = 30});
  CHECK(log.size() == 59);
}

TEST_CASE("MultiArmLoop anticipates each arm's field on its own arm's HIP", "[anticipate]") {
  VirtualClock clock;
  SimulatedArm arm_a(testing::ArmRig::free_arm()), arm_b(testing::ArmRig::free_arm());
  SimulatedTransport link_a(arm_a, [&clock] { return clock.now(); });
  SimulatedTransport link_b(arm_b, [&clock] { return clock.now(); });
  ForceArm device_a(link_a), device_b(link_b);
  MultiArmLoop<ForceArm, 2, VirtualClock> loop({&device_a, &device_b}, clock, testing::ArmRig::quiet({}));
  std::vector<Logged::Entry> log_a, log_b;
  log_a.reserve(400);
  log_b.reserve(400);
  Logged a{&log_a, &clock, {0.3, 0.0, 0.0}}, b{&log_b, &clock, {0.0, -0.2, 0.0}};
  REQUIRE(loop.run({.max_ticks = 100}, a, b) == StopReason::tick_limit);
  for (const auto* log : {&log_a, &log_b}) {
    REQUIRE(log->size() == 199);
    for (std::size_t i = 1; i + 1 < log->size(); i += 2) {
      REQUIRE((*log)[i].what == 'a');
      CHECK((*log)[i].probe.position == predicted_probe((*log)[i - 1].probe, 1e-3).position);
      CHECK((*log)[i + 1].at - (*log)[i].at == PacingConfig{}.look_ahead_ns);  // before the deadline
    }
  }
  CHECK(loop.statistics().look_aheads == 99);
  // off (the first arm's setting, which sets the shared timing): never
  LoopConfig off = testing::ArmRig::quiet({});
  off.anticipate = false;
  MultiArmLoop<ForceArm, 2, VirtualClock> quiet({&device_a, &device_b}, clock, off);
  log_a.clear();
  log_b.clear();
  REQUIRE(quiet.run({.max_ticks = 50}, a, b) == StopReason::tick_limit);
  CHECK(log_a.size() == 50);
  CHECK(log_b.size() == 50);
}
