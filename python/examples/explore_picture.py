#!/usr/bin/env python3
"""Explore a picture's force field: what the arm feels on a photograph.

    PYTHONPATH=build/python python3 python/examples/explore_picture.py [IMAGE] [--out DIR]

Writes DIR/picture_forces.png (the picture with force arrows and the force
magnitude for three mask sizes) and DIR/picture_stroke.png (the force felt
along one horizontal stroke across the picture, in newtons, on the device).
No arm is needed.
"""
import argparse
import os
import pathlib

import matplotlib
matplotlib.use("Agg")
import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np

import hapticfield as hf

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("image", nargs="?", default=str(ROOT / "examples" / "data" / "coffee.png"))
    parser.add_argument("--out", default="out/python")
    a = parser.parse_args()
    os.makedirs(a.out, exist_ok=True)
    try:
        photo = matplotlib.image.imread(a.image)
    except (OSError, ValueError) as e:
        parser.exit(1, f"explore_picture: cannot read '{a.image}': {e}\n")

    # 1. Force maps: the normalised force (1 = a black/white edge) at every pixel, for three mask sizes.
    sizes = (5, 17, 65)
    fig, axes = plt.subplots(1, 4, figsize=(16, 3.6), layout="constrained")
    axes[0].imshow(photo)
    fx, fy = hf.force_map(a.image, mask="prewitt", size=17)
    step = 12
    ys, xs = np.mgrid[step // 2:fx.shape[0]:step, step // 2:fx.shape[1]:step]
    axes[0].quiver(xs, ys, fx[ys, xs], -fy[ys, xs], color="red", angles="xy", scale=4, width=0.004)
    axes[0].set(title="Prewitt 17 x 17: force arrows", xlabel="x [px]", ylabel="y [px]")
    for ax, size in zip(axes[1:], sizes):
        fx, fy = hf.force_map(a.image, mask="prewitt", size=size)
        im = ax.imshow(np.hypot(fx, fy), cmap="magma", vmin=0.0)
        ax.set(title=f"|F|, Prewitt {size} x {size}", xlabel="x [px]")
        fig.colorbar(im, ax=ax, label="|F| (1 = black/white edge)")
    fig.savefig(os.path.join(a.out, "picture_forces.png"), dpi=80)
    plt.close(fig)

    # 2. A stroke on the device: the picture spans 80 mm; the probe crosses it at 50 mm/s, 1 kHz.
    field = hf.tangible_field(a.image, size=17, gain=1.0, workspace_mm=80.0)
    n = 1600
    x = np.linspace(-0.04, 0.04, n)  # [m]
    positions = np.column_stack([x, np.zeros(n), np.zeros(n)])
    forces = field.forces(positions)
    checks = hf.tangible_forces(a.image, np.array([[0.0, 0.0]]))  # the same library, in pixels
    assert np.all(np.isfinite(checks))
    fig, ax = plt.subplots(figsize=(9, 3.4), layout="constrained")
    ax.plot(x * 1e3, forces[:, 0], label="Fx", color="tab:blue")
    ax.plot(x * 1e3, forces[:, 1], label="Fy", color="tab:green")
    ax.plot(x * 1e3, np.hypot(forces[:, 0], forces[:, 1]), label="|F|", color="black", lw=0.8)
    ax.set(xlabel="probe x on the device [mm] (y = 0, the picture's middle row)", ylabel="force [N]",
           title="Tangible image felt along one stroke (gain 1 N at a black/white edge)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.savefig(os.path.join(a.out, "picture_stroke.png"), dpi=80)
    plt.close(fig)
    print(f"wrote {a.out}/picture_forces.png and {a.out}/picture_stroke.png")


if __name__ == "__main__":
    main()
