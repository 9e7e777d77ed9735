#!/usr/bin/env python3
"""Corpus throughput of hapticfield.batch: files per second for the serial loop and Dask local clusters.

    PYTHONPATH=build/python python3 python/bench_batch.py [--pictures N] [--size WxH] [--workers 1,2]
                                                        [--processes] [--repeats R] [--folder DIR]

The corpus: N generated pictures of W x H px (noise over rings, so every mask has edges to find), or the
pictures of --folder; the jobs: a force map, a relief and its normals for each. Each configuration runs R
times into a fresh output folder (nothing to resume); its time includes starting and stopping the cluster, as
a user's run does. Prints a Markdown table: the best and mean time, files per second (best), and the speed-up
against the serial loop measured in the same run. Every run's outputs are checked byte for byte against the
serial loop's.
"""
import argparse
import os
import pathlib
import shutil
import statistics
import struct
import sys
import tempfile
import time
import zlib

import numpy as np

import hapticfield.batch as hb


def write_png(path, pixels):
    """An 8-bit gray PNG (H x W uint8), with zlib alone."""
    h, w = pixels.shape

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + pixels[y].tobytes() for y in range(h))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) +
                     chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def make_corpus(folder, count, width, height):
    rng = np.random.default_rng(1)
    y, x = np.mgrid[0:height, 0:width]
    for i in range(count):
        rings = 127.5 + 100.0 * np.sin(np.hypot(x - width * rng.random(), y - height * rng.random()) / (3 + i % 7))
        picture = np.clip(rings + rng.normal(0.0, 20.0, rings.shape), 0, 255).astype(np.uint8)
        write_png(folder / f"picture_{i:04d}.png", picture)


def files_of(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pictures", type=int, default=48)
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--workers", default="1,2")
    parser.add_argument("--threads", type=int, default=1, help="threads per worker")
    parser.add_argument("--processes", action="store_true", help="workers in processes of their own")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--folder", help="a folder of pictures instead of generated ones")
    a = parser.parse_args()
    width, height = (int(v) for v in a.size.split("x"))
    workers = [int(w) for w in a.workers.split(",")]
    if a.pictures < 1 or a.repeats < 1 or min(workers) < 1:
        parser.error("--pictures, --repeats and --workers must be >= 1")
    jobs = [hb.force_map(), hb.relief(), hb.normals()]
    work = pathlib.Path(tempfile.mkdtemp(prefix="bench_batch_"))
    try:
        corpus = pathlib.Path(a.folder) if a.folder else work / "corpus"
        if not a.folder:
            corpus.mkdir()
            make_corpus(corpus, a.pictures, width, height)
        count = len(hb.corpus(corpus))
        configurations = [("serial loop", "serial", 1)] + [
            (f"LocalCluster, {w} worker{'s' if w > 1 else ''} x {a.threads} thread{'s' if a.threads > 1 else ''}"
             f" ({'processes' if a.processes else 'threads'})", None, w) for w in workers]
        oracle = None
        rows = []
        for label, scheduler, w in configurations:
            times = []
            for r in range(a.repeats):
                out = work / f"out_{len(rows)}_{r}"
                start = time.perf_counter()
                report = hb.run(corpus, jobs, out, scheduler=scheduler, workers=w, threads_per_worker=a.threads,
                                processes=a.processes, progress=False)
                times.append(time.perf_counter() - start)
                if not report.ok:
                    sys.exit(f"bench_batch: {report.failed[0]}")
                made = files_of(out)
                if oracle is None:
                    oracle = made
                elif made != oracle:
                    sys.exit(f"bench_batch: {label} wrote other bytes than the serial loop")
                shutil.rmtree(out)
            rows.append((label, min(times), statistics.mean(times)))
        print(f"| {count} pictures ({a.size} px unless --folder), 3 jobs each, {a.repeats} repeats, "
              f"{os.cpu_count()} cores | best [s] | mean [s] | files/s (best) | speed-up (best) |")
        print("|---|---|---|---|---|")
        for label, best, mean in rows:
            print(f"| {label} | {best:.2f} | {mean:.2f} | {count / best:.1f} | {rows[0][1] / best:.2f} |")
        print("all outputs byte-identical to the serial loop's")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
