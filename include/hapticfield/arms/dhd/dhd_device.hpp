#pragma once
/// @file dhd_device.hpp
/// DhdDevice: a Force Dimension arm (omega, delta, sigma, lambda; the
/// Falcon through the SDK) through the DHD SDK, loaded at run time
/// (dhd_api.hpp). Unlike HD, the SDK owns no thread: our ServoLoop drives
/// dhdGetPosition / dhdSetForce like any Device. The controller's velocity
/// threshold and watchdog stay at their defaults (expert mode is never
/// entered: a handle moving too fast brakes, and forces drop when commands
/// stop). A saturated motor (dhdSetForce returns DHD_MOTOR_SATURATED) sets
/// over_current in the next state: the safety chain zeroes the force while
/// it lasts and slews it back. Never run on a real arm: docs/arms-dhd.md.

#include <time.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include <glm/vec3.hpp>

#include "hapticfield/arms/dhd/dhd_api.hpp"
#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"
#include "hapticfield/device/transport.hpp"

namespace hapticfield {

/// DHD's frame (x toward the operator, y right, z up, origin at the
/// workspace centre) to ours (x right, y up, z toward the user): a proper
/// rotation, ours = (dhd y, dhd z, dhd x).
[[nodiscard]] constexpr glm::dvec3 dhd_to_ours(const glm::dvec3& d) noexcept {
  return {d.y, d.z, d.x};
}
/// Ours to DHD's frame: dhd = (ours z, ours x, ours y).
[[nodiscard]] constexpr glm::dvec3 ours_to_dhd(const glm::dvec3& o) noexcept {
  return {o.z, o.x, o.y};
}

struct DhdConfig {
  int index{0};  ///< which of the connected devices (dhdOpenID), 0..dhdGetDeviceCount()-1
  /// A libdhd to load instead of libdhd.so.3 / libdhd.so (a path); "":
  /// those, or $HAPTICFIELD_DHD_LIBRARY when set.
  std::string library{};
  /// Force limit [N]; 0: 8 N for a Falcon (CHAI3D's figure), 5 N for every
  /// other model (a conservative figure of ours, unverified).
  double max_force{0.0};
  glm::dvec3 workspace_min{-0.08, -0.08, -0.08};  ///< [m] our frame (unverified)
  glm::dvec3 workspace_max{0.08, 0.08, 0.08};     ///< [m] our frame (unverified)
  TimeSource now{};  ///< host time [ns] for velocity by differences (SDKs without dhdGetLinearVelocity)

  /// @throws std::invalid_argument naming the first bad setting.
  void validate() const {
    if (index < 0 || index > 126) throw std::invalid_argument("DhdConfig: index must be 0..126");
    if (!std::isfinite(max_force) || max_force < 0.0)
      throw std::invalid_argument("DhdConfig: max_force must be finite and >= 0 [N] (0: the model's)");
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(workspace_min[i]) || !std::isfinite(workspace_max[i]) || workspace_min[i] >= workspace_max[i])
        throw std::invalid_argument("DhdConfig: workspace_min must be finite and < workspace_max [m]");
  }
};

/// Counts since construction.
struct DhdCounters {
  std::uint64_t reads{0};
  std::uint64_t timeguard_reads{0};  ///< DHD_TIMEGUARD: the SDK's data was still fresh
  std::uint64_t saturations{0};      ///< dhdSetForce returned DHD_MOTOR_SATURATED
  std::uint64_t errors{0};           ///< calls that returned -1
  int last_error{0};                 ///< dhdErrorGetLast() after the last failed call
};

class DhdDevice {
 public:
  /// Loads libdhd, opens device `index` and leaves its forces disabled
  /// until set_armed(true).
  /// @throws LibraryError (library or symbol missing), DeviceError (no
  ///         device, the index beyond the count, open failed) naming the
  ///         SDK's message; std::invalid_argument for a bad config.
  explicit DhdDevice(DhdConfig config = {}) : config_(std::move(config)) {
    config_.validate();
    api_ = dhd::Api::load(config_.library);
    const int count = api_.get_device_count();
    if (count < 0) throw DeviceError("Force Dimension: dhdGetDeviceCount failed: " + api_.last_error());
    if (count == 0)
      throw DeviceError(
          "Force Dimension: no device found (dhdGetDeviceCount is 0); is it plugged in and powered, "
          "and may this user open it (udev rule for USB vendor 1451)?");
    if (config_.index >= count)
      throw DeviceError("Force Dimension: no device " + std::to_string(config_.index) + ": " + std::to_string(count) +
                        " connected (indices 0.." + std::to_string(count - 1) + ")");
    const int id = api_.open_id(static_cast<char>(config_.index));
    if (id < 0)
      throw DeviceError("Force Dimension: dhdOpenID(" + std::to_string(config_.index) +
                        ") failed: " + api_.last_error());
    id_ = static_cast<char>(id);
    open_ = true;
    api_.enable_force(dhd::off, id_);
    const int type = api_.get_system_type != nullptr ? api_.get_system_type(id_) : -1;
    const char* name = api_.get_system_name != nullptr ? api_.get_system_name(id_) : nullptr;
    system_type_ = type;
    info_.name = std::string("Force Dimension ") + (name != nullptr && *name ? name : "device");
    info_.max_force = config_.max_force > 0.0 ? config_.max_force : type == dhd::device_falcon ? 8.0 : 5.0;
    info_.continuous_force = info_.max_force;
    info_.workspace_min = config_.workspace_min;
    info_.workspace_max = config_.workspace_max;
    info_.nominal_rate = 1000.0;
    info_.degrees_of_freedom = 3;
    info_.validate();
  }

