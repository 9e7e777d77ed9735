"""The hapticfield module against the C++ tools, closed forms and itself."""
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import hapticfield as hf


def step_edge(width=40, height=30, edge=20):
    """White (255) left of column `edge`, black (0) from it on [gray levels, uint8]."""
    image = np.full((height, width), 255, np.uint8)
    image[:, edge:] = 0
    return image


# --- tangible images -----------------------------------------------------------

@pytest.mark.skipif(not os.environ.get("HAPTICFIELD_TANGIBLE_IMAGE"), reason="tangible_image not built")
@pytest.mark.parametrize("mask,size,border", [("prewitt", 17, "suspend"), ("sobel", 3, "clamp"),
                                              ("gauss", 9, "reflect"), ("emboss", 21, "fade")])
def test_tangible_forces_equal_the_tangible_image_tool(tmp_path, coffee, mask, size, border):
    rng = np.random.default_rng(7)
    xy = np.column_stack([rng.uniform(-5, 260, 400), rng.uniform(-5, 200, 400)])
    xy[:50] = np.round(xy[:50])  # pixel centres too
    probes, forces = tmp_path / "probes.csv", tmp_path / "forces.csv"
    np.savetxt(probes, xy, delimiter=",", fmt="%.17g", header="x,y", comments="")
    subprocess.run([os.environ["HAPTICFIELD_TANGIBLE_IMAGE"], coffee, "--mask", mask, "--size", str(size),
                    "--border", border, "--probes", str(probes), "--forces", str(forces)],
                   check=True, capture_output=True)
    tool = np.loadtxt(forces, delimiter=",", skiprows=1)
    ours = hf.tangible_forces(coffee, xy, mask=mask, size=size, border=border)
    np.testing.assert_array_equal(tool[:, :2], xy)
    np.testing.assert_array_equal(ours, tool[:, 2:])  # the same numbers, bit for bit


def test_a_black_white_edge_gives_unit_force_toward_the_dark_side():
    image = step_edge()
    xs = np.linspace(15, 25, 201)
    f = hf.tangible_forces(image, np.column_stack([xs, np.full_like(xs, 15.0)]))
    assert np.max(f[:, 0]) == pytest.approx(1.0, abs=1e-9)  # the paper's normalisation
    assert np.all(f[:, 0] >= 0.0)                           # toward the black side (+x)
    np.testing.assert_allclose(f[:, 1], 0.0, atol=1e-12)    # no force along the edge
    far = hf.tangible_forces(image, np.array([[10.0, 15.0], [30.0, 15.0]]), size=5)
    np.testing.assert_allclose(far, 0.0, atol=1e-12)        # flat regions: no force


def test_arrays_and_paths_agree_and_rgb_uses_the_paper_weights():
    gray = step_edge()
    rgb = np.stack([gray, gray, gray], axis=2).astype(np.uint8)
    xy = np.array([[19.5, 10.0], [20.0, 12.0]])
    np.testing.assert_array_equal(hf.tangible_forces(gray, xy), hf.tangible_forces(rgb, xy))
    red = np.zeros((30, 40, 3), np.uint8)
    red[:, :20, 0] = 255  # only the red channel: gray 0.3 x 255 on the left
    f = hf.tangible_forces(red, np.array([[19.5, 15.0]]), size=3)
    assert f[0, 0] == pytest.approx(0.3, abs=1e-12)


def test_force_map_equals_tangible_forces_at_pixel_centres(coffee):
    for mask, size in [("prewitt", 17), ("sobel", 3)]:
        fx, fy = hf.force_map(coffee, mask=mask, size=size)
        h, w = fx.shape
        ys, xs = np.mgrid[0:h:7, 0:w:5]
        xy = np.column_stack([xs.ravel(), ys.ravel()]).astype(float)
        f = hf.tangible_forces(coffee, xy, mask=mask, size=size)
        np.testing.assert_allclose(fx[ys, xs].ravel(), f[:, 0], atol=1e-5)  # float32 map
        np.testing.assert_allclose(fy[ys, xs].ravel(), f[:, 1], atol=1e-5)


