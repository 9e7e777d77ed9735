#pragma once
/// @file openhaptics_device.hpp
/// OpenHapticsDevice: a 3D Systems Touch / Phantom through the OpenHaptics
/// HDAPI, loaded at run time (libHD.so; hd_api.hpp). HD owns the 1 kHz
/// servo thread: every device call must happen inside a callback of its
/// scheduler, between hdBeginFrame and hdEndFrame. The device schedules one
/// callback of its own at the highest priority; each HD tick it latches the
/// state, applies the newest force our loop commanded and publishes the
/// state through two lock-free rings (rt/spsc_ring.hpp). Our ServoLoop (any
/// clock, any thread, through AnyDevice too) then runs on it like on any
/// Device, with its safety chain, statistics, trusted-pose rule and stop
/// semantics unchanged; the price is one HD tick between a state and the
/// force computed from it. Never run on a real arm: docs/arms-openhaptics.md.

#include <atomic>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>

#include <glm/vec3.hpp>

#include "hapticfield/arms/openhaptics/hd_api.hpp"
#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"
#include "hapticfield/rt/spsc_ring.hpp"

namespace hapticfield {

struct OpenHapticsConfig {
  std::string device_name{};  ///< hdInitDevice name as configured in Touch_Setup; "": HD_DEFAULT_DEVICE
  /// A libHD to load instead of libHD.so (a path); "": libHD.so, or
  /// $HAPTICFIELD_HD_LIBRARY when set.
  std::string library{};
  double scheduler_rate{1000.0};  ///< hdSetSchedulerRate [Hz]
  /// hdInitDevice attempts when a crashed run left the device initiated
  /// (HD_DEVICE_ALREADY_INITIATED): each disables the current device first.
  int init_attempts{10};
  glm::dvec3 origin_mm{0.0};  ///< HD point [mm] that becomes our origin
  /// Force limit [N]; 0: HD_NOMINAL_MAX_FORCE as the device reports it.
  double max_force{0.0};
  /// Longest wait for the HD tick that commands zero before the scheduler
  /// is stopped at shutdown [ms].
  int shutdown_wait_ms{100};

  /// @throws std::invalid_argument naming the first bad setting.
  void validate() const {
    if (!std::isfinite(scheduler_rate) || scheduler_rate < 100.0 || scheduler_rate > 10000.0)
      throw std::invalid_argument("OpenHapticsConfig: scheduler_rate must be within [100, 10000] [Hz]");
    if (init_attempts < 1 || init_attempts > 100)
      throw std::invalid_argument("OpenHapticsConfig: init_attempts must be 1..100");
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(origin_mm[i])) throw std::invalid_argument("OpenHapticsConfig: origin_mm must be finite [mm]");
    if (!std::isfinite(max_force) || max_force < 0.0)
      throw std::invalid_argument("OpenHapticsConfig: max_force must be finite and >= 0 [N] (0: the device's)");
    if (shutdown_wait_ms < 0 || shutdown_wait_ms > 5000)
      throw std::invalid_argument("OpenHapticsConfig: shutdown_wait_ms must be 0..5000 [ms]");
  }
};

/// Counts since construction (read from the loop's thread).
struct OpenHapticsCounters {
  std::uint64_t ticks{0};           ///< HD ticks seen by read()
  std::uint64_t dropped_states{0};  ///< states the HD thread could not publish (ring full: our loop is slower)
  std::uint64_t guard_errors{0};    ///< HD_WARM_MOTORS, HD_EXCEEDED_*, HD_FORCE_ERROR
  std::uint32_t last_error{0};      ///< the last HD error code seen (0: none)
};

namespace hd {
/// Error codes that end the run: the device or its link is gone.
[[nodiscard]] constexpr bool is_fatal(ErrorCode e) noexcept {
  return e == device_fault || e == comm_error || e == timer_error || e == bad_handle || e == illegal_begin;
}
/// The four guards of our status bits each HD guard error sets (0: none).
[[nodiscard]] constexpr std::uint16_t guard_bits(ErrorCode e) noexcept {
  if (e == warm_motors) return status_bits::over_temperature;
  if (e == exceeded_max_force || e == exceeded_max_force_impulse || e == exceeded_max_velocity || e == force_error)
    return status_bits::over_current;
  return 0;
}
}  // namespace hd

