#!/usr/bin/env python3
"""Generate a large tetrahedral mesh for parser benchmarks (output is NOT committed).

    python3 tools/meshes/make_large_mesh.py OUT_PREFIX [--tets 1600000] [--order 2]

Writes OUT_PREFIX.v41-ascii.msh, OUT_PREFIX.v41-binary.msh, OUT_PREFIX.v22-ascii.msh and
OUT_PREFIX.v22-binary.msh: a box [0, 1] x [0, 0.5] x [0, 0.25] meshed with 10-node tetrahedra
(--order 2, default) or 4-node ones (--order 1), at least --tets of them, physical groups
"volume" (3), "bottom" (2, z = 0) and "top" (2, z = 0.25).
A good place is the git-ignored tools/large/ folder, e.g. `tools/large/box`.

The uniform mesh size is calibrated: a coarse first-order mesh (about --tets / 8 tetrahedra)
measures the tetrahedron density of the 3-D algorithm, the size is then chosen for about 4 % more
than --tets and refined again should the count still fall short; the second-order nodes are added
once at the end. Uses 2 threads (HXT 3-D algorithm). Measured: --tets 200000 takes 13 s and 0.2 GB
of memory on 2 cores; the default 1.6 M tetrahedra (~2.3 M nodes) should take 2-3 minutes,
~1.5 GB of memory and ~1 GB of disk for the four files together.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import gmsh

BOX = (1.0, 0.5, 0.25)
VARIANTS = [("v41-ascii", 4.1, 0), ("v41-binary", 4.1, 1), ("v22-ascii", 2.2, 0), ("v22-binary", 2.2, 1)]


def log(msg: str, t0: float) -> None:
    print(f"[{time.perf_counter() - t0:7.1f} s] {msg}", flush=True)


def mesh_box(h: float) -> int:
    """(Re)mesh the box with first-order tetrahedra of uniform size h; returns their number."""
    gmsh.model.mesh.clear()
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), h)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.model.mesh.generate(3)
    return sum(len(gmsh.model.mesh.getElementsByType(et)[0]) for et in gmsh.model.mesh.getElementTypes(3))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out_prefix", type=Path, help="output path prefix, e.g. tools/large/box")
    ap.add_argument("--tets", type=int, default=1_600_000, help="minimum number of tetrahedra")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--order", type=int, choices=(1, 2), default=2, help="element order")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()

    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", args.threads)
    gmsh.option.setNumber("Mesh.MaxNumThreads1D", args.threads)
    gmsh.option.setNumber("Mesh.MaxNumThreads2D", args.threads)
    gmsh.option.setNumber("Mesh.MaxNumThreads3D", args.threads)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)  # HXT: fast, parallel
    gmsh.option.setNumber("Mesh.Optimize", 1)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 1)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)
    gmsh.model.add("large_box")
    lx, ly, lz = BOX
    box = gmsh.model.occ.addBox(0, 0, 0, lx, ly, lz)
    gmsh.model.occ.synchronize()
    bottom = top = None
    for _, s in gmsh.model.getEntities(2):
        b = gmsh.model.getBoundingBox(2, s)
        if abs(b[5] - b[2]) < 1e-6:
            if abs(b[2]) < 1e-6:
                bottom = s
            elif abs(b[2] - lz) < 1e-6:
                top = s
    gmsh.model.addPhysicalGroup(3, [box], tag=1, name="volume")
    gmsh.model.addPhysicalGroup(2, [bottom], tag=2, name="bottom")
    gmsh.model.addPhysicalGroup(2, [top], tag=3, name="top")

    # calibration on a coarse mesh of about tets / 8 elements (first order: cheap), then mesh at the
    # calibrated size, refining again while the count falls short; second order only at the end
    volume = lx * ly * lz
    density_guess = 5.0  # tetrahedra per h^3
    target = 1.04 * args.tets
    n_cal = max(2000.0, args.tets / 8.0)
    h = (density_guess * volume / n_cal) ** (1.0 / 3.0)
    n = mesh_box(h)
    log(f"calibration: h = {h:.5g} -> {n} tetrahedra ({n * h**3 / volume:.2f} per h^3)", t0)
    # the density (tetrahedra per h^3) drops by ~10 % from the calibration to the final size
    n *= 0.9
    for _ in range(5):
        h *= (n / target) ** (1.0 / 3.0)
        n = mesh_box(h)
        log(f"h = {h:.5g}: {n} tetrahedra ({n * h**3 / volume:.2f} per h^3)", t0)
        if n >= args.tets:
            break
    else:
        print("could not reach the requested number of tetrahedra", file=sys.stderr)
        return 1
    if args.order == 2:
        gmsh.model.mesh.setOrder(2)
        n = sum(len(gmsh.model.mesh.getElementsByType(et)[0]) for et in gmsh.model.mesh.getElementTypes(3))
        log(f"second order: {n} 10-node tetrahedra", t0)

    n_nodes = len(gmsh.model.mesh.getNodes()[0])
    n_tri = sum(len(gmsh.model.mesh.getElements(2, s)[1][0]) for s in (bottom, top))
    args.out_prefix.parent.mkdir(parents=True, exist_ok=True)
    for suffix, version, binary in VARIANTS:
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.option.setNumber("Mesh.SaveParametric", 0)
        path = Path(f"{args.out_prefix}.{suffix}.msh")
        gmsh.write(str(path))
        log(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)", t0)
    gmsh.finalize()
    print(f"tetra{4 if args.order == 1 else 10} elements: {n}")
    print(f"triangle{3 if args.order == 1 else 6} elements (bottom + top): {n_tri}")
    print(f"nodes: {n_nodes}")
    log("done", t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
