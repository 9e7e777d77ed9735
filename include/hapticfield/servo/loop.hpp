#pragma once
/// @file loop.hpp
/// ServoLoop: the fixed-rate loop that reads a Device, asks a HapticField
/// (or a callback) for a force, passes it through the SafetyChain and
/// commands it. Absolute deadlines; after an overrun whole periods are
/// skipped instead of bursting; statistics every tick; an injectable clock.

#include <array>
#include <atomic>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/error.hpp"
#include "hapticfield/core/field.hpp"
#include "hapticfield/core/probe.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/rt/realtime_thread.hpp"
#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/pacer.hpp"
#include "hapticfield/servo/safety.hpp"
#include "hapticfield/servo/statistics.hpp"

namespace hapticfield {

/// Real-time scheduling request for the loop thread.
enum class RealTime : std::uint8_t {
  off,          ///< ordinary scheduling
  best_effort,  ///< ask for SCHED_FIFO, mlockall and 1 ns timer slack; run on if refused (realtime_refused())
  enforce,      ///< as best_effort, but refuse to start when anything is refused
};

/// Loop limits: rates from 1 Hz to 10 kHz.
inline constexpr double min_servo_rate = 1.0;      ///< [Hz]
inline constexpr double max_servo_rate = 10000.0;  ///< [Hz]
/// RunLimits::max_ticks for a run that ends only on request or disconnect.
inline constexpr std::uint64_t no_tick_limit = UINT64_MAX;

struct LoopConfig {
  double rate{1000.0};  ///< servo rate [Hz], 1..10000
  RealTime realtime{RealTime::best_effort};
  int priority{80};       ///< SCHED_FIFO priority (1..99)
  PacingConfig pacing{};  ///< sleep (default) or hybrid sleep-then-spin to each deadline (servo/pacer.hpp)
  SafetyConfig safety{};
  bool auto_home{true};       ///< request homing when the device is not homed
  bool auto_arm{true};        ///< request arming at start (the device arms once homed)
  bool disarm_on_exit{true};  ///< disarm when run() returns
  /// In the slack before each deadline, the field's look-ahead
  /// (core/field.hpp: anticipate() on the last HIP moved one period by its
  /// velocity), so the memory the tick reads is in cache when it runs (a
  /// proxy on a large mesh: docs/surfaces.md). Hybrid pacing runs it in
  /// its spin margin; sleep mode wakes PacingConfig::look_ahead_ns before
  /// the deadline for it and sleeps again (Pacer::wait(clock, ready)).
  /// Only while the field's looks_ahead() is true: other fields, and
  /// callbacks not made by with_anticipation(), are paced as before.
  bool anticipate{true};
  /// After a stale-state or missed-deadline latch, clear it and re-arm (with
  /// the soft start) once new states have arrived on time for this long [s];
  /// 0: never (clear_fault() only). Disconnects, impossible states and
  /// throwing callbacks never recover by themselves. When the device has
  /// latched a fault of its own meanwhile (its watchdog tripped while no
  /// command got through), the loop clears it first with the device's
  /// clear_fault() (the arm is disarmed and at zero force then; that one
  /// call is a blocking control request, bounded by the transport's
  /// timeout); a device fault that cannot be cleared (e-stop held, a device
  /// without clear_fault(), a refused clear) means no recovery. A recovery
  /// is counted in the statistics only when force has really come back.
  double recover_after{0.0};

