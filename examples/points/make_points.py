"""Writes struts.ply, the point cloud of examples/sources.toml: a "scan" of three struts of
radius 0.15 along the axes through the cell's centre, as points on their outer surface with
outward normals (binary PLY, float32). Run from this directory: python3 make_points.py (needs
NumPy)."""

import numpy as np

R = 0.15
rng = np.random.default_rng(26)
rows = []
for axis in range(3):
    u, v = [a for a in range(3) if a != axis]
    t = rng.uniform(-0.5, 0.5, 1200)
    theta = rng.uniform(0.0, 2 * np.pi, 1200)
    p = np.zeros((1200, 3))
    n = np.zeros((1200, 3))
    p[:, axis] = t
    p[:, u], p[:, v] = R * np.cos(theta), R * np.sin(theta)
    n[:, u], n[:, v] = np.cos(theta), np.sin(theta)
    # Only what a scanner sees: the surface outside the other two struts.
    outside = np.ones(1200, bool)
    for other in range(3):
        if other != axis:
            rest = [a for a in range(3) if a != other]
            outside &= np.hypot(p[:, rest[0]], p[:, rest[1]]) >= R
    rows.append(np.hstack([p, n])[outside])
cloud = np.vstack(rows).astype("<f4")
header = (
    "ply\nformat binary_little_endian 1.0\n"
    f"comment three struts, made by make_points.py\nelement vertex {len(cloud)}\n"
    + "".join(f"property float {c}\n" for c in ["x", "y", "z", "nx", "ny", "nz"])
    + "end_header\n"
)
with open("struts.ply", "wb") as f:
    f.write(header.encode())
    f.write(cloud.tobytes())
