"""The build backend of `pip install .` (pyproject.toml).

With scikit-build-core at hand (pip with the package index installs it in its isolated build
environment) every hook is scikit-build-core's. Without it (`pip install . --no-build-isolation` on a
machine without the index, e.g. Debian 12, which does not package scikit-build-core) the wheel is the
CMake build's own: the module built in a temporary directory and the `wheel` target
(python/make_wheel.py, the standard library only). What cannot be done ends in one line saying why.
"""
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

try:
    from scikit_build_core import build as _skbuild
except ImportError:
    _skbuild = None

ROOT = pathlib.Path(__file__).resolve().parents[2]


def __getattr__(name):
    """The optional hooks (metadata, editable installs) are scikit-build-core's when it is here."""
    if _skbuild is not None and not name.startswith("__"):
        return getattr(_skbuild, name)
    raise AttributeError(name)


def _fail(message):
    print(f"hapticfield: {message}", file=sys.stderr)
    raise SystemExit(1)


def get_requires_for_build_wheel(config_settings=None):
    if _skbuild is not None:
        return _skbuild.get_requires_for_build_wheel(config_settings)
    return []


def build_sdist(sdist_directory, config_settings=None):
    if _skbuild is None:
        _fail("a source distribution needs scikit-build-core (pip with the package index); "
              "for a wheel without it: cmake --build build --target wheel")
    return _skbuild.build_sdist(sdist_directory, config_settings)


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    if _skbuild is not None:
        return _skbuild.build_wheel(wheel_directory, config_settings, metadata_directory)
    return _cmake_wheel(pathlib.Path(wheel_directory))


def _run(command, log, what):
    with open(log, "ab") as out:
        done = subprocess.run(command, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT, check=False)
    if done.returncode == 0:
        return
    text = pathlib.Path(log).read_text(errors="replace")
    found = re.search(r"hapticfield: the Python module cannot be built here.*?\)", text, re.S)
    if found:
        _fail(" ".join(found.group(0).split())[len("hapticfield: "):])
    _fail(f"{what} failed (exit status {done.returncode}); the log: {log}")


def _cmake_wheel(wheel_directory):
    cmake = shutil.which("cmake")
    if cmake is None:
        _fail("without scikit-build-core the module is built with CMake (3.25 or later), which is not on the PATH "
              "(Debian: apt install cmake; scripts/deps.sh installs everything)")
    build = pathlib.Path(tempfile.mkdtemp(prefix="hapticfield-wheel-"))
    log = build / "build.log"
    _run([cmake, "-S", str(ROOT), "-B", str(build / "cmake"), "-DCMAKE_BUILD_TYPE=Release",
          "-DHAPTICFIELD_BUILD_PYTHON=ON", "-DHAPTICFIELD_REQUIRE_PYTHON=ON", "-DHAPTICFIELD_BUILD_TESTS=OFF",
          "-DHAPTICFIELD_BUILD_EXAMPLES=OFF", "-DHAPTICFIELD_BUILD_BENCH=OFF", f"-DPython3_EXECUTABLE={sys.executable}"],
         log, "configuring with CMake")
    jobs = str(os.cpu_count() or 1)
    _run([cmake, "--build", str(build / "cmake"), "--target", "wheel", "-j", jobs], log, "building the module")
    wheels = sorted((build / "cmake" / "dist").glob("hapticfield-*.whl"))
    if not wheels:
        _fail(f"the wheel target wrote no wheel; the log: {log}")
    wheel_directory.mkdir(parents=True, exist_ok=True)
    shutil.copy2(wheels[-1], wheel_directory / wheels[-1].name)
    name = wheels[-1].name
    shutil.rmtree(build, ignore_errors=True)
    return name
