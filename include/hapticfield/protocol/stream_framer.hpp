#pragma once
/// @file stream_framer.hpp
/// StreamFramer: cuts a byte stream (a USB serial port, a UART) into
/// reports. Two framings:
///   - reports: a frame is a report id byte followed by the rest of that
///     report (protocol::report_size(id) bytes in all), ending in a valid
///     CRC-16. An unknown id or a bad CRC drops one byte and scans again
///     (resynchronisation); a partial frame waits for more bytes, unless a
///     complete valid frame follows it (then the head was a stray byte).
///   - lines: '\n'-terminated text lines (the '\n' removed, NUL padding
///     stripped), at most max_line bytes; longer lines are dropped whole.
///   - fixed: every frame is the next N bytes (binary request/reply
///     protocols whose replies carry no length or checksum). N is set with
///     set_frame_size() between exchanges; nothing in the bytes can show a
///     boundary, so the owner resynchronises: drop_pending() throws away a
///     partial frame (SerialTransport does it when a waiting read times out
///     mid-frame; a request/reply device does it when every request has
///     its reply and bytes are still left over).
/// Fixed storage, no allocation, no exceptions: the firmware core and the
/// host's SerialTransport both use it (docs/device-protocol.md, "Serial
/// framing").

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "hapticfield/device/status.hpp"
#include "hapticfield/protocol/reports.hpp"

namespace hapticfield {

/// How a byte stream is cut into reports.
enum class Framing : std::uint8_t {
  reports,  ///< binary reports of this protocol, found by id and CRC
  lines,    ///< '\n'-terminated text lines
  fixed,    ///< frames of a fixed size N (set_frame_size), no boundary marks
};

/// Counts of what a StreamFramer met.
struct FramerCounters {
  std::uint64_t frames{0};    ///< frames (or lines) returned
  std::uint64_t skipped{0};   ///< bytes dropped while resynchronising
  std::uint64_t overflow{0};  ///< bytes lost to a full buffer or an over-long line
};

/// Capacity: bytes held between reads (>= 2 reports).
template <std::size_t Capacity = 512>
class StreamFramer {
  static_assert(Capacity >= 2 * protocol::max_report_size, "StreamFramer: capacity below two reports");

 public:
  /// @param max_line  longest line in line framing [bytes] (clamped to 1..Capacity-1)
  explicit StreamFramer(Framing framing = Framing::reports, std::size_t max_line = 256) noexcept
      : framing_(framing), max_line_(max_line < 1 ? 1 : (max_line >= Capacity ? Capacity - 1 : max_line)) {}

  /// Free space at the end of the buffer, for a read() straight into it;
  /// then commit() the bytes read. Moves pending bytes to the front first.
  [[nodiscard]] std::span<std::uint8_t> space() noexcept {
    compact();
    return {buffer_.data() + end_, Capacity - end_};
  }
  void commit(std::size_t n) noexcept { end_ += n <= Capacity - end_ ? n : Capacity - end_; }

  /// Copies bytes in; what does not fit is counted as overflow. Returns the
  /// number of bytes taken.
  std::size_t push(std::span<const std::uint8_t> bytes) noexcept {
    const std::span<std::uint8_t> free = space();
    const std::size_t n = bytes.size() < free.size() ? bytes.size() : free.size();
    if (n) std::memcpy(free.data(), bytes.data(), n);
    commit(n);
    counters_.overflow += bytes.size() - n;
    return n;
  }

  /// Takes the next complete frame (or line) into out and sets size: ok, or
  /// no_data while none is complete.
  Status next(std::span<std::uint8_t> out, std::size_t& size) noexcept {
    if (framing_ == Framing::fixed) return next_fixed(out, size);
    return framing_ == Framing::lines ? next_line(out, size) : next_report(out, size);
  }

  /// Fixed framing: frames of n bytes from now on (1..Capacity/2; 0: none,
  /// next() returns no_data). Pending bytes are dropped (counted as
  /// skipped): they belonged to the previous exchange. False when n is out
  /// of range (nothing changes).
  bool set_frame_size(std::size_t n) noexcept {
    if (n > Capacity / 2) return false;
    drop_pending();
    frame_size_ = n;
    return true;
  }
  [[nodiscard]] std::size_t frame_size() const noexcept { return frame_size_; }

  /// Drops every pending byte (counted as skipped): resynchronisation of a
  /// fixed-size stream. Returns how many bytes went.
  std::size_t drop_pending() noexcept {
    const std::size_t n = end_ - begin_;
    counters_.skipped += n;
    begin_ = end_ = 0;
    return n;
  }