def test_tangible_field_maps_the_picture_into_the_device_plane():
    image = step_edge(64, 64, 32)
    field = hf.tangible_field(image, gain=2.0, px_per_mm=10.0)
    # The picture is centred: pixel x = 31.5 (the edge) is at device x = 0; device y up.
    f = field.force([0.0, 0.0, 0.0])
    assert f[0] == pytest.approx(2.0, rel=1e-9) and abs(f[1]) < 1e-12 and f[2] == 0.0
    assert np.all(field.force([0.01, 0.0, 0.0]) == 0.0)  # 100 px right: outside the picture, suspended


# --- evaluating fields over arrays -------------------------------------------------

def make_scene():
    return hf.plane_contact([hf.lattice_texture(noise="gaussian", sigma=0.5, seed=3, gain=0.3,
                                                scale_with_normal_force=True, axes=(1, 1, 0)),
                             hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)],
                            stiffness=1500.0, damping=2.0)


def stroke(n=2000, speed=0.05, depth=1e-3, rate=1000.0):
    t = np.arange(n) / rate
    positions = np.column_stack([-0.05 + speed * t, np.full(n, 0.002), np.full(n, -depth)])
    velocities = np.tile([speed, 0.0, 0.0], (n, 1))
    return positions, velocities


def test_vectorised_forces_equal_one_probe_at_a_time():
    positions, velocities = stroke(500)
    batch = make_scene().forces(positions, velocities)
    one = make_scene()
    single = np.array([one.force(p, v) for p, v in zip(positions, velocities)])
    np.testing.assert_array_equal(batch, single)


def test_a_single_stateless_part_copied_into_the_contact_gives_the_shared_parts_forces():
    positions, velocities = stroke(800)
    positions[::7, 2] = 0.001  # some probes off the plane
    friction = hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)
    light = hf.plane_contact([friction], stiffness=1500.0, damping=2.0)  # friction copied in, evaluated inline
    shared = hf.plane_contact([friction, hf.zero()], stiffness=1500.0, damping=2.0)  # through the shared part
    batch = light.forces(positions, velocities)
    np.testing.assert_array_equal(batch, shared.forces(positions, velocities))
    np.testing.assert_array_equal(batch, np.array([light.force(p, v) for p, v in zip(positions, velocities)]))
    assert np.count_nonzero(batch[:, 0]) > 600


def test_forces_write_into_a_given_array():
    positions, velocities = stroke(300)
    out = np.full((300, 3), np.nan)
    result = make_scene().forces(positions, velocities, out=out)
    assert np.shares_memory(result, out)
    np.testing.assert_array_equal(out, make_scene().forces(positions, velocities))
    with pytest.raises(ValueError, match="out"):
        make_scene().forces(positions, velocities, out=np.zeros((300, 3), dtype=np.float32))


def test_contact_is_fc_plus_texture_plus_friction_in_closed_form():
    k, depth, speed, mu, b = 1500.0, 1e-3, 0.05, 0.4, 0.5
    plane = hf.plane_contact(stiffness=k)
    f = plane.force([0.0, 0.0, -depth], [speed, 0.0, 0.0])
    np.testing.assert_allclose(f, [0.0, 0.0, k * depth], rtol=1e-12)  # Fc = k d n
    friction = hf.plane_contact([hf.friction(coulomb=mu, viscous=b, scale_with_normal_force=True)], stiffness=k)
    f = friction.force([0.0, 0.0, -depth], [speed, 0.0, 0.0])
    u0 = 2e-3  # the default smoothing speed [m/s]
    expected = -(mu * k * depth * speed / math.hypot(speed, u0) + b * speed)
    assert f[0] == pytest.approx(expected, rel=1e-12)
    assert np.all(plane.force([0.0, 0.0, 0.001]) == 0.0)  # free space: nothing
    sphere = hf.sphere_contact(centre=(0, 0, 0), radius=0.02, stiffness=1000.0)
    np.testing.assert_allclose(sphere.force([0.0, 0.019, 0.0]), [0.0, 1.0, 0.0], rtol=1e-9)


