"""Run by run_wheel.cmake: the wheel's files are the package's, and its RECORD hashes every one of them."""
import base64
import hashlib
import sys
import zipfile

with zipfile.ZipFile(sys.argv[1]) as z:
    names = z.namelist()
    dist_info = next(n.split("/")[0] for n in names if n.endswith(".dist-info/WHEEL"))
    package = sorted(n for n in names if not n.startswith(dist_info))
    assert len(package) == 4 and package[0].startswith("hapticfield/__init__.") and package[0].endswith(".so"), package
    assert package[1:] == ["hapticfield/__init__.pyi", "hapticfield/batch.py", "hapticfield/py.typed"], package
    wheel = z.read(f"{dist_info}/WHEEL").decode()
    assert "Root-Is-Purelib: false" in wheel and "Wheel-Version: 1.0" in wheel, wheel
    metadata = z.read(f"{dist_info}/METADATA").decode()
    assert "Name: hapticfield" in metadata and "Requires-Dist: numpy" in metadata, metadata
    rows = [line.split(",") for line in z.read(f"{dist_info}/RECORD").decode().splitlines()]
    assert sorted(r[0] for r in rows) == sorted(names), (rows, names)
    for path, digest, size in rows:
        if path == f"{dist_info}/RECORD":
            assert digest == "" and size == "", (path, digest, size)
            continue
        data = z.read(path)
        expected = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        assert digest == f"sha256={expected}" and int(size) == len(data), (path, digest, size)
print(f"{sys.argv[1]}: {len(names)} files, RECORD matches")
