#pragma once
/// @file loop.hpp
/// ServoLoop: the fixed-rate loop that reads a Device, asks a HapticField
/// (or a callback) for a force, passes it through the SafetyChain and
/// commands it. Absolute deadlines; after an overrun whole periods are
/// skipped instead of bursting; statistics every tick; an injectable clock.

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <concepts>
#include <cstdint>
#include <cstdio>
#include <cstring>
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
#include "hapticfield/servo/clock.hpp"
#include "hapticfield/servo/safety.hpp"
#include "hapticfield/servo/statistics.hpp"

namespace hapticfield {

/// Real-time scheduling request for the loop thread.
enum class RealTime : std::uint8_t {
  off,          ///< ordinary scheduling
  best_effort,  ///< ask for SCHED_FIFO, mlockall and 1 ns timer slack; warn once if refused
  enforce,      ///< as best_effort, but refuse to start when anything is refused
};

/// Loop limits: rates from 1 Hz to 10 kHz.
inline constexpr double min_servo_rate = 1.0;      ///< [Hz]
inline constexpr double max_servo_rate = 10000.0;  ///< [Hz]

struct LoopConfig {
  double rate{1000.0};                   ///< servo rate [Hz], 1..10000
  RealTime realtime{RealTime::best_effort};
  int priority{80};                      ///< SCHED_FIFO priority (1..99)
  SafetyConfig safety{};
  bool auto_home{true};                  ///< request homing when the device is not homed
  bool auto_arm{true};                   ///< request arming at start (the device arms once homed)
  bool disarm_on_exit{true};             ///< disarm when run() returns

  /// @throws std::invalid_argument naming the bad parameter.
  void validate() const {
    if (!std::isfinite(rate) || rate < min_servo_rate || rate > max_servo_rate)
      throw std::invalid_argument("LoopConfig: rate must be within [1, 10000] [Hz]");
    if (priority < 1 || priority > 99) throw std::invalid_argument("LoopConfig: priority must be within 1..99");
  }
};

/// What a callback sees each tick.
struct TickInput {
  Probe probe{};              ///< HIP state for fields
  DeviceState state{};        ///< newest device state
  Status read_status{Status::no_data};
  std::uint64_t tick{0};      ///< tick index since run() started
};

/// Why run() returned.
enum class StopReason : std::uint8_t { requested, tick_limit, disconnected };

struct RunLimits {
  std::uint64_t max_ticks{0};  ///< 0: no limit
};

/// Thrown by run() after a callback threw: the arm has already been sent
/// zero force and disarmed. The callback's exception is nested
/// (std::rethrow_if_nested).
class ServoError : public Error {
 public:
  ServoError(const std::string& what, std::vector<DeviceState> last_states)
      : Error(what), last_states_(std::move(last_states)) {}
  /// The last device states before the failure, oldest first.
  [[nodiscard]] const std::vector<DeviceState>& last_states() const noexcept { return last_states_; }

 private:
  std::vector<DeviceState> last_states_;
};

namespace detail {
/// Requests real-time scheduling for the calling thread; returns what was
/// refused ("" when everything was granted).
inline std::string request_realtime(int priority, bool& locked) {
  std::string refused;
  sched_param sp{};
  sp.sched_priority = priority;
  if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp); e != 0)
    refused += std::string("SCHED_FIFO priority ") + std::to_string(priority) + " (" + std::strerror(e) + ")";
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    refused += std::string(refused.empty() ? "" : ", ") + "mlockall (" + std::strerror(errno) + ")";
  } else {
    locked = true;
  }
  if (prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) != 0)
    refused += std::string(refused.empty() ? "" : ", ") + "timer slack (" + std::strerror(errno) + ")";
  return refused;
}
inline std::atomic<bool>& realtime_warned() {
  static std::atomic<bool> warned{false};
  return warned;
}
}  // namespace detail

/// The servo loop over a Device D on a clock C.
///
/// @code
///   SimulatedArm arm;  VirtualClock clock;
///   SimulatedTransport link(arm, [&] { return clock.now(); });
///   ForceArm device(link);
///   ServoLoop loop(device, clock);
///   loop.run(my_field, {.max_ticks = 1000});
/// @endcode
template <Device D, ServoClock C = SteadyClock>
class ServoLoop {
 public:
  static constexpr std::size_t history_size = 8;  ///< states kept for ServoError