def test_sum_scale_and_clamp():
    a = hf.plane_contact(stiffness=1000.0)
    p = [0.0, 0.0, -0.002]
    np.testing.assert_allclose((a + a).force(p), [0.0, 0.0, 4.0])
    np.testing.assert_allclose(hf.scale(a, 0.5).force(p), [0.0, 0.0, 1.0])
    np.testing.assert_allclose(hf.clamp(a, 1.5).force(p), [0.0, 0.0, 1.5])
    np.testing.assert_allclose(hf.sum([a, a, a]).force(p), [0.0, 0.0, 6.0])


def test_textures_are_repeatable_and_seeded():
    positions, velocities = stroke(1000)
    one = make_scene().forces(positions, velocities)
    again = make_scene().forces(positions, velocities)
    np.testing.assert_array_equal(one, again)
    other = hf.plane_contact([hf.lattice_texture(sigma=0.5, seed=4, gain=0.3, scale_with_normal_force=True,
                                                 axes=(1, 1, 0))]).forces(positions, velocities)
    assert np.max(np.abs(one[:, 1] - other[:, 1])) > 0.01
    assert np.all(np.isfinite(one))


def test_stateful_fields_reset():
    tex = hf.temporal_texture(sigma=1.0, seed=5, order=4, band="band_pass", f1=30, f2=120)
    positions, velocities = stroke(300)
    first = tex.forces(positions, velocities)
    tex.reset()
    np.testing.assert_array_equal(tex.forces(positions, velocities), first)


def test_fbm_and_local_sphere_build_and_give_finite_forces():
    positions, velocities = stroke(400)
    for tex in [hf.lattice_texture(octaves=5, h=0.5, grain=(4e-3, 4e-3, 4e-3)),
                hf.lattice_texture(noise="laplacian", dim=3, interpolation="cubic"),
                hf.local_sphere_texture(noise="uniform", radius=5e-4)]:
        f = tex.forces(positions, velocities)
        assert np.all(np.isfinite(f)) and np.std(f[:, 0]) > 0.0


# --- signals ---------------------------------------------------------------------

def test_butterworth_is_3_db_down_at_its_cutoff():
    rate, fc = 1000.0, 100.0
    t = np.arange(4000) / rate
    for order in (2, 4, 6):
        y = hf.butterworth(np.sin(2 * np.pi * fc * t), order=order, band="low_pass", f1=fc, rate=rate)
        amplitude = np.sqrt(2.0 * np.mean(y[2000:] ** 2))
        assert amplitude == pytest.approx(1 / math.sqrt(2), rel=2e-3)
    y = hf.butterworth(np.sin(2 * np.pi * 60.0 * t), order=4, band="band_pass", f1=30, f2=120, rate=rate)
    assert np.sqrt(2.0 * np.mean(y[2000:] ** 2)) == pytest.approx(1.0, abs=0.05)


def test_fir_low_pass_passes_dc_and_stops_high_frequencies():
    y = hf.fir_low_pass(np.ones(200), cutoff=60.0)
    assert y[-1] == pytest.approx(1.0, abs=2e-3)
    t = np.arange(2000) / 1000.0
    z = hf.fir_low_pass(np.sin(2 * np.pi * 300.0 * t), cutoff=60.0)
    assert np.max(np.abs(z[100:])) < 0.01


def test_noise_moments_and_repeatability():
    g = hf.noise("gaussian", sigma=2.0, seed=9, n=200000)
    assert np.mean(g) == pytest.approx(0.0, abs=0.02) and np.std(g) == pytest.approx(2.0, rel=0.01)
    np.testing.assert_array_equal(g, hf.noise("gaussian", sigma=2.0, seed=9, n=200000))
    u = hf.noise("uniform", sigma=1.0, seed=9, n=200000)
    assert np.max(np.abs(u)) <= math.sqrt(3.0) and np.std(u) == pytest.approx(1.0, rel=0.01)


