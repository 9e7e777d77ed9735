"""hapticfield.batch: a corpus of pictures made into force maps, reliefs and normals, on Dask or in a loop.

The serial loop is the oracle: a two-worker LocalCluster writes the same bytes. A second run skips what is
there and complete and makes what is missing or cut short; a corrupt picture fails alone; a run stopped in the
middle of a write leaves no output. relief_map, the call behind reliefs and normals, is checked against its
closed form on random pictures."""
import io
import os
import pathlib
import random
import shutil
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest

import hapticfield as hf
import hapticfield.batch as hb
from conftest import SOURCE

OPENCV_SAMPLES = pathlib.Path("/usr/share/doc/opencv-doc/examples/data")


def write_png(path, pixels):
    """An 8-bit gray (H x W) or RGB (H x W x 3) PNG, with zlib alone."""
    pixels = np.asarray(pixels, dtype=np.uint8)
    h, w = pixels.shape[:2]
    colour = 2 if pixels.ndim == 3 else 0
    raw = b"".join(b"\x00" + pixels[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) +
                     chunk(b"IEND", b""))


@pytest.fixture
def pictures(tmp_path):
    """A folder of real pictures (coffee.png, a few OpenCV samples when opencv-doc is installed) and generated
    ones (gray and colour, one in a subfolder)."""
    folder = tmp_path / "pictures"
    folder.mkdir()
    shutil.copy(SOURCE / "examples" / "data" / "coffee.png", folder / "coffee.png")
    for name in ("HappyFish.jpg", "LinuxLogo.jpg", "pic1.png", "blox.jpg"):
        if (OPENCV_SAMPLES / name).is_file():
            shutil.copy(OPENCV_SAMPLES / name, folder / name)
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:60, 0:80]
    write_png(folder / "rings.png", 127.5 + 127.5 * np.sin(np.hypot(x - 40, y - 30) / 3))
    write_png(folder / "noise.png", rng.integers(0, 256, (50, 70, 3)))
    (folder / "more").mkdir()
    write_png(folder / "more" / "steps.png", (x // 10 * 30) % 256)
    return folder


def dask():
    pytest.importorskip("distributed", reason="Dask's distributed is not installed (Debian: python3-distributed)")


def outputs(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


JOBS = [hb.force_map(), hb.relief(mm_per_level=0.02, blur=1.0), hb.normals(mm_per_level=0.02, blur=1.0),
        hb.force_map(mask="sobel", name="sobel")]


def test_a_two_worker_cluster_writes_the_bytes_the_serial_loop_writes(pictures, tmp_path):
    dask()
    serial = hb.run(pictures, JOBS, tmp_path / "serial", pattern="**/*", scheduler="serial", progress=False)
    bar = io.StringIO()
    cluster = hb.run(pictures, JOBS, tmp_path / "cluster", pattern="**/*", workers=2, progress=bar)
    assert serial.ok and cluster.ok, (serial.failed, cluster.failed)
    assert serial.inputs == cluster.inputs >= 4 and len(serial.written) == len(JOBS) * serial.inputs
    expected, got = outputs(tmp_path / "serial"), outputs(tmp_path / "cluster")
    assert sorted(expected) == sorted(got) and "more/steps.png.sobel.npy" in got
    assert [name for name in expected if expected[name] != got[name]] == []
    assert bar.getvalue().endswith(f"batch: {serial.inputs}/{serial.inputs} inputs, 0 failed\n"), bar.getvalue()


def test_the_outputs_are_what_the_library_calls_return(pictures, tmp_path):
    hb.run(pictures / "coffee.png", JOBS, tmp_path, scheduler="serial", progress=False)
    fx, fy = hf.force_map(str(pictures / "coffee.png"))
    force = np.load(tmp_path / "coffee.png.force_map.npy")
    assert force.dtype == np.float32 and np.array_equal(force, np.stack([fx, fy], axis=-1))
    sobel = np.load(tmp_path / "coffee.png.sobel.npy")
    assert np.array_equal(sobel[..., 0], hf.force_map(str(pictures / "coffee.png"), mask="sobel")[0])
    heights, normal = hf.relief_map(str(pictures / "coffee.png"), mm_per_level=0.02, blur=1.0)
    assert np.array_equal(np.load(tmp_path / "coffee.png.relief.npy"), heights)
    assert np.array_equal(np.load(tmp_path / "coffee.png.normals.npy"), normal)
    assert heights.shape == fx.shape and normal.shape == fx.shape + (3,)


def test_a_second_run_makes_only_what_is_missing_or_cut_short(pictures, tmp_path):
    dask()
    out = tmp_path / "out"
    first = hb.run(pictures, JOBS, out, scheduler="serial", progress=False)
    oracle = outputs(out)
    again = hb.run(pictures, JOBS, out, workers=2, progress=False)
    assert again.written == [] and len(again.skipped) == len(first.written) and again.ok
    # an output removed, one cut short (as by a full disk), and a temporary file left by a killed run
    removed, cut = out / "rings.png.relief.npy", out / "noise.png.force_map.npy"
    removed.unlink()
    cut.write_bytes(cut.read_bytes()[:-5])
    (out / ".coffee.png.normals.npy.0123.part").write_bytes(b"\x93NUMPY half")
    third = hb.run(pictures, JOBS, out, workers=2, progress=False)
    assert third.written == sorted([cut, removed]) and len(third.skipped) == len(first.written) - 2
    assert outputs(out) == oracle  # the same bytes, and the stale temporary file is gone


def test_a_corrupt_picture_is_reported_and_the_rest_is_made(pictures, tmp_path):
    dask()
    (pictures / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n" + os.urandom(200))
    good = (pictures / "coffee.png").read_bytes()
    (pictures / "cut.jpg").write_bytes(b"\xff\xd8\xff" + good[3:40])
    write_png(pictures / "tiny.png", [[10]])  # 1 x 1 px: no relief (it needs 2 x 2)
    for scheduler in ("serial", None):
        out = tmp_path / str(scheduler)
        report = hb.run(pictures, [hb.force_map(), hb.relief()], out, scheduler=scheduler, progress=False)
        failed = {(f.input.name, f.job) for f in report.failed}
        assert failed >= {("broken.png", "force_map"), ("broken.png", "relief"), ("cut.jpg", "force_map"),
                          ("cut.jpg", "relief"), ("tiny.png", "relief")}, report.failed
        assert all("Error" in f.message and "\n" not in f.message for f in report.failed)
        assert (out / "coffee.png.relief.npy").is_file() and (out / "rings.png.force_map.npy").is_file()
        assert not list(out.glob("broken*")) and not list(out.glob(".*.part"))
        assert len(report.written) + len(report.failed) == 2 * report.inputs


def test_a_write_stopped_halfway_leaves_no_output(pictures, tmp_path, monkeypatch):
    real = np.lib.format.write_array

    def stops_halfway(f, array, **kwargs):
        f.write(b"\x93NUMPY")
        raise KeyboardInterrupt  # as a kill would, mid-file

    monkeypatch.setattr(np.lib.format, "write_array", stops_halfway)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        hb.run(pictures / "coffee.png", hb.force_map(), out, scheduler="serial", progress=False)
    assert list(out.iterdir()) == []
    monkeypatch.setattr(np.lib.format, "write_array", real)
    assert len(hb.run(pictures / "coffee.png", hb.force_map(), out, scheduler="serial").written) == 1


def test_inputs_as_a_list_and_what_is_refused(pictures, tmp_path):
    files = [pictures / "rings.png", str(pictures / "more" / "steps.png"), pictures / "missing.png"]
    report = hb.run(files, hb.relief(), tmp_path, scheduler="serial", progress=False)
    assert [p.name for p in report.written] == ["rings.png.relief.npy", "steps.png.relief.npy"]
    assert [(f.input.name, f.job) for f in report.failed] == [("missing.png", "relief")]
    assert "FileError" in report.failed[0].message
    with pytest.raises(ValueError, match="same outputs"):
        hb.corpus([pictures / "rings.png", tmp_path / "rings.png"])
    with pytest.raises(FileNotFoundError):
        hb.run(tmp_path / "nowhere", hb.relief(), tmp_path, scheduler="serial")
    with pytest.raises(ValueError, match="mask"):
        hb.force_map(mask="nonsense")
    with pytest.raises(ValueError, match="mm_per_level"):
        hb.relief(mm_per_level=-1.0)
    with pytest.raises(ValueError, match="same outputs"):
        hb.run(pictures, [hb.force_map(), hb.force_map(mask="sobel")], tmp_path, scheduler="serial")
    with pytest.raises(ValueError, match="scheduler"):
        hb.run(pictures, hb.force_map(), tmp_path, scheduler=3)


def test_relief_map_is_the_closed_form_of_its_picture():
    seed = random.randrange(1 << 32)
    rng = np.random.default_rng(seed)
    for _ in range(50):
        h, w = rng.integers(2, 40, 2)
        gray = rng.integers(0, 256, (h, w)).astype(np.uint8)
        pixel, mm = float(rng.uniform(1e-5, 1e-3)), float(rng.uniform(1e-3, 0.1))
        dark = bool(rng.integers(0, 2))
        heights, normal = hf.relief_map(gray, pixel_size=pixel, mm_per_level=mm, dark_is_high=dark)
        levels = 255.0 - gray if dark else gray.astype(float)
        expected = levels * mm * 1e-3
        assert np.allclose(heights, expected, rtol=1e-12, atol=1e-15), f"seed {seed}"
        # central differences (one-sided at the border), y up the picture: rows run down it
        hx = np.gradient(expected, pixel, axis=1) if w > 1 else np.zeros_like(expected)
        hy = -np.gradient(expected, pixel, axis=0)
        n = np.stack([-hx, -hy, np.ones_like(hx)], axis=-1)
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        assert np.allclose(normal, n, atol=1e-12), f"seed {seed}"


def run_cli(*args, cwd):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    return subprocess.run([sys.executable, "-m", "hapticfield.batch", *map(str, args)], capture_output=True,
                          text=True, timeout=300, cwd=cwd, env=env)


def test_the_command_line_as_a_user_runs_it(pictures, tmp_path):
    r = run_cli("--help", cwd=tmp_path)
    assert r.returncode == 0 and r.stdout.startswith("usage: python3 -m hapticfield.batch") and r.stderr == ""
    (pictures / "broken.png").write_bytes(b"not a picture")
    r = run_cli(pictures, "--out", tmp_path / "out", "--job", "relief:mm_per_level=0.02,blur=1", "--job", "force_map",
                "--scheduler", "serial", cwd=tmp_path)
    assert r.returncode == 1 and "batch: " + str(pictures / "broken.png") + ": relief: FileError" in r.stderr, r.stderr
    oracle = hb.run(pictures, [hb.relief(mm_per_level=0.02, blur=1.0), hb.force_map()], tmp_path / "oracle",
                    scheduler="serial", progress=False)
    assert outputs(tmp_path / "out") == outputs(tmp_path / "oracle") and len(oracle.failed) == 2
    for bad, status in ((["--job", "shine"], 2), (["--workers", "x"], 2), (["--job", "relief:blur"], 2),
                        (["--job", "force_map:mask=nonsense"], 1), ([], 2)):
        r = run_cli(pictures, "--out", tmp_path / "bad", *bad, cwd=tmp_path) if bad else run_cli(cwd=tmp_path)
        assert r.returncode == status and r.stderr.count("\n") == 1 and r.stderr.startswith("batch: "), (bad, r.stderr)
    r = run_cli(tmp_path / "nowhere", "--out", tmp_path / "bad", "--scheduler", "serial", cwd=tmp_path)
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and "no such folder" in r.stderr, r.stderr
