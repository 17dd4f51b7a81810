#!/usr/bin/env python3
"""Generate the Gmsh models bundled with nlrom (``meshes/``).

Usage::

    python3 tools/meshes/make_meshes.py            # all models
    python3 tools/meshes/make_meshes.py --only sector_conforming cube_tet4
    python3 tools/meshes/make_meshes.py --only sector8
    python3 tools/meshes/make_meshes.py --list

Every model is written in four variants:

* ``meshes/<name>.msh``                      MSH 4.1 ASCII (canonical)
* ``meshes/formats/<name>.v41-binary.msh``  MSH 4.1 binary
* ``meshes/formats/<name>.v22-ascii.msh``   MSH 2.2 ASCII
* ``meshes/formats/<name>.v22-binary.msh``  MSH 2.2 binary

Only elements of physical groups are saved (``Mesh.SaveAll=0``); every physical group has a name
and no elementary entity belongs to two physical groups of the same dimension (MSH 2.2 would
otherwise duplicate its elements). Physical tags are unique across dimensions.

The output is deterministic: one thread, a fixed random seed and every mesh option that matters
set explicitly (see ``reset_options``), so a re-run reproduces the files byte for byte with the
same Gmsh version (tools/requirements-dev.txt pins it).

The sector models follow docs conventions section 2 (cyclic symmetry): N sectors about the z axis
through the origin, the sector spans theta in [0, alpha], alpha = 2 pi / N; the high frontier
(theta = alpha) is the image of the low frontier (theta = 0) under the rotation R_alpha, node by
node, including the mid-edge nodes of the second-order elements. The script verifies this (and
the shroud-face properties) with assertions before writing anything.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

import gmsh

REPO = Path(__file__).resolve().parents[2]
MESH_DIR = REPO / "meshes"

# (suffix, MshFileVersion, Binary)
VARIANTS = [
    ("v41-ascii", 4.1, 0),  # canonical: meshes/<name>.msh
    ("v41-binary", 4.1, 1),
    ("v22-ascii", 2.2, 0),
    ("v22-binary", 2.2, 1),
]


def variant_path(out_dir: Path, name: str, suffix: str) -> Path:
    """Where variant ``suffix`` of model ``name`` is written (canonical = 4.1 ASCII)."""
    if suffix == "v41-ascii":
        return out_dir / f"{name}.msh"
    return out_dir / "formats" / f"{name}.{suffix}.msh"


# --------------------------------------------------------------------------------------------
# Gmsh session helpers
# --------------------------------------------------------------------------------------------


VERBOSE = False


def start(model_name: str, threads: int = 1) -> None:
    """Fresh Gmsh session (options back to their defaults, no config files read)."""
    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 1 if VERBOSE else 0)
    gmsh.option.setNumber("General.Verbosity", 5 if VERBOSE else 2)
    gmsh.model.add(model_name)
    reset_options(threads)


def reset_options(threads: int = 1) -> None:
    """Fix every option that influences the mesh or the files (determinism)."""
    num = gmsh.option.setNumber
    num("General.NumThreads", threads)
    num("Mesh.MaxNumThreads1D", threads)
    num("Mesh.MaxNumThreads2D", threads)
    num("Mesh.MaxNumThreads3D", threads)
    num("Mesh.RandomSeed", 1)
    num("Geometry.Tolerance", 1e-8)
    num("Geometry.OCCBooleanPreserveNumbering", 1)
    num("Mesh.Algorithm", 6)  # Frontal-Delaunay 2D
    num("Mesh.Algorithm3D", 1)  # Delaunay 3D
    num("Mesh.RecombineAll", 0)
    num("Mesh.RecombinationAlgorithm", 1)
    num("Mesh.SubdivisionAlgorithm", 0)
    num("Mesh.Optimize", 1)
    num("Mesh.OptimizeNetgen", 0)
    num("Mesh.OptimizeThreshold", 0.3)
    num("Mesh.Smoothing", 1)
    num("Mesh.MeshSizeFromPoints", 1)
    num("Mesh.MeshSizeFromCurvature", 0)
    num("Mesh.MeshSizeExtendFromBoundary", 1)
    num("Mesh.MeshSizeFactor", 1.0)
    num("Mesh.MeshSizeMin", 0.0)
    num("Mesh.MeshSizeMax", 1e22)
    num("Mesh.MinimumCirclePoints", 7)
    num("Mesh.MinimumCurvePoints", 3)
    num("Mesh.ElementOrder", 1)
    num("Mesh.SecondOrderIncomplete", 0)
    num("Mesh.SecondOrderLinear", 0)  # mid-edge nodes follow the geometry
    num("Mesh.HighOrderOptimize", 0)
    num("Mesh.ScalingFactor", 1.0)
    num("Mesh.FirstNodeTag", 1)
    num("Mesh.FirstElementTag", 1)
    # output
    num("Mesh.SaveAll", 0)
    num("Mesh.SaveParametric", 0)
    num("Mesh.SaveTopology", 0)
    num("Mesh.SaveGroupsOfNodes", 0)
    num("Mesh.SaveGroupsOfElements", 1)
    num("Mesh.SaveElementTagType", 1)
    num("Mesh.SaveWithoutOrphans", 0)
    num("Mesh.PreserveNumberingMsh2", 0)
    num("Mesh.PartitionSplitMeshFiles", 0)


def write_variants(name: str, out_dir: Path) -> list[Path]:
    """Write the current model in the four variants; returns the paths."""
    (out_dir / "formats").mkdir(parents=True, exist_ok=True)
    paths = []
    for suffix, version, binary in VARIANTS:
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.option.setNumber("Mesh.SaveParametric", 0)
        path = variant_path(out_dir, name, suffix)
        gmsh.write(str(path))
        paths.append(path)
    return paths


def add_group(dim: int, tags: list[int], name: str, tag: int) -> None:
    gmsh.model.addPhysicalGroup(dim, list(tags), tag=tag, name=name)


def check_groups_disjoint() -> None:
    """No elementary entity may belong to two physical groups of the same dimension."""
    for dim in range(4):
        seen: dict[int, str] = {}
        for d, ptag in gmsh.model.getPhysicalGroups(dim):
            name = gmsh.model.getPhysicalName(d, ptag)
            assert name, f"physical group ({d}, {ptag}) has no name"
            for ent in gmsh.model.getEntitiesForPhysicalGroup(d, ptag):
                assert ent not in seen, (
                    f"entity ({d}, {ent}) is in physical groups {seen[ent]!r} and {name!r}"
                )
                seen[int(ent)] = name
    tags = [t for _, t in gmsh.model.getPhysicalGroups()]
    assert len(tags) == len(set(tags)), f"physical tags are not unique across dimensions: {tags}"


def mesh_stats() -> dict:
    """Node and element counts of what will be written (elements of physical groups only)."""
    counts: dict[str, int] = {}
    node_tags: set[int] = set()
    for dim, ptag in gmsh.model.getPhysicalGroups():
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            etypes, etags, enodes = gmsh.model.mesh.getElements(dim, ent)
            for et, tg, nd in zip(etypes, etags, enodes):
                ename = gmsh.model.mesh.getElementProperties(et)[0]
                counts[ename] = counts.get(ename, 0) + len(tg)
                node_tags.update(int(n) for n in nd)
    all_nodes = gmsh.model.mesh.getNodes()[0]
    return {"nodes": len(all_nodes), "used_nodes": len(node_tags), "elements": counts}


def rotation_z(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def affine_rotation_z(theta: float) -> list[float]:
    """Row-major 4x4 affine transform (rotation by theta about z) for gmsh setPeriodic."""
    a = np.eye(4)
    a[:3, :3] = rotation_z(theta)
    return [float(v) for v in a.reshape(-1)]


def face_mesh_nodes(dim: int, tag: int) -> np.ndarray:
    """Coordinates (n x 3) of every node used by the elements of an entity, mid-edge ones included."""
    _, _, enodes = gmsh.model.mesh.getElements(dim, tag)
    tags = np.unique(np.concatenate([np.asarray(n, dtype=np.int64) for n in enodes]))
    coords = np.empty((len(tags), 3))
    for i, t in enumerate(tags):
        coords[i] = gmsh.model.mesh.getNode(int(t))[0]
    return coords


def match_by_position(src: np.ndarray, dst: np.ndarray, tol: float) -> float:
    """Check that the point sets src and dst coincide one to one; returns the max distance."""
    from scipy.spatial import cKDTree

    assert src.shape == dst.shape, f"node counts differ: {len(src)} vs {len(dst)}"
    tree = cKDTree(dst)
    dist, idx = tree.query(src)
    assert len(np.unique(idx)) == len(idx), "matching is not one to one"
    worst = float(dist.max()) if len(dist) else 0.0
    assert worst <= tol, f"unmatched node: distance {worst:.3e} > tol {tol:.3e} at {src[dist.argmax()]}"
    return worst


# --------------------------------------------------------------------------------------------
# a) Shrouded bladed-disk sector
# --------------------------------------------------------------------------------------------


@dataclasses.dataclass
class SectorParams:
    n_sectors: int = 24
    # disk: annular sector
    r_hub: float = 0.10
    r_rim: float = 0.15
    z_min: float = 0.0
    z_max: float = 0.03
    # blade: thin plate with tapered (sharp) leading and trailing edges, radial span to r_tip
    r_tip: float = 0.25
    chord: float = 0.03
    thickness: float = 0.004
    taper: float = 0.005  # chordwise length of the tapered edge zones
    stagger_deg: float = 30.0  # angle of the chord from the z axis, in the z/theta plane
    root_depth: float = 0.01  # the plate starts this far inside the rim (fused into the disk)
    # tip shroud: annular block over the whole sector angle
    shroud_height: float = 0.01  # radial: r in [r_tip, r_tip + shroud_height]
    shroud_z_min: float = 0.0  # covers the whole axial extent of the staggered blade
    shroud_z_max: float = 0.03
    # mesh sizes (m)
    h_disk: float = 0.015
    h_blade: float = 0.005
    h_shroud: float = 0.007
    h_contact: float = 0.005  # structured mesh of the shroud contact face (theta = alpha)
    # non-conforming variant: mesh size factor on the shroud target face (theta = 0).
    # None = conforming (shroud faces periodic, the contact face is the master).
    target_size_factor: float | None = None
    order: int = 2

    @property
    def alpha(self) -> float:
        return 2.0 * math.pi / self.n_sectors

    @property
    def size(self) -> float:
        return self.r_tip + self.shroud_height


def _revolved_annulus(r0: float, r1: float, z0: float, z1: float, angle: float) -> int:
    """Annular sector r in [r0, r1], z in [z0, z1], theta in [0, angle] (revolved rectangle)."""
    occ = gmsh.model.occ
    rect = occ.addRectangle(r0, 0.0, 0.0, r1 - r0, z1 - z0)  # in the xy plane
    occ.rotate([(2, rect)], 0, 0, 0, 1, 0, 0, math.pi / 2)  # (x, y, 0) -> (x, 0, y)
    occ.translate([(2, rect)], 0, 0, z0)
    out = occ.revolve([(2, rect)], 0, 0, 0, 0, 0, 1, angle)
    vols = [t for d, t in out if d == 3]
    assert len(vols) == 1
    return vols[0]


def _blade_local_to_global(p: SectorParams, xyz) -> np.ndarray:
    """Blade local frame: x radial, y thickness, z chord (centred) -> global coordinates.

    The chord is rotated by the stagger angle about the radial axis (so it lies in the z/theta
    plane), centred axially on the disk and the plate is centred on theta = alpha / 2.
    """
    x, y, z = xyz
    b = math.radians(p.stagger_deg)
    y2 = y * math.cos(b) - z * math.sin(b)
    z2 = y * math.sin(b) + z * math.cos(b) + 0.5 * (p.z_min + p.z_max)
    return rotation_z(p.alpha / 2) @ np.array([x, y2, z2])


def build_sector_geometry(p: SectorParams) -> dict:
    """Create the fused sector volume; returns the tags of the entities of interest."""
    occ = gmsh.model.occ
    a = p.alpha
    disk = _revolved_annulus(p.r_hub, p.r_rim, p.z_min, p.z_max, a)
    r_sh = p.r_tip + p.shroud_height
    shroud = _revolved_annulus(p.r_tip, r_sh, p.shroud_z_min, p.shroud_z_max, a)

    # blade: hexagonal plate profile in the local (y, z) plane, extruded along local x (radial)
    c, t, ch = 0.5 * p.chord, 0.5 * p.thickness, 0.5 * p.chord - p.taper
    profile = [(0.0, -c), (t, -ch), (t, ch), (0.0, c), (-t, ch), (-t, -ch)]  # (y, z)
    x0 = p.r_rim - p.root_depth
    x1 = p.r_tip + 0.5 * p.shroud_height
    pts = [occ.addPoint(x0, y, z) for y, z in profile]
    lines = [occ.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    out = occ.extrude([(2, surf)], x1 - x0, 0, 0)
    blade = [tg for d, tg in out if d == 3][0]
    occ.rotate([(3, blade)], 0, 0, 0, 1, 0, 0, math.radians(p.stagger_deg))
    occ.translate([(3, blade)], 0, 0, 0.5 * (p.z_min + p.z_max))
    occ.rotate([(3, blade)], 0, 0, 0, 0, 0, 1, a / 2)

    fused, _ = occ.fuse([(3, disk)], [(3, blade), (3, shroud)])
    assert len(fused) == 1 and fused[0][0] == 3, f"fuse gave {fused}"

    # excitation point: middle of the free part of the leading edge (local y = 0, z = -c), i.e.
    # halfway between where that edge leaves the rim (r = r_rim) and enters the shroud (r = r_tip)
    e0 = rotation_z(-a / 2) @ _blade_local_to_global(p, (0.0, 0.0, -c))  # x = 0 on that line
    off = e0[1]  # circumferential offset of the edge line from the blade mid-plane
    xa = math.sqrt(p.r_rim**2 - off**2)
    xb = math.sqrt(p.r_tip**2 - off**2)
    pe = _blade_local_to_global(p, (0.5 * (xa + xb), 0.0, -c))
    pt = occ.addPoint(*pe)
    frag, fmap = occ.fragment(fused, [(0, pt)])
    occ.synchronize()
    vols = gmsh.model.getEntities(3)
    assert len(vols) == 1, f"expected one volume, got {vols}"
    pt_new = [tg for d, tg in fmap[1] if d == 0]
    assert len(pt_new) == 1
    pt = pt_new[0]
    adj_up, _ = gmsh.model.getAdjacencies(0, pt)
    assert len(adj_up) == 2, f"excitation point is not on the leading-edge curve (adjacent curves {adj_up})"
    assert np.allclose(gmsh.model.getValue(0, pt, []), pe, atol=1e-12)

    # identify the faces
    tol = 1e-9 * p.size
    found = {k: [] for k in ("left", "right", "hub", "target", "contact")}
    for _, s in gmsh.model.getEntities(2):
        kind = gmsh.model.getType(2, s)
        cx, cy, cz = occ.getCenterOfMass(2, s)
        r, th = math.hypot(cx, cy), math.atan2(cy, cx)
        if kind == "Plane":
            # a face on a radial plane theta = const: all its bounding-box corners satisfy it
            on0 = abs(th) < 1e-9
            ona = abs(th - a) < 1e-9
            if on0 or ona:
                side = "left" if r < p.r_rim + tol else ("target" if r > p.r_tip - tol else None)
                assert side is not None, f"unexpected radial-plane face {s} at r={r}"
                if ona:
                    side = {"left": "right", "target": "contact"}[side]
                found[side].append(s)
        elif kind == "Cylinder" and abs(r - p.r_hub) < 0.1 * (p.r_rim - p.r_hub):
            found["hub"].append(s)
    for k, v in found.items():
        assert len(v) == 1, f"face {k}: found {v}"
    faces = {k: v[0] for k, v in found.items()}
    faces["volume"] = vols[0][1]
    faces["excitation"] = pt
    return faces


def _set_sector_sizes(p: SectorParams, faces: dict) -> None:
    """Mesh sizes at the geometry points (sizes inside entities are interpolated from them)."""
    a = p.alpha
    target_pts = {t for _, t in gmsh.model.getBoundary([(2, faces["target"])], recursive=True)}
    for _, t in gmsh.model.getEntities(0):
        x, y, z = gmsh.model.getValue(0, t, [])
        r, th = math.hypot(x, y), math.atan2(y, x)
        on_frontier = abs(th) < 1e-9 or abs(th - a) < 1e-9
        if on_frontier and r < p.r_rim + 1e-9:
            h = p.h_disk  # the 8 corners of the disk
        elif on_frontier:
            h = p.h_shroud  # the 8 corners of the shroud
            if t in target_pts and p.target_size_factor is not None:
                h = p.target_size_factor * p.h_contact
        else:
            h = p.h_blade  # blade/rim and blade/shroud intersections, excitation point
        gmsh.model.mesh.setSize([(0, t)], h)


def _set_transfinite_rectangle(surface: int, h: float) -> None:
    """Structured triangles on a 4-sided face: ceil(length / h) segments on each side."""
    curves = [c for _, c in gmsh.model.getBoundary([(2, surface)], oriented=False)]
    assert len(curves) == 4, f"face {surface} has {len(curves)} sides"
    for c in curves:
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        ends = gmsh.model.getValue(1, c, [lo[0], hi[0]]).reshape(2, 3)
        length = float(np.linalg.norm(ends[1] - ends[0]))  # the sides are straight segments
        gmsh.model.mesh.setTransfiniteCurve(c, max(1, math.ceil(length / h - 1e-9)) + 1)
    gmsh.model.mesh.setTransfiniteSurface(surface, arrangement="Alternate")


def make_sector(name: str, p: SectorParams, out_dir: Path, reference_contact: np.ndarray | None = None):
    """Build, mesh, verify and write one sector model. Returns the contact-face node coordinates."""
    start(name)
    faces = build_sector_geometry(p)
    a = p.alpha
    _set_sector_sizes(p, faces)
    gmsh.option.setNumber("Mesh.MeshSizeMax", p.h_disk)
    gmsh.option.setNumber("Mesh.ElementOrder", p.order)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)

    # periodicity: high frontier (slave) = R_alpha(low frontier (master))
    gmsh.model.mesh.setPeriodic(2, [faces["right"]], [faces["left"]], affine_rotation_z(+a))
    # The shroud contact face (theta = alpha) gets a structured (transfinite) mesh. It must be
    # identical in the conforming and the non-conforming model, and an unstructured mesh was not:
    # with the same sizes and the same boundary discretisation, Gmsh 4.15 meshed the face
    # differently once it became a periodic master or once the target face changed (most likely
    # because the 2-D algorithms draw from one random sequence shared by all surfaces, meshed in turn).
    _set_transfinite_rectangle(faces["contact"], p.h_contact)
    if p.target_size_factor is None:
        # conforming: the contact face is the MASTER and the target face its image under R_alpha^-1
        gmsh.model.mesh.setPeriodic(2, [faces["target"]], [faces["contact"]], affine_rotation_z(-a))

    add_group(3, [faces["volume"]], "volume", 1)
    add_group(2, [faces["left"]], "left_frontier", 2)
    add_group(2, [faces["right"]], "right_frontier", 3)
    add_group(2, [faces["hub"]], "hub", 4)
    add_group(2, [faces["contact"]], "shroud_contact", 5)
    add_group(2, [faces["target"]], "shroud_target", 6)
    add_group(0, [faces["excitation"]], "excitation", 7)
    check_groups_disjoint()

    gmsh.model.mesh.generate(3)

    # ---- verification (all nodes of the faces' elements, mid-edge nodes included) ----
    tol = 1e-9 * p.size
    R = rotation_z(a)
    left = face_mesh_nodes(2, faces["left"])
    right = face_mesh_nodes(2, faces["right"])
    d_front = match_by_position(left @ R.T, right, tol)
    target = face_mesh_nodes(2, faces["target"])
    contact = face_mesh_nodes(2, faces["contact"])
    report = {"frontier_nodes": len(left), "frontier_maxdist": d_front,
              "target_nodes": len(target), "contact_nodes": len(contact)}
    if p.target_size_factor is None:
        report["shroud_maxdist"] = match_by_position(target @ R.T, contact, tol)
    else:
        assert len(target) != len(contact), "non-conforming shroud faces have the same node count"
    if reference_contact is not None:
        # the contact face must be node for node the one of the conforming model (to 1e-12 m);
        # pairing by nearest neighbour (one to one) rather than by a lexicographic sort, which a
        # 1-ulp difference in one coordinate could reorder
        assert contact.shape == reference_contact.shape, (
            f"contact face: {len(contact)} nodes vs {len(reference_contact)} in the reference")
        report["contact_vs_reference"] = match_by_position(contact, reference_contact, 1e-12)
    ex = faces["excitation"]
    en = gmsh.model.mesh.getNodes(0, ex)
    assert len(en[0]) == 1
    report["excitation_node"] = int(en[0][0])
    report["excitation_xyz"] = [float(v) for v in en[1]]
    (etype,), (etags,), _ = gmsh.model.mesh.getElements(3)
    report["min_sicn"] = float(np.min(gmsh.model.mesh.getElementQualities(etags, "minSICN")))
    report.update(mesh_stats())
    write_variants(name, out_dir)
    gmsh.finalize()
    return contact, report


# --------------------------------------------------------------------------------------------
# b) small meshes for unit tests
# --------------------------------------------------------------------------------------------


def _faces_at(axis: int, value: float, tol: float = 1e-6) -> list[int]:
    """Surfaces lying in the plane x[axis] = value (OCC bounding boxes are padded by 1e-7)."""
    out = []
    for _, s in gmsh.model.getEntities(2):
        b = gmsh.model.getBoundingBox(2, s)
        if abs(b[axis] - value) < tol and abs(b[axis + 3] - value) < tol:
            out.append(s)
    return out


def make_cube(name: str, order: int, h: float, out_dir: Path) -> dict:
    """Unit cube [0,1]^3, tetrahedra of order 1 or 2; groups volume, bottom (z=0), top (z=1)."""
    start(name)
    occ = gmsh.model.occ
    box = occ.addBox(0, 0, 0, 1, 1, 1)
    occ.synchronize()
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    add_group(3, [box], "volume", 1)
    add_group(2, _faces_at(2, 0.0), "bottom", 2)
    add_group(2, _faces_at(2, 1.0), "top", 3)
    check_groups_disjoint()
    gmsh.model.mesh.generate(3)
    stats = mesh_stats()
    write_variants(name, out_dir)
    gmsh.finalize()
    return stats


def make_bar(name: str, kind: str, out_dir: Path, length: float = 1.0, side: float = 0.05,
             nx: int = 40, ny: int = 2, h_tet: float = 0.03) -> dict:
    """Slender cantilever bar [0,L] x [0,a] x [0,a]; groups volume, clamp (x=0), tip (x=L).

    kind = "hex20": transfinite, recombined, serendipity 20-node hexahedra (nx x ny x ny);
    kind = "tet10": unstructured 10-node tetrahedra of size h_tet.
    """
    start(name)
    occ = gmsh.model.occ
    box = occ.addBox(0, 0, 0, length, side, side)
    occ.synchronize()
    if kind == "hex20":
        for _, c in gmsh.model.getEntities(1):
            b = gmsh.model.getBoundingBox(1, c)
            along_x = (b[3] - b[0]) > 0.5 * length
            gmsh.model.mesh.setTransfiniteCurve(c, (nx if along_x else ny) + 1)
        for _, s in gmsh.model.getEntities(2):
            gmsh.model.mesh.setTransfiniteSurface(s)
            gmsh.model.mesh.setRecombine(2, s)
        gmsh.model.mesh.setTransfiniteVolume(box)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
    else:
        gmsh.model.mesh.setSize(gmsh.model.getEntities(0), h_tet)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h_tet)
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    add_group(3, [box], "volume", 1)
    add_group(2, _faces_at(0, 0.0), "clamp", 2)
    add_group(2, _faces_at(0, length), "tip", 3)
    check_groups_disjoint()
    gmsh.model.mesh.generate(3)
    stats = mesh_stats()
    write_variants(name, out_dir)
    gmsh.finalize()
    return stats


def make_blade(name: str, cells: tuple[int, int, int], out_dir: Path, chord: float = 0.03,
               thickness: float = 0.004, span: float = 0.05, r_root: float = 0.2) -> dict:
    """Straight cantilever blade surrogate of Thorin et al. (2018)'s simple sector: the box
    [0, chord] x [-thickness/2, thickness/2] x [r_root, r_root + span] (x axial along the rotation
    axis, y circumferential, z radial), transfinite serendipity 20-node hexahedra with
    cells = (n_chord, n_thickness, n_span) (n_thickness even). The two halves y < 0 and y > 0 are
    fragmented so that the tip has an edge on the mid-thickness line y = 0.
    Groups: volume (3), root (2, z = r_root), tip_contact (1, the tip line y = 0, z = r_root + span).
    """
    nx, ny, nz = cells
    assert ny % 2 == 0, "the thickness cell count must be even (a node line at y = 0)"
    start(name)
    occ = gmsh.model.occ
    lo = occ.addBox(0, -thickness / 2, r_root, chord, thickness / 2, span)
    hi = occ.addBox(0, 0, r_root, chord, thickness / 2, span)
    occ.fragment([(3, lo)], [(3, hi)])
    occ.synchronize()
    for _, c in gmsh.model.getEntities(1):
        b = gmsh.model.getBoundingBox(1, c)
        ext = [b[3] - b[0], b[4] - b[1], b[5] - b[2]]
        axis = max(range(3), key=lambda k: ext[k])
        n = [nx, ny // 2, nz][axis]
        gmsh.model.mesh.setTransfiniteCurve(c, n + 1)
    for _, s in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(s)
        gmsh.model.mesh.setRecombine(2, s)
    for _, v in gmsh.model.getEntities(3):
        gmsh.model.mesh.setTransfiniteVolume(v)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1)
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    z_tip = r_root + span
    tip_line = []
    for _, c in gmsh.model.getEntities(1):
        b = gmsh.model.getBoundingBox(1, c)
        if abs(b[1]) < 1e-6 and abs(b[4]) < 1e-6 and abs(b[2] - z_tip) < 1e-6 and abs(b[5] - z_tip) < 1e-6:
            tip_line.append(c)
    assert len(tip_line) == 1, f"tip line curves: {tip_line}"
    add_group(3, [v for _, v in gmsh.model.getEntities(3)], "volume", 1)
    add_group(2, _faces_at(2, r_root), "root", 2)
    add_group(1, tip_line, "tip_contact", 3)
    check_groups_disjoint()
    gmsh.model.mesh.generate(3)
    stats = mesh_stats()
    write_variants(name, out_dir)
    gmsh.finalize()
    return stats


def make_damper_bar(name: str, out_dir: Path, length: float = 1.25, side: float = 0.01,
                    nx: int = 40) -> dict:
    """Bar damper on a mesh: the bar [0,L] x [0,a] x [0,a] clamped at x = 0 and pressed between
    two pads on its faces z = 0 and z = a (the distributed microslip bar of Cigeroglu, An & Menq
    2007, section 4.1, as a solid). Transfinite first-order hexahedra, nx x 1 x 1, so the mesh is
    symmetric about the planes y = a/2 and z = a/2.
    Groups: volume (3), clamp (2, x = 0), tip (2, x = L), pads (2, the faces z = 0 and z = a).
    """
    start(name)
    occ = gmsh.model.occ
    box = occ.addBox(0, 0, 0, length, side, side)
    occ.synchronize()
    for _, c in gmsh.model.getEntities(1):
        b = gmsh.model.getBoundingBox(1, c)
        along_x = (b[3] - b[0]) > 0.5 * length
        gmsh.model.mesh.setTransfiniteCurve(c, (nx if along_x else 1) + 1)
    for _, s in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(s)
        gmsh.model.mesh.setRecombine(2, s)
    gmsh.model.mesh.setTransfiniteVolume(box)
    add_group(3, [box], "volume", 1)
    add_group(2, _faces_at(0, 0.0), "clamp", 2)
    add_group(2, _faces_at(0, length), "tip", 3)
    add_group(2, _faces_at(2, 0.0) + _faces_at(2, side), "pads", 4)
    check_groups_disjoint()
    gmsh.model.mesh.generate(3)
    stats = mesh_stats()
    write_variants(name, out_dir)
    gmsh.finalize()
    return stats


def make_mixed(name: str, order: int, incomplete: bool, out_dir: Path) -> dict:
    """A small mesh with as many element types as Gmsh makes, for parser coverage.

    Layout (all in [0,2] x [0,1] x [0,2]):
      * z in [0,1], x in [0,1]: structured hexahedra (transfinite quads extruded in 2 layers)
      * z in [0,1], x in [1,2]: prisms (triangulated rectangle extruded in 2 layers, recombined)
      * z in [1,2]: unstructured tetrahedra on top; above the hexahedra the bottom face of the tet
        region is made of quadrangles, so Gmsh inserts pyramids there.
    Physical groups: hexes, prisms, tets (3), bottom (2: quads + triangles), edge (1), corner (0).
    """
    start(name)
    occ = gmsh.model.occ
    s0 = occ.addRectangle(0, 0, 0, 1, 1)
    s1 = occ.addRectangle(1, 0, 0, 1, 1)
    occ.fragment([(2, s0)], [(2, s1)])
    occ.synchronize()
    lower = occ.extrude([(2, s0), (2, s1)], 0, 0, 1, numElements=[2], recombine=True)
    occ.synchronize()
    lower_vols = [t for d, t in lower if d == 3]
    tops = [lower[i - 1] for i, (d, t) in enumerate(lower) if d == 3]  # extrude: [top, vol, sides]
    upper = occ.extrude(tops, 0, 0, 1)
    occ.synchronize()
    upper_vols = [t for d, t in upper if d == 3]
    assert len(lower_vols) == 2 and len(upper_vols) == 2

    def vol_at(x: float, z: float) -> int:
        for _, v in gmsh.model.getEntities(3):
            b = gmsh.model.getBoundingBox(3, v)
            if b[0] - 1e-7 <= x <= b[3] + 1e-7 and b[2] - 1e-7 <= z <= b[5] + 1e-7:
                return v
        raise AssertionError

    hexv, prismv = vol_at(0.5, 0.5), vol_at(1.5, 0.5)
    # s0: 2 x 2 transfinite quads; the edge shared with s1 has 3 nodes too
    for _, c in gmsh.model.getBoundary([(2, s0)], oriented=False):
        gmsh.model.mesh.setTransfiniteCurve(c, 3)
    gmsh.model.mesh.setTransfiniteSurface(s0)
    gmsh.model.mesh.setRecombine(2, s0)
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), 0.5)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1 if incomplete else 0)

    add_group(3, [hexv], "hexes", 1)
    add_group(3, [prismv], "prisms", 2)
    add_group(3, upper_vols, "tets", 3)
    add_group(2, [s0, s1], "bottom", 4)
    edge = [c for _, c in gmsh.model.getEntities(1)
            if np.allclose(gmsh.model.getBoundingBox(1, c), [0, 0, 0, 0, 0, 2], atol=1e-6)]
    if not edge:  # the vertical edge x=y=0 is split at z=1: take the lower part
        edge = [c for _, c in gmsh.model.getEntities(1)
                if np.allclose(gmsh.model.getBoundingBox(1, c), [0, 0, 0, 0, 0, 1], atol=1e-6)]
    assert len(edge) == 1, f"edge x=y=0: {edge}"
    add_group(1, edge, "edge", 5)
    corner = [t for _, t in gmsh.model.getEntities(0)
              if np.allclose(gmsh.model.getValue(0, t, []), [0, 0, 0], atol=1e-9)]
    add_group(0, corner, "corner", 6)
    check_groups_disjoint()
    gmsh.model.mesh.generate(3)
    stats = mesh_stats()
    expected = {
        1: ["Point", "Line 2", "Triangle 3", "Quadrilateral 4", "Tetrahedron 4", "Hexahedron 8",
            "Prism 6", "Pyramid 5"],
        2: ["Point", "Line 3", "Triangle 6", "Quadrilateral 9", "Tetrahedron 10", "Hexahedron 27",
            "Prism 18", "Pyramid 14"],
        3: ["Point", "Line 3", "Triangle 6", "Quadrilateral 8", "Tetrahedron 10", "Hexahedron 20",
            "Prism 15", "Pyramid 13"],
    }[order + (1 if incomplete else 0)]
    assert sorted(stats["elements"]) == sorted(expected), f"element types {sorted(stats['elements'])}"
    write_variants(name, out_dir)
    gmsh.finalize()
    return stats


# --------------------------------------------------------------------------------------------


def sector_params(variant: str, **overrides) -> SectorParams:
    """Parameters of the bundled sector variants; overrides allow new variants (e.g. n_sectors=6)."""
    p = SectorParams(**overrides)
    if variant == "sector8":
        # N = 8 (alpha = 45 deg), coarse, for full-annulus tests (8 copies merged at the frontiers).
        # Thicker disk and shroud, wider and thicker blade than the N = 24 sector so that coarse
        # elements stay valid (min SICN 0.15); the shroud still spans exactly theta in [0, alpha].
        base = dict(n_sectors=8, z_max=0.04, chord=0.04, thickness=0.008, taper=0.008,
                    shroud_height=0.02, shroud_z_max=0.04, h_disk=0.03, h_blade=0.012,
                    h_shroud=0.025, h_contact=0.01)
        base.update(overrides)
        p = SectorParams(**base)
    if variant == "nonconforming":
        # finer target face (0.6 x the contact face's size): 213 target nodes against 65
        p.target_size_factor = 0.6 if p.target_size_factor is None else p.target_size_factor
    if variant == "coarse_target":
        # coarser target face (2 x): 33 target nodes against 65 contact nodes, about the ratio of
        # the paper's FEM2 (Battiato 2021, Table 1: 169 target nodes against 289 contact nodes)
        p.target_size_factor = 2.0 if p.target_size_factor is None else p.target_size_factor
    return p


MODELS = ["sector_conforming", "sector_nonconforming", "sector_coarse_target", "cube_tet4", "cube_tet10",
          "bar_hex20", "bar_tet10", "mixed_o1", "mixed_o2", "mixed_o2i", "sector8", "blade", "blade_coarse",
          "damper_bar"]


def build_all(out_dir: Path, only: list[str] | None) -> None:
    jobs = list(MODELS)
    if only:
        unknown = set(only) - set(jobs)
        assert not unknown, f"unknown models {unknown}; known: {jobs}"
        needs_reference = {"sector_nonconforming", "sector_coarse_target"} & set(only)
        if needs_reference and "sector_conforming" not in only:
            only = ["sector_conforming"] + list(only)  # needed for the contact-face comparison
        jobs = [j for j in jobs if j in only]
    t_all = time.perf_counter()
    reference_contact = None
    for job in jobs:
        t0 = time.perf_counter()
        if job == "sector_conforming":
            reference_contact, info = make_sector(job, sector_params("conforming"), out_dir)
        elif job == "sector_nonconforming":
            _, info = make_sector(job, sector_params("nonconforming"), out_dir, reference_contact)
        elif job == "sector_coarse_target":
            _, info = make_sector(job, sector_params("coarse_target"), out_dir, reference_contact)
        elif job == "sector8":
            _, info = make_sector(job, sector_params("sector8"), out_dir)
        elif job == "cube_tet4":
            info = make_cube(job, 1, 0.15, out_dir)
        elif job == "cube_tet10":
            info = make_cube(job, 2, 0.35, out_dir)
        elif job == "bar_hex20":
            info = make_bar(job, "hex20", out_dir)
        elif job == "bar_tet10":
            info = make_bar(job, "tet10", out_dir)
        elif job == "blade":
            info = make_blade(job, (3, 2, 12), out_dir)
        elif job == "blade_coarse":
            info = make_blade(job, (2, 2, 4), out_dir)
        elif job == "damper_bar":
            info = make_damper_bar(job, out_dir)
        elif job == "mixed_o1":
            info = make_mixed(job, 1, False, out_dir)
        elif job == "mixed_o2":
            info = make_mixed(job, 2, False, out_dir)
        elif job == "mixed_o2i":
            info = make_mixed(job, 2, True, out_dir)
        dt = time.perf_counter() - t0
        print(f"{job:22s} {dt:6.2f} s  nodes={info['nodes']}  used={info['used_nodes']}  "
              f"elements={info['elements']}")
        extra = {k: v for k, v in info.items() if k not in ("nodes", "used_nodes", "elements")}
        if extra:
            print(f"{'':22s} checks: {extra}")
    print(f"total {time.perf_counter() - t_all:.1f} s, gmsh {gmsh.__version__}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=MESH_DIR, help="output folder (default: meshes/)")
    ap.add_argument("--only", nargs="+", help="generate only these models")
    ap.add_argument("--list", action="store_true", help="list the models and exit")
    ap.add_argument("-v", "--verbose", action="store_true", help="show Gmsh's messages")
    args = ap.parse_args(argv)
    if args.list:
        print("\n".join(MODELS))
        return 0
    global VERBOSE
    VERBOSE = args.verbose
    build_all(args.out, args.only)
    return 0


if __name__ == "__main__":
    sys.exit(main())
