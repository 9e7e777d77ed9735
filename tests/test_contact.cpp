// Tests of the contact composition F = Fc + Ft + Ff (core/contact.hpp,
// core/constraints.hpp, core/surface_frame.hpp) and of friction and textures
// acting in the tangent plane of the surface they touch: closed forms for
// Coulomb friction on a wall and on tilted planes, independence of Fc and
// friction from the texture, HaTT model choice by |Fc|, constraints that
// never pull, non-finite input, and zero allocations per tick.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "hapticfield/core.hpp"
#include "hapticfield/texture.hpp"
#include "hapticfield/texture/hatt.hpp"

using namespace hapticfield;
using namespace hapticfield::texture;
using Catch::Matchers::WithinAbs;

namespace {

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();
constexpr double infinity = std::numeric_limits<double>::infinity();

Probe probe_at(glm::dvec3 position, glm::dvec3 velocity = glm::dvec3{0.0}, double stale_normal_force = 0.0) {
  Probe p;
  p.position = position;
  p.velocity = velocity;
  p.normal_force = stale_normal_force;  // whatever the caller had: the composition replaces it
  return p;
}

// Coulomb friction mu [-] x |Fc| with a stick region far below any speed used here
Friction coulomb(double mu, glm::dvec3 configured_normal = glm::dvec3{0.0}) {
  return Friction(FrictionConfig{mu, 0.0, 0.0, 1e-12, true, configured_normal});
}

glm::dvec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    const glm::dvec3 v{g(rng), g(rng), g(rng)};
    const double l = glm::length(v);
    if (l > 1e-3) return v / l;
  }
}

}  // namespace

// --- constraints -------------------------------------------------------------------

TEST_CASE("a plane constraint reports depth, normal and Fc = k depth n inside, nothing outside") {
  const PlaneConstraint wall(PlaneConstraintConfig{glm::dvec3{0.0, 0.0, 0.01}, glm::dvec3{0, 0, 1}, 1000.0, 0.0});
  const Contact in = wall.contact(probe_at({0.02, -0.03, 0.008}));
  CHECK(in.touching);
  CHECK_THAT(in.depth, WithinAbs(2e-3, 1e-15));
  CHECK(in.normal == glm::dvec3{0, 0, 1});
  CHECK_THAT(in.force.z, WithinAbs(2.0, 1e-12));
  CHECK(in.force.x == 0.0);
  CHECK(in.force.y == 0.0);
  CHECK(wall.force(probe_at({0.02, -0.03, 0.008})) == in.force);
  const Contact out = wall.contact(probe_at({0.0, 0.0, 0.0101}));
  CHECK_FALSE(out.touching);
  CHECK(out.force == glm::dvec3{0.0});
  CHECK(out.normal == glm::dvec3{0.0});
  CHECK_FALSE(wall.contact(probe_at({0.0, 0.0, 0.01})).touching);  // on the surface: depth 0, no contact
}

TEST_CASE("a sphere constraint pushes radially out with k (r - |p - c|)") {
  const SphereConstraint ball(SphereConstraintConfig{glm::dvec3{0.01, 0.0, 0.0}, 0.02, 500.0, 0.0});
  const Contact c = ball.contact(probe_at({0.01, 0.0, 0.015}));  // 5 mm inside, above the centre
  CHECK(c.touching);
  CHECK_THAT(c.depth, WithinAbs(5e-3, 1e-15));
  CHECK_THAT(glm::length(c.normal - glm::dvec3{0, 0, 1}), WithinAbs(0.0, 1e-15));
  CHECK_THAT(c.force.z, WithinAbs(2.5, 1e-12));
  const Contact side = ball.contact(probe_at({-0.002, 0.0, 0.0}));  // 8 mm deep along -x
  CHECK_THAT(side.normal.x, WithinAbs(-1.0, 1e-15));
  CHECK_THAT(side.force.x, WithinAbs(-500.0 * 8e-3, 1e-12));
  CHECK(ball.contact(probe_at({0.01, 0.0, 0.0})).normal == glm::dvec3{0, 0, 1});  // the centre: +z by convention
  CHECK_FALSE(ball.contact(probe_at({0.031, 0.0, 0.0})).touching);
}

