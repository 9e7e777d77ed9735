#pragma once
/// @file falcon_libusb.hpp
/// LibusbFalconUsb: the Falcon's USB link over libusb-1.0 (Debian
/// libusb-1.0-0-dev; CMake target hapticfield::falcon_usb, through
/// pkg-config libusb-1.0). The only code that includes libusb.h.
///
/// FTDI vendor requests are synchronous control transfers (setup only).
/// Writes of up to 16 bytes (the commands) are asynchronous bulk transfers that
/// never wait; one bulk IN transfer of one USB packet is kept in flight and
/// polled without waiting, so a tick never blocks on the bus. libusb's own
/// submit may allocate inside the library (its Linux back end does), which
/// our allocation test cannot see. Never run against a real Falcon here
/// (docs/arms-falcon.md).

// libusb.h declares zero-sized arrays (a GNU extension) that -Wpedantic rejects.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpedantic"
#endif
#include <libusb.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "hapticfield/arms/falcon/falcon_codec.hpp"
#include "hapticfield/arms/falcon/falcon_usb.hpp"
#include "hapticfield/device/device_error.hpp"

namespace hapticfield {

class LibusbFalconUsb final : public FalconUsb {
 public:
  /// Falcons (USB 0403:cb48) on the bus.
  /// @throws DeviceError when libusb cannot start.
  [[nodiscard]] static unsigned count() {
    libusb_context* ctx = nullptr;
    if (libusb_init(&ctx) != 0) throw DeviceError("Falcon: libusb_init failed");
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx, &list);
    unsigned found = 0;
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device_descriptor desc{};
      if (libusb_get_device_descriptor(list[i], &desc) == 0 && desc.idVendor == falcon::vendor_id &&
          desc.idProduct == falcon::product_id)
        ++found;
    }
    if (n >= 0) libusb_free_device_list(list, 1);
    libusb_exit(ctx);
    return found;
  }

  /// Opens the index-th Falcon (0: the first) and claims its interface.
  /// @throws DeviceError "no Falcon found", an index beyond the Falcons
  ///         found, or a device that cannot be opened (permissions: the
  ///         udev rule of docs/arms-falcon.md).
  explicit LibusbFalconUsb(unsigned index = 0) {
    if (libusb_init(&ctx_) != 0) throw DeviceError("Falcon: libusb_init failed");
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx_, &list);
    libusb_device* chosen = nullptr;
    unsigned found = 0;
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device_descriptor desc{};
      if (libusb_get_device_descriptor(list[i], &desc) != 0 || desc.idVendor != falcon::vendor_id ||
          desc.idProduct != falcon::product_id)
        continue;
      if (found++ == index) chosen = list[i];
    }
    if (chosen) {
      where_ = "USB bus " + std::to_string(libusb_get_bus_number(chosen)) + " address " +
               std::to_string(libusb_get_device_address(chosen));
      const int e = libusb_open(chosen, &handle_);
      if (e != 0) handle_ = nullptr;
      if (e == LIBUSB_ERROR_ACCESS)
        open_error_ = "permission denied: install the udev rule of docs/arms-falcon.md";
      else if (e != 0)
        open_error_ = libusb_error_name(e);
    }
    if (n >= 0) libusb_free_device_list(list, 1);
    if (!chosen) {
      libusb_exit(ctx_);
      if (found == 0) throw DeviceError("Falcon: no Falcon found (USB 0403:cb48); check its cable and power supply");
      throw DeviceError("Falcon: index " + std::to_string(index) + " but only " + std::to_string(found) +
                        " Falcon(s) found");
    }
    if (!handle_) {
      libusb_exit(ctx_);
      throw DeviceError("Falcon: cannot open the Falcon at " + where_ + ": " + open_error_);
    }
    libusb_set_auto_detach_kernel_driver(handle_, 1);
    if (const int e = libusb_claim_interface(handle_, 0); e != 0) {
      libusb_close(handle_);
      libusb_exit(ctx_);
      throw DeviceError("Falcon: cannot claim the Falcon's interface at " + where_ + ": " + libusb_error_name(e));
    }
    in_ = libusb_alloc_transfer(0);
    out_ = libusb_alloc_transfer(0);
    if (!in_ || !out_) {
      close();
      throw DeviceError("Falcon: cannot allocate USB transfers");
    }
  }

  ~LibusbFalconUsb() override { close(); }
  LibusbFalconUsb(const LibusbFalconUsb&) = delete;
  LibusbFalconUsb& operator=(const LibusbFalconUsb&) = delete;

  Status control(std::uint8_t request, std::uint16_t value) noexcept override {
    if (!handle_ || gone_) return Status::disconnected;
    const int e = libusb_control_transfer(handle_, 0x40, request, value, 0, nullptr, 0, 1000);
    return e >= 0 ? Status::ok : fail(e);
  }

  Status write(std::span<const std::uint8_t> bytes) noexcept override {
    if (!handle_ || gone_) return Status::disconnected;
    pump(0);
    if (bytes.size() > falcon::packet_size) {  // a firmware chunk: wait for it
      for (int i = 0; i < 1000 && out_busy_; ++i)
        pump(1000);
      if (out_busy_) return Status::timeout;
      int sent = 0;
      const int e = libusb_bulk_transfer(handle_, falcon::endpoint_out, const_cast<unsigned char*>(bytes.data()),
                                         static_cast<int>(bytes.size()), &sent, 1000);
      if (e != 0) return fail(e);
      return sent == static_cast<int>(bytes.size()) ? Status::ok : Status::timeout;
    }
    if (out_busy_) return Status::overflow;
    std::copy(bytes.begin(), bytes.end(), out_buf_.begin());
    libusb_fill_bulk_transfer(out_, handle_, falcon::endpoint_out, out_buf_.data(), static_cast<int>(bytes.size()),
                              &LibusbFalconUsb::out_done, this, 1000);
    if (const int e = libusb_submit_transfer(out_); e != 0) return fail(e);
    out_busy_ = true;
    return Status::ok;
  }

  Status read(std::span<std::uint8_t> buffer, std::size_t& size, int timeout_us) noexcept override {
    size = 0;
    if (!handle_ || gone_) return Status::disconnected;
    if (rx_size_ == 0) {
      if (!in_busy_) {
        libusb_fill_bulk_transfer(in_, handle_, falcon::endpoint_in, in_buf_.data(), static_cast<int>(in_buf_.size()),
                                  &LibusbFalconUsb::in_done, this, 0);
        if (const int e = libusb_submit_transfer(in_); e != 0) return fail(e);
        in_busy_ = true;
      }
      pump(timeout_us);
      if (gone_) return Status::disconnected;
    }
    if (rx_size_ == 0) return Status::no_data;
    const std::size_t n = std::min(buffer.size(), rx_size_);
    std::copy_n(rx_.begin(), n, buffer.begin());
    std::copy(rx_.begin() + static_cast<std::ptrdiff_t>(n), rx_.begin() + static_cast<std::ptrdiff_t>(rx_size_),
              rx_.begin());
    rx_size_ -= n;
    size = n;
    return Status::ok;
  }

  [[nodiscard]] std::string_view where() const noexcept override { return where_; }

 private:
  static void LIBUSB_CALL out_done(libusb_transfer* t) {
    auto* self = static_cast<LibusbFalconUsb*>(t->user_data);
    self->out_busy_ = false;
    if (t->status == LIBUSB_TRANSFER_NO_DEVICE) self->gone_ = true;
  }
  static void LIBUSB_CALL in_done(libusb_transfer* t) {
    auto* self = static_cast<LibusbFalconUsb*>(t->user_data);
    self->in_busy_ = false;
    if (t->status == LIBUSB_TRANSFER_NO_DEVICE) self->gone_ = true;
    if (t->status != LIBUSB_TRANSFER_COMPLETED) return;
    // every USB packet of the transfer starts with the FTDI's 2 status bytes
    const auto got = static_cast<std::size_t>(t->actual_length);
    for (std::size_t at = 0; at < got; at += falcon::usb_packet_size) {
      const std::size_t end = std::min(got, at + falcon::usb_packet_size);
      for (std::size_t i = at + falcon::ftdi_status_bytes; i < end && self->rx_size_ < self->rx_.size(); ++i)
        self->rx_[self->rx_size_++] = t->buffer[i];
    }
  }

  void pump(int timeout_us) noexcept {
    timeval tv{};
    tv.tv_sec = timeout_us / 1000000;
    tv.tv_usec = timeout_us % 1000000;
    libusb_handle_events_timeout_completed(ctx_, &tv, nullptr);
  }

  Status fail(int e) noexcept {
    if (e == LIBUSB_ERROR_NO_DEVICE || e == LIBUSB_ERROR_IO) {
      gone_ = true;
      return Status::disconnected;
    }
    return e == LIBUSB_ERROR_TIMEOUT ? Status::timeout : Status::fault;
  }

  void close() noexcept {
    if (!ctx_) return;
    if (handle_) {
      if (in_busy_ && in_) libusb_cancel_transfer(in_);
      if (out_busy_ && out_) libusb_cancel_transfer(out_);
      for (int i = 0; i < 100 && (in_busy_ || out_busy_); ++i)
        pump(10000);
    }
    if (in_ && !in_busy_) libusb_free_transfer(in_);
    if (out_ && !out_busy_) libusb_free_transfer(out_);
    in_ = out_ = nullptr;
    if (handle_) {
      libusb_release_interface(handle_, 0);
      libusb_close(handle_);
      handle_ = nullptr;
    }
    libusb_exit(ctx_);
    ctx_ = nullptr;
  }

  libusb_context* ctx_{nullptr};
  libusb_device_handle* handle_{nullptr};
  libusb_transfer* in_{nullptr};
  libusb_transfer* out_{nullptr};
  std::array<unsigned char, falcon::usb_packet_size> in_buf_{};
  std::array<unsigned char, falcon::usb_packet_size> out_buf_{};
  std::array<std::uint8_t, 4096> rx_{};
  std::size_t rx_size_{0};
  std::string where_{};
  std::string open_error_{};
  bool in_busy_{false};
  bool out_busy_{false};
  bool gone_{false};
};

/// Opens the index-th Falcon over libusb; see LibusbFalconUsb.
[[nodiscard]] inline std::unique_ptr<LibusbFalconUsb> open_falcon_usb(unsigned index = 0) {
  return std::make_unique<LibusbFalconUsb>(index);
}

}  // namespace hapticfield
