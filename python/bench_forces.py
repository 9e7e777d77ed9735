#!/usr/bin/env python3
"""Vectorised evaluation from Python against the same loop in C++, in one run.

    PYTHONPATH=build/python python3 python/bench_forces.py [--probes N] [--repeats R] [--baseline PATH]

The scene: a plane (1500 N/m), the picture as a tangible image (80 mm wide),
a Gaussian lattice texture and friction scaled by |Fc|: F = Fc + Ft + Ff.
The baseline is build/bench/bench_vectorised, the same scene and probes
through a plain C++ loop over the concrete field type. Prints the mean and
worst time of R repeats for both, their ratio, and both checksums (the sum
of all forces in order: equal to the last digit when the forces are).
"""
import argparse
import os
import pathlib
import subprocess
import sys
import time

import numpy as np

import hapticfield as hf

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--probes", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--baseline", default=str(ROOT / "build" / "bench" / "bench_vectorised"))
    parser.add_argument("--image", default=str(ROOT / "examples" / "data" / "coffee.png"))
    a = parser.parse_args()
    if a.probes < 1 or a.repeats < 1:
        parser.error("--probes and --repeats must be >= 1")
    if not os.access(a.baseline, os.X_OK):
        sys.exit(f"bench_forces: no baseline program at {a.baseline} (build the bench_vectorised target)")

    i = np.arange(a.probes, dtype=np.int64)
    positions = np.column_stack([-0.04 + 0.08 * ((i * 7919) % 100003) / 100003.0,
                                 -0.03 + 0.06 * ((i * 104729) % 99991) / 99991.0,
                                 np.full(a.probes, -0.001)])
    velocities = np.tile([0.05, 0.02, 0.0], (a.probes, 1))

    def full():
        return hf.plane_contact([hf.tangible_field(a.image, workspace_mm=80.0),
                                 hf.lattice_texture(noise="gaussian", sigma=0.5, seed=3, grain=(1e-3, 1e-3, 1e-3),
                                                    interpolation="linear", gain=0.3, scale_with_normal_force=True,
                                                    axes=(1, 1, 0)),
                                 hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)],
                                stiffness=1500.0)

    def light():
        return hf.plane_contact([hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)],
                                stiffness=1500.0)

    print(f"| scene ({a.probes} probes, {a.repeats} repeats) | path | mean [ms] | worst [ms] | ns/probe (mean) | "
          "ratio (mean / worst) | checksum |")
    print("|---|---|---|---|---|---|---|")
    into = np.zeros((a.probes, 3))  # reused, as the C++ loop reuses its output
    for name, scene in [("full: plane + picture + texture + friction", full), ("light: plane + friction", light)]:
        times = []
        for _ in range(a.repeats):
            field = scene()
            t0 = time.perf_counter()
            forces = field.forces(positions, velocities, out=into)
            times.append(time.perf_counter() - t0)
        checksum = float(np.cumsum(forces.ravel())[-1])  # summed in order, as the C++ loop sums
        mean, worst = sum(times) / len(times), max(times)
        for label, extra in [("C++ loop, concrete type", []), ("C++ loop, one AnyField", ["--erased"])]:
            out = subprocess.run([a.baseline, a.image, "--probes", str(a.probes), "--repeats", str(a.repeats),
                                  "--scene", name.split(":")[0]] + extra,
                                 check=True, capture_output=True, text=True).stdout.split()
            base = dict(zip(out[0::2], out[1::2]))
            base_mean, base_worst = float(base["mean_s"]), float(base["worst_s"])
            print(f"| {name} | {label} | {base_mean * 1e3:.1f} | {base_worst * 1e3:.1f} | "
                  f"{base_mean / a.probes * 1e9:.1f} | Python / this: {mean / base_mean:.2f} / "
                  f"{worst / base_worst:.2f} | {float(base['checksum']):.17g} |")
        print(f"| {name} | Python Field.forces | {mean * 1e3:.1f} | {worst * 1e3:.1f} | "
              f"{mean / a.probes * 1e9:.1f} | | {checksum:.17g} |")


if __name__ == "__main__":
    main()
