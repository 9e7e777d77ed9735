#pragma once
/// @file board.hpp
/// The tiny HAL a board implements so the firmware core runs on it, and the
/// one-period step every board's main loop calls. A board is any type with:
///   void read_inputs(BoardInputs&)            clock [us], encoders, e-stop, driver flags
///   void write_outputs(const MotorOutputs&)   currents (PWM) and the driver enable
///   std::size_t usb_receive(std::span<std::uint8_t>)   bytes or one output report received (0: none)
///   bool usb_send(std::span<const std::uint8_t>)       queue one report; false when the link is busy
/// (docs/firmware.md). No virtual functions: the compiler inlines the glue.

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticfield/firmware/core.hpp"
#include "hapticfield/firmware/stream_port.hpp"

namespace hapticfield::firmware {

template <class B>
concept Board = requires(B& board, BoardInputs& in, const MotorOutputs& out, std::span<std::uint8_t> rx,
                         std::span<const std::uint8_t> tx) {
  { board.read_inputs(in) }
  noexcept;
  { board.write_outputs(out) }
  noexcept;
  { board.usb_receive(rx) }
  noexcept->std::convertible_to<std::size_t>;
  { board.usb_send(tx) }
  noexcept->std::convertible_to<bool>;
};

/// One firmware period on a HID board: every received output report goes
/// to the core (feature reports arrive through the USB stack's control
/// callbacks, which call get_feature/set_feature directly), then tick,
/// drive the motors, send the state report. Returns false when the report
/// could not be queued (the host reads too slowly: it is simply lost).
template <Board B>
bool step_hid(FirmwareCore& core, B& board) noexcept {
  std::array<std::uint8_t, protocol::max_report_size> rx{};
  for (int i = 0; i < 8; ++i) {  // bounded: a flood cannot starve the tick
    const std::size_t n = board.usb_receive(rx);
    if (n == 0) break;
    core.receive(std::span<const std::uint8_t>(rx.data(), n < rx.size() ? n : rx.size()));
  }
  BoardInputs in;
  board.read_inputs(in);
  board.write_outputs(core.tick(in));
  return board.usb_send(core.report());
}

/// One firmware period on a serial (CDC) board: received bytes are framed
/// by the port (commands and in-band feature reports), then as step_hid.
template <Board B, std::size_t Capacity>
bool step_stream(FirmwareCore& core, StreamPort<Capacity>& port, B& board) noexcept {
  std::array<std::uint8_t, 64> rx{};
  for (int i = 0; i < 8; ++i) {
    const std::size_t n = board.usb_receive(rx);
    if (n == 0) break;
    port.feed(std::span<const std::uint8_t>(rx.data(), n < rx.size() ? n : rx.size()));
  }
  port.service(core, [&board](std::span<const std::uint8_t> reply) noexcept { (void)board.usb_send(reply); });
  BoardInputs in;
  board.read_inputs(in);
  board.write_outputs(core.tick(in));
  return board.usb_send(core.report());
}

}  // namespace hapticfield::firmware
