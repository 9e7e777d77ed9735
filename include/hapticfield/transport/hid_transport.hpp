#pragma once
/// @file hid_transport.hpp
/// HidTransport: the report protocol over hidapi (hidraw backend). The only
/// code in the library that includes hidapi.h; include it (and link
/// hapticfield::hid) only for real hardware.
///
/// One I/O thread owns the hid_device: it reads input reports into a
/// lock-free ring the servo thread drains each tick (ForceArm keeps the
/// newest), and writes only the newest pending command (an older one is
/// stale by then). A read error means the device is gone: every later call
/// returns Status::disconnected.

#include <hidapi.h>

#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <cwchar>
#include <mutex>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hapticfield/core/error.hpp"
#include "hapticfield/device/device_error.hpp"
#include "hapticfield/device/transport.hpp"
#include "hapticfield/protocol/reports.hpp"
#include "hapticfield/rt/spsc_ring.hpp"

namespace hapticfield {

/// The shipped udev rule that gives users access to the hidraw node.
inline constexpr const char* udev_rule_name = "udev/70-hapticfield.rules";

/// One HID device hidapi can see.
struct HidDeviceInfo {
  std::string path;
  std::uint16_t vendor_id{0};
  std::uint16_t product_id{0};
  std::uint16_t usage_page{0};
  std::string product;
  std::string serial;
};

namespace detail {
inline std::string narrow(const wchar_t* w) {
  std::string s;
  if (!w) return s;
  for (; *w; ++w)
    s += (*w < 128) ? static_cast<char>(*w) : '?';
  return s;
}
inline std::string hex4(std::uint16_t v) {
  char b[8];
  std::snprintf(b, sizeof b, "%04x", v);
  return b;
}
/// The message for a hidraw node that exists but cannot be opened.
inline std::string open_error_message(const std::string& path, int error) {
  if (error == EACCES || error == EPERM)
    return "HidTransport: permission denied on " + path + ". Install the udev rule " + udev_rule_name + " (sudo cp " +
           udev_rule_name +
           " /etc/udev/rules.d/ && sudo udevadm control --reload && "
           "sudo udevadm trigger), then unplug and replug the arm";
  if (error == ENOENT) return "HidTransport: no device at " + path + " (unplugged, or a wrong path)";
  return "HidTransport: cannot open " + path + ": " + std::strerror(error);
}
inline void hid_init_once() {
  static const int r = hid_init();
  if (r != 0) throw DeviceError("HidTransport: hid_init failed");
}
/// One report as it waits in a queue between the servo and I/O threads:
/// its bytes (at most 64) and how many.
struct QueuedReport {
  std::array<std::uint8_t, protocol::max_report_size> bytes{};
  std::size_t size{0};
};

/// Queues a report (cut to 64 bytes); false when the ring is full.
template <std::size_t N>
bool push_report(rt::SpscRing<QueuedReport, N>& ring, std::span<const std::uint8_t> report) noexcept {
  QueuedReport queued;
  queued.size = report.size() < queued.bytes.size() ? report.size() : queued.bytes.size();
  std::memcpy(queued.bytes.data(), report.data(), queued.size);
  return ring.try_push(queued);
}

/// Copies the oldest queued report into out (cut to out's size) and its
/// length into size; false when none is queued.
template <std::size_t N>
bool pop_report(rt::SpscRing<QueuedReport, N>& ring, std::span<std::uint8_t> out, std::size_t& size) noexcept {
  const std::optional<QueuedReport> queued = ring.try_pop();
  if (!queued) return false;
  size = queued->size < out.size() ? queued->size : out.size();
  std::memcpy(out.data(), queued->bytes.data(), size);
  return true;
}

}  // namespace detail

class HidTransport final : public Transport {
 public:
  /// Every HID device with the given ids (0 matches any).
  [[nodiscard]] static std::vector<HidDeviceInfo> enumerate(std::uint16_t vendor_id = 0, std::uint16_t product_id = 0) {
    detail::hid_init_once();
    std::vector<HidDeviceInfo> out;
    hid_device_info* list = hid_enumerate(vendor_id, product_id);
    for (hid_device_info* d = list; d; d = d->next)
      out.push_back({d->path ? d->path : "", d->vendor_id, d->product_id, d->usage_page,
                     detail::narrow(d->product_string), detail::narrow(d->serial_number)});
    hid_free_enumeration(list);
    return out;
  }

  /// Opens the first device with these ids.
  /// @throws DeviceError: no such device ("no device"), permission denied
  ///         (names the udev rule), or any other open failure.
  HidTransport(std::uint16_t vendor_id, std::uint16_t product_id) {
    const std::vector<HidDeviceInfo> all = enumerate(vendor_id, product_id);
    if (all.empty()) {
      const std::size_t any = enumerate().size();
      throw DeviceError("HidTransport: no device with VID:PID " + detail::hex4(vendor_id) + ":" +
                        detail::hex4(product_id) + " found (" + std::to_string(any) +
                        " HID devices present); is the arm plugged in and powered?");
    }
    open(all.front().path);
  }

