#pragma once
/// @file proxy.hpp
/// ProxyConstraint: the god-object (Zilles & Salisbury, "A constraint-based
/// god-object method for haptic display", IROS 1995) or virtual proxy
/// (Ruspini, Kolarov & Khatib, "The haptic display of complex graphical
/// environments", SIGGRAPH 1997) on any Shape.
///
/// The HIP may sink into the surface; the proxy may not. Each tick the proxy
/// moves toward the HIP as far as the surface lets it:
///
///   1. It sweeps from where it is toward the goal (the HIP at first).
///      Every move is a swept first_hit() query that stops just before the
///      first surface met, so the proxy never crosses a surface, however
///      thin, whatever the speed (no pop-through).
///   2. Each surface met adds its plane (face normal n, through the hit point
///      lifted by the offset) to the constraints of the tick, at most three
///      (an edge: two, a corner: three). The goal becomes the point nearest
///      the HIP on all of them (a least-squares projection with the normal
///      equations of the planes; a plane whose multiplier comes out negative,
///      one the HIP has left, is released). Back to 1, at most six moves.
///      A pass that leaves the proxy off every face (it slid along a plane
///      past a convex edge) starts another from there with no planes, at
///      most four; if the last one still floats the proxy goes back to where
///      it last met a face.
///   A ball (ProxyConfig::radius > 0) that begins a tick free but already
///   overlapping the surface has come through it from behind (a ball is
///   stopped r off the front): it passes on, free, until clear
///   (ProxyTick::embedded), as one begun in the surface does; not on a
///   shape whose closest() sees another surface than its sweeps (a height
///   field: S::closest_matches_sweep false), where overlap is not exact.
///   0. With ProxyConfig::stick_first (the default) and friction, the
///      friction cone is tested first, on last tick's planes (step 3's
///      rule): a proxy that sticks stays where it is, with no sweep; one
///      that slides goes mu_k d behind the HIP's point on them, over its
///      face with no sweep (a point on one flat face) or in one swept move,
///      settled onto the surface by a second where it curves away below.
///      Where that move meets the surface (it curves up ahead), steps 1-2
///      take it on toward the HIP moved by the slide's lag, with no step 3.
///      Where they end past the cone (in a crease whose face the HIP does
///      not press on), the friction is decided once more from there, on the
///      planes the HIP presses, and only if that fails too the full tick
///      runs. Else 1-4.
///   3. Friction (the friction cone of Salisbury et al. 1995 and of Ruspini
///      1997): with d the depth and s the distance the proxy would slide from
///      where it was, it stays where it was (sticks) while s <= mu_s d, and
///      when it slides it lags mu_k d behind, so the tangential force is mu_k
///      times the normal one. In a crease, where it was counts on the faces
///      the HIP presses on from there (the one it came along), not on the
///      crease line. A held point off the surface (a plane's extension past
///      its face, the surface curved away below) or behind it (curved up
///      between) is reached over the surface instead: steps 1-2 toward the
///      HIP moved by the lag, kept when they end inside the cone; else no
///      friction that tick.
///   4. The depth d is measured from the surface point nearest the HIP on
///      this tick's planes without the lift (the face, the crease line or the
///      corner); Fc = max(0, k d - b v.n) n + k (proxy - frictionless proxy):
///      the damping b acts on the normal velocity and never pulls into the
///      surface, the second term is friction's. n is the direction from the
///      HIP to that surface point; with one plane and a shaded normal (mesh
///      vertex normals) the touched point's normal (force shading,
///      Morgenbesser & Srinivasan 1996).
///
/// The offset that keeps the proxy off the surface is relative to the size
/// of the primitive it touches (plus a few rounding units of the
/// coordinates), never absolute, so 20 um and 10 cm triangles both hold.
/// The contact reports the touched point's uv, tangent frame, primitive and
/// material (a closest() query at the proxy), for the parts of a
/// ContactField; last_tick() tells what the tick did, with the nodes its
/// queries visited.
///
/// The first tick (and the first after reset()) puts the proxy at the HIP:
/// a HIP that starts inside a solid is not touching until it has left it
/// (surfaces are one-sided). A query that runs out of its node budget
/// leaves the proxy where it is for that tick (ProxyTick::blocked).
///
/// Shapes that change between ticks (surface/moving_shape.hpp): a shape
/// with advance(time) is advanced at the start of every tick (a changed
/// shape drops the planes held for ProxyConfig::stick_first); one that also
/// has carry(p) and surface_velocity(p) moves rigidly: the proxy is first
/// carried with it (it keeps its place in the shape's frame, so the move
/// toward the HIP runs, in effect, in the shape's frame, where the shape is
/// still), and the damping acts on the HIP's velocity relative to the
/// surface's at the proxy. Static shapes take none of these steps.
///
/// anticipate(next) runs the tick `next` would make on a copy of the proxy
/// and drops it: the servo loop calls it in the slack before each
/// deadline, so the tree's nodes and triangles the coming tick reads are in
/// cache when it runs (after 1 ms asleep a tick otherwise meets many of
/// them in memory: docs/surfaces.md, Cost). A ball keeps the region of the
/// tree the copy's sweeps gathered (its sweep cache, whose use never
/// changes an answer), so the tick does not gather it again. Static shapes
/// whose queries change nothing (PureQueries) only.

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/contact.hpp"
#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/surface/shape.hpp"

