// Every field laid on a curved surface through on_surface (surface/
// on_surface.hpp), felt through the proxy on a SphereShape and on a
// HeightFieldShape: a tangible image, a lattice and an fBm texture, HaTT
// models (vibration and friction), the normals field of Kim & Kwon and
// Coulomb friction. Each tick of a stroke that slides 1 to 2 mm deep along
// the surface is checked against the same field evaluated on the flat plane
// at offset + scale uv (a twin of the field fed the flat probe by hand),
// turned into the touched point's (t, b, n) frame; against a closed form
// where the field has one (the lattice value, mu |Fc|, the picture's force
// at the pixel); in the tangent plane where the field has no normal part;
// and finite always.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core.hpp"
#include "hapticfield/kernels.hpp"
#include "hapticfield/normals/normal_field.hpp"
#include "hapticfield/surface.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"
#include "surface_meshes.hpp"

using namespace hapticfield;
using namespace hapticfield::texture;
using Catch::Matchers::WithinAbs;
using test::probe_at;

namespace {

namespace fs = std::filesystem;
constexpr double pi = std::numbers::pi;
constexpr double k = 1000.0;  // proxy stiffness [N/m]

/// One touching tick as the checks see it.
struct Tick {
  Probe hip;              ///< what the surface field got
  Contact contact;        ///< the proxy's contact of the tick
  glm::dvec3 texture;     ///< F - Fc: the laid field's part [N]
  glm::dvec3 flat_force;  ///< the twin field on the flat plane [N] (flat frame)
  Probe flat;             ///< the flat probe the twin got
  /// How far the touched point's shaded frame (t, b) may be from normal to
  /// the proxy's n [-]: they agree to rounding on the ball; on the sampled
  /// hills to a few 1e-5 inside a cell, but where the proxy rests on a
  /// crease between cells (two or three planes) n points at the crease
  /// line, up to 0.9 degrees (1.5e-2) from the shaded normal (measured on
  /// this stroke). on_surface turns t and b into the plane normal to n, so
  /// the laid field stays exactly normal to n either way.
  double frame_tolerance{1e-9};
  /// The frame on_surface uses: t and b turned into the plane normal to n.
  [[nodiscard]] glm::dvec3 n() const { return contact.normal; }
  [[nodiscard]] glm::dvec3 t() const {
    const glm::dvec3 t0 = contact.surface_tangent;
    return glm::normalize(t0 - glm::dot(t0, n()) * n());
  }
  [[nodiscard]] glm::dvec3 b() const {
    const glm::dvec3 b0 = glm::cross(n(), t());
    return glm::dot(b0, contact.surface_bitangent) < 0.0 ? -b0 : b0;
  }
  /// The twin's force turned into the touched point's frame.
  [[nodiscard]] glm::dvec3 expected() const { return flat_force.x * t() + flat_force.y * b() + flat_force.z * n(); }
};

/// A stroke: the HIP position at tick i (velocity by central difference).
using Path = std::function<glm::dvec3(double)>;
constexpr double dt = 1e-3;  // [s]
constexpr int ticks = 2000;

/// The sphere's stroke: 2 mm above at t = 0, then 1 to 2 mm deep along a
/// wavy path between longitudes 0.6 and 2.6 rad, latitudes within 0.4 rad.
constexpr double radius = 0.03;
glm::dvec3 sphere_path(double t) {
  const double a = 0.6 + 1.0 * t, phi = 0.4 * std::sin(1.3 * t);
  const double r = t <= 0.0 ? radius + 0.002 : radius - 0.0015 - 0.0005 * std::sin(5.0 * t);
  return r * glm::dvec3{std::cos(a) * std::cos(phi), std::sin(a) * std::cos(phi), std::sin(phi)};
}

/// The height field: h = 2 mm sin(2 pi x / 3 cm) cos(2 pi y / 4 cm) over
/// 6 x 6 cm, 0.5 mm apart.
double hills(double x, double y) {
  return 0.002 * std::sin(2.0 * pi * x / 0.03) * std::cos(2.0 * pi * y / 0.04);
}
HeightFieldShape hill_shape() {
  const int n = 121;
  std::vector<double> h;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      h.push_back(hills(i * 5e-4, j * 5e-4));
  return HeightFieldShape(n, n, 5e-4, 5e-4, h);
}
/// A circle of radius 1.5 cm about the centre, 1 to 1.5 mm under the hills.
glm::dvec3 hill_path(double t) {
  const double x = 0.03 + 0.015 * std::cos(1.0 * t), y = 0.03 + 0.015 * std::sin(1.0 * t);
  const double depth = t <= 0.0 ? -0.003 : 0.001 + 0.0005 * std::sin(5.0 * t);
  return {x, y, hills(x, y) - depth};
}

/// uv -> flat metres, so both strokes stay within 10 mm of the flat origin.
const UvMapping sphere_map{{0.06, 0.06}, {-0.045, -0.03}};
const UvMapping hill_map{{0.03, 0.03}, {-0.015, -0.015}};

/// Strokes the field laid on the shape and a twin of it on the flat plane;
/// returns the touching ticks.
template <class S, class F>
std::vector<Tick> stroke(S shape, const F& field, const UvMapping& map, const Path& path, double frame_tolerance) {
  auto surface = contact(ProxyConstraint(std::move(shape), ProxyConfig{k}), on_surface(F(field), map));
  F twin = field;
  std::vector<Tick> out;
  for (int i = 0; i < ticks; ++i) {
    const double t = i * dt;
    Probe hip = probe_at(path(t), (path(t + 0.5 * dt) - path(t - 0.5 * dt)) / dt);
    hip.time = t;
    hip.period = dt;
    const glm::dvec3 f = surface.force(hip);
    REQUIRE(is_finite(f));
    const Contact& c = surface.last_contact();
    if (!c.touching) continue;
    Tick tick{hip, c, f - c.force, glm::dvec3{0.0}, Probe{}, frame_tolerance};
    // the flat plane: position offset + scale uv, velocity in (t, b, n),
    // normal +z, the tick's |Fc|
    Probe& flat = tick.flat;
    const glm::dvec2 at = map.offset + map.scale * c.surface_uv;
    flat.position = {at.x, at.y, 0.0};
    flat.velocity = {glm::dot(hip.velocity, tick.t()), glm::dot(hip.velocity, tick.b()),
                     glm::dot(hip.velocity, tick.n())};
    flat.normal_force = glm::length(c.force);
    flat.surface_normal = {0.0, 0.0, 1.0};
    flat.surface_tangent = {1.0, 0.0, 0.0};
    flat.surface_bitangent = {0.0, 1.0, 0.0};
    flat.surface_uv = c.surface_uv;
    flat.primitive = c.primitive;
    flat.material = c.material;
    flat.time = t;
    flat.period = dt;
    tick.flat_force = twin.force(flat);
    out.push_back(tick);
  }
  return out;
}

/// The checks every field passes: the laid force is the flat one turned
/// into the frame (to 1e-9 of it), of the same magnitude, finite; the frame
/// orthonormal; the stroke touched nearly throughout.
void check_common(const std::vector<Tick>& run) {
  REQUIRE(run.size() > ticks * 9 / 10);
  for (const Tick& s : run) {
    INFO("t = " << s.hip.time);
    REQUIRE(is_finite(s.texture));
    REQUIRE(glm::length(s.texture - s.expected()) <= 1e-9 * (1.0 + glm::length(s.flat_force)));
    const double e = s.frame_tolerance;
    REQUIRE_THAT(glm::length(s.texture), WithinAbs(glm::length(s.flat_force), 1e-9 + e * glm::length(s.flat_force)));
    REQUIRE_THAT(glm::dot(s.t(), s.b()), WithinAbs(0.0, 1e-12));  // t and b: exactly orthonormal
    REQUIRE_THAT(glm::dot(s.t(), s.n()), WithinAbs(0.0, e));
    REQUIRE_THAT(glm::dot(s.b(), s.n()), WithinAbs(0.0, e));
  }
}

/// A field with no normal part pushes in the tangent plane.
void check_tangential(const std::vector<Tick>& run) {
  for (const Tick& s : run) {
    INFO("t = " << s.hip.time);
    REQUIRE_THAT(s.flat_force.z, WithinAbs(0.0, 1e-12));
    // exactly normal to the proxy's n (also at creases, where the shaded
    // frame is up to frame_tolerance off), and within that tolerance of the
    // shaded tangent plane
    REQUIRE_THAT(glm::dot(s.texture, s.n()), WithinAbs(0.0, 1e-9 * (1.0 + glm::length(s.texture))));
    const glm::dvec3 shaded = glm::normalize(glm::cross(s.contact.surface_tangent, s.contact.surface_bitangent));
    REQUIRE_THAT(glm::dot(s.texture, shaded), WithinAbs(0.0, 1e-9 + 2.0 * s.frame_tolerance * glm::length(s.texture)));
  }
}

/// How many ticks carried a force above `level` [N].
int acting(const std::vector<Tick>& run, double level) {
  int n = 0;
  for (const Tick& s : run)
    n += glm::length(s.texture) > level;
  return n;
}

fs::path source_dir() {
  return fs::path(HAPTICFIELD_SOURCE_DIR);
}

fs::path shared_data() {
  if (const char* env = std::getenv("HAPTICFIELD_SHARED_DATA"); env && *env) return fs::path(env);
  const fs::path p = source_dir() / ".." / "shared" / "data";
  return fs::is_directory(p) ? p : fs::path();
}

/// Runs a field on both shapes.
template <class F, class Check>
void on_both(const F& field, Check&& check) {
  {
    INFO("on the sphere");
    const auto run = stroke(SphereShape(SphereShapeConfig{{0, 0, 0}, radius}), field, sphere_map, sphere_path, 1e-9);
    check_common(run);
    check(run);
  }
  {
    INFO("on the height field");
    const auto run = stroke(hill_shape(), field, hill_map, hill_path, 2e-2);
    check_common(run);
    check(run);
  }
}

const NoiseLattice<GaussianNoise, 3> lattice(GaussianNoise(1.0), 11, glm::dvec3{5e-4}, Interpolation::linear);

}  // namespace

