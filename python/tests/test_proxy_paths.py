"""contacts(paths=True): the way the proxy went in each tick, checked piece by piece against a brute-force scan of
every triangle written here in numpy (not the library's tree): no piece passes through a face from its front."""
import os
import pathlib
import random

import numpy as np
import pytest

import hapticfield as hf

SHARED = pathlib.Path(os.environ.get("HAPTICFIELD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2])) \
    .parent / "shared" / "data"


def crossings(a, b, vertices, faces):
    """Indices of the triangles the segment a -> b passes through from the front (a in front of the plane, b
    behind it, the crossing inside the triangle), by a plain scan of all of them."""
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    n = np.cross(v1 - v0, v2 - v0)  # toward the front (counter-clockwise faces)
    size = np.linalg.norm(n, axis=1)
    ha, hb = np.einsum("ij,ij->i", n, a - v0), np.einsum("ij,ij->i", n, b - v0)
    # clearly in front, then clearly behind: more than 1e-9 of the triangle's size off its plane
    margin = 1e-9 * size * np.sqrt(size)
    through = (ha > margin) & (hb < -margin)
    s = np.where(through, ha / np.where(through, ha - hb, 1.0), 0.0)
    p = a + s[:, None] * (b - a)
    # inside: on the inner side of all three edges (the plane's own normal decides)
    inside = np.ones(len(faces), bool)
    for e0, e1 in ((v0, v1), (v1, v2), (v2, v0)):
        inside &= np.einsum("ij,ij->i", np.cross(e1 - e0, p - e0), n) > 0.0
    return np.nonzero(through & inside)[0]


def slab(thickness=3e-4, half=0.01):
    """A closed box 2 half wide and `thickness` thick about z = 0, faces out [m]."""
    x0, y0, z0, x1, y1, z1 = -half, -half, -thickness / 2, half, half, thickness / 2
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]])
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [2, 3, 7], [2, 7, 6], [0, 4, 7], [0, 7, 3], [1, 2, 6], [1, 6, 5]])
    return v, f


def check_paths(c, vertices, faces, what):
    """Each tick's path starts where the last one stayed and ends at the proxy; no piece crosses a face."""
    path, proxy = c["path"], c["proxy"]
    assert len(path) == len(proxy)
    pieces = 0
    for k, points in enumerate(path):
        assert points.ndim == 2 and points.shape[1] == 3 and len(points) >= 1, f"{what}: tick {k}"
        np.testing.assert_array_equal(points[-1], proxy[k], err_msg=f"{what}: tick {k} ends off the proxy")
        if k > 0:
            np.testing.assert_array_equal(points[0], proxy[k - 1], err_msg=f"{what}: tick {k} starts elsewhere")
        for q in range(len(points) - 1):
            pieces += 1
            hit = crossings(points[q], points[q + 1], vertices, faces)
            assert hit.size == 0, f"{what}: tick {k}, piece {q} passes through triangle {hit[0]}"
    return pieces


def test_the_oracle_finds_a_piece_through_a_face_and_passes_one_beside_it():
    v, f = slab()
    assert crossings(np.array([0.001, 0.002, 0.01]), np.array([0.001, 0.002, 0.0]), v, f).size == 1  # the top
    assert crossings(np.array([0.001, 0.002, 0.01]), np.array([0.001, 0.002, -0.01]), v, f).size == 1  # not the
    # bottom, met from behind; beside the slab, nothing
    assert crossings(np.array([0.02, 0.0, 0.01]), np.array([0.02, 0.0, -0.01]), v, f).size == 0


def test_paths_of_random_presses_and_slides_over_a_thin_slab_never_pass_through_it():
    # a 0.3 mm slab, 20 mm wide: presses straight down at up to 2 m/s, and slides pressed 1 mm in across it and
    # off its edges at 26 mm/s and 2 m/s, random starts and directions, a point and a 0.5 mm ball
    seed = random.randrange(1 << 32)
    rng = np.random.default_rng(seed)
    v, f = slab()
    surface = hf.mesh_surface_from_arrays(v, f)
    pieces = 0
    for radius in (0.0, 0.0005):
        for trial in range(12):
            field = hf.surface_contact(surface, stiffness=1500.0, static_friction=0.4, dynamic_friction=0.3,
                                       radius=radius)
            speed = (0.026, 2.0)[trial % 2]
            start = np.append(rng.uniform(-0.008, 0.008, 2), 0.003 + radius)
            heading = rng.normal(size=2)
            heading /= np.linalg.norm(heading)
            down = start + np.linspace(0.0, 1.0, 40)[:, None] * ([0.0, 0.0, -0.0042 - radius])
            ticks = int(0.03 / (speed * 1e-3)) if speed < 1 else 40
            along = down[-1] + (np.arange(1, ticks + 1) * speed * 1e-3)[:, None] * np.append(heading, 0.0)
            probes = np.vstack([down, along])
            c = field.contacts(probes, velocities=np.gradient(probes, 1e-3, axis=0), paths=True)
            assert c["touching"].any(), f"seed {seed}: radius {radius}, trial {trial} never touched"
            pieces += check_paths(c, v, f, f"seed {seed}: radius {radius}, trial {trial}")
    assert pieces > 1000


def test_the_bunny_ear_s_jump_goes_round_the_rim_piece_by_piece():
    # stanford-bunny.obj in its own units, the probe down through the ear: at t = 0.498 s the proxy goes 2.86 mm in
    # one tick from the ear's top to its far side. The straight chord from where it started to where it stayed
    # cuts the ear's tip; the pieces it took go round the rim, and none passes through a face.
    path = SHARED / "meshes" / "stanford-bunny.obj"
    if not path.exists():
        pytest.skip(f"{path} is absent")
    vertices, faces = read_obj(path)
    t = np.arange(500) * 1e-3
    probes = np.column_stack([np.full(500, -0.03), 0.170 - 0.026 * t, np.zeros(500)])
    c = hf.surface_contact(hf.mesh_surface(path)).contacts(probes, velocities=np.tile([0.0, -0.026, 0.0], (500, 1)),
                                                         paths=True)
    jumps = np.linalg.norm(np.diff(c["proxy"], axis=0), axis=1)
    k = int(np.argmax(jumps)) + 1
    assert k == 498 and jumps[k - 1] > 2e-3
    chord = crossings(c["proxy"][k - 1], c["proxy"][k], vertices, faces)
    assert chord.size >= 1  # the straight chord would pass through the ear
    ear = c["path"][k]
    assert len(ear) >= 4 and np.linalg.norm(np.diff(ear, axis=0), axis=1).sum() > jumps[k - 1]
    check_paths(c, vertices, faces, "bunny")


def read_obj(path):
    """An OBJ's vertices and triangles (fans of its polygons), read here, not by the library."""
    vertices, faces = [], []
    with open(path) as text:
        for line in text:
            word = line.split()
            if not word:
                continue
            if word[0] == "v":
                vertices.append([float(x) for x in word[1:4]])
            elif word[0] == "f":
                corner = [int(w.split("/")[0]) for w in word[1:]]
                corner = [c - 1 if c > 0 else len(vertices) + c for c in corner]
                faces.extend([corner[0], corner[i], corner[i + 1]] for i in range(1, len(corner) - 1))
    return np.array(vertices), np.array(faces)
