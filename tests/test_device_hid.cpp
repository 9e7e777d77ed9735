// Tests of the hidapi transport on a machine without the arm: it compiles,
// enumerates, and reports clear errors.
#include <catch2/catch.hpp>

#include <cerrno>
#include <string>

#include "hapticfield/transport/hid_transport.hpp"

using namespace hapticfield;

TEST_CASE("HidTransport reports a clear 'no device' error when the arm is absent") {
  // The reference ids; the build machine has no such device.
  if (!HidTransport::enumerate(default_vendor_id, default_product_id).empty()) {
    WARN("a device with the reference ids is present: skipping the absent-device check");
    return;
  }
  try {
    HidTransport t(default_vendor_id, default_product_id);
    FAIL("opened a device that is not there");
  } catch (const DeviceError& e) {
    const std::string what = e.what();
    CHECK(what.find("no device with VID:PID 1209:0001") != std::string::npos);
    CHECK(what.find("plugged in") != std::string::npos);
  }
}

TEST_CASE("HidTransport rejects an unknown path with a clear error") {
  try {
    HidTransport t(std::string("/dev/hidraw-hapticfield-none"));
    FAIL("opened a path that does not exist");
  } catch (const DeviceError& e) {
    CHECK(std::string(e.what()).find("no device at /dev/hidraw-hapticfield-none") != std::string::npos);
  }
}

TEST_CASE("permission denied names the udev rule that fixes it") {
  const std::string m = detail::open_error_message("/dev/hidraw3", EACCES);
  CHECK(m.find("permission denied on /dev/hidraw3") != std::string::npos);
  CHECK(m.find("udev/70-hapticfield.rules") != std::string::npos);
  CHECK(m.find("/etc/udev/rules.d/") != std::string::npos);
  // The rule file ships where the message says.
  const std::string rule = std::string(HAPTICFIELD_SOURCE_DIR) + "/" + udev_rule_name;
  std::FILE* f = std::fopen(rule.c_str(), "r");
  REQUIRE(f != nullptr);
  char buffer[2048] = {};
  const std::size_t n = std::fread(buffer, 1, sizeof buffer - 1, f);
  std::fclose(f);
  const std::string text(buffer, n);
  CHECK(text.find("ATTRS{idVendor}==\"1209\"") != std::string::npos);
  CHECK(text.find("ATTRS{idProduct}==\"0001\"") != std::string::npos);
  CHECK(text.find("hidraw") != std::string::npos);
}

TEST_CASE("enumeration works without devices") {
  CHECK_NOTHROW(HidTransport::enumerate());
}
