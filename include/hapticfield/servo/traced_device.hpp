#pragma once
/// @file traced_device.hpp
/// TracedDevice: a Device decorator that records a run, one row a tick, for
/// traces (servo_demo --trace, run_servo()["trace"]). Each tick's callback
/// opens a row (open()); the loop's write that follows, the tick's command
/// after the safety chain, fills that row's force. The zero force a stopping
/// run writes after its last tick opens no row, so every row holds what its
/// own tick commanded. Rows go only into capacity reserved before the run:
/// no allocation in a tick.

#include <vector>

#include <glm/vec3.hpp>

#include "hapticfield/device/state.hpp"
#include "hapticfield/device/status.hpp"
#include "hapticfield/servo/loop.hpp"

namespace hapticfield {

/// One traced tick.
struct TraceRow {
  double t{0.0};             ///< the probe's time [s]
  glm::dvec3 position{0.0};  ///< the HIP [m]
  glm::dvec3 force{0.0};     ///< commanded after the safety chain [N]
  double period{0.0};        ///< since the previous tick [s] (0 when not given)
  bool homed{false};         ///< the tick's device state said homed
  bool armed{false};         ///< the tick's device state said armed (motors on)
};

template <Device D>
class TracedDevice {
 public:
  /// rows: reserved by the caller for the ticks to trace (rows beyond its
  /// capacity are not traced).
  TracedDevice(D& device, std::vector<TraceRow>& rows) noexcept : device_(&device), rows_(&rows) {}

  Status read(DeviceState& state) noexcept { return device_->read(state); }
  Status write(const glm::dvec3& force) noexcept {
    if (open_) rows_->back().force = force, open_ = false;
    last_written_ = force;
    return device_->write(force);
  }
  Status set_armed(bool on) noexcept { return device_->set_armed(on); }
  Status request_home() noexcept { return device_->request_home(); }
  decltype(auto) info() const noexcept { return device_->info(); }
  Status clear_fault() noexcept requires requires(D& d) { d.clear_fault(); }
  { return device_->clear_fault(); }

  /// A row for this tick (call from the loop's callback), while the
  /// reserved rows last; period [s] since the previous tick.
  void open(const TickInput& in, double period = 0.0) noexcept {
    open_ = rows_->size() < rows_->capacity();
    if (open_)
      rows_->push_back({in.probe.time, in.probe.position, glm::dvec3{0.0}, period, in.state.homed(), in.state.armed()});
  }

  /// The last force written to the device [N], the stop's own command
  /// included (zero after a stop).
  [[nodiscard]] const glm::dvec3& last_written() const noexcept { return last_written_; }

 private:
  D* device_;
  std::vector<TraceRow>* rows_;
  bool open_{false};
  glm::dvec3 last_written_{0.0};
};

}  // namespace hapticfield
