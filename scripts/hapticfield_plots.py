#!/usr/bin/env python3
"""Plots with axes, ticks, units and legends for hapticfield's examples (matplotlib).

    hapticfield_plots.py servo --trace T.csv --periods P.csv --nominal-ms MS --limit N --out DIR
    hapticfield_plots.py texture --dir DIR [--quiet]
    hapticfield_plots.py forcemap --dir DIR --full-scale S [--title T] [--scale-note N]
    hapticfield_plots.py video --forces F.csv --cuts C.csv --mode play|probes --out PNG
    hapticfield_plots.py strokes --dir DIR
    hapticfield_plots.py vibration --spectrum S.csv --out PNG [--title TEXT]
    hapticfield_plots.py --check      exit 0 when matplotlib is present

servo: T.csv is servo_demo's trace (t_s, x_m, y_m, z_m, fx_N, fy_N, fz_N,
period_s, homed, armed); P.csv the loop's tick-period histogram (period_ms, count). Writes
DIR/force.png and DIR/periods.png.

texture: DIR holds texture_gallery's gallery.csv (stem, name, axis,
description, rate_Hz) and per texture STEM_trace.csv and STEM_psd.csv.
Writes DIR/STEM.png per texture and DIR/gallery.png.

forcemap: DIR holds tangible_image --maps' fx.tiff and fy.tiff (32-bit
float planes, normalised force, 1 = a black/white edge). Writes DIR/maps.png:
fx, fy and |F| with axes [px] and colour bars, all at the full scale S.

video: F.csv is t_s,fx,fy (tangible_video: --mode play, the lateral force
commanded [N] against video time; --mode probes, the normalised force at the
probes); C.csv is frame,time (the scene cuts found). Writes PNG.

strokes: DIR holds false_texture's strokes.csv and regions.csv (region,
gray_lo, gray_hi, name, colour #rrggbb). Writes DIR/strokes.png.

vibration: S.csv is the vibration example's --spectrum output
(frequency_Hz, audio_dB, model_dB): the PSD played on the audio path
against the HaTT model's own. Writes the PNG named by --out.

Exit status: 0 done, 1 bad input (missing or malformed files), 2 usage
error, 3 matplotlib missing.
"""
import argparse
import csv
import math
import os
import sys

try:
    import matplotlib
    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt
except ImportError:
    plt = None

AXES = "xyz"


def fail(message, status=1):
    print(f"hapticfield_plots: {message}", file=sys.stderr)
    sys.exit(status)


