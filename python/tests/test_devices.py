"""The device front door from Python: list_devices() and run_servo(device=...) on every simulated arm."""
import numpy as np
import pytest

import hapticfield as hf


def test_list_devices_one_line_per_family_the_simulated_arm_present():
    listing = hf.list_devices()
    families = [family for family, _, _ in listing]
    assert families[:5] == ["sim", "hid", "serial", "woody", "inverse3"]
    assert len(set(families)) == len(families)
    for family, present, line in listing:
        assert isinstance(present, bool)
        assert "\n" not in line
        assert (": present: " in line) == present or "not built in this version" in line
    assert listing[0][1] is True


@pytest.mark.parametrize("device", ["sim", "woody:p1:sim", "woody:p4:sim", "woody:p2:vintage:sim", "inverse3:sim"])
def test_run_servo_on_every_simulated_arm_pushes_then_stops_at_zero(device):
    # the plane z = 0: a scripted hand holds the handle 8 mm behind it; the
    # Inverse3's twin has no hand: its handle rests at z = 5 cm, behind z = 6 cm
    plane = hf.plane_contact(point=(0.0, 0.0, 0.06)) if device.startswith("inverse3") else hf.plane_contact()
    run = hf.run_servo(plane, seconds=0.8, device=device, hand="hold")
    assert run["stop_reason"] == "tick_limit"
    assert len(run["trace"]["t"]) == 800
    assert np.max(np.linalg.norm(run["trace"]["force"], axis=1)) > 0.05
    assert np.allclose(run["final_force"], 0.0)


@pytest.mark.parametrize("device, message", [
    ("usb", "device 'usb': unknown device"),
    ("sim:fast", "device 'sim:fast': sim takes nothing"),
    ("hid:12345:1", "hexadecimal"),
    ("woody:p9:sim", "generation must be p1, p2 or p4"),
    ("woody:p4", "needs the arm's tty"),
    ("inverse3:", "nothing after"),
])
def test_a_bad_device_string_is_a_value_error_naming_it(device, message):
    with pytest.raises(ValueError, match=message):
        hf.run_servo(hf.zero(), device=device)


@pytest.mark.parametrize("device", ["hid", "serial:/dev/ttyACM0", "woody:p4:/dev/ttyACM0", "inverse3:/dev/ttyACM0"])
def test_a_real_arm_needs_confirm_hardware_and_the_wall_clock(device):
    with pytest.raises(ValueError, match="confirm_hardware"):
        hf.run_servo(hf.zero(), device=device)
    with pytest.raises(ValueError, match="virtual clock.*real arm"):
        hf.run_servo(hf.zero(), device=device, clock="virtual", confirm_hardware=True)


def test_a_missing_serial_arm_is_one_error_naming_its_path():
    with pytest.raises(hf.Error, match="/no/such/tty"):
        hf.run_servo(hf.zero(), device="serial:/no/such/tty", confirm_hardware=True)