  /// @throws std::invalid_argument naming the bad parameter.
  void validate() const {
    if (!std::isfinite(rate) || rate < min_servo_rate || rate > max_servo_rate)
      throw std::invalid_argument("LoopConfig: rate must be within [1, 10000] [Hz]");
    if (priority < 1 || priority > 99) throw std::invalid_argument("LoopConfig: priority must be within 1..99");
    if (!std::isfinite(recover_after) || recover_after < 0.0 || recover_after > 3600.0)
      throw std::invalid_argument("LoopConfig: recover_after must be within [0, 3600] [s] (0: never)");
    pacing.validate();
  }
};

/// What a callback sees each tick.
struct TickInput {
  Probe probe{};        ///< HIP state for fields
  DeviceState state{};  ///< newest device state
  Status read_status{Status::no_data};
  std::uint64_t tick{0};  ///< tick index since run() started
  bool trusted{false};    ///< the state is one to act on (ServoLoop::trusted())
};

/// A callback for ServoLoop::run() with the field it drives: the loop calls
/// the field's look-ahead ahead of each tick (LoopConfig::anticipate). Made
/// by with_anticipation().
template <class Callback, HapticField F>
struct AnticipatingCallback {
  Callback& callback;
  const F& field;
  glm::dvec3 operator()(const TickInput& in) noexcept(std::is_nothrow_invocable_v<Callback&, const TickInput&>) {
    return glm::dvec3(callback(in));
  }
  void anticipate(const Probe& next) const noexcept { anticipate_if_able(field, next); }
  [[nodiscard]] bool looks_ahead() const noexcept { return field_looks_ahead(field); }
};

/// `callback` (glm::dvec3(const TickInput&)) with the field it asks for a
/// force, whose look-ahead the loop then calls ahead of each tick. Both
/// must outlive the run.
template <class Callback, HapticField F>
[[nodiscard]] AnticipatingCallback<Callback, F> with_anticipation(Callback& callback, const F& field) noexcept {
  return AnticipatingCallback<Callback, F>{callback, field};
}

/// Why run() returned.
enum class StopReason : std::uint8_t { requested, tick_limit, disconnected };

struct RunLimits {
  std::uint64_t max_ticks{no_tick_limit};  ///< ticks before run() returns, >= 1; no_tick_limit: none

  /// @throws std::invalid_argument for max_ticks == 0.
  void validate() const {
    if (max_ticks == 0)
      throw std::invalid_argument("RunLimits: max_ticks must be >= 1 (no_tick_limit: run until stopped)");
  }
};

/// Thrown by run() after a callback threw (the arm has already been sent
/// zero force and disarmed; the callback's exception is nested, see
/// std::rethrow_if_nested), and by run() at the start when it cannot arm.
class ServoError : public Error {
 public:
  ServoError(const std::string& what, std::vector<DeviceState> last_states)
      : Error(what), last_states_(std::move(last_states)) {}
  /// The last device states before the failure, oldest first.
  [[nodiscard]] const std::vector<DeviceState>& last_states() const noexcept { return last_states_; }

 private:
  std::vector<DeviceState> last_states_;
};

/// The servo loop over a Device D on a clock C.
///
/// @code
///   SimulatedArm arm;  VirtualClock clock;
///   SimulatedTransport link(arm, [&] { return clock.now(); });
///   ForceArm device(link);
///   ServoLoop loop(device, clock);
///   loop.run(my_field, {.max_ticks = 1000});
/// @endcode
template <Device D, std::size_t N, ServoClock C>
class MultiArmLoop;

template <Device D, ServoClock C = SteadyClock>
class ServoLoop {
  template <Device, std::size_t, ServoClock>
  friend class MultiArmLoop;

 public:
  static constexpr std::size_t history_size = 8;  ///< states kept for ServoError

  /// Safety stages turned off by the configuration are not announced here:
  /// config().safety.disabled_stages() names them for the caller to show.
  /// @throws std::invalid_argument for a bad rate, priority or safety setting.
  ServoLoop(D& device, C& clock, LoopConfig config = {})
      : device_(&device),
        clock_(&clock),
        config_(config),
        safety_((config_.validate(), config_.safety), device.info().max_force),
        stats_(std::make_unique<LoopStatistics>()) {
    period_ns_ = static_cast<std::int64_t>(std::llround(1e9 / config_.rate));
    period_ = static_cast<double>(period_ns_) * 1e-9;
  }

  /// Runs a field until request_stop(), the tick limit or a disconnect.
  /// Blocks the calling thread. Every run starts the same way: zero force
  /// from the safety chain's point of view, homing and arming as configured,
  /// and the soft start from the moment the device reports armed.
  /// @throws std::invalid_argument for max_ticks == 0; ServoError when a
  ///         latched safety fault forbids arming (clear_fault() first);
  ///         std::runtime_error when RealTime::enforce is not granted.
  template <HapticField F>
  StopReason run(F& field, RunLimits limits = {}) {
    auto compute = [&field](const TickInput& in) noexcept { return glm::dvec3(field.force(in.probe)); };
    auto ahead = with_anticipation(compute, field);
    return run_impl(ahead, limits);
  }

