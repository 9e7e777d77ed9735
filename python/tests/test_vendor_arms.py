"""run_servo(device='openhaptics' / 'dhd') against the stand-in libHD / libdhd the C++ tests build
(build/tests/standins/), each run in a child Python as a user runs it: the run ends with zero force on
the arm, a device error mid-run ends it as disconnected with zero force, a missing SDK is one hf.Error."""
import os
import pathlib
import subprocess
import sys

import pytest

import hapticfield as hf

# The module sits in <build>/python/hapticfield/; the stand-ins in <build>/tests/standins/.
BUILD = pathlib.Path(hf.__file__).resolve().parents[2]
STANDINS = BUILD / "tests" / "standins"
HD = STANDINS / "hd" / "libHD.so"
DHD = STANDINS / "dhd" / "libdhd.so.3"

RUN = """
import hapticfield as hf
run = hf.run_servo(hf.plane_contact(point=(0.0, 0.0, 0.02)), seconds=0.5, device={device!r},
                   confirm_hardware=True, realtime="off")
print(run["stop_reason"], *run["final_force"])
"""


def report(path: pathlib.Path) -> dict:
    """What the stand-in wrote when the arm was closed, key -> rest of the line."""
    return dict(line.split(" ", 1) for line in path.read_text().splitlines())


def run_child(device, env_extra, tmp_path):
    report_path = tmp_path / "report.txt"
    env = dict(os.environ, HFSTANDIN_REPORT=str(report_path), **env_extra)
    done = subprocess.run([sys.executable, "-c", RUN.format(device=device)], env=env, capture_output=True,
                          text=True, timeout=120)
    return done, report_path


ARMS = [
    pytest.param("openhaptics", {"HAPTICFIELD_HD_LIBRARY": str(HD)}, "HFSTANDIN_HD", "device_error_at=200", id="hd"),
    # the documented name, found through the loader's search path
    pytest.param("dhd", {"LD_LIBRARY_PATH": str(DHD.parent)}, "HFSTANDIN_DHD", "com_error_at=200", id="dhd"),
]


@pytest.mark.skipif(not (HD.exists() and DHD.exists()), reason="the stand-ins are built with the C++ tests")
@pytest.mark.parametrize("device, library, faults, device_error", ARMS)
def test_run_servo_on_a_vendor_arm_ends_at_zero_force(device, library, faults, device_error, tmp_path):
    done, report_path = run_child(device, {**library, faults: ""}, tmp_path)
    assert done.returncode == 0, done.stderr
    reason, *force = done.stdout.split()
    assert reason == "tick_limit"
    assert [float(f) for f in force] == [0.0, 0.0, 0.0]
    assert report(report_path)["last_force"] == "0 0 0"


@pytest.mark.skipif(not (HD.exists() and DHD.exists()), reason="the stand-ins are built with the C++ tests")
@pytest.mark.parametrize("device, library, faults, device_error", ARMS)
def test_a_device_error_mid_run_ends_it_disconnected_at_zero_force(device, library, faults, device_error,
                                                                     tmp_path):
    done, report_path = run_child(device, {**library, faults: device_error}, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[0] == "disconnected"
    assert report(report_path)["last_force"] == "0 0 0"


@pytest.mark.parametrize("device, library", [("openhaptics", "libHD.so"), ("dhd", "libdhd.so.3")])
def test_without_the_sdk_the_error_names_the_library(device, library, monkeypatch):
    monkeypatch.delenv("HAPTICFIELD_HD_LIBRARY", raising=False)
    monkeypatch.delenv("HAPTICFIELD_DHD_LIBRARY", raising=False)
    try:
        import ctypes
        ctypes.CDLL(library)
        pytest.skip(f"{library} is installed here")
    except OSError:
        pass
    with pytest.raises(hf.Error, match=library.replace(".", r"\.")):
        hf.run_servo(hf.zero(), device=device, confirm_hardware=True)