TEST_CASE("on a curved surface: a lattice texture scaled by |Fc| is the lattice at the mapped uv, tangential",
          "[surface][fields]") {
  const auto field = TextureField(SpatialSource(lattice), TextureConfig{0.5, 1e-3, true, glm::dvec3{1, 1, 0}});
  on_both(field, [](const std::vector<Tick>& run) {
    check_tangential(run);
    for (const Tick& s : run) {
      // closed form: 0.5 |Fc| (g.x t + g.y b), g the lattice at the flat point
      const glm::dvec3 g = lattice(s.flat.position);
      const double fc = glm::length(s.contact.force);
      REQUIRE(glm::length(s.texture - 0.5 * fc * (g.x * s.t() + g.y * s.b())) < 1e-9);
    }
    CHECK(acting(run, 1e-3) > ticks * 8 / 10);
  });
}

TEST_CASE("on a curved surface: an fBm texture is the fBm at the mapped uv, tangential", "[surface][fields]") {
  const Fbm<GaussianNoise> fbm(lattice, 0.7, 4);
  const auto field = TextureField(SpatialSource(fbm), TextureConfig{0.3, 1e-3, false, glm::dvec3{1, 1, 0}});
  on_both(field, [&fbm](const std::vector<Tick>& run) {
    check_tangential(run);
    for (const Tick& s : run) {
      const glm::dvec3 g = fbm(s.flat.position);  // not scaled by |Fc|: 0.3 N per unit
      REQUIRE(glm::length(s.texture - 0.3 * (g.x * s.t() + g.y * s.b())) < 1e-9);
    }
    CHECK(acting(run, 1e-3) > ticks * 8 / 10);
  });
}

