#pragma once
/// @file local_model.hpp
/// The local model a physics simulator hands to the 1 kHz servo loop, and
/// the field that renders it: an intermediate representation (Adachi,
/// Kumano & Ogino, VRAIS 1995; Mark et al., "Adding force feedback to
/// graphics systems", SIGGRAPH 1996). The simulator thread publishes, each
/// step, what the tool touches as up to local_model_max_planes contact
/// planes (a point, the normal toward the tool, the touched body's velocity
/// there) or, in the virtual-coupling mode, the tool body's pose and
/// velocity. The servo thread renders it every tick without allocation:
///
///   local_model       each plane pushes the tool ball (radius r, centred on
///                     the HIP) out along its normal with a spring-damper,
///                     the plane moved by its velocity since it arrived
///                     (first order, at most two simulator periods ahead):
///                       d = r - (x - p - v_p a) . n,
///                       f = max(0, k d - b (v - v_p) . n) n   while d > 0;
///                     with Coulomb friction (static mu_s, dynamic mu_k):
///                     a proxy on the plane where the HIP's projection c
///                     first touched it, carried with the plane's velocity,
///                     pulls the HIP back with k (p_f - c) while that stays
///                     within mu_s |f| (sticking); beyond, the proxy slides,
///                     held mu_k |f| / k behind c (the force mu_k |f| against
///                     the slip), until the HIP comes back within the mu_k
///                     cone and it sticks again (the friction cone of Zilles
///                     & Salisbury 1995 and Salisbury et al. 1995, with a
///                     static and a dynamic cone, on each plane);
///   virtual_coupling  F = K (x_tool - x) + B (v_tool - v)
///                     (physics/virtual_coupling.hpp).
///
/// Every tick the field gives the simulator back the impulse it rendered:
/// -f dt on the touched body (at the contact point) or on the tool, summed
/// since the scene started (HandleSample), so no impulse is lost when the
/// simulator reads fewer samples than the servo writes. The hand's momentum
/// lost is the scene's momentum gained, exactly.
///
/// Lockstep (a simulator stepped from the servo's own clock, for loops on a
/// virtual clock): while LocalModelLink::lockstep is set, each tick first
/// waits, spinning with yield, until the model of the simulator step its
/// servo time has made due has come (lockstep_steps_due()): step j is taken
/// with the HIP and the impulses of servo time j T and rendered from servo
/// time j T on, whatever either thread's speed. No allocation, no lock; a
/// real-time loop never sets it.
///
/// Faults: a model marked faulty, or one that stops changing for longer
/// than its stall_time, gives zero force from the next tick on and counts
/// an event; the force then fades in again over fade_time once the models
/// are good. A new scene fades in over fade_time while the old one, frozen
/// as it was last seen, fades out (a changed scene never jerks the arm;
/// what the old scene renders then is not pushed back: its bodies are gone).

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <thread>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/rt/latest_value.hpp"

