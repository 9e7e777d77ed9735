// A Falcon-over-USB user: hapticfield::falcon_usb brings libusb-1.0's headers and library (no device is opened).
#include <hapticfield/arms/falcon/falcon_libusb.hpp>

#include <cstdio>
#include <type_traits>

#ifndef HAPTICFIELD_HAS_LIBUSB
#error "hapticfield::falcon_usb must define HAPTICFIELD_HAS_LIBUSB"
#endif

int main() {
  static_assert(std::is_class_v<hapticfield::LibusbFalconUsb>);
  const libusb_version* version = libusb_get_version();  // libusb-1.0 is linked and loads
  std::printf("consumer_falcon_usb: libusb %u.%u.%u\n", version->major, version->minor, version->micro);
  return version->major == 1 ? 0 : 1;
}
