// Tests of the hidapi transport on a machine without the arm: it compiles,
// enumerates, reports clear errors, and its report queues keep order,
// bounds and lengths.
#include <catch2/catch.hpp>

#include <array>
#include <cerrno>
#include <cstddef>
#include <cstdint>
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

TEST_CASE("the report queues keep order and lengths, cut long reports and refuse when full") {
  rt::SpscRing<detail::QueuedReport, 4> ring;
  std::array<std::uint8_t, 80> long_report{};
  for (std::size_t i = 0; i < long_report.size(); ++i)
    long_report[i] = static_cast<std::uint8_t>(i + 1);
  const std::array<std::uint8_t, 3> short_report{0xA1, 0xB2, 0xC3};

  REQUIRE(detail::push_report(ring, long_report));  // 80 bytes: more than any report of the protocol
  REQUIRE(detail::push_report(ring, short_report));
  REQUIRE(detail::push_report(ring, short_report));
  REQUIRE(detail::push_report(ring, short_report));
  CHECK_FALSE(detail::push_report(ring, short_report));  // full: refused, not overwritten
  CHECK(ring.rejected() == 1);

  std::array<std::uint8_t, 64> out{};
  std::size_t size = 0;
  REQUIRE(detail::pop_report(ring, out, size));
  CHECK(size == protocol::max_report_size);  // cut to 64 bytes
  CHECK(out[0] == 1);
  CHECK(out[63] == 64);

  std::array<std::uint8_t, 2> small{};
  REQUIRE(detail::pop_report(ring, small, size));
  CHECK(size == 2);  // cut to the reader's buffer
  CHECK(small[0] == 0xA1);
  CHECK(small[1] == 0xB2);

  REQUIRE(detail::pop_report(ring, out, size));
  CHECK(size == 3);
  CHECK(out[2] == 0xC3);
  REQUIRE(detail::pop_report(ring, out, size));
  CHECK_FALSE(detail::pop_report(ring, out, size));  // empty
}
