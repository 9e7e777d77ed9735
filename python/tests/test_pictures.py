"""Pictures as arrays: channel order, white level, 16-bit; and what a servo trace says of each tick."""
import csv
import os
import struct
import subprocess
import zlib

import numpy as np
import pytest

import hapticfield as hf

XY = np.array([[x, y] for x in np.arange(2.0, 37.0, 1.25) for y in (3.0, 11.5, 20.0)])


def write_png(path, pixels):
    """A PNG (gray or RGB, 8- or 16-bit, by the array's shape and dtype), written here byte by byte."""
    depth = 16 if pixels.dtype == np.uint16 else 8
    colour = 2 if pixels.ndim == 3 else 0
    h, w = pixels.shape[:2]
    samples = pixels.astype(">u2" if depth == 16 else np.uint8)
    rows = b"".join(b"\x00" + row.tobytes() for row in samples.reshape(h, -1))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, colour, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def picture(dtype=np.uint8, channels=3, seed=7):
    """A 24 x 40 colour picture: random blocks, so that every channel matters."""
    top = np.iinfo(dtype).max
    blocks = np.random.default_rng(seed).integers(0, top + 1, (6, 10, channels), dtype=np.int64)
    image = np.kron(blocks, np.ones((4, 4, 1), np.int64)).astype(dtype)
    return image[:, :, 0] if channels == 1 else image


# --- channel order ---------------------------------------------------------------

def test_a_bgr_array_read_as_bgr_gives_the_forces_of_the_rgb_array_and_of_the_file(tmp_path):
    rgb = picture()
    bgr = np.ascontiguousarray(rgb[:, :, ::-1])
    path = tmp_path / "colour.png"
    write_png(path, rgb)  # OpenCV decodes it into B, G, R: an oracle of its own for the order
    from_file = hf.tangible_forces(str(path), XY, size=5)
    np.testing.assert_array_equal(hf.tangible_forces(rgb, XY, size=5, channels="rgb"), from_file)
    np.testing.assert_array_equal(hf.tangible_forces(bgr, XY, size=5, channels="bgr"), from_file)
    np.testing.assert_array_equal(hf.tangible_forces(rgb, XY, size=5), from_file)  # rgb is the default
    assert not np.allclose(hf.tangible_forces(bgr, XY, size=5), from_file)  # the trap the argument names
    for name in ("force_map", "tangible_field"):  # every call that takes a picture takes channels
        call = getattr(hf, name)
        a, b = call(rgb, size=5, channels="rgb"), call(bgr, size=5, channels="bgr")
        if name == "force_map":
            np.testing.assert_array_equal(a[0], b[0])
            np.testing.assert_array_equal(a[1], b[1])
        else:
            p = np.column_stack([np.linspace(-0.002, 0.002, 40), np.zeros(40), np.zeros(40)])
            np.testing.assert_array_equal(a.forces(p), b.forces(p))


def test_an_rgba_array_ignores_alpha_in_either_order():
    rgba = picture(channels=4)
    bgra = np.ascontiguousarray(rgba[:, :, [2, 1, 0, 3]])
    expected = hf.tangible_forces(np.ascontiguousarray(rgba[:, :, :3]), XY, size=5)
    np.testing.assert_array_equal(hf.tangible_forces(rgba, XY, size=5), expected)
    np.testing.assert_array_equal(hf.tangible_forces(bgra, XY, size=5, channels="bgr"), expected)


@pytest.mark.parametrize("call", [
    lambda c: hf.tangible_forces(picture(), XY, size=5, channels=c),
    lambda c: hf.force_map(picture(), size=5, channels=c),
    lambda c: hf.tangible_field(picture(), size=5, channels=c),
    lambda c: hf.tangible_forces(picture(channels=1), XY, size=5, channels=c),  # checked for gray too
])
@pytest.mark.parametrize("bad", ["RGB ", "brg", "", "gray"])
def test_an_unknown_channel_order_is_refused(call, bad):
    with pytest.raises(ValueError, match="channels: unknown .*choose bgr, rgb"):
        call(bad)


# --- white level -------------------------------------------------------------------

