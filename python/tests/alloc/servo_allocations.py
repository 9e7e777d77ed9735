"""Counts the allocation calls of run_servo on this thread (run under LD_PRELOAD=alloc_counter.so).

    servo_allocations.py SCENE [--clip PATTERN] [--hatt MODEL] [--coffee PNG] [--short S] [--long S] [--pairs N]
                         [--clock virtual|wall]

Builds SCENE (full: plane contact with a tangible image, a lattice texture,
friction, a HaTT texture and a video; surface: a relief from the picture felt
through the proxy, with the tangible image and a lattice laid on it by uv and
friction; physics: a moving plane, a deforming mesh and, when the module has MuJoCo, the table scene stepped
in lockstep; allocating: the test-only field that allocates every tick), warms up, then runs the loop for S_short and S_long
seconds, N times each, and prints one JSON line: for each run its ticks and
the malloc/free calls made on this thread: by the whole run_servo call, and
by the loop alone (run_servo reports those when this counter is preloaded).
The loop runs on the virtual clock unless --clock wall: what it renders (and
so which ticks evaluate the field) does not depend on how busy the machine is.
"""
import argparse
import ctypes
import json
import pathlib

import numpy as np

import hapticfield as hf

counter = ctypes.CDLL(None)  # the preloaded counter's symbols are global
counter.hapticfield_malloc_calls.restype = ctypes.c_ulong
counter.hapticfield_free_calls.restype = ctypes.c_ulong


# run_servo's hand for the scene (the surface scene lies below where the simulated arm starts)
HAND = {}


def scene(a):
    if a.scene == "physics":
        plane = hf.moving_surface(hf.plane_surface(), pose=hf.Pose(translation=(0.0, 0.0, -0.006)))
        vertices = np.array([[-0.02, -0.02, -0.007], [0.02, -0.02, -0.007], [0.02, 0.02, -0.007], [-0.02, 0.02, -0.007]])
        mesh = hf.deforming_mesh(vertices, np.array([[0, 1, 2], [0, 2, 3]]))
        parts = [hf.surface_contact(plane, stiffness=1500.0, damping=0.5), hf.surface_contact(mesh, stiffness=1500.0)]
        if hf.has_mujoco:  # stepped on its own thread, the loop waiting for each step
            table = pathlib.Path(__file__).resolve().parents[3] / "examples" / "data" / "mujoco_table.xml"
            parts.append(hf.mujoco_scene(table, rate=500.0))
        return hf.sum(parts)
    if a.scene == "allocating":
        return hf.plane_contact([hf._allocating_field()])
    if a.scene == "surface":
        relief = hf.height_field_from_picture(a.coffee, pixel_size=6e-4, mm_per_level=0.004, blur=2.0,
                                              origin=(-0.1, -0.08, -0.022))
        HAND.update(hand_centre=(0.0, 0.0, -0.024), hand_size=0.04)
        parts = [hf.on_surface(hf.tangible_field(a.coffee, workspace_mm=80.0), scale=0.08, offset=-0.04),
                 hf.on_surface(hf.lattice_texture(sigma=0.5, gain=0.3, scale_with_normal_force=True, axes=(1, 1, 0)),
                               scale=0.08),
                 hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)]
        return hf.surface_contact(relief, parts, stiffness=1500.0, damping=0.5, static_friction=0.3,
                                  dynamic_friction=0.2)
    parts = [hf.tangible_field(a.coffee, workspace_mm=80.0),
             hf.lattice_texture(noise="gaussian", sigma=0.5, gain=0.3, scale_with_normal_force=True, axes=(1, 1, 0)),
             hf.friction(coulomb=0.4, viscous=0.5, scale_with_normal_force=True)]
    if a.hatt:
        parts.append(hf.hatt_texture(a.hatt))
    if a.clip:
        parts.append(hf.video_field(a.clip, workspace_mm=80.0, size=5, loop=True))
    return hf.plane_contact(parts, stiffness=1500.0)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("scene", choices=["full", "surface", "physics", "allocating"])
    p.add_argument("--clip")
    p.add_argument("--hatt")
    p.add_argument("--coffee")
    p.add_argument("--short", type=float, default=0.5)
    p.add_argument("--long", type=float, default=2.5)
    p.add_argument("--pairs", type=int, default=1)
    p.add_argument("--clock", choices=["virtual", "wall"], default="virtual")
    a = p.parse_args()
    field = scene(a)
    hf.run_servo(field, seconds=0.3, clock=a.clock, **HAND)  # warm-up: first-use allocations (lazy tables, caches)
    runs = []
    for _ in range(a.pairs):
        for seconds in (a.short, a.long):
            counter.hapticfield_count_here(1)
            result = hf.run_servo(field, seconds=seconds, clock=a.clock, **HAND)
            runs.append({"seconds": seconds, "ticks": result["statistics"]["ticks"],
                         "malloc": counter.hapticfield_malloc_calls(), "free": counter.hapticfield_free_calls(),
                         "peak_force_n": result["statistics"]["peak_force_n"],
                         "loop_malloc": result["loop_allocations"], "loop_free": result["loop_frees"],
                         "missed": result["statistics"]["missed_deadlines"],
                         "safety_events": result["statistics"]["safety_events"]})
            counter.hapticfield_count_here(0)
            del result
    print(json.dumps(runs))


if __name__ == "__main__":
    main()