class OpenHapticsDevice {
  /// One HD tick's state, in HD units (mm, mm/s).
  struct Sample {
    double position[3];
    double velocity[3];
    int buttons;
    hd::ErrorCode error;  ///< the worst error of the tick (fatal first), 0: none
    std::uint64_t tick;
  };
  struct Command {
    double force[3];  ///< [N], HD frame (= ours)
  };

 public:
  /// Loads libHD, initialises the device (retrying a device a crashed run
  /// left initiated), checks its calibration, enables force output with
  /// the device's clamps, starts the scheduler and schedules the servo
  /// callback.
  /// @throws LibraryError (libHD or a symbol missing), DeviceError (no
  ///         device, calibration needed, a scheduler error), each naming the
  ///         HD error and what to do; std::invalid_argument for a bad config.
  explicit OpenHapticsDevice(OpenHapticsConfig config = {}) : config_(std::move(config)) {
    config_.validate();
    api_ = hd::Api::load(config_.library);
    initialise();
  }

  OpenHapticsDevice(const OpenHapticsDevice&) = delete;
  OpenHapticsDevice& operator=(const OpenHapticsDevice&) = delete;

  /// Commands zero (waiting up to shutdown_wait_ms for an HD tick to apply
  /// it), then shuts down in the documented order: hdStopScheduler,
  /// hdUnschedule, hdDisableDevice.
  ~OpenHapticsDevice() { shutdown(); }

  [[nodiscard]] const DeviceInfo& info() const noexcept { return info_; }
  [[nodiscard]] const OpenHapticsConfig& config() const noexcept { return config_; }
  [[nodiscard]] const OpenHapticsCounters& counters() const noexcept { return counters_; }
  /// The library loaded (its name or path).
  [[nodiscard]] const std::string& library() const noexcept { return api_.library.name(); }
  /// The model HD reports (HD_DEVICE_MODEL_TYPE).
  [[nodiscard]] const std::string& model() const noexcept { return model_; }
  /// HD ticks run by the scheduler so far (any thread).
  [[nodiscard]] std::uint64_t scheduler_ticks() const noexcept { return hd_ticks_.load(std::memory_order_acquire); }

  /// The newest HD tick's state in our frame (HD's axes are ours: x right,
  /// y up, z toward the user; mm to m). no_data when no tick ran since the
  /// last read (a scheduler that stopped calling shows as no new state:
  /// the loop's stale-state guard zeroes the force and latches);
  /// disconnected after HD_DEVICE_FAULT, HD_COMM_ERROR, HD_TIMER_ERROR.
  /// HD_WARM_MOTORS sets over_temperature, HD_EXCEEDED_* and HD_FORCE_ERROR
  /// over_current, held until clear_fault().
  Status read(DeviceState& state) noexcept {
    Sample newest{};
    bool fresh = false;
    while (auto s = states_.try_pop()) {
      ++counters_.ticks;
      take_error(s->error);
      newest = *s;
      fresh = true;
    }
    counters_.dropped_states = states_.rejected();
    if (fatal_) return Status::disconnected;
    if (!fresh) return Status::no_data;
    publish(newest, state);
    return Status::ok;
  }

  /// Posts a force [N] in our frame for the next HD tick; magnitude clamped
  /// to max_force, zero when disarmed, faulted or non-finite.
  Status write(const glm::dvec3& force) noexcept {
    const Command c = command_for(force);
    if (!commands_.try_push(c)) return Status::overflow;  // the HD thread is behind: it still has a newer one
    return fatal_ ? Status::disconnected : Status::ok;
  }

  /// Our gate on force output: off commands zero from the next HD tick on.
  Status set_armed(bool on) noexcept {
    armed_.store(on, std::memory_order_relaxed);
    if (!on) commands_.try_push(Command{{0.0, 0.0, 0.0}});
    return fatal_ ? Status::disconnected : Status::ok;
  }
  /// The Touch needs no homing once calibrated (checked at construction).
  Status request_home() noexcept { return Status::ok; }
  /// Clears the guard faults (HD_WARM_MOTORS, HD_EXCEEDED_*); a fatal
  /// error stays (Status::disconnected).
  Status clear_fault() noexcept {
    if (fatal_) return Status::disconnected;
    guard_flags_ = 0;
    return Status::ok;
  }