  /// Runs a callback glm::dvec3(const TickInput&). When it throws, zero force
  /// is commanded and the arm disarmed first, then ServoError (with the
  /// last states, the callback's exception nested) is thrown. A callback
  /// with anticipate(const Probe&) const noexcept (with_anticipation())
  /// has it called ahead of each tick, as a field's.
  template <class Callback>
  requires(!HapticField<Callback> && std::is_invocable_r_v<glm::dvec3, Callback&, const TickInput&>) StopReason
      run(Callback& callback, RunLimits limits = {}) {
    return run_impl(callback, limits);
  }

  /// Asks run() to return after the current tick (any thread). A request
  /// made before run() starts ends that run before its first tick: the
  /// request is consumed by the run it stops.
  void request_stop() noexcept { stop_.store(true, std::memory_order_release); }

  /// For users who own the thread: reads the newest state and fills in.
  /// Call once per tick, then write_once().
  Status read_once(TickInput& in) noexcept {
    const std::int64_t now = clock_->now();
    if (!started_) begin(now);
    if (clear_requested_.exchange(false, std::memory_order_acq_rel)) clear_now();
    const Status s = device_->read(state_);
    if (s == Status::ok) {
      last_state_time_ = now;
      ticks_without_state_ = 0;
      history_[history_next_++ % history_size] = state_;
      if (!state_.homed() && config_.auto_home) device_->request_home();
      if (state_.armed() && armed_since_ < 0) armed_since_ = now;
      if (!state_.armed()) armed_since_ = -1;
    } else {
      ++ticks_without_state_;
      fresh_since_ = -1;
    }
    if (s == Status::ok && fresh_since_ < 0) fresh_since_ = now;
    if (s == Status::disconnected) disconnected_ = true;
    resync_ = s == Status::resync;
    // A state the device cannot be in (the device says so, or a non-finite
    // pose from any device) latches: such a pose must steer nothing.
    impossible_ =
        s == Status::impossible || (s == Status::ok && !(is_finite(state_.position) && is_finite(state_.velocity)));
    assess_trust();
    in.state = state_;
    in.read_status = s;
    in.tick = tick_;
    in.trusted = trusted_;
    in.probe = Probe{};  // contact (normal force, surface normal) is the fields' business
    in.probe.position = state_.position;
    in.probe.velocity = state_.velocity;
    in.probe.time = static_cast<double>(now - start_) * 1e-9;
    in.probe.period = period_;
    now_ = now;
    return s;
  }

  /// Passes force [N] through the safety chain and commands it.
  Status write_once(const glm::dvec3& force) noexcept {
    SafetyInput si;
    si.force = force;
    si.velocity = state_.velocity;
    si.period = period_;
    si.state_age = state_.valid ? static_cast<double>(now_ - last_state_time_) * 1e-9 : 0.0;
    si.ticks_without_state = state_.valid ? ticks_without_state_ : 0;
    si.missed_in_a_row = missed_in_a_row_;
    si.time_since_armed =
        (armed_since_ >= 0 && state_.armed()) ? static_cast<double>(now_ - armed_since_) * 1e-9 : -1.0;
    si.device_fault = state_.faulted();
    si.disconnected = disconnected_;
    si.link_resync = resync_;
    si.impossible_state = impossible_;
    const std::uint32_t before = safety_.latched();
    const glm::dvec3 out = safety_.process(si);
    if (safety_.latched() && !before) {  // the watchdog disarms, and says so
      disarm();
      stats_->add_latch(safety_.latched(), run_time());
      recovering_ = false;
    }
    if (recovering_ && out != glm::dvec3{0.0}) {  // force is back: now it is a recovery
      recovering_ = false;
      stats_->add_recovery(run_time());
    }
    maybe_recover();
    assess_trust();
    if (safety_.events() & ~(safety_events::device_fault)) stats_->add_safety_event();
    stats_->record_force(glm::length(out));
    command_ = out;
    ++tick_;
    return device_->write(out);
  }

