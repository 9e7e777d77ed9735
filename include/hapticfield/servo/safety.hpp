#pragma once
/// @file safety.hpp
/// The safety chain every command passes, inside the library:
///   1. finite check      non-finite force -> zero and a fault event
///   2. passivity         optional observer/controller (Hannaford & Ryu 2002)
///   3. magnitude clamp   |F| <= max_force, direction kept
///   4. soft start        linear ramp of the limit after arming
///   5. slew limit        |F(n) - F(n-1)| <= slew_rate * period
///   6. watchdog          K ticks without a new state: zero until one arrives;
///                        state older than M or N missed deadlines in a
///                        row: zero, disarm and latch; a state the device
///                        cannot be in (impossible_state): zero, disarm, latch
/// A stage can be turned off only explicitly, and disabled_stages() names
/// every stage that is off so the loop can say so.

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "hapticfield/core/vector_math.hpp"

namespace hapticfield {

/// Events raised by the safety chain (bit mask).
namespace safety_events {
inline constexpr std::uint32_t non_finite = 1u << 0;        ///< force had NaN/Inf: zeroed
inline constexpr std::uint32_t clamped = 1u << 1;           ///< magnitude limited
inline constexpr std::uint32_t slew_limited = 1u << 2;      ///< change limited
inline constexpr std::uint32_t passivity = 1u << 3;         ///< passivity controller added damping
inline constexpr std::uint32_t stale_state = 1u << 4;       ///< watchdog: state too old (latches)
inline constexpr std::uint32_t missed_deadlines = 1u << 5;  ///< watchdog: K overruns in a row (latches)
inline constexpr std::uint32_t device_fault = 1u << 6;      ///< device reports a fault or is not armed: zero
inline constexpr std::uint32_t disconnected = 1u << 7;      ///< device gone (latches)
inline constexpr std::uint32_t callback_threw = 1u << 8;    ///< the user callback threw (latches)
inline constexpr std::uint32_t no_new_state = 1u << 9;      ///< K ticks without a new state: zero until one arrives
inline constexpr std::uint32_t bad_period =
    1u << 10;  ///< period NaN, Inf or outside [1e-4, 1] s: zero (the slew limit needs it)
inline constexpr std::uint32_t energy_overflow = 1u << 11;  ///< passivity energy went non-finite: zero, observer reset
inline constexpr std::uint32_t link_resync = 1u
                                             << 12;  ///< the device's report stream jumped: zero until it is consistent
inline constexpr std::uint32_t other_arm = 1u
                                           << 13;  ///< another arm of a MultiArmLoop latched (ArmFaultPolicy::stop_all)
/// The device sent a state it cannot be in: beyond its joint limits (with
/// a margin), out of its workspace, faster than it can move, or a
/// non-finite position or velocity (latches: the pose cannot be trusted).
inline constexpr std::uint32_t impossible_state = 1u << 14;
/// Events that latch the watchdog until SafetyChain::clear().
inline constexpr std::uint32_t latching =
    stale_state | missed_deadlines | disconnected | callback_threw | other_arm | impossible_state;
/// Events that zero the force for this tick without latching.
inline constexpr std::uint32_t zeroing =
    non_finite | device_fault | no_new_state | bad_period | energy_overflow | link_resync;

/// Comma-separated names of the bits set in events ("" for none).
[[nodiscard]] inline std::string names(std::uint32_t events) {
  static constexpr const char* table[] = {"non-finite force",
                                          "clamped",
                                          "slew limited",
                                          "passivity",
                                          "stale state",
                                          "missed deadlines",
                                          "device fault or not armed",
                                          "disconnected",
                                          "callback threw",
                                          "no new state",
                                          "bad period",
                                          "passivity energy overflow",
                                          "link resynchronising",
                                          "another arm latched",
                                          "impossible state"};
  std::string s;
  for (std::uint32_t i = 0; i < sizeof table / sizeof table[0]; ++i)
    if (events & (1u << i)) s += (s.empty() ? "" : ", ") + std::string(table[i]);
  return s;
}
}  // namespace safety_events

struct SafetyConfig {
  double max_force{0.0};  ///< magnitude limit [N]; 0 = the device's max_force
  bool slew_enabled{true};
  double slew_rate{1000.0};  ///< largest change of the force [N/s]
  bool soft_start_enabled{true};
  double soft_start{0.25};  ///< ramp time of the force limit after arming [s]
  bool watchdog_enabled{true};
  double max_state_age{10e-3};     ///< state older than this zeroes, disarms and latches [s]
  int max_ticks_without_state{2};  ///< this many ticks in a row without a new state zero the force (until one arrives)
  int max_missed_deadlines{3};    ///< this many overrunning ticks in a row zero and disarm (a late wake is one, however
                                  ///< many periods it skipped)
  bool passivity_enabled{false};  ///< Hannaford & Ryu passivity observer/controller
  double passivity_max_damping{50.0};  ///< cap on the controller's damping alpha [N s/m]