  /// Schedules another callback with HD (hdScheduleAsynchronous) at the
  /// highest priority; 0 and the error in last_error() when HD refuses.
  hd::SchedulerHandle schedule(hd::Callback callback, void* data) noexcept {
    const hd::SchedulerHandle h = api_.schedule_asynchronous(callback, data, hd::max_scheduler_priority);
    const hd::ErrorCode e = api_.get_error().error_code;
    if (e == hd::success) return h;
    counters_.last_error = e;
    return 0;
  }
  /// Removes a callback schedule() added (hdUnschedule).
  void unschedule(hd::SchedulerHandle h) noexcept {
    if (h != 0) api_.unschedule(h);
  }

  /// For OpenHapticsServo, which runs our tick inside its own HD callback:
  /// while direct, the device's own callback leaves the frames alone.
  void set_direct(bool on) noexcept { direct_.store(on, std::memory_order_release); }

  /// Inside an HD callback: begins this tick's frame and reads the state
  /// (as read() does, without the rings). Outside one (live false): no_data.
  Status read_frame(DeviceState& state, bool live) noexcept {
    if (fatal_) return Status::disconnected;
    if (!live) return Status::no_data;
    Sample s{};
    api_.make_current_device(handle_);
    api_.begin_frame(handle_);
    frame_open_ = true;
    api_.get_doublev(hd::current_position, s.position);
    api_.get_doublev(hd::current_velocity, s.velocity);
    api_.get_integerv(hd::current_buttons, &s.buttons);
    s.tick = counters_.ticks++;
    take_error(drain_errors());
    if (fatal_) return Status::disconnected;
    publish(s, state);
    return Status::ok;
  }

  /// Inside an HD callback: sets the force [N, our frame] (clamped, zero
  /// when disarmed, faulted or non-finite) and ends the frame (opening one
  /// when the tick has none, as a stop's zero after the tick's own write).
  /// Outside one (live false): remembered only; HD is not called.
  Status write_frame(const glm::dvec3& force, bool live) noexcept {
    const Command c = command_for(force);
    if (!live) return fatal_ ? Status::disconnected : Status::ok;
    if (!frame_open_) {
      api_.make_current_device(handle_);
      api_.begin_frame(handle_);
    }
    api_.set_doublev(hd::current_force, c.force);
    api_.end_frame(handle_);
    frame_open_ = false;
    take_error(drain_errors());
    return fatal_ ? Status::disconnected : Status::ok;
  }

  /// A message for the last HD error seen, "" when none.
  [[nodiscard]] std::string last_error() const {
    return counters_.last_error == 0 ? std::string{} : "OpenHaptics: " + api_.describe(counters_.last_error);
  }

 private:
  /// What a force [N] becomes on the arm: clamped, zero when disarmed,
  /// faulted or non-finite.
  [[nodiscard]] Command command_for(const glm::dvec3& force) const noexcept {
    Command c{{0.0, 0.0, 0.0}};
    const bool finite = std::isfinite(force.x) && std::isfinite(force.y) && std::isfinite(force.z);
    if (armed_.load(std::memory_order_relaxed) && guard_flags_ == 0 && finite) {
      const double m = std::sqrt(force.x * force.x + force.y * force.y + force.z * force.z);
      const double k = m > info_.max_force ? info_.max_force / m : 1.0;
      for (int i = 0; i < 3; ++i)
        c.force[i] = force[i] * k;
    }
    return c;
  }

  /// Notes one tick's error: fatal ones end the run, guard errors set
  /// their fault bits until clear_fault().
  void take_error(hd::ErrorCode e) noexcept {
    if (e == hd::success) return;
    counters_.last_error = e;
    if (hd::is_fatal(e)) fatal_ = true;
    if (const std::uint16_t bits = hd::guard_bits(e)) {
      guard_flags_ |= bits;
      ++counters_.guard_errors;
    }
  }

  /// The worst of the errors HD has queued on this thread: fatal over
  /// guard over the rest (0: none).
  hd::ErrorCode drain_errors() noexcept {
    hd::ErrorCode worst = hd::success;
    for (int i = 0; i < 8; ++i) {
      const hd::ErrorCode e = api_.get_error().error_code;
      if (e == hd::success) break;
      if (hd::is_fatal(e) || (!hd::is_fatal(worst) && (hd::guard_bits(e) || worst == hd::success))) worst = e;
    }
    return worst;
  }

