"""Shapes that move and deform while the loop runs, and a MuJoCo scene felt through run_servo, against closed
forms and the C++ bridge's laws; every run on the virtual clock."""
import os
import pathlib
import time

import numpy as np
import pytest

import hapticfield as hf
from grid_meshes import grid

SOURCE = pathlib.Path(os.environ.get("HAPTICFIELD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
K = 1200.0  # stiffness [N/m]
DT = 1e-3  # the servo period [s]

needs_mujoco = pytest.mark.skipif(not hf.has_mujoco, reason="the module is built without MuJoCo")


def scene_file(name):
    return str(SOURCE / "examples" / "data" / name)


# --- moving shapes ---------------------------------------------------------------

def test_a_plane_moving_into_a_still_probe_pushes_it_with_k_times_the_overlap():
    # the plane z = 0 placed 2 mm low, rising at 5 cm/s from t = 0: its face at z(t) = -0.002 + 0.05 t
    plane = hf.moving_surface(hf.plane_surface(), pose=hf.Pose(translation=(0.0, 0.0, -0.002)),
                              velocity=(0.0, 0.0, 0.05))
    field = hf.surface_contact(plane, stiffness=K)
    n = 90  # 90 ms: within the 0.1 s a snapshot is extrapolated
    still = np.zeros((n, 3))
    f = field.forces(still, period=DT)
    t = np.arange(n) * DT
    overlap = np.clip(-0.002 + 0.05 * t, 0.0, None)
    assert np.abs(f[:, :2]).max() == 0.0
    assert np.allclose(f[:, 2], K * overlap, rtol=0.0, atol=K * 1e-7)  # [N]: the proxy's lift is 1e-6 m at most
    assert f[-1, 2] > 2.0  # it was pushed [N]


def test_the_damping_acts_on_the_velocity_relative_to_the_moving_surface():
    b = 3.0  # [N s/m]
    plane = hf.moving_surface(hf.plane_surface(), pose=hf.Pose(translation=(0.0, 0.0, -0.001)),
                              velocity=(0.0, 0.0, 0.05))
    field = hf.surface_contact(plane, stiffness=K, damping=b)
    t = np.arange(60) * DT
    f = field.forces(np.zeros((60, 3)), period=DT)
    overlap = -0.001 + 0.05 * t
    touching = overlap > 1e-6
    # a still probe against a surface coming at 5 cm/s: F = k d + b v_s
    assert np.allclose(f[touching, 2], K * overlap[touching] + b * 0.05, rtol=0.0, atol=K * 1e-7)
    assert np.all(f[~touching & (overlap < -1e-6), 2] == 0.0)


def test_a_pose_set_between_ticks_is_felt_at_the_next_tick():
    plane = hf.moving_surface(hf.plane_surface())
    field = hf.surface_contact(plane, stiffness=K)
    rng = np.random.default_rng()
    heights = rng.uniform(-0.003, 0.003, 200)
    heights[0] = -0.001  # the probe starts outside (a HIP that starts inside a solid feels nothing)
    for i, z in enumerate(heights):
        plane.set_pose(hf.Pose(translation=(0.0, 0.0, z)), time=i * DT)
        f = field.forces(np.zeros((1, 3)), period=DT, start_time=i * DT)
        # the proxy is carried with the plane: the overlap is the plane's height above the still probe
        assert f[0, 2] == pytest.approx(K * max(z, 0.0), abs=K * 1e-7), (i, z)
    pose, velocity, angular_velocity, time = plane.moving_pose
    assert pose.translation[2] == heights[-1] and time == pytest.approx(199 * DT)
    assert list(velocity) == [0.0, 0.0, 0.0] and list(angular_velocity) == [0.0, 0.0, 0.0]


def test_a_sphere_sweeping_past_never_captures_the_proxy_inside():
    # a ball of 1 cm passing through a still probe at 1 m/s: the proxy is carried out with its surface
    ball = hf.moving_surface(hf.sphere_surface(radius=0.01), pose=hf.Pose(translation=(-0.03, 0.0, 0.002)),
                             velocity=(1.0, 0.0, 0.0))
    field = hf.surface_contact(ball, stiffness=K)
    c = field.contacts(np.zeros((60, 3)), period=DT)
    t = np.arange(60) * DT
    centre = np.stack([-0.03 + t, np.zeros_like(t), np.full_like(t, 0.002)], axis=1)
    assert np.all(np.linalg.norm(c["proxy"] - centre, axis=1) >= 0.01 - 1e-6)  # never inside [m]
    assert c["touching"].any()


def test_moving_surface_refuses_bad_poses_and_a_surface_that_already_moves():
    plane = hf.moving_surface(hf.plane_surface())
    with pytest.raises(ValueError):
        plane.set_pose(velocity=(float("nan"), 0.0, 0.0))
    with pytest.raises(ValueError):
        plane.set_pose(time=float("inf"))
    with pytest.raises(ValueError, match="already moves"):
        hf.moving_surface(plane)
    assert isinstance(plane, hf.Surface) and plane.kind == "plane" and plane.bounds is None


# --- deforming meshes ------------------------------------------------------------

def bump(vertices, height):
    v = vertices.copy()
    v[:, 2] = height * np.exp(-(v[:, 0] ** 2 + v[:, 1] ** 2) / (2 * 0.008 ** 2))
    return v


@pytest.mark.parametrize("shade_normals", [True, False])
def test_a_refit_mesh_is_felt_as_a_rebuilt_one(shade_normals):
    vertices, faces = grid()
    mesh = hf.deforming_mesh(vertices, faces, shade_normals=shade_normals)
    field = hf.surface_contact(mesh, stiffness=K)  # made before the deformation: its tree is refitted
    rng = np.random.default_rng()
    for frame in range(3):
        moved = bump(vertices, rng.uniform(0.001, 0.004))
        mesh.set_vertices(moved)
        rebuilt = hf.surface_contact(hf.mesh_surface_from_arrays(moved, faces, shade_normals=shade_normals), stiffness=K)
        # presses from above at random points of the bump, each from free to 1.5 mm in
        start = np.append(rng.uniform(-0.008, 0.008, 2), 0.008)
        end = start.copy()
        end[2] = bump(start[None, :], moved[:, 2].max())[0, 2] - 0.0015
        path = start + np.linspace(0.0, 1.0, 80)[:, None] * (end - start)
        field.reset()
        got, want = field.forces(path), rebuilt.forces(path)
        assert np.abs(got).max() > 0.1, frame  # it was touched [N]
        assert np.allclose(got, want, rtol=0.0, atol=1e-9), (frame, np.abs(got - want).max())
    assert mesh.frames == 3


def test_a_deforming_mesh_pushes_a_touching_probe_as_it_rises():
    vertices, faces = grid()
    mesh = hf.deforming_mesh(vertices, faces, shade_normals=False)
    field = hf.surface_contact(mesh, stiffness=K)
    # pressed 0.5 mm into the flat mesh, then held still
    press = np.array([[0.001, 0.0013, 0.004 - 0.0045 * k / 20] for k in range(21)])
    f = field.forces(press)
    assert f[-1, 2] == pytest.approx(K * 0.0005, abs=K * 1e-7)
    for i, z in enumerate(np.linspace(0.0001, 0.003, 30)):
        mesh.set_vertices(vertices + [0.0, 0.0, z])
        f = field.forces(press[-1:], start_time=(21 + i) * DT)
        # a touching proxy is put back in front of the face it touched: the overlap grows with the face
        assert f[0, 2] == pytest.approx(K * (z + 0.0005), abs=K * 1e-7), (i, z)


def test_set_vertices_refuses_wrong_shapes_and_values():
    vertices, faces = grid(4)
    mesh = hf.deforming_mesh(vertices, faces, shade_normals=False)
    with pytest.raises(ValueError, match="one row per vertex"):
        mesh.set_vertices(vertices[:-1])
    with pytest.raises(ValueError, match="N x 3"):
        mesh.set_vertices(vertices[:, :2])
    bad = vertices.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="row 3"):
        mesh.set_vertices(bad)
    with pytest.raises(ValueError, match="normals"):
        mesh.set_vertices(vertices, normals=np.tile([0.0, 0.0, 1.0], (len(vertices), 1)))
    assert mesh.frames == 0


# --- a MuJoCo scene --------------------------------------------------------------

@needs_mujoco
def test_a_mujoco_scene_in_run_servo_steps_in_lockstep_and_is_the_same_run_to_run():
    def run():
        scene = hf.mujoco_scene(scene_file("mujoco_ball.xml"), rate=500.0)
        result = hf.run_servo(scene, seconds=1.0, hand="hold", hand_centre=(0.03, 0.0, 0.0))
        return scene, result
    first, a = run()
    second, b = run()
    assert first.events["steps"] == 500  # 1 s at 500 Hz, stepped from the loop's time
    assert first.events["overruns"] == 0 and first.events["stalls"] == 0
    assert np.abs(a["trace"]["force"]).max() > 0.1  # the hand met the ball [N]
    assert first.body("ball")["velocity"][0] > 0.0  # pushed away
    assert np.array_equal(a["trace"]["force"], b["trace"]["force"])
    assert np.array_equal(a["trace"]["position"], b["trace"]["position"])
    assert first.body("ball") == second.body("ball")
    assert first.simulated_time == pytest.approx(1.0)


@needs_mujoco
def test_on_the_wall_clock_the_scene_steps_on_its_own_thread_for_the_run_only():
    scene = hf.mujoco_scene(scene_file("mujoco_ball.xml"), rate=500.0)
    result = hf.run_servo(scene, seconds=0.1, clock="wall", hand="hold", hand_centre=(0.03, 0.0, 0.0))
    assert len(result["trace"]["t"]) == 100
    steps = scene.events["steps"]  # as many as the machine managed in real time
    time.sleep(0.03)
    assert scene.events["steps"] == steps  # stopped with the run
    assert scene.step(2) and scene.events["steps"] == steps + 2  # and stepped by hand after it


@needs_mujoco
def test_momentum_the_hand_gives_is_momentum_the_ball_gains_stepped_by_hand():
    rng = np.random.default_rng()
    for mode in ("local_model", "virtual_coupling"):
        rate = float(rng.choice([100.0, 500.0]))
        scene = hf.mujoco_scene(scene_file("mujoco_ball.xml"), rate=rate, mode=mode, fade_time=0.0)
        ratio = int(round(1.0 / (rate * DT)))
        speed = rng.uniform(0.05, 0.3)
        aim = np.array([0.08, *rng.uniform(-0.01, 0.01, 2)])
        path = np.linspace(0.0, 1.0, 700)[:, None] * aim[None, :]
        velocity = aim * speed / np.linalg.norm(aim)
        f = np.zeros((len(path), 3))
        for i in range(len(path)):  # the virtual clock: one tick, then a step when it is due
            f[i] = scene.forces(path[i:i + 1], velocities=velocity[None, :], start_time=i * DT)[0]
            if (i + 1) % ratio == 0:
                scene.step()
                if i + 1 == ratio:
                    ball0, tool0, impulse0 = scene.body("ball"), scene.body("tool"), f[:i + 1].sum(axis=0) * DT
        ball, tool = scene.body("ball"), scene.body("tool")
        gained = ball["mass"] * (np.array(ball["velocity"]) - ball0["velocity"])
        if mode == "virtual_coupling":
            gained += tool["mass"] * (np.array(tool["velocity"]) - tool0["velocity"])
        given = -(f.sum(axis=0) * DT - impulse0)
        assert np.linalg.norm(given) > 1e-3, mode  # [N s]
        assert np.linalg.norm(gained - given) <= 1e-9 + 1e-9 * np.linalg.norm(given), (mode, rate, gained, given)


@needs_mujoco
def test_the_door_turns_about_its_hinge_stepped_by_hand():
    scene = hf.mujoco_scene(scene_file("mujoco_door.xml"), rate=200.0, fade_time=0.0)
    # the door's face is 2.7 cm beyond the origin; the hand pushes 8 cm off the hinge at 5 cm/s
    n = 1500
    path = np.zeros((n, 3))
    path[:, 0] = -0.03
    path[:, 2] = -np.minimum(np.arange(n) * DT * 0.05, 0.06)
    velocity = np.gradient(path, DT, axis=0)
    worst = 0.0
    for i in range(0, n, 5):  # five ticks, then a step (200 Hz)
        scene.forces(path[i:i + 5], velocities=velocity[i:i + 5], start_time=i * DT)
        scene.step()
        door = scene.body("door")["position"]
        worst = max(worst, abs(np.hypot(door[0] - 0.05, door[2] + 0.03) - 0.05))
    assert scene.joint_position("hinge") < -0.2  # pushed away at its left [rad]
    assert worst < 1e-3  # about its hinge [m]


@needs_mujoco
def test_a_mujoco_scene_refuses_bad_input_with_one_clear_error(tmp_path):
    with pytest.raises(hf.FileError, match="no_such_scene"):
        hf.mujoco_scene(str(tmp_path / "no_such_scene.xml"))
    toolless = tmp_path / "toolless.xml"
    toolless.write_text("<mujoco><worldbody/></mujoco>")
    with pytest.raises(hf.Error, match="no tool body"):
        hf.mujoco_scene(toolless)
    with pytest.raises(ValueError, match="rate"):
        hf.mujoco_scene(scene_file("mujoco_ball.xml"), rate=5.0)
    with pytest.raises(ValueError, match="T plane_stiffness / 2"):
        hf.mujoco_scene(scene_file("mujoco_ball.xml"), rate=100.0, damping=1.0)
    with pytest.raises(ValueError, match="choose"):
        hf.mujoco_scene(scene_file("mujoco_ball.xml"), mode="glue")
    scene = hf.mujoco_scene(scene_file("mujoco_ball.xml"))
    with pytest.raises(ValueError, match="no body"):
        scene.body("nothing")
    assert scene.fault == "none" and scene.fault_message == "" and scene.rate == pytest.approx(500.0)
    assert scene.tool_radius == pytest.approx(0.004)


@pytest.mark.skipif(hf.has_mujoco, reason="the module is built with MuJoCo")
def test_without_mujoco_mujoco_scene_says_so():
    with pytest.raises(hf.Error, match="no MuJoCo"):
        hf.mujoco_scene(scene_file("mujoco_ball.xml"))
