"""Materials over uv from Python (material(), surface_contact(material=...)) against closed forms, and the glTF
extension MPEG_haptic_material written from numpy pictures and read back (save_haptic_material,
load_haptic_material) on a constructed model and on the Khronos Duck."""
import base64
import json
import os
import pathlib
import struct

import numpy as np
import pytest

import hapticfield as hf

SHARED = pathlib.Path(os.environ.get("HAPTICFIELD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2])) \
    .parent / "shared" / "data"


def flat(size=0.06, spacing=2e-3):
    """A flat height field at z = 0 over [-size/2, size/2]^2: uv (x, y) / size + 1/2."""
    n = int(round(size / spacing)) + 1
    return hf.height_field(np.zeros((n, n)), spacing=spacing, origin=(-size / 2, -size / 2, 0.0))


def press(x, y, depth, n=20):
    t = np.linspace(0.0, 1.0, n)[:, None]
    return np.array([x, y, 0.004]) * (1.0 - t) + np.array([x, y, -depth]) * t


def test_a_two_region_material_gives_each_side_its_stiffness_and_friction():
    m = hf.material(stiffness=np.array([[800.0, 2400.0]]), static_friction=np.array([[0.2, 0.8]]), clamp=True)
    assert m.sample(0.1, 0.5)["stiffness"] == pytest.approx(800.0)
    assert m.sample(0.9, 0.5)["dynamic_friction"] == pytest.approx(0.8)  # defaults to static_friction
    assert m.sample(0.5, 0.5)["stiffness"] == pytest.approx(1600.0)  # bilinear between the texel centres
    field = hf.surface_contact(flat(), material=m)
    assert "with material" in field.description
    for x, k, mu in ((-0.02, 800.0, 0.2), (0.02, 2400.0, 0.8)):  # u = 0.17 and 0.83: each side's own texel
        field.reset()
        f = field.forces(press(x, 0.0, 0.002))
        assert f[-1, 2] == pytest.approx(k * 0.002, rel=1e-6)  # Fn = k(uv) d
        # sliding along x at 2 mm depth: the friction cone gives |Ft| / Fn = mu once the proxy slides
        slide = np.column_stack([x + np.linspace(0.0, 0.004, 200), np.zeros(200), np.full(200, -0.002)])
        g = field.forces(slide)
        ratio = np.hypot(g[-50:, 0], g[-50:, 1]) / g[-50:, 2]
        np.testing.assert_allclose(ratio, mu, rtol=1e-6)


def test_a_relief_over_uv_gives_k_d_plus_h_and_leans_downhill():
    # an 11-column ramp, 0.5 mm at its top, clamped, on a 0.06 m footprint (uv = (x, y) / 0.06 + 1/2): between the
    # first and last texel centres h(u) is linear and the one-texel central differences exact
    size, top, k, depth, n = 0.06, 0.0005, 1200.0, 0.002, 11
    ramp = np.tile(np.linspace(0.0, top, n), (3, 1))
    field = hf.surface_contact(flat(size), [hf.on_surface(hf.uv_relief(ramp, k, size, clamp=True))], stiffness=k)
    slope = top / ((n - 1) / n * size)
    for u in np.linspace(1.6 / n, 1.0 - 1.6 / n, 9):
        field.reset()
        f = field.forces(press((u - 0.5) * size, 0.0, depth))
        h = top * (u * n - 0.5) / (n - 1)
        assert f[-1, 2] == pytest.approx(k * (depth + h), rel=1e-6)
        assert f[-1, 0] == pytest.approx(-(k * depth + k * h) * slope, rel=1e-6)
        assert f[-1, 1] == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(ValueError, match="heights"):
        hf.uv_relief(-0.001)


def test_bad_materials_are_one_value_error_each():
    with pytest.raises(ValueError, match="stiffness"):
        hf.material(stiffness=0.0)
    with pytest.raises(ValueError, match="not finite"):
        hf.material(stiffness=np.array([[1000.0, np.nan]]))
    with pytest.raises(ValueError, match="friction"):
        hf.material(static_friction=np.array([[0.2, -0.1]]))
    with pytest.raises(ValueError, match="vibration"):
        hf.material(vibration=-1)
    with pytest.raises(ValueError, match="H x W"):
        hf.material(stiffness=np.ones(4))


def quad_gltf(path, side=0.2):
    """A side x side square in z = 0 (normal +z), uv over it (glTF v down), as a self-contained .gltf."""
    positions = [0, 0, 0, side, 0, 0, side, side, 0, 0, side, 0]
    uvs = [0, 1, 1, 1, 1, 0, 0, 0]
    data = struct.pack("<12f", *positions) + struct.pack("<8f", *uvs) + struct.pack("<6H", 0, 1, 2, 0, 2, 3) + b"\0\0"
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [0, 0, 0], "max": [side, side, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                      {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0,
    }
    path.write_text(json.dumps(doc))
    return path


def test_a_haptic_material_written_from_numpy_pictures_reads_back_and_is_felt(tmp_path):
    if not hasattr(hf, "load_haptic_material"):
        pytest.skip("built without the glTF and .hjif readers")
    half = np.zeros((4, 4), np.uint8)
    half[:, 2:] = 255
    ids = np.array([[1, 2], [1, 2]], np.uint8)
    base = quad_gltf(tmp_path / "quad.gltf")
    out = tmp_path / "quad_haptic.glb"
    hf.save_haptic_material(base, out, stiffness=(half, 500.0, 2000.0), friction=(half, 0.1, 0.6), vibration=ids,
                            name="painted")
    m = hf.load_haptic_material(out)
    assert "painted" in m.description
    left, right = m.sample(0.3, 0.5), m.sample(0.7, 0.5)  # between two black, two white texel centres
    assert (left["stiffness"], right["stiffness"]) == (500.0, 2000.0)
    assert right["static_friction"] == pytest.approx(0.6, abs=1e-6)
    assert (left["vibration"], right["vibration"]) == (1, 2)
    field = hf.surface_contact(hf.mesh_surface(out), material=m)
    for x, k in ((0.06, 500.0), (0.14, 2000.0)):  # u = 0.3 and 0.7
        field.reset()
        f = field.forces(press(x, 0.1, 0.001))
        assert f[-1, 2] == pytest.approx(k * 0.001, rel=1e-6)
    with pytest.raises(ValueError, match="no 3"):
        hf.load_haptic_material(out, index=3)
    with pytest.raises(ValueError, match="at least one"):
        hf.save_haptic_material(base, out)
    with pytest.raises(hf.FileError):
        hf.load_haptic_material(tmp_path / "missing.gltf")


def test_the_duck_keeps_its_geometry_with_a_haptic_material(tmp_path):
    duck = SHARED / "gltf" / "Duck.gltf"
    if not duck.exists() or not hasattr(hf, "load_haptic_material"):
        pytest.skip("../shared/data/gltf/Duck.gltf absent, or built without the glTF reader")
    out = tmp_path / "duck.gltf"
    hf.save_haptic_material(duck, out, stiffness=(np.full((2, 2), 128, np.uint8), 300.0, 1300.0))
    before, after = hf.mesh_surface(duck), hf.mesh_surface(out)
    assert after.bounds == before.bounds
    assert hf.load_haptic_material(out).sample(0.5, 0.5)["stiffness"] == pytest.approx(300.0 + 1000.0 * 128 / 255)