namespace hapticfield {

/// Most proxy moves (swept queries) in one pass of a tick.
inline constexpr int proxy_max_moves = 6;
/// Most passes in one tick: a pass that leaves the proxy off every face (it
/// slid past a convex edge) is followed by another from there; the passes
/// make at most proxy_max_passes x proxy_max_moves swept queries, with a
/// closest() after each pass. Besides: the friction move (one sweep, or,
/// where the surface curves between, the passes once more over it), or
/// step 0's slide and settling sweeps (ProxyConfig::stick_first) and, when
/// the motion it hands on ends past the cone, the passes once more where it
/// ended and, if that fails too, the full tick from the start.
inline constexpr int proxy_max_passes = 4;
/// Most points of the path the proxy takes in one tick (its start, the end
/// of every swept move and the friction move): last_path().
inline constexpr int proxy_max_path = 2 * proxy_max_passes * proxy_max_moves + 3;

/// The proxy's path in one tick: points[0] is where it started, each next
/// point the end of one straight piece, the last where it stays. Every
/// piece was swept against the shape (or lies over one flat face), so it
/// never enters the surface from the front (surface/proxy_check.hpp checks
/// it against a brute-force scan).
struct ProxyPath {
  std::array<glm::dvec3, proxy_max_path> points{};  ///< [m]; only the first `count` are set
  int count{0};
};

/// ProxyConfig::tick_node_budget's default: twice a mesh query's own
/// budget (bvh_default_max_nodes), about 4x the 99th percentile of a 2 mm
/// ball's tick on bench_surface's million-triangle sheet.
inline constexpr std::uint32_t proxy_default_tick_node_budget = 8192;

struct ProxyConfig {
  double stiffness{1500.0};      ///< k [N/m]
  double damping{0.0};           ///< b on the normal velocity while touching [N s/m]
  double static_friction{0.0};   ///< mu_s [-]: the proxy sticks while the HIP is inside this cone
  double dynamic_friction{0.0};  ///< mu_k [-] <= mu_s: the cone while sliding
  double offset{1e-6};           ///< the proxy's height above the surface, relative to the primitive's size [-]
  /// Test the friction cone first, on last tick's planes at the held point
  /// (step 0 in the file comment): a stuck proxy makes no swept query, a
  /// sliding one one or two. Off: the cone is tested against the
  /// frictionless proxy, found by sweeping over the surface (on a curved
  /// mesh, several moves up to mu d away, then the friction move back). On
  /// a flat face the two agree; on a curved mesh they differ a little
  /// (stick or slide near the cone's edge), both keeping the force within
  /// a few % of the cone.
  bool stick_first{true};
  /// The tool's radius [m], 0..proxy_max_radius: 0, a point (the god-object
  /// proper); > 0, a ball centred on the HIP whose moves are swept spheres
  /// against the shape (its Minkowski sum: faces, edge cylinders, corner
  /// balls), so it rests r above a plane and never enters a crack narrower
  /// than 2 r. The shape must answer sweep_sphere() for a radius > 0.
  double radius{0.0};
  /// Most tree nodes (or grid cells) all the queries of one tick may visit
  /// together, where the shape counts them: once past it the tick makes no
  /// further move, and the proxy stays where it has got to, every piece of
  /// its path swept (ProxyTick::blocked). The worst tick then visits at most
  /// this plus the budget of the one query that crossed it (a mesh's
  /// MeshShapeConfig::max_nodes) and of the closest() queries that follow
  /// (one per pass); without it, up to 4 x proxy_max_passes x
  /// proxy_max_moves + 3 queries of a full budget each.
  std::uint32_t tick_node_budget{proxy_default_tick_node_budget};
};

/// Largest tool radius a proxy takes [m].
inline constexpr double proxy_max_radius = 0.05;

/// What the last tick did (for tests and benches).
struct ProxyTick {
  int moves{0};   ///< swept queries made (friction's one included)
  int planes{0};  ///< constraint planes at the end of the tick (0..3)
  std::uint32_t nodes{
      0};               ///< tree nodes (or grid cells) visited by all the tick's queries, where the shape counts them
  bool blocked{false};  ///< a query ran out of its budget, or the tick of its own: the proxy stayed
  bool sliding{false};  ///< friction: the proxy slides (else sticks)
  /// Step 0 (ProxyConfig::stick_first) finished the tick: the proxy stuck,
  /// or slid along the planes of the tick before (and settled onto the
  /// surface below), with no constrained motion.
  bool held_first{false};
  /// A ball that began overlapping the surface (at the first tick, after
  /// reset(), or come through it from behind): it follows the HIP with no
  /// force until it is clear of it.
  bool embedded{false};
};

template <Shape S>
class ProxyConstraint {
 public:
  /// @throws std::invalid_argument for a stiffness that is not finite and
  ///         > 0, a negative or non-finite damping, friction coefficients
  ///         that are not 0 <= mu_k <= mu_s (finite), or an offset outside
  ///         (0, 0.01].
  ProxyConstraint(S shape, const ProxyConfig& config) : shape_(std::move(shape)), config_(config) {
    if (!std::isfinite(config.stiffness) || config.stiffness <= 0.0)
      throw std::invalid_argument("ProxyConstraint: stiffness must be finite and > 0 [N/m]");
    if (!std::isfinite(config.damping) || config.damping < 0.0)
      throw std::invalid_argument("ProxyConstraint: damping must be finite and >= 0 [N s/m]");
    if (!std::isfinite(config.static_friction) || !std::isfinite(config.dynamic_friction) ||
        config.dynamic_friction < 0.0 || config.dynamic_friction > config.static_friction)
      throw std::invalid_argument("ProxyConstraint: need 0 <= dynamic_friction <= static_friction [-]");
    if (!std::isfinite(config.offset) || config.offset <= 0.0 || config.offset > 0.01)
      throw std::invalid_argument("ProxyConstraint: offset must be in (0, 0.01] (relative to a primitive's size)");
    if (!std::isfinite(config.radius) || config.radius < 0.0 || config.radius > proxy_max_radius)
      throw std::invalid_argument("ProxyConstraint: radius must be in [0, 0.05] [m]");
    if (config.radius > 0.0 && !sweeps_spheres)
      throw std::invalid_argument("ProxyConstraint: this shape has no sweep_sphere(), so the tool's radius must be 0");
  }

