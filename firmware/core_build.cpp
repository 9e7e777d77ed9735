// The firmware core built for a microcontroller (.ci/run, docs/firmware.md):
// a do-nothing board instantiates the whole HID and serial step so the
// object holds every function a real board links. Its size is the core's
// code size; the board glue adds the USB stack and the drivers.
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticfield/firmware/board.hpp"

namespace {

struct NullBoard {
  volatile std::uint32_t clock_us{0};
  volatile std::int32_t encoder{0};
  volatile std::int16_t current{0};
  volatile std::uint8_t last_byte{0};
  void read_inputs(hapticfield::firmware::BoardInputs& in) noexcept {
    in.now_us = clock_us;
    in.encoder = {encoder, encoder, encoder};
  }
  void write_outputs(const hapticfield::firmware::MotorOutputs& out) noexcept { current = out.current_ma[0]; }
  std::size_t usb_receive(std::span<std::uint8_t> rx) noexcept {
    rx[0] = last_byte;
    return last_byte ? 1 : 0;
  }
  bool usb_send(std::span<const std::uint8_t> tx) noexcept {
    last_byte = tx[0];
    return true;
  }
};
static_assert(hapticfield::firmware::Board<NullBoard>);

hapticfield::firmware::FirmwareCore core;
hapticfield::firmware::StreamPort<256> port;
NullBoard board;

}  // namespace

extern "C" bool hapticfield_firmware_step_hid() {
  return hapticfield::firmware::step_hid(core, board);
}
extern "C" bool hapticfield_firmware_step_serial() {
  return hapticfield::firmware::step_stream(core, port, board);
}
extern "C" int hapticfield_firmware_get_feature(std::uint8_t id, std::uint8_t* out, std::size_t capacity) {
  std::size_t size = 0;
  return core.get_feature(id, std::span<std::uint8_t>(out, capacity), size) == hapticfield::Status::ok
             ? static_cast<int>(size)
             : -1;
}
extern "C" int hapticfield_firmware_set_feature(const std::uint8_t* in, std::size_t size) {
  return static_cast<int>(core.set_feature(std::span<const std::uint8_t>(in, size)));
}