def read_columns(path, names):
    """The named columns of a CSV file with a header line, as lists of floats."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        fail(f"cannot read '{path}': {e.strerror}")
    if not rows:
        fail(f"'{path}' has no data rows")
    missing = [n for n in names if n not in rows[0]]
    if missing:
        fail(f"'{path}' lacks the column(s) {', '.join(missing)}")
    try:
        return {n: [float(r[n]) for r in rows] for n in names}
    except (TypeError, ValueError):
        fail(f"'{path}' holds a value that is not a number")


def servo(args):
    trace = read_columns(args.trace, ["t_s", "fx_N", "fy_N", "fz_N"])
    t = trace["t_s"]
    magnitude = [math.sqrt(x * x + y * y + z * z) for x, y, z in zip(trace["fx_N"], trace["fy_N"], trace["fz_N"])]
    fig, ax = plt.subplots(figsize=(9, 3.6), dpi=100, layout="constrained")
    for key, label, colour in [("fx_N", "Fx", "tab:blue"), ("fy_N", "Fy", "tab:green"), ("fz_N", "Fz", "tab:red")]:
        ax.plot(t, trace[key], lw=0.8, color=colour, label=label)
    ax.plot(t, magnitude, lw=0.8, color="black", label="|F|")
    ax.axhline(args.limit, color="grey", ls="--", lw=0.8, label=f"limit ±{args.limit:g} N")
    ax.axhline(-args.limit, color="grey", ls="--", lw=0.8)
    ax.set(xlabel="time [s]", ylabel="commanded force [N]", title="Force commanded after the safety chain")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", ncol=5, fontsize="small")
    fig.savefig(os.path.join(args.out, "force.png"))
    plt.close(fig)

    hist = read_columns(args.periods, ["period_ms", "count"])
    fig, ax = plt.subplots(figsize=(9, 3.6), dpi=100, layout="constrained")
    widths = [hist["period_ms"][1] - hist["period_ms"][0] if len(hist["period_ms"]) > 1 else 1e-3] * len(hist["count"])
    ax.bar(hist["period_ms"], hist["count"], width=widths, align="edge", color="tab:blue", label="ticks per 1 µs bin")
    ax.axvline(args.nominal_ms, color="tab:red", lw=1.0, label=f"nominal {args.nominal_ms:g} ms")
    ax.set_yscale("log")
    ax.set(xlabel="tick period [ms]", ylabel="ticks (log scale)", title="Servo loop tick periods")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")
    fig.savefig(os.path.join(args.out, "periods.png"))
    plt.close(fig)
    print(f"plots: {os.path.join(args.out, 'force.png')}, {os.path.join(args.out, 'periods.png')} (matplotlib)")


def vibration(args):
    s = read_columns(args.spectrum, ["frequency_Hz", "audio_dB", "model_dB"])
    f = s["frequency_Hz"]
    errors = sorted(abs(a - m) for fr, a, m in zip(f, s["audio_dB"], s["model_dB"]) if fr <= 4000.0)
    fig, ax = plt.subplots(figsize=(7, 3.4), dpi=90, layout="constrained")
    ax.plot(f, s["audio_dB"], lw=0.8, color="tab:blue", label="played on the audio path (Welch PSD)")
    ax.plot(f, s["model_dB"], lw=1.4, color="black", ls="--", label="the model's own PSD (closed form)")
    ax.axvline(500.0, color="tab:red", lw=0.8, ls=":", label="Nyquist of a 1 kHz force loop")
    if errors:
        ax.text(0.99, 0.97, f"median |error| up to 4 kHz: {errors[len(errors) // 2]:.2f} dB", ha="right", va="top",
                transform=ax.transAxes, fontsize="small")
    ax.set(xlabel="frequency [Hz]", ylabel="acceleration PSD [dB re 1 (m/s²)²/Hz]", title=args.title)
    ax.set_xlim(0.0, max(f))
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize="small")
    fig.savefig(args.out)
    plt.close(fig)
    print(f"plot: {args.out} (matplotlib)")


def texture_panels(axes, entry, trace, psd):
    t, f = trace["time_s"], trace[f"f{AXES[entry['axis']]}_N"]
    shown = [i for i, x in enumerate(t) if x <= 0.5]  # the first 0.5 s
    axes[0].plot([t[i] for i in shown], [f[i] for i in shown], lw=0.7, color="tab:blue",
                 label=f"F{AXES[entry['axis']]}")
    axes[0].set(xlabel="time [s]", ylabel="force [N]")
    axes[0].legend(loc="upper right", fontsize="x-small")
    axes[0].grid(alpha=0.3)
    pairs = [(fr, p) for fr, p in zip(psd["frequency_Hz"], psd["psd_N2_per_Hz"]) if fr > 0 and p > 0]
    if max(f) - min(f) < 1e-9:  # a constant force [N]: its spectrum is rounding noise
        axes[1].text(0.5, 0.5, f"constant {f[0]:.3g} N: no spectrum", ha="center", va="center",
                     transform=axes[1].transAxes)
    elif pairs:
        axes[1].loglog([p[0] for p in pairs], [p[1] for p in pairs], lw=0.8, color="tab:orange", label="Welch PSD")
        axes[1].legend(loc="lower left", fontsize="x-small")
    axes[1].set(xlabel="frequency [Hz]", ylabel="PSD [N²/Hz]")
    axes[1].grid(alpha=0.3, which="both")


def texture(args):
    index = os.path.join(args.dir, "gallery.csv")
    try:
        with open(index, newline="") as f:
            entries = list(csv.DictReader(f))
    except OSError as e:
        fail(f"cannot read '{index}': {e.strerror}")
    if not entries or any(k not in entries[0] for k in ("stem", "name", "axis", "description")):
        fail(f"'{index}' lacks stem, name, axis or description")
    loaded = []
    for e in entries:
        if e["axis"] not in ("0", "1", "2") or os.sep in e["stem"] or e["stem"] in ("", ".", ".."):
            fail(f"'{index}': bad row for '{e['stem']}'")
        e["axis"] = int(e["axis"])
        trace = read_columns(os.path.join(args.dir, e["stem"] + "_trace.csv"), ["time_s", "fx_N", "fy_N", "fz_N"])
        psd = read_columns(os.path.join(args.dir, e["stem"] + "_psd.csv"), ["frequency_Hz", "psd_N2_per_Hz"])
        loaded.append((e, trace, psd))
        fig, axes = plt.subplots(2, 1, figsize=(6.4, 4.8), dpi=100, layout="constrained")
        fig.suptitle(f"{e['name']}: {e['description']}", fontsize="medium")
        texture_panels(axes, e, trace, psd)
        fig.savefig(os.path.join(args.dir, e["stem"] + ".png"))
        plt.close(fig)
        if not args.quiet:
            print(f"  {e['stem']}.png  ({e['description']})")
    cols = 3
    rows = (len(loaded) + cols - 1) // cols
    fig, axes = plt.subplots(2 * rows, cols, figsize=(4.2 * cols, 3.6 * rows), dpi=args.gallery_dpi, layout="constrained",
                             squeeze=False)
    for k in range(rows * cols):
        r, c = 2 * (k // cols), k % cols
        if k < len(loaded):
            e, trace, psd = loaded[k]
            texture_panels([axes[r][c], axes[r + 1][c]], e, trace, psd)
            axes[r][c].set_title(e["name"], fontsize="small")
        else:
            axes[r][c].axis("off")
            axes[r + 1][c].axis("off")
    fig.savefig(os.path.join(args.dir, "gallery.png"))
    plt.close(fig)
    if not args.quiet:
        print(f"  gallery.png ({len(loaded)} plots, matplotlib)")


def read_float_plane(path):
    """A 32-bit float TIFF plane as a 2D numpy array."""
    import numpy as np
    from PIL import Image
    try:
        with Image.open(path) as image:
            plane = np.asarray(image, dtype=np.float32)
    except OSError as e:
        fail(f"cannot read '{path}': {e.strerror or e}")
    if plane.ndim != 2 or plane.size == 0:
        fail(f"'{path}' is not a single float plane")
    return plane


def forcemap(args):
    import numpy as np
    fx = read_float_plane(os.path.join(args.dir, "fx.tiff"))
    fy = read_float_plane(os.path.join(args.dir, "fy.tiff"))
    if fx.shape != fy.shape:
        fail("fx.tiff and fy.tiff differ in size")
    s = args.full_scale
    h, w = fx.shape
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2 * max(0.5, min(2.0, h / w)) + 1.2), dpi=100, layout="constrained")
    label = "normalised force (1 = black/white edge)"
    panels = [(fx, "fx (+ right)", "RdBu_r", -s, s), (fy, "fy (+ down)", "RdBu_r", -s, s),
              (np.hypot(fx, fy), "|F|", "gray", 0.0, s)]
    for ax, (plane, name, cmap, lo, hi) in zip(axes, panels):
        im = ax.imshow(plane, cmap=cmap, vmin=lo, vmax=hi, extent=(0, w, h, 0), interpolation="nearest")
        ax.set(title=name, xlabel="x [px]", ylabel="y [px] (down)")
        fig.colorbar(im, ax=ax, shrink=0.85, label=label)
    fig.suptitle(f"{args.title}\nfull colour = {s:.4g} ({args.scale_note})", fontsize="medium")
    fig.savefig(os.path.join(args.dir, "maps.png"))
    plt.close(fig)


def video(args):
    forces = read_columns(args.forces, ["t_s", "fx", "fy"])
    t = forces["t_s"]
    magnitude = [math.hypot(x, y) for x, y in zip(forces["fx"], forces["fy"])]
    try:
        with open(args.cuts, newline="") as f:
            cuts = [(int(r["frame"]), float(r["time"])) for r in csv.DictReader(f)]
    except OSError as e:
        fail(f"cannot read '{args.cuts}': {e.strerror}")
    except (KeyError, TypeError, ValueError):
        fail(f"'{args.cuts}' is not frame,time lines")
    fig, ax = plt.subplots(figsize=(10, 4), dpi=100, layout="constrained")
    ax.plot(t, forces["fx"], lw=0.8, color="tab:blue", label="fx")
    ax.plot(t, forces["fy"], lw=0.8, color="tab:green", label="fy")
    ax.plot(t, magnitude, lw=0.8, color="black", label="|F| lateral" if args.mode == "play" else "|F|")
    for k, (frame, time) in enumerate(cuts):
        ax.axvline(time, color="tab:orange", lw=1.0, ls="--", label="scene cut" if k == 0 else None)
        ax.annotate(f"cut, frame {frame}", (time, 1.0), xycoords=("data", "axes fraction"), rotation=90,
                    va="top", ha="right", fontsize="x-small", color="tab:orange")
    if args.mode == "play":
        ax.set(xlabel="video time [s] (1x from the first tick)", ylabel="lateral force commanded [N]",
               title=f"Force sent to the arm while playing: fx, fy (device frame); scene cuts found: {len(cuts)}")
    else:
        ax.set(xlabel="video time [s]", ylabel="normalised force (1 = black/white edge)",
               title=f"Force at the probes (fy down); scene cuts found: {len(cuts)}")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize="small")
    fig.savefig(args.out)
    plt.close(fig)


def strokes(args):
    path = os.path.join(args.dir, "strokes.csv")
    data = read_columns(path, ["stroke", "x_mm", "region", "ft_x_N", "ff_x_N", "data_texture_x_N"])
    try:
        with open(os.path.join(args.dir, "regions.csv"), newline="") as f:
            regions = {int(r["region"]): r for r in csv.DictReader(f)}
    except OSError as e:
        fail(f"cannot read '{os.path.join(args.dir, 'regions.csv')}': {e.strerror}")
    except (KeyError, TypeError, ValueError):
        fail("regions.csv is not region,gray_lo,gray_hi,name lines")
    def colour(region):  # the legend's colour in false_texture.png
        return regions.get(region, {}).get("colour") or plt.get_cmap("tab10")(region % 10)

    ids = sorted({int(s) for s in data["stroke"]})
    fig, axes = plt.subplots(len(ids), 1, figsize=(10, 2.6 * len(ids) + 0.8), dpi=100, layout="constrained",
                             sharex=True, squeeze=False)
    for ax, stroke in zip(axes[:, 0], ids):
        rows = [i for i, s in enumerate(data["stroke"]) if int(s) == stroke]
        x = [data["x_mm"][i] for i in rows]
        region = [int(data["region"][i]) for i in rows]
        start = 0
        for i in range(1, len(rows) + 1):  # the region under the stroke as coloured spans
            if i == len(rows) or region[i] != region[start]:
                if region[start] >= 0:
                    ax.axvspan(x[start], x[i - 1], color=colour(region[start]), alpha=0.2, lw=0)
                start = i
        ax.plot(x, [data["ft_x_N"][i] for i in rows], lw=0.7, color="black", label="false texture Fx")
        ax.plot(x, [data["ff_x_N"][i] for i in rows], lw=0.9, color="tab:red", label="brightness friction Fx")
        ax.plot(x, [data["data_texture_x_N"][i] for i in rows], lw=0.6, color="tab:purple", alpha=0.7,
                label="darkness-scaled texture Fx")
        ax.set(ylabel="force [N]", title=f"stroke {stroke + 1} of {len(ids)}")
        ax.grid(alpha=0.3)
    handles = [plt.Rectangle((0, 0), 1, 1, color=colour(k), alpha=0.35) for k in sorted(regions)]
    names = [f"gray {regions[k]['gray_lo']}..{regions[k]['gray_hi']}: {regions[k]['name']}" for k in sorted(regions)]
    lines, labels = axes[0, 0].get_legend_handles_labels()
    axes[0, 0].legend(lines + handles, labels + names, loc="upper right", fontsize="x-small", ncol=2)
    axes[-1, 0].set_xlabel("x along the stroke [mm] (the picture spans -50..50 mm; 50 mm/s, 1 N pressed)")
    fig.suptitle("false_texture: force along each stroke, regions shaded", fontsize="medium")
    fig.savefig(os.path.join(args.dir, "strokes.png"))
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true", help="exit 0 when matplotlib is present, 3 when not")
    parser.add_argument("--quiet-missing", action="store_true", help="exit 3 without a message when matplotlib is missing")
    sub = parser.add_subparsers(dest="command")
    s = sub.add_parser("servo", help="servo_demo's force and tick-period plots")
    s.add_argument("--trace", required=True)
    s.add_argument("--periods", required=True)
    s.add_argument("--nominal-ms", type=float, required=True)
    s.add_argument("--limit", type=float, required=True, help="the device's force limit [N]")
    s.add_argument("--out", required=True)
    t = sub.add_parser("texture", help="texture_gallery's trace and spectrum plots")
    t.add_argument("--dir", required=True)
    t.add_argument("--gallery-dpi", type=float, default=80.0, help="resolution of gallery.png [dots per inch]")
    t.add_argument("--quiet", action="store_true", help="list no files (texture_gallery lists them itself)")
    m = sub.add_parser("forcemap", help="tangible_image --maps: fx, fy and |F| with axes and colour bars")
    m.add_argument("--dir", required=True)
    m.add_argument("--full-scale", type=float, required=True, help="force at full colour (normalised)")
    m.add_argument("--title", default="force map")
    m.add_argument("--scale-note", default="", help="where the full scale comes from")
    v = sub.add_parser("video", help="tangible_video's force plot with its scene cuts")
    v.add_argument("--forces", required=True)
    v.add_argument("--cuts", required=True)
    v.add_argument("--mode", choices=["play", "probes"], required=True)
    v.add_argument("--out", required=True)
    k = sub.add_parser("strokes", help="false_texture's strokes with their regions")
    k.add_argument("--dir", required=True)
    vb = sub.add_parser("vibration", help="the vibration example's spectrum against the model's")
    vb.add_argument("--spectrum", required=True)
    vb.add_argument("--out", required=True, help="the PNG to write")
    vb.add_argument("--title", default="A 10 kHz HaTT model played at audio rate")
    args = parser.parse_args()
    if plt is None:
        if args.quiet_missing:  # the examples then try another interpreter or draw their own plots
            sys.exit(3)
        fail("matplotlib is not installed (Debian: python3-matplotlib)", 3)
    if args.check:
        return
    if args.command is None:
        parser.error("choose servo, texture, forcemap, video, strokes or vibration")
    if args.command == "vibration":
        folder = os.path.dirname(args.out) or "."
        if not os.path.isdir(folder):
            fail(f"--out: folder '{folder}' does not exist")
        vibration(args)
    elif args.command == "servo":
        if not os.path.isdir(args.out):
            fail(f"--out: '{args.out}' is not a folder")
        servo(args)
    elif args.command == "forcemap":
        if not (0 < args.full_scale < math.inf):
            parser.error("--full-scale must be a positive finite number")
        if not os.path.isdir(args.dir):
            fail(f"--dir: '{args.dir}' is not a folder")
        forcemap(args)
    elif args.command == "video":
        video(args)
    elif args.command == "strokes":
        if not os.path.isdir(args.dir):
            fail(f"--dir: '{args.dir}' is not a folder")
        strokes(args)
    else:
        if not (0 < args.gallery_dpi <= 600):
            parser.error("--gallery-dpi must be in (0, 600]")
        if not os.path.isdir(args.dir):
            fail(f"--dir: '{args.dir}' is not a folder")
        texture(args)


if __name__ == "__main__":
    main()
