#!/usr/bin/env python3
"""How fast run_servo(clock="virtual") runs: simulated seconds per wall second.

    PYTHONPATH=build/python python3 python/bench_virtual.py [--seconds S] [--repeats R] [--rate HZ]

Runs the servo loop on the simulated arm, on the virtual clock, for S
simulated seconds, R times for each scene: the zero field (the loop, the
simulated arm and its link alone) and the full scene (a plane at 1500 N/m
holding the picture as a tangible image 80 mm wide, a Gaussian lattice
texture and friction scaled by |Fc|). Prints, per scene, the wall time of
each run [s] and simulated seconds per wall second (mean and worst run).
The whole call is timed: the loop and building the trace arrays.
"""
import argparse
import pathlib
import time

import hapticfield as hf

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--rate", type=float, default=1000.0)
    parser.add_argument("--image", default=str(ROOT / "examples" / "data" / "coffee.png"))
    a = parser.parse_args()
    if not (0.0 < a.seconds <= 3600.0) or a.repeats < 1:
        parser.error("--seconds must be within (0, 3600] and --repeats >= 1")

    scenes = {
        "zero": hf.zero(),
        "full": hf.plane_contact([hf.tangible_field(a.image, workspace_mm=80.0),
                                  hf.lattice_texture(noise="gaussian", sigma=0.5, seed=3, grain=(1e-3,) * 3, gain=0.3,
                                                     scale_with_normal_force=True, axes=(1, 1, 0)),
                                  hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)],
                                 stiffness=1500.0),
    }
    print(f"run_servo(clock='virtual'), simulated arm, {a.seconds:g} simulated s at {a.rate:g} Hz, {a.repeats} runs")
    for name, field in scenes.items():
        hf.run_servo(field, seconds=min(a.seconds, 1.0), rate=a.rate, clock="virtual")  # warm-up
        walls = []
        for _ in range(a.repeats):
            start = time.perf_counter()
            result = hf.run_servo(field, seconds=a.seconds, rate=a.rate, clock="virtual")
            walls.append(time.perf_counter() - start)
            assert result["statistics"]["ticks"] == round(a.seconds * a.rate)
        mean = sum(walls) / len(walls)
        print(f"{name:5s}: wall {', '.join(f'{w:.3f}' for w in walls)} s; simulated s per wall s: "
              f"mean {a.seconds / mean:.1f}, worst {a.seconds / max(walls):.1f} "
              f"({a.seconds * a.rate / mean / 1e6:.2f} M ticks/s)")


if __name__ == "__main__":
    main()
