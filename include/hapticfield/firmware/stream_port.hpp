#pragma once
/// @file stream_port.hpp
/// StreamPort: the firmware side of a byte-stream link (USB CDC serial, a
/// UART). Bytes received are fed in; service() cuts them into frames
/// (StreamFramer, report framing), hands each to FirmwareCore::handle_frame
/// and sends the answers through the board's sink. No heap, no exceptions.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hapticfield/firmware/core.hpp"
#include "hapticfield/protocol/stream_framer.hpp"

namespace hapticfield::firmware {

template <std::size_t Capacity = 256>
class StreamPort {
 public:
  /// Takes received bytes; a full buffer that holds no frame is dropped.
  void feed(std::span<const std::uint8_t> bytes) noexcept {
    while (!bytes.empty()) {
      if (framer_.full()) framer_.discard();
      bytes = bytes.subspan(framer_.push(bytes));
    }
  }

  /// Handles every complete frame; sink(std::span<const std::uint8_t>) sends
  /// an answer (a feature report or a feature reply) to the host.
  template <class Sink>
  void service(FirmwareCore& core, Sink&& sink) noexcept {
    std::size_t size = 0;
    while (framer_.next(frame_, size) == Status::ok) {
      const std::size_t n = core.handle_frame(std::span<const std::uint8_t>(frame_.data(), size), reply_);
      if (n) sink(std::span<const std::uint8_t>(reply_.data(), n));
    }
  }

  [[nodiscard]] const FramerCounters& counters() const noexcept { return framer_.counters(); }

 private:
  StreamFramer<Capacity> framer_{Framing::reports};
  std::array<std::uint8_t, protocol::max_report_size> frame_{};
  std::array<std::uint8_t, protocol::max_report_size> reply_{};
};

}  // namespace hapticfield::firmware