TEST_CASE("Fc never pulls: damping acts on the normal velocity while penetrating, clipped at zero") {
  const glm::dvec3 n = glm::normalize(glm::dvec3{0.3, -0.2, 1.0});
  const PlaneConstraint plane(PlaneConstraintConfig{glm::dvec3{0.0}, n, 800.0, 20.0});
  // pressing in at 0.05 m/s, 1 mm deep: k d + b |vn| = 0.8 + 1.0 N
  const Contact pressing = plane.contact(probe_at(-1e-3 * n, -0.05 * n));
  CHECK_THAT(glm::dot(pressing.force, n), WithinAbs(1.8, 1e-12));
  // leaving at 0.1 m/s from 1 mm deep: k d - b vn = 0.8 - 2 < 0 -> zero, still touching
  const Contact leaving = plane.contact(probe_at(-1e-3 * n, 0.1 * n));
  CHECK(leaving.touching);
  CHECK(leaving.force == glm::dvec3{0.0});
  // tangential velocity is not damped
  const glm::dvec3 t = glm::normalize(glm::cross(n, glm::dvec3{1, 0, 0}));
  CHECK_THAT(glm::dot(plane.contact(probe_at(-1e-3 * n, 0.3 * t)).force, n), WithinAbs(0.8, 1e-12));
  // random states: Fc . n >= 0 and Fc parallel to n, for the plane and the sphere
  const SphereConstraint ball(SphereConstraintConfig{glm::dvec3{0.0}, 0.02, 1200.0, 15.0});
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> u(-0.03, 0.03), vel(-0.5, 0.5);
  for (int i = 0; i < 2000; ++i) {
    const Probe p = probe_at({u(rng), u(rng), u(rng)}, {vel(rng), vel(rng), vel(rng)});
    for (const Contact& c : {plane.contact(p), ball.contact(p)}) {
      REQUIRE(glm::dot(c.force, c.normal) >= 0.0);
      REQUIRE(glm::length(glm::cross(c.force, c.normal)) <= 1e-12 * (1.0 + glm::length(c.force)));
      REQUIRE(c.touching == (c.depth > 0.0));
    }
  }
}