  /// Clears a latched safety fault and re-requests arming; the force ramps
  /// up through the soft start again. Safe from any thread: the loop applies
  /// it at the start of its next tick, or at the start of the next run(),
  /// which also clears the device's own latched faults (a firmware
  /// watchdog trip) when the device has clear_fault().
  void clear_fault() noexcept { clear_requested_.store(true, std::memory_order_release); }

  [[nodiscard]] LoopSnapshot statistics() const noexcept { return stats_->snapshot(); }
  /// Starts the statistics afresh (e.g. after a warm-up).
  void reset_statistics() noexcept { stats_->reset(); }
  [[nodiscard]] const LoopStatistics& detailed_statistics() const noexcept { return *stats_; }
  [[nodiscard]] const SafetyChain& safety() const noexcept { return safety_; }
  [[nodiscard]] glm::dvec3 last_command() const noexcept { return command_; }
  /// The newest state; check trusted() before steering anything by it.
  [[nodiscard]] const DeviceState& state() const noexcept { return state_; }
  /// True when state() is a pose to act on (couple another arm to, draw a
  /// cursor at): a decoded state, homed (an unhomed pose is offset by
  /// whatever the encoders held at power-up: after a reboot, at start-up),
  /// free of device faults, armed exactly as the loop asked, fresh (fewer
  /// than max_ticks_without_state ticks without a new state), not
  /// resynchronising, not impossible, not disconnected, and no latch.
  /// Updated by read_once() and write_once().
  [[nodiscard]] bool trusted() const noexcept { return trusted_; }
  [[nodiscard]] double period() const noexcept { return period_; }
  [[nodiscard]] const LoopConfig& config() const noexcept { return config_; }
  /// True when the last real-time request was fully granted.
  [[nodiscard]] bool realtime_granted() const noexcept { return realtime_granted_; }
  /// What the last RealTime::best_effort request was refused ("" when all
  /// was granted or nothing was asked): the loop runs on and prints
  /// nothing; a tool tells its user (with rt::realtime_advice).
  [[nodiscard]] const std::string& realtime_refused() const noexcept { return realtime_refused_; }

 private:
  /// The known state every run starts from: the device was last sent zero
  /// (or nothing), so the safety chain starts from zero; no state is fresh
  /// yet; the soft start counts from the first state that reports armed.
  void begin(std::int64_t now) noexcept {
    started_ = true;
    start_ = now;
    last_state_time_ = now;
    fresh_since_ = -1;
    armed_since_ = -1;
    ticks_without_state_ = 0;
    missed_in_a_row_ = 0;
    disconnected_ = false;
    resync_ = false;
    impossible_ = false;
    recovering_ = false;
    state_.valid = false;
    trusted_ = false;
    armed_requested_ = false;
    command_ = glm::dvec3{0.0};
    safety_.restart();
    if (config_.auto_home) device_->request_home();
    if (config_.auto_arm) arm();
  }

  void clear_now() noexcept {
    safety_.clear();
    missed_in_a_row_ = 0;
    armed_since_ = -1;  // soft start again from the next armed state
    if (config_.auto_arm) arm();
  }

  void arm() noexcept {
    armed_requested_ = true;
    device_->set_armed(true);
  }
  void disarm() noexcept {
    armed_requested_ = false;
    device_->set_armed(false);
  }

  /// See trusted().
  void assess_trust() noexcept {
    trusted_ = state_.valid && state_.homed() && !state_.faulted() && state_.armed() == armed_requested_ &&
               ticks_without_state_ < config_.safety.max_ticks_without_state && !resync_ && !impossible_ &&
               !disconnected_ && safety_.latched() == 0 && is_finite(state_.position);
  }