  /// The contact of this tick; moves the proxy. A non-finite position gives
  /// no contact and leaves the proxy where it is; a non-finite velocity
  /// only drops the damping (Fc from the position stays).
  [[nodiscard]] Contact contact(const Probe& probe) noexcept {
    tick_ = ProxyTick{};
    path_.count = 0;
    if constexpr (advances) {
      if (shape_.advance(probe.time)) {
        held_planes_ = Planes{};
        if constexpr (!carries)
          if (started_ && touching_) lift(face_);
      }
      if constexpr (carries)
        if (started_) proxy_ = shape_.carry(proxy_);
    }
    if (!is_finite(probe.position)) return Contact{};
    // a moving shape keeps a non-finite velocity for relative() to drop
    const glm::dvec3 velocity = is_finite(probe.velocity) || carries ? probe.velocity : glm::dvec3{0.0};
    const glm::dvec3 goal = probe.position;
    if (!started_ || !is_finite(proxy_)) {
      started_ = true;
      touching_ = false;
      return follow_free(goal);
    }
    if (embedded_) return follow_free(goal);  // a ball that began in the surface, until it is clear of it
    const glm::dvec3 start = proxy_;
    visit(start);
    // where the constrained motion heads: the HIP, or, when step 0 has
    // decided the friction but could not finish the move, the HIP moved by
    // the friction's lag (its point on the planes is where the proxy holds)
    glm::dvec3 aim = goal;
    bool friction_decided = false;
    Motion m{start};
    const bool was_sliding = sliding_;
    if (config_.stick_first) {  // 0: the friction cone first
      Contact held;
      const FrictionFirst first = stick(probe.position, velocity, held, aim, m);
      if (first == FrictionFirst::held) return held;
      friction_decided = first == FrictionFirst::aimed;  // (from where its slide met the surface)
      if (!friction_decided) path_.count = 1;
    }
    // 1-2: constrained motion toward the aim
    move_toward(aim, start, m);
    if (friction_decided && !m.embedded && !m.blocked && !in_cone(goal, m) && !decide_again(goal, m)) {
      // the lag step 0 chose on last tick's planes does not hold where the
      // proxy came to (over a crest: past the cone, off the surface, or on
      // a plane the HIP does not press on): the full tick, as if step 0 had
      // not run; with the tick's budget spent, the proxy stays (blocked)
      path_.count = 1;
      m = Motion{start};
      friction_decided = false;
      sliding_ = was_sliding;
      if (tick_.nodes < config_.tick_node_budget)
        move_toward(goal, start, m);
      else
        m.blocked = true;
    }
    if (m.embedded) {
      // a free ball that overlaps the surface where it starts came through
      // it from behind (a ball is stopped r off the front): it passes on,
      // free, until clear, as a ball begun in the surface
      const Contact none = follow_free(goal);
      tick_.embedded = true;  // it overlapped where it began this tick
      return none;
    }
    glm::dvec3 x = m.x;
    Planes planes = m.planes;
    const Hit& last_hit = m.last_hit;
    Hit touched = m.touched;
    const bool blocked = m.blocked;
    // the frictionless proxy: where the motion ended, or, aimed, the HIP's
    // point on its planes
    glm::dvec3 frictionless = friction_decided ? planes.project_equal(goal) : x;

    // the surface point the HIP is pushed toward: the nearest point to the
    // HIP on this tick's planes without the proxy's lift (the face, the
    // crease line or the corner itself); the depth is measured from it
    glm::dvec3 on_surface = planes.project_equal(goal, false);
    double depth = glm::length(on_surface - goal);  // [m]

    // 3: friction cone
    if (friction_decided) {  // step 0 decided it (sliding_)
      if (planes.count == 0) sliding_ = false;
    } else if (planes.count > 0 && touching_ && !blocked && config_.static_friction > 0.0 && depth > 0.0) {
      // where the proxy was, on this tick's constraints
      const glm::dvec3 held = held_point(planes, start);
      const glm::dvec3 slide = held - frictionless;
      const double s = glm::length(slide);
      const double mu = sliding_ ? config_.dynamic_friction : config_.static_friction;
      glm::dvec3 candidate = held;
      if (s > mu * depth) {
        sliding_ = true;
        candidate = frictionless + (config_.dynamic_friction * depth / s) * slide;
      } else {
        sliding_ = false;
      }
      if (glm::length(candidate - frictionless) > planes.tolerance) {
        const double within = reach(planes);  // [m]
        if (Hit same = on_same_face(candidate, within, touched); planes.count == 1 && over_face(same, candidate)) {
          x = candidate;  // both ends over one flat face: nothing can lie between them
          visit(x);
          touched = same;
        } else if (tick_.nodes < config_.tick_node_budget) {  // (else the tick's budget is spent: frictionless)
          bool replanned = false;  // the proxy ends where `back` has it, on other planes than the frictionless motion's
          Motion back{frictionless};
          const Hit h = sweep(frictionless, candidate, &planes.normal[0]);
          ++tick_.moves;
          if (h.complete && !h.found()) {
            // held where it is still on the surface; a plane's extension
            // past the end of its face is not (the surface curved away below)
            const Hit there = nearest(candidate, within, touched);
            if (there.found()) {
              x = candidate;
              visit(x);
              touched = there;
            } else {
              back.x = candidate;  // off the surface: from there, down onto it
              visit(candidate);
              back.last_hit = touched;
              replanned = follow_surface(goal, frictionless, candidate, back);
            }
          } else if (h.complete) {  // the surface curves up between: from where the move met it
            back.planes = planes;
            back.last_hit = h;
            if (!stop_at(h, candidate - frictionless, glm::length(candidate - frictionless), back.x, back.planes))
              visit(frictionless);  // (three planes held already: it stays, frictionless)
            else
              replanned = follow_surface(goal, frictionless, candidate, back);
          }
          if (replanned) {  // held on the planes it came to: the force from those, as step 0's next tick
            x = back.x;
            touched = back.touched;
            planes = back.planes;
            frictionless = planes.project_equal(goal);
            on_surface = planes.project_equal(goal, false);
            depth = glm::length(on_surface - goal);
          }
        }
      }
    } else if (planes.count == 0) {
      sliding_ = false;  // a new contact starts stuck
    }
    tick_.planes = planes.count;
    tick_.sliding = sliding_;
    tick_.blocked = blocked;

    proxy_ = x;
    const bool touching = planes.count > 0 || (blocked && touching_);
    touching_ = touching;
    if (config_.stick_first) {  // what step 0 starts from next tick
      held_planes_ = touching && !blocked ? planes : Planes{};
      held_face_ = touched.found() ? touched : last_hit;
    }
    if constexpr (advances && !carries) face_ = touched.found() ? touched : last_hit;
    if (!touching) return Contact{};

    return respond(goal, relative(velocity, x), planes, x, frictionless, on_surface, depth,
                   touched.found() ? touched : last_hit);
  }

  /// Fc alone [N].
  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept { return contact(probe).force; }

  /// The tick `next` would make, run on a copy of this proxy and dropped:
  /// no answer of the next tick changes, but the tree nodes and triangles
  /// that tick reads are in cache when it comes (core/field.hpp,
  /// AnticipatingField). A ball keeps the copy's sweep cache (a mesh's
  /// region of the tree, gathered where the copy swept): the tick answers
  /// the same with any region, and where it sweeps as the copy did it does
  /// not gather one again (its ProxyTick::nodes count fewer; so a tick that
  /// would run out of ProxyConfig::tick_node_budget without the look-ahead
  /// may not with it, and answer differently). Only on a
  /// shape that stands still (no advance(): a moving shape's would take its
  /// pose feed's newest pose) and whose queries change nothing
  /// (PureQueries); on any other, nothing is done.
  void anticipate(const Probe& next) const noexcept {
    anticipate_with(next, [](ProxyConstraint&) noexcept {});
  }
  /// anticipate() with the material the next tick will be given first
  /// (set_material()'s arguments): a material surface reads its map at the
  /// proxy's held point before each tick.
  void anticipate(const Probe& next, double stiffness, double damping, double static_friction,
                  double dynamic_friction) const noexcept {
    anticipate_with(next, [&](ProxyConstraint& scratch) noexcept {
      (void)scratch.set_material(stiffness, damping, static_friction, dynamic_friction);
    });
  }
  /// True when anticipate() does something (the shape stands still and is
  /// PureQueries).
  [[nodiscard]] static constexpr bool looks_ahead() noexcept { return anticipates; }

  /// Forgets the proxy: the next tick starts it at the HIP.
  void reset() noexcept {
    started_ = false;
    touching_ = false;
    embedded_ = false;
    sliding_ = false;
    proxy_ = glm::dvec3{0.0};
    held_planes_ = Planes{};
    held_face_ = Hit{};
    hint_ = no_primitive;
    sweep_cache_ = SweepCache{};
  }

  /// The proxy's position [m] (on the surface while touching, else the HIP).
  [[nodiscard]] const glm::dvec3& proxy() const noexcept { return proxy_; }
  [[nodiscard]] bool touching() const noexcept { return touching_; }
  [[nodiscard]] const ProxyTick& last_tick() const noexcept { return tick_; }
  /// The path the proxy took in the last tick (ProxyPath).
  [[nodiscard]] const ProxyPath& last_path() const noexcept { return path_; }
  [[nodiscard]] const S& shape() const noexcept { return shape_; }
  [[nodiscard]] const ProxyConfig& config() const noexcept { return config_; }
  /// Tick-safe: the surface's material from the next move on (a material
  /// map sampled at the touched point, material/material_surface.hpp).
  /// Never throws: stiffness [N/m] is kept > 0, damping [N s/m] and mu_s
  /// [-] >= 0, mu_k [-] in [0, mu_s]; false (nothing changed) when a value
  /// is not finite.
  bool set_material(double stiffness, double damping, double static_friction, double dynamic_friction) noexcept {
    if (!std::isfinite(stiffness) || !std::isfinite(damping) || !std::isfinite(static_friction) ||
        !std::isfinite(dynamic_friction))
      return false;
    config_.stiffness = std::fmax(stiffness, 1e-9);
    config_.damping = std::fmax(damping, 0.0);
    config_.static_friction = std::fmax(static_friction, 0.0);
    config_.dynamic_friction = std::clamp(dynamic_friction, 0.0, config_.static_friction);
    return true;
  }

