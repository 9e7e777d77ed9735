"""Tangible video from Python against the tangible_video tool, still pictures and itself.

The clips are PNG sequences written by clips.py (lossless, so the gray levels
are known): a dark bar moving right on a light ground, then a cut to a light
disc on black.
"""
import os
import subprocess
import sys
import time

import numpy as np
import pytest

import hapticfield as hf
from clips import CUT, FPS, frame, write_clip, write_png

pytestmark = pytest.mark.skipif(not hf.has_video, reason="the module was built without OpenCV videoio")


@pytest.fixture
def clip(tmp_path):
    """A 16-frame PNG sequence with one cut at frame CUT; returns its printf pattern."""
    return write_clip(tmp_path / "clip")


PLAIN = dict(size=5, border="clamp", denoise="none")


# --- offline forces and cuts -------------------------------------------------------

@pytest.mark.skipif(not os.environ.get("HAPTICFIELD_TANGIBLE_VIDEO"), reason="tangible_video not built")
@pytest.mark.parametrize("options", [dict(size=5, border="clamp", denoise="none", fade=0.1),
                                     dict(mask="sobel", border="reflect", denoise="temporal", fade=0.04),
                                     dict(mask="prewitt", size=9, border="suspend", denoise="both", fade=0.0)])
def test_video_forces_equal_the_tangible_video_tool(tmp_path, clip, options):
    rng = np.random.default_rng(11)
    n = 600
    t = rng.uniform(0.0, 16 / FPS, n)  # unsorted on purpose
    t[:40] = np.round(t[:40] * FPS) / FPS  # frame times too
    xy = np.column_stack([rng.uniform(-3, 99, n), rng.uniform(-3, 67, n)])
    probes, forces, cuts = tmp_path / "probes.csv", tmp_path / "forces.csv", tmp_path / "cuts.csv"
    np.savetxt(probes, np.column_stack([t, xy]), delimiter=",", fmt="%.17g", header="t,x,y", comments="")
    args = [os.environ["HAPTICFIELD_TANGIBLE_VIDEO"], clip, "--probes", str(probes), "--forces", str(forces),
            "--cuts", str(cuts), "--fade-ms", repr(options["fade"] * 1e3)]
    for key in ("mask", "size", "border", "denoise"):
        if key in options:
            args += ["--" + key, str(options[key])]
    subprocess.run(args, check=True, capture_output=True)
    tool = np.loadtxt(forces, delimiter=",", skiprows=1)
    ours = hf.video_forces(clip, t, xy, **options)
    np.testing.assert_array_equal(tool[:, :3], np.column_stack([t, xy]))  # the tool kept the input order too
    np.testing.assert_array_equal(ours, tool[:, 3:])  # the same numbers, bit for bit
    assert np.count_nonzero(ours) > 30  # the probes met edges
    tool_cuts = np.loadtxt(cuts, delimiter=",", skiprows=1, ndmin=2)
    found = hf.video_cuts(clip)
    assert [c[0] for c in found] == [int(r[0]) for r in tool_cuts]
    np.testing.assert_allclose([c[1] for c in found], tool_cuts[:, 1], rtol=1e-8)


def test_video_cuts_find_the_written_cut(clip):
    assert hf.video_cuts(clip) == [(CUT, pytest.approx(CUT / FPS, abs=1e-12))]


def test_at_a_frame_time_the_force_is_that_frames_still_picture_force(clip):
    xy = np.array([[x, y] for x in np.arange(14.0, 60.0, 0.75) for y in (20.0, 31.5, 50.0)])
    for k in (3, 5, 12):  # past the fade-in of the first frame and of the cut
        t = np.full(len(xy), k / FPS)
        video = hf.video_forces(clip, t, xy, **PLAIN)
        still = hf.tangible_forces(frame(k), xy, size=5, border="clamp", levels=255.0)
        np.testing.assert_allclose(video, still, atol=1e-6)  # the frame's gray levels went through float32
        assert np.max(np.abs(still)) > 0.5


def test_between_frames_the_force_blends_linearly(clip):
    xy = np.array([[x, 32.0] for x in np.arange(18.0, 40.0, 0.5)])
    k, w = 4, 0.25
    a = hf.video_forces(clip, np.full(len(xy), k / FPS), xy, **PLAIN)
    b = hf.video_forces(clip, np.full(len(xy), (k + 1) / FPS), xy, **PLAIN)
    mid = hf.video_forces(clip, np.full(len(xy), (k + w) / FPS), xy, **PLAIN)
    np.testing.assert_allclose(mid, (1 - w) * a + w * b, atol=1e-9)


# --- the live field ------------------------------------------------------------------

