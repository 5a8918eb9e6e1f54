"""Writes foam_scan.npy, the "CT scan" of examples/sources.toml: an open-cell foam (struts
along the cell edges, thickened at the nodes) seen as 8-bit grey values with the blur and
noise of a scanner. Run from this directory: python3 make_scan.py (needs NumPy)."""

import numpy as np

N = 40
rng = np.random.default_rng(26)

# Voxel centres of the cell [-1/2, 1/2]^3, array index [i, j, k] = (x, y, z).
c = (np.arange(N) + 0.5) / N - 0.5
x, y, z = np.meshgrid(c, c, c, indexing="ij")
tau = 2 * np.pi
# Solid where the sum of cosines is low: a network of struts through the cell's corners.
foam = np.cos(tau * x) + np.cos(tau * y) + np.cos(tau * z) < -0.9

grey = np.where(foam, 200.0, 40.0)
# The scanner's blur (a 3-voxel box, periodic) and noise.
for axis in range(3):
    grey = (np.roll(grey, -1, axis) + grey + np.roll(grey, 1, axis)) / 3
grey += rng.normal(0.0, 25.0, grey.shape)
np.save("foam_scan.npy", np.clip(grey, 0, 255).astype(np.uint8))