 private:
  /// The constraint planes of one tick: n . x >= c.
  struct Planes {
    std::array<glm::dvec3, 3> normal{};
    std::array<double, 3> c{};
    std::array<double, 3> lift{};  ///< each plane's offset above its surface [m]
    std::array<std::uint32_t, 3> primitive{no_primitive, no_primitive, no_primitive};  ///< the face each lies on
    int count{0};
    int active{0};           ///< the first `active` planes bind (after release)
    double tolerance{0.0};   ///< smallest offset seen: motions below it are none [m]
    double max_offset{0.0};  ///< largest offset seen [m]

    /// Adds a plane (of face `face`); false when three are held already.
    bool add(const glm::dvec3& n, double offset_c, double eps, std::uint32_t face) noexcept {
      tolerance = count == 0 ? 0.01 * eps : std::fmin(tolerance, 0.01 * eps);
      max_offset = std::fmax(max_offset, eps);
      for (int i = 0; i < count; ++i)
        if (glm::dot(normal[static_cast<std::size_t>(i)], n) > 1.0 - 1e-12) {  // the same plane again
          if (offset_c > c[static_cast<std::size_t>(i)]) {
            c[static_cast<std::size_t>(i)] = offset_c;
            lift[static_cast<std::size_t>(i)] = eps;
            primitive[static_cast<std::size_t>(i)] = face;
          }
          return true;
        }
      if (count == 3) return false;
      normal[static_cast<std::size_t>(count)] = n;
      c[static_cast<std::size_t>(count)] = offset_c;
      lift[static_cast<std::size_t>(count)] = eps;
      primitive[static_cast<std::size_t>(count)] = face;
      ++count;
      return true;
    }

    /// The point nearest to g on the planes, as equalities, with multipliers
    /// lambda (x = g + sum lambda_i n_i); false when the planes are
    /// dependent (parallel, or three through one line).
    bool solve(const glm::dvec3& g, int m, glm::dvec3& x, std::array<double, 3>& lambda,
               bool lifted = true) const noexcept {
      std::array<double, 3> r{};
      for (int i = 0; i < m; ++i)
        r[static_cast<std::size_t>(i)] = c[static_cast<std::size_t>(i)] -
                                         (lifted ? 0.0 : lift[static_cast<std::size_t>(i)]) -
                                         glm::dot(normal[static_cast<std::size_t>(i)], g);
      lambda = {0.0, 0.0, 0.0};
      if (m == 1) {
        lambda[0] = r[0];
      } else if (m == 2) {
        const double g12 = glm::dot(normal[0], normal[1]);
        const double det = 1.0 - g12 * g12;
        if (!(det > 1e-10)) return false;
        lambda[0] = (r[0] - g12 * r[1]) / det;
        lambda[1] = (r[1] - g12 * r[0]) / det;
      } else if (m == 3) {
        // x - g = N^T lambda with N n_i . x = c_i: the Gram system G lambda = r by Cramer
        const glm::dvec3 &a = normal[0], &b = normal[1], &e = normal[2];
        const double det = glm::dot(a, glm::cross(b, e));  // of the normals: G = N N^T, det G = det^2
        if (!(det * det > 1e-10)) return false;
        // x = g + d with n_i . d = r_i: d = (r0 (b x e) + r1 (e x a) + r2 (a x b)) / det
        const glm::dvec3 d = (r[0] * glm::cross(b, e) + r[1] * glm::cross(e, a) + r[2] * glm::cross(a, b)) / det;
        x = g + d;
        // lambda from N^T lambda = d: lambda_i = d . (dual basis)
        const double g01 = glm::dot(a, b), g02 = glm::dot(a, e), g12 = glm::dot(b, e);
        const double m00 = 1.0 - g12 * g12, m01 = g02 * g12 - g01, m02 = g01 * g12 - g02;
        const double m11 = 1.0 - g02 * g02, m12 = g01 * g02 - g12, m22 = 1.0 - g01 * g01;
        const double gd = det * det;
        lambda[0] = (m00 * r[0] + m01 * r[1] + m02 * r[2]) / gd;
        lambda[1] = (m01 * r[0] + m11 * r[1] + m12 * r[2]) / gd;
        lambda[2] = (m02 * r[0] + m12 * r[1] + m22 * r[2]) / gd;
        return true;
      }
      x = g;
      for (int i = 0; i < m; ++i)
        x += lambda[static_cast<std::size_t>(i)] * normal[static_cast<std::size_t>(i)];
      return true;
    }

    void remove(int i) noexcept {
      for (int k = i; k + 1 < count; ++k) {
        normal[static_cast<std::size_t>(k)] = normal[static_cast<std::size_t>(k + 1)];
        c[static_cast<std::size_t>(k)] = c[static_cast<std::size_t>(k + 1)];
        lift[static_cast<std::size_t>(k)] = lift[static_cast<std::size_t>(k + 1)];
        primitive[static_cast<std::size_t>(k)] = primitive[static_cast<std::size_t>(k + 1)];
      }
      --count;
    }

    /// The point nearest to g with every held plane binding whose
    /// multiplier stays >= 0; planes that would pull (the HIP left them)
    /// or are dependent on the others are dropped.
    glm::dvec3 project(const glm::dvec3& g) noexcept {
      for (;;) {
        glm::dvec3 x{0.0};
        std::array<double, 3> lambda{};
        if (!solve(g, count, x, lambda)) {
          remove(count - 1);  // dependent: drop the newest
          continue;
        }
        int worst = -1;
        double most_negative = 0.0;
        for (int i = 0; i < count; ++i)
          if (lambda[static_cast<std::size_t>(i)] < most_negative) {
            most_negative = lambda[static_cast<std::size_t>(i)];
            worst = i;
          }
        if (worst < 0) return x;
        remove(worst);
      }
    }

    /// The point nearest to g on all held planes as equalities (g itself
    /// when they are dependent); lifted false: on the surfaces themselves,
    /// without the proxy's lift.
    [[nodiscard]] glm::dvec3 project_equal(const glm::dvec3& g, bool lifted = true) const noexcept {
      glm::dvec3 x{0.0};
      std::array<double, 3> lambda{};
      return solve(g, count, x, lambda, lifted) ? x : g;
    }
  };

  /// Where the constrained motion (steps 1-2) has the proxy.
  struct Motion {
    glm::dvec3 x{0.0};     ///< where it is [m]
    Planes planes{};       ///< the planes it is held to
    Hit last_hit{};        ///< the face it met last
    Hit touched{};         ///< the face it ends on (found: on the surface)
    bool blocked{false};   ///< a query, or the tick, ran out of its budget
    bool embedded{false};  ///< a free ball met the surface it overlaps where it started
  };