  /// @throws std::invalid_argument for a bad rate, priority or safety setting.
  ServoLoop(D& device, C& clock, LoopConfig config = {})
      : device_(&device), clock_(&clock), c_(config), safety_((c_.validate(), c_.safety), device.info().max_force),
        stats_(std::make_unique<LoopStatistics>()) {
    period_ns_ = static_cast<std::int64_t>(std::llround(1e9 / c_.rate));
    period_ = static_cast<double>(period_ns_) * 1e-9;
    const std::string off = c_.safety.disabled_stages();
    if (!off.empty()) std::fprintf(stderr, "hapticfield: safety stages disabled by configuration: %s\n", off.c_str());
  }

  /// Runs a field until request_stop(), the tick limit or a disconnect.
  /// Blocks the calling thread. @throws std::runtime_error when
  /// RealTime::enforce is not granted.
  template <HapticField F>
  StopReason run(F& field, RunLimits limits = {}) {
    auto compute = [&field](const TickInput& in) noexcept { return glm::dvec3(field.force(in.probe)); };
    return run_impl(compute, limits);
  }

  /// Runs a callback glm::dvec3(const TickInput&). When it throws, zero force
  /// is commanded and the arm disarmed first, then ServoError (with the
  /// last states, the callback's exception nested) is thrown.
  template <class Callback>
    requires(!HapticField<Callback> && std::is_invocable_r_v<glm::dvec3, Callback&, const TickInput&>)
  StopReason run(Callback& callback, RunLimits limits = {}) {
    return run_impl(callback, limits);
  }

  /// Asks run() to return after the current tick (any thread).
  void request_stop() noexcept { stop_.store(true, std::memory_order_relaxed); }

  /// For users who own the thread: reads the newest state and fills in.
  /// Call once per tick, then write_once().
  Status read_once(TickInput& in) noexcept {
    const std::int64_t now = clock_->now();
    if (!started_) begin(now);
    const Status s = device_->read(state_);
    if (s == Status::ok) {
      last_state_time_ = now;
      ticks_without_state_ = 0;
      history_[history_next_++ % history_size] = state_;
      if (!state_.homed() && c_.auto_home) device_->request_home();
      if (state_.armed() && armed_since_ < 0) armed_since_ = now;
      if (!state_.armed()) armed_since_ = -1;
    } else {
      ++ticks_without_state_;
    }
    if (s == Status::disconnected) disconnected_ = true;
    in.state = state_;
    in.read_status = s;
    in.tick = tick_;
    in.probe.position = state_.position;
    in.probe.velocity = state_.velocity;
    in.probe.normal_force = glm::length(safety_.previous());  // |F| commanded last tick [N]
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
    si.time_since_armed = (armed_since_ >= 0 && state_.armed()) ? static_cast<double>(now_ - armed_since_) * 1e-9 : -1.0;
    si.device_fault = state_.faulted();
    si.disconnected = disconnected_;
    const std::uint32_t before = safety_.latched();
    const glm::dvec3 out = safety_.process(si);
    if (safety_.latched() && !before) device_->set_armed(false);  // the watchdog disarms
    if (safety_.events() & ~(safety_events::device_fault)) stats_->add_safety_event();
    stats_->record_force(glm::length(out));
    command_ = out;
    ++tick_;
    return device_->write(out);
  }

  /// Clears a latched safety fault and re-requests arming (soft start again).
  void clear_fault() noexcept {
    safety_.clear();
    missed_in_a_row_ = 0;
    if (c_.auto_arm) device_->set_armed(true);
  }

  [[nodiscard]] LoopSnapshot statistics() const noexcept { return stats_->snapshot(); }
  /// Starts the statistics afresh (e.g. after a warm-up).
  void reset_statistics() noexcept { stats_->reset(); }
  [[nodiscard]] const LoopStatistics& detailed_statistics() const noexcept { return *stats_; }
  [[nodiscard]] const SafetyChain& safety() const noexcept { return safety_; }
  [[nodiscard]] glm::dvec3 last_command() const noexcept { return command_; }
  [[nodiscard]] const DeviceState& state() const noexcept { return state_; }
  [[nodiscard]] double period() const noexcept { return period_; }
  [[nodiscard]] const LoopConfig& config() const noexcept { return c_; }
  /// True when the last real-time request was fully granted.
  [[nodiscard]] bool realtime_granted() const noexcept { return realtime_granted_; }