  /// LoopConfig::recover_after: a stale-state or missed-deadline latch is
  /// cleared once states have arrived on every tick, on time, for that long,
  /// with the device's own latched fault first (it accepts that only while
  /// disarmed, as the latch left it); counted once force is back.
  void maybe_recover() noexcept {
    constexpr std::uint32_t recoverable = safety_events::stale_state | safety_events::missed_deadlines;
    const std::uint32_t latched = safety_.latched();
    if (config_.recover_after <= 0.0 || !latched || (latched & ~recoverable) || fresh_since_ < 0 ||
        missed_in_a_row_ > 0)
      return;
    if (static_cast<double>(now_ - fresh_since_) * 1e-9 < config_.recover_after) return;
    if (state_.faulted()) {
      if (state_.armed() || (state_.flags & status_bits::estop)) return;  // not yet disarmed, or held: wait
      if constexpr (requires(D & d) { d.clear_fault(); }) {
        if (device_->clear_fault() != Status::ok) {
          fresh_since_ = now_;  // refused: try again after another recover_after
          return;
        }
      } else {
        return;  // nothing on this device can clear it
      }
    }
    clear_now();
    recovering_ = true;
  }

  /// Time since the run started [s].
  [[nodiscard]] double run_time() const noexcept { return static_cast<double>(now_ - start_) * 1e-9; }

  std::vector<DeviceState> last_states() const {
    std::vector<DeviceState> v;
    const std::size_t n = history_next_ < history_size ? history_next_ : history_size;
    for (std::size_t i = history_next_ - n; i < history_next_; ++i)
      v.push_back(history_[i % history_size]);
    return v;
  }

  void apply_realtime() {
    realtime_granted_ = false;
    realtime_refused_.clear();
    if (config_.realtime == RealTime::off) return;
    rt::RealTimeGrant grant = rt::request_realtime(config_.priority);
    locked_ = grant.memory_locked;
    realtime_granted_ = grant.granted();
    if (realtime_granted_) return;
    realtime_refused_ = std::move(grant.refused);
    if (config_.realtime == RealTime::enforce) {
      restore_realtime();
      throw std::runtime_error("ServoLoop: RealTime::enforce refused: " + realtime_refused_ + "; " +
                               rt::realtime_advice);
    }
  }

  void restore_realtime() noexcept {
    if (config_.realtime == RealTime::off) return;
    rt::release_realtime(locked_);
    locked_ = false;
  }

  void safe_stop() noexcept {
    device_->write(glm::dvec3{0.0});
    if (config_.disarm_on_exit) {
      disarm();
      device_->write(glm::dvec3{0.0});
    }
    trusted_ = false;
    command_ = glm::dvec3{0.0};
    safety_.restart();  // what the device now has
    started_ = false;   // read_once() after a run starts afresh (homing, arming, soft start)
  }

  /// What every run does before its first tick: a pending clear_fault()
  /// (with the device's own fault), the latch check, then begin().
  /// @throws ServoError when a latched fault forbids arming.
  void prepare_run(std::int64_t now) {
    if (clear_requested_.exchange(false, std::memory_order_acq_rel)) {
      clear_now();
      // Between runs (not in a tick) a device's own latched fault can be
      // cleared too; it accepts that only while disarmed, as it is now.
      if constexpr (requires(D & d) { d.clear_fault(); }) device_->clear_fault();
    }
    if (const std::uint32_t latched = safety_.latched())
      throw ServoError("ServoLoop: cannot arm: the safety chain latched (" + safety_events::names(latched) +
                           ") in an earlier run; remove the cause and call clear_fault() first",
                       last_states());
    begin(now);
  }

  /// The watchdog's view of how the tick ended: late (one event, whatever
  /// it skipped) or on time.
  void note_deadline(bool overran) noexcept {
    if (overran) {
      ++missed_in_a_row_;
      fresh_since_ = -1;
    } else {
      missed_in_a_row_ = 0;
    }
  }

  /// Latches a fault from outside the chain (another arm, a throwing
  /// callback): zero force, disarm, counted.
  void latch_fault(std::uint32_t bits) noexcept {
    const std::uint32_t before = safety_.latched();
    safety_.latch(bits);
    trusted_ = false;
    if (!before) {
      disarm();
      stats_->add_latch(safety_.latched(), run_time());
      recovering_ = false;
    }
  }