namespace hapticfield {

/// Most contact planes in one local model.
inline constexpr int local_model_max_planes = 8;
/// Bodies (by simulator id, 0..63) a local model can push back on; planes of
/// bodies beyond are rendered as static.
inline constexpr int local_model_max_bodies = 64;
/// ContactPlane::body of a plane whose body does not move (the world).
inline constexpr int static_body = -1;

/// Simulator steps of period T [s] due by servo time t [s] in lockstep:
/// floor(t / T), rounding up what a sum of servo periods misses by 1e-6 T.
[[nodiscard]] inline std::uint64_t lockstep_steps_due(double servo_time, double period) noexcept {
  if (!(servo_time > 0.0) || !(period > 0.0)) return 0;
  return static_cast<std::uint64_t>(std::floor(servo_time / period + 1e-6));
}

/// How the hand meets the simulated scene.
enum class CouplingMode : std::uint8_t {
  local_model,       ///< contact planes rendered at the servo rate (the default)
  virtual_coupling,  ///< a spring-damper to a simulated tool body
};

/// One plane of the local model, in the device frame.
struct ContactPlane {
  glm::dvec3 point{0.0};         ///< a point of the touched surface [m]
  glm::dvec3 normal{0.0};        ///< unit normal, out of the touched body toward the tool
  glm::dvec3 velocity{0.0};      ///< the touched body's velocity at point [m/s]
  double stiffness{0.0};         ///< k [N/m]
  double damping{0.0};           ///< b on the normal relative velocity [N s/m]
  int body{static_body};         ///< the simulator's body id (0..local_model_max_bodies-1) or static_body
  double static_friction{0.0};   ///< mu_s: sticks while the tangential force is within mu_s |f| [-]
  double dynamic_friction{0.0};  ///< mu_k <= mu_s: the sliding force is mu_k |f| [-]
};

/// What the simulator thread publishes each step (device frame).
struct LocalModel {
  std::uint64_t sequence{0};       ///< step count: a model that stops changing is a stalled simulator
  std::uint32_t scene{0};          ///< changes when the scene changes
  bool fault{false};               ///< the simulator failed: render nothing
  std::uint64_t lockstep_step{0};  ///< lockstep: the steps taken, the last one at servo time lockstep_step T
  CouplingMode mode{CouplingMode::local_model};
  double tool_radius{0.0};  ///< r [m]
  double period{0.01};      ///< the simulator's step period [s]
  double stall_time{0.05};  ///< no new model for longer than this is a stall [s]
  double fade_time{0.2};    ///< force fade-in after a scene change or a fault [s]
  std::array<ContactPlane, local_model_max_planes> planes{};
  int plane_count{0};
  // virtual coupling
  glm::dvec3 tool_position{0.0};   ///< [m]
  glm::dvec3 tool_velocity{0.0};   ///< [m/s]
  int tool_body{static_body};      ///< the tool's body id
  double coupling_stiffness{0.0};  ///< K [N/m]
  double coupling_damping{0.0};    ///< B [N s/m]
};

/// What the servo thread publishes each tick (device frame): the handle,
/// and the impulses it rendered on each body since (scene, epoch) began.
struct HandleSample {
  std::uint64_t tick{0};     ///< servo ticks since the field started
  double time{0.0};          ///< servo time since the field started: the sum of the ticks' periods [s]
  std::uint32_t scene{0};    ///< the scene the impulses belong to
  std::uint32_t epoch{0};    ///< changes when the field is reset (its sums restart at zero)
  bool valid{false};         ///< position and velocity are set
  glm::dvec3 position{0.0};  ///< HIP [m]
  glm::dvec3 velocity{0.0};  ///< [m/s]
  std::array<glm::dvec3, local_model_max_bodies> impulse{};          ///< sum of f dt on each body [N s]
  std::array<glm::dvec3, local_model_max_bodies> angular_impulse{};  ///< sum of p x f dt about the origin [N m s]
};

/// The two one-way channels between the simulator thread and the servo
/// thread, and the servo side's event counts (readable from any thread).
struct LocalModelLink {
  LatestValue<LocalModel> model;               ///< simulator -> servo
  LatestValue<HandleSample> handle;            ///< servo -> simulator
  std::atomic<std::uint64_t> stalls{0};        ///< times the models stopped coming
  std::atomic<std::uint64_t> faults_seen{0};   ///< times a faulty model arrived
  std::atomic<std::uint64_t> zeroed_ticks{0};  ///< ticks that gave zero force for a stall or a fault
  /// A simulator steps in lockstep with the servo's time: each tick waits for the model of the step due.
  std::atomic<bool> lockstep{false};
};

/// The servo side: a HapticField (and ResettableField) over a link. One
/// field per link; the link must outlive it.
class LocalModelField {
 public:
  explicit LocalModelField(LocalModelLink& link) noexcept : link_(&link) {}

  [[nodiscard]] glm::dvec3 force(const Probe& probe) noexcept {
    ++tick_;
    const double dt = std::isfinite(probe.period) && probe.period > 0.0 ? probe.period : servo_period;
    const bool finite_position = is_finite(probe.position);
    const glm::dvec3 velocity = is_finite(probe.velocity) ? probe.velocity : glm::dvec3{0.0};
    if (finite_position) {
      sample_.position = probe.position;
      sample_.velocity = velocity;
      sample_.valid = true;
    }
    sample_.tick = tick_;
    const double rendered = sample_.time;  // servo time at the start of this tick [s]
    sample_.time += dt;
    const LocalModel* model = link_->model.latest();
    // lockstep: the model of the step due at this tick's start, once the simulator has taken it
    while (model != nullptr && link_->lockstep.load(std::memory_order_acquire) &&
           model->lockstep_step < lockstep_steps_due(rendered, model->period)) {
      std::this_thread::yield();
      model = link_->model.latest();
    }
    glm::dvec3 total{0.0};
    if (model != nullptr) total = render(*model, probe.position, velocity, dt, finite_position);
    link_->handle.publish(sample_);
    return is_finite(total) ? total : glm::dvec3{0.0};
  }