  /// @throws std::invalid_argument naming the first bad parameter.
  void validate(double device_max_force) const {
    const auto pos = [](double v) { return std::isfinite(v) && v > 0.0; };
    if (!pos(device_max_force))
      throw std::invalid_argument("SafetyConfig: the device max_force must be finite and > 0 [N]");
    if (!std::isfinite(max_force) || max_force < 0.0 || max_force > device_max_force)
      throw std::invalid_argument(
          "SafetyConfig: max_force must be finite, >= 0 (0: device limit) and <= the device max_force [N]");
    if (slew_enabled && !pos(slew_rate))
      throw std::invalid_argument("SafetyConfig: slew_rate must be finite and > 0 [N/s]");
    if (soft_start_enabled && !pos(soft_start))
      throw std::invalid_argument("SafetyConfig: soft_start must be finite and > 0 [s]");
    if (watchdog_enabled) {
      if (!pos(max_state_age)) throw std::invalid_argument("SafetyConfig: max_state_age must be finite and > 0 [s]");
      if (max_ticks_without_state < 1)
        throw std::invalid_argument("SafetyConfig: max_ticks_without_state must be >= 1");
      if (max_missed_deadlines < 1) throw std::invalid_argument("SafetyConfig: max_missed_deadlines must be >= 1");
    }
    if (passivity_enabled && !pos(passivity_max_damping))
      throw std::invalid_argument("SafetyConfig: passivity_max_damping must be finite and > 0 [N s/m]");
  }

  /// Comma-separated names of the stages that are off ("" when all are on;
  /// the passivity controller is an option and is not listed).
  [[nodiscard]] std::string disabled_stages() const {
    std::string s;
    const auto add = [&s](const char* name) { s += s.empty() ? name : std::string(", ") + name; };
    if (!slew_enabled) add("slew limit");
    if (!soft_start_enabled) add("soft start");
    if (!watchdog_enabled) add("watchdog");
    return s;
  }
};

/// What the chain needs to know about this tick.
struct SafetyInput {
  glm::dvec3 force{0.0};          ///< force the field or callback asked for [N]
  glm::dvec3 velocity{0.0};       ///< handle velocity [m/s] (passivity observer)
  double period{1e-3};            ///< nominal tick period [s]
  double state_age{0.0};          ///< now - arrival of the newest state [s]
  int ticks_without_state{0};     ///< ticks in a row with no new state
  int missed_in_a_row{0};         ///< overrunning ticks in a row (one per late tick)
  double time_since_armed{-1.0};  ///< [s]; negative while the device is not armed
  bool device_fault{false};       ///< the device reports a fault bit
  bool disconnected{false};       ///< the transport reports the device gone
  bool link_resync{false};        ///< the report stream jumped and is not yet consistent
  bool impossible_state{false};   ///< the device sent a state it cannot be in (latches)
};

class SafetyChain {
 public:
  /// Periods the chain accepts: the servo loop's 10 kHz to 1 Hz [s]. Any
  /// other period (NaN, Inf, zero, negative, absurd) zeroes the force.
  static constexpr double min_period = 1e-4;
  static constexpr double max_period = 1.0;

  /// @throws std::invalid_argument via SafetyConfig::validate.
  SafetyChain(const SafetyConfig& config, double device_max_force) : config_(config) {
    config_.validate(device_max_force);
    limit_ = config_.max_force > 0.0 ? config_.max_force : device_max_force;
  }

