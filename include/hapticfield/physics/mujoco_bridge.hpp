#pragma once
/// @file mujoco_bridge.hpp
/// MujocoBridge: a MuJoCo (2.2.2 C API) scene stepped on its own thread at
/// its own rate, felt through the 1 kHz servo loop by a LocalModelField
/// (physics/local_model.hpp). The only header that includes MuJoCo.
///
/// The scene (MJCF) holds a tool: a body with a free joint and a sphere
/// geom (its radius is the tool's). Each step (step_once()):
///
///   1. the newest HandleSample (the HIP and the impulses the servo
///      rendered) is read; the impulse each body got since the last step
///      is applied over the step (xfrc_applied at the body's centre of mass,
///      the torque from the contact points): the hand's force goes back into
///      the scene (after a stall, what the servo rendered against the frozen
///      model is dropped, never delivered as one burst);
///   2. local_model mode: the tool is placed on the HIP (pose and velocity)
///      and its contacts are made inactive (a gap wider than any
///      penetration: MuJoCo lists them but its solver ignores them), so the
///      tool only finds what it touches and the hand's force reaches the
///      scene through step 1 alone; virtual_coupling mode: the tool is a
///      free body pushed by the coupling's impulse (its weight cancelled);
///   3. the model steps period/timestep substeps (mj_step);
///   4. the tool's contacts within detect_distance become the local model's
///      planes (nearest first), published with the tool's pose.
///
/// Why not a mocap body welded to the tool, as MuJoCo's users advise for
/// driving a body: a weld is a soft constraint whose time constant MuJoCo
/// keeps at >= 2 timesteps, so it is softest exactly at the low simulator
/// rates this bridge must survive, and its stiffness is hidden in solref;
/// placing the tool (local model) or coupling it with an explicit K and B
/// (virtual coupling) keeps the law and its passivity bound in our hands.
///
/// Faults, on the simulator thread: a step whose state turns non-finite
/// (MuJoCo's own bad-qpos/qvel/qacc warnings, or NaN found after the step),
/// or that hits MuJoCo's error hook, latches a fault and publishes a faulty
/// model: the servo's field gives zero force from its next tick. MuJoCo's
/// error handler (mju_user_error) must never return; the bridge installs
/// one (once, process-wide) that jumps back (longjmp) to the step that
/// called it when the calling thread is a bridge's, and otherwise keeps
/// MuJoCo's behaviour (print, exit). MuJoCo is never called from the servo
/// thread. A step that takes longer than its period counts an overrun;
/// models that stop coming are a stall the field detects by itself. A new
/// scene (load()) or a cleared fault fades the force in again.
///
/// Two runners (start()): real time (the default) steps at the rate on the
/// wall clock, for a real-time servo loop; lockstep (for a servo loop on a
/// virtual clock: tests, off-line runs, Python's run_servo) steps on its own
/// thread when the servo's time reaches the next step's, j T, with the HIP
/// and impulses of that tick, while the servo's field waits for that step's
/// model before rendering the next tick (LocalModelLink::lockstep). A run in
/// lockstep is then the same run to run and machine to machine, and equals
/// one stepped by hand with step_once() after each tick that reaches j T.

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <mujoco/mujoco.h>

#include "hapticfield/core/error.hpp"
#include "hapticfield/core/vector_math.hpp"
#include "hapticfield/physics/local_model.hpp"
#include "hapticfield/physics/virtual_coupling.hpp"

namespace hapticfield {

/// A scene MuJoCo cannot load or use (a missing tool, a bad tool), or a
/// library that does not match the headers.
class MujocoError : public Error {
 public:
  using Error::Error;
};

/// Simulator rates the bridge accepts [Hz] (100..1000 is the design range).
inline constexpr double min_simulator_rate = 10.0;
inline constexpr double max_simulator_rate = 10000.0;

struct MujocoBridgeConfig {
  CouplingMode mode{CouplingMode::local_model};
  double rate{500.0};                  ///< simulator steps per second [Hz]
  std::string tool_body{"tool"};       ///< the free body with the sphere geom
  glm::dvec3 scene_origin{0.0};        ///< the scene point at the device's origin [m], scene frame
  double plane_stiffness{1000.0};      ///< k of the local model's planes [N/m]
  double plane_damping{1.0};           ///< b of the planes on the normal relative velocity, >= T k / 2 [N s/m]
  double plane_static_friction{0.0};   ///< mu_s of the planes' Coulomb friction (0: frictionless) [-]
  double plane_dynamic_friction{0.0};  ///< mu_k, 0 <= mu_k <= mu_s [-]
  VirtualCoupling coupling{};          ///< the virtual_coupling mode's K and B
  double detect_distance{0.01};        ///< tool-to-surface distance within which planes are published [m]
  double stall_time{0.05};             ///< no model for this long zeroes the force [s]
  double fade_time{0.2};               ///< force fade-in after a scene change or a fault [s]
  /// start() steps in lockstep with the servo's time (a loop on a virtual
  /// clock) instead of at the rate on the wall clock.
  bool lockstep{false};
  /// Called on the simulator thread before each substep, inside the step's
  /// protection (tests inject faults here); must not throw; may be empty.
  std::function<void(const mjModel*, mjData*)> before_step;
  /// The clock overruns are measured on [ns]; empty: std::chrono::steady_clock.
  std::function<std::int64_t()> clock;