def test_hatt_models_synthesise_vibration(hatt_dir):
    path = str(hatt_dir / "Models_Toolkit 1kHz ARMA.xml")
    info = hf.hatt_model(path)
    assert info["models"] > 0 and info["sample_rate"] > 0
    field = hf.plane_contact([hf.hatt_texture(path, friction=False)], stiffness=1000.0)
    positions, velocities = stroke(2000)
    f = field.forces(positions, velocities)
    vibration = f[:, 2] - 1000.0 * 1e-3  # remove Fc = k d [N]
    assert np.all(np.isfinite(f)) and np.std(vibration[200:]) > 1e-4


# --- normals from a picture ---------------------------------------------------

def rotation(yaw, pitch):
    cy, sy, cp, sp = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rx = np.array([[1, 0, 0], [0, cp, -sp], [0, sp, cp]])
    return ry @ rx


def test_estimate_normal_recovers_a_known_rotation():
    K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
    R = rotation(0.4, -0.3)
    t = np.array([-40.0, -25.0, 500.0])  # [mm]
    W, H = 80.0, 50.0
    plane = np.array([[0, 0], [W, 0], [W, H], [0, H]], dtype=float)
    cam = (R @ np.column_stack([plane, np.zeros(4)]).T).T + t
    pixels = (K @ cam.T).T
    pixels = pixels[:, :2] / pixels[:, 2:]
    pose = hf.estimate_normal(pixels, K, size=(W, H))
    n = R[:, 2] if R[:, 2] @ (R @ [W / 2, H / 2, 0] + t) < 0 else -R[:, 2]  # toward the camera
    np.testing.assert_allclose(pose["normal"], n, atol=1e-6)
    assert pose["rms_reprojection_px"] < 1e-6
    same = hf.estimate_plane_normal(plane, pixels, K)
    np.testing.assert_allclose(same["normal"], n, atol=1e-6)


def test_normal_field_gradient_mode_pushes_downhill():
    n = np.array([0.6, 0.0, -0.8])
    field = hf.normal_field(100, 100, [(np.array([[0, 0], [99, 0], [99, 99], [0, 99]], float), n)],
                            mode="gradient", max_force=0.5)
    f = field.force([0.0, 0.0, 0.0])
    assert math.hypot(f[0], f[1]) == pytest.approx(0.5 * 0.6, rel=1e-9)


# --- the servo loop -------------------------------------------------------------

@pytest.mark.parametrize("clock", ["virtual", "wall"])
def test_run_servo_on_the_simulated_arm(coffee, clock):
    # Only what holds however loaded the machine is: the tick count, the shapes, the force limit.
    field = hf.plane_contact([hf.tangible_field(coffee, workspace_mm=80.0)])
    result = hf.run_servo(field, seconds=0.3, rate=1000.0, clock=clock)
    stats, trace = result["statistics"], result["trace"]
    assert stats["ticks"] == 300 and result["stop_reason"] == "tick_limit"
    assert trace["t"].shape == (300,) and trace["position"].shape == (300, 3) and trace["force"].shape == (300, 3)
    assert np.all(np.diff(trace["t"]) > 0.0)
    assert np.all(np.linalg.norm(trace["force"], axis=1) <= result["max_force_n"] + 1e-12)
    assert int(result["period_histogram"].sum()) == 299  # one period between each pair of ticks


def test_a_virtual_run_renders_the_same_forces_every_time(coffee):
    def run(**options):
        scene = hf.plane_contact([hf.tangible_field(coffee, workspace_mm=80.0),
                                  hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)])
        return hf.run_servo(scene, seconds=0.8, rate=1000.0, hand="circle", hand_size=0.03, **options)

    first, second, default = run(clock="virtual"), run(clock="virtual"), run()
    for other in (second, default):  # the simulated arm runs on the virtual clock unless told otherwise
        for key in ("t", "position", "force"):
            np.testing.assert_array_equal(first["trace"][key], other["trace"][key])
    stats = first["statistics"]
    assert stats["ticks"] == 800 and first["stop_reason"] == "tick_limit"
    assert stats["missed_deadlines"] == 0 and stats["latches"] == 0
    assert stats["peak_force_n"] > 0.5  # the plane pushed back [N]
    np.testing.assert_allclose(np.diff(first["trace"]["t"]), 1e-3, rtol=0, atol=1e-12)  # every tick on time
    # Time only moves when the loop sleeps: every period is the nominal one, in one histogram bin.
    assert stats["period_max_s"] == pytest.approx(1e-3, abs=1e-12)
    assert int(first["period_histogram"].max()) == 799


