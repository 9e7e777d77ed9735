"""Surfaces from Python (height fields, meshes, analytic shapes) against closed forms, the plane contact
and real mesh files."""
import os
import pathlib
import struct
import threading
import time
import zlib

import numpy as np
import pytest

import hapticfield as hf

SHARED = pathlib.Path(os.environ.get("HAPTICFIELD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2])) \
    .parent / "shared" / "data"

K = 1200.0  # stiffness [N/m]


def press(start, end, n=40):
    """Probes from `start` (free) to `end` (pressed in) in n steps, as consecutive ticks [m]."""
    t = np.linspace(0.0, 1.0, n)[:, None]
    return np.asarray(start, float) * (1.0 - t) + np.asarray(end, float) * t


def flat(z=0.002, size=0.06, spacing=2e-3, origin=(-0.03, -0.03, 0.0)):
    n = int(round(size / spacing)) + 1
    return hf.height_field(np.full((n, n), z), spacing=spacing, origin=origin)


# --- height fields --------------------------------------------------------------

def test_a_flat_height_field_pushes_like_the_plane_k_depth_along_the_normal():
    surface = flat(z=0.002)
    field = hf.surface_contact(surface, stiffness=K)
    plane = hf.plane_contact([], point=(0.0, 0.0, 0.002), normal=(0.0, 0.0, 1.0), stiffness=K)
    path = press((0.004, -0.003, 0.006), (0.004, -0.003, 0.002 - 0.003))
    f = field.forces(path)
    depth = np.clip(0.002 - path[:, 2], 0.0, None)
    np.testing.assert_allclose(f[:, 2], K * depth, rtol=1e-6, atol=1e-9)  # the closed form, k d
    np.testing.assert_allclose(f[:, :2], 0.0, atol=1e-9)
    np.testing.assert_allclose(f, plane.forces(path), rtol=1e-6, atol=1e-9)  # and the plane contact
    field.reset()
    c = field.contacts(path)
    np.testing.assert_array_equal(c["touching"], depth > 0.0)
    np.testing.assert_allclose(c["depth"], depth, atol=1e-9)
    np.testing.assert_allclose(c["normal"][c["touching"]], [[0.0, 0.0, 1.0]] * int(c["touching"].sum()), atol=1e-12)
    np.testing.assert_allclose(c["proxy"][-1], [0.004, -0.003, 0.002], atol=1e-8)  # on the surface above the HIP
    # uv runs 0..1 over the footprint: (0.004 + 0.03) / 0.06 and (-0.003 + 0.03) / 0.06
    np.testing.assert_allclose(c["uv"][-1], [0.034 / 0.06, 0.027 / 0.06], atol=1e-9)
    assert c["primitive"][0] == -1 and c["primitive"][-1] == 13 * 30 + 17  # cell j (W - 1) + i, 2 mm cells


def test_float32_heights_are_taken_and_the_surface_describes_itself():
    s = hf.height_field(np.zeros((4, 5), dtype=np.float32), spacing=(1e-3, 2e-3), origin=(1.0, 2.0, 3.0))
    assert s.kind == "height_field" and s.samples == [5, 4]
    assert s.footprint == pytest.approx([4e-3, 6e-3])
    lo, hi = s.bounds
    assert lo == pytest.approx([1.0, 2.0, 3.0]) and hi == pytest.approx([1.004, 2.006, 3.0])


@pytest.mark.parametrize("a,b", [(0.3, -0.2), (-0.5, 0.1), (0.0, 0.7)])
def test_a_tilted_height_field_pushes_along_its_analytic_normal(a, b):
    # z = a x + b y: the normal is (-a, -b, 1) / |.|, the depth of a HIP dz below it dz / |.|
    x = np.linspace(-0.02, 0.02, 41)
    X, Y = np.meshgrid(x, x)
    surface = hf.height_field(a * X + b * Y, spacing=1e-3, origin=(-0.02, -0.02, 0.0))
    field = hf.surface_contact(surface, stiffness=K)
    n = np.array([-a, -b, 1.0]) / np.linalg.norm([-a, -b, 1.0])
    x0, y0, dz = 0.003, -0.004, 0.002
    top = a * x0 + b * y0
    c = field.contacts(press((x0, y0, top + 0.004), (x0, y0, top - dz)))
    assert c["touching"][-1]
    np.testing.assert_allclose(c["normal"][-1], n, atol=1e-9)
    np.testing.assert_allclose(c["force"][-1], K * dz * n[2] * n, rtol=1e-6)


def test_a_paraboloid_height_field_has_the_analytic_normal_to_second_order():
    # z = -(x^2 + y^2) / (2 R), a cap of radius R: the normal at (x, y) is (x / R, y / R, 1) / |.|
    R, h = 0.05, 5e-4
    x = np.arange(-0.02, 0.02 + h / 2, h)
    X, Y = np.meshgrid(x, x)
    surface = hf.height_field(-(X ** 2 + Y ** 2) / (2 * R), spacing=h, origin=(x[0], x[0], 0.0))
    rng = np.random.default_rng(3)
    for x0, y0 in rng.uniform(-0.015, 0.015, (8, 2)):
        field = hf.surface_contact(surface, stiffness=K)
        top = -(x0 ** 2 + y0 ** 2) / (2 * R)
        c = field.contacts(press((x0, y0, top + 0.003), (x0, y0, top - 2e-4)))
        n = np.array([x0 / R, y0 / R, 1.0]) / np.linalg.norm([x0 / R, y0 / R, 1.0])
        assert c["touching"][-1]
        assert np.degrees(np.arccos(min(1.0, c["normal"][-1] @ n))) < 0.1  # central differences: O(h^2)
        f = c["force"][-1]
        assert np.degrees(np.arccos(min(1.0, f @ n / np.linalg.norm(f)))) < 0.1


def test_a_relief_from_a_picture_reads_as_it_is_seen():
    # a white square (255) in the top-left quarter of a black picture: high at small x, large y
    picture = np.zeros((20, 30), dtype=np.uint8)
    picture[:10, :15] = 255
    s = hf.height_field_from_picture(picture, pixel_size=1e-3, mm_per_level=0.01)
    assert s.samples == [30, 20] and s.bounds[1][2] == pytest.approx(2.55e-3)
    field = hf.surface_contact(s, stiffness=K)
    high = field.contacts(press((0.005, 0.015, 0.006), (0.005, 0.015, 0.002)))
    assert high["touching"][-1] and high["force"][-1, 2] == pytest.approx(K * 0.55e-3, rel=1e-6)
    field.reset()
    low = field.contacts(press((0.025, 0.005, 0.006), (0.025, 0.005, -0.001)))
    assert low["force"][-1, 2] == pytest.approx(K * 1e-3, rel=1e-6)
    dark = hf.height_field_from_picture(picture, pixel_size=1e-3, dark_is_high=True, blur=1.0)
    assert dark.bounds[1][2] == pytest.approx(2.55e-3, rel=1e-3)


def write_png(path, levels, bits):
    """A one-channel PNG of 8 or 16 bits (big-endian samples), written with zlib alone."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    h, w = levels.shape
    rows = b"".join(b"\0" + levels[j].astype(">u2" if bits == 16 else "u1").tobytes() for j in range(h))
    with open(path, "wb") as out:
        out.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, bits, 0, 0, 0, 0)) +
                  chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def write_float_tiff(path, values):
    """A one-channel 32-bit float TIFF (little-endian, one uncompressed strip), written with struct alone."""
    h, w = values.shape
    data = values.astype("<f4").tobytes()
    tags = [(256, 4, w), (257, 4, h), (258, 3, 32), (259, 3, 1), (262, 3, 1), (273, 4, 0), (277, 3, 1),
            (278, 4, h), (279, 4, len(data)), (339, 3, 3)]  # 339 SampleFormat 3: IEEE float
    ifd_size = 2 + 12 * len(tags) + 4
    tags = [(t, k, 8 + ifd_size if t == 273 else v) for t, k, v in tags]
    ifd = struct.pack("<H", len(tags)) + b"".join(
        struct.pack("<HHI", t, k, 1) + (struct.pack("<HH", v, 0) if k == 3 else struct.pack("<I", v))
        for t, k, v in tags) + struct.pack("<I", 0)
    path.write_bytes(b"II*\0" + struct.pack("<I", 8) + ifd + data)


def test_a_float_tiff_depth_map_in_metres(tmp_path):
    x = np.arange(16) * 1e-3
    X, Y = np.meshgrid(x, x[:12])
    path = tmp_path / "depth.tif"
    write_float_tiff(path, 0.01 + 0.2 * X)  # [m], a slope of 0.2 rising along x; the picture's rows: y down
    d = hf.depth_map(path, pixel_size=1e-3, metres_per_unit=1.0)
    assert d.samples == [16, 12] and d.bounds[1][2] == pytest.approx(0.01 + 0.2 * 0.015, rel=1e-6)
    field = hf.surface_contact(d, stiffness=K)
    top = 0.01 + 0.2 * 0.0075
    f = field.forces(press((0.0075, 0.005, top + 0.004), (0.0075, 0.005, top - 0.001)))[-1]
    n = np.array([-0.2, 0.0, 1.0]) / np.linalg.norm([-0.2, 0.0, 1.0])
    np.testing.assert_allclose(f, K * 0.001 * n[2] * n, rtol=1e-5)
    write_float_tiff(path, np.array([[0.0, np.nan], [0.0, 0.0]]))
    with pytest.raises(hf.FileError, match="not finite"):
        hf.depth_map(path, metres_per_unit=1.0)


def test_a_picture_file_and_a_16_bit_depth_map(tmp_path, coffee):
    s = hf.height_field_from_picture(coffee, pixel_size=2e-4, mm_per_level=0.02, blur=1.0)
    assert s.samples[0] > 100 and 0.0 < s.bounds[1][2] <= 255 * 0.02e-3 + 1e-12
    depth = np.tile(np.arange(0, 2000, 100, dtype=np.uint16), (10, 1))  # um, rising along x
    path = tmp_path / "depth.png"
    write_png(path, depth, 16)
    d = hf.depth_map(path, pixel_size=1e-3, metres_per_unit=1e-6)
    assert d.samples == [20, 10] and d.bounds[1][2] == pytest.approx(1.9e-3)
    field = hf.surface_contact(d, stiffness=K)
    f = field.forces(press((0.0105, 0.004, 0.004), (0.0105, 0.004, 1.05e-3 - 1e-3)))[-1]
    n = np.array([-0.1, 0.0, 1.0]) / np.linalg.norm([-0.1, 0.0, 1.0])  # slope 100 um per mm
    np.testing.assert_allclose(f / np.linalg.norm(f), n, atol=1e-6)


# --- analytic shapes and meshes -------------------------------------------------

def test_a_sphere_surface_pushes_along_the_radius():
    centre, R = np.array([0.01, -0.02, 0.0]), 0.03
    rng = np.random.default_rng(5)
    for d in rng.normal(size=(10, 3)):
        d /= np.linalg.norm(d)
        field = hf.surface_contact(hf.sphere_surface(centre=tuple(centre), radius=R), stiffness=K)
        f = field.forces(press(centre + 1.3 * R * d, centre + (R - 0.002) * d))[-1]
        np.testing.assert_allclose(f, K * 0.002 * d, rtol=1e-6, atol=1e-9)


def icosphere(levels=3):
    """Unit icosphere: vertices, triangles (counter-clockwise seen from outside)."""
    t = (1.0 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        mid, g = {}, []

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                mid[key] = len(v) - 1
            return mid[key]
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = g
    return np.array(v), np.array(f)


def write_stl(path, vertices, triangles):
    with open(path, "wb") as out:
        out.write(b"\0" * 80 + struct.pack("<I", len(triangles)))
        for tri in triangles:
            a, b, c = vertices[tri]
            n = np.cross(b - a, c - a)
            out.write(struct.pack("<12fH", *(n / np.linalg.norm(n)), *a, *b, *c, 0))


def test_an_icosphere_mesh_pushes_along_the_radius_through_force_shading(tmp_path):
    v, f = icosphere(3)  # 1280 faces, radius 30 mm, written in millimetres
    path = tmp_path / "ball.stl"
    write_stl(path, v * 30.0, f)
    ball = hf.mesh_surface(path, scale=1e-3, origin=(0.0, 0.0, -0.05))
    assert ball.kind == "mesh" and ball.triangles == 1280
    np.testing.assert_allclose(ball.bounds, [[-0.03, -0.03, -0.08], [0.03, 0.03, -0.02]], atol=1e-6)
    centre = np.array([0.0, 0.0, -0.05])
    rng = np.random.default_rng(11)
    for d in rng.normal(size=(10, 3)):
        d /= np.linalg.norm(d)
        field = hf.surface_contact(ball, stiffness=K)
        c = field.contacts(press(centre + 0.04 * d, centre + 0.028 * d))
        f = c["force"][-1]
        assert c["touching"][-1]
        assert np.degrees(np.arccos(f @ d / np.linalg.norm(f))) < 1.0  # along the radius, not the facet
        # the depth below the true ball, within the chord error of 1280 facets (0.3 mm at 30 mm)
        assert np.linalg.norm(f) == pytest.approx(K * 0.002, abs=K * 3e-4)


def test_stick_first_and_the_tick_node_budget_reach_the_proxy():
    """stick_first=False is the full tick: on a flat face it feels the same; on a curved mesh it differs a little,
    both keeping the friction force within the static cone. tick_node_budget=0 lets the proxy make no move: it
    never touches."""
    mu_s, mu_k = 0.5, 0.4
    slide = np.column_stack([np.linspace(-0.01, 0.01, 400), np.full(400, 0.003), np.full(400, -0.002)])
    slide = np.vstack([press((-0.01, 0.003, 0.005), slide[0]), slide])  # pressed in from above, then slid
    grid = np.array([(x, y, 0.0) for y in (-0.05, 0.05) for x in (-0.05, 0.05)])
    square = hf.mesh_surface_from_arrays(grid, np.array([[0, 1, 3], [0, 3, 2]]))
    flat = [hf.surface_contact(square, stiffness=K, static_friction=mu_s, dynamic_friction=mu_k,
                               stick_first=first).forces(slide) for first in (True, False)]
    assert np.abs(flat[0][:, 0]).max() > 0.5 * mu_k * K * 0.002  # it slides, with friction
    np.testing.assert_allclose(flat[0], flat[1], atol=1e-9)
    v, f = icosphere(3)
    ball = hf.mesh_surface_from_arrays(v * 0.03, f, origin=(0.0, 0.0, -0.03))
    # around the top of a 30 mm ball, 2 mm deep
    arc = np.array([(0.02 * np.sin(a), 0.003, -0.002 + 0.03 * (np.cos(a) - 1.0)) for a in np.linspace(-0.6, 0.6, 600)])
    arc = np.vstack([press(arc[0] + (0.0, 0.0, 0.01), arc[0]), arc])
    curved = []
    for first in (True, False):
        c = hf.surface_contact(ball, stiffness=K, static_friction=mu_s, dynamic_friction=mu_k,
                               stick_first=first).contacts(arc)
        assert c["touching"][40:].all()
        normal = np.einsum("ij,ij->i", c["force"], c["normal"])
        tangential = np.linalg.norm(c["force"] - normal[:, None] * c["normal"], axis=1)
        assert (tangential <= 1.1 * mu_s * normal + 1e-9).all()
        curved.append(c["force"])
    assert np.abs(curved[0] - curved[1]).max() > 1e-6
    press_in = press((0.0, 0.0, 0.01), (0.0, 0.0, -0.002))
    assert np.linalg.norm(hf.surface_contact(square, stiffness=K).forces(press_in)[-1]) == pytest.approx(K * 0.002)
    assert not hf.surface_contact(square, stiffness=K, tick_node_budget=0).forces(press_in).any()


def real_meshes():
    names = ["meshes/spot.obj", "meshes/stanford-bunny.obj", "meshes/fandisk.obj", "gltf/Duck.gltf",
             "gltf/BoxTextured.gltf"]
    return [pytest.param(SHARED / n, id=n) for n in names]


@pytest.mark.parametrize("path", real_meshes())
def test_a_real_mesh_gives_finite_forces_over_a_trajectory(path):
    if not path.exists():
        pytest.skip(f"{path} is absent")
    raw = hf.mesh_surface(path)
    lo, hi = np.array(raw.bounds)
    scale = 0.1 / np.linalg.norm(hi - lo)  # a hand-sized object, 0.1 m across
    centre = (lo + hi) / 2 * scale
    mesh = hf.mesh_surface(path, scale=scale, origin=tuple(-centre))
    field = hf.surface_contact(mesh, [hf.on_surface(hf.lattice_texture(sigma=0.5, gain=0.2), scale=0.05)],
                               stiffness=K, damping=1.0, static_friction=0.4, dynamic_friction=0.3)
    # down from above onto the top until it touches, then circles pressed 2 mm in, then up and away
    down = press((0.0, 0.0, 0.08), (0.0, 0.0, -0.06), 1400)
    first = np.argmax(field.contacts(down)["touching"])
    assert first > 0  # it met the object on the way down
    top = down[first, 2]
    field.reset()
    a = np.linspace(0, 4 * np.pi, 2000)
    circle = np.column_stack([0.004 * np.sin(a), 0.004 * (1 - np.cos(a)), np.full_like(a, top - 0.002)])
    path_ = np.vstack([down[:first], press(down[first], circle[0], 20), circle,
                       press(circle[-1], (0.0, 0.0, 0.2), 400)])
    c = field.contacts(path_, velocities=np.gradient(path_, 1e-3, axis=0))
    assert np.all(np.isfinite(c["force"])) and np.all(np.isfinite(c["proxy"]))
    assert c["touching"][first:first + 20 + 2000].mean() > 0.2  # on the object for part of the circles
    assert not c["touching"][-1]
    assert np.all(c["primitive"][c["touching"]] >= 0) and np.all(c["primitive"][c["touching"]] < mesh.triangles)
    assert np.max(np.linalg.norm(c["force"], axis=1)) < 1.5 * K * 0.02  # 2 mm in, on slopes up to 20 mm [N]


def test_a_plane_surface_and_the_plane_contact_agree_with_friction_in_the_cone():
    field = hf.surface_contact(hf.plane_surface(point=(0, 0, 0), normal=(0, 0, 1)), stiffness=K,
                               static_friction=0.5, dynamic_friction=0.4)
    path = np.vstack([press((0, 0, 0.003), (0, 0, -0.002), 20), press((0, 0, -0.002), (0.01, 0, -0.002), 200)])
    f = field.forces(path)
    np.testing.assert_allclose(f[:, 2], K * np.clip(-path[:, 2], 0, None), rtol=1e-6, atol=1e-9)
    tangential = np.linalg.norm(f[:, :2], axis=1)
    assert np.all(tangential <= 0.5 * f[:, 2] + 1e-9)  # inside the static cone
    assert tangential[-1] == pytest.approx(0.4 * f[-1, 2], rel=1e-6)  # sliding: mu_k |Fn|
    assert f[-1, 0] < 0.0  # against the motion


# --- fields laid on surfaces ------------------------------------------------------

def test_a_field_laid_on_a_flat_height_field_by_its_footprint_is_the_plane_contacts(coffee):
    # uv x footprint + origin is the HIP's own (x, y) on a flat field, so a tangible image and a lattice laid
    # on it give what the plane contact gives with the same parts
    surface = flat(z=0.0, size=0.08, spacing=4e-3, origin=(-0.04, -0.04, 0.0))
    image = hf.tangible_field(coffee, workspace_mm=80.0, gain=0.8)
    lattice = hf.lattice_texture(sigma=0.5, gain=0.3, scale_with_normal_force=True, axes=(1, 1, 0))
    on = hf.surface_contact(surface, [hf.on_surface(p, scale=surface.footprint, offset=(-0.04, -0.04))
                                      for p in (image, lattice)], stiffness=K)
    plane = hf.plane_contact([image, lattice], stiffness=K)
    a = np.linspace(0, 2 * np.pi, 1500)
    path = np.vstack([press((0.01, 0.0, 0.003), (0.01, 0.0, -0.002), 50),
                      np.column_stack([0.01 * np.cos(a), 0.02 * np.sin(a), np.full_like(a, -0.002)])])
    v = np.gradient(path, 1e-3, axis=0)
    f_on, f_plane = on.forces(path, velocities=v), plane.forces(path, velocities=v)
    assert np.max(np.linalg.norm(f_plane[:, :2], axis=1)) > 0.1  # the parts push
    np.testing.assert_allclose(f_on, f_plane, atol=1e-6)


def test_a_field_on_a_sphere_pushes_in_its_tangent_plane():
    R = 0.03
    texture = hf.on_surface(hf.lattice_texture(sigma=1.0, gain=0.5, axes=(1, 1, 1)), scale=(0.2, 0.1))
    field = hf.surface_contact(hf.sphere_surface(radius=R), [texture], stiffness=K)
    a = np.linspace(0.3, 1.2, 800)
    path = np.vstack([press((0, 0, 0.04), (0, 0, 0.028), 30),
                      np.column_stack([0.028 * np.sin(a), np.zeros_like(a), 0.028 * np.cos(a)])])
    c = field.contacts(path, velocities=np.gradient(path, 1e-3, axis=0))
    t = c["touching"]
    parts = (c["force"] - c["contact_force"])[t]
    assert np.max(np.linalg.norm(parts, axis=1)) > 0.05
    np.testing.assert_allclose(c["normal"][t], path[t] / np.linalg.norm(path[t], axis=1)[:, None], atol=1e-3)
    # the lattice's z (along the normal) comes back along the normal, x and y in the tangent plane:
    # a texture with axes (1, 1, 0) adds nothing along the touched point's normal
    flat_only = hf.surface_contact(hf.sphere_surface(radius=R), [hf.on_surface(
        hf.lattice_texture(sigma=1.0, gain=0.5, axes=(1, 1, 0)), scale=(0.2, 0.1))], stiffness=K)
    g = flat_only.contacts(path, velocities=np.gradient(path, 1e-3, axis=0))
    tangential = (g["force"] - g["contact_force"])[t]
    assert np.max(np.linalg.norm(tangential, axis=1)) > 0.05
    along = np.einsum("ij,ij->i", tangential, g["normal"][t])
    np.testing.assert_allclose(along, 0.0, atol=1e-9)


# --- the servo loop ----------------------------------------------------------------

def test_run_servo_on_a_relief_ends_without_safety_events(coffee):
    # the simulated arm starts near z = -16 mm; the relief lies below it and the hand presses into it
    relief = hf.height_field_from_picture(coffee, pixel_size=6e-4, mm_per_level=0.004, blur=2.0,
                                          origin=(-0.1, -0.08, -0.022))
    image = hf.tangible_field(coffee, workspace_mm=80.0, gain=0.5)
    field = hf.surface_contact(relief, [hf.on_surface(image, scale=0.08, offset=-0.04),
                                        hf.friction(coulomb=0.3, scale_with_normal_force=True)],
                               stiffness=K, damping=0.5)
    result = hf.run_servo(field, seconds=2.0, hand_centre=(0.0, 0.0, -0.024), hand_size=0.04)
    stats, trace = result["statistics"], result["trace"]
    assert result["stop_reason"] == "tick_limit" and stats["ticks"] == 2000
    # no latch; the safety events counted are the soft start's clamps (the arm lands on the relief while the
    # force limit ramps up after arming) and the slew limit at that first contact
    assert stats["latches"] == 0 and stats["last_latch"] == "" and stats["missed_deadlines"] == 0
    assert stats["peak_force_n"] > 0.5  # it pressed on the relief [N]
    assert np.all(np.isfinite(trace["force"]))
    assert np.all(np.linalg.norm(trace["force"], axis=1) <= result["max_force_n"] + 1e-12)
    # the same run twice renders the same forces (virtual clock)
    field.reset()
    again = hf.run_servo(field, seconds=2.0, hand_centre=(0.0, 0.0, -0.024), hand_size=0.04)
    np.testing.assert_array_equal(trace["force"], again["trace"]["force"])


@pytest.mark.parametrize("shape", ["sphere", "icosphere mesh"])
def test_run_servo_into_a_ball_ends_without_safety_events(tmp_path, shape):
    # the hand rasters at z = -8 mm through a ball of 10 mm on its first row: the arm meets the ball after
    # the soft start (0.8 s in), and the force grows within the slew limit: no clamp, no event at all
    centre = (0.03, 0.03, -0.008)
    if shape == "sphere":
        ball = hf.sphere_surface(centre=centre, radius=0.01)
    else:
        v, f = icosphere(3)
        write_stl(tmp_path / "ball.stl", v * 10.0, f)  # [mm]
        ball = hf.mesh_surface(tmp_path / "ball.stl", scale=1e-3, origin=centre)
    texture = hf.on_surface(hf.lattice_texture(sigma=0.5, gain=0.1, scale_with_normal_force=True, axes=(1, 1, 0)),
                            scale=0.03)
    field = hf.surface_contact(ball, [texture], stiffness=1500.0, damping=0.5)
    result = hf.run_servo(field, seconds=3.0)
    stats, trace = result["statistics"], result["trace"]
    assert stats["ticks"] == 3000 and result["stop_reason"] == "tick_limit"
    assert stats["safety_events"] == 0 and stats["latches"] == 0 and stats["missed_deadlines"] == 0
    assert stats["peak_force_n"] > 1.0  # it pushed the hand back off the ball [N]
    touching = np.linalg.norm(trace["force"], axis=1) > 0.0
    out = trace["position"][touching] - centre
    # pushed along the radius, from inside the ball
    radial = np.einsum("ij,ij->i", trace["force"][touching], out / np.linalg.norm(out, axis=1)[:, None])
    assert np.all(np.linalg.norm(out, axis=1) < 0.0101) and np.all(radial > 0.0)


def test_a_part_of_a_running_surface_is_refused_to_other_threads():
    lattice = hf.lattice_texture()
    field = hf.surface_contact(hf.sphere_surface(), [hf.on_surface(lattice)])
    token = hf.ServoStop()
    worker = threading.Thread(target=lambda: hf.run_servo(field, seconds=3600.0, clock="wall", stop=token))
    worker.start()
    try:
        while not token.running:
            time.sleep(0.005)
        with pytest.raises(RuntimeError, match="in use"):
            lattice.forces(np.zeros((1, 3)))
    finally:
        token.request()
        worker.join()
    lattice.forces(np.zeros((1, 3)))  # free again


# --- bad inputs ----------------------------------------------------------------------

@pytest.mark.parametrize("make,error,words", [
    (lambda: hf.height_field(np.array([[0.0, np.nan], [0.0, 0.0]])), ValueError, "row 0, column 1 is not finite"),
    (lambda: hf.height_field(np.array([[0.0, 0.0], [np.inf, 0.0]], dtype=np.float32)), ValueError, "not finite"),
    (lambda: hf.height_field(np.zeros((0, 0))), ValueError, "at least 2 x 2"),
    (lambda: hf.height_field(np.zeros((1, 5))), ValueError, "at least 2 x 2"),
    (lambda: hf.height_field(np.zeros(9)), ValueError, "2-D"),
    (lambda: hf.height_field(np.broadcast_to(np.float32(0.0), (10001, 10001))), ValueError, "100 Mpx"),
    (lambda: hf.height_field(np.array([["a", "b"], ["c", "d"]])), TypeError, "float64 or float32"),
    (lambda: hf.height_field(np.zeros((3, 3)), spacing=0.0), ValueError, "spacing"),
    (lambda: hf.height_field(np.zeros((3, 3)), spacing=(1e-3, np.nan)), ValueError, "spacing"),
    (lambda: hf.height_field(np.zeros((3, 3)), origin=(0, np.inf, 0)), ValueError, "origin"),
    (lambda: hf.height_field(np.zeros((3, 3)), max_nodes=0), ValueError, "max_nodes"),
    (lambda: hf.height_field_from_picture(np.zeros((0, 0), dtype=np.uint8)), ValueError, "empty"),
    (lambda: hf.height_field_from_picture(np.full((4, 4), 300.0), levels=255.0), ValueError, "within [0, 255"),
    (lambda: hf.height_field_from_picture(np.full((4, 4), 0.5)), ValueError, "levels="),
    (lambda: hf.height_field_from_picture(np.zeros((4, 4), np.uint8), channels="grb"), ValueError, "channels"),
    (lambda: hf.height_field_from_picture(np.zeros((4, 4), np.uint8), mm_per_level=-1.0), ValueError, "mm_per_level"),
    (lambda: hf.height_field_from_picture(np.zeros((4, 4), np.uint8), blur=np.nan), ValueError, "blur"),
    (lambda: hf.height_field_from_picture("/nonexistent/photo.png"), OSError, "photo.png"),
    (lambda: hf.depth_map("/nonexistent/depth.png"), OSError, "depth.png"),
    (lambda: hf.depth_map("/nonexistent/depth.exr"), hf.FileError, "OpenEXR"),
    (lambda: hf.depth_map(3), TypeError, "path"),
    (lambda: hf.mesh_surface("/nonexistent/ball.stl"), OSError, "ball.stl"),
    (lambda: hf.mesh_surface("/nonexistent/ball.ply"), hf.FileError, "unknown mesh format"),
    (lambda: hf.mesh_surface("/nonexistent/ball.obj", scale=0.0), ValueError, "scale"),
    (lambda: hf.plane_surface(normal=(0, 0, 2)), ValueError, "unit"),
    (lambda: hf.sphere_surface(radius=-1.0), ValueError, "radius"),
    (lambda: hf.surface_contact(hf.sphere_surface(), stiffness=0.0), ValueError, "stiffness"),
    (lambda: hf.surface_contact(hf.sphere_surface(), damping=-1.0), ValueError, "damping"),
    (lambda: hf.surface_contact(hf.sphere_surface(), static_friction=0.2, dynamic_friction=0.3), ValueError,
     "dynamic_friction"),
    (lambda: hf.surface_contact(hf.sphere_surface(), tick_node_budget=-1), ValueError, "tick_node_budget"),
    (lambda: hf.surface_contact(hf.sphere_surface(), tick_node_budget=1 << 32), ValueError, "tick_node_budget"),
    (lambda: hf.on_surface(hf.zero(), scale=(np.nan, 1.0)), ValueError, "finite"),
    (lambda: hf.surface_contact(hf.sphere_surface()).contacts(np.zeros((3, 2))), ValueError, "N x 3"),
    (lambda: hf.surface_contact(hf.sphere_surface()).contacts(np.zeros((3, 3)), period=0.0), ValueError,
     "period"),
])
def test_bad_inputs_raise_clear_errors(make, error, words):
    with pytest.raises(error, match=None) as e:
        make()
    assert words in str(e.value)


HOSTILE = {
    "short.stl": b"\0" * 80 + struct.pack("<I", 1_000_000) + b"\1" * 50,  # declares 1M facets, holds one
    "nan.stl": b"\0" * 80 + struct.pack("<I", 1) + struct.pack("<12fH", 0, 0, 1, *[float("nan")] * 9, 0),
    "indices.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n",
    "nan.obj": b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
    "empty.obj": b"# nothing\n",
    "broken.gltf": b'{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 1e12, "uri": "data.bin"}], "mesh',
    "buffers.gltf": b'{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 999999999999, "uri": "../../x.bin"}],'
                    b' "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}',
    "junk.glb": b"glTF\2\0\0\0" + struct.pack("<I", 1 << 31) + b"\xff" * 64,
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_a_hostile_mesh_file_raises_not_crashes(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(HOSTILE[name])
    with pytest.raises((hf.Error, ValueError)) as e:
        hf.mesh_surface(path)
    assert name in str(e.value) or "mesh" in str(e.value)


def test_a_hostile_depth_map_raises(tmp_path):
    eight_bit = tmp_path / "eight.png"
    write_png(eight_bit, np.zeros((4, 4), np.uint8), 8)
    with pytest.raises(hf.FileError, match="8-bit"):
        hf.depth_map(eight_bit)
    huge = tmp_path / "huge.png"  # declares 100000 x 100000 px in its header
    write_png(huge, np.zeros((1, 1), np.uint16), 16)
    data = bytearray(huge.read_bytes())
    data[16:24] = struct.pack(">II", 100000, 100000)
    huge.write_bytes(bytes(data))
    with pytest.raises(hf.FileError):
        hf.depth_map(huge)
    garbage = tmp_path / "garbage.png"
    garbage.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 40)
    with pytest.raises(hf.FileError):
        hf.depth_map(garbage)


# --- a picture as a relief in one line ----------------------------------------------

def test_picture_relief_is_the_relief_with_the_tangible_image_laid_on_it(coffee):
    # the one-liner against the same scene composed from the pieces: the relief from the picture, and the
    # tangible image centred on the flat frame at the relief's pitch, laid on it by uv
    width, mm, gain = 0.1, 0.02, 1.5
    one = hf.picture_relief(coffee, mm_per_level=mm, width_m=width, texture_gain=gain, stiffness=K)
    relief = hf.height_field_from_picture(coffee, mm_per_level=mm, pixel_size=1.0)  # for its size only
    w, h = relief.samples
    pitch = width / (w - 1)
    relief = hf.height_field_from_picture(coffee, mm_per_level=mm, pixel_size=pitch)
    footprint = np.array(relief.footprint)
    image = hf.tangible_field(coffee, px_per_mm=1e-3 / pitch, gain=gain)
    composed = hf.surface_contact(relief, [hf.on_surface(image, scale=tuple(footprint), offset=tuple(-footprint / 2))],
                                  stiffness=K)
    a = np.linspace(0, 2 * np.pi, 3000)
    centre = footprint / 2
    path = np.vstack([press((centre[0], centre[1], 0.01), (centre[0], centre[1], 0.0), 100),
                      np.column_stack([centre[0] + 0.02 * np.sin(a), centre[1] + 0.015 * (1 - np.cos(a)),
                                       np.full_like(a, 0.0)])])
    v = np.gradient(path, 1e-3, axis=0)
    c = one.contacts(path, velocities=v)
    assert c["touching"][100:].mean() > 0.9
    parts = c["force"] - c["contact_force"]
    assert np.max(np.linalg.norm(parts, axis=1)) > 0.2  # the picture pushes along the relief [N]
    np.testing.assert_allclose(c["force"], composed.forces(path, velocities=v), atol=1e-9)


def test_picture_relief_from_an_array_and_its_bad_inputs():
    picture = np.zeros((20, 30), dtype=np.uint8)
    picture[:, 15:] = 255  # white (high) on the right
    relief = hf.picture_relief(picture, mm_per_level=0.01, width_m=0.029, texture_gain=0.0, stiffness=K)
    f = relief.forces(press((0.025, 0.01, 0.006), (0.025, 0.01, 0.002)))[-1]
    np.testing.assert_allclose(f, [0.0, 0.0, K * 0.55e-3], atol=1e-9)  # the white plateau, 2.55 mm high
    with pytest.raises(ValueError, match="width_m"):
        hf.picture_relief(picture, width_m=0.0)
    with pytest.raises(ValueError, match="texture_gain"):
        hf.picture_relief(picture, texture_gain=-1.0)
    with pytest.raises(ValueError, match="2 x 2"):
        hf.picture_relief(np.zeros((1, 5), dtype=np.uint8))
    with pytest.raises(ValueError, match="levels="):
        hf.picture_relief(picture / 255.0)  # a float picture without its white level
    np.testing.assert_allclose(
        hf.picture_relief(picture[:, :, None].repeat(3, axis=2) / 255.0, levels=1.0, channels="bgr", width_m=0.029,
                          texture_gain=0.0, stiffness=K).forces(press((0.025, 0.01, 0.006), (0.025, 0.01, 0.002)))[-1],
        f, atol=1e-9)
    with pytest.raises(OSError, match="photo.png"):
        hf.picture_relief("/nonexistent/photo.png")


def test_the_surfaces_example_runs_and_feels_k_depth(coffee):
    # python/examples/surfaces.py is the example of python/README.md and docs/surfaces.md
    import subprocess
    import sys
    example = pathlib.Path(__file__).resolve().parents[1] / "examples" / "surfaces.py"
    r = subprocess.run([sys.executable, str(example), "--picture", coffee], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    assert "touching 100% of ticks, normal force 1.50 N" in r.stdout  # k x 1 mm
    assert "latches 0" in r.stdout and "picture relief of coffee.png" in r.stdout


@pytest.mark.parametrize("doc,heading", [("python/README.md", "## Surfaces"), ("docs/surfaces.md", "## From Python")])
def test_the_docs_show_the_example_s_code(doc, heading):
    root = pathlib.Path(__file__).resolve().parents[2]
    text = (root / doc).read_text()
    start = text.index("```python\n", text.index(heading)) + len("```python\n")
    block = text[start:text.index("```", start)]
    example = (root / "python" / "examples" / "surfaces.py").read_text()
    body = "\n".join(("    " + line) if line else "" for line in block.splitlines()[3:])  # after the imports
    assert body.replace('"examples/data/coffee.png"', "a.picture") in example
