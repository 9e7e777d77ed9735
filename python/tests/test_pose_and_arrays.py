"""Placing shapes (Pose, pose=) and meshes from numpy arrays, against closed forms: a posed plane pushes k depth
along its turned normal, a posed mesh feels like its vertices moved one by one, the arrays are checked row by row,
a broadcast array is refused before anything is allocated, and the same file and path give the same forces here
as in feel_shape (one force-shading default)."""
import os
import pathlib
import random
import resource
import subprocess
import sys
import time

import numpy as np
import pytest

import hapticfield as hf
from grid_meshes import wavy_grid, wavy_height

SEED = int(os.environ.get("HAPTICFIELD_TEST_SEED", random.SystemRandom().randrange(2 ** 32)))
print(f"test_pose_and_arrays: seed {SEED} (repeat with HAPTICFIELD_TEST_SEED={SEED})")


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    return q  # w, x, y, z


def quaternion_matrix(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def box_arrays(lo=(-0.01, -0.015, -0.005), hi=(0.012, 0.01, 0.008)):
    """An axis-aligned box, 12 triangles facing out."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]])
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [2, 3, 7], [2, 7, 6], [0, 4, 7], [0, 7, 3], [1, 2, 6], [1, 6, 5]])
    return v, f


def octahedron_stl(path, r=0.02):
    pts = [(r, 0, 0), (-r, 0, 0), (0, r, 0), (0, -r, 0), (0, 0, r), (0, 0, -r)]
    faces = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    with open(path, "w") as out:
        out.write("solid o\n")
        for face in faces:
            out.write("facet normal 0 0 0\nouter loop\n")
            for k in face:
                out.write("vertex %r %r %r\n" % pts[k])
            out.write("endloop\nendfacet\n")
        out.write("endsolid o\n")
    return path


def test_pose_forms_agree_and_bad_rotations_are_refused():
    a = hf.Pose.about((0, 0, 1), 90.0, translation=(1, 2, 3))
    b = hf.Pose(np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]), (1, 2, 3))
    c = hf.Pose((np.sqrt(0.5), 0, 0, np.sqrt(0.5)), (1, 2, 3))
    for p in (b, c):
        np.testing.assert_allclose(p.rotation, a.rotation, atol=1e-15)
        assert p.translation == pytest.approx([1, 2, 3])
    assert "Pose(rotation=" in repr(a)
    for bad, says in [(np.diag([-1.0, 1, 1]), "reflection"), (np.diag([2.0, 1, 1]), "orthonormal"),
                      ((1.0, 0.1, 0, 0), "unit length"), ((np.nan, 0, 0, 0), "quaternion"),
                      (np.eye(2), "3 x 3 matrix or a quaternion"), ((1, 0, 0), "got shape (3,)")]:
        with pytest.raises(ValueError, match=r".*" + says.replace("(", r"\(").replace(")", r"\)")):
            hf.Pose(bad)
    with pytest.raises(ValueError, match="translation"):
        hf.Pose(None, (0, np.inf, 0))
    with pytest.raises(ValueError, match="pose or origin, not both"):
        hf.height_field(np.zeros((3, 3)), origin=(0, 0, 0), pose=hf.Pose())


def test_a_posed_plane_pushes_k_depth_along_its_turned_normal():
    rng = np.random.default_rng(SEED)
    for _ in range(10):
        q = random_rotation(rng)
        t = rng.uniform(-0.1, 0.1, 3)
        pose = hf.Pose(q, t)
        n = quaternion_matrix(q) @ np.array([0.0, 0.0, 1.0])
        field = hf.surface_contact(hf.plane_surface(pose=pose), stiffness=1500.0)
        depths = np.linspace(0.0, 0.003, 31)[1:]
        path = np.vstack([t + 0.01 * n, t[None, :] - depths[:, None] * n[None, :]])
        f = field.forces(path)
        np.testing.assert_allclose(f[1:], 1500.0 * depths[:, None] * n[None, :], atol=1e-9)


def test_a_posed_mesh_feels_like_its_vertices_moved(tmp_path):
    rng = np.random.default_rng(SEED + 1)
    v, f = box_arrays()
    for _ in range(5):
        q = random_rotation(rng)
        t = rng.uniform(-0.1, 0.1, 3)
        R = quaternion_matrix(q)
        posed = hf.mesh_surface_from_arrays(v, f, pose=hf.Pose(q, t))
        moved = hf.mesh_surface_from_arrays(v @ R.T + t, f)
        lo, hi = posed.bounds
        np.testing.assert_allclose(lo, (v @ R.T + t).min(axis=0), atol=1e-15)
        np.testing.assert_allclose(hi, (v @ R.T + t).max(axis=0), atol=1e-15)
        # a stroke from above the box's top down through it, in the box's frame, then turned
        s = np.linspace(0.0, 1.0, 300)[:, None]
        local = (1 - s) * np.array([rng.uniform(-0.008, 0.01), rng.uniform(-0.012, 0.008), 0.03]) + \
            s * np.array([rng.uniform(-0.008, 0.01), rng.uniform(-0.012, 0.008), 0.004 + 1e-4 * rng.uniform()])
        path = local @ R.T + t
        a = hf.surface_contact(posed, stiffness=1500.0).contacts(path)
        b = hf.surface_contact(moved, stiffness=1500.0).contacts(path)
        assert a["touching"].any()
        np.testing.assert_array_equal(a["touching"], b["touching"])
        np.testing.assert_allclose(a["force"], b["force"], atol=1e-6)
        np.testing.assert_allclose(a["proxy"], b["proxy"], atol=1e-9)
        np.testing.assert_allclose(a["normal"], b["normal"], atol=1e-9)

    # the same file through mesh_surface with a pose
    stl = octahedron_stl(tmp_path / "octa.stl")
    q = random_rotation(rng)
    t = rng.uniform(-0.1, 0.1, 3)
    posed = hf.mesh_surface(stl, pose=hf.Pose(q, t))
    assert posed.pose.translation == pytest.approx(t)
    np.testing.assert_allclose(posed.pose.rotation, quaternion_matrix(q), atol=1e-15)
    path = np.array([[0.004, 0.004 + 5e-5 * i, 0.03 - 3e-4 * i] for i in range(101)]) @ quaternion_matrix(q).T + t
    plain = hf.mesh_surface(stl)
    fa = hf.surface_contact(posed).forces(path)
    fb = hf.surface_contact(plain).forces((path - t) @ quaternion_matrix(q))
    np.testing.assert_allclose(fa, fb @ quaternion_matrix(q).T, atol=1e-6)


def test_origin_still_moves_a_shape():
    a = hf.height_field(np.zeros((4, 5)), spacing=1e-3, origin=(1.0, 2.0, 3.0))
    b = hf.height_field(np.zeros((4, 5)), spacing=1e-3, pose=hf.Pose(translation=(1.0, 2.0, 3.0)))
    assert a.bounds == b.bounds
    np.testing.assert_allclose(a.bounds, [[1.0, 2.0, 3.0], [1.004, 2.003, 3.0]], atol=1e-15)
    sphere = hf.sphere_surface(radius=0.01, pose=hf.Pose.about((1, 0, 0), 30.0, (0.0, 0.1, 0.0)))
    np.testing.assert_allclose(sphere.bounds, [[-0.01, 0.09, -0.01], [0.01, 0.11, 0.01]], atol=1e-15)


def test_mesh_from_arrays_gives_the_closed_form_and_says_what_it_does():
    v, f = box_arrays((-0.01, -0.01, -0.01), (0.01, 0.01, 0.01))
    uvs = v[:, :2] * 10 + 0.5
    for shade in (True, False):
        s = hf.mesh_surface_from_arrays(v.astype(np.float32), f.astype(np.uint32), uvs=uvs, shade_normals=shade)
        assert s.kind == "mesh" and s.triangles == 12 and s.warnings == []
        assert s.normals == ("vertex normals from the faces (force shading)" if shade else "face normals (flat facets)")
    # given normals win (all +z here): the top pushes straight up with k depth at any point of it
    s = hf.mesh_surface_from_arrays(v, f, normals=np.tile([0.0, 0.0, 2.0], (8, 1)))
    assert s.normals == "the file's vertex normals (force shading)"
    path = np.array([[0.003, -0.004, 0.02], [0.003, -0.004, 0.009], [0.0035, -0.004, 0.008]])
    force = hf.surface_contact(s, stiffness=1000.0).forces(path)
    np.testing.assert_allclose(force[1:], [[0, 0, 1.0], [0, 0, 2.0]], atol=1e-9)
    # a triangle with no area among others: kept, named in the warnings
    s = hf.mesh_surface_from_arrays(np.vstack([v, [[0.0, 0.0, 0.0]]]), np.vstack([f, [[0, 0, 1]]]))
    assert s.warnings == ["1 of 13 triangles have zero area (kept; the surface skips them)"]


@pytest.mark.parametrize("args, error, says", [
    (lambda v, f: (v[:, :2], f), ValueError, r"vertices: expected an N x 3 array, got shape \(8, 2\)"),
    (lambda v, f: (v, f.astype(float)), ValueError, "faces: expected integer indices, got dtype float64"),
    (lambda v, f: (v.astype(str), f), ValueError, "vertices: expected real numbers"),
    (lambda v, f: (v, f - 1), ValueError, "faces: row 0 uses vertex -1 of 8"),
    (lambda v, f: (v, f + 1), ValueError, "faces: row 3 uses vertex 8 of 8"),
    (lambda v, f: (np.where(np.arange(8)[:, None] == 5, np.nan, v), f), ValueError, "vertices: row 5 is not finite"),
    (lambda v, f: (v, f[:0]), ValueError, "no triangles"),
    (lambda v, f: (v, np.zeros((2, 3), dtype=int)), ValueError, "all 2 triangles have zero area"),
    (lambda v, f: (np.broadcast_to(v[:1], (8, 3)), f), ValueError, "broadcast array"),
    (lambda v, f: (v, np.broadcast_to(f[:1], (10 ** 6, 3))), ValueError, "faces: a broadcast array"),
])
def test_mesh_from_arrays_refuses_bad_arrays(args, error, says):
    v, f = box_arrays()
    with pytest.raises(error, match=says):
        hf.mesh_surface_from_arrays(*args(v, f))


def test_mesh_from_arrays_checks_uvs_and_normals():
    v, f = box_arrays()
    with pytest.raises(ValueError, match=r"uvs: expected an N x 2 array"):
        hf.mesh_surface_from_arrays(v, f, uvs=np.zeros((8, 3)))
    with pytest.raises(ValueError, match=r"uvs: need one row per vertex \(8\)"):
        hf.mesh_surface_from_arrays(v, f, uvs=np.zeros((7, 2)))
    with pytest.raises(ValueError, match="uvs: row 2 is not finite"):
        hf.mesh_surface_from_arrays(v, f, uvs=np.where(np.arange(8)[:, None] == 2, np.inf, np.zeros((8, 2))))
    with pytest.raises(ValueError, match="normals: row 0 is zero or not finite"):
        hf.mesh_surface_from_arrays(v, f, normals=np.zeros((8, 3)))
    with pytest.raises(ValueError, match="max_triangles"):
        hf.mesh_surface_from_arrays(v, f, max_triangles=0)
    with pytest.raises(ValueError, match="faces: 12 rows, more than the limit of 11"):
        hf.mesh_surface_from_arrays(v, f, max_triangles=11)


# Run in a fresh interpreter: how many bytes of its mappings a mesh of 400 x 400 vertices (318 402 triangles, a tree
# of some 50 MB) marks for transparent huge pages (VmFlags "hg" in /proc/self/smaps) with huge_pages=argv[1].
MARKED_BY_A_MESH = """
import sys
import hapticfield as hf
sys.path.insert(0, sys.argv[2])
from grid_meshes import wavy_grid

def marked():
    total = size = 0
    with open("/proc/self/smaps") as smaps:
        for line in smaps:
            if line.startswith("Size:"):
                size = int(line.split()[1]) * 1024
            elif line.startswith("VmFlags:") and "hg" in line.split()[1:]:
                total += size
    return total

v, f = wavy_grid(400)
before = marked()
surface = hf.mesh_surface_from_arrays(v, f, huge_pages=sys.argv[1] == "on")
print(marked() - before)
"""


def transparent_huge_pages_offered():
    try:
        return "[never]" not in pathlib.Path("/sys/kernel/mm/transparent_hugepage/enabled").read_text()
    except OSError:
        return False


def test_huge_pages_moves_the_mesh_not_its_forces(tmp_path):
    # the same forces, contacts and proxy bit for bit with the mesh on 2 MB pages and off them: strokes pressed
    # 0.2-2 mm into a wavy sheet of 20 000 triangles at random, from every maker of meshes
    rng = np.random.default_rng(SEED + 11)
    v, f = wavy_grid(101)
    for _ in range(3):
        start, end = rng.uniform(-0.04, 0.04, 2), rng.uniform(-0.04, 0.04, 2)
        s = np.linspace(0.0, 1.0, 400)[:, None]
        xy = (1 - s) * start + s * end
        down = np.minimum(1.0, 4 * s[:, 0])  # from 3 mm above the surface to `depth` under it, then along
        depth = rng.uniform(0.0002, 0.002)
        path = np.column_stack([xy, wavy_height(xy[:, 0], xy[:, 1]) + 0.003 * (1 - down) - depth * down])
        made = [hf.mesh_surface_from_arrays(v, f, huge_pages=h) for h in (True, False)]
        made += [hf.deforming_mesh(v, f, huge_pages=h) for h in (True, False)]
        runs = [hf.surface_contact(m, stiffness=1500.0, static_friction=0.4).contacts(path) for m in made]
        assert runs[0]["touching"].sum() > 100
        for run in runs[1:]:
            for key in ("touching", "force", "proxy", "normal"):
                np.testing.assert_array_equal(runs[0][key], run[key])
    stl = octahedron_stl(tmp_path / "octa.stl")
    path = np.array([[0.004, 0.004 + 5e-5 * i, 0.03 - 3e-4 * i] for i in range(101)])
    np.testing.assert_array_equal(hf.surface_contact(hf.mesh_surface(stl, huge_pages=False)).forces(path),
                                  hf.surface_contact(hf.mesh_surface(stl)).forces(path))
    with pytest.raises(TypeError):
        hf.mesh_surface_from_arrays(v, f, huge_pages="yes")

    # the switch reaches the memory: each in a fresh process (the kernel's mark stays on an address range after
    # it is freed), tens of MB marked with it on, none with it off
    if not transparent_huge_pages_offered():
        pytest.skip("this kernel offers no transparent huge pages: only the forces were compared")
    here = str(pathlib.Path(__file__).parent)
    marked = {flag: int(subprocess.run([sys.executable, "-c", MARKED_BY_A_MESH, flag, here], capture_output=True,
                                       text=True, check=True).stdout) for flag in ("on", "off")}
    assert marked["on"] >= 20 << 20, marked
    assert marked["off"] == 0, marked


def test_a_broadcast_height_array_is_refused_at_once():
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"heights: a broadcast array \(stride 0 along axis 0\) is refused"):
        hf.height_field(np.broadcast_to(np.float32(0.001), (10000, 10000)))
    with pytest.raises(ValueError, match="overlap in memory"):
        base = np.zeros(20000)
        hf.height_field(np.lib.stride_tricks.as_strided(base, shape=(10000, 10000), strides=(8, 8)))
    assert time.perf_counter() - start < 1.0
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000  # kB: nothing near 800 MB
    # a real (owned) array of the same values is fine, a transposed view too
    s = hf.height_field(np.ascontiguousarray(np.broadcast_to(np.float32(0.001), (20, 30))).T)
    assert list(s.samples) == [20, 30]


def feel_shape_tool():
    """The feel_shape of the same build as the module (build/python/hapticfield next to build/examples), if any."""
    if os.environ.get("HAPTICFIELD_FEEL_SHAPE"):
        return pathlib.Path(os.environ["HAPTICFIELD_FEEL_SHAPE"])
    tool = pathlib.Path(hf.__file__).resolve().parents[2] / "examples" / "feel_shape"
    return tool if tool.exists() else None


@pytest.mark.parametrize("name", ["octa.stl", "octa_obj"])
def test_feel_shape_and_python_feel_the_same_file_the_same(tmp_path, name):
    tool = feel_shape_tool()
    if tool is None:
        pytest.skip("feel_shape is not built next to this module")
    if name == "octa.stl":
        shape = octahedron_stl(tmp_path / name)
    else:  # the same octahedron as an OBJ without normals
        shape = tmp_path / "octa.obj"
        r = 0.02
        shape.write_text(f"v {r} 0 0\nv {-r} 0 0\nv 0 {r} 0\nv 0 {-r} 0\nv 0 0 {r}\nv 0 0 {-r}\n"
                         "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n")
    t = np.arange(101) / 1000.0
    path = np.column_stack([np.full(101, 0.004), 0.004 + 5e-5 * np.arange(101), 0.03 - 3e-4 * np.arange(101)])
    probes = tmp_path / "press.csv"
    np.savetxt(probes, np.column_stack([t, path]), delimiter=",", header="t,x,y,z", comments="", fmt="%.17g")
    for flags, shade in (([], True), (["--facets"], False)):
        out = subprocess.run([str(tool), str(shape), "--probes", str(probes), *flags], capture_output=True,
                             text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        rows = np.loadtxt(out.stdout.splitlines()[1:], delimiter=",")
        f = hf.surface_contact(hf.mesh_surface(shape, shade_normals=shade)).forces(path)
        assert rows[:, 13].sum() > 20  # touching
        np.testing.assert_allclose(rows[:, 4:7], f, atol=1e-9)
        print(f"{name} {'shaded' if shade else 'facets'}: Fy at the end {rows[-1, 5]:.4f} N in feel_shape, "
              f"{f[-1, 1]:.4f} N in Python")