  /// One tick: the force to command [N]. Never non-finite, |F| <= limit,
  /// and |F - previous| <= slew_rate * period except when the chain zeroes
  /// the force (a fault, a watchdog trip): going to zero is immediate.
  [[nodiscard]] glm::dvec3 process(const SafetyInput& in) noexcept {
    events_ = 0;
    glm::dvec3 f = in.force;
    // 6. watchdog and device faults first: they override everything.
    if (in.disconnected) events_ |= safety_events::disconnected;
    if (in.impossible_state) events_ |= safety_events::impossible_state;
    if (config_.watchdog_enabled) {
      if (!(in.state_age <= config_.max_state_age)) events_ |= safety_events::stale_state;
      if (in.ticks_without_state >= config_.max_ticks_without_state) events_ |= safety_events::no_new_state;
      if (in.missed_in_a_row >= config_.max_missed_deadlines) events_ |= safety_events::missed_deadlines;
    }
    latched_ |= events_ & safety_events::latching;
    if (in.device_fault || !(in.time_since_armed >= 0.0)) events_ |= safety_events::device_fault;
    if (in.link_resync) events_ |= safety_events::link_resync;
    // Without a usable period there is no slew limit and no energy: zero.
    if (!(in.period >= min_period && in.period <= max_period)) events_ |= safety_events::bad_period;
    const glm::dvec3 v = is_finite(in.velocity) ? in.velocity : glm::dvec3{0.0};
    if (latched_ || (events_ & safety_events::zeroing)) return zero(v, in.period);
    // 1. finite check
    if (!is_finite(f)) {
      events_ |= safety_events::non_finite;
      return zero(v, in.period);
    }
    // 2. passivity controller (Hannaford & Ryu, "Time-domain passivity
    //    control of haptic interfaces", IEEE TRA 18(1), 2002) for an
    //    impedance-causality element): observed energy flowing into the
    //    virtual environment E(n) = sum -F.v dt; when it would go negative,
    //    add damping alpha = -E / (dt |v|^2) so that it does not.
    if (config_.passivity_enabled) {
      const double vv = glm::dot(v, v);
      const double predicted = energy_ - glm::dot(f, v) * in.period;
      if (!std::isfinite(predicted) || !std::isfinite(vv)) {  // extreme velocity: the observer cannot judge
        events_ |= safety_events::energy_overflow;
        energy_ = 0.0;
        return zero(v, in.period);
      }
      if (predicted < 0.0 && vv > 1e-12) {
        const double alpha = std::fmin(-predicted / (in.period * vv), config_.passivity_max_damping);
        f -= alpha * v;
        events_ |= safety_events::passivity;
      }
    }
    // 3. clamp, 4. soft start: one limit.
    double limit = limit_;
    if (config_.soft_start_enabled && in.time_since_armed < config_.soft_start)
      limit *= std::fmax(0.0, in.time_since_armed) / config_.soft_start;
    glm::dvec3 out = clamp_magnitude(f, limit);
    if (out != f) events_ |= safety_events::clamped;
    // 5. slew limit (inside a ball around the previous command, so the
    //    result stays inside the clamp ball: both balls are convex).
    if (config_.slew_enabled) {
      const double step = config_.slew_rate * in.period;
      const glm::dvec3 delta = out - previous_;
      if (glm::dot(delta, delta) > step * step) {
        out = previous_ + clamp_magnitude(delta, step);
        if (glm::length(out) > limit) out = clamp_magnitude(out, limit);  // rounding guard
        events_ |= safety_events::slew_limited;
      }
    }
    return commit(out, v, in.period);
  }

  /// Latched watchdog events (safety_events::latching bits).
  [[nodiscard]] std::uint32_t latched() const noexcept { return latched_; }
  /// Events of the last process() call.
  [[nodiscard]] std::uint32_t events() const noexcept { return events_; }
  /// Latches a fault from outside (a throwing callback).
  void latch(std::uint32_t bits) noexcept { latched_ |= bits; }
  /// Clears the latch; the next force starts from zero.
  void clear() noexcept {
    latched_ = 0;
    restart();
  }
  /// Starts again from what the device really has after a stop: zero force
  /// commanded (the slew limit ramps from zero), observer energy zero. The
  /// latch is kept.
  void restart() noexcept {
    previous_ = glm::dvec3{0.0};
    energy_ = 0.0;
  }
  /// Observed energy into the virtual environment [J] (passivity observer).
  [[nodiscard]] double observed_energy() const noexcept { return energy_; }
  [[nodiscard]] double limit() const noexcept { return limit_; }
  [[nodiscard]] const SafetyConfig& config() const noexcept { return config_; }
  [[nodiscard]] glm::dvec3 previous() const noexcept { return previous_; }

 private:
  glm::dvec3 zero(const glm::dvec3& v, double period) noexcept { return commit(glm::dvec3{0.0}, v, period); }
  glm::dvec3 commit(const glm::dvec3& out, const glm::dvec3& v, double period) noexcept {
    if (config_.passivity_enabled && std::isfinite(period)) {
      energy_ -= glm::dot(out, v) * period;
      if (!std::isfinite(energy_)) energy_ = 0.0;  // never leave the observer disabled
    }
    previous_ = out;
    return out;
  }

  SafetyConfig config_;
  double limit_{1.0};
  glm::dvec3 previous_{0.0};
  double energy_{0.0};
  std::uint32_t events_{0};
  std::uint32_t latched_{0};
};

}  // namespace hapticfield