  /// 4: the force and what the parts see, for the proxy at x on `planes`
  /// (the HIP's surface point on_surface, depth [m], the touched face).
  [[nodiscard]] Contact respond(const glm::dvec3& goal, const glm::dvec3& velocity, const Planes& planes,
                                const glm::dvec3& x, const glm::dvec3& frictionless, const glm::dvec3& on_surface,
                                double depth, const Hit& touched) noexcept {
    glm::dvec3 n = planes.count == 1 ? planes.normal[0] : (depth > 0.0 ? (on_surface - goal) / depth : glm::dvec3{0.0});
    if (glm::length(n) == 0.0 && touched.found()) n = touched.face_normal;
    // force shading: the touched point's interpolated normal (the touched
    // face may be the next one past a convex edge, within a few offsets)
    if (planes.count == 1 && touched.found() && glm::dot(touched.normal, n) > 0.5) n = touched.normal;
    if (!is_finite(n) || glm::length(n) == 0.0) n = glm::dvec3{0.0, 0.0, 1.0};
    const double push = config_.stiffness * depth - config_.damping * glm::dot(velocity, n);  // [N]
    const glm::dvec3 force = (push > 0.0 ? push : 0.0) * n + config_.stiffness * (x - frictionless);
    if (!is_finite(force)) {  // never with finite inputs; the proxy starts again at the HIP next tick
      started_ = false;
      touching_ = false;
      return Contact{};
    }
    Contact c;
    c.touching = true;
    c.depth = depth;
    c.normal = n;
    c.force = force;
    if (touched.found()) {
      c.surface_uv = touched.uv;
      c.surface_tangent = touched.tangent;
      c.surface_bitangent = touched.bitangent;
      c.primitive = touched.primitive;
      c.material = touched.material;
    }
    return c;
  }

  /// What step 0 (stick()) did: held the proxy (the tick is done), decided
  /// the friction and left the move to the constrained motion toward an
  /// aim, or nothing (the full tick).
  enum class FrictionFirst { held, aimed, full };

  /// The friction cone first (Salisbury et al. 1995), on last tick's
  /// planes at the point the proxy holds: while the HIP presses on every
  /// one of them, the proxy sticks inside the cone, or slides mu_k d behind
  /// the HIP's point on them outside it, as steps 1-3 would on a flat face.
  /// A stuck proxy does not move. A sliding one ends over the face it
  /// touched (a point on one flat, convex face: nothing lies between, no
  /// sweep), or its move is swept and held where the surface still is
  /// within reach, or settled onto it where it curved away below (held).
  /// A move that meets the surface (it curves up ahead) stops there with
  /// the friction decided (aimed): the constrained motion goes on from
  /// there (`from`: the point, the plane met) toward `aim`, the HIP moved
  /// by the slide's lag. Anything else takes the full tick.
  [[nodiscard]] FrictionFirst stick(const glm::dvec3& goal, const glm::dvec3& velocity, Contact& out, glm::dvec3& aim,
                                    Motion& from) noexcept {
    if (!config_.stick_first || !touching_ || !(config_.static_friction > 0.0) || held_planes_.count == 0 ||
        !held_face_.found())
      return FrictionFirst::full;
    Planes planes = held_planes_;
    glm::dvec3 frictionless = planes.project(goal);
    if (planes.count != held_planes_.count) return FrictionFirst::full;  // the HIP has left a plane
    glm::dvec3 on_surface = planes.project_equal(goal, false);
    double depth = glm::length(on_surface - goal);
    if (!(depth > 0.0)) return FrictionFirst::full;
    const glm::dvec3 held = held_point(planes, proxy_);
    const glm::dvec3 slide = held - frictionless;
    const double s = glm::length(slide);
    const bool sliding = s > (sliding_ ? config_.dynamic_friction : config_.static_friction) * depth;
    glm::dvec3 x = sliding ? frictionless + (config_.dynamic_friction * depth / s) * slide : held;
    if (!is_finite(x)) return FrictionFirst::full;
    const double within = reach(planes);  // [m]
    Hit touched = on_same_face(x, within, held_face_);
    if (planes.count != 1 || !over_face(touched, x)) {
      // not one flat face under both ends (a ball, a crease, past an edge)
      const double length = glm::length(x - proxy_);  // [m]
      // a slide longer than the depth (and the radius) is no small step
      // along the surface (a flick, a jump of the HIP): the full tick
      if (length > std::fmax(depth, config_.radius)) return FrictionFirst::full;
      if (length > planes.tolerance) {
        const Hit h = sweep(proxy_, x, &planes.normal[0]);
        ++tick_.moves;
        if (!h.complete) return FrictionFirst::full;
        if (h.found()) {  // the surface rises ahead: the constrained motion goes on from where it met it
          sliding_ = sliding;
          aim = goal + (x - frictionless);
          from = Motion{proxy_};  // with the planes this tick meets (the held one may end where it met this)
          (void)stop_at(h, x - proxy_, length, from.x, from.planes);
          from.last_hit = h;
          return FrictionFirst::aimed;
        }
        touched = nearest(x, within, held_face_);
        if (!touched.found() && !settle(goal, length, planes, x, frictionless, on_surface, depth, touched))
          return FrictionFirst::full;
      } else if (!touched.found()) {
        touched = nearest(x, within, held_face_);
      }
      if (!touched.found()) return FrictionFirst::full;
    }
    tick_.planes = planes.count;
    sliding_ = sliding;
    tick_.sliding = sliding;
    tick_.held_first = true;
    proxy_ = x;
    visit(x);
    held_planes_ = planes;
    held_face_ = touched;
    if constexpr (advances && !carries) face_ = touched;
    out = respond(goal, relative(velocity, x), planes, x, frictionless, on_surface, depth, touched);
    return FrictionFirst::held;
  }

  /// Steps 1-2 from where m has the proxy toward `aim` (the HIP, or the
  /// HIP moved by a friction lag decided in step 0): swept moves, each
  /// surface met adding its plane, up to proxy_max_moves a pass, and a new
  /// pass from wherever a pass leaves the proxy off every face, up to
  /// proxy_max_passes (then back to where it last met a face).
  void move_toward(const glm::dvec3& aim, const glm::dvec3& start, Motion& m) noexcept {
    glm::dvec3 anchor = m.x;             // where the proxy last stopped against a face: on the surface
    int anchor_point = path_.count - 1;  // its index in the path
    for (int pass = 0; pass < proxy_max_passes; ++pass) {
      for (int move = 0; move < proxy_max_moves; ++move) {
        const glm::dvec3 target = m.planes.project(aim);
        const glm::dvec3 d = target - m.x;
        const double length = glm::length(d);
        if (!(length > m.planes.tolerance)) break;
        if (tick_.nodes >= config_.tick_node_budget) {  // the tick's budget is spent: no further move
          m.blocked = true;
          break;
        }
        const Hit h = sweep(m.x, target, m.planes.count > 0 ? &m.planes.normal[0] : nullptr);
        ++tick_.moves;
        if (!h.complete) {
          m.blocked = true;
          break;
        }
        if (closest_matches_sweep && h.found() && !touching_ && tick_.moves == 1 && overlaps(start)) {
          m.embedded = true;
          return;
        }
        if (!h.found()) {
          m.x = target;
          visit(m.x);
          break;
        }
        const bool added = stop_at(h, d, length, m.x, m.planes);
        anchor = m.x;
        anchor_point = path_.count - 1;
        m.last_hit = h;
        if (!added) break;
      }
      m.planes.project(aim);  // the final active set (releases planes the aim has left)
      if (m.blocked || m.planes.count == 0) return;
      m.touched = nearest(m.x, reach(m.planes), m.last_hit);
      if (m.touched.found() || !m.touched.complete) return;
      if (pass + 1 == proxy_max_passes) {  // still off every face: back to where it last met one
        m.x = anchor;                      // (back along the path it came: the pieces after it are undone)
        path_.count = anchor_point + 1;
        m.touched = m.last_hit;
        return;
      }
      m.planes = Planes{};  // slid past the end of its faces: sweep on from here toward the aim
    }
  }