def test_a_float_picture_needs_its_white_level():
    gray = picture(channels=1)
    unit = gray / 255.0
    with pytest.raises(ValueError, match="levels="):
        hf.tangible_forces(unit, XY, size=5)
    with pytest.raises(ValueError, match="levels="):
        hf.tangible_field(unit.astype(np.float32))
    with pytest.raises(ValueError, match="levels="):
        hf.force_map(gray > 128)  # bool: no scale either
    expected = hf.tangible_forces(gray, XY, size=5)
    np.testing.assert_allclose(hf.tangible_forces(unit, XY, size=5, levels=1.0), expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(hf.tangible_forces(gray.astype(float), XY, size=5, levels=255), expected)
    # Integer arrays other than uint16 are gray levels [0, 255]; beyond that is an error, not a weaker force.
    np.testing.assert_array_equal(hf.tangible_forces(gray.astype(np.int64), XY, size=5), expected)
    with pytest.raises(ValueError, match=r"within \[0, 255"):
        hf.tangible_forces(gray.astype(np.int32) * 4, XY, size=5)
    with pytest.raises(ValueError, match=r"within \[0, 1"):
        hf.tangible_forces(gray.astype(float), XY, size=5, levels=1.0)


@pytest.mark.parametrize("levels", [0.0, -1.0, float("nan"), float("inf")])
def test_a_bad_white_level_is_refused(levels):
    with pytest.raises(ValueError, match="levels: "):
        hf.tangible_forces(picture(channels=1) / 255.0, XY, size=5, levels=levels)


def test_a_non_numeric_array_is_refused():
    with pytest.raises(TypeError, match="numeric array"):
        hf.tangible_forces(np.full((24, 40), "a"), XY, size=5)
    with pytest.raises(TypeError, match="numeric array"):
        hf.tangible_forces(np.ones((24, 40), complex), XY, size=5, levels=1.0)


@pytest.mark.parametrize("channels", [1, 3])
def test_a_uint16_array_equals_the_16_bit_png_of_the_same_data(tmp_path, channels):
    data = picture(np.uint16, channels)
    path = tmp_path / "deep.png"
    write_png(path, data)
    from_file = hf.tangible_forces(str(path), XY, size=5)
    np.testing.assert_array_equal(hf.tangible_forces(data, XY, size=5), from_file)
    fx, fy = hf.force_map(data, size=5)
    fx_file, fy_file = hf.force_map(str(path), size=5)
    np.testing.assert_array_equal(fx, fx_file)
    np.testing.assert_array_equal(fy, fy_file)
    # The same picture at 8 bits (levels x 257 at 16) gives the same forces.
    eight = picture(np.uint8, channels)
    np.testing.assert_allclose(hf.tangible_forces(eight.astype(np.uint16) * 257, XY, size=5),
                               hf.tangible_forces(eight, XY, size=5), rtol=0, atol=1e-12)


# --- servo traces -------------------------------------------------------------------

def scene():
    return hf.plane_contact([hf.tangible_field(picture(), size=5, workspace_mm=80.0)])


def test_the_trace_says_which_ticks_were_before_homing_and_arming():
    r = hf.run_servo(scene(), seconds=0.4, clock="virtual")
    t = r["trace"]
    homed, armed, force = t["homed"], t["armed"], t["force"]
    assert homed.dtype == bool and armed.dtype == bool and homed.shape == armed.shape == t["t"].shape
    assert not homed[0] and not armed[0]      # the simulated arm starts unhomed and disarmed
    assert armed[-1] and homed[-1]
    assert np.all(homed[armed])               # arming follows homing
    first = int(np.argmax(armed))
    assert 0 < first and np.all(armed[first:])  # armed once, for good (no latch on this run)
    assert r["statistics"]["latches"] == 0
    np.testing.assert_array_equal(force[~armed], 0.0)  # no force commanded before the arm was on
    assert np.max(np.linalg.norm(force[armed], axis=1)) > 0.5


def test_the_last_row_of_a_trace_is_its_own_tick_not_a_placeholder():
    # On the virtual clock a run is the same every time: the 300 ticks of a short run are the first
    # 300 of a longer one, whose row 299 was written while the loop still ran.
    short = hf.run_servo(scene(), seconds=0.3, clock="virtual")["trace"]
    long = hf.run_servo(scene(), seconds=0.4, clock="virtual")["trace"]
    assert len(short["t"]) == 300 and len(long["t"]) == 400
    for key in ("t", "position", "force", "homed", "armed"):
        np.testing.assert_array_equal(short[key], long[key][:300])
    assert np.linalg.norm(short["force"][-1]) > 0.5  # the hand still pressed: a real force


def read_trace(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return rows


@pytest.mark.skipif(not os.environ.get("HAPTICFIELD_SERVO_DEMO"), reason="servo_demo not built")
def test_servo_demo_traces_say_homed_and_armed_and_end_on_a_real_row(tmp_path):
    def run(seconds):
        out = tmp_path / f"trace_{seconds}.csv"
        r = subprocess.run([os.environ["HAPTICFIELD_SERVO_DEMO"], "--seconds", str(seconds), "--clock", "virtual",
                            "--trace", str(out)], capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        return read_trace(out)

    short, long = run(0.5), run(0.6)
    assert len(short) == 500 and len(long) == 600
    assert short == long[:500]  # the last row of the short run is what its tick commanded
    assert list(short[0])[-2:] == ["homed", "armed"]
    homed = [r["homed"] == "1" for r in long]
    armed = [r["armed"] == "1" for r in long]
    assert not homed[0] and not armed[0] and armed[-1]
    assert all(h for h, a in zip(homed, armed) if a)
    for r, a in zip(long, armed):
        if not a:
            assert float(r["fx_N"]) == float(r["fy_N"]) == float(r["fz_N"]) == 0.0
    assert max(abs(float(r["fz_N"])) for r in short[-50:]) > 0.0
