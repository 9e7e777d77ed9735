"""scripts/hapticfield_plots.py and the examples that call it."""
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from conftest import SOURCE

SCRIPT = SOURCE / "scripts" / "hapticfield_plots.py"
matplotlib = pytest.importorskip("matplotlib")
import matplotlib.image  # noqa: E402


def plots(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True)


def servo_inputs(tmp_path):
    t = np.arange(500) / 1000.0
    trace = np.column_stack([t, np.zeros((500, 3)), np.sin(t), np.cos(t), np.full(500, 2.0), np.full(500, 1e-3)])
    np.savetxt(tmp_path / "trace.csv", trace, delimiter=",", header="t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,period_s",
               comments="")
    hist = np.column_stack([np.arange(800, 1201) * 1e-3, np.exp(-0.5 * ((np.arange(800, 1201) - 1000) / 20.0) ** 2) * 100])
    np.savetxt(tmp_path / "periods.csv", hist, delimiter=",", header="period_ms,count", comments="", fmt="%.6g")
    return ["servo", "--trace", tmp_path / "trace.csv", "--periods", tmp_path / "periods.csv", "--nominal-ms", 1,
            "--limit", 3.3, "--out", tmp_path]


def test_servo_plots_are_drawn(tmp_path):
    r = plots(*servo_inputs(tmp_path))
    assert r.returncode == 0, r.stderr
    for name in ("force.png", "periods.png"):
        image = matplotlib.image.imread(tmp_path / name)
        assert image.shape[0] > 300 and image.shape[1] > 800
        assert np.std(image[..., :3]) > 0.05  # not blank


def test_texture_plots_are_drawn(tmp_path):
    t = np.arange(1000) / 1000.0
    np.savetxt(tmp_path / "a_trace.csv", np.column_stack([t, np.sin(60 * t), 0 * t, 0 * t]), delimiter=",",
               header="time_s,fx_N,fy_N,fz_N", comments="")
    f = np.arange(129) * 1000 / 256
    np.savetxt(tmp_path / "a_psd.csv", np.column_stack([f, 1e-3 / (1 + f)]), delimiter=",",
               header="frequency_Hz,psd_N2_per_Hz", comments="")
    (tmp_path / "gallery.csv").write_text('stem,name,axis,description,rate_Hz\na,"a sine","0","10 Hz, ""pure""",1000\n')
    r = plots("texture", "--dir", tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "a.png").stat().st_size > 10000 and (tmp_path / "gallery.png").exists()


def test_vibration_spectrum_plot_is_drawn(tmp_path):
    f = np.arange(1, 427) * 48000 / 4096
    model = -20 - 40 * f / 5000
    np.savetxt(tmp_path / "s.csv", np.column_stack([f, model + 0.5 * np.sin(f), model]), delimiter=",",
               header="frequency_Hz,audio_dB,model_dB", comments="")
    r = plots("vibration", "--spectrum", tmp_path / "s.csv", "--out", tmp_path / "v.png")
    assert r.returncode == 0, r.stderr
    image = matplotlib.image.imread(tmp_path / "v.png")
    assert image.shape[0] > 250 and image.shape[1] > 500
    assert np.std(image[..., :3]) > 0.05  # not blank


def test_vibration_bad_input(tmp_path):
    (tmp_path / "s.csv").write_text("frequency_Hz,audio_dB\n1,2\n")
    r = plots("vibration", "--spectrum", tmp_path / "s.csv", "--out", tmp_path / "v.png")
    assert r.returncode == 1 and "lacks the column" in r.stderr and r.stderr.count("\n") == 1
    r = plots("vibration", "--spectrum", tmp_path / "s.csv", "--out", tmp_path / "nowhere" / "v.png")
    assert r.returncode == 1 and "does not exist" in r.stderr
    assert plots("vibration", "--out", tmp_path / "v.png").returncode == 2  # --spectrum missing


@pytest.mark.parametrize("change,status,message", [
    (lambda a, p: a.__setitem__(2, p / "missing.csv"), 1, "cannot read"),
    (lambda a, p: (p / "trace.csv").write_text("t_s,fx_N\n0,1\n"), 1, "lacks the column"),
    (lambda a, p: (p / "trace.csv").write_text("t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N\n0,0,0,0,a,0,0\n"), 1, "not a number"),
    (lambda a, p: (p / "periods.csv").write_text("period_ms,count\n"), 1, "no data rows"),
    (lambda a, p: a.__setitem__(10, p / "nowhere"), 1, "not a folder"),
    (lambda a, p: a.__setitem__(6, "fast"), 2, "invalid float"),
])
def test_bad_input_is_one_line_and_an_exit_status(tmp_path, change, status, message):
    args = servo_inputs(tmp_path)
    change(args, tmp_path)
    r = plots(*args)
    assert r.returncode == status and message in r.stderr


def test_help_and_usage():
    r = plots("--help")
    assert r.returncode == 0 and "servo" in r.stdout
    assert plots().returncode == 2
    assert plots("texture").returncode == 2  # --dir missing


@pytest.mark.skipif(not os.environ.get("HAPTICFIELD_SERVO_DEMO"), reason="servo_demo not built")
def test_servo_demo_falls_back_to_its_own_plots_and_says_so(tmp_path):
    env = dict(os.environ, HAPTICFIELD_PLOT_SCRIPT=str(tmp_path / "no_script.py"))
    r = subprocess.run([os.environ["HAPTICFIELD_SERVO_DEMO"], "--seconds", "0.2", "--realtime", "off", "--plots",
                        tmp_path / "p"], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert "simple plots: the plot script" in r.stdout
    assert (tmp_path / "p" / "force.png").exists() and (tmp_path / "p" / "periods.png").exists()


@pytest.mark.skipif(not os.environ.get("HAPTICFIELD_SERVO_DEMO"), reason="servo_demo not built")
def test_servo_demo_uses_matplotlib_when_present(tmp_path):
    env = dict(os.environ, HAPTICFIELD_PYTHON=sys.executable, HAPTICFIELD_PLOT_SCRIPT=str(SCRIPT))
    r = subprocess.run([os.environ["HAPTICFIELD_SERVO_DEMO"], "--seconds", "0.2", "--realtime", "off", "--plots",
                        tmp_path / "p"], capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert "(matplotlib)" in r.stdout
    assert (tmp_path / "p" / "periods.csv").exists() and (tmp_path / "p" / "trace.csv").exists()


@pytest.mark.parametrize("example", ["explore_picture.py", "textures.py"])
def test_python_examples_run(tmp_path, example):
    r = subprocess.run([sys.executable, str(SOURCE / "python" / "examples" / example), "--out", tmp_path],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    pngs = list(pathlib.Path(tmp_path).glob("*.png"))
    assert len(pngs) >= 2


def test_without_matplotlib_the_script_exits_3(tmp_path):
    # python -S leaves out site-packages, and so matplotlib
    args = [sys.executable, "-S", str(SCRIPT)]
    r = subprocess.run(args + ["texture", "--dir", str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 3 and "matplotlib is not installed" in r.stderr
    r = subprocess.run(args + ["--quiet-missing", "texture", "--dir", str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 3 and r.stderr == ""