  template <class Compute>
  StopReason run_impl(Compute& compute, RunLimits limits) {
    limits.validate();
    prepare_run(clock_->now());
    apply_realtime();
    struct Restore {
      ServoLoop* self;
      ~Restore() { self->restore_realtime(); }
    } restore{this};
    Pacer pacer(period_ns_, config_.pacing);
    pacer.start(clock_->now());
    const std::uint64_t first_tick = tick_;
    TickInput in;
    for (;;) {
      if (stop_.exchange(false, std::memory_order_acq_rel)) {
        safe_stop();
        return StopReason::requested;
      }
      if (tick_ - first_tick >= limits.max_ticks) {
        safe_stop();
        return StopReason::tick_limit;
      }
      const std::int64_t deadline = pacer.deadline();
      const std::int64_t wake = wait_for_tick(pacer, compute, in.probe, tick_ > first_tick);
      read_once(in);
      glm::dvec3 f{0.0};
      if constexpr (std::is_nothrow_invocable_v<Compute&, const TickInput&>) {
        f = compute(in);
      } else {
        try {
          f = compute(in);
        } catch (...) {
          latch_fault(safety_events::callback_threw);
          safe_stop();
          std::throw_with_nested(ServoError("ServoLoop: the callback threw at tick " + std::to_string(in.tick) +
                                                "; zero force commanded and the arm disarmed",
                                            last_states()));
        }
      }
      write_once(f);
      const std::int64_t end = clock_->now();
      stats_->record(wake, pacer.period_observed(), wake - deadline, end - wake);
      const std::int64_t skipped = pacer.finish(end);  // overran: whole periods skipped, no burst
      if (pacer.overran()) {
        stats_->add_missed(static_cast<std::uint64_t>(skipped));
        stats_->add_overrun();
      }
      note_deadline(pacer.overran());
      if (disconnected_) {
        safe_stop();
        return StopReason::disconnected;
      }
    }
  }

  /// The pacer's wait for the next deadline, with the look-ahead of a
  /// callback whose field has one that does something
  /// (LoopConfig::anticipate) on `last` (the HIP of the tick before, when
  /// there was one) moved one period on, in the slack before the deadline
  /// (Pacer::wait(clock, ready)); what it did goes into the statistics.
  template <class Compute>
  std::int64_t wait_for_tick(Pacer& pacer, const Compute& compute, const Probe& last, bool has_last) noexcept {
    if constexpr (LooksAhead<Compute>) {
      if (config_.anticipate && has_last && compute.looks_ahead()) {
        const std::int64_t wake = pacer.wait(
            *clock_, [&compute, &last, this]() noexcept { compute.anticipate(predicted_probe(last, period_)); });
        stats_->add_look_ahead(pacer.look_ahead());
        return wake;
      }
    }
    return pacer.wait(*clock_);
  }

  D* device_;
  C* clock_;
  LoopConfig config_;
  SafetyChain safety_;
  std::unique_ptr<LoopStatistics> stats_;
  std::int64_t period_ns_{1'000'000};
  double period_{1e-3};
  DeviceState state_{};
  std::array<DeviceState, history_size> history_{};
  std::size_t history_next_{0};
  glm::dvec3 command_{0.0};
  std::int64_t start_{0};
  std::int64_t now_{0};
  std::int64_t last_state_time_{0};
  std::int64_t armed_since_{-1};
  std::uint64_t tick_{0};
  std::int64_t fresh_since_{-1};  ///< start of the current run of on-time ticks with new states [ns]; -1: none
  int ticks_without_state_{0};
  int missed_in_a_row_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> clear_requested_{false};
  bool started_{false};
  bool disconnected_{false};
  bool resync_{false};
  bool impossible_{false};       ///< the last read brought a state the device cannot be in
  bool armed_requested_{false};  ///< what the loop last asked the device: armed or not
  bool trusted_{false};          ///< see trusted()
  bool recovering_{false};       ///< recover_after cleared a latch; counted once force is back
  bool locked_{false};
  bool realtime_granted_{false};
  std::string realtime_refused_;
};

}  // namespace hapticfield