TEST_CASE("bad constraint parameters throw at setup") {
  using C = PlaneConstraintConfig;
  CHECK_THROWS_AS(PlaneConstraint(C{glm::dvec3{0.0}, glm::dvec3{0, 0, 2}, 1000.0, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(PlaneConstraint(C{glm::dvec3{0.0}, glm::dvec3{0.0}, 1000.0, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(PlaneConstraint(C{glm::dvec3{not_a_number}, glm::dvec3{0, 0, 1}, 1000.0, 0.0}),
                  std::invalid_argument);
  CHECK_THROWS_AS(PlaneConstraint(C{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 0.0, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(PlaneConstraint(C{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, infinity, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(PlaneConstraint(C{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1000.0, -1.0}), std::invalid_argument);
  using S = SphereConstraintConfig;
  CHECK_THROWS_AS(SphereConstraint(S{glm::dvec3{0.0}, 0.0, 1000.0, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(SphereConstraint(S{glm::dvec3{0.0}, 0.01, -5.0, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(SphereConstraint(S{glm::dvec3{0.0, infinity, 0.0}, 0.01, 1000.0, 0.0}), std::invalid_argument);
}

// --- the surface frame ----------------------------------------------------------------

TEST_CASE("the surface frame is orthonormal and right-handed; +z gives the device frame exactly") {
  const SurfaceFrame z = surface_frame(glm::dvec3{0, 0, 1});
  CHECK(z.tangent1 == glm::dvec3{1, 0, 0});
  CHECK(z.tangent2 == glm::dvec3{0, 1, 0});
  CHECK(z.normal == glm::dvec3{0, 0, 1});
  std::mt19937 rng(7);
  std::vector<glm::dvec3> normals{
      {0, 0, -1}, glm::normalize(glm::dvec3{1e-9, 0, -1}), glm::normalize(glm::dvec3{0, 1e-5, -1})};
  for (int i = 0; i < 1000; ++i)
    normals.push_back(random_unit(rng));
  for (const glm::dvec3& n : normals) {
    const SurfaceFrame f = surface_frame(n);
    REQUIRE_THAT(glm::length(f.tangent1), WithinAbs(1.0, 1e-12));
    REQUIRE_THAT(glm::length(f.tangent2), WithinAbs(1.0, 1e-12));
    REQUIRE_THAT(glm::dot(f.tangent1, f.tangent2), WithinAbs(0.0, 1e-12));
    REQUIRE_THAT(glm::dot(f.tangent1, n), WithinAbs(0.0, 1e-12));
    REQUIRE_THAT(glm::dot(f.tangent2, n), WithinAbs(0.0, 1e-12));
    REQUIRE(glm::length(glm::cross(f.tangent1, f.tangent2) - n) < 1e-12);
  }
}

// --- the composition: closed forms ---------------------------------------------------------

TEST_CASE(
    "pressing a wall with 2 N while sliding: Coulomb mu = 0.4 gives 0.8 N against the tangential velocity, same tick") {
  auto field =
      contact(PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1000.0, 0.0}), coulomb(0.4));
  // 2 mm deep at 1000 N/m: |Fc| = 2 N; sliding at 0.1 m/s in (0.6, -0.8), pressing in at 0.01 m/s
  for (double stale : {0.0, 50.0}) {  // the incoming normal_force (e.g. last tick's |F|) is ignored
    const glm::dvec3 f = field.force(probe_at({0.01, 0.02, -2e-3}, {0.06, -0.08, -0.01}, stale));
    CHECK_THAT(field.last_contact().force.z, WithinAbs(2.0, 1e-12));
    CHECK_THAT(f.x, WithinAbs(-0.8 * 0.6, 1e-12));
    CHECK_THAT(f.y, WithinAbs(0.8 * 0.8, 1e-12));
    CHECK_THAT(f.z, WithinAbs(2.0, 1e-12));  // friction has no normal component: Fc alone
  }
  // the same friction on its own, given the tick's |Fc| and normal by hand, agrees
  Probe by_hand = probe_at({0.01, 0.02, -2e-3}, {0.06, -0.08, -0.01}, 2.0);
  by_hand.surface_normal = glm::dvec3{0, 0, 1};
  CHECK(glm::length(coulomb(0.4).force(by_hand) - glm::dvec3{-0.48, 0.64, 0.0}) < 1e-12);
}

TEST_CASE("doubling a texture's amplitude changes nothing in Fc or in the friction") {
  const PlaneConstraint wall(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1500.0, 5.0});
  const NoiseLattice<GaussianNoise, 3> lat(GaussianNoise(1.0), 11, glm::dvec3{5e-4}, Interpolation::linear);
  const auto texture = [&](double gain) {
    return TextureField(SpatialSource(lat), TextureConfig{gain, 1e-3, true, glm::dvec3{1.0, 1.0, 1.0}});
  };
  const Friction friction(FrictionConfig{0.4, 0.8, 0.0, 2e-3, true, glm::dvec3{0.0}});
  auto single = contact(wall, texture(0.3), friction);
  auto twice = contact(wall, texture(0.6), friction);
  auto bare = contact(wall, friction);
  // each field fed its own previous output as normal_force, the way a loop
  // without a contact composition would: through contact() it must not matter
  glm::dvec3 last_single{0.0}, last_twice{0.0}, last_bare{0.0};
  double worst = 0.0;
  int textured = 0;
  for (int i = 0; i < 3000; ++i) {
    const double t = i * 1e-3;
    const glm::dvec3 pos{0.04 * std::sin(2.1 * t), 0.03 * std::cos(1.3 * t), -1e-3 - 5e-4 * std::sin(7.0 * t)};
    const glm::dvec3 vel{0.084 * std::cos(2.1 * t), -0.039 * std::sin(1.3 * t), -3.5e-3 * std::cos(7.0 * t)};
    last_single = single.force(probe_at(pos, vel, glm::length(last_single)));
    last_twice = twice.force(probe_at(pos, vel, glm::length(last_twice)));
    last_bare = bare.force(probe_at(pos, vel, glm::length(last_bare)));
    REQUIRE(single.last_contact().force == bare.last_contact().force);
    REQUIRE(twice.last_contact().force == bare.last_contact().force);
    // F = Fc + Ft + Ff with Ff the same in all three: F2 - Fbare = 2 (F1 - Fbare)
    const glm::dvec3 ft1 = last_single - last_bare;
    const glm::dvec3 ft2 = last_twice - last_bare;
    worst = std::max(worst, glm::length(ft2 - 2.0 * ft1));
    textured += glm::length(ft1) > 0.0;
  }
  CHECK(worst < 1e-12);
  CHECK(textured > 2900);  // the texture did act
}

TEST_CASE("a HaTT texture selects its model by |Fc| of this tick") {
  const HattModelSet s =
      load_hatt_model_set(std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / "tests/data/hatt/Models_Synthetic Grid.xml");
  // vertices (speed [mm/s], force [N]): 1 = (300, 0.5), 3 = (300, 3)
  auto field =
      contact(PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1000.0, 0.0}),
              HattTexture<>(s, HattConfig{0.0, glm::dvec3{0, 0, 1}, 1, 1, 1e-3, true}));  // mass 0: friction only
  const auto uses_model = [&](std::size_t v) {
    const auto a = field.part<0>().ar_coefficients();
    REQUIRE(a.size() == s.models[v].ar_coeff.size() + 1);
    for (std::size_t k = 0; k + 1 < a.size(); ++k)
      if (std::fabs(a[k + 1] - s.models[v].ar_coeff[k]) > 1e-9) return false;
    return true;
  };
  // 3 mm deep -> |Fc| = 3 N; a stale normal force of 0.5 N comes in and is ignored
  glm::dvec3 f = field.force(probe_at({0.0, 0.0, -3e-3}, {0.3, 0.0, 0.0}, 0.5));
  CHECK(uses_model(3));
  CHECK_THAT(f.x, WithinAbs(-0.3 * 3.0, 1e-9));  // HaTT friction mu |Fc|, mu = 0.3
  CHECK_THAT(f.z, WithinAbs(3.0, 1e-9));
  // 0.5 mm deep -> |Fc| = 0.5 N, while the stale value claims 3 N
  f = field.force(probe_at({0.0, 0.0, -0.5e-3}, {0.3, 0.0, 0.0}, 3.0));
  CHECK(uses_model(1));
  CHECK_THAT(f.x, WithinAbs(-0.3 * 0.5, 1e-9));
}

TEST_CASE("a HaTT texture on a tilted plane vibrates along that plane's normal and rubs in its tangent plane") {
  const HattModelSet s =
      load_hatt_model_set(std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / "tests/data/hatt/Models_Synthetic Grid.xml");
  const glm::dvec3 n = glm::normalize(glm::dvec3{0.3, -0.2, 1.0});
  const PlaneConstraint plane(PlaneConstraintConfig{glm::dvec3{0.0}, n, 1000.0, 0.0});
  // The configured normal (+z) is only a fallback: the touched plane's wins.
  auto vibration = contact(plane, HattTexture<>(s, HattConfig{0.05, glm::dvec3{0, 0, 1}, 7, 1, 1e-3, false}));
  auto rubbing = contact(plane, HattTexture<>(s, HattConfig{0.0, glm::dvec3{0, 0, 1}, 7, 1, 1e-3, true}));
  const SurfaceFrame frame = surface_frame(n);
  double largest = 0.0;
  for (int i = 0; i < 500; ++i) {
    // slide along the plane's first tangent, 2 mm deep
    const glm::dvec3 v = 0.2 * frame.tangent1;
    const glm::dvec3 p = -2e-3 * n + static_cast<double>(i) * 1e-3 * v;
    const glm::dvec3 fc = plane.force(probe_at(p, v));
    const glm::dvec3 ft = vibration.force(probe_at(p, v)) - fc;
    const glm::dvec3 ff = rubbing.force(probe_at(p, v)) - fc;
    REQUIRE(glm::length(glm::cross(ft, n)) <= 1e-9 * (1.0 + glm::length(ft)));  // Ft is along n
    REQUIRE(std::fabs(glm::dot(ff, n)) <= 1e-12);                               // Ff lies in the tangent plane
    REQUIRE(glm::dot(ff, v) < 0.0);                                             // and opposes the sliding
    largest = std::max(largest, glm::length(ft));
  }
  CHECK(largest > 1e-3);  // the model did vibrate
}

TEST_CASE("no contact: no texture and no friction, and the parts are not called") {
  auto field =
      contact(PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1000.0, 0.0}),
              TextureField(DistanceSource(NoiseLattice<GaussianNoise, 2>(GaussianNoise(1.0), 3, glm::dvec3{1e-3})),
                           TextureConfig{1.0, 0.0, false, glm::dvec3{1.0}}),  // not force-scaled: would act anywhere
              Friction(FrictionConfig{0.5, 2.0, 0.0, 2e-3, false, glm::dvec3{0.0}}));
  for (int i = 0; i < 100; ++i) {
    const glm::dvec3 f = field.force(probe_at({i * 1e-4, 0.0, 1e-3}, {0.1, 0.0, 0.0}, 2.0));  // 1 mm above
    REQUIRE(f == glm::dvec3{0.0});
    REQUIRE_FALSE(field.last_contact().touching);
  }
  CHECK(field.part<0>().source().distance() == 0.0);
  // touching: both act; reset() forwards to the parts
  CHECK(glm::length(field.force(probe_at({0.0, 0.0, -1e-3}, {0.1, 0.0, 0.0}))) > 1.0);
  (void)field.force(probe_at({2e-3, 0.0, -1e-3}, {0.1, 0.0, 0.0}));
  CHECK_THAT(field.part<0>().source().distance(), WithinAbs(2e-3, 1e-15));
  field.reset();
  CHECK(field.part<0>().source().distance() == 0.0);
  CHECK_FALSE(field.last_contact().touching);
  STATIC_REQUIRE(ResettableField<decltype(field)>);
}

// --- tangent planes of tilted surfaces -----------------------------------------------------------

TEST_CASE("friction on a tilted plane lies in its tangent plane and opposes the tangential velocity") {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> vel(-0.2, 0.2);
  for (int i = 0; i < 500; ++i) {
    glm::dvec3 n = random_unit(rng);
    if (i == 0) n = glm::normalize(glm::dvec3{1.0, 0.0, 1.0});  // 45 degrees about y
    const glm::dvec3 origin{0.01, -0.02, 0.005};
    // configured normal +z: the touched plane's normal must win
    auto field =
        contact(PlaneConstraint(PlaneConstraintConfig{origin, n, 1000.0, 0.0}), coulomb(0.4, glm::dvec3{0, 0, 1}));
    const glm::dvec3 v{vel(rng), vel(rng), vel(rng)};
    const glm::dvec3 vt = v - glm::dot(v, n) * n;
    if (glm::length(vt) < 1e-3) continue;
    const glm::dvec3 f = field.force(probe_at(origin - 1.5e-3 * n, v));
    const double fc = glm::length(field.last_contact().force);
    REQUIRE_THAT(fc, WithinAbs(1.5, 1e-12));
    const glm::dvec3 ff = f - field.last_contact().force;
    REQUIRE_THAT(glm::dot(ff, n), WithinAbs(0.0, 1e-12));
    REQUIRE(glm::length(ff + 0.4 * fc * glm::normalize(vt)) < 1e-12);
  }
}

TEST_CASE("a texture with axes {1, 1, 0} acts only in the tangent plane; {0, 0, 1} only along the normal") {
  const NoiseLattice<GaussianNoise, 3> lat(GaussianNoise(1.0), 5, glm::dvec3{4e-4}, Interpolation::linear);
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) {
    const glm::dvec3 n = random_unit(rng);
    const PlaneConstraint plane(PlaneConstraintConfig{glm::dvec3{0.0}, n, 1000.0, 0.0});
    auto lateral =
        contact(plane, TextureField(SpatialSource(lat), TextureConfig{0.5, 1e-3, true, glm::dvec3{1, 1, 0}}));
    auto bumps = contact(plane, TextureField(SpatialSource(lat), TextureConfig{0.5, 1e-3, true, glm::dvec3{0, 0, 1}}));
    const SurfaceFrame frame = surface_frame(n);
    const glm::dvec3 pos = -1e-3 * n + 0.013 * frame.tangent1 - 0.007 * frame.tangent2;
    const glm::dvec3 v = 0.05 * frame.tangent1 + 0.02 * n;
    const glm::dvec3 ft = lateral.force(probe_at(pos, v)) - lateral.last_contact().force;
    const glm::dvec3 fn = bumps.force(probe_at(pos, v)) - bumps.last_contact().force;
    REQUIRE(glm::length(ft) > 0.0);
    REQUIRE_THAT(glm::dot(ft, n), WithinAbs(0.0, 1e-12));
    REQUIRE(glm::length(glm::cross(fn, n)) < 1e-12);
    // closed form: 0.5 |Fc| (g.x t1 + g.y t2), g the lattice at the HIP
    const glm::dvec3 g = lat(pos);
    REQUIRE(glm::length(ft - 0.5 * 1.0 * (g.x * frame.tangent1 + g.y * frame.tangent2)) < 1e-12);
  }
  // sliding is tangential speed: pressing straight in keeps the texture silent
  auto lateral = contact(PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1000.0, 0.0}),
                         TextureField(SpatialSource(lat), TextureConfig{0.5, 1e-3, true, glm::dvec3{1, 1, 0}}));
  const glm::dvec3 f = lateral.force(probe_at({0.0, 0.0, -1e-3}, {0.0, 0.0, -0.05}));
  CHECK(f == lateral.last_contact().force);
}

TEST_CASE("inside a contact the local circle works in the touched surface's tangent plane") {
  const glm::dvec3 n = glm::normalize(glm::dvec3{1.0, 0.0, 1.0});
  const SurfaceFrame frame = surface_frame(n);
  // configured for a +z surface; the tilted plane's normal must win
  auto field = contact(PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, n, 1000.0, 0.0}),
                       TextureField(LocalSphere<GaussianNoise>(GaussianNoise(1.0), 4, 1e-3, glm::dvec3{0, 0, 1}),
                                    TextureConfig{1.0, 0.0, false, glm::dvec3{1.0}}));
  for (int i = 1; i <= 50; ++i)
    (void)field.force(probe_at(-i * 1e-4 * n, -0.01 * n));  // 5 mm straight in
  CHECK(field.part<0>().source().samples_drawn() == 2);     // the first pair only
  for (int i = 1; i <= 50; ++i)
    (void)field.force(probe_at(-5e-3 * n + i * 1e-4 * frame.tangent1, 0.01 * frame.tangent1));
  CHECK(field.part<0>().source().samples_drawn() >= 6);  // 5 mm along the surface: a sample per mm
}

// --- bad input in a tick, allocation ------------------------------------------------------------

TEST_CASE("non-finite probe data give zero force") {
  auto field = contact(PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, 1000.0, 0.0}),
                       TextureField(TemporalSource(GaussianNoise(1.0), 1), TextureConfig{}), coulomb(0.4));
  CHECK(field.force(probe_at({not_a_number, 0.0, -1e-3}, {0.1, 0.0, 0.0})) == glm::dvec3{0.0});
  CHECK_FALSE(field.last_contact().touching);
  CHECK(field.force(probe_at({0.0, 0.0, infinity}, {0.1, 0.0, 0.0})) == glm::dvec3{0.0});
  CHECK_FALSE(field.last_contact().touching);
  Probe odd = probe_at({0.0, 0.0, -1e-3}, {0.1, 0.0, 0.0}, not_a_number);  // garbage contact data coming in is replaced
  odd.surface_normal = glm::dvec3{not_a_number};
  CHECK(glm::length(field.force(odd)) > 0.0);
  CHECK(is_finite(field.force(odd)));
  // the parts alone: a non-finite surface normal gives zero
  odd.normal_force = 1.0;
  CHECK(coulomb(0.4).force(odd) == glm::dvec3{0.0});
  TextureField tex(TemporalSource(GaussianNoise(1.0), 1), TextureConfig{});
  CHECK(tex.force(odd) == glm::dvec3{0.0});
  TextureField sphere(LocalSphere<GaussianNoise>(GaussianNoise(1.0), 2, 5e-4), TextureConfig{});
  CHECK(sphere.force(odd) == glm::dvec3{0.0});
  CHECK(StickSlipFriction(StickSlipConfig{}).force(odd) == glm::dvec3{0.0});
  const PlaneConstraint plane(PlaneConstraintConfig{});
  CHECK_FALSE(plane.contact(probe_at({0.0, 0.0, -infinity})).touching);
  CHECK(plane.force(probe_at({0.0, 0.0, not_a_number})) == glm::dvec3{0.0});
}

namespace {
/// A part that remembers the velocity it was given and pushes nothing.
struct VelocitySeen {
  glm::dvec3* seen;
  [[nodiscard]] glm::dvec3 force(const Probe& p) noexcept {
    *seen = p.velocity;
    return glm::dvec3{0.0};
  }
};
}  // namespace

TEST_CASE("a non-finite velocity keeps Fc from the position and drops only the damping") {
  const double k = 1000.0, b = 5.0, depth = 2e-3;
  const PlaneConstraint plane(PlaneConstraintConfig{glm::dvec3{0.0}, glm::dvec3{0, 0, 1}, k, b});
  const SphereConstraint ball(SphereConstraintConfig{glm::dvec3{0.0}, 0.02, k, b});
  const glm::dvec3 in_plane{0.01, 0.0, -depth};
  const glm::dvec3 in_ball{0.0, 0.02 - depth, 0.0};
  for (const double bad : {not_a_number, infinity, -infinity}) {
    CAPTURE(bad);
    for (const glm::dvec3 v : {glm::dvec3{bad, 0.0, 0.0}, glm::dvec3{0.0, 0.0, bad}, glm::dvec3{bad}}) {
      // the constraints alone: the spring term k depth n, no damping
      const Contact p = plane.contact(probe_at(in_plane, v));
      CHECK(p.touching);
      CHECK_THAT(p.force.z, WithinAbs(k * depth, 1e-12));
      CHECK(p.force.x == 0.0);
      const Contact s = ball.contact(probe_at(in_ball, v));
      CHECK(s.touching);
      CHECK_THAT(s.force.y, WithinAbs(k * depth, 1e-12));
      // the composition: Fc kept, the parts see a zero velocity
      glm::dvec3 seen{-1.0};
      auto field = contact(PlaneConstraint(plane.config()), VelocitySeen{&seen}, coulomb(0.4));
      const glm::dvec3 f = field.force(probe_at(in_plane, v));
      CHECK(field.last_contact().touching);
      CHECK_THAT(f.z, WithinAbs(k * depth, 1e-12));
      CHECK(is_finite(f));
      CHECK(seen == glm::dvec3{0.0});
      auto on_ball = contact(SphereConstraint(ball.config()), VelocitySeen{&seen});
      CHECK_THAT(on_ball.force(probe_at(in_ball, v)).y, WithinAbs(k * depth, 1e-12));
    }
  }
  // a finite velocity still damps: moving into the plane at 0.1 m/s adds b x 0.1
  CHECK_THAT(plane.contact(probe_at(in_plane, {0.0, 0.0, -0.1})).force.z, WithinAbs(k * depth + b * 0.1, 1e-12));
}

TEST_CASE("a contact composition allocates nothing per tick") {
  const HattModelSet s =
      load_hatt_model_set(std::filesystem::path(HAPTICFIELD_SOURCE_DIR) / "tests/data/hatt/Models_Synthetic Grid.xml");
  const ScalarMap data(2, 2, {0.0f, 1.0f, 0.5f, 0.25f}, PlaneMapping::fit(2, 2, 100.0));
  auto field = contact(
      PlaneConstraint(PlaneConstraintConfig{glm::dvec3{0.0}, glm::normalize(glm::dvec3{0.2, 0.1, 1.0}), 1200.0, 3.0}),
      TextureField(TemporalSource(GaussianNoise(1.0), 1), TextureConfig{0.3, 1e-3, true, glm::dvec3{1, 1, 0}},
                   Butterworth<4>::band_pass(20.0, 200.0, 1000.0)),
      TextureField(LocalSphere<GaussianNoise>(GaussianNoise(1.0), 2, 5e-4),
                   TextureConfig{0.2, 1e-3, true, glm::dvec3{1.0}}),
      Friction(FrictionConfig{0.4, 0.5, 0.0, 2e-3, true, glm::dvec3{0.0}}), StickSlipFriction(StickSlipConfig{}),
      DataModulated(Friction(FrictionConfig{0.2, 0.0, 0.0, 2e-3, true, glm::dvec3{0.0}}), data, 0.5, 1.0),
      HattTexture<>(s, HattConfig{}));
  AnyField erased(contact(SphereConstraint(SphereConstraintConfig{}), coulomb(0.3)));
  glm::dvec3 total{0.0};
  const long allocations = test::count_allocations([&] {
    for (int i = 0; i < 5000; ++i) {
      const double t = i * 1e-3;
      const Probe p = probe_at({0.03 * std::sin(t), 0.02 * std::cos(3 * t), -1e-3 + 2e-3 * std::sin(5 * t)},
                               {0.03 * std::cos(t), -0.06 * std::sin(3 * t), 0.01 * std::cos(5 * t)});
      total += field.force(p) + erased.force(p);
    }
  });
  if (test::allocations_counted) CHECK(allocations == 0);
  CHECK(is_finite(total));
}
