#pragma once
/// @file recording.hpp
/// RecordingTransport (records any session, decorating another transport)
/// and ReplayTransport (plays a recorded session back on a time source).
///
/// File format: the line "hapticfield-recording 1\n", then records of
/// [u8 kind][i64 LE time since the first record, ns][u8 length][bytes];
/// kind 'I' input report, 'O' output report, 'F' feature report got,
/// 'S' feature report sent.

#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/reports.hpp"

namespace hapticfield {

/// One recorded report.
struct RecordedReport {
  std::int64_t time{0};  ///< [ns] since the first record
  char kind{'I'};        ///< 'I', 'O', 'F' or 'S'
  std::uint8_t size{0};
  std::array<std::uint8_t, protocol::max_report_size> bytes{};
};

namespace detail {
inline constexpr const char* recording_magic = "hapticfield-recording 1\n";
}  // namespace detail

/// Records every report that passes into a buffer reserved at construction
/// (no allocation or I/O per tick); save() writes the file afterwards.
class RecordingTransport final : public Transport {
 public:
  /// @param capacity  records kept [reports]; later ones are counted as dropped
  /// @throws std::invalid_argument for a missing time source or zero capacity.
  RecordingTransport(Transport& inner, TimeSource now, std::size_t capacity = 200'000)
      : inner_(&inner), now_(std::move(now)) {
    if (!now_) throw std::invalid_argument("RecordingTransport: a time source is required");
    if (capacity == 0) throw std::invalid_argument("RecordingTransport: capacity must be > 0 [reports]");
    records_.reserve(capacity);
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept override {
    const Status s = inner_->read(buffer, size, timeout_us);
    if (s == Status::ok) record('I', buffer.first(size));
    return s;
  }
  Status write(std::span<const std::uint8_t> report) noexcept override {
    record('O', report);
    return inner_->write(report);
  }
  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept override {
    const Status s = inner_->get_feature(buffer, size);
    if (s == Status::ok) record('F', buffer.first(size));
    return s;
  }
  Status send_feature(std::span<const std::uint8_t> report) noexcept override {
    record('S', report);
    return inner_->send_feature(report);
  }

  [[nodiscard]] const std::vector<RecordedReport>& records() const noexcept { return records_; }
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_; }

  /// Writes the recording. @throws std::runtime_error naming the path.
  void save(const std::string& path) const {
    std::ofstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error("RecordingTransport: cannot write " + path);
    f << detail::recording_magic;
    for (const RecordedReport& r : records_) {
      std::array<std::uint8_t, 10> head{};
      head[0] = static_cast<std::uint8_t>(r.kind);
      for (int i = 0; i < 8; ++i)
        head[1 + i] = static_cast<std::uint8_t>((static_cast<std::uint64_t>(r.time) >> (8 * i)) & 0xFF);
      head[9] = r.size;
      f.write(reinterpret_cast<const char*>(head.data()), head.size());
      f.write(reinterpret_cast<const char*>(r.bytes.data()), r.size);
    }
    if (!f) throw std::runtime_error("RecordingTransport: writing " + path + " failed");
  }

 private:
  void record(char kind, std::span<const std::uint8_t> bytes) noexcept {
    if (records_.size() == records_.capacity()) {
      ++dropped_;
      return;
    }
    const std::int64_t now = now_();
    if (records_.empty()) t0_ = now;
    RecordedReport r;
    r.time = now - t0_;
    r.kind = kind;
    r.size = static_cast<std::uint8_t>(bytes.size() < r.bytes.size() ? bytes.size() : r.bytes.size());
    std::memcpy(r.bytes.data(), bytes.data(), r.size);
    records_.push_back(r);  // within the reserved capacity: no allocation
  }

  Transport* inner_;
  TimeSource now_;
  std::vector<RecordedReport> records_;
  std::int64_t t0_{0};
  std::uint64_t dropped_{0};
};

/// Plays the input reports of a recording back at their recorded times on
/// a time source; answers feature requests with the recorded replies;
/// accepts and counts output reports. After the last input report read()
/// returns disconnected (the session is over).
class ReplayTransport final : public Transport {
 public:
  /// @throws std::runtime_error when the file is missing, not a recording
  ///         or truncated; std::invalid_argument without a time source.
  ReplayTransport(const std::string& path, TimeSource now) : now_(std::move(now)) {
    if (!now_) throw std::invalid_argument("ReplayTransport: a time source is required");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error("ReplayTransport: cannot open " + path);
    std::string magic(std::strlen(detail::recording_magic), '\0');
    f.read(magic.data(), static_cast<std::streamsize>(magic.size()));
    if (!f || magic != detail::recording_magic)
      throw std::runtime_error("ReplayTransport: " + path + " is not a hapticfield recording");
    for (;;) {
      std::array<std::uint8_t, 10> head{};
      f.read(reinterpret_cast<char*>(head.data()), head.size());
      if (f.gcount() == 0) break;
      if (f.gcount() != static_cast<std::streamsize>(head.size()))
        throw std::runtime_error("ReplayTransport: " + path + " is truncated");
      RecordedReport r;
      r.kind = static_cast<char>(head[0]);
      std::uint64_t t = 0;
      for (int i = 0; i < 8; ++i)
        t |= static_cast<std::uint64_t>(head[1 + i]) << (8 * i);
      r.time = static_cast<std::int64_t>(t);
      r.size = head[9];
      if (r.size > r.bytes.size() || (r.kind != 'I' && r.kind != 'O' && r.kind != 'F' && r.kind != 'S'))
        throw std::runtime_error("ReplayTransport: " + path + " holds a malformed record");
      f.read(reinterpret_cast<char*>(r.bytes.data()), r.size);
      if (f.gcount() != r.size) throw std::runtime_error("ReplayTransport: " + path + " is truncated");
      if (r.kind == 'I') inputs_.push_back(r);
      if (r.kind == 'F') features_.push_back(r);
    }
    start_ = now_();
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int) noexcept override {
    if (next_ >= inputs_.size()) return Status::disconnected;
    const RecordedReport& r = inputs_[next_];
    if (r.time > now_() - start_) return Status::no_data;  // times since the recording began
    if (buffer.size() < r.size) return Status::short_report;
    std::memcpy(buffer.data(), r.bytes.data(), r.size);
    size = r.size;
    ++next_;
    return Status::ok;
  }
  Status write(std::span<const std::uint8_t>) noexcept override {
    ++writes_;
    return Status::ok;
  }
  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept override {
    if (buffer.empty()) return Status::short_report;
    for (const RecordedReport& r : features_)
      if (r.size > 0 && r.bytes[0] == buffer[0] && buffer.size() >= r.size) {
        std::memcpy(buffer.data(), r.bytes.data(), r.size);
        size = r.size;
        return Status::ok;
      }
    return Status::unsupported;
  }
  Status send_feature(std::span<const std::uint8_t>) noexcept override { return Status::ok; }

  [[nodiscard]] std::size_t input_reports() const noexcept { return inputs_.size(); }
  [[nodiscard]] std::uint64_t writes() const noexcept { return writes_; }

 private:
  TimeSource now_;
  std::vector<RecordedReport> inputs_;
  std::vector<RecordedReport> features_;
  std::size_t next_{0};
  std::int64_t start_{0};
  std::uint64_t writes_{0};
};

}  // namespace hapticfield