  /// Starts again: the next model fades in; the impulse sums restart (a new
  /// epoch, which the simulator follows).
  void reset() noexcept {
    ++sample_.epoch;
    sample_.impulse.fill(glm::dvec3{0.0});
    sample_.angular_impulse.fill(glm::dvec3{0.0});
    fade_start_ = tick_;
    zeroed_ = false;
    anchors_ = {};
  }

  /// True while the last tick gave zero force for a stall or a fault.
  [[nodiscard]] bool zeroed() const noexcept { return zeroed_; }
  /// Contact planes touched in the last tick.
  [[nodiscard]] int touching() const noexcept { return touching_; }
  /// Energy held in the rendered springs at the last tick [J]: sum of
  /// k d^2 / 2 over the planes touched, or K |x_tool - x|^2 / 2 (with the
  /// fade): what a passivity observer at the HIP counts as the model's own.
  [[nodiscard]] double spring_energy() const noexcept { return spring_energy_; }

 private:
  glm::dvec3 render(const LocalModel& model, const glm::dvec3& x, const glm::dvec3& v, double dt,
                    bool finite_position) noexcept {
    if (model.sequence != sequence_) {
      sequence_ = model.sequence;
      arrived_ = tick_;
    }
    if (model.scene != sample_.scene || !started_) {  // a new scene: its sums start at zero, its force fades in
      if (started_ && !zeroed_) {                     // ... while the old one's fades out
        previous_ = current_;
        has_previous_ = true;
      }
      started_ = true;
      sample_.scene = model.scene;
      sample_.impulse.fill(glm::dvec3{0.0});
      sample_.angular_impulse.fill(glm::dvec3{0.0});
      fade_start_ = tick_;
      anchors_ = {};
    }
    current_ = model;
    touching_ = 0;
    spring_energy_ = 0.0;
    const double age = static_cast<double>(tick_ - arrived_) * dt;  // [s] since this model arrived
    const bool stalled = age > model.stall_time;
    if (stalled && !stalled_) link_->stalls.fetch_add(1, std::memory_order_relaxed);
    stalled_ = stalled;
    if (model.fault && sequence_ != faulty_sequence_) {
      faulty_sequence_ = sequence_;
      link_->faults_seen.fetch_add(1, std::memory_order_relaxed);
    }
    if (stalled || model.fault || !finite_position) {
      if (stalled || model.fault) link_->zeroed_ticks.fetch_add(1, std::memory_order_relaxed);
      zeroed_ = stalled || model.fault;
      has_previous_ = false;
      anchors_ = {};        // the friction proxies start again where the HIP touches
      fade_start_ = tick_;  // fade in again once good models come
      return glm::dvec3{0.0};
    }
    zeroed_ = false;
    const double faded = static_cast<double>(tick_ - fade_start_) * dt;
    const double fade = model.fade_time > 0.0 ? std::min(1.0, faded / model.fade_time) : 1.0;
    if (fade >= 1.0) has_previous_ = false;
    glm::dvec3 total = model_force(model, x, v, dt, age, fade, true);
    // the old scene, frozen where it was, fades out (its bodies are gone: no push back)
    if (has_previous_) total += model_force(previous_, x, v, dt, 0.0, 1.0 - fade, false);
    return total;
  }

  /// The force of one model scaled by weight; push: give the bodies their impulses.
  glm::dvec3 model_force(const LocalModel& model, const glm::dvec3& x, const glm::dvec3& v, double dt, double age,
                         double weight, bool push) noexcept {
    const double ahead = std::min(age, 2.0 * model.period);  // extrapolation [s]
    glm::dvec3 total{0.0};
    if (model.mode == CouplingMode::virtual_coupling) {
      const glm::dvec3 tool = model.tool_position + model.tool_velocity * ahead;
      const glm::dvec3 f =
          weight * (model.coupling_stiffness * (tool - x) + model.coupling_damping * (model.tool_velocity - v));
      spring_energy_ += 0.5 * weight * model.coupling_stiffness * glm::dot(tool - x, tool - x);
      if (push) push_back(model.tool_body, tool, f, dt);
      return f;
    }
    const int count = std::clamp(model.plane_count, 0, local_model_max_planes);
    std::array<FrictionAnchor, local_model_max_planes> next{};  // this tick's friction proxies
    for (int i = 0; i < count; ++i) {
      const ContactPlane& plane = model.planes[static_cast<std::size_t>(i)];
      const glm::dvec3 point = plane.point + plane.velocity * ahead;
      const double height = glm::dot(x - point, plane.normal);  // [m]
      const double depth = model.tool_radius - height;
      if (!(depth > 0.0)) continue;
      const double force = plane.stiffness * depth - plane.damping * glm::dot(v - plane.velocity, plane.normal);
      if (!(force > 0.0)) continue;
      ++touching_;
      spring_energy_ += 0.5 * weight * plane.stiffness * depth * depth;
      const glm::dvec3 contact = x - height * plane.normal;  // the HIP's projection on the plane
      glm::dvec3 f = force * plane.normal;
      if (push && plane.static_friction > 0.0)
        f += friction(plane, point, contact, force, dt, weight, next[static_cast<std::size_t>(i)]);
      f *= weight;
      total += f;
      if (push) push_back(plane.body, contact, f, dt);
    }
    if (push) anchors_ = next;
    return total;
  }