  /// One HD sample in our frame (HD's axes are ours; mm to m).
  void publish(const Sample& s, DeviceState& state) const noexcept {
    constexpr double m_per_mm = 1e-3;
    for (int i = 0; i < 3; ++i) {
      state.position[i] = (s.position[i] - config_.origin_mm[i]) * m_per_mm;
      state.velocity[i] = s.velocity[i] * m_per_mm;
    }
    state.buttons = static_cast<std::uint8_t>(s.buttons & 0xff);
    state.device_time = static_cast<double>(s.tick) / config_.scheduler_rate;
    state.sequence = static_cast<std::uint16_t>(s.tick & 0xffff);
    state.flags = static_cast<std::uint16_t>(status_bits::homed | guard_flags_ |
                                             (armed_.load(std::memory_order_relaxed) ? status_bits::armed : 0));
    state.valid = true;
  }

  void initialise() {
    const char* name = config_.device_name.empty() ? hd::default_device : config_.device_name.c_str();
    const std::string shown = config_.device_name.empty() ? "the default device" : "'" + config_.device_name + "'";
    clear_errors();
    handle_ = api_.init_device(name);
    hd::ErrorInfo e = api_.get_error();
    for (int attempt = 1; attempt < config_.init_attempts && e.error_code == hd::device_already_initiated; ++attempt) {
      // Left initiated by a run that crashed: disable it and try again.
      clear_errors();
      api_.disable_device(api_.get_current_device());
      clear_errors();
      handle_ = api_.init_device(name);
      e = api_.get_error();
    }
    if (e.error_code != hd::success || handle_ == hd::invalid_handle)
      throw DeviceError("OpenHaptics: hdInitDevice(" + shown + ") failed: " + api_.describe(e.error_code) +
                        (e.error_code == hd::device_already_initiated
                             ? "; another program holds the device, or a crashed run left it initiated"
                             : "; is the Touch driver installed, the device plugged in and configured with "
                               "Touch_Setup?"));
    initiated_ = true;
    clear_errors();
    const hd::Enum calibration = api_.check_calibration();
    if (calibration != hd::calibration_ok) {
      fail_closed();
      throw DeviceError(std::string("OpenHaptics: the device needs calibration (") +
                        (calibration == hd::calibration_needs_manual_input ? "HD_CALIBRATION_NEEDS_MANUAL_INPUT"
                         : calibration == hd::calibration_needs_update     ? "HD_CALIBRATION_NEEDS_UPDATE"
                                                                           : "an unknown hdCheckCalibration result") +
                        "): put the stylus in its inkwell, or calibrate it with Touch_Diagnostic, then try again");
    }
    api_.make_current_device(handle_);
    api_.enable(hd::force_output);
    api_.enable(hd::max_force_clamping);
    api_.enable(hd::software_force_limit);
    api_.set_scheduler_rate(static_cast<hd::ULong>(std::lround(config_.scheduler_rate)));
    check("enabling force output and setting the scheduler rate");
    double value = 0.0;
    api_.get_doublev(hd::nominal_max_force, &value);
    const double nominal = value;
    value = 0.0;
    api_.get_doublev(hd::nominal_max_continuous_force, &value);
    const double continuous = value;
    double box[6]{};
    api_.get_doublev(hd::usable_workspace_dimensions, box);
    const hd::String model = api_.get_string(hd::device_model_type);
    check("reading the device's limits");
    model_ = model != nullptr && *model ? model : "OpenHaptics device";
    info_.name = "OpenHaptics " + model_;
    info_.max_force = config_.max_force > 0.0                     ? config_.max_force
                      : (std::isfinite(nominal) && nominal > 0.0) ? nominal
                                                                  : 3.3;  // Omni-like default, unverified
    info_.continuous_force =
        (std::isfinite(continuous) && continuous > 0.0 && continuous <= info_.max_force) ? continuous : info_.max_force;
    bool box_ok = true;
    for (int i = 0; i < 3; ++i)
      box_ok = box_ok && std::isfinite(box[i]) && std::isfinite(box[i + 3]) && box[i] < box[i + 3];
    if (box_ok)
      for (int i = 0; i < 3; ++i) {
        info_.workspace_min[i] = (box[i] - config_.origin_mm[i]) * 1e-3;
        info_.workspace_max[i] = (box[i + 3] - config_.origin_mm[i]) * 1e-3;
      }
    info_.nominal_rate = config_.scheduler_rate;
    info_.degrees_of_freedom = 3;
    info_.validate();
    api_.start_scheduler();
    scheduler_started_ = true;
    check("starting the scheduler (hdStartScheduler)");
    callback_ = api_.schedule_asynchronous(&OpenHapticsDevice::servo_tick, this, hd::max_scheduler_priority);
    check("scheduling the servo callback (hdScheduleAsynchronous)");
    scheduled_ = true;
  }