 private:
  void begin(std::int64_t now) noexcept {
    started_ = true;
    start_ = now;
    last_state_time_ = now;
    if (c_.auto_home) device_->request_home();
    if (c_.auto_arm) device_->set_armed(true);
  }

  std::vector<DeviceState> last_states() const {
    std::vector<DeviceState> v;
    const std::size_t n = history_next_ < history_size ? history_next_ : history_size;
    for (std::size_t i = history_next_ - n; i < history_next_; ++i) v.push_back(history_[i % history_size]);
    return v;
  }

  void apply_realtime() {
    realtime_granted_ = false;
    if (c_.realtime == RealTime::off) return;
    const std::string refused = detail::request_realtime(c_.priority, locked_);
    realtime_granted_ = refused.empty();
    if (refused.empty()) return;
    const std::string advice =
        "grant the user real-time limits (e.g. '@realtime - rtprio 95' and '- memlock unlimited' in "
        "/etc/security/limits.d/) or CAP_SYS_NICE and CAP_IPC_LOCK";
    if (c_.realtime == RealTime::enforce) {
      restore_realtime();
      throw std::runtime_error("ServoLoop: RealTime::enforce refused: " + refused + "; " + advice);
    }
    if (!detail::realtime_warned().exchange(true))
      std::fprintf(stderr, "hapticfield: real-time scheduling not granted (%s); running best-effort. %s\n",
                   refused.c_str(), advice.c_str());
  }

  void restore_realtime() noexcept {
    if (c_.realtime == RealTime::off) return;
    sched_param sp{};
    sp.sched_priority = 0;
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
    if (locked_) munlockall();
    locked_ = false;
  }

  void safe_stop() noexcept {
    device_->write(glm::dvec3{0.0});
    if (c_.disarm_on_exit) {
      device_->set_armed(false);
      device_->write(glm::dvec3{0.0});
    }
    command_ = glm::dvec3{0.0};
  }

  template <class Compute>
  StopReason run_impl(Compute& compute, RunLimits limits) {
    apply_realtime();
    struct Restore {
      ServoLoop* self;
      ~Restore() { self->restore_realtime(); }
    } restore{this};
    stop_.store(false, std::memory_order_relaxed);
    std::int64_t deadline = clock_->now();
    std::int64_t previous_wake = deadline;
    const std::uint64_t first_tick = tick_;
    TickInput in;
    for (;;) {
      if (stop_.load(std::memory_order_relaxed)) { safe_stop(); return StopReason::requested; }
      if (limits.max_ticks && tick_ - first_tick >= limits.max_ticks) { safe_stop(); return StopReason::tick_limit; }
      clock_->sleep_until(deadline);
      const std::int64_t wake = clock_->now();
      read_once(in);
      glm::dvec3 f{0.0};
      if constexpr (std::is_nothrow_invocable_v<Compute&, const TickInput&>) {
        f = compute(in);
      } else {
        try {
          f = compute(in);
        } catch (...) {
          safety_.latch(safety_events::callback_threw);
          safe_stop();
          std::throw_with_nested(ServoError("ServoLoop: the callback threw at tick " + std::to_string(in.tick) +
                                                "; zero force commanded and the arm disarmed",
                                            last_states()));
        }
      }
      write_once(f);
      const std::int64_t end = clock_->now();
      stats_->record(wake, wake - previous_wake, wake - deadline, end - wake);
      previous_wake = wake;
      deadline += period_ns_;
      if (end > deadline) {  // overran: skip whole periods instead of bursting
        const std::int64_t skipped = (end - deadline) / period_ns_ + 1;
        deadline += skipped * period_ns_;
        stats_->add_missed(static_cast<std::uint64_t>(skipped));
        missed_in_a_row_ += static_cast<int>(skipped);
      } else {
        missed_in_a_row_ = 0;
      }
      if (disconnected_) { safe_stop(); return StopReason::disconnected; }
    }
  }

  D* device_;
  C* clock_;
  LoopConfig c_;
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
  int ticks_without_state_{0};
  int missed_in_a_row_{0};
  std::atomic<bool> stop_{false};
  bool started_{false};
  bool disconnected_{false};
  bool locked_{false};
  bool realtime_granted_{false};
};

}  // namespace hapticfield