  /// @throws std::invalid_argument naming the bad parameter.
  void validate() const {
    if (!std::isfinite(rate) || rate < min_simulator_rate || rate > max_simulator_rate)
      throw std::invalid_argument("MujocoBridgeConfig: rate must be within [10, 10000] [Hz]");
    if (tool_body.empty()) throw std::invalid_argument("MujocoBridgeConfig: tool_body must name a body");
    if (!is_finite(scene_origin)) throw std::invalid_argument("MujocoBridgeConfig: scene_origin must be finite [m]");
    if (!std::isfinite(plane_stiffness) || plane_stiffness <= 0.0)
      throw std::invalid_argument("MujocoBridgeConfig: plane_stiffness must be finite and > 0 [N/m]");
    if (!std::isfinite(plane_damping) || plane_damping < 0.0)
      throw std::invalid_argument("MujocoBridgeConfig: plane_damping must be finite and >= 0 [N s/m]");
    // a plane moves with its body, which the simulator updates every T: the
    // same sampled spring as the coupling's, under the same bound
    if (plane_damping < plane_stiffness / rate / 2.0 * (1.0 - 1e-12))
      throw std::invalid_argument(
          "MujocoBridgeConfig: plane_damping must be >= T plane_stiffness / 2 at the simulator period T = 1 / rate");
    if (!std::isfinite(plane_static_friction) || !std::isfinite(plane_dynamic_friction) ||
        plane_dynamic_friction < 0.0 || plane_dynamic_friction > plane_static_friction)
      throw std::invalid_argument(
          "MujocoBridgeConfig: need 0 <= plane_dynamic_friction <= plane_static_friction, finite [-]");
    if (mode == CouplingMode::virtual_coupling) coupling.validate(1.0 / rate);
    if (!std::isfinite(detect_distance) || detect_distance <= 0.0 || detect_distance > 0.1)
      throw std::invalid_argument("MujocoBridgeConfig: detect_distance must be in (0, 0.1] [m]");
    if (!std::isfinite(stall_time) || stall_time <= 0.0 || stall_time > 1.0)
      throw std::invalid_argument("MujocoBridgeConfig: stall_time must be in (0, 1] [s]");
    if (!std::isfinite(fade_time) || fade_time < 0.0 || fade_time > 10.0)
      throw std::invalid_argument("MujocoBridgeConfig: fade_time must be in [0, 10] [s]");
  }
};

/// Why the simulator stopped.
enum class SimulatorFault : std::uint8_t {
  none,
  non_finite,    ///< the state turned NaN or infinite
  mujoco_error,  ///< MuJoCo's error hook was called
};

/// Counts of what happened on the simulator thread.
struct MujocoEvents {
  std::uint64_t steps{0};          ///< steps done
  std::uint64_t overruns{0};       ///< steps that took longer than their period
  std::uint64_t non_finite{0};     ///< steps whose state turned non-finite
  std::uint64_t mujoco_errors{0};  ///< calls of MuJoCo's error hook
  std::uint64_t warnings{0};       ///< MuJoCo warnings (contact list full, ...)
  std::uint64_t scene_changes{0};  ///< load() calls that took effect
};

/// A body's state, in the device frame.
struct BodyState {
  glm::dvec3 position{0.0};  ///< centre of mass [m]
  glm::dvec3 velocity{0.0};  ///< of the centre of mass [m/s]
  double mass{0.0};          ///< [kg]
};

namespace detail {

/// Where MuJoCo's error hook jumps back to on a bridge's thread.
struct MujocoJump {
  std::jmp_buf buffer;
  char message[256]{};
};
inline thread_local MujocoJump* mujoco_jump = nullptr;
inline thread_local std::uint64_t* mujoco_warning_count = nullptr;
inline void (*mujoco_previous_error)(const char*) = nullptr;
inline void (*mujoco_previous_warning)(const char*) = nullptr;

inline void mujoco_error_hook(const char* message) {
  if (MujocoJump* jump = mujoco_jump) {
    std::snprintf(jump->message, sizeof jump->message, "%s", message ? message : "");
    std::longjmp(jump->buffer, 1);
  }
  if (mujoco_previous_error != nullptr) mujoco_previous_error(message);
  std::fprintf(stderr, "MuJoCo error: %s\n", message ? message : "");  // MuJoCo's own default: report and exit
  std::exit(EXIT_FAILURE);
}

inline void mujoco_warning_hook(const char* message) {
  if (std::uint64_t* count = mujoco_warning_count) {
    ++*count;
    return;
  }
  if (mujoco_previous_warning != nullptr)
    mujoco_previous_warning(message);
  else
    std::fprintf(stderr, "MuJoCo warning: %s\n", message ? message : "");
}

/// Installs the hooks once per process (they are process-global in MuJoCo).
inline void install_mujoco_hooks() {
  static std::once_flag once;
  std::call_once(once, [] {
    mujoco_previous_error = mju_user_error;
    mujoco_previous_warning = mju_user_warning;
    mju_user_error = mujoco_error_hook;
    mju_user_warning = mujoco_warning_hook;
  });
}

/// Runs body() (MuJoCo calls) so that MuJoCo's error hook returns here:
/// true when body() finished, false when it called the hook (jump.message
/// says why). Nothing between here and MuJoCo may own a resource.
template <class Body>
bool run_protected(MujocoJump& jump, std::uint64_t& warnings, Body& body) noexcept {
  MujocoJump* const outer = mujoco_jump;
  std::uint64_t* const outer_warnings = mujoco_warning_count;
  mujoco_jump = &jump;
  mujoco_warning_count = &warnings;
  if (setjmp(jump.buffer) == 0) {
    body();
    mujoco_jump = outer;
    mujoco_warning_count = outer_warnings;
    return true;
  }
  mujoco_jump = outer;
  mujoco_warning_count = outer_warnings;
  return false;
}

/// The device frame (y up, z toward the user) to MuJoCo's z-up scene frame
/// (y away from the user): (x, y, z) -> (x, -z, y), a rotation.
[[nodiscard]] inline glm::dvec3 device_to_scene(const glm::dvec3& d) noexcept {
  return {d.x, -d.z, d.y};
}
[[nodiscard]] inline glm::dvec3 scene_to_device(const glm::dvec3& s) noexcept {
  return {s.x, s.z, -s.y};
}
[[nodiscard]] inline glm::dvec3 vec(const mjtNum* p) noexcept {
  return {p[0], p[1], p[2]};
}

struct ModelDeleter {
  void operator()(mjModel* m) const noexcept { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const noexcept { mj_deleteData(d); }
};

}  // namespace detail

class MujocoBridge {
 public:
  /// Loads the scene (MJCF).
  /// @throws std::invalid_argument for a bad configuration, FileError for a
  ///         missing or unreadable file or MJCF MuJoCo refuses (its message),
  ///         MujocoError for a scene without a usable tool or a MuJoCo
  ///         library that does not match the headers.
  explicit MujocoBridge(const std::string& path, MujocoBridgeConfig config = {}) : config_(std::move(config)) {
    config_.validate();
    if (mj_version() != mjVERSION_HEADER)
      throw MujocoError("MuJoCo library version " + std::to_string(mj_version()) + " does not match the headers (" +
                        std::to_string(mjVERSION_HEADER) + ")");
    detail::install_mujoco_hooks();
    period_ = 1.0 / config_.rate;
    scene_ = open(path);
    publish_model();
  }
  MujocoBridge(const MujocoBridge&) = delete;
  MujocoBridge& operator=(const MujocoBridge&) = delete;
  ~MujocoBridge() { stop(); }