def test_video_field_properties_and_composition(clip):
    video = hf.video_field(clip, workspace_mm=60.0, **PLAIN)
    assert (video.width, video.height, video.fps) == (96, 64, FPS)
    assert video.duration == pytest.approx(16 / FPS)
    assert isinstance(video, hf.Field) and "video" in video.description
    scene = hf.plane_contact([video, hf.friction(coulomb=0.2)])
    assert "video" in scene.description
    assert video.error() == ""


def test_playback_controls_move_the_video_time(clip):
    video = hf.video_field(clip, **PLAIN)
    p = np.zeros((1, 3))

    def video_time_at(loop_time):
        video.forces(p, start_time=loop_time)
        return video.statistics()["video_time_s"]

    assert video_time_at(10.0) == pytest.approx(0.0)  # the first tick anchors loop time to the start
    assert video_time_at(10.2) == pytest.approx(0.2)
    video.pause()
    assert video_time_at(10.4) == pytest.approx(0.2)
    video.resume()  # a change of state applies from the next tick on
    assert video_time_at(10.5) == pytest.approx(0.2)
    assert video_time_at(10.6) == pytest.approx(0.3)
    video.set_rate(2.0)
    assert video_time_at(10.7) == pytest.approx(0.3)
    assert video_time_at(10.8) == pytest.approx(0.5)  # two video seconds a loop second
    video.seek(0.1)
    assert video_time_at(10.9) == pytest.approx(0.1)


def test_run_servo_on_a_video_field_gives_forces_and_statistics(clip):
    video = hf.video_field(clip, workspace_mm=60.0, gain=1.0, loop=True, **PLAIN)
    scene = hf.plane_contact([video], stiffness=1500.0)
    # The virtual clock (the simulated arm's default), the video in lockstep: every tick waits for its frame.
    result = hf.run_servo(scene, seconds=0.6, rate=1000.0, hand="raster", hand_size=0.02)
    assert result["statistics"]["ticks"] == 600
    tangential = np.linalg.norm(result["trace"]["force"][:, :2], axis=1)
    assert np.max(tangential) > 0.05  # the video's edges were felt [N]
    s = video.statistics()
    assert s["prepared"] >= 15 and s["published"] >= 14 and s["dropped"] == 0  # every frame of 0.6 s came
    assert s["stale_ticks"] == 0  # in lockstep no tick feels a window late past its hold
    assert 0.59 < s["video_time_s"] < 0.6  # the last tick's
    assert video.error() == "" and not video.lockstep  # lockstep for the run only
    video.stop()


def test_a_virtual_run_on_a_video_field_renders_the_same_forces_every_time(clip):
    def scene(video):
        return hf.plane_contact([video, hf.friction(coulomb=0.2)], stiffness=1500.0)

    first_video = hf.video_field(clip, workspace_mm=60.0, gain=1.0, **PLAIN)
    runs = [hf.run_servo(scene(first_video), seconds=0.7, hand="circle", hand_size=0.03),  # past the cut
            hf.run_servo(scene(hf.video_field(clip, workspace_mm=60.0, gain=1.0, **PLAIN)), seconds=0.7,
                         hand="circle", hand_size=0.03),
            hf.run_servo(scene(first_video), seconds=0.7, hand="circle", hand_size=0.03)]  # the same field again
    for other in runs[1:]:
        np.testing.assert_array_equal(runs[0]["trace"]["force"], other["trace"]["force"])
    assert np.max(np.linalg.norm(runs[0]["trace"]["force"][:, :2], axis=1)) > 0.05
    assert first_video.statistics()["dropped"] == 0


def test_a_clip_smaller_than_the_mask_is_refused_when_the_field_is_made(tmp_path):
    # The first frame's size is checked before the worker starts (it used to
    # start, stop on its error and leave a field that gave zero force).
    d = tmp_path / "tiny"
    d.mkdir()
    for k in range(3):
        write_png(d / f"{k:04d}.png", np.full((6, 6), 100.0))
    with pytest.raises(ValueError, match="smaller than the 17 x 17 mask"):
        hf.video_field(str(d / "%04d.png"), size=17)


# --- bad input ------------------------------------------------------------------------