TEST_CASE("on a curved surface: a tangible image pushes toward the picture's darker pixels along the surface",
          "[surface][fields]") {
  const GrayImage gray = load_gray((source_dir() / "examples/data/coffee.png").string());
  const double gain = 1.2;                                         // [N] at a black/white edge
  const PlaneMapping mapping = PlaneMapping::fit(600, 400, 40.0);  // 15 px/mm, centred
  const TangibleImage image(gray, TangibleConfig{});
  const TangibleImageField<TangibleImage> field(image, mapping, gain);
  on_both(field, [&](const std::vector<Tick>& run) {
    check_tangential(run);
    for (const Tick& s : run) {
      // the pixel by hand: 15 px/mm from the centre (299.5, 199.5), y down
      const glm::dvec2 px{299.5 + 15000.0 * s.flat.position.x, 199.5 - 15000.0 * s.flat.position.y};
      const glm::dvec2 a = image.at(px.x, px.y);
      REQUIRE(glm::length(s.texture - gain * (a.x * s.t() - a.y * s.b())) < 1e-9);
    }
    CHECK(acting(run, 0.01) > ticks / 4);
  });
}

TEST_CASE("on a curved surface: Coulomb friction is mu |Fc| against the tangential velocity", "[surface][fields]") {
  const Friction field(FrictionConfig{0.4, 0.0, 0.0, 1e-12, true});
  on_both(field, [](const std::vector<Tick>& run) {
    check_tangential(run);
    for (const Tick& s : run) {
      const glm::dvec3 vt = glm::dot(s.hip.velocity, s.t()) * s.t() + glm::dot(s.hip.velocity, s.b()) * s.b();
      const double fc = glm::length(s.contact.force);
      REQUIRE(glm::length(s.texture + 0.4 * fc * glm::normalize(vt)) < 1e-9);
    }
    CHECK(acting(run, 0.1) > ticks * 8 / 10);
  });
}