  /// A friction proxy on a plane: where it holds the HIP's projection [m].
  struct FrictionAnchor {
    glm::dvec3 point{0.0};   ///< on the plane [m]
    glm::dvec3 normal{0.0};  ///< the plane's, to know it again next tick
    int body{static_body};
    bool valid{false};
    bool sliding{false};  ///< out of the static cone: the dynamic one holds it
  };

  /// The tangential force of Coulomb friction on plane (moved to `point`)
  /// for a normal force `normal_force` [N] at the HIP's projection `contact`;
  /// `anchor` is set to the proxy it leaves for the next tick; weight: the
  /// fade, for the energy held.
  glm::dvec3 friction(const ContactPlane& plane, const glm::dvec3& point, const glm::dvec3& contact,
                      double normal_force, double dt, double weight, FrictionAnchor& anchor) noexcept {
    glm::dvec3 held = contact;  // a new touch: the proxy where the HIP touches, no tangential force
    bool sliding = false;
    for (const FrictionAnchor& a : anchors_) {
      // the same plane as last tick: the same body, the same normal (to 0.8 degree)
      if (!a.valid || a.body != plane.body || glm::dot(a.normal, plane.normal) < 0.9999) continue;
      const glm::dvec3 carried = a.point + plane.velocity * dt;  // the proxy moves with the surface
      held = carried - glm::dot(carried - point, plane.normal) * plane.normal;
      sliding = a.sliding;
      break;
    }
    const double k = plane.stiffness;
    glm::dvec3 slip = contact - held;  // tangential: both on the plane [m]
    slip -= glm::dot(slip, plane.normal) * plane.normal;
    const double stretch = glm::length(slip);
    const double mu_k = std::min(plane.dynamic_friction, plane.static_friction);
    // sticking: the static cone holds it; sliding: the dynamic one, within which it sticks again
    sliding = k * stretch > (sliding ? mu_k : plane.static_friction) * normal_force && stretch > 0.0;
    if (sliding) {  // the proxy follows, mu_k |f| / k behind
      held = contact - slip * (mu_k * normal_force / k / stretch);
      slip = contact - held;
    }
    anchor = {held, plane.normal, plane.body, true, sliding};
    spring_energy_ += 0.5 * weight * k * glm::dot(slip, slip);
    return -k * slip;
  }

  /// The body gets -f dt at point p (the HIP got f).
  void push_back(int body, const glm::dvec3& p, const glm::dvec3& f, double dt) noexcept {
    if (body < 0 || body >= local_model_max_bodies) return;
    const auto b = static_cast<std::size_t>(body);
    sample_.impulse[b] -= f * dt;
    sample_.angular_impulse[b] -= glm::cross(p, f) * dt;
  }

  LocalModelLink* link_;
  HandleSample sample_{};
  std::uint64_t tick_{0};
  std::uint64_t sequence_{0};
  std::uint64_t arrived_{0};
  std::uint64_t fade_start_{0};
  std::uint64_t faulty_sequence_{0};
  LocalModel current_{};                                          ///< the model of the last tick
  LocalModel previous_{};                                         ///< the scene before a change, fading out
  std::array<FrictionAnchor, local_model_max_planes> anchors_{};  ///< the friction proxies of the last tick
  bool has_previous_{false};
  bool started_{false};
  bool stalled_{false};
  bool zeroed_{false};
  int touching_{0};
  double spring_energy_{0.0};
};

static_assert(ResettableField<LocalModelField>);

}  // namespace hapticfield
