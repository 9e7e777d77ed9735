"""The README's Python block and scripts/demo.sh do what the README says."""
import os
import re
import subprocess
import sys

import pytest

from conftest import SOURCE

README = SOURCE / "README.md"


def python_blocks():
    return re.findall(r"^```python\n(.*?)^```", README.read_text(), flags=re.S | re.M)


def test_readme_python_block_uses_pictures_the_repository_ships():
    blocks = python_blocks()
    assert blocks, "README.md has no ```python block"
    pictures = [p for b in blocks for p in re.findall(r"\"([^\"]+\.(?:png|jpe?g|tiff?|bmp))\"", b)]
    assert pictures, "the README's Python block names no picture"
    for picture in pictures:
        assert (SOURCE / picture).is_file(), f"README's Python block uses '{picture}', which the repository lacks"


def test_readme_python_block_runs_from_the_top_folder():
    pytest.importorskip("hapticfield")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    for block in python_blocks():
        r = subprocess.run([sys.executable, "-c", block], cwd=SOURCE, capture_output=True, text=True, env=env,
                           timeout=300)
        assert r.returncode == 0, r.stderr


def demo_commands():
    r = subprocess.run(["bash", str(SOURCE / "scripts" / "demo.sh"), "--dry-run"], capture_output=True, text=True,
                       env=dict(os.environ, HAPTICFIELD_BUILD_DIR="b"))
    assert r.returncode == 0, r.stderr
    return r.stdout.splitlines()


def test_demo_builds_every_example_the_readme_runs_next():
    lines = demo_commands()
    builds = [line for line in lines if line.startswith("cmake --build b ")]
    assert len(builds) == 1
    targets = set(builds[0].split("--target", 1)[1].split())
    # the tools the README runs from build/examples/ in the sections after the quick start, up to the servo loop's
    head = README.read_text().split("\n## Textures and friction", 1)[0]
    wanted = set(re.findall(r"build/examples/(\w+)", head)) | {"tangible_image"}
    assert "servo_demo" in wanted
    assert wanted <= targets, f"demo.sh builds {sorted(targets)}, the README runs {sorted(wanted)}"
    # and it runs what it built, from the build folder it was given
    assert any(line.startswith("b/examples/tangible_image ") for line in lines)


def test_demo_rejects_an_unknown_option():
    r = subprocess.run(["bash", str(SOURCE / "scripts" / "demo.sh"), "--fast"], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "--fast" in r.stderr
