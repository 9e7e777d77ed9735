// EXAMPLE ONLY: not built here, never run on hardware (docs/firmware.md).
// Board glue for a Teensy 4.0/4.1 (Teensyduino, Tools > USB Type: Serial):
// the reference firmware core over USB serial at high speed (480 Mbit/s),
// with this protocol's reports framed in-band (docs/device-protocol.md,
// "Serial framing"); the host opens it with SerialTransport.
//
// Why serial and not HID here: Teensyduino's RawHID has no feature reports
// and reports without ids, so the in-band serial framing carries the
// feature reports instead. USB serial moves data on bulk endpoints, which
// have no polling interval: a frame goes out at the next microframe
// (125 us) the host controller schedules. Were the arm HID at high speed,
// bInterval would be an exponent: the period is 2^(bInterval-1) microframes
// of 125 us, so bInterval 4 polls every 1 ms and 1 every 125 us (not 1 ms
// as at full speed).
#include <array>
#include <cstdint>
#include <span>

#include "hapticfield/firmware/board.hpp"

using namespace hapticfield;

namespace {

firmware::FirmwareCore core;  // default FirmwareConfig: edit it for the arm
firmware::StreamPort<256> port;

/// The HAL (firmware/board.hpp) on Teensy 4: encoders through the i.MX RT
/// quadrature decoders and motor PWM are the builder's code.
struct Teensy4Board {
  void read_inputs(firmware::BoardInputs& in) noexcept {
    in.now_us = micros();
    in.encoder = read_encoders();
    in.estop = digitalReadFast(kEstopPin) == LOW;
    in.over_current = digitalReadFast(kFaultPin) == LOW;
  }
  void write_outputs(const firmware::MotorOutputs& out) noexcept {
    digitalWriteFast(kEnablePin, out.enable ? HIGH : LOW);
    for (int i = 0; i < 3; ++i) set_current_ma(i, out.current_ma[static_cast<std::size_t>(i)]);
  }
  std::size_t usb_receive(std::span<std::uint8_t> buffer) noexcept {
    const int available = Serial.available();
    if (available <= 0) return 0;
    const std::size_t n = static_cast<std::size_t>(available) < buffer.size() ? available : buffer.size();
    return Serial.readBytes(reinterpret_cast<char*>(buffer.data()), n);
  }
  bool usb_send(std::span<const std::uint8_t> frame) noexcept {
    if (Serial.availableForWrite() < static_cast<int>(frame.size())) return false;  // never block the tick
    Serial.write(frame.data(), frame.size());
    return true;
  }

  static constexpr int kEstopPin = 2, kFaultPin = 3, kEnablePin = 4;
  std::array<std::int32_t, 3> read_encoders() noexcept;       // builder's code
  void set_current_ma(int joint, std::int16_t ma) noexcept;   // builder's code
};

Teensy4Board board;
IntervalTimer tick_timer;
volatile bool tick_due = false;

}  // namespace

void setup() {
  pinMode(2, INPUT_PULLUP);
  pinMode(3, INPUT_PULLUP);
  pinMode(4, OUTPUT);
  digitalWriteFast(4, LOW);
  Serial.begin(115200);  // the rate is ignored by USB serial
  tick_timer.begin([] { tick_due = true; }, core.config().period_us);  // [us]
}

void loop() {
  if (!tick_due) return;
  tick_due = false;
  firmware::step_stream(core, port, board);
}