TEST_CASE("on a curved surface: HaTT models vibrate along the normal and rub mu |Fc| in the tangent plane",
          "[surface][fields][hatt]") {
  std::vector<fs::path> files{source_dir() / "tests/data/hatt/Models_Synthetic Grid.xml"};
  if (const fs::path shared = shared_data(); !shared.empty()) {
    const fs::path real = shared / "hatt/10000Hz/Models_Sandpaper 100.xml";
    if (fs::exists(real)) files.push_back(real);
  }
  if (files.size() == 1) WARN("the real HaTT model (shared data, hatt/10000Hz) is absent: synthetic models only");
  for (const fs::path& file : files) {
    INFO(file.filename().string());
    const HattModelSet set = load_hatt_model_set(file);
    const HattTexture<> vibration(set, HattConfig{0.05, glm::dvec3{0, 0, 1}, 7, 1, 1e-3, false});
    on_both(vibration, [](const std::vector<Tick>& run) {
      for (const Tick& s : run) {
        REQUIRE(glm::length(glm::cross(s.texture, s.n())) <= 1e-9 * (1.0 + glm::length(s.texture)));  // along n
        REQUIRE(glm::length(glm::dvec2(s.flat_force)) < 1e-12);  // no tangential part in the flat frame
      }
      CHECK(acting(run, 1e-4) > ticks / 2);  // the model did vibrate
    });
    const HattTexture<> rubbing(set, HattConfig{0.0, glm::dvec3{0, 0, 1}, 7, 1, 1e-3, true});
    const double mu = set.mu;
    on_both(rubbing, [mu](const std::vector<Tick>& run) {
      check_tangential(run);
      for (const Tick& s : run) {
        const glm::dvec3 vt = glm::dot(s.hip.velocity, s.t()) * s.t() + glm::dot(s.hip.velocity, s.b()) * s.b();
        REQUIRE(glm::length(s.texture + mu * glm::length(s.contact.force) * glm::normalize(vt)) < 1e-9);
      }
    });
  }
}

TEST_CASE("on a curved surface: the normals field (Kim & Kwon) feels the picture's slopes along the surface",
          "[surface][fields][normals]") {
  // a 200 x 200 px picture of two faces, 6.4 px/mm about the flat origin
  const std::vector<ImageFace> faces{
      {{{0, 0}, {100, 0}, {100, 199}, {0, 199}}, glm::normalize(glm::dvec3{0.4, 0.1, -1.0})},
      {{{100, 0}, {199, 0}, {199, 199}, {100, 199}}, glm::normalize(glm::dvec3{-0.2, 0.5, -1.0})}};
  for (const NormalForceMode mode : {NormalForceMode::along_motion, NormalForceMode::gradient}) {
    INFO((mode == NormalForceMode::gradient ? "gradient" : "along the motion"));
    NormalFieldConfig options;
    options.mode = mode;
    const NormalField field(200, 200, faces, options);
    on_both(field, [&](const std::vector<Tick>& run) {
      check_tangential(run);
      if (mode != NormalForceMode::gradient) return;
      for (const Tick& s : run) {
        // closed form: F_max (n_x, n_y) of the face under the flat point,
        // in image axes (y down the picture: along -b)
        const double px = 99.5 + 6400.0 * s.flat.position.x;
        if (std::fabs(px - 100.0) < 1.0) continue;  // on the faces' shared edge
        const glm::dvec3 n = faces[px < 100.0 ? 0 : 1].normal;
        REQUIRE(glm::length(s.texture - 0.6 * (n.x * s.t() - n.y * s.b())) < 1e-9);
      }
      CHECK(acting(run, 0.01) > ticks / 2);
    });
  }
}

TEST_CASE("on a curved surface: non-finite and extreme probes give finite forces for every field",
          "[surface][fields]") {
  auto field = contact(ProxyConstraint(hill_shape(), ProxyConfig{k}),
                       on_surface(TextureField(SpatialSource(lattice), TextureConfig{0.5, 1e-3, true}), hill_map),
                       on_surface(Friction(FrictionConfig{0.4, 0.0, 0.0, 1e-12, true}), hill_map));
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  (void)field.force(probe_at({0.03, 0.03, 0.01}));
  for (const glm::dvec3 p : {glm::dvec3{0.03, 0.03, -0.002}, glm::dvec3{nan, 0.0, 0.0}, glm::dvec3{0.03, inf, 0.0},
                             glm::dvec3{0.03, 0.03, -1e6}, glm::dvec3{1e300, 1e300, -1e300}})
    for (const glm::dvec3 v : {glm::dvec3{0.0}, glm::dvec3{1e6, -1e6, 0.0}, glm::dvec3{nan, 0.0, 0.0}})
      CHECK(is_finite(field.force(probe_at(p, v))));
}
