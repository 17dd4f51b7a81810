#!/usr/bin/env python3
"""A sector of a solid disk (no hole): nodes on the cyclic symmetry axis, for tests/cyclic_axis.rs.

    python3 tools/meshes/make_disk_mesh.py [--out meshes/disk8.msh]

One N = 8 sector (45°) of a steel-sized disk of radius 0.1 m and thickness 0.01 m about the z
axis, 10-node tetrahedra (size 0.02 m), meshed periodically (Gmsh `setPeriodic`, rotation by
+45° about z from "low" to "high") so that every high-frontier node is the rotation of a low one.
The z-axis edge belongs to both frontiers. Physical groups: "volume" (3-D), "low" (the y = 0
face), "high" (the 45° face), "rim" (the cylindrical face r = 0.1 m, clamped in the test).
Written as MSH 4.1 ASCII. gmsh version pinned in tools/requirements-dev.txt.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

N, RADIUS, THICKNESS, SIZE = 8, 0.1, 0.01, 0.02


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("meshes/disk8.msh"))
    args = ap.parse_args(argv)
    import gmsh

    alpha = 2 * math.pi / N
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.option.setNumber("Mesh.MeshSizeMax", SIZE)
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.add("disk8")
    vol = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, THICKNESS, RADIUS, angle=alpha)
    gmsh.model.occ.synchronize()
    faces = {}
    for _, f in gmsh.model.getEntities(2):
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(2, f)
        if abs(z1 - z0) < 1e-6:
            continue  # top and bottom
        com = gmsh.model.occ.getCenterOfMass(2, f)
        angle = math.atan2(com[1], com[0])
        r = math.hypot(com[0], com[1])
        if abs(angle) < 1e-6:
            faces["low"] = f
        elif abs(angle - alpha / 2) < 1e-3 and r > 0.5 * RADIUS:
            faces["rim"] = f
        else:
            faces["high"] = f
    assert set(faces) == {"low", "high", "rim"}, faces
    c, s = math.cos(alpha), math.sin(alpha)
    rot = [c, -s, 0, 0, s, c, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
    gmsh.model.mesh.setPeriodic(2, [faces["high"]], [faces["low"]], rot)
    gmsh.model.addPhysicalGroup(3, [vol], name="volume")
    for name in ("low", "high", "rim"):
        gmsh.model.addPhysicalGroup(2, [faces[name]], name=name)
    gmsh.model.mesh.generate(3)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    gmsh.write(str(args.out))
    n_nodes = len(gmsh.model.mesh.getNodes()[0])
    gmsh.finalize()
    print(f"{args.out}: {n_nodes} nodes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
