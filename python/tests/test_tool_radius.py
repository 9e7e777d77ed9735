"""The tool's radius (surface_contact(radius=)): a ball centred on the HIP, swept against the shape. Closed forms
as in tests/test_sphere_proxy.cpp: on a plane the ball rests r above it with Fc = k (r - the HIP's height); it does
not enter a crack narrower than 2 r and falls into a wider one; out-of-range radii and a ball on a height field
raise ValueError."""
import math
import struct
import zlib

import numpy as np
import pytest

import hapticfield as hf

K = 1500.0  # stiffness [N/m]


def press(start, goal, ticks=100):
    """Probes from `start` to `goal` in `ticks` ticks, then held at `goal` as many more [m]."""
    t = np.minimum(1.0, np.arange(2 * ticks + 1) / ticks)[:, None]
    return np.asarray(start, float) * (1.0 - t) + np.asarray(goal, float) * t


def flat_square(side=0.1):
    """Two triangles covering [-side / 2, side / 2]^2 at z = 0, facing +z."""
    h = side / 2
    vertices = np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])
    return vertices, np.array([[0, 1, 2], [0, 2, 3]])


def box(lo, hi):
    """The 8 corners and 12 outward, counter-clockwise triangles of the box [lo, hi]."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    vertices = np.array([[(x0, x1)[i], (y0, y1)[j], (z0, z1)[k]] for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    faces = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                      [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]])
    return vertices, faces


def write_stl(path, vertices, faces):
    with open(path, "wb") as out:
        out.write(b"\0" * 80 + struct.pack("<I", len(faces)))
        for a, b, c in vertices[faces]:
            n = np.cross(b - a, c - a)
            out.write(struct.pack("<12fH", *(n / np.linalg.norm(n)), *a, *b, *c, 0))


def write_png16(path, levels):
    """A one-channel 16-bit PNG (a depth map), written with zlib alone."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    h, w = levels.shape
    rows = b"".join(b"\0" + levels[j].astype(">u2").tobytes() for j in range(h))
    with open(path, "wb") as out:
        out.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0)) +
                  chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def flat_surfaces(tmp_path):
    vertices, faces = flat_square()
    stl = tmp_path / "square.stl"
    write_stl(stl, vertices, faces)
    return {"plane": hf.plane_surface(), "mesh from arrays": hf.mesh_surface_from_arrays(vertices, faces),
            "STL": hf.mesh_surface(stl)}


@pytest.mark.parametrize("r", [0.0005, 0.002, 0.005])
def test_a_ball_on_a_plane_and_a_flat_mesh_rests_r_above_it_with_fc_k_r_minus_the_hip_height(tmp_path, r):
    for name, surface in flat_surfaces(tmp_path).items():
        field = hf.surface_contact(surface, stiffness=K, radius=r)
        for hip in (0.5 * r, 0.0, -0.002):
            field.reset()
            c = field.contacts(press((0.0, 0.0, 0.01), (0.004, -0.003, hip)))
            assert c["touching"][-1], name
            np.testing.assert_allclose(c["contact_force"][-1], [0.0, 0.0, K * (r - hip)], rtol=1e-5, atol=1e-9,
                                       err_msg=f"{name}, r {r}, HIP at z = {hip}")
            # the proxy is the ball's centre: r above the face (and the proxy's lift, 1e-6 of a face's size)
            assert c["proxy"][-1] == pytest.approx([0.004, -0.003, r], abs=2e-7), name
            np.testing.assert_allclose(c["normal"][-1], [0.0, 0.0, 1.0], atol=1e-12)
        # free until the ball's lowest point reaches the face: the HIP r + 0.1 mm above it touches nothing
        field.reset()
        assert not field.contacts(press((0.0, 0.0, 0.01), (0.0, 0.0, r + 1e-4)))["touching"].any(), name


def test_radius_zero_is_the_point_proxy(tmp_path):
    for name, surface in flat_surfaces(tmp_path).items():
        path = press((0.0, 0.0, 0.01), (0.001, 0.002, -0.001))
        np.testing.assert_array_equal(hf.surface_contact(surface, stiffness=K).forces(path),
                                      hf.surface_contact(surface, stiffness=K, radius=0.0).forces(path), name)
        assert hf.surface_contact(surface, stiffness=K).forces(path)[-1] == pytest.approx([0.0, 0.0, K * 0.001])