def test_the_gil_is_released_while_the_loop_runs():
    # The wall clock: a virtual run of 0.4 s may be over before this thread runs at all. A loaded
    # 2-core machine still gives this thread far more than 1000 turns of the loop in 0.4 s.
    done = []
    worker = threading.Thread(target=lambda: done.append(hf.run_servo(hf.zero(), seconds=0.4, clock="wall")))
    worker.start()
    spins = 0
    while worker.is_alive():
        spins += 1
    worker.join()
    assert done and spins > 1000  # Python ran here while the loop ran


# Ctrl-C in a child running a run of an hour on the wall clock. It says "running" once the loop runs
# (the ServoStop token it passes only tells it so), then the parent sends SIGINT.
INTERRUPTED_CHILD = """
import json, signal, sys, threading, time
import numpy as np
import hapticfield as hf
# Python keeps SIGINT ignored when it starts ignored (a test run started in the background by a
# non-interactive shell): Ctrl-C's own handler, whatever the parent did.
signal.signal(signal.SIGINT, signal.default_int_handler)
token = hf.ServoStop()
def tell():
    while not token.running:
        time.sleep(0.01)
    time.sleep(0.3)  # most often the arm has armed and pushes by now; nothing below counts on it
    print("running", flush=True)
threading.Thread(target=tell, daemon=True).start()
try:
    hf.run_servo(hf.plane_contact([]), seconds=3600.0, clock="wall", stop=token)
    print(json.dumps({"raised": None}))
except KeyboardInterrupt as e:
    r = e.result
    f = r["trace"]["force"]
    print(json.dumps({"raised": type(e).__name__, "stop_reason": r["stop_reason"], "ticks": r["statistics"]["ticks"],
                      "rows": len(r["trace"]["t"]),
                      "last_force": float(np.linalg.norm(f[-1])), "pushed": float(np.max(np.linalg.norm(f, axis=1)))}))
"""


