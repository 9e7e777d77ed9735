"""mypy --strict passes on the Python the documentation shows (every ```python block of README.md,
python/README.md and docs/*.md) and on python/examples/*.py, against the module under test and the stubs
beside it: the build tree's (build/python/hapticfield/: __init__.pyi and py.typed beside the extension, from
cmake/HapticfieldPythonStubs.cmake) and, from there, an install's (the same package)."""
import os
import pathlib
import re
import shutil
import subprocess
import sys

import pytest

from conftest import SOURCE

HERE = pathlib.Path(__file__).resolve().parent
STUB = SOURCE / "python" / "stubs" / "hapticfield" / "__init__.pyi"
DOCS = [SOURCE / "README.md", SOURCE / "python" / "README.md", *sorted((SOURCE / "docs").glob("*.md"))]
EXAMPLES = sorted((SOURCE / "python" / "examples").glob("*.py"))
BLOCK = re.compile(r"^```python[^\n]*\n(.*?)^```", re.S | re.M)

mypy_api = pytest.importorskip("mypy", reason="mypy is not installed (Debian: python3-mypy, see scripts/deps.sh)")


def python_blocks():
    """(where, code) for every ```python block of the documentation; where = 'path:first line'."""
    for doc in DOCS:
        text = doc.read_text()
        for m in BLOCK.finditer(text):
            yield f"{doc.relative_to(SOURCE)}:{text.count(chr(10), 0, m.start()) + 2}", m.group(1)


def write_blocks(directory):
    """Each block as its own module; returns {file name: where it comes from}."""
    names = {}
    for where, code in python_blocks():
        path, line = where.rsplit(":", 1)
        name = re.sub(r"\W", "_", path) + f"_line_{line}.py"
        (directory / name).write_text(code)
        names[name] = where
    return names


def run_mypy(files, cwd, cache, **env):
    environment = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "MYPYPATH")}
    environment.update(env)
    return subprocess.run([sys.executable, "-m", "mypy", "--strict", "--config-file", str(HERE / "mypy.ini"),
                           "--cache-dir", str(cache), "--no-color-output", *map(str, files)],
                          capture_output=True, text=True, timeout=600, cwd=cwd, env=environment)


def explained(r, names):
    """mypy's report, each block's file named with the document and line it comes from."""
    text = r.stdout + r.stderr
    return text + "".join(f"\n{name} is {where}" for name, where in names.items() if name in text)


@pytest.fixture(scope="module")
def module_dir():
    """build/python: the directory the build tree's package hapticfield/ is in."""
    import hapticfield as hf
    module = pathlib.Path(hf.__file__).resolve()
    if not (module.parents[2] / "CMakeCache.txt").is_file():
        pytest.skip(f"an installed package is under test ({module}); the build tree's stubs are checked from a build")
    return module.parents[1]


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("mypy_cache")


def test_the_documentation_has_python_blocks_and_the_examples_exist():
    assert len(list(python_blocks())) >= 5 and EXAMPLES


def test_the_build_tree_holds_the_committed_stubs_beside_the_module(module_dir):
    stub = module_dir / "hapticfield" / "__init__.pyi"
    assert stub.is_file(), f"{stub} is missing: build the module's target again (cmake --build)"
    assert stub.read_text() == STUB.read_text(), f"{stub} is stale: build the module's target again"
    assert (module_dir / "hapticfield" / "py.typed").is_file()


def test_the_documentation_and_the_examples_pass_mypy_strict(module_dir, cache, tmp_path):
    # found as `PYTHONPATH=build/python python3 -m mypy` finds it: the package hapticfield/ (py.typed) on the path
    names = write_blocks(tmp_path)
    r = run_mypy([*sorted(tmp_path.glob("*.py")), *EXAMPLES], tmp_path, cache, PYTHONPATH=str(module_dir))
    assert r.returncode == 0, explained(r, names)
    assert f"no issues found in {len(names) + len(EXAMPLES)} source files" in r.stdout, r.stdout


CHECKS = '''import numpy as np
import hapticfield as hf

p = np.array([0.0, 0.0, -0.001])
f = hf.plane_contact([hf.zero()], point=(0, 0, 0), normal=[0.0, 0.0, 1.0]).force(p)
g = hf.sphere_contact((hf.zero(),), centre=np.zeros(3, dtype=np.int64), radius=0.02).forces([[0.0, 0.0, 0.0]])
surface = hf.height_field(np.zeros((2, 2)), spacing=(1e-3, 1e-3), origin=(np.float32(0), 0, 0))
footprint = surface.footprint
if footprint is not None:
    h = hf.on_surface(hf.zero(), scale=footprint, offset=np.zeros(2))
'''
REFUSED = '''import numpy as np
import hapticfield as hf

hf.plane_contact(point="abc")
hf.on_surface(hf.zero(), scale=hf.height_field(np.zeros((2, 2))).footprint)
'''


def test_what_the_stubs_accept_is_what_the_module_accepts(module_dir, cache, tmp_path):
    # the same program type-checks and runs; what mypy refuses, the module refuses too
    (tmp_path / "checks.py").write_text(CHECKS)
    r = run_mypy([tmp_path / "checks.py"], tmp_path, cache, PYTHONPATH=str(module_dir))
    assert r.returncode == 0, r.stdout + r.stderr
    exec(compile(CHECKS, "checks.py", "exec"), {})
    (tmp_path / "refused.py").write_text(REFUSED)
    r = run_mypy([tmp_path / "refused.py"], tmp_path, cache, PYTHONPATH=str(module_dir))
    assert r.returncode == 1 and [f"refused.py:{n}:" in r.stdout for n in (4, 5)] == [True] * 2, r.stdout
    import hapticfield as hf
    import numpy as np
    with pytest.raises(TypeError):
        hf.plane_contact(point="abc")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        hf.on_surface(hf.zero(), scale=None)  # type: ignore[arg-type]


def test_the_stubs_are_found_through_mypypath_too(module_dir, cache, tmp_path):
    # hapticfield/__init__.pyi, the directory given as MYPYPATH (no PYTHONPATH)
    (tmp_path / "checks.py").write_text(CHECKS)
    r = run_mypy([tmp_path / "checks.py"], tmp_path, cache, MYPYPATH=str(module_dir))
    assert r.returncode == 0, r.stdout + r.stderr


def test_an_install_of_the_module_is_found_by_mypy(module_dir, cache, tmp_path):
    # cmake --install of the python component into a fresh prefix: hapticfield/ with __init__.pyi and py.typed
    build = module_dir.parent
    cmake = shutil.which("cmake")
    if not cmake or not (build / "CMakeCache.txt").is_file():
        pytest.skip("no CMake build tree to install from")
    if "HAPTICFIELD_INSTALL:BOOL=ON" not in (build / "CMakeCache.txt").read_text():
        pytest.skip("this build has no install rules (HAPTICFIELD_INSTALL is OFF)")
    prefix = tmp_path / "prefix"
    r = subprocess.run([cmake, "--install", str(build), "--prefix", str(prefix), "--component", "python"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    typed = list(prefix.rglob("hapticfield/py.typed"))
    assert len(typed) == 1, list(prefix.rglob("*"))
    site = typed[0].parent.parent
    work = tmp_path / "work"
    work.mkdir()
    names = write_blocks(work)
    r = run_mypy(sorted(work.glob("*.py")), work, cache, PYTHONPATH=str(site))
    assert r.returncode == 0, explained(r, names)