  /// Opens a hidraw node by path (e.g. /dev/hidraw3).
  /// @throws DeviceError as above.
  explicit HidTransport(const std::string& path) {
    detail::hid_init_once();
    open(path);
  }

  ~HidTransport() override {
    running_.store(false, std::memory_order_relaxed);
    if (io_.joinable()) io_.join();
    if (device_) hid_close(device_);
  }

  /// Pops the oldest queued input report; with timeout_us > 0 spins (with
  /// yields) up to that long for one, then returns Status::timeout.
  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept override {
    if (detail::pop_report(input_, buffer, size)) return Status::ok;
    if (timeout_us > 0) {
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::microseconds(timeout_us);
      while (std::chrono::steady_clock::now() < deadline) {
        if (detail::pop_report(input_, buffer, size)) return Status::ok;
        if (disconnected_.load(std::memory_order_acquire)) return Status::disconnected;
        std::this_thread::yield();
      }
      return Status::timeout;
    }
    return disconnected_.load(std::memory_order_acquire) ? Status::disconnected : Status::no_data;
  }

  Status write(std::span<const std::uint8_t> report) noexcept override {
    if (disconnected_.load(std::memory_order_acquire)) return Status::disconnected;
    return detail::push_report(output_, report) ? Status::ok : Status::overflow;
  }

  /// Feature reports are setup calls: they take the device lock the I/O
  /// thread holds around each hidapi call (never on the tick path).
  Status get_feature(std::span<std::uint8_t> buffer, std::size_t& size) noexcept override {
    if (disconnected_.load(std::memory_order_acquire)) return Status::disconnected;
    std::lock_guard<std::mutex> lock(device_mutex_);
    const int n = hid_get_feature_report(device_, buffer.data(), buffer.size());
    if (n < 0) return Status::disconnected;
    size = static_cast<std::size_t>(n);
    return Status::ok;
  }

  Status send_feature(std::span<const std::uint8_t> report) noexcept override {
    if (disconnected_.load(std::memory_order_acquire)) return Status::disconnected;
    std::lock_guard<std::mutex> lock(device_mutex_);
    return hid_send_feature_report(device_, report.data(), report.size()) < 0 ? Status::disconnected : Status::ok;
  }

  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  [[nodiscard]] std::uint64_t input_overflows() const noexcept { return overflows_.load(std::memory_order_relaxed); }

 private:
  void open(const std::string& path) {
    path_ = path;
    if (::access(path.c_str(), F_OK) != 0) throw DeviceError(detail::open_error_message(path, errno));
    if (::access(path.c_str(), R_OK | W_OK) != 0) throw DeviceError(detail::open_error_message(path, errno));
    device_ = hid_open_path(path.c_str());
    if (!device_) throw DeviceError(detail::open_error_message(path, errno ? errno : EIO));
    running_.store(true, std::memory_order_relaxed);
    io_ = std::thread([this] { io_loop(); });
  }

  void io_loop() noexcept {
    std::array<std::uint8_t, protocol::max_report_size> in{};
    std::array<std::uint8_t, protocol::max_report_size> out{};
    while (running_.load(std::memory_order_relaxed)) {
      int n = 0;
      {
        std::lock_guard<std::mutex> lock(device_mutex_);
        n = hid_read_timeout(device_, in.data(), in.size(), 1);
      }
      if (n < 0) {
        disconnected_.store(true, std::memory_order_release);
        return;
      }
      if (n > 0 && !detail::push_report(input_, std::span<const std::uint8_t>(in.data(), static_cast<std::size_t>(n))))
        overflows_.fetch_add(1, std::memory_order_relaxed);
      // Write only the newest pending command; older ones are stale.
      std::size_t size = 0, newest = 0;
      while (detail::pop_report(output_, out, size))
        newest = size;
      if (newest) {
        std::lock_guard<std::mutex> lock(device_mutex_);
        if (hid_write(device_, out.data(), newest) < 0) {
          disconnected_.store(true, std::memory_order_release);
          return;
        }
      }
    }
  }

  hid_device* device_{nullptr};
  std::string path_;
  std::thread io_;
  std::mutex device_mutex_;
  rt::SpscRing<detail::QueuedReport, 256> input_;
  rt::SpscRing<detail::QueuedReport, 16> output_;
  std::atomic<bool> running_{false};
  std::atomic<bool> disconnected_{false};
  std::atomic<std::uint64_t> overflows_{0};
};

}  // namespace hapticfield