  /// Throws DeviceError (after shutting down) when HD reports an error.
  void check(const char* doing) {
    const hd::ErrorInfo e = api_.get_error();
    if (e.error_code == hd::success) return;
    clear_errors();
    fail_closed();
    throw DeviceError(std::string("OpenHaptics: ") + doing + " failed: " + api_.describe(e.error_code));
  }

  void clear_errors() noexcept {
    for (int i = 0; i < 64 && api_.get_error().error_code != hd::success; ++i) {
    }
  }

  void fail_closed() noexcept {
    quitting_.store(true, std::memory_order_release);
    if (scheduler_started_) api_.stop_scheduler();
    if (scheduled_) api_.unschedule(callback_);
    if (initiated_) api_.disable_device(handle_);
    scheduler_started_ = scheduled_ = initiated_ = false;
  }

  void shutdown() noexcept {
    if (!initiated_) return;
    armed_.store(false, std::memory_order_relaxed);
    quitting_.store(true, std::memory_order_release);  // the callback commands zero from now on
    const std::uint64_t seen = hd_ticks_.load(std::memory_order_acquire);
    for (int waited_us = 0; waited_us < config_.shutdown_wait_ms * 1000 && scheduler_started_ && !fatal_;
         waited_us += 200) {
      if (zeroed_ticks_.load(std::memory_order_acquire) > 0 && hd_ticks_.load(std::memory_order_acquire) > seen) break;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    fail_closed();  // hdStopScheduler, hdUnschedule, hdDisableDevice
  }

  /// The HD servo callback: one frame per tick; lock-free, no allocation.
  static hd::CallbackCode servo_tick(void* data) noexcept {
    auto& self = *static_cast<OpenHapticsDevice*>(data);
    return self.tick();
  }

  hd::CallbackCode tick() noexcept {
    const std::uint64_t n = hd_ticks_.fetch_add(1, std::memory_order_acq_rel);
    if (direct_.load(std::memory_order_acquire)) return hd::callback_continue;  // OpenHapticsServo has the frames
    Sample s{};
    api_.make_current_device(handle_);
    api_.begin_frame(handle_);
    api_.get_doublev(hd::current_position, s.position);
    api_.get_doublev(hd::current_velocity, s.velocity);
    api_.get_integerv(hd::current_buttons, &s.buttons);
    while (auto c = commands_.try_pop())
      hd_force_ = *c;
    const bool quitting = quitting_.load(std::memory_order_acquire);
    const bool zero = quitting || !armed_.load(std::memory_order_relaxed);
    const double none[3] = {0.0, 0.0, 0.0};
    api_.set_doublev(hd::current_force, zero ? none : hd_force_.force);
    api_.end_frame(handle_);
    s.error = drain_errors();
    s.tick = n;
    states_.try_push(s);  // full: our loop is behind; it reads the newest it gets
    if (quitting) zeroed_ticks_.fetch_add(1, std::memory_order_release);
    return hd::callback_continue;
  }

  OpenHapticsConfig config_;
  hd::Api api_;
  DeviceInfo info_{};
  std::string model_;
  hd::Handle handle_{hd::invalid_handle};
  hd::SchedulerHandle callback_{0};
  bool initiated_{false};
  bool scheduler_started_{false};
  bool scheduled_{false};
  // HD thread -> loop: states; loop -> HD thread: forces.
  rt::SpscRing<Sample, 64> states_;
  rt::SpscRing<Command, 64> commands_;
  Command hd_force_{{0.0, 0.0, 0.0}};  ///< the HD thread's current force
  std::atomic<bool> armed_{false};
  std::atomic<bool> quitting_{false};
  std::atomic<bool> direct_{false};
  bool frame_open_{false};  ///< direct mode: read_frame() began this tick's frame
  std::atomic<std::uint64_t> hd_ticks_{0};
  std::atomic<std::uint64_t> zeroed_ticks_{0};
  // The loop's thread only.
  OpenHapticsCounters counters_{};
  std::uint16_t guard_flags_{0};
  bool fatal_{false};
};

}  // namespace hapticfield
