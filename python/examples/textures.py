#!/usr/bin/env python3
"""Synthesise stochastic textures and plot their force and spectrum.

    PYTHONPATH=build/python python3 python/examples/textures.py [--out DIR] [--hatt FILE]

Strokes a plane (1000 N/m, pressed with 1 N) at 50 mm/s for 2 s at 1 kHz
with several textures, F = Fc + Ft (+ Ff), and writes DIR/textures.png:
the lateral force over the first 0.5 s and its power spectrum per texture.
Also DIR/filters.png: the library's Butterworth filters on white noise.
"""
import argparse
import os
import pathlib
from typing import Tuple

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import numpy.typing as npt

import hapticfield as hf

ROOT = pathlib.Path(__file__).resolve().parents[2]
RATE = 1000.0   # [Hz]
SPEED = 0.05    # [m/s]
K = 1000.0      # plane stiffness [N/m]
Array = npt.NDArray[np.float64]


def welch(x: Array, fs: float, seg: int = 256) -> Tuple[Array, Array]:
    """Welch PSD [N^2/Hz], Hann window, 50 % overlap."""
    w = np.hanning(seg)
    x = x - np.mean(x)
    frames = [x[i:i + seg] * w for i in range(0, len(x) - seg + 1, seg // 2)]
    p = np.mean([np.abs(np.fft.rfft(f)) ** 2 for f in frames], axis=0) / (fs * np.sum(w ** 2))
    p[1:-1] *= 2
    return np.fft.rfftfreq(seg, 1 / fs), p


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out/python")
    parser.add_argument("--hatt", default=str(ROOT / "tests" / "data" / "hatt" / "Models_Toolkit 1kHz ARMA.xml"))
    a = parser.parse_args()
    os.makedirs(a.out, exist_ok=True)

    n = int(2.0 * RATE)
    t = np.arange(n) / RATE
    positions = np.column_stack([-0.05 + SPEED * t, np.full(n, 0.002), np.full(n, -1.0 / K)])
    velocities = np.tile([SPEED, 0.0, 0.0], (n, 1))
    lateral, gain = (1, 1, 0), 0.5  # tangential only, 0.5 N per texture unit
    textures = {
        "Gaussian lattice, 1 mm, linear": hf.lattice_texture("gaussian", 0.5, seed=2, axes=lateral, gain=gain),
        "Gaussian lattice, 1 mm, cubic": hf.lattice_texture("gaussian", 0.5, seed=2, interpolation="cubic",
                                                            axes=lateral, gain=gain),
        "fBm h = 0.5, 6 octaves from 4 mm": hf.lattice_texture("gaussian", 0.5, seed=7, grain=(4e-3,) * 3, octaves=6,
                                                               h=0.5, axes=lateral, gain=gain),
        "local circle, 0.5 mm": hf.local_sphere_texture("gaussian", 0.5, seed=6, radius=5e-4, axes=lateral, gain=gain),
        "temporal, Butterworth 30-120 Hz": hf.temporal_texture("gaussian", 1.0, seed=10, order=4, band="band_pass",
                                                               f1=30, f2=120, axes=lateral, gain=gain),
        "friction mu 0.3 + viscous 2 N s/m": hf.friction(coulomb=0.3, viscous=2.0, scale_with_normal_force=True),
    }
    if os.path.exists(a.hatt):
        textures[f"HaTT {hf.hatt_model(a.hatt)['name']} (vertical)"] = hf.hatt_texture(a.hatt, friction=False)

    fig, axes = plt.subplots(len(textures), 2, figsize=(11, 2.2 * len(textures)), layout="constrained", squeeze=False)
    for row, (name, texture) in enumerate(textures.items()):
        f = hf.plane_contact([texture], stiffness=K).forces(positions, velocities)
        axis = 2 if name.startswith("HaTT") else 0
        signal = f[:, axis] - (1.0 if axis == 2 else 0.0)  # Fc = 1 N removed from Fz
        shown = t <= 0.5
        axes[row][0].plot(t[shown], signal[shown], lw=0.7)
        axes[row][0].set(ylabel=f"F{'xyz'[axis]} [N]", title=name)
        freq, p = welch(signal, RATE)
        if np.ptp(signal) > 1e-9:
            axes[row][1].loglog(freq[1:], p[1:], lw=0.8, color="tab:orange", label="Welch PSD")
            axes[row][1].legend(loc="lower left", fontsize="x-small")
        else:  # a constant force has no spectrum to show
            axes[row][1].text(0.5, 0.5, f"constant {signal[0]:.2f} N", ha="center", va="center",
                              transform=axes[row][1].transAxes)
        axes[row][1].set(ylabel="PSD [N²/Hz]")
        for ax in axes[row]:
            ax.grid(alpha=0.3, which="both")
    axes[-1][0].set_xlabel("time [s]")
    axes[-1][1].set_xlabel("frequency [Hz]")
    fig.savefig(os.path.join(a.out, "textures.png"), dpi=70)
    plt.close(fig)

    white = hf.noise("gaussian", 1.0, seed=1, n=20000)[:, 0]
    fig, ax = plt.subplots(figsize=(8, 3.4), layout="constrained")
    for order in (2, 4, 8):
        freq, p = welch(hf.butterworth(white, order=order, band="low_pass", f1=100.0, rate=RATE), RATE, seg=1024)
        ax.loglog(freq[1:], p[1:], lw=0.8, label=f"Butterworth low-pass order {order}")
    freq, p = welch(hf.fir_low_pass(white, cutoff=100.0, rate=RATE), RATE, seg=1024)
    ax.loglog(freq[1:], p[1:], lw=0.8, label="FIR 63 taps")
    ax.axvline(100.0, color="grey", ls="--", lw=0.8, label="cutoff 100 Hz")
    ax.set(xlabel="frequency [Hz]", ylabel="PSD [1/Hz]", title="Filters on white Gaussian noise at 1 kHz")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")
    fig.savefig(os.path.join(a.out, "filters.png"), dpi=80)
    plt.close(fig)
    print(f"wrote {a.out}/textures.png and {a.out}/filters.png")


if __name__ == "__main__":
    main()