@pytest.mark.parametrize("gap", [0.003, 0.0039, 0.0041, 0.006])
def test_a_crack_narrower_than_2r_is_not_entered_a_wider_one_is(gap):
    r = 0.002
    left, left_faces = box((-0.03, -0.02, -0.02), (-gap / 2, 0.02, 0.0))
    right, right_faces = box((gap / 2, -0.02, -0.02), (0.03, 0.02, 0.0))
    surface = hf.mesh_surface_from_arrays(np.vstack([left, right]), np.vstack([left_faces, right_faces + 8]),
                                          shade_normals=False)
    field = hf.surface_contact(surface, stiffness=K, radius=r)
    c = field.contacts(press((0.0, 0.0, 0.01), (0.0, 0.0, -0.01)))
    if gap < 2 * r:
        # on both rims: the centre sqrt(r^2 - (gap / 2)^2) above the top, pushed straight up
        rest = math.sqrt(r * r - gap * gap / 4)
        assert c["touching"][-1]
        assert c["proxy"][-1][2] == pytest.approx(rest, rel=1e-3)
        np.testing.assert_allclose(c["contact_force"][-1], [0.0, 0.0, K * (rest + 0.01)], rtol=1e-5, atol=1e-6)
    else:
        assert c["proxy"][-1][2] < -0.009  # fell in: nothing below in the crack
        assert not c["touching"][-1]
    # a point proxy falls into every crack
    point = hf.surface_contact(surface, stiffness=K).contacts(press((0.0, 0.0, 0.01), (0.0, 0.0, -0.01)))
    assert point["proxy"][-1][2] < -0.009


def test_a_ball_on_a_sphere_surface_rests_at_R_plus_r_from_its_centre():
    R, r = 0.03, 0.004
    field = hf.surface_contact(hf.sphere_surface(centre=(0.0, 0.0, 0.0), radius=R), stiffness=K, radius=r)
    c = field.contacts(press((0.0, 0.0, 0.05), (0.001, 0.0, R)))
    assert c["touching"][-1]
    assert np.linalg.norm(c["proxy"][-1]) == pytest.approx(R + r, rel=1e-5)
    assert np.linalg.norm(c["contact_force"][-1]) == pytest.approx(K * (R + r - math.hypot(0.001, R)), rel=1e-3)


@pytest.mark.parametrize("radius", [-1e-3, 0.0501, 1.0, math.nan, math.inf, -math.inf])
def test_a_radius_out_of_range_raises_a_value_error(radius):
    with pytest.raises(ValueError, match=r"radius: the tool's radius must be in \[0, 0.05\] m"):
        hf.surface_contact(hf.plane_surface(), radius=radius)
    with pytest.raises(ValueError, match=r"radius: the tool's radius must be in \[0, 0.05\] m"):
        hf.picture_relief(np.zeros((20, 30), dtype=np.uint8), radius=radius)


def test_a_ball_on_height_fields_depth_maps_and_reliefs_rests_r_above_them(tmp_path):
    r = 0.002
    depth = tmp_path / "depth.png"
    write_png16(depth, np.full((21, 21), 1000, dtype=np.uint16))
    for surface in (hf.height_field(np.zeros((21, 21)), spacing=1e-3), hf.depth_map(depth, pixel_size=1e-3)):
        top = surface.bounds[1][2]
        c = hf.surface_contact(surface, stiffness=K, radius=r).contacts(
            press((0.01, 0.01, top + 0.01), (0.01, 0.01, top - 0.001)))
        assert c["touching"][-1]
        assert c["proxy"][-1][2] == pytest.approx(top + r, rel=1e-6)
        np.testing.assert_allclose(c["contact_force"][-1], [0.0, 0.0, K * (r + 0.001)], rtol=1e-6, atol=1e-9)
    # a relief of a uniform picture: a plane 100 levels x 0.01 mm = 1 mm high
    relief = hf.picture_relief(np.full((20, 30), 100, dtype=np.uint8), width_m=0.03, texture_gain=0.0,
                               stiffness=K, radius=r)
    c = relief.contacts(press((0.015, 0.01, 0.02), (0.015, 0.01, 0.0)))
    assert c["touching"][-1]
    assert c["proxy"][-1][2] == pytest.approx(0.001 + r, rel=1e-6)
    hf.surface_contact(hf.plane_surface(), radius=0.05)


@pytest.mark.parametrize("r", [0.0, 0.0005])
def test_the_look_ahead_leaves_the_forces_unchanged_and_can_be_switched_off(r):
    # a ball (or the point) slid over a box's top with friction: the same run with the loop's look-ahead
    # (the default) and without it renders the same forces, bit for bit; only the first anticipates ticks
    vertices, faces = box((-0.04, -0.04, -0.05), (0.04, 0.04, -0.01))
    field = hf.surface_contact(hf.mesh_surface_from_arrays(vertices, faces), radius=r, stiffness=K, damping=0.5,
                               static_friction=0.5, dynamic_friction=0.4)
    runs = [hf.run_servo(field, seconds=2.0, hand="circle", hand_centre=(0.0, 0.0, -0.012), hand_size=0.03,
                         anticipate=anticipate) for anticipate in (True, False)]
    ahead, plain = runs
    touching = np.linalg.norm(plain["trace"]["force"], axis=1) > 0.5
    assert touching.sum() > 500  # pressed into the top for most of the run [N]
    assert np.array_equal(ahead["trace"]["force"], plain["trace"]["force"])
    assert np.array_equal(ahead["trace"]["position"], plain["trace"]["position"])
    assert ahead["statistics"]["look_aheads"] > 1000 and plain["statistics"]["look_aheads"] == 0
