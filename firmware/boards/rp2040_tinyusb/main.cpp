// EXAMPLE ONLY: not built here, never run on hardware (docs/firmware.md).
// Board glue for an RP2040 (Raspberry Pi Pico SDK + TinyUSB): the reference
// firmware core speaking the HID report protocol. Pins, encoder decoding and
// the motor driver are placeholders a builder replaces with their own.
#include <cstdint>
#include <span>

#include "hardware/pwm.h"
#include "pico/stdlib.h"
#include "tusb.h"

#include "hapticfield/firmware/board.hpp"

namespace {

using namespace hapticfield;

firmware::FirmwareCore core;  // default FirmwareConfig: edit it for the arm

/// The HAL (firmware/board.hpp): four calls, no virtual functions.
struct Rp2040Board {
  std::array<std::uint8_t, protocol::max_report_size> rx{};
  std::size_t rx_size{0};  // one output report, stored by tud_hid_set_report_cb

  void read_inputs(firmware::BoardInputs& in) noexcept {
    in.now_us = time_us_32();
    in.encoder = read_encoders();     // PIO quadrature counters (builder's code)
    in.estop = !gpio_get(kEstopPin);  // normally closed e-stop loop
    in.over_current = !gpio_get(kFaultPin);
  }
  void write_outputs(const firmware::MotorOutputs& out) noexcept {
    gpio_put(kEnablePin, out.enable);
    for (int i = 0; i < 3; ++i)
      set_current_ma(i, out.current_ma[static_cast<std::size_t>(i)]);  // PWM + direction
  }
  std::size_t usb_receive(std::span<std::uint8_t> buffer) noexcept {
    const std::size_t n = rx_size;
    for (std::size_t i = 0; i < n && i < buffer.size(); ++i)
      buffer[i] = rx[i];
    rx_size = 0;
    return n;
  }
  bool usb_send(std::span<const std::uint8_t> report) noexcept {
    if (!tud_hid_ready()) return false;  // the host has not taken the last one: this one is lost
    // TinyUSB prepends the report id itself: pass it separately.
    return tud_hid_report(report[0], report.data() + 1, static_cast<std::uint16_t>(report.size() - 1));
  }

  static constexpr unsigned kEstopPin = 2, kFaultPin = 3, kEnablePin = 4;
  std::array<std::int32_t, 3> read_encoders() noexcept;      // builder's code
  void set_current_ma(int joint, std::int16_t ma) noexcept;  // builder's code
};
static_assert(firmware::Board<Rp2040Board>);

Rp2040Board board;

}  // namespace

// TinyUSB callbacks: feature reports go straight to the core.
extern "C" std::uint16_t tud_hid_get_report_cb(std::uint8_t, std::uint8_t id, hid_report_type_t type,
                                               std::uint8_t* buffer, std::uint16_t length) {
  if (type != HID_REPORT_TYPE_FEATURE) return 0;
  std::array<std::uint8_t, protocol::max_report_size> report{};
  std::size_t size = 0;
  if (core.get_feature(id, report, size) != Status::ok || size - 1 > length) return 0;
  for (std::size_t i = 1; i < size; ++i)
    buffer[i - 1] = report[i];  // without the id byte
  return static_cast<std::uint16_t>(size - 1);
}

extern "C" void tud_hid_set_report_cb(std::uint8_t, std::uint8_t id, hid_report_type_t type, const std::uint8_t* buffer,
                                      std::uint16_t length) {
  std::array<std::uint8_t, protocol::max_report_size> report{};
  if (length + 1u > report.size()) return;
  report[0] = id;  // put the id back in front: the codecs expect it
  for (std::uint16_t i = 0; i < length; ++i)
    report[i + 1u] = buffer[i];
  const std::span<const std::uint8_t> bytes(report.data(), length + 1u);
  if (type == HID_REPORT_TYPE_FEATURE) {
    (void)core.set_feature(bytes);
  } else {
    for (std::size_t i = 0; i < bytes.size(); ++i)
      board.rx[i] = bytes[i];
    board.rx_size = bytes.size();
  }
}

int main() {
  tusb_init();
  // The pins and PWM slices are set up here (builder's code).
  std::uint32_t next = time_us_32();
  for (;;) {
    tud_task();
    if (static_cast<std::int32_t>(time_us_32() - next) >= 0) {  // one firmware period [us]
      next += core.config().period_us;
      firmware::step_hid(core, board);
    }
  }
}
