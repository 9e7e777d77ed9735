"""Fields shared between threads: a second thread is refused with a RuntimeError, the process never crashes.

A field keeps state (filters, samplers, a video's frame window) and is
evaluated by one thread at a time. Each check that could crash runs in a
child interpreter for a bounded time, so a crash is a failed test, not a
dead test run; it asserts only what holds however loaded the machine is.
"""
import json
import subprocess
import sys
import threading

import numpy as np
import pytest

import hapticfield as hf
from clips import write_clip

IN_USE = "in use by another thread"

# Three threads calling forces on one video field for 3 s (wall time), each through its own loop time.
THREE_THREADS = """
import json, sys, threading, time
import numpy as np
import hapticfield as hf
video = hf.video_field(sys.argv[1], workspace_mm=60.0, loop=True, size=5, border="clamp", denoise="none")
n = 50
p = np.column_stack([np.linspace(-0.03, 0.03, n), np.linspace(-0.02, 0.02, n), np.zeros(n)])
calls, refused, other = [0], [], []
def hammer():
    end, t = time.monotonic() + 3.0, 0.0
    while time.monotonic() < end:
        try:
            video.forces(p, start_time=t)
        except RuntimeError as e:
            (refused if "in use by another thread" in str(e) else other).append(str(e))
        t += n * 1e-3
        calls[0] += 1
threads = [threading.Thread(target=hammer) for _ in range(3)]
[t.start() for t in threads]
[t.join() for t in threads]
print(json.dumps({"calls": calls[0], "refused": len(refused), "other": other[:3]}))
"""

# run_servo on a scene holding a video field (wall clock) while this thread calls forces on the video.
BESIDE_THE_LOOP = """
import json, sys, threading, time
import numpy as np
import hapticfield as hf
video = hf.video_field(sys.argv[1], workspace_mm=60.0, loop=True, size=5, border="clamp", denoise="none")
token = hf.ServoStop()
runs = []
loop = threading.Thread(target=lambda: runs.append(hf.run_servo(hf.plane_contact([video]), seconds=3600.0,
                                                                  clock="wall", stop=token)))
loop.start()
while not token.running:
    time.sleep(0.001)
p = np.column_stack([np.linspace(-0.03, 0.03, 200), np.zeros(200), np.zeros(200)])
calls, refused, message = 0, 0, ""
end, t = time.monotonic() + 3.0, 0.0
while time.monotonic() < end:
    calls += 1
    try:
        video.forces(p, start_time=t)
    except RuntimeError as e:
        refused += 1
        message = str(e)
    t += 0.2
token.request()
loop.join()
after = video.forces(p)  # free again once the run is over
print(json.dumps({"calls": calls, "refused": refused, "message": message, "stop_reason": runs[0]["stop_reason"],
                  "after": float(np.abs(after).sum())}))
"""


def child(script, *args):
    r = subprocess.run([sys.executable, "-c", script, *map(str, args)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, (r.returncode, r.stderr[-2000:])  # -11: the process crashed
    return json.loads(r.stdout.strip().splitlines()[-1])


pytestmark_video = pytest.mark.skipif(not hf.has_video, reason="the module was built without OpenCV videoio")


@pytestmark_video
def test_three_threads_calling_forces_on_one_video_field_are_refused_not_crashed(tmp_path):
    r = child(THREE_THREADS, write_clip(tmp_path / "clip"))
    assert r["calls"] > 0 and r["other"] == [], r  # how many were refused depends on scheduling


@pytestmark_video
def test_forces_on_a_video_field_beside_a_running_loop_are_refused_not_crashed(tmp_path):
    r = child(BESIDE_THE_LOOP, write_clip(tmp_path / "clip"))
    assert r["calls"] > 0 and r["refused"] == r["calls"], r  # the loop held the video the whole time
    assert "build a second field" in r["message"] and r["stop_reason"] == "requested"


def test_a_field_in_use_refuses_every_other_use_until_the_run_ends(coffee):
    texture = hf.lattice_texture(noise="gaussian", sigma=0.5, gain=0.3)
    picture = hf.tangible_field(coffee, workspace_mm=80.0)
    scene = hf.plane_contact([texture, picture])
    token = hf.ServoStop()
    runs = []
    loop = threading.Thread(target=lambda: runs.append(hf.run_servo(scene, seconds=3600.0, clock="wall",
                                                                      stop=token)))
    loop.start()
    try:
        while not token.running and loop.is_alive():
            threading.Event().wait(0.001)
        p = np.zeros((4, 3))
        for use in (lambda: texture.forces(p), lambda: texture.force([0.0, 0.0, 0.0]), lambda: picture.reset(),
                    lambda: scene.forces(p), lambda: hf.sum([hf.zero(), texture]).forces(p),
                    lambda: hf.run_servo(hf.scale(picture, 2.0), seconds=0.01)):
            with pytest.raises(RuntimeError, match=IN_USE + ".*build a second field"):
                use()
        assert hf.lattice_texture(noise="gaussian", sigma=0.5).forces(p).shape == (4, 3)  # another field is free
    finally:
        token.request()
        loop.join()
    assert runs[0]["stop_reason"] == "requested"
    assert texture.forces(np.zeros((4, 3))).shape == (4, 3) and scene.forces(np.zeros((4, 3))).shape == (4, 3)


def test_a_field_made_of_one_part_twice_is_not_in_its_own_way():
    part = hf.lattice_texture(noise="gaussian", sigma=0.5, gain=0.3)
    twice = hf.sum([part, hf.scale(part, 2.0), part + part])
    assert twice.forces(np.zeros((3, 3))).shape == (3, 3)
    assert hf.run_servo(hf.plane_contact([twice, part]), seconds=0.05)["stop_reason"] == "tick_limit"