def test_ctrl_c_stops_a_run_within_ticks_and_keeps_the_trace():
    child = subprocess.Popen([sys.executable, "-c", INTERRUPTED_CHILD], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "running"
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        out, _ = child.communicate(timeout=60)
        took = time.monotonic() - sent
    finally:
        child.kill()
    # Generous bounds, whatever the load: the loop stops within a few ticks of the signal.
    assert took < 10.0, took
    r = json.loads(out.strip().splitlines()[-1])
    assert r["raised"] == "KeyboardInterrupt" and r["stop_reason"] == "interrupted", r
    assert r["rows"] == r["ticks"] > 0  # the trace up to the signal, one row a tick
    # The last row is the last tick's own command (the stop's zero force after it is no tick of the trace);
    # never beyond the arm's limit [N].
    assert r["last_force"] <= r["pushed"] <= 3.3


def test_another_thread_stops_a_run_with_a_servo_stop_token():
    token = hf.ServoStop()
    assert not token.requested and not token.running
    done = []
    worker = threading.Thread(target=lambda: done.append(
        hf.run_servo(hf.plane_contact([]), seconds=3600.0, clock="wall", stop=token)))
    worker.start()
    waited = 0.0
    while not token.running and worker.is_alive() and waited < 60.0:  # [s] generous, whatever the load
        threading.Event().wait(0.01)
        waited += 0.01
    assert token.running
    token.request()
    worker.join(timeout=10.0)
    assert not worker.is_alive() and not token.running
    r = done[0]
    # on a busy machine the request may come before the loop's first tick: zero ticks is a right answer too
    assert r["stop_reason"] == "requested" and r["statistics"]["ticks"] == len(r["trace"]["t"])
    assert not any(r["final_force"])  # the arm was left with zero force
    assert token.requested  # a token stays requested: it ends any run it is given until cleared
    again = hf.run_servo(hf.zero(), seconds=1.0, stop=token)
    assert again["stop_reason"] == "requested" and again["statistics"]["ticks"] == 0
    token.clear()
    assert hf.run_servo(hf.zero(), seconds=0.01, stop=token)["stop_reason"] == "tick_limit"


def test_the_servo_clocks_example_runs():
    # Only what holds under any load: the virtual runs repeat, the token stops the hour-long run.
    r = subprocess.run([sys.executable, os.path.join(os.path.dirname(__file__), "..", "examples", "servo_clocks.py"),
                        "--seconds", "0.3"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "virtual runs equal bit for bit: True" in r.stdout and "stop requested" in r.stdout
    assert "force the arm was left with 0.000 N" in r.stdout


# --- bad input ------------------------------------------------------------------

@pytest.mark.parametrize("call,error,message", [
    (lambda: hf.tangible_forces("/no/such.png", np.zeros((1, 2))), hf.FileError, "no such file"),
    (lambda: hf.tangible_forces(np.zeros((30, 30), np.uint8), np.zeros((3, 3))), ValueError, "N x 2"),
    (lambda: hf.tangible_forces(np.zeros((30, 30), np.uint8), np.zeros((1, 2)), size=4), ValueError, "size 4 px"),
    (lambda: hf.tangible_forces(np.zeros((30, 30), np.uint8), np.zeros((1, 2)), mask="box"), ValueError, "unknown 'box'"),
    (lambda: hf.tangible_forces(np.zeros((10, 10), np.uint8), np.zeros((1, 2))), ValueError, "smaller than the 17 x 17"),
    (lambda: hf.tangible_forces(np.full((30, 30), np.nan), np.zeros((1, 2)), levels=1.0), ValueError, "finite"),
    (lambda: hf.tangible_forces(np.zeros((30, 30, 2), np.uint8), np.zeros((1, 2))), ValueError, "H x W"),
    (lambda: hf.tangible_field(np.zeros((30, 30), np.uint8), gain=-1.0), ValueError, "gain"),
    (lambda: hf.zero().forces(np.zeros((4, 2))), ValueError, "N x 3"),
    (lambda: hf.zero().forces(np.zeros((4, 3)), velocities=np.zeros((3, 3))), ValueError, "as many rows"),
    (lambda: hf.zero().forces(np.zeros((4, 3)), period=0.0), ValueError, "period"),
    (lambda: hf.plane_contact(normal=(0, 0, 2)), ValueError, "unit vector"),
    (lambda: hf.friction(coulomb=-1.0), ValueError, "Friction"),
    (lambda: hf.lattice_texture(dim=4), ValueError, "dim"),
    (lambda: hf.butterworth(np.zeros(10), order=9), ValueError, "1..8"),
    (lambda: hf.butterworth(np.zeros(10), f1=600.0, rate=1000.0), ValueError, "Butterworth"),
    (lambda: hf.hatt_texture("/no/such.xml"), hf.FileError, "no such file"),
    (lambda: hf.estimate_normal(np.zeros((3, 2)), np.eye(3)), ValueError, "4 corners"),
    (lambda: hf.run_servo(hf.zero(), seconds=0.0), ValueError, "seconds"),
    (lambda: hf.run_servo(hf.zero(), device="usb"), ValueError, "device"),
    (lambda: hf.run_servo(hf.zero(), device="hid"), ValueError, "hid"),
    (lambda: hf.run_servo(hf.zero(), device="hid", clock="virtual", confirm_hardware=True), ValueError,
     "virtual clock.*real arm"),
    (lambda: hf.run_servo(hf.zero(), clock="sundial"), ValueError, "clock: unknown 'sundial'"),
    (lambda: hf.run_servo(hf.zero(), clock="virtual", realtime="best_effort"), ValueError, "realtime"),
])
def test_bad_input_raises_with_the_library_message(call, error, message):
    with pytest.raises(error, match=message):
        call()


def test_file_errors_are_library_errors():
    assert issubclass(hf.FileError, hf.Error) and issubclass(hf.Error, RuntimeError)
    assert issubclass(hf.FileError, OSError)  # `except OSError` catches a missing file too
    with pytest.raises(OSError, match="no such file"):
        hf.tangible_forces("/no/such.png", np.zeros((1, 2)))


@pytest.mark.skipif(hf.has_video, reason="this build has tangible video (tests in test_video.py)")
def test_without_videoio_the_video_calls_raise():
    for call in (lambda: hf.video_forces("clip.mp4", [0.0], [[0.0, 0.0]]), lambda: hf.video_cuts("clip.mp4"),
                 lambda: hf.video_field("clip.mp4")):
        with pytest.raises(hf.Error, match="no OpenCV videoio"):
            call()


def test_hatt_file_that_is_not_xml(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text("not xml at all <")
    with pytest.raises(hf.FileError):
        hf.hatt_texture(str(bad))


def rss_kib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") // 1024


def test_no_leak_over_repeated_construction():
    positions, velocities = stroke(200)
    picture = np.random.default_rng(1).uniform(0, 255, (200, 300))  # 480 KB of gray levels a copy

    def cycle():
        scene = hf.plane_contact([hf.tangible_field(picture, levels=255.0), hf.lattice_texture(), hf.friction(coulomb=0.2),
                                  hf.temporal_texture()])
        scene.forces(positions, velocities)
        hf.force_map(picture, levels=255.0)
        try:
            hf.tangible_forces("/no/such.png", np.zeros((1, 2)))
        except hf.FileError:
            pass

    for _ in range(30):
        cycle()
    before = rss_kib()
    for _ in range(300):
        cycle()
    grown = rss_kib() - before
    assert grown < 8 * 1024, f"resident memory grew by {grown} KiB over 300 constructions"


def test_non_finite_probes_give_zero_force(coffee):
    bad = np.array([[np.nan, 1.0], [1e300, -1e300], [np.inf, 0.0]])
    np.testing.assert_array_equal(hf.tangible_forces(coffee, bad), 0.0)
    scene = make_scene()
    positions = np.array([[np.nan, 0.0, -1e-3], [0.0, 0.0, -1e-3], [0.0, np.inf, -1e-3]])
    velocities = np.array([[0.05, 0.0, 0.0], [np.inf, 0.0, 0.0], [0.05, 0.0, 0.0]])
    forces = scene.forces(positions, velocities)
    np.testing.assert_array_equal(forces[[0, 2]], 0.0)  # a non-finite position: no force
    # a non-finite velocity keeps the contact force of the position and drops only what the velocity adds
    still = make_scene().forces(positions[1:2], np.zeros((1, 3)))
    np.testing.assert_array_equal(forces[1:2], still)
    assert np.linalg.norm(still) > 0.0
    assert np.all(np.isfinite(hf.tangible_field(coffee).forces(positions)))


def test_tick_budget_reports_the_tick_cost_without_an_allocation_counter():
    r = hf.tick_budget(hf.plane_contact([], stiffness=1500.0), ticks=2000)
    assert r["ticks"] == 2000
    assert 0 < r["p50_ns"] <= r["p99_ns"] <= r["p999_ns"] <= r["worst_ns"]
    assert r["allocations"] is None and r["allocations_per_tick"] is None  # no counter preloaded here
    assert r["exceptions"] == 0
    assert "not counted" in r["summary"]
    for bad in ({"ticks": 0}, {"speed": -1.0}, {"radius": 0.0}, {"period": 0.0}, {"share": 2.0}):
        with pytest.raises(ValueError):
            hf.tick_budget(hf.plane_contact([], stiffness=1500.0), **bad)
