"""The allocation proof: a servo tick allocates nothing for a field built in Python.

run_servo runs the loop on a thread of its own; when an allocation counter
is preloaded into a child interpreter (alloc/alloc_counter.c, built by CMake
as hapticfield_alloc_counter), run_servo counts that thread's malloc and free
calls around the loop (loop_allocations, loop_frees): both must be 0, for a
run of 0.5 s and one of 2.5 s. The video field's worker thread, which
prepares frames and allocates by design, is not counted. The calling
thread is counted by the script for the whole call (setup, watching the
loop for Ctrl-C every few ms, trace arrays, the result dict): a long run
minus a short one is 0 up to the interpreter's own noise. A field that
allocates every tick shows that the counter catches it. The loop runs on
the virtual clock, so which ticks evaluate the field does not depend on the
load; one test runs on the wall clock, where the calling thread watches for
2.5 s instead of 0.5 s.
"""
import json
import os
import pathlib
import subprocess
import sys

import pytest

import hapticfield as hf
from clips import write_clip

COUNTER = os.environ.get("HAPTICFIELD_ALLOC_COUNTER", "")
HERE = pathlib.Path(__file__).resolve().parent

pytestmark = pytest.mark.skipif(not os.path.exists(COUNTER), reason="alloc_counter not built")


def counted_runs(*args):
    env = dict(os.environ, LD_PRELOAD=COUNTER)
    out = subprocess.run([sys.executable, str(HERE / "alloc" / "servo_allocations.py"), *map(str, args)],
                         env=env, check=True, capture_output=True, text=True, timeout=300).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_the_counter_sees_the_calls_it_should():
    script = ("import ctypes; c = ctypes.CDLL(None); c.hapticfield_malloc_calls.restype = ctypes.c_ulong; "
              "c.hapticfield_count_here(1); c.hapticfield_alloc_self_test(1000); "
              "print(c.hapticfield_malloc_calls(), c.hapticfield_free_calls())")
    out = subprocess.run([sys.executable, "-c", script], env=dict(os.environ, LD_PRELOAD=COUNTER), check=True,
                         capture_output=True, text=True).stdout.split()
    assert int(out[0]) >= 1000 and int(out[1]) >= 1000


def test_a_tick_allocates_nothing_for_a_full_composition(tmp_path, coffee, hatt_dir):
    args = ["full", "--coffee", coffee, "--hatt", hatt_dir / "Models_Toolkit 1kHz ARMA.xml", "--pairs", 2]
    if hf.has_video:
        args += ["--clip", write_clip(tmp_path / "clip")]
    runs = counted_runs(*args)
    for run in runs:
        assert run["loop_malloc"] == 0 and run["loop_free"] == 0, runs  # not one call in 500 or 2500 ticks
        assert run["peak_force_n"] > 0.5  # the scene pushed back [N]
    for short, long in zip(runs[0::2], runs[1::2]):
        assert long["ticks"] - short["ticks"] == 2000
        # The whole call: Python and numpy around the loop once in a while make an extra pair of calls
        # (+2 seen in 1 of ~40 runs, outside the loop); per tick that would be 2000.
        assert abs(long["malloc"] - short["malloc"]) <= 4, runs
        assert abs(long["free"] - short["free"]) <= 4, runs
    assert runs[0]["malloc"] > 0  # run_servo's own setup was counted: the counter was live


def test_a_tick_allocates_nothing_on_a_surface_with_fields_laid_on_it(coffee):
    # the proxy on a relief (quadtree queries, friction, the contact report) and the parts by uv
    runs = counted_runs("surface", "--coffee", coffee)
    for run in runs:
        assert run["loop_malloc"] == 0 and run["loop_free"] == 0, runs
        assert run["peak_force_n"] > 0.3  # the arm rested on the relief [N]
    short, long = runs
    assert long["ticks"] - short["ticks"] == 2000
    assert abs(long["malloc"] - short["malloc"]) <= 4 and abs(long["free"] - short["free"]) <= 4, runs


def test_a_tick_allocates_nothing_for_moving_shapes_and_a_mujoco_scene_in_lockstep():
    # a moving plane and a deforming mesh (each swaps in its newest snapshot every tick) and the MuJoCo table
    # scene, whose simulator thread (not counted: it steps MuJoCo) the loop waits for at every step
    runs = counted_runs("physics")
    for run in runs:
        assert run["loop_malloc"] == 0 and run["loop_free"] == 0, runs
        assert run["peak_force_n"] > 0.3  # the moving plane pushed the arm [N]
    short, long = runs
    assert long["ticks"] - short["ticks"] == 2000
    assert abs(long["malloc"] - short["malloc"]) <= 4 and abs(long["free"] - short["free"]) <= 4, runs


def test_watching_a_wall_clock_run_allocates_nothing(coffee):
    # Only allocation counts: the wall clock makes the rest depend on the load.
    short, long = counted_runs("full", "--coffee", coffee, "--clock", "wall")
    assert short["loop_malloc"] == long["loop_malloc"] == short["loop_free"] == long["loop_free"] == 0
    # 500 more polls of the watching thread (one every 4 ms) cost nothing either.
    assert abs(long["malloc"] - short["malloc"]) <= 4 and abs(long["free"] - short["free"]) <= 4, (short, long)


def test_a_field_that_allocates_every_tick_is_caught():
    runs = counted_runs("allocating", "--short", 0.2, "--long", 0.4, "--pairs", 2)
    # One malloc and one free a tick once the hand touches the plane: the first ticks command zero without
    # evaluating the field. On the virtual clock those ticks are the same in every run, however loaded the
    # machine is, so the counts are exact.
    for run in runs:
        assert run["loop_free"] == run["loop_malloc"] and run["ticks"] - 60 <= run["loop_malloc"] < run["ticks"], runs
    for short, long in zip(runs[0::2], runs[1::2]):
        assert long["ticks"] - short["ticks"] == 200
        assert long["loop_malloc"] - short["loop_malloc"] == 200, runs  # one a tick, not one missed
    assert runs[0]["loop_malloc"] == runs[2]["loop_malloc"] and runs[1]["loop_malloc"] == runs[3]["loop_malloc"], runs


def test_without_a_counter_run_servo_reports_none():
    result = hf.run_servo(hf.zero(), seconds=0.01)
    assert result["loop_allocations"] is None and result["loop_frees"] is None


def test_tick_budget_counts_a_tick_that_allocates_and_says_it_does_not_fit():
    # Timing is the machine's business; allocations are not: the verdict for
    # a field that allocates every tick is "does not fit" on any machine.
    script = ("import json, hapticfield as hf; "
              "a = hf.tick_budget(hf._allocating_field(), ticks=500); "
              "p = hf.tick_budget(hf.plane_contact([], stiffness=1500.0), ticks=500); "
              "print(json.dumps([a['allocations'], a['fits_1khz'], a['fits_10khz'], p['allocations'], a['ticks']]))")
    out = subprocess.run([sys.executable, "-c", script], env=dict(os.environ, LD_PRELOAD=COUNTER), check=True,
                         capture_output=True, text=True, timeout=300).stdout
    allocations, fits_1khz, fits_10khz, plane_allocations, ticks = json.loads(out.strip().splitlines()[-1])
    assert ticks == 500
    assert allocations >= 500  # one (or more) a tick
    assert not fits_1khz and not fits_10khz
    assert plane_allocations == 0