  /// Step 3's friction move where the frictionless planes do not carry it
  /// (the surface curves up between, or away below, the frictionless point
  /// and the held one, `candidate`): the constrained motion from where
  /// `back` has it toward the HIP moved by the friction's lag, so that the
  /// proxy lags behind over the surface itself, not along a plane's
  /// extension. True when it ends on the surface, every move swept, inside
  /// the static cone on the planes it came to (back then has the proxy);
  /// else the proxy stays frictionless this tick.
  [[nodiscard]] bool follow_surface(const glm::dvec3& goal, const glm::dvec3& frictionless, const glm::dvec3& candidate,
                                    Motion& back) noexcept {
    if (move_and_hold(goal + (candidate - frictionless), frictionless, goal, back)) return true;
    visit(frictionless);  // (the path ends where the proxy stays: the frictionless point)
    return false;
  }

  /// Steps 1-2 from where m has the proxy toward `aim`, kept (m then has
  /// the proxy) when they end on the surface inside the static cone on the
  /// planes the HIP presses (hold_on_pressed); else m and the path are as
  /// they were.
  [[nodiscard]] bool move_and_hold(const glm::dvec3& aim, const glm::dvec3& start, const glm::dvec3& goal,
                                   Motion& m) noexcept {
    const int before = path_.count;
    Motion on = m;
    move_toward(aim, start, on);
    if (on.blocked || on.embedded || !on.touched.found() || !hold_on_pressed(goal, on)) {
      path_.count = before;
      return false;
    }
    m = on;
    return true;
  }

  /// Where step 0's aimed motion ended outside the cone (it came into a
  /// crease and the HIP presses on one of its faces only, or the surface
  /// curved), the friction decided once more from there, on the planes the
  /// HIP presses: stuck where it stopped inside the cone, else the
  /// constrained motion on toward the HIP moved by mu_k d toward where it
  /// stopped. True (m then has the proxy) when that ends on the surface
  /// inside the cone; false leaves m as it was (the full tick follows).
  [[nodiscard]] bool decide_again(const glm::dvec3& goal, Motion& m) noexcept {
    if (!(config_.static_friction > 0.0) || tick_.nodes >= config_.tick_node_budget) return false;
    Planes pressed = m.planes;
    const glm::dvec3 free = pressed.project(goal);  // the HIP's point on the planes it presses
    if (pressed.count == 0) return false;
    const double depth = glm::length(pressed.project_equal(goal, false) - goal);  // [m]
    if (!(depth > 0.0)) return false;
    const glm::dvec3 slide = m.x - free;
    const double s = glm::length(slide);
    if (s <= (sliding_ ? config_.dynamic_friction : config_.static_friction) * depth) {  // stuck where it stopped
      Motion stuck = m;
      if (!hold_on_pressed(goal, stuck)) return false;
      sliding_ = false;
      m = stuck;
      return true;
    }
    Motion on = m;
    on.planes = pressed;
    if (!move_and_hold(goal + (config_.dynamic_friction * depth / s) * slide, m.x, goal, on)) return false;
    sliding_ = true;
    m = on;
    return true;
  }

  /// Where a proxy that was at p holds on `planes` (step 3's and step 0's
  /// rule): p on them, but in a crease on those it presses on from p (the
  /// face it came along), not on the crease line, which would keep only the
  /// slide along the crease and snap the proxy onto it.
  /// A plane counts as left when p lies more than the largest offset in
  /// front of it (a point on two planes, within rounding, keeps both).
  [[nodiscard]] static glm::dvec3 held_point(const Planes& planes, const glm::dvec3& p) noexcept {
    Planes from = planes;
    if (planes.count > 1)
      for (int i = from.count - 1; i >= 0; --i)
        if (glm::dot(from.normal[static_cast<std::size_t>(i)], p) - from.c[static_cast<std::size_t>(i)] >
            planes.max_offset)
          from.remove(i);
    return (from.count > 0 ? from : planes).project_equal(p);
  }

  /// m's planes cut to those the HIP presses on (in a crease, it may have
  /// left the face the proxy came off), and its touched face one of theirs
  /// (the force's normal is that face's); true when m then lies on the
  /// surface inside the static cone about the HIP's point on them (m
  /// changed), false otherwise (m as it was). On curved primitives (a
  /// height field's bilinear cells) a plane is the tangent plane where the
  /// proxy met a cell, and the proxy held on it comes onto the cells
  /// around, which hold no plane but are the surface under it: there the
  /// face it touches (found within reach: on the surface) is enough.
  [[nodiscard]] bool hold_on_pressed(const glm::dvec3& goal, Motion& m) const noexcept {
    Motion held = m;
    (void)held.planes.project(goal);
    if (held.planes.count == 0) return false;
    if constexpr (curved_primitives) {
      if (!held.touched.found()) return false;
    } else {
      for (int i = 0; i < held.planes.count && !on_planes(held.planes, held.touched); ++i) {
        Hit face;
        face.primitive = held.planes.primitive[static_cast<std::size_t>(i)];
        held.touched = on_same_face(m.x, reach(held.planes), face);
      }
      if (!on_planes(held.planes, held.touched)) return false;
    }
    if (!in_cone(goal, held)) return false;
    m = held;
    return true;
  }

  /// True when face h was found and holds one of `planes` (a plane of
  /// its own, or of its edge or corner for a ball), or lies in one.
  [[nodiscard]] static bool on_planes(const Planes& planes, const Hit& h) noexcept {
    if (!h.found()) return false;
    for (int i = 0; i < planes.count; ++i)
      if (planes.primitive[static_cast<std::size_t>(i)] == h.primitive ||
          glm::dot(planes.normal[static_cast<std::size_t>(i)], h.face_normal) > 1.0 - 1e-12)
        return true;
    return false;
  }

  /// True when the proxy where m has it is on the surface, the HIP presses
  /// on every plane it is held to, and it lies inside the static friction
  /// cone about the HIP's point on them.
  [[nodiscard]] bool in_cone(const glm::dvec3& goal, const Motion& m) const noexcept {
    if (m.planes.count == 0) return false;  // off the surface
    Planes pressed = m.planes;
    const glm::dvec3 free = pressed.project(goal);      // the HIP's point on the planes, all binding
    if (pressed.count != m.planes.count) return false;  // the HIP has left a plane
    const double depth = glm::length(m.planes.project_equal(goal, false) - goal);  // [m]
    return glm::length(m.x - free) <= config_.static_friction * depth * (1.0 + 1e-9);
  }

