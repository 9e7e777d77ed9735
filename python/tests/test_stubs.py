"""The committed type stubs (python/stubs) are those of the module as built: regenerated, they do not change."""
import ast
import inspect
import os
import pathlib
import subprocess
import sys

import pytest

SOURCE = pathlib.Path(os.environ.get("HAPTICFIELD_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SCRIPT = SOURCE / "scripts" / "make_stubs.py"
STUB = SOURCE / "python" / "stubs" / "hapticfield" / "__init__.pyi"


def test_the_committed_stubs_are_current():
    r = subprocess.run([sys.executable, str(SCRIPT), "--check"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, (
        "python/stubs/hapticfield/__init__.pyi is stale; regenerate it with "
        "`PYTHONPATH=build/python python3 scripts/make_stubs.py`\n" + r.stdout[-4000:] + r.stderr)


def test_the_stubs_name_every_public_binding():
    import hapticfield as hf
    tree = ast.parse(STUB.read_text())
    named = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    named |= {n.target.id for n in tree.body if isinstance(n, ast.AnnAssign)}
    # the package's pure-Python submodules (hapticfield.batch), once imported, are attributes too: not bindings
    public = {n for n in dir(hf) if not n.startswith("__") and not inspect.ismodule(getattr(hf, n))} | {"__version__"}
    assert public <= named, sorted(public - named)


def test_a_written_copy_goes_where_asked(tmp_path):
    r = subprocess.run([sys.executable, str(SCRIPT), "--out", str(tmp_path)], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "hapticfield" / "__init__.pyi").read_text() == STUB.read_text()
    assert (tmp_path / "hapticfield" / "py.typed").exists()


def test_without_the_module_the_script_says_how_to_find_it(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = subprocess.run([sys.executable, "-s", str(SCRIPT), "--check"], capture_output=True, text=True, timeout=120,
                       env=env, cwd=tmp_path)
    if r.returncode == 0:
        pytest.skip("hapticfield is installed for this interpreter")
    assert r.returncode == 2 and "PYTHONPATH" in r.stderr and r.stderr.count("\n") == 1


def test_the_stubs_agree_with_the_module_for_mypy_stubtest(tmp_path):
    # mypy type-checks the stubs (e.g. a None default needs Optional) and stubtest imports the module and
    # checks that every name exists on both sides. pybind11 functions carry no runtime signature to compare:
    # the signatures are those of the docstrings, which test_the_committed_stubs_are_current holds to.
    pytest.importorskip("mypy")
    import hapticfield as hf
    # What pybind11 does differently by design: its classes have a metaclass of their own, and a class
    # bound without a constructor inherits pybind11's __init__(self, *args, **kwargs), which refuses.
    classes = {n: c for n, c in vars(hf).items() if isinstance(c, type) and not issubclass(c, BaseException)}
    allow = [f"hapticfield.{n}" for n in classes]  # the class object itself, not its members
    allow += [f"hapticfield.{n}.__init__" for n, c in classes.items()
              if type(vars(c).get("__init__")).__name__ != "instancemethod"]
    allow += ["hapticfield.batch"]  # pure Python, typed in its own source (python/hapticfield/batch.py): no stub
    (tmp_path / "allow.txt").write_text("\n".join(allow) + "\n")
    # The module this test imported (a build's hapticfield.so, or an installed hapticfield/__init__.so).
    module = pathlib.Path(hf.__file__).resolve()
    where = module.parent.parent if module.name.startswith("__init__") else module.parent
    env = dict(os.environ, MYPYPATH=str(STUB.parent.parent), PYTHONPATH=str(where))
    r = subprocess.run([sys.executable, "-m", "mypy.stubtest", "hapticfield", "--allowlist", str(tmp_path / "allow.txt"),
                        "--ignore-unused-allowlist"],
                       capture_output=True, text=True, timeout=300, env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stdout[-6000:] + r.stderr[-2000:]
