"""Synthetic video clips for the tests: lossless PNG sequences of known frames.

Scene 0 is a dark bar moving right 2 px a frame on a light ground; from frame
CUT on, scene 1 is a light disc on black. Image sequences play at 25 frames/s.
"""
import struct
import zlib

import numpy as np

FPS = 25.0  # an image sequence's rate [frames/s]
CUT = 8     # the first frame of the second scene


def write_png(path, gray):
    """An 8-bit gray PNG from an H x W array of levels [0, 255]."""
    h, w = gray.shape
    rows = b"".join(b"\x00" + bytes(row) for row in gray.astype(np.uint8))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def frame(k, w=96, h=64):
    """Frame k [gray levels]."""
    if k < CUT:
        m = np.full((h, w), 230.0)
        x = 20 + 2 * k
        m[10:h - 10, x:x + 12] = 30.0
    else:
        y, x = np.mgrid[0:h, 0:w]
        m = np.where((x - w / 2) ** 2 + (y - h / 2) ** 2 <= 18 ** 2, 220.0, 20.0)
    return m


def write_clip(directory, frames=16):
    """Writes the clip into directory (created); returns its printf pattern."""
    directory.mkdir(parents=True, exist_ok=True)
    for k in range(frames):
        write_png(directory / f"{k:04d}.png", frame(k))
    return str(directory / "%04d.png")