@pytest.mark.parametrize("call,error,message", [
    (lambda c: hf.video_forces("/no/such.mp4", [0.0], [[0.0, 0.0]]), hf.FileError, "no such file"),
    (lambda c: hf.video_field("/no/such.mp4"), OSError, "no such file"),
    (lambda c: hf.video_cuts("/no/such.mp4"), hf.FileError, "no such file"),
    (lambda c: hf.video_forces(c, [0.0, 0.1], [[0.0, 0.0]]), ValueError, "as many rows"),
    (lambda c: hf.video_forces(c, [[0.0]], [[0.0, 0.0]]), ValueError, "1-D"),
    (lambda c: hf.video_forces(c, [-0.1], [[0.0, 0.0]]), ValueError, "video times"),
    (lambda c: hf.video_forces(c, [np.nan], [[0.0, 0.0]]), ValueError, "video times"),
    (lambda c: hf.video_forces(c, [0.0], [[0.0, 0.0]], mask="box"), ValueError, "unknown 'box'"),
    (lambda c: hf.video_forces(c, [0.0], [[0.0, 0.0]], size=4), ValueError, "size 4 px"),
    (lambda c: hf.video_forces(c, [0.0], [[0.0, 0.0]], denoise="median"), ValueError, "unknown 'median'"),
    (lambda c: hf.video_forces(c, [0.0], [[0.0, 0.0]], fade=20.0), ValueError, "fade"),
    (lambda c: hf.video_field(c, rate=0.0), ValueError, "rate"),
    (lambda c: hf.video_field(c, rate=17.0), ValueError, "rate"),
    (lambda c: hf.video_field(c, start=-1.0), ValueError, "start"),
    (lambda c: hf.video_field(c, gain=-1.0), ValueError, "gain"),
    (lambda c: hf.video_field(c, fade=-0.1), ValueError, "fade"),
    (lambda c: hf.video_field(c, px_per_mm=2.0, workspace_mm=50.0), ValueError, "not both"),
    (lambda c: hf.video_field(c, px_per_mm=0.0), ValueError, "px_per_mm"),
    (lambda c: hf.video_field(c).set_rate(0.0), ValueError, "rate"),
    (lambda c: hf.video_field(c).seek(float("nan")), ValueError, "seek"),
])
def test_bad_video_input_raises_with_the_library_message(clip, call, error, message):
    with pytest.raises(error, match=message):
        call(clip)


def test_a_file_that_is_not_a_video(tmp_path):
    bad = tmp_path / "notes.mp4"
    bad.write_text("not a video\n" * 100)
    with pytest.raises(hf.FileError, match="cannot decode"):
        hf.video_field(str(bad))
    with pytest.raises(OSError):
        hf.video_forces(str(bad), [0.0], [[0.0, 0.0]])


# --- FFmpeg's own log lines ------------------------------------------------------

OPENCV_DOC = "/usr/share/doc/opencv-doc/examples/data"

# Opens each clip with the three video calls; prints nothing itself on stderr.
OPEN_CLIPS = """
import sys, time
import numpy as np
import hapticfield as hf
for path in sys.argv[1:]:
    for call in (lambda: hf.video_cuts(path),
                 lambda: hf.video_forces(path, np.linspace(0.0, 3.0, 40), np.full((40, 2), 30.0), size=5),
                 lambda: hf.video_field(path, size=5).forces(np.zeros((2000, 3)))):
        try:
            call()
        except (hf.Error, ValueError) as e:
            print("raised:", e)
"""


def damaged_copy(source, target, seed):
    """source with 5000 bytes past its headers overwritten at random: decoder errors on most frames."""
    data = bytearray(open(source, "rb").read())
    rng = np.random.default_rng(seed)
    for k in rng.integers(10000, len(data), 5000):
        data[k] = rng.integers(0, 256)
    target.write_bytes(bytes(data))
    return str(target)


@pytest.mark.skipif(not os.path.exists(OPENCV_DOC + "/Megamind_bugy.avi"), reason="opencv-doc's clips not installed")
def test_damaged_and_odd_clips_leave_stderr_free_of_ffmpeg_lines(tmp_path):
    clips = [OPENCV_DOC + "/Megamind_bugy.avi",                                      # damaged as shipped
             damaged_copy(OPENCV_DOC + "/Megamind_bugy.avi", tmp_path / "damaged.avi", 5),
             damaged_copy(OPENCV_DOC + "/Megamind.avi", tmp_path / "damaged2.avi", 7)]
    (tmp_path / "truncated.avi").write_bytes(open(OPENCV_DOC + "/Megamind.avi", "rb").read()[:3000])
    (tmp_path / "text.avi").write_text("not a video\n")
    clips += [str(tmp_path / "truncated.avi"), str(tmp_path / "text.avi")]
    env = {k: v for k, v in os.environ.items() if not k.startswith("OPENCV_")}  # the defaults, as a user has them
    r = subprocess.run([sys.executable, "-c", OPEN_CLIPS, *clips], capture_output=True, text=True, env=env,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.count("raised:") >= 6  # the truncated and the text file were refused, with our message
    assert r.stderr == "", r.stderr[:2000]  # no "[mpeg4 @ 0x...] ac-tex damaged" and the like
