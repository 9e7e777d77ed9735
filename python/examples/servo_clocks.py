#!/usr/bin/env python3
"""The servo loop on the simulated arm, on the virtual and on the wall clock; stopping a run.

    PYTHONPATH=build/python python3 python/examples/servo_clocks.py [IMAGE] [--seconds S]

A plane (1500 N/m) holding a picture as a tangible image, with friction,
raster-scanned by the simulated arm's scripted hand:

1. twice on the virtual clock (the simulated arm's default): S simulated
   seconds in a few ms of wall time, the same forces bit for bit;
2. once on the wall clock, in real time: the forces differ from the
   virtual run's wherever the scheduler woke the loop late;
3. a run of an hour on the wall clock, stopped after 0.5 s from this
   thread through a ServoStop token (Ctrl-C would stop it too, raising
   KeyboardInterrupt with the result as its `result` attribute).
"""
import argparse
import pathlib
import threading
import time
from typing import Any, Dict, List

import numpy as np

import hapticfield as hf

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("image", nargs="?", default=str(ROOT / "examples" / "data" / "coffee.png"))
    parser.add_argument("--seconds", type=float, default=1.0, help="length of runs 1 and 2 [s]")
    a = parser.parse_args()
    scene = hf.plane_contact([hf.tangible_field(a.image, workspace_mm=80.0),
                              hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)],
                             stiffness=1500.0)

    def summary(name: str, run: Dict[str, Any], wall: float) -> None:
        s = run["statistics"]
        print(f"{name:8s}: {s['ticks']} ticks in {wall * 1e3:.1f} ms wall, stop {run['stop_reason']}, "
              f"peak {s['peak_force_n']:.3f} N, missed deadlines {s['missed_deadlines']}, "
              f"period p99 {s['period_p99_s'] * 1e3:.3f} ms")

    runs: Dict[str, Dict[str, Any]] = {}
    for name, clock in (("virtual", "virtual"), ("again", "virtual"), ("wall", "wall")):
        start = time.perf_counter()
        runs[name] = hf.run_servo(scene, seconds=a.seconds, clock=clock)
        summary(name, runs[name], time.perf_counter() - start)
    same = np.array_equal(runs["virtual"]["trace"]["force"], runs["again"]["trace"]["force"])
    differ = np.max(np.abs(runs["virtual"]["trace"]["force"] - runs["wall"]["trace"]["force"]))
    print(f"virtual runs equal bit for bit: {same}; largest difference from the wall-clock run: {differ:.3f} N")

    stop = hf.ServoStop()
    result: List[Dict[str, Any]] = []
    loop = threading.Thread(target=lambda: result.append(hf.run_servo(scene, seconds=3600.0, clock="wall",
                                                                        stop=stop)))
    start = time.perf_counter()
    loop.start()
    time.sleep(0.5)
    stop.request()
    loop.join()
    summary("stopped", result[0], time.perf_counter() - start)
    print(f"last traced force {np.linalg.norm(result[0]['trace']['force'][-1]):.3f} N (the last tick's command)")
    print(f"force the arm was left with {np.linalg.norm(result[0]['final_force']):.3f} N (the stop's command)")


if __name__ == "__main__":
    main()
