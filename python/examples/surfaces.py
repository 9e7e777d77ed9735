#!/usr/bin/env python3
"""Surfaces from Python: a height field felt through the proxy, with a texture laid on it by uv.

    PYTHONPATH=build/python python3 python/examples/surfaces.py [--picture PNG]

Builds a 2 mm bump on a 6 x 6 cm height field 25 mm below the origin (the
simulated arm starts about 16 mm below it: a surface is felt from above
only), strokes it 1 mm deep, then runs the servo loop on the simulated arm
(virtual clock) with the hand pressing on it, and feels a picture as a
relief in one line. Prints what it measured.
"""
import argparse
import pathlib

import numpy as np

import hapticfield as hf

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--picture", default=str(ROOT / "examples" / "data" / "coffee.png"))
    a = parser.parse_args()

    # a bump 2 mm high on a 6 x 6 cm height field, 0.5 mm between samples, its corner at (-3, -3, -25) cm
    x = np.arange(-0.03, 0.03 + 1e-9, 5e-4)
    X, Y = np.meshgrid(x, x)
    z0 = -0.025
    bump = hf.height_field(0.002 * np.exp(-(X ** 2 + Y ** 2) / 0.01 ** 2), spacing=5e-4, origin=(-0.03, -0.03, z0))

    # felt through the proxy (k = 1500 N/m, b = 1 N s/m), with a lattice texture laid on it by uv
    # (1 uv unit = the 6 cm footprint: a height field has one, other surfaces None) and friction
    footprint = bump.footprint
    assert footprint is not None
    texture = hf.lattice_texture(sigma=0.5, gain=0.3, scale_with_normal_force=True, axes=(1, 1, 0))
    field = hf.surface_contact(bump, [hf.on_surface(texture, scale=footprint),
                                      hf.friction(coulomb=0.3, scale_with_normal_force=True)],
                               stiffness=1500.0, damping=1.0)

    # a stroke across the top, 1 mm deep, from a point above: forces and where the proxy is
    s = np.linspace(-0.02, 0.02, 1000)
    stroke = np.column_stack([s, np.zeros_like(s), z0 + 0.002 * np.exp(-s ** 2 / 0.01 ** 2) - 0.001])
    path = np.vstack([[(-0.02, 0.0, z0 + 0.01)], stroke])
    c = field.contacts(path, velocities=np.gradient(path, 1e-3, axis=0))
    normal_force = np.einsum("ij,ij->i", c["contact_force"], c["normal"])
    print(f"stroke: touching {c['touching'].mean():.0%} of ticks, normal force {normal_force[1:].mean():.2f} N "
          f"(k x 1 mm = 1.5 N), proxy up to {1e3 * (c['proxy'][1:, 2].max() - z0):.2f} mm above the base")

    # the servo loop on the simulated arm: the hand rasters over the bump 1 mm below its base
    field.reset()
    run = hf.run_servo(field, seconds=2.0, hand_centre=(0.0, 0.0, z0 - 0.001), hand_size=0.04)
    st = run["statistics"]
    print(f"servo: {st['ticks']} ticks, peak {st['peak_force_n']:.2f} N, latches {st['latches']}")

    # a picture as a relief in one line: 0.02 mm per gray level, 10 cm wide, its tangible image on it
    relief = hf.picture_relief(a.picture, mm_per_level=0.02, width_m=0.1)
    f = relief.forces(np.array([[0.05, 0.03, 0.01], [0.05, 0.03, 0.0]]))
    print(f"picture relief: {relief.description}, force at (5, 3, 0) cm: {np.round(f[-1], 3)} N")


if __name__ == "__main__":
    main()
