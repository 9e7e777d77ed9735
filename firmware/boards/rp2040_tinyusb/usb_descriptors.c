// EXAMPLE ONLY: not built here, never run on hardware (docs/firmware.md).
// USB descriptors for the RP2040 example: one HID interface on the vendor
// usage page 0xFF48 with numbered reports (docs/device-protocol.md), an
// interrupt IN and OUT endpoint of 64 bytes polled every 1 ms.
#include "tusb.h"

// 0x1209:0x0001 is the pid.codes TEST id: a product gets its own PID
// (docs/firmware.md, "USB ids").
#define HF_VID 0x1209
#define HF_PID 0x0001

// Polling interval of the interrupt endpoints. At full speed (the RP2040's
// only speed) bInterval counts frames of 1 ms: 1 = every frame, set
// explicitly because some examples default to 10 ms.
#define HF_EP_INTERVAL_MS 1

static tusb_desc_device_t const device = {
    .bLength = sizeof(tusb_desc_device_t),
    .bDescriptorType = TUSB_DESC_DEVICE,
    .bcdUSB = 0x0200,
    .bDeviceClass = 0,
    .bDeviceSubClass = 0,
    .bDeviceProtocol = 0,
    .bMaxPacketSize0 = CFG_TUD_ENDPOINT0_SIZE,
    .idVendor = HF_VID,
    .idProduct = HF_PID,
    .bcdDevice = 0x0100,
    .iManufacturer = 1,
    .iProduct = 2,
    .iSerialNumber = 3,
    .bNumConfigurations = 1,
};

uint8_t const* tud_descriptor_device_cb(void) { return (uint8_t const*)&device; }

// Report descriptor: vendor page 0xFF48, usage 1; per report id its size
// without the id byte: input 0x01 (39), output 0x02 (15), features 0x10
// (49), 0x11 (7), 0x12 (3).
#define HF_REPORT(id, kind, count) \
  HID_REPORT_ID(id) HID_USAGE(1) HID_LOGICAL_MIN(0) HID_LOGICAL_MAX_N(255, 2) HID_REPORT_SIZE(8) \
  HID_REPORT_COUNT(count) kind(HID_DATA | HID_VARIABLE | HID_ABSOLUTE)

static uint8_t const report_descriptor[] = {
    HID_USAGE_PAGE_N(0xFF48, 2), HID_USAGE(0x01), HID_COLLECTION(HID_COLLECTION_APPLICATION),
    HF_REPORT(0x01, HID_INPUT, 39),
    HF_REPORT(0x02, HID_OUTPUT, 15),
    HF_REPORT(0x10, HID_FEATURE, 49),
    HF_REPORT(0x11, HID_FEATURE, 7),
    HF_REPORT(0x12, HID_FEATURE, 3),
    HID_COLLECTION_END,
};

uint8_t const* tud_hid_descriptor_report_cb(uint8_t instance) {
  (void)instance;
  return report_descriptor;
}

#define CONFIG_TOTAL_LEN (TUD_CONFIG_DESC_LEN + TUD_HID_INOUT_DESC_LEN)
static uint8_t const configuration[] = {
    TUD_CONFIG_DESCRIPTOR(1, 1, 0, CONFIG_TOTAL_LEN, 0x00, 100),
    // interface 0, no string, no boot protocol, OUT 0x01, IN 0x81, 64 bytes, bInterval 1 [ms]
    TUD_HID_INOUT_DESCRIPTOR(0, 0, HID_ITF_PROTOCOL_NONE, sizeof(report_descriptor), 0x01, 0x81, 64,
                             HF_EP_INTERVAL_MS),
};

uint8_t const* tud_descriptor_configuration_cb(uint8_t index) {
  (void)index;
  return configuration;
}

// String descriptors (manufacturer, product, serial) are the builder's.