  /// The proxy moving from x by d (of `length` [m]) stops at hit h, backed
  /// off along the move by the offset (its path takes the point), and h's
  /// plane, lifted by the radius and the offset, joins `planes` (false when
  /// three are held already).
  bool stop_at(const Hit& h, const glm::dvec3& d, double length, glm::dvec3& x, Planes& planes) noexcept {
    x = stopped(h, d, length, x);
    visit(x);
    return planes.add(h.face_normal, glm::dot(h.face_normal, h.point) + config_.radius + offset_for(h), offset_for(h),
                      h.primitive);
  }

  /// Where a move from x by d (of `length` [m]) stops at hit h: backed off
  /// along the move so as to stay the hit primitive's offset in front of it.
  [[nodiscard]] glm::dvec3 stopped(const Hit& h, const glm::dvec3& d, double length,
                                   const glm::dvec3& x) const noexcept {
    const double facing = -glm::dot(d, h.face_normal) / length;  // cos of the angle of incidence, > 0
    const double back = facing > 1e-6 ? offset_for(h) / facing : length;
    return x + (std::fmax(0.0, h.t * length - back) / length) * d;
  }

  /// A proxy that slid `length` [m] along its one held plane to x and found
  /// the surface gone from under it (curved away past the face it held):
  /// swept down the plane's normal by as much, onto the surface (x, planes,
  /// the frictionless point, the surface point under the HIP, the depth and
  /// the touched face then describe where it settled). False when nothing
  /// is met within that, the HIP does not press on the new plane, or the
  /// tick's budget is spent: the full tick takes over.
  [[nodiscard]] bool settle(const glm::dvec3& goal, double length, Planes& planes, glm::dvec3& x,
                            glm::dvec3& frictionless, glm::dvec3& on_surface, double& depth, Hit& touched) noexcept {
    if (planes.count != 1 || tick_.nodes >= config_.tick_node_budget) return false;
    const glm::dvec3 down = -length * planes.normal[0];
    const Hit h = sweep(x, x + down);
    ++tick_.moves;
    if (!h.complete || !h.found()) return false;
    visit(x);                                                             // the slide's end, then down from it
    if (!(-glm::dot(down, h.face_normal) / length > 1e-6)) return false;  // it grazes the face it met
    Planes onto;
    (void)onto.add(h.face_normal, glm::dot(h.face_normal, h.point) + config_.radius + offset_for(h), offset_for(h),
                   h.primitive);
    const glm::dvec3 free = onto.project(goal);
    if (onto.count != 1) return false;  // the HIP is off the new plane
    const glm::dvec3 under = onto.project_equal(goal, false);
    const double pressed = glm::length(under - goal);  // [m]
    if (!(pressed > 0.0)) return false;
    const glm::dvec3 settled = stopped(h, down, length, x);
    // held only inside the static cone on the new plane (else the full tick)
    if (glm::length(onto.project_equal(settled) - free) > config_.static_friction * pressed) return false;
    x = settled;
    planes = onto;
    frictionless = free;
    on_surface = under;
    depth = pressed;
    touched = h;
    return true;
  }

  /// The proxy at the HIP this tick, with no contact: a ball that overlaps
  /// the surface there stays free (embedded_) until it is clear of it.
  [[nodiscard]] Contact follow_free(const glm::dvec3& goal) noexcept {
    proxy_ = goal;
    embedded_ = overlaps(goal);
    tick_.embedded = embedded_;
    path_.count = 0;
    visit(goal);
    return Contact{};
  }

  /// Appends a point to the tick's path.
  void visit(const glm::dvec3& p) noexcept {
    if (path_.count < proxy_max_path) path_.points[static_cast<std::size_t>(path_.count++)] = p;
  }

  /// How far from the surface the proxy still touches it [m]: a few of its
  /// offsets above the tick's planes, plus the tool's radius.
  [[nodiscard]] double reach(const Planes& planes) const noexcept {
    return 4.0 * planes.max_offset + planes.tolerance + config_.radius;
  }

  /// anticipate()'s run: a scratch copy, readied by `ready`, makes the
  /// tick; a ball keeps its sweep cache.
  template <class Ready>
  void anticipate_with(const Probe& next, Ready&& ready) const noexcept {
    if constexpr (anticipates) {
      ProxyConstraint scratch(*this);
      ready(scratch);
      (void)scratch.contact(next);
      if (config_.radius > 0.0) sweep_cache_ = scratch.sweep_cache_;
    }
  }

  /// The shape changes between ticks: advance(time) at the start of each.
  static constexpr bool advances = requires(S & s) {
    { s.advance(0.0) } -> std::same_as<bool>;
  };
  /// The shape moves rigidly: carry(p) and surface_velocity(p).
  static constexpr bool carries = requires(const S& s, const glm::dvec3& p) {
    { s.carry(p) } -> std::same_as<glm::dvec3>;
    { s.surface_velocity(p) } -> std::same_as<glm::dvec3>;
  };
  /// anticipate() runs a copy's tick: the shape stands still, its queries
  /// change nothing and its copy cannot allocate (a mesh's shares its tree).
  static constexpr bool anticipates = !advances && PureQueries<S>;

  /// The HIP's velocity the damping acts on: relative to the surface at the
  /// proxy `at` on a moving shape (zero for a non-finite HIP velocity).
  [[nodiscard]] glm::dvec3 relative(const glm::dvec3& velocity, const glm::dvec3& at) const noexcept {
    if constexpr (carries) {
      if (!is_finite(velocity)) return glm::dvec3{0.0};
      return velocity - shape_.surface_velocity(at);
    } else {
      return velocity;
    }
  }

  /// A deforming shape (advances, does not carry) changed under a touching
  /// proxy: back in front of the face it touched, at its lift over the face
  /// as it is now, when the face has come up to it or past it (a surface
  /// pressing on the proxy pushes it out).
  void lift(const Hit& face) noexcept {
    if constexpr (requires { shape_.on_primitive(face.primitive, proxy_, 1.0); }) {
      if (!face.found()) return;
      const Hit now = shape_.on_primitive(face.primitive, proxy_, std::numeric_limits<double>::infinity());
      if (!now.found()) return;
      const double above = config_.radius + offset_for(now);  // [m]
      if (glm::dot(proxy_ - now.point, now.face_normal) < above) proxy_ = now.point + above * now.face_normal;
    }
  }

  /// True when a ball of the tool's radius centred at p overlaps the
  /// surface (some point nearer than the radius); never for a point. Swept
  /// from there, it would meet what it overlaps at once, wherever it moved:
  /// such a ball is left free until it is clear (embedded_).
  [[nodiscard]] bool overlaps(const glm::dvec3& p) noexcept {
    if (!(config_.radius > 0.0)) return false;
    const Hit h = nearest(p, config_.radius, Hit{});
    return h.found() && h.distance < config_.radius * (1.0 - 1e-9);
  }