  /// Drops every pending byte (counted as overflow): a full buffer that
  /// holds no frame.
  void discard() noexcept {
    counters_.overflow += end_ - begin_;
    begin_ = end_ = 0;
  }

  [[nodiscard]] std::size_t pending() const noexcept { return end_ - begin_; }
  [[nodiscard]] bool full() const noexcept { return begin_ == 0 && end_ == Capacity; }
  [[nodiscard]] const FramerCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] Framing framing() const noexcept { return framing_; }

 private:
  void compact() noexcept {
    if (begin_ == 0) return;
    const std::size_t n = end_ - begin_;
    if (n) std::memmove(buffer_.data(), buffer_.data() + begin_, n);
    begin_ = 0;
    end_ = n;
  }

  Status next_report(std::span<std::uint8_t> out, std::size_t& size) noexcept {
    while (end_ > begin_) {
      const std::size_t need = protocol::report_size(buffer_[begin_]);
      if (need == 0 || need > out.size()) {
        ++begin_;
        ++counters_.skipped;
        continue;
      }
      if (end_ - begin_ < need) {  // partial, or a stray byte that looks like an id
        if (!skip_to_complete_frame(out.size())) return Status::no_data;  // wait for the rest
        continue;
      }
      const std::span<const std::uint8_t> frame(buffer_.data() + begin_, need);
      if (protocol::detail::get_u16(frame, need - 2) != protocol::crc16(frame.first(need - 2))) {
        ++begin_;  // not a frame boundary after all: rescan from the next byte
        ++counters_.skipped;
        continue;
      }
      std::memcpy(out.data(), frame.data(), need);
      size = need;
      begin_ += need;
      ++counters_.frames;
      return Status::ok;
    }
    return Status::no_data;
  }

  Status next_fixed(std::span<std::uint8_t> out, std::size_t& size) noexcept {
    while (frame_size_ != 0 && end_ - begin_ >= frame_size_) {
      const std::size_t at = begin_;
      begin_ += frame_size_;
      if (frame_size_ > out.size()) {
        counters_.overflow += frame_size_;
        continue;
      }  // caller's buffer too small
      std::memcpy(out.data(), buffer_.data() + at, frame_size_);
      size = frame_size_;
      ++counters_.frames;
      return Status::ok;
    }
    return Status::no_data;
  }

  /// A complete, valid frame further on means the head is garbage (a stray
  /// byte that looked like an id): skip to it. False when there is none.
  bool skip_to_complete_frame(std::size_t limit) noexcept {
    for (std::size_t at = begin_ + 1; at < end_; ++at) {
      const std::size_t need = protocol::report_size(buffer_[at]);
      if (need == 0 || need > limit || end_ - at < need) continue;
      const std::span<const std::uint8_t> frame(buffer_.data() + at, need);
      if (protocol::detail::get_u16(frame, need - 2) != protocol::crc16(frame.first(need - 2))) continue;
      counters_.skipped += at - begin_;
      begin_ = at;
      return true;
    }
    return false;
  }

  Status next_line(std::span<std::uint8_t> out, std::size_t& size) noexcept {
    while (end_ > begin_) {
      std::size_t at = begin_;
      while (at < end_ && buffer_[at] != '\n')
        ++at;
      if (at == end_) {                   // no end of line yet
        if (end_ - begin_ > max_line_) {  // too long already: drop it up to its '\n'
          counters_.overflow += end_ - begin_;
          begin_ = end_;
          dropping_ = true;
        }
        return Status::no_data;
      }
      const std::size_t line_begin = begin_;
      begin_ = at + 1;
      if (dropping_) {
        counters_.overflow += at + 1 - line_begin;
        dropping_ = false;
        continue;
      }
      std::size_t n = 0;
      bool fits = true;
      for (std::size_t i = line_begin; i < at; ++i) {
        if (buffer_[i] == 0) continue;  // NUL padding
        if (n == max_line_ || n == out.size()) {
          fits = false;
          break;
        }
        out[n++] = buffer_[i];
      }
      if (!fits) {
        counters_.overflow += at + 1 - line_begin;
        continue;
      }
      if (n == 0) continue;  // only padding
      size = n;
      ++counters_.frames;
      return Status::ok;
    }
    return Status::no_data;
  }

  std::array<std::uint8_t, Capacity> buffer_{};
  std::size_t begin_{0};
  std::size_t end_{0};
  FramerCounters counters_{};
  Framing framing_;
  std::size_t max_line_;
  std::size_t frame_size_{0};  ///< fixed framing [bytes]; 0: none set
  bool dropping_{false};
};

}  // namespace hapticfield