  /// The channels the servo side reads and writes.
  [[nodiscard]] LocalModelLink& link() noexcept { return link_; }
  /// The field the servo loop renders: one per bridge (the link has one
  /// reader and one writer on each side).
  [[nodiscard]] LocalModelField field() noexcept { return LocalModelField(link_); }

  /// One simulator step (the threaded runner calls it at the rate; tests
  /// call it on their own clock). False when the simulator is faulted.
  bool step_once() noexcept {
    std::lock_guard<std::mutex> lock(mutex_);
    if (faulted_) {
      publish_model();
      return false;
    }
    const std::int64_t started = now();
    Scene& s = *scene_;
    mjModel* m = s.model.get();
    mjData* d = s.data.get();
    const HandleSample* handle = link_.handle.latest();
    const int old_bad = bad_state_warnings(d);
    std::uint64_t warnings = 0;
    auto body = [&] {
      mju_zero(d->xfrc_applied, 6 * m->nbody);
      if (handle != nullptr) apply_impulses(*handle);
      for (int k = 0; k < s.substeps; ++k) {
        if (config_.before_step) config_.before_step(m, d);
        place_tool(handle, d);
        mj_step(m, d);
      }
      place_tool(handle, d);
      mj_fwdPosition(m, d);
      mj_fwdVelocity(m, d);
    };
    const bool finished = detail::run_protected(jump_, warnings, body);
    events_.warnings.fetch_add(warnings, std::memory_order_relaxed);
    if (!finished) {
      events_.mujoco_errors.fetch_add(1, std::memory_order_relaxed);
      latch(SimulatorFault::mujoco_error, std::string("MuJoCo error: ") + jump_.message);
    } else if (bad_state_warnings(d) != old_bad || !finite_state(m, d)) {
      events_.non_finite.fetch_add(1, std::memory_order_relaxed);
      latch(SimulatorFault::non_finite, "the simulator's state turned non-finite");
    }
    sim_time_ += period_;
    events_.steps.fetch_add(1, std::memory_order_relaxed);
    publish_model();
    // in lockstep the wall clock says nothing of the servo's time: no overrun
    if (!link_.lockstep.load(std::memory_order_relaxed) && now() - started > static_cast<std::int64_t>(period_ * 1e9))
      events_.overruns.fetch_add(1, std::memory_order_relaxed);
    return !faulted_;
  }

