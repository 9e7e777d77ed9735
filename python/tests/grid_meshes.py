"""Grid meshes for the tests: a square of n x n vertices cut into 2 (n - 1)^2 triangles facing +z."""
import numpy as np


def grid(n=12, size=0.04):
    """A flat square n x n vertices, 2 (n - 1)^2 triangles facing +z, centred on the origin [m]; each square's
    two triangles in turn, row by row."""
    x, y = np.meshgrid(np.linspace(-size / 2, size / 2, n), np.linspace(-size / 2, size / 2, n))
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    a = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    faces = np.stack([np.stack([a, a + 1, a + n + 1], axis=1), np.stack([a, a + n + 1, a + n], axis=1)], axis=1)
    return vertices, faces.reshape(-1, 3).astype(np.int64)


def wavy_height(x, y, amplitude=0.002, wavelength=0.03):
    """The wavy sheet's height at x, y [m]."""
    return amplitude * np.sin(2 * np.pi * x / wavelength) * np.sin(2 * np.pi * y / wavelength)


def wavy_grid(n, size=0.1):
    """grid(n, size) lifted to wavy_height: a sheet of hills and dips 2 mm high, 30 mm apart."""
    vertices, faces = grid(n, size)
    vertices[:, 2] = wavy_height(vertices[:, 0], vertices[:, 1])
    return vertices, faces
