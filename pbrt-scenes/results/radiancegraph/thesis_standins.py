#!/usr/bin/python3
"""Writes stand-in volumes for the radiance-graph thesis's scenes (repository tsvdh/PbrtScenes),
whose `bunny_cloud.nvdb` and `wdas_cloud_quarter.nvdb` are kept out of its snapshots (Git LFS).

Run with Debian's Python and OpenVDB (apt-get install python3-openvdb libnanovdb-tools), with
the thesis's scene repository as the argument:

    /usr/bin/python3 pbrt-scenes/results/radiancegraph/thesis_standins.py path/to/PbrtScenes

Each stand-in is a smooth, lumpy cloud of density up to 1 filling the box the scene's boundary
shape was made for, in the scene's medium space: for `disney-cloud/`, the 206 × 140 × 254 box
centred at (-10, 73, -42.5) that its bounding sphere encloses; for `bunny-cloud/`, a ball of
radius 36 inside its radius-45 sphere. They are not the Disney cloud or the bunny: the scenes'
lights, cameras, coefficients and configs are used unchanged, the images differ.
"""

import os
import subprocess
import sys
import tempfile

import numpy as np
import pyopenvdb as vdb


def lumps(x, y, z):
    """Deterministic smooth noise in [0, 1] from a few sines (no random state)."""
    n = (
        np.sin(1.7 * x + 0.3) * np.cos(1.3 * y - 0.7) * np.sin(1.1 * z + 1.9)
        + 0.5 * np.sin(3.1 * x - 1.2 * y + 0.4) * np.cos(2.9 * z + 0.8 * x)
        + 0.25 * np.sin(6.3 * y + 5.7 * z - 2.1) * np.cos(6.1 * x + 0.5)
    )
    return 0.5 + 0.5 * n / 1.75


def cloud(center, radii, voxel, path):
    """A fog volume: an ellipsoid with a soft edge, modulated by lumps(), voxel size `voxel`."""
    center, radii = np.array(center, float), np.array(radii, float)
    dims = tuple(int(np.ceil(2 * r / voxel)) + 2 for r in radii)
    origin = np.floor((center - radii) / voxel).astype(int) - 1
    i, j, k = np.meshgrid(*(np.arange(d) for d in dims), indexing="ij")
    p = (np.stack([i, j, k], -1) + origin + 0.5) * voxel
    u = (p - center) / radii
    r = np.sqrt((u * u).sum(-1))
    edge = np.clip((1.0 - r) / 0.25, 0.0, 1.0)
    d = edge * edge * (3 - 2 * edge) * (0.35 + 0.65 * lumps(u[..., 0] * 2, u[..., 1] * 2, u[..., 2] * 2))
    g = vdb.FloatGrid()
    g.name = "density"
    g.gridClass = vdb.GridClass.FOG_VOLUME
    g.copyFromArray(d.astype(np.float32), ijk=tuple(int(o) for o in origin), tolerance=1e-4)
    g.transform = vdb.createLinearTransform(voxelSize=voxel)
    with tempfile.TemporaryDirectory() as t:
        v = os.path.join(t, "c.vdb")
        vdb.write(v, grids=[g])
        subprocess.run(["nanovdb_convert", "-f", v, path], check=True, stdout=subprocess.DEVNULL)
    print(f"wrote {path}: {dims[0]}x{dims[1]}x{dims[2]} voxels of {voxel}")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    root = sys.argv[1]
    cloud((-10, 73, -42.5), (103, 70, 127), 2.0, os.path.join(root, "disney-cloud", "wdas_cloud_quarter.nvdb"))
    cloud((0, 0, 0), (36, 30, 33), 1.0, os.path.join(root, "bunny-cloud", "bunny_cloud.nvdb"))


if __name__ == "__main__":
    main()