  DhdDevice(const DhdDevice&) = delete;
  DhdDevice& operator=(const DhdDevice&) = delete;
  DhdDevice(DhdDevice&& o) noexcept = delete;

  /// Zero force, forces disabled, dhdClose.
  ~DhdDevice() {
    if (!open_) return;
    api_.set_force(0.0, 0.0, 0.0, id_);
    api_.enable_force(dhd::off, id_);
    api_.close(id_);
  }

  [[nodiscard]] const DeviceInfo& info() const noexcept { return info_; }
  [[nodiscard]] const DhdConfig& config() const noexcept { return config_; }
  [[nodiscard]] const DhdCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] int system_type() const noexcept { return system_type_; }
  [[nodiscard]] const std::string& library() const noexcept { return api_.library.name(); }
  /// The SDK's message for the last failed call ("" when none failed).
  [[nodiscard]] std::string last_error() const { return counters_.errors ? error_text_ : std::string{}; }

  /// Position and velocity in our frame [m, m/s]. disconnected after a
  /// failed call (the read, or the last write); DHD_ERROR_TIMEOUT gives
  /// no_data (the loop's stale-state guard takes over).
  Status read(DeviceState& state) noexcept {
    if (failed_) return Status::disconnected;
    glm::dvec3 p{0.0};
    const int r = api_.get_position(&p.x, &p.y, &p.z, id_);
    if (r < 0) {
      const int e = note_error();
      if (e == dhd::error_timeout) return Status::no_data;
      failed_ = true;
      return Status::disconnected;
    }
    if (r == dhd::timeguard) ++counters_.timeguard_reads;
    ++counters_.reads;
    const std::int64_t t = now_ns();
    glm::dvec3 v{0.0};
    bool have_velocity = false;
    if (api_.get_linear_velocity != nullptr) have_velocity = api_.get_linear_velocity(&v.x, &v.y, &v.z, id_) >= 0;
    if (!have_velocity && have_last_ && t > last_time_)
      v = (p - last_position_) / (static_cast<double>(t - last_time_) * 1e-9);
    last_position_ = p;
    last_time_ = t;
    have_last_ = true;
    state.position = dhd_to_ours(p);
    state.velocity = dhd_to_ours(v);
    state.buttons = api_.get_button_mask != nullptr ? static_cast<std::uint8_t>(api_.get_button_mask(id_) & 0xff) : 0;
    state.device_time = static_cast<double>(t) * 1e-9;
    state.sequence = static_cast<std::uint16_t>(counters_.reads & 0xffff);
    state.flags = static_cast<std::uint16_t>(status_bits::homed | (armed_ ? status_bits::armed : 0) |
                                             (saturated_ ? status_bits::over_current : 0));
    state.valid = true;
    return Status::ok;
  }

  /// Commands force [N] (our frame, turned into DHD's), magnitude clamped
  /// to max_force; zero when disarmed or non-finite.
  Status write(const glm::dvec3& force) noexcept {
    if (failed_) return Status::disconnected;
    glm::dvec3 f{0.0};
    if (armed_ && std::isfinite(force.x) && std::isfinite(force.y) && std::isfinite(force.z)) {
      const double m = std::sqrt(force.x * force.x + force.y * force.y + force.z * force.z);
      f = m > info_.max_force ? force * (info_.max_force / m) : force;
    }
    const glm::dvec3 d = ours_to_dhd(f);
    const int r = api_.set_force(d.x, d.y, d.z, id_);
    if (r < 0) {
      note_error();
      failed_ = true;
      return Status::disconnected;
    }
    saturated_ = r == dhd::motor_saturated;
    if (saturated_) ++counters_.saturations;
    return Status::ok;
  }

  /// dhdEnableForce on or off (off sends zero first).
  Status set_armed(bool on) noexcept {
    if (failed_) return Status::disconnected;
    if (!on) api_.set_force(0.0, 0.0, 0.0, id_);
    if (api_.enable_force(on ? dhd::on : dhd::off, id_) < 0) {
      note_error();
      failed_ = true;
      return Status::disconnected;
    }
    armed_ = on;
    return Status::ok;
  }
  /// The SDK calibrates at open: nothing to request.
  Status request_home() noexcept { return Status::ok; }
  /// Saturation clears with the next unsaturated command; a failed call stays.
  Status clear_fault() noexcept { return failed_ ? Status::disconnected : Status::ok; }

 private:
  int note_error() noexcept {
    ++counters_.errors;
    counters_.last_error = api_.error_get_last();
    const char* s = api_.error_get_last_str();
    if (s == nullptr) s = "DHD error";
    error_text_.assign(s, strnlen(s, 200));  // capacity reserved at construction: no allocation
    return counters_.last_error;
  }

  [[nodiscard]] std::int64_t now_ns() const noexcept {
    if (config_.now) return config_.now();
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  }

  DhdConfig config_;
  dhd::Api api_;
  DeviceInfo info_{};
  DhdCounters counters_{};
  std::string error_text_ = std::string(256, '\0');
  glm::dvec3 last_position_{0.0};
  std::int64_t last_time_{0};
  int system_type_{-1};
  char id_{-1};
  bool open_{false};
  bool armed_{false};
  bool saturated_{false};
  bool failed_{false};
  bool have_last_{false};
};

}  // namespace hapticfield