  /// closest() sees the surface the sweeps meet (a shape says otherwise
  /// with closest_matches_sweep = false: a height field's bilinear patches
  /// against its cells' triangles), so overlaps() is exact for a ball.
  static constexpr bool closest_matches_sweep = !requires { requires !S::closest_matches_sweep; };
  /// The shape says its primitives are flat (a mesh's triangles).
  static constexpr bool flat_primitives = requires { requires S::flat_primitives; };
  /// The shape answers for one primitive (on_primitive()).
  static constexpr bool answers_one_primitive = requires(const S& s, const glm::dvec3& p) {
    s.on_primitive(std::uint32_t{0}, p, 0.0);
  };
  /// Its primitives may curve: it answers for one but does not say they
  /// are flat (a height field's bilinear cells).
  static constexpr bool curved_primitives = !flat_primitives && answers_one_primitive;

  /// The shape can sweep a ball (sweep_sphere), for a radius > 0.
  static constexpr bool sweeps_spheres = requires(const S& s, const glm::dvec3& p) { s.sweep_sphere(p, p, 1.0); };

  /// shape_.first_hit (a point) or shape_.sweep_sphere (a ball of the
  /// tool's radius), counting the nodes it visits when the shape can.
  /// `slide`: the normal of a plane the move runs along (the ball slides on
  /// it), for a shape that passes by what lies behind the ball's reach
  /// (MeshShape::sweep_sphere's); the answer is the same without it.
  [[nodiscard]] Hit sweep(const glm::dvec3& from, const glm::dvec3& to,
                          [[maybe_unused]] const glm::dvec3* slide = nullptr) noexcept {
    if constexpr (sweeps_spheres) {
      if (config_.radius > 0.0) {
        if constexpr (requires(QueryStats * q, std::uint32_t hint) { shape_.sweep_sphere(from, to, 1.0, q, hint); }) {
          // the primitive met last is tried first (MeshShape::sweep_sphere's
          // hint), and the shape's region of the last sweeps kept (its cache)
          QueryStats q;
          Hit h;
          if constexpr (requires(QueryStats * s, SweepCache * c, const glm::dvec3* n) {
                          shape_.sweep_sphere(from, to, 1.0, s, std::uint32_t{0}, c, n);
                        })
            h = shape_.sweep_sphere(from, to, config_.radius, &q, hint_, &sweep_cache_, slide);
          else if constexpr (requires(QueryStats * s, SweepCache * c) {
                               shape_.sweep_sphere(from, to, 1.0, s, std::uint32_t{0}, c);
                             })
            h = shape_.sweep_sphere(from, to, config_.radius, &q, hint_, &sweep_cache_);
          else
            h = shape_.sweep_sphere(from, to, config_.radius, &q, hint_);
          tick_.nodes += q.nodes;
          if (h.found()) hint_ = h.primitive;
          return h;
        } else if constexpr (requires(QueryStats * q) { shape_.sweep_sphere(from, to, 1.0, q); }) {
          QueryStats q;
          const Hit h = shape_.sweep_sphere(from, to, config_.radius, &q);
          tick_.nodes += q.nodes;
          return h;
        } else {
          return shape_.sweep_sphere(from, to, config_.radius);
        }
      }
    }
    if constexpr (requires(QueryStats * q) { shape_.first_hit(from, to, q); }) {
      QueryStats q;
      const Hit h = shape_.first_hit(from, to, &q);
      tick_.nodes += q.nodes;
      return h;
    } else {
      return shape_.first_hit(from, to);
    }
  }

  /// The point over `face` (the primitive the proxy is on) nearest to p,
  /// when the shape's primitives are flat (S::flat_primitives) and p is
  /// within max_distance of it; else nothing. A move between two points over
  /// one flat, convex face needs no sweep.
  [[nodiscard]] Hit on_same_face(const glm::dvec3& p, double max_distance, const Hit& face) const noexcept {
    if constexpr (flat_primitives && answers_one_primitive) {
      if (face.found()) return shape_.on_primitive(face.primitive, p, max_distance);
    }
    return Hit{};
  }

  /// True when p lies in front of the face of `on` (its closest point on
  /// the face, found) at half the proxy's offset or more, straight over the
  /// face's inside (not past an edge): a move of a point proxy over one
  /// flat, convex face between two such points stays in front of it. Behind
  /// the face, off its edge where a neighbour may rise, or for a ball, a
  /// move is swept instead.
  [[nodiscard]] bool over_face(const Hit& on, const glm::dvec3& p) const noexcept {
    // a ball reaches r around its centre: another face may come within r of
    // the move however high both ends are over this one, so it always sweeps
    if (!on.found() || config_.radius > 0.0) return false;
    const double height = glm::dot(p - on.point, on.face_normal);  // [m]
    return height >= config_.radius + 0.5 * offset_for(on) && height >= on.distance * (1.0 - 1e-9);
  }

  /// shape_.closest, counting as sweep() does; first the primitive of
  /// `hint` alone when the shape can answer for one (on_primitive()), which
  /// costs no traversal while the proxy stays on the face it last met. A
  /// ball's query reads its sweeps' cache where the shape takes one (a
  /// mesh's region: its leaves alone answer where the query lies inside).
  [[nodiscard]] Hit nearest(const glm::dvec3& p, double max_distance, const Hit& hint) noexcept {
    if constexpr (requires { shape_.on_primitive(hint.primitive, p, max_distance); }) {
      if (hint.found()) {
        const Hit h = shape_.on_primitive(hint.primitive, p, max_distance);
        if (h.found()) return h;
      }
    }
    if constexpr (requires(QueryStats * q) { shape_.closest(p, max_distance, q); }) {
      QueryStats q;
      Hit h;
      if constexpr (requires(const SweepCache* c) { shape_.closest(p, max_distance, &q, c); })
        h = shape_.closest(p, max_distance, &q, config_.radius > 0.0 ? &sweep_cache_ : nullptr);
      else
        h = shape_.closest(p, max_distance, &q);
      tick_.nodes += q.nodes;
      return h;
    } else {
      return shape_.closest(p, max_distance);
    }
  }

  /// The proxy's height above the primitive of a hit [m].
  [[nodiscard]] double offset_for(const Hit& h) const noexcept {
    const double coordinate = largest_component(h.point);
    return config_.offset * h.size + 64.0 * std::numeric_limits<double>::epsilon() * coordinate;
  }

  S shape_;
  ProxyConfig config_;
  glm::dvec3 proxy_{0.0};
  bool started_{false};
  bool embedded_{false};  ///< a ball that began overlapping the surface, free until clear (overlaps())
  bool touching_{false};
  bool sliding_{false};
  Planes held_planes_{};              ///< the constraint planes of the last tick that touched
  Hit held_face_{};                   ///< the face the proxy last touched
  Hit face_{};                        ///< a deforming shape's face the proxy touched last tick
  std::uint32_t hint_{no_primitive};  ///< the primitive a ball's sweep met last, tried first by the next
  using SweepCache = SweepCacheOf<S>;
  /// What the shape keeps between a ball's sweeps (MeshShape: its region of
  /// the tree); a cache: anticipate() may leave its copy's here.
  mutable SweepCache sweep_cache_{};
  ProxyTick tick_{};
  ProxyPath path_{};
};

}  // namespace hapticfield
