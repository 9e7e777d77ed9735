"""Run by run_install.cmake in a fresh interpreter: the installed package is the one imported, and it works."""
import os
import sys

import hapticfield as hf

site = os.path.realpath(sys.argv[1])
here = os.path.dirname(os.path.realpath(hf.__file__))
assert here == os.path.join(site, "hapticfield"), f"imported {hf.__file__}, not the installed package in {site}"
assert os.path.isfile(os.path.join(here, "__init__.pyi")) and os.path.isfile(os.path.join(here, "py.typed"))
# A penalty plane of 1500 N/m pressed 1 mm: 1.5 N along its normal (closed form).
f = hf.plane_contact(stiffness=1500.0).force([0.0, 0.0, -0.001])
assert abs(f[2] - 1.5) < 1e-12 and f[0] == 0.0 and f[1] == 0.0, f
# The pure-Python part of the package comes with it, in the same place.
import hapticfield.batch as hb  # noqa: E402

assert os.path.dirname(os.path.realpath(hb.__file__)) == here, hb.__file__
assert hb.force_map().name == "force_map"
print(f"hapticfield {hf.__version__} imported from {hf.__file__}")