  /// Steps on a thread of its own: in lockstep when config().lockstep (see
  /// start(bool)), else at the rate in real time. Does nothing when running.
  void start() { start(config_.lockstep); }

  /// Steps on a thread of its own. Real time (lockstep false): at the rate
  /// (absolute deadlines; after an overrun the late steps are skipped, not
  /// bunched). Lockstep: step j when the servo's time (HandleSample::time)
  /// reaches j T, counted from the servo time at start (no steps to catch
  /// up), the field waiting for each; for loops on a virtual clock only (a
  /// real-time loop would wait on a slow simulator). Does nothing when
  /// running.
  void start(bool lockstep) {
    if (thread_.joinable()) return;
    stop_requested_.store(false, std::memory_order_release);
    if (lockstep) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const HandleSample* h = link_.handle.latest();
        lockstep_step_.store(h != nullptr ? lockstep_steps_due(h->time, period_) : 0, std::memory_order_relaxed);
        publish_model();  // the step due now is the one taken
      }
      link_.lockstep.store(true, std::memory_order_release);
      thread_ = std::thread([this] { run_lockstep(); });
      return;
    }
    thread_ = std::thread([this] {
      using Clock = std::chrono::steady_clock;
      const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(period_ * 1e9));
      auto next = Clock::now();
      while (!stop_requested_.load(std::memory_order_acquire)) {
        (void)step_once();
        next += period;
        const auto late = Clock::now();
        if (late > next + period) next = late;  // skip the missed steps
        std::this_thread::sleep_until(next);
      }
    });
  }
  /// Stops the thread (the field then sees a stall and gives zero force).
  /// In lockstep, the steps the servo's time has made due are taken first.
  void stop() noexcept {
    stop_requested_.store(true, std::memory_order_release);
    if (thread_.joinable()) thread_.join();
    link_.lockstep.store(false, std::memory_order_release);
  }
  [[nodiscard]] bool running() const noexcept { return thread_.joinable(); }
  /// True while the thread steps in lockstep with the servo's time.
  [[nodiscard]] bool lockstep_running() const noexcept { return link_.lockstep.load(std::memory_order_acquire); }

  /// Changes the scene (call from any thread but the servo's): loads it here,
  /// swaps it in between two steps; the field fades its force in again.
  /// @throws as the constructor; the old scene stays on failure.
  void load(const std::string& path) {
    std::unique_ptr<Scene> next = open(path);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      std::swap(scene_, next);
      ++scene_id_;
      faulted_ = false;
      fault_ = SimulatorFault::none;
      sim_time_ = 0.0;
      events_.scene_changes.fetch_add(1, std::memory_order_relaxed);
      publish_model();
    }
  }

  /// Clears a latched fault: the scene starts again from its initial state
  /// (a new scene to the field, so the force fades in).
  void clear_fault() {
    std::lock_guard<std::mutex> lock(mutex_);
    mj_resetData(scene_->model.get(), scene_->data.get());
    scene_->tool_placed = false;
    scene_->applied_impulse.fill(glm::dvec3{0.0});
    scene_->applied_angular.fill(glm::dvec3{0.0});
    ++scene_id_;
    faulted_ = false;
    fault_ = SimulatorFault::none;
    publish_model();
  }

  [[nodiscard]] bool faulted() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return faulted_;
  }
  [[nodiscard]] SimulatorFault fault() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return fault_;
  }
  /// One line saying why the simulator stopped (empty: no fault).
  [[nodiscard]] std::string fault_message() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return fault_message_;
  }
  [[nodiscard]] MujocoEvents events() const noexcept {
    return {events_.steps.load(),         events_.overruns.load(), events_.non_finite.load(),
            events_.mujoco_errors.load(), events_.warnings.load(), events_.scene_changes.load()};
  }
  [[nodiscard]] double period() const noexcept { return period_; }
  /// The tool's radius in the current scene [m].
  [[nodiscard]] double tool_radius() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return scene_->tool_radius;
  }
  [[nodiscard]] const MujocoBridgeConfig& config() const noexcept { return config_; }

  // ---- inspection: between step_once() calls, never while start()ed ----

  /// Simulated time since the scene started [s].
  [[nodiscard]] double simulated_time() const noexcept { return sim_time_; }
  [[nodiscard]] const mjModel* model() const noexcept { return scene_->model.get(); }
  [[nodiscard]] const mjData* data() const noexcept { return scene_->data.get(); }
  /// A body's id, or -1.
  [[nodiscard]] int body_id(const std::string& name) const noexcept {
    return mj_name2id(scene_->model.get(), mjOBJ_BODY, name.c_str());
  }
  /// A body's centre of mass, its velocity (device frame) and its mass.
  /// @throws std::invalid_argument for an unknown body.
  [[nodiscard]] BodyState body(const std::string& name) const {
    const int b = body_id(name);
    if (b < 0) throw std::invalid_argument("MujocoBridge: no body '" + name + "' in the scene");
    const mjModel* m = scene_->model.get();
    const mjData* d = scene_->data.get();
    mjtNum v[6];
    mj_objectVelocity(m, d, mjOBJ_BODY, b, v, 0);
    return {to_device_point(detail::vec(d->xipos + 3 * b)), detail::scene_to_device(detail::vec(v + 3)),
            m->body_mass[b]};
  }
  /// A joint's position (qpos[0] of it: an angle [rad] or a slide [m]).
  /// @throws std::invalid_argument for an unknown joint.
  [[nodiscard]] double joint_position(const std::string& name) const {
    const int j = mj_name2id(scene_->model.get(), mjOBJ_JOINT, name.c_str());
    if (j < 0) throw std::invalid_argument("MujocoBridge: no joint '" + name + "' in the scene");
    return scene_->data->qpos[scene_->model->jnt_qposadr[j]];
  }
  /// Kinetic energy plus gravity's potential energy of every moving body
  /// [J]: the tool counts with its kinetic energy in virtual_coupling mode
  /// (its weight is cancelled), not at all in local_model mode (there it is
  /// the hand's, placed on the HIP).
  [[nodiscard]] double scene_energy() const noexcept {
    const mjModel* m = scene_->model.get();
    const mjData* d = scene_->data.get();
    double energy = 0.0;
    for (int b = 1; b < m->nbody; ++b) {
      const bool tool = b == scene_->tool;
      if ((tool && config_.mode == CouplingMode::local_model) || m->body_weldid[b] == 0) continue;
      mjtNum v[6];
      mj_objectVelocity(m, d, mjOBJ_BODY, b, v, 1);  // local: rot about the principal axes, then lin
      const double mass = m->body_mass[b];
      const mjtNum* inertia = m->body_inertia + 3 * b;
      energy += 0.5 * mass * (v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
      energy += 0.5 * (inertia[0] * v[0] * v[0] + inertia[1] * v[1] * v[1] + inertia[2] * v[2] * v[2]);
      if (tool) continue;
      energy -= mass * (m->opt.gravity[0] * d->xipos[3 * b] + m->opt.gravity[1] * d->xipos[3 * b + 1] +
                        m->opt.gravity[2] * d->xipos[3 * b + 2]);
    }
    for (int j = 0; j < m->njnt; ++j) {  // joint springs of hinges and slides
      if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE) continue;
      const int a = m->jnt_qposadr[j];
      const double stretch = d->qpos[a] - m->qpos_spring[a];
      energy += 0.5 * m->jnt_stiffness[j] * stretch * stretch;
    }
    return energy;
  }

 private:
  struct Scene {
    std::unique_ptr<mjModel, detail::ModelDeleter> model;
    std::unique_ptr<mjData, detail::DataDeleter> data;
    int tool{-1};
    int tool_qpos{0};
    int tool_dof{0};
    double tool_radius{0.0};
    int substeps{1};
    std::array<glm::dvec3, local_model_max_bodies> applied_impulse{};
    std::array<glm::dvec3, local_model_max_bodies> applied_angular{};
    std::uint32_t epoch{0};
    bool tool_placed{false};  ///< virtual_coupling: the tool was put on the HIP
    bool sample_seen{false};  ///< a handle sample of this scene was applied
    double sample_time{0.0};  ///< its servo time [s]
  };

  std::unique_ptr<Scene> open(const std::string& path) const {
    (void)check_file(path);
    auto s = std::make_unique<Scene>();
    char error[512] = "";
    s->model.reset(mj_loadXML(path.c_str(), nullptr, error, sizeof error));
    if (!s->model) throw FileError("MuJoCo cannot load '" + path + "': " + error);
    mjModel* m = s->model.get();
    s->tool = mj_name2id(m, mjOBJ_BODY, config_.tool_body.c_str());
    if (s->tool < 0) throw MujocoError("'" + path + "' has no tool body '" + config_.tool_body + "'");
    if (m->body_jntnum[s->tool] != 1 || m->jnt_type[m->body_jntadr[s->tool]] != mjJNT_FREE)
      throw MujocoError("'" + path + "': the tool body '" + config_.tool_body + "' must have one free joint");
    if (m->body_mass[s->tool] <= 0.0)
      throw MujocoError("'" + path + "': the tool body '" + config_.tool_body + "' must have a mass");
    s->tool_qpos = m->jnt_qposadr[m->body_jntadr[s->tool]];
    s->tool_dof = m->jnt_dofadr[m->body_jntadr[s->tool]];
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_bodyid[g] != s->tool) continue;
      if (m->geom_type[g] == mjGEOM_SPHERE && s->tool_radius == 0.0) s->tool_radius = m->geom_size[3 * g];
      if (config_.mode == CouplingMode::local_model) {  // found, listed, never solved
        m->geom_margin[g] = config_.detect_distance;
        m->geom_gap[g] = 1e3;
      }
    }
    if (!(s->tool_radius > 0.0))
      throw MujocoError("'" + path + "': the tool body '" + config_.tool_body + "' needs a sphere geom");
    s->substeps = std::max(1, static_cast<int>(std::lround(period_ / m->opt.timestep)));
    m->opt.timestep = period_ / s->substeps;
    std::uint64_t warnings = 0;
    MujocoJump jump;
    mjData* made = nullptr;
    auto make = [&] {
      made = mj_makeData(m);
      if (made != nullptr) mj_forward(m, made);
    };
    if (!detail::run_protected(jump, warnings, make) || made == nullptr) {
      if (made != nullptr) mj_deleteData(made);
      throw MujocoError("'" + path + "': MuJoCo cannot make its data: " + jump.message);
    }
    s->data.reset(made);
    return s;
  }
  using MujocoJump = detail::MujocoJump;

  /// The lockstep runner: steps while the servo's time has made steps due,
  /// spinning with yield between (then sleeping 0.1 ms once the servo has
  /// been idle for a while); on stop, the steps due are taken first.
  void run_lockstep() {
    int idle = 0;
    for (;;) {
      const bool stopping = stop_requested_.load(std::memory_order_acquire);
      std::uint64_t due = 0;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const HandleSample* h = link_.handle.latest();
        due = h != nullptr ? lockstep_steps_due(h->time, period_) : 0;
      }
      if (due > lockstep_step_.load(std::memory_order_relaxed)) {
        lockstep_step_.fetch_add(1, std::memory_order_relaxed);
        (void)step_once();  // with the newest sample: the servo waits for this step's model
        idle = 0;
        continue;
      }
      if (stopping) return;
      if (++idle < 10000)
        std::this_thread::yield();
      else
        std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }

  [[nodiscard]] std::int64_t now() const {
    if (config_.clock) return config_.clock();
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  [[nodiscard]] glm::dvec3 to_device_point(const glm::dvec3& s) const noexcept {
    return detail::scene_to_device(s - config_.scene_origin);
  }
  [[nodiscard]] glm::dvec3 to_scene_point(const glm::dvec3& d) const noexcept {
    return detail::device_to_scene(d) + config_.scene_origin;
  }

  static int bad_state_warnings(const mjData* d) noexcept {
    return d->warning[mjWARN_BADQPOS].number + d->warning[mjWARN_BADQVEL].number + d->warning[mjWARN_BADQACC].number;
  }
  static bool finite_state(const mjModel* m, const mjData* d) noexcept {
    for (int i = 0; i < m->nq; ++i)
      if (!std::isfinite(d->qpos[i])) return false;
    for (int i = 0; i < m->nv; ++i)
      if (!std::isfinite(d->qvel[i]) || !std::isfinite(d->qacc[i])) return false;
    return true;
  }

  /// The impulse each body got since the last step, spread over this step.
  void apply_impulses(const HandleSample& h) noexcept {
    Scene& s = *scene_;
    if (h.scene != scene_id_) return;  // the servo has not seen this scene yet
    if (h.epoch != s.epoch) {
      s.epoch = h.epoch;
      s.applied_impulse.fill(glm::dvec3{0.0});
      s.applied_angular.fill(glm::dvec3{0.0});
    }
    // after a stall the servo rendered a frozen model for up to stall_time:
    // that backlog is dropped, not delivered in one step as a burst
    const bool backlog = s.sample_seen && h.time - s.sample_time > 2.0 * period_ + 1e-9;
    s.sample_seen = true;
    s.sample_time = h.time;
    const mjModel* m = s.model.get();
    mjData* d = s.data.get();
    const int bodies = std::min(m->nbody, local_model_max_bodies);
    for (int b = 1; b < bodies; ++b) {
      const auto i = static_cast<std::size_t>(b);
      const glm::dvec3 dj = h.impulse[i] - s.applied_impulse[i];
      const glm::dvec3 dl = h.angular_impulse[i] - s.applied_angular[i];
      if (!is_finite(dj) || !is_finite(dl)) continue;
      s.applied_impulse[i] = h.impulse[i];
      s.applied_angular[i] = h.angular_impulse[i];
      if (backlog || (dj == glm::dvec3{0.0} && dl == glm::dvec3{0.0})) continue;
      // scene frame: p_s = R p_d + o, so L_s = R L_d + o x R J_d; the torque about the centre of mass c
      const glm::dvec3 j = detail::device_to_scene(dj);
      const glm::dvec3 l = detail::device_to_scene(dl) + glm::cross(config_.scene_origin, j);
      const glm::dvec3 c = detail::vec(d->xipos + 3 * b);
      const glm::dvec3 force = j / period_;
      const glm::dvec3 torque = (l - glm::cross(c, j)) / period_;
      for (int k = 0; k < 3; ++k) {
        d->xfrc_applied[6 * b + k] += force[k];
        d->xfrc_applied[6 * b + 3 + k] += torque[k];
      }
    }
    if (config_.mode == CouplingMode::virtual_coupling)  // the tool's weight is the scene's, not the hand's
      for (int k = 0; k < 3; ++k)
        d->xfrc_applied[6 * s.tool + k] -= m->body_subtreemass[s.tool] * m->opt.gravity[k];
  }

  /// local_model mode: the tool on the HIP (no rotation), at its velocity,
  /// every step; virtual_coupling mode: once, when a scene first sees the
  /// HIP (the coupling starts relaxed, never with a jerk).
  void place_tool(const HandleSample* h, mjData* d) noexcept {
    if (h == nullptr || !h->valid) return;
    Scene& s = *scene_;
    if (config_.mode == CouplingMode::virtual_coupling) {
      if (s.tool_placed) return;
      s.tool_placed = true;
    }
    const glm::dvec3 p = to_scene_point(h->position);
    const glm::dvec3 v = detail::device_to_scene(h->velocity);
    mjtNum* q = d->qpos + s.tool_qpos;
    mjtNum* w = d->qvel + s.tool_dof;
    for (int k = 0; k < 3; ++k) {
      q[k] = p[k];
      w[k] = v[k];
      w[3 + k] = 0.0;
    }
    q[3] = 1.0;
    q[4] = q[5] = q[6] = 0.0;
  }

  void latch(SimulatorFault fault, std::string message) {
    faulted_ = true;
    fault_ = fault;
    fault_message_ = std::move(message);
  }

  void publish_model() noexcept {
    const Scene& s = *scene_;
    const mjModel* m = s.model.get();
    const mjData* d = s.data.get();
    LocalModel out;
    out.sequence = ++sequence_;
    out.scene = scene_id_;
    out.fault = faulted_;
    out.lockstep_step = lockstep_step_.load(std::memory_order_relaxed);
    out.mode = config_.mode;
    out.tool_radius = s.tool_radius;
    out.period = period_;
    out.stall_time = config_.stall_time;
    out.fade_time = config_.fade_time;
    out.tool_body = s.tool < local_model_max_bodies ? s.tool : static_body;
    out.coupling_stiffness = config_.coupling.stiffness;
    out.coupling_damping = config_.coupling.damping;
    if (!faulted_) {
      mjtNum v[6];
      mj_objectVelocity(m, d, mjOBJ_XBODY, s.tool, v, 0);
      out.tool_position = to_device_point(detail::vec(d->xpos + 3 * s.tool));
      out.tool_velocity = detail::scene_to_device(detail::vec(v + 3));
      if (config_.mode == CouplingMode::local_model) collect_planes(out);
    }
    link_.model.publish(out);
  }

  /// The tool's contacts, nearest first, as planes on the touched bodies.
  void collect_planes(LocalModel& out) const noexcept {
    const Scene& s = *scene_;
    const mjModel* m = s.model.get();
    const mjData* d = s.data.get();
    std::array<double, local_model_max_planes> distance{};
    int count = 0;
    for (int i = 0; i < d->ncon; ++i) {
      const mjContact& c = d->contact[i];
      const int b1 = m->geom_bodyid[c.geom1];
      const int b2 = m->geom_bodyid[c.geom2];
      if ((b1 == s.tool) == (b2 == s.tool)) continue;  // not the tool's, or the tool with itself
      if (!(c.dist < config_.detect_distance) || !std::isfinite(c.dist)) continue;
      const int other = b1 == s.tool ? b2 : b1;
      // frame[0..2] points from geom1 to geom2; n points from the other body to the tool
      glm::dvec3 n = detail::vec(c.frame);
      if (b1 == s.tool) n = -n;
      const glm::dvec3 pos = detail::vec(c.pos);
      const glm::dvec3 surface = pos - n * (c.dist / 2.0);
      glm::dvec3 velocity{0.0};
      int body = static_body;
      if (m->body_weldid[other] != 0) {
        mjtNum v[6];
        mj_objectVelocity(m, d, mjOBJ_BODY, other, v, 0);  // world frame, at the centre of mass
        velocity = detail::vec(v + 3) + glm::cross(detail::vec(v), surface - detail::vec(d->xipos + 3 * other));
        if (other < local_model_max_bodies) body = other;
      }
      ContactPlane plane{to_device_point(surface), detail::scene_to_device(n), detail::scene_to_device(velocity),
                         config_.plane_stiffness,  config_.plane_damping,      body};
      plane.static_friction = config_.plane_static_friction;
      plane.dynamic_friction = config_.plane_dynamic_friction;
      if (!is_finite(plane.point) || !is_finite(plane.normal) || !is_finite(plane.velocity)) continue;
      // keep the nearest local_model_max_planes, sorted by distance
      int at = count;
      if (count == local_model_max_planes) {
        if (!(c.dist < distance[local_model_max_planes - 1])) continue;
        at = local_model_max_planes - 1;  // the farthest makes way
      } else {
        ++count;
      }
      while (at > 0 && distance[static_cast<std::size_t>(at - 1)] > c.dist) {
        out.planes[static_cast<std::size_t>(at)] = out.planes[static_cast<std::size_t>(at - 1)];
        distance[static_cast<std::size_t>(at)] = distance[static_cast<std::size_t>(at - 1)];
        --at;
      }
      out.planes[static_cast<std::size_t>(at)] = plane;
      distance[static_cast<std::size_t>(at)] = c.dist;
    }
    out.plane_count = count;
  }

  MujocoBridgeConfig config_;
  double period_{0.01};
  std::unique_ptr<Scene> scene_;
  LocalModelLink link_;
  mutable std::mutex mutex_;
  MujocoJump jump_;
  std::uint64_t sequence_{0};
  std::uint32_t scene_id_{1};
  double sim_time_{0.0};
  bool faulted_{false};
  SimulatorFault fault_{SimulatorFault::none};
  std::string fault_message_;
  struct AtomicEvents {
    std::atomic<std::uint64_t> steps{0}, overruns{0}, non_finite{0}, mujoco_errors{0}, warnings{0}, scene_changes{0};
  } events_;
  std::thread thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<std::uint64_t> lockstep_step_{0};  ///< lockstep: the steps taken (see LocalModel::lockstep_step)
};

}  // namespace hapticfield
