#!/usr/bin/env python3
"""Independent reference for nlrom's FE assembly: natural frequencies of a tetra10 Gmsh model
computed with scikit-fem (isoparametric, curved second-order geometry).

Default model: the bundled shrouded bladed-disk sector `meshes/sector_conforming.msh` (MSH 4.1,
1878 tetra10), E = 210e9 Pa, nu = 0.3, rho = 7800 kg/m^3, SI units, every node of the `hub`
elements clamped (3 components), lowest 20 eigenfrequencies (Hz).

Command lines (from the repository root; see `--help` for all options):

    python3 tools/validation/skfem_compare.py
        Verify the mesh import (below), assemble at --intorder (default 8), print the 20
        frequencies, the eigen-residuals and the timings.

    python3 tools/validation/skfem_compare.py --convergence [--orders 2,3,4,5,6,7,8,9]
        Same, then the frequencies for every listed skfem quadrature order and their relative
        differences to the highest order (9; skfem has no tetrahedron rule above intorder 9):
        shows that the reference is converged in the rule.

    python3 tools/validation/skfem_compare.py --write tests/data/skfem_sector_modes.json [--free]
        Write the reference record {"mesh", "material", "clamp", "intorder", "quadrature_degree",
        "quadrature_points", "frequencies_hz", "residuals", "dofs", "skfem_version", "volume",
        "mass", ...}; with --free also "free_free" (no clamp, informational).

    python3 tools/validation/skfem_compare.py --check [--nlrom target/release/nlrom] [--reference JSON]
                                   [--case-degree D] [--tol 1e-6] [--keep-case FILE.toml]
        e.g. python3 tools/validation/skfem_compare.py --check --reference tests/data/skfem_sector_modes.json
        Write a temporary case file (temp dir, absolute mesh path)

            title = "skfem comparison"
            [model]
            mesh = "/abs/path/meshes/sector_conforming.msh"
            material = { young = 210000000000.0, poisson = 0.3, density = 7800.0 }
            clamp = ["hub"]
            quadrature = { stiffness = D, mass = D }

        (D = the polynomial degree skfem's rule integrates exactly at --intorder, or the
        reference's "quadrature_degree"; --case-degree overrides it, e.g. if nlrom lacks a rule
        of that degree -- harmless, see Quadrature), run
        `nlrom modes CASE --stage full --num 20 --json` (stdout: one JSON object),
        and compare its "frequencies_hz" (and "dofs") with skfem's, computed now or read from
        --reference (then scikit-fem is not needed). Prints a table (mode, skfem Hz, nlrom Hz,
        relative difference); exit status 1 if any relative difference exceeds --tol (1e-6), if
        the free-DOF counts differ (unless --no-dofs-check) or if nlrom fails.

    python3 tools/validation/skfem_compare.py --free
        Also the free-free spectrum (no clamp): 6 rigid-body modes near 0 Hz, then elastic ones.

Quadrature. skfem's `intorder` selects a tabulated tetrahedron rule; the degree it integrates
exactly is NOT always equal to intorder. Measured on monomials (this script measures it again at
run time, `rule_degree`), scikit-fem 12.0.2:

    intorder   1  2  3  4   5   6   7   8   9   (10+: not available)
    points     1  4  5  11  14  15  24  31  45
    degree     1  2  3  4   4   5   6   7   8

On an isoparametric tetra10 the mass integrand N_i N_j det J is a polynomial of degree 2+2+3 = 7,
so intorder >= 8 integrates the consistent mass exactly; det J alone is of degree 3, so the volume
is exact from intorder 3. The stiffness integrand contains J^-1 (rational) on curved elements and
is never integrated exactly. Measured on the bundled sector (--convergence; max over the 20 modes
of the relative difference to intorder 9):

    intorder        2       3       4       5       6        7        8
    max |rel|   1.5e-4  1.2e-4  3.9e-8  1.6e-8  7.4e-10  3.2e-10  1.9e-10

Intorders 2-3 under-integrate the mass (degree < 4): 1e-4. From intorder 6 on the differences are
at the round-off floor of the eigen-solution (~1e-10 on modes 1-2, the most sensitive to
round-off in K since their eigenvalues are the smallest; modes 5-20 agree to ~1e-12 at 8 vs 9).
The default intorder is 8 (31 points, degree 7: mass exact, stiffness rule error < 1e-10). nlrom is
asked for rules of the same degree (D = 7), not for the same points; any rule of degree >= 4 is
within ~4e-8 of the converged values, far below the 1e-6 tolerance of --check.

Eigenvalues: scipy eigsh(K_ff, 20, M_ff, sigma=0, which='LM') on the free DOFs (clamped rows and
columns removed); residual = |K phi - lambda M phi| / max(|K phi|, (|lambda|+|sigma|) |M phi|).
Free-free (--free): no clamp, 26 modes, shift sigma = -(2 pi f_11)^2 (f_11 = 11th clamped
frequency) since K is singular; 6 rigid-body modes at |f| < 0.003 Hz (round-off), residuals ~1e-12.

Node order. Gmsh's tetra10: corners 0-3, then edges (0,1),(1,2),(2,0),(3,0),(3,2),(3,1). meshio
5.3.5's Gmsh reader permutes tetra10 to VTK order with [0,1,2,3,4,5,6,7,9,8] (meshio/gmsh/common.py,
`_gmsh_to_meshio_order`), giving edges (0,1),(1,2),(2,0),(0,3),(1,3),(2,3). skfem's MeshTet2 takes
`t` with 10 rows: 4 vertices, then the mid-edge nodes in the order of RefTet.edges =
(0,1),(1,2),(0,2),(0,3),(1,3),(2,3) -- the same as ElementTetP2.doflocs and as VTK
(MeshTet2.__post_init__ renumbers them into skfem's DOF order: vertices first, then edges). So the
meshio connectivity goes to MeshTet2 unchanged (which is also what skfem.io.meshio does). Verified
at run time (`verify_import`), independently of meshio and skfem:
  * this script parses the MSH 4.1 ASCII file itself (raw Gmsh order) and checks that the raw
    connectivity with the permutation [0..7,9,8] equals meshio's, element by element;
  * it maps every (element, local node) to skfem's DOF and checks that skfem's DOF location equals
    the node's coordinates bit for bit, and that the map node -> DOF is one-to-one;
  * it computes the volume of every element by an isoparametric quadrature written here in numpy
    (Gmsh-order quadratic shape functions, Stroud conical-product rule of degree 7) from the RAW
    Gmsh connectivity, and requires skfem's element volumes to agree to 1e-12 (relative) and the
    totals likewise; det J > 0 at all quadrature points;
  * it checks that the consistent mass matrix gives total mass rho * volume per component (1e-12)
    and no coupling between components;
  * for information it shows that the check is sensitive: with nodes 8 and 9 swapped the numpy
    volume is ~0 (det J < 0 in places) and skfem refuses the raw Gmsh order ("Zero Jacobian
    determinant"); straight-sided elements (mid-edge nodes on the chords) change the volume by
    ~1e-4 relative on this mesh.

Timings on the bundled sector (2 shared cores): import + verification 0.5 s; assembly (K and M)
2.5 s at intorder 2-4, 9 s at 8, 18 s at 9; eigsh 5 s (free-free 10 s); default run ~17 s;
--free --convergence --write ~115 s.

Requires numpy, scipy, meshio (reading) and scikit-fem (computing) -- tools/requirements-dev.txt.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
DEFAULT_MESH = "meshes/sector_conforming.msh"
DEFAULT_MATERIAL = {"young": 210e9, "poisson": 0.3, "density": 7800.0}
DEFAULT_CLAMP = ["hub"]
# meshio 5.3.5, meshio/gmsh/common.py: tetra10 Gmsh -> meshio (VTK) order
GMSH_TO_VTK_TETRA10 = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]
GMSH_TETRA10_EDGES = [(0, 1), (1, 2), (2, 0), (3, 0), (3, 2), (3, 1)]  # local nodes 4..9
SKFEM_TETRA10_EDGES = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]  # RefTet.edges


def log(*a):
    print(*a, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------------------------
# Raw Gmsh MSH 4.1 ASCII reader (independent of meshio)
# --------------------------------------------------------------------------------------------

def read_msh41_ascii(path: Path):
    """Return (node_tags [n], coords [n,3], tetra10 node tags [e,10] in Gmsh order), in file order."""
    with open(path, "r") as f:
        lines = f.read().split("\n")
    i = 0
    node_tags, coords, tets = [], [], []
    fmt_ok = False
    while i < len(lines):
        s = lines[i].strip()
        if s == "$MeshFormat":
            v, ft, _ = lines[i + 1].split()
            if not v.startswith("4.1") or ft != "0":
                raise SystemExit(f"{path}: raw reader handles MSH 4.1 ASCII only (got {v}, type {ft})")
            fmt_ok = True
            i += 2
        elif s == "$Nodes":
            nblocks = int(lines[i + 1].split()[0])
            i += 2
            for _ in range(nblocks):
                edim, _etag, param, n = (int(x) for x in lines[i].split())
                i += 1
                tags = [int(lines[i + k]) for k in range(n)]
                i += n
                for k in range(n):
                    xyz = lines[i + k].split()
                    if param and len(xyz) < 3 + edim:
                        raise SystemExit(f"{path}: line {i + k + 1}: short parametric node line")
                    coords.append([float(x) for x in xyz[:3]])
                i += n
                node_tags.extend(tags)
        elif s == "$Elements":
            nblocks = int(lines[i + 1].split()[0])
            i += 2
            for _ in range(nblocks):
                _edim, _etag, etype, n = (int(x) for x in lines[i].split())
                i += 1
                if etype == 11:  # tetra10
                    for k in range(n):
                        row = [int(x) for x in lines[i + k].split()]
                        if len(row) != 11:
                            raise SystemExit(f"{path}: line {i + k + 1}: tetra10 needs 10 nodes")
                        tets.append(row[1:])
                i += n
        else:
            i += 1
    if not fmt_ok:
        raise SystemExit(f"{path}: no $MeshFormat")
    return (np.array(node_tags, dtype=np.int64), np.array(coords, dtype=np.float64),
            np.array(tets, dtype=np.int64).reshape(-1, 10))


# --------------------------------------------------------------------------------------------
# Independent numpy isoparametric quadrature (Gmsh node order)
# --------------------------------------------------------------------------------------------

def stroud_tet_rule(n: int):
    """Conical-product (collapsed Gauss-Jacobi) rule on the unit tetrahedron, exact to degree 2n-1.

    x = u, y = v (1-u), z = w (1-u)(1-v), dV = (1-u)^2 (1-v) du dv dw."""
    from scipy.special import roots_jacobi, roots_legendre
    tu, wu = roots_jacobi(n, 2.0, 0.0)
    tv, wv = roots_jacobi(n, 1.0, 0.0)
    tw, ww = roots_legendre(n)
    u, wu = (1 + tu) / 2, wu / 8
    v, wv = (1 + tv) / 2, wv / 4
    w, ww = (1 + tw) / 2, ww / 2
    U, V, Wc = np.meshgrid(u, v, w, indexing="ij")
    WU, WV, WW = np.meshgrid(wu, wv, ww, indexing="ij")
    x = U
    y = V * (1 - U)
    z = Wc * (1 - U) * (1 - V)
    return np.vstack([x.ravel(), y.ravel(), z.ravel()]), (WU * WV * WW).ravel()


def rule_degree(X: np.ndarray, W: np.ndarray, max_degree: int = 16, rtol: float = 1e-12) -> int:
    """Highest d such that the rule integrates every monomial of degree <= d on the unit tet."""
    deg = -1
    for d in range(max_degree + 1):
        for a in range(d + 1):
            for b in range(d + 1 - a):
                c = d - a - b
                exact = math.factorial(a) * math.factorial(b) * math.factorial(c) / math.factorial(d + 3)
                q = float(np.sum(W * X[0] ** a * X[1] ** b * X[2] ** c))
                if abs(q - exact) > rtol * exact:
                    return deg
        deg = d
    return deg


def tet10_gmsh_grads(X: np.ndarray) -> np.ndarray:
    """Gradients dN_i/dxi_b of the Gmsh-ordered tetra10 shape functions, shape [10, 3, nq]."""
    x, y, z = X
    L = [1 - x - y - z, x, y, z]
    dL = np.array([[-1, -1, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    nq = X.shape[1]
    G = np.zeros((10, 3, nq))
    for i in range(4):  # N_i = L_i (2 L_i - 1)
        G[i] = np.outer(dL[i], 4 * L[i] - 1)
    for k, (a, b) in enumerate(GMSH_TETRA10_EDGES):  # N = 4 L_a L_b
        G[4 + k] = 4 * (np.outer(dL[a], L[b]) + np.outer(dL[b], L[a]))
    return G


def numpy_element_volumes(coords: np.ndarray, conn_gmsh: np.ndarray, n: int = 4):
    """Element volumes by isoparametric quadrature from Gmsh-order connectivity; also min det J."""
    X, W = stroud_tet_rule(n)
    G = tet10_gmsh_grads(X)                       # [10, 3, nq]
    P = coords[conn_gmsh]                         # [e, 10, 3]
    J = np.einsum("eia,ibq->eqab", P, G)          # dx_a / dxi_b
    det = np.linalg.det(J)                        # [e, nq]
    return det @ W, float(det.min())


# --------------------------------------------------------------------------------------------
# meshio import -> skfem
# --------------------------------------------------------------------------------------------

def load_meshio(path: Path, clamp: list[str]):
    import meshio
    m = meshio.read(path)
    phys = m.cell_data["gmsh:physical"]
    names = {name: (int(v[0]), int(v[1])) for name, v in m.field_data.items()}
    tets, clamp_nodes = [], set()
    for name in clamp:
        if name not in names:
            raise SystemExit(f"{path}: no physical group {name!r} (have {sorted(names)})")
    dims = {"vertex": 0, "line": 1, "line3": 1, "triangle": 2, "triangle6": 2, "quad": 2,
            "quad8": 2, "quad9": 2, "tetra": 3, "tetra10": 3}
    for block, tags in zip(m.cells, phys):
        if block.type == "tetra10":
            tets.append(block.data)
        elif block.type not in dims:
            raise SystemExit(f"{path}: unexpected cell type {block.type}")
        for name in clamp:
            tag, dim = names[name]
            sel = (tags == tag) & (dims[block.type] == dim)
            clamp_nodes.update(np.unique(block.data[sel]).tolist())
    if not tets:
        raise SystemExit(f"{path}: no tetra10 elements")
    other3d = [b.type for b in m.cells if dims.get(b.type) == 3 and b.type != "tetra10"]
    if other3d:
        raise SystemExit(f"{path}: only tetra10 volumes are supported (also found {other3d})")
    return m.points.astype(np.float64), np.vstack(tets).astype(np.int64), np.array(sorted(clamp_nodes))


class Model:
    """skfem MeshTet2 + P2 vector basis; node -> DOF maps; verification results."""

    def __init__(self, mesh_path: Path, clamp: list[str]):
        t0 = time.perf_counter()
        self.mesh_path = mesh_path
        self.points, self.tet_vtk, self.clamp_nodes = load_meshio(mesh_path, clamp)
        from skfem import MeshTet2
        self.mesh = MeshTet2(np.ascontiguousarray(self.points.T), np.ascontiguousarray(self.tet_vtk.T))
        # node (meshio index) -> skfem scalar P2 DOF (= column of mesh.doflocs)
        edofs = self.mesh.dofs.element_dofs            # [10, e], local order = ElementTetP2
        node2dof = np.full(len(self.points), -1, dtype=np.int64)
        node2dof[self.tet_vtk.T.ravel()] = edofs.ravel()
        if not np.array_equal(node2dof[self.tet_vtk.T], edofs):
            raise SystemExit("node -> skfem DOF map is not single-valued (node order mismatch)")
        used = node2dof >= 0
        if len(np.unique(node2dof[used])) != used.sum() or used.sum() != self.mesh.doflocs.shape[1]:
            raise SystemExit("node -> skfem DOF map is not one-to-one")
        if not np.array_equal(self.mesh.doflocs[:, node2dof[used]].T, self.points[used]):
            raise SystemExit("skfem DOF locations differ from the node coordinates")
        self.node2dof = node2dof
        self.unused_nodes = int((~used).sum())
        self.t_import = time.perf_counter() - t0

    def vector_dofs(self, basis, scalar_dofs: np.ndarray) -> np.ndarray:
        """Vector-basis DOFs [3, n] (row = component) of scalar P2 DOFs."""
        nv = self.mesh.nvertices
        out = np.empty((3, len(scalar_dofs)), dtype=np.int64)
        isv = scalar_dofs < nv
        out[:, isv] = basis.nodal_dofs[:, scalar_dofs[isv]]
        out[:, ~isv] = basis.edge_dofs[:, scalar_dofs[~isv] - nv]
        for c in range(3):
            if not np.array_equal(basis.doflocs[:, out[c]], self.mesh.doflocs[:, scalar_dofs]):
                raise SystemExit("vector DOF locations do not match the scalar DOF locations")
        return out

    def verify_import(self) -> dict:
        """Raw-Gmsh connectivity and numpy quadrature vs meshio/skfem (see the module docstring)."""
        from skfem import Basis, ElementTetP2, MeshTet2
        t0 = time.perf_counter()
        tags, coords, tets_gmsh_tags = read_msh41_ascii(self.mesh_path)
        if not np.array_equal(coords, self.points):
            raise SystemExit("raw reader and meshio disagree on node coordinates/order")
        index = {int(t): k for k, t in enumerate(tags)}
        conn_gmsh = np.vectorize(index.__getitem__)(tets_gmsh_tags)
        if not np.array_equal(conn_gmsh[:, GMSH_TO_VTK_TETRA10], self.tet_vtk):
            raise SystemExit("meshio's tetra10 connectivity is not the raw Gmsh one permuted by "
                             f"{GMSH_TO_VTK_TETRA10}")
        # mid-edge nodes sit near the chord midpoints (Gmsh edge order) -- plausibility check
        P = coords[conn_gmsh]
        off = 0.0
        for k, (a, b) in enumerate(GMSH_TETRA10_EDGES):
            chord = np.linalg.norm(P[:, b] - P[:, a], axis=1)
            off = max(off, float(np.max(np.linalg.norm(P[:, 4 + k] - (P[:, a] + P[:, b]) / 2, axis=1) / chord)))
        if off > 0.25:
            raise SystemExit(f"a mid-edge node is {off:.2f} chord lengths off its edge midpoint")
        vol_np_e, min_det = numpy_element_volumes(coords, conn_gmsh)
        if min_det <= 0:
            raise SystemExit(f"non-positive det J ({min_det:.3e}) in the mesh")
        straight = P.copy()
        for k, (a, b) in enumerate(GMSH_TETRA10_EDGES):
            straight[:, 4 + k] = (P[:, a] + P[:, b]) / 2
        vol_straight = float(numpy_element_volumes(straight.reshape(-1, 3),
                                                   np.arange(straight.shape[0] * 10).reshape(-1, 10))[0].sum())
        # skfem element volumes (det J of degree 3: exact from intorder 3; use 4)
        b = Basis(self.mesh, ElementTetP2(), intorder=4)
        det_sk = self.mesh.mapping().detDF(b.X)
        vol_sk_e = b.dx.sum(axis=1)
        vol_sk, vol_np = float(vol_sk_e.sum()), float(vol_np_e.sum())
        elem_rel = float(np.max(np.abs(vol_sk_e - vol_np_e) / np.abs(vol_np_e)))
        tot_rel = abs(vol_sk - vol_np) / vol_np
        # deliberately wrong: raw Gmsh order fed to skfem as if it were VTK order
        # (skfem itself refuses that mesh: "Zero Jacobian determinant"); same error seen from the
        # other side: meshio-order connectivity read with Gmsh-order shape functions
        wrong = MeshTet2(np.ascontiguousarray(self.points.T), np.ascontiguousarray(conn_gmsh.T))
        try:
            Basis(wrong, ElementTetP2(), intorder=4)
            skfem_wrong = "accepted"
        except Exception as e:  # noqa: BLE001 - report whatever skfem says
            skfem_wrong = f"rejected ({e})"
        vol_wrong_e, min_det_wrong = numpy_element_volumes(coords, self.tet_vtk)
        vol_wrong = float(vol_wrong_e.sum())
        res = {
            "elements": int(conn_gmsh.shape[0]), "nodes": int(len(coords)),
            "volume_numpy": vol_np, "volume_skfem": vol_sk,
            "volume_rel_diff": tot_rel, "element_volume_max_rel_diff": elem_rel,
            "min_detJ_numpy": min_det, "min_detJ_skfem": float(det_sk.min()),
            "volume_straight_sided": vol_straight, "volume_wrong_order": vol_wrong,
            "min_detJ_wrong_order": min_det_wrong, "skfem_wrong_order": skfem_wrong,
            "max_midnode_offset_over_chord": off,
            "seconds": time.perf_counter() - t0,
        }
        if not (tot_rel <= 1e-12 and elem_rel <= 1e-12):
            raise SystemExit(f"volume mismatch skfem vs numpy: total {tot_rel:.3e}, element {elem_rel:.3e}")
        if det_sk.min() <= 0:
            raise SystemExit("skfem sees a non-positive det J (orientation/order problem)")
        self.volume = vol_np
        return res


def rule_info(intorder: int):
    from skfem.quadrature import get_quadrature_tet
    X, W = get_quadrature_tet(intorder)
    return int(X.shape[1]), rule_degree(X, W)


def assemble(model: Model, material: dict, intorder: int):
    from skfem import Basis, BilinearForm, ElementTetP2, ElementVector
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity
    E, nu, rho = material["young"], material["poisson"], material["density"]
    lam, mu = lame_parameters(E, nu)
    assert abs(lam - E * nu / ((1 + nu) * (1 - 2 * nu))) <= 1e-15 * lam and abs(mu - E / (2 * (1 + nu))) <= 1e-15 * mu

    @BilinearForm
    def mass(u, v, w):
        return rho * dot(u, v)

    t0 = time.perf_counter()
    basis = Basis(model.mesh, ElementVector(ElementTetP2()), intorder=intorder)
    K = linear_elasticity(lam, mu).assemble(basis).tocsr()
    M = mass.assemble(basis).tocsr()
    return basis, K, M, time.perf_counter() - t0


def check_mass(model: Model, basis, M, rho: float) -> float:
    """Max relative error of u_c^T M u_d against rho*V*delta_cd (u_c = unit translation)."""
    used = np.nonzero(model.node2dof >= 0)[0]
    vd = model.vector_dofs(basis, model.node2dof[used])
    err = 0.0
    target = rho * model.volume
    for c in range(3):
        uc = np.zeros(M.shape[0])
        uc[vd[c]] = 1.0
        for d in range(3):
            ud = np.zeros(M.shape[0])
            ud[vd[d]] = 1.0
            val = uc @ (M @ ud)
            err = max(err, abs(val - (target if c == d else 0.0)) / target)
    if err > 1e-12:
        raise SystemExit(f"mass matrix total mass differs from rho*volume by {err:.3e}")
    return err


def solve_modes(K, M, free: np.ndarray, num: int, sigma: float = 0.0):
    from scipy.sparse.linalg import eigsh
    Kf = K[free][:, free].tocsc()
    Mf = M[free][:, free].tocsc()
    t0 = time.perf_counter()
    lam, phi = eigsh(Kf, k=num, M=Mf, sigma=sigma, which="LM")
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    KP, MP = Kf @ phi, Mf @ phi
    # relative residual; the (|lambda| + |sigma|) scale keeps it meaningful for rigid-body modes
    res = np.linalg.norm(KP - MP * lam, axis=0) / np.maximum(
        np.linalg.norm(KP, axis=0), (np.abs(lam) + abs(sigma)) * np.linalg.norm(MP, axis=0))
    freqs = np.sign(lam) * np.sqrt(np.abs(lam)) / (2 * np.pi)
    return freqs, res, time.perf_counter() - t0


def compute(model: Model, material: dict, intorder: int, num: int, free_free: bool = False) -> dict:
    npts, deg = rule_info(intorder)
    basis, K, M, t_asm = assemble(model, material, intorder)
    mass_err = check_mass(model, basis, M, material["density"])
    clamped = model.vector_dofs(basis, model.node2dof[model.clamp_nodes]).ravel()
    free = np.setdiff1d(np.arange(K.shape[0]), clamped)
    freqs, res, t_eig = solve_modes(K, M, free, num)
    out = {"intorder": intorder, "quadrature_points": npts, "quadrature_degree": deg,
           "frequencies_hz": freqs.tolist(), "residuals": res.tolist(),
           "dofs": int(len(free)), "total_dofs": int(K.shape[0]),
           "clamped_nodes": int(len(model.clamp_nodes)), "clamped_dofs": int(len(clamped)),
           "mass": float(material["density"] * model.volume), "mass_rel_err": mass_err,
           "seconds_assembly": t_asm, "seconds_eigsh": t_eig}
    if free_free:
        # K is singular: shift below zero (lambda in rad^2/s^2). A shift in the middle of the
        # clamped spectrum gives residuals ~1e-11; the elastic frequencies do not depend on it
        # (checked: shifts -(2 pi 96 Hz)^2 ... -(2 pi 5 kHz)^2 agree to ~1e-11)
        allf = np.arange(K.shape[0])
        sigma = -(2 * np.pi * freqs[len(freqs) // 2]) ** 2
        f2, r2, t2 = solve_modes(K, M, allf, num + 6, sigma=sigma)
        out["free_free"] = {"frequencies_hz": f2.tolist(), "residuals": r2.tolist(),
                            "dofs": int(K.shape[0]), "sigma": sigma, "seconds_eigsh": t2}
    return out


# --------------------------------------------------------------------------------------------
# nlrom comparison
# --------------------------------------------------------------------------------------------

def toml_string(s: str) -> str:
    return json.dumps(s)  # a JSON string of printable text is a valid TOML basic string


def write_case(path: Path, mesh_abs: Path, material: dict, clamp: list[str], degree: int):
    text = (
        'title = "skfem comparison"\n'
        "[model]\n"
        f"mesh = {toml_string(str(mesh_abs))}\n"
        f"material = {{ young = {float(material['young'])!r}, poisson = {float(material['poisson'])!r}, "
        f"density = {float(material['density'])!r} }}\n"
        f"clamp = [{', '.join(toml_string(c) for c in clamp)}]\n"
        f"quadrature = {{ stiffness = {int(degree)}, mass = {int(degree)} }}\n"
    )
    path.write_text(text)
    return text


def run_check(args, ref: dict, mesh_abs: Path) -> int:
    nlrom = Path(args.nlrom)
    if not nlrom.is_absolute() and not nlrom.exists():
        nlrom = REPO / nlrom
    if not nlrom.exists():
        log(f"error: nlrom executable not found: {args.nlrom} (build it: cargo build --release)")
        return 1
    num = len(ref["frequencies_hz"])
    with tempfile.TemporaryDirectory(prefix="skfem_compare_") as tmp:
        case = Path(tmp) / "skfem_comparison.toml"
        degree = args.case_degree if args.case_degree is not None else ref["quadrature_degree"]
        text = write_case(case, mesh_abs, ref["material"], ref["clamp"], degree)
        if args.keep_case:
            Path(args.keep_case).write_text(text)
        cmd = [str(nlrom), "modes", str(case), "--stage", "full", "--num", str(num), "--json"]
        log("running:", " ".join(cmd))
        t0 = time.perf_counter()
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        except subprocess.TimeoutExpired:
            log(f"error: nlrom timed out after {args.timeout} s")
            return 1
        wall = time.perf_counter() - t0
    if p.returncode != 0:
        log(f"error: nlrom exited with status {p.returncode}\n--- stderr ---\n{p.stderr.strip()}\n"
            f"--- stdout ---\n{p.stdout.strip()[:2000]}\n--- case file ---\n{text}")
        return 1
    try:
        out = json.loads(p.stdout)
        got = [float(x) for x in out["frequencies_hz"]]
    except (ValueError, KeyError, TypeError) as e:
        log(f"error: nlrom stdout is not one JSON object with a 'frequencies_hz' list ({e}):\n{p.stdout[:2000]}")
        return 1
    bad = 0
    if len(got) < num:
        log(f"error: nlrom returned {len(got)} frequencies, {num} requested")
        bad += 1
    want = ref["frequencies_hz"]
    print(f"nlrom modes: {wall:.2f} s wall (case quadrature degree {degree}); reference: skfem "
          f"{ref['skfem_version']}, intorder {ref['intorder']} (degree {ref['quadrature_degree']}), "
          f"tolerance {args.tol:g}")
    print(f"{'mode':>4} {'skfem Hz':>18} {'nlrom Hz':>18} {'rel. diff':>10}")
    worst = 0.0
    for i in range(num):
        if i < len(got):
            rel = abs(got[i] - want[i]) / abs(want[i])
            worst = max(worst, rel)
            flag = "" if rel <= args.tol else "  FAIL"
            bad += rel > args.tol
            print(f"{i + 1:>4} {want[i]:>18.9f} {got[i]:>18.9f} {rel:>10.2e}{flag}")
        else:
            print(f"{i + 1:>4} {want[i]:>18.9f} {'-':>18} {'-':>10}  FAIL")
    print(f"max relative difference: {worst:.3e}")
    nd = out.get("dofs")
    if nd is None:
        print("nlrom reported no 'dofs'")
        bad += not args.no_dofs_check
    elif int(nd) != int(ref["dofs"]):
        hint = " (= total DOF including the clamped ones)" if int(nd) == ref.get("total_dofs") else ""
        print(f"DOF count differs: skfem {ref['dofs']} free DOF, nlrom {nd}{hint}"
              + (" (ignored: --no-dofs-check)" if args.no_dofs_check else "  FAIL"))
        bad += not args.no_dofs_check
    else:
        print(f"free DOF: {nd} (both)")
    print("OK" if bad == 0 else f"FAILED ({bad} problem(s))")
    return 0 if bad == 0 else 1


# --------------------------------------------------------------------------------------------

def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", default=DEFAULT_MESH, help="Gmsh MSH 4.1 ASCII tetra10 mesh (default %(default)s)")
    ap.add_argument("--intorder", type=int, default=8, help="skfem quadrature order (default %(default)s)")
    ap.add_argument("--num", type=int, default=20, help="number of modes (default %(default)s)")
    ap.add_argument("--convergence", action="store_true", help="frequencies for every --orders rule")
    ap.add_argument("--orders", default="2,3,4,5,6,7,8,9", help="intorders for --convergence (default %(default)s)")
    ap.add_argument("--free", action="store_true", help="also the free-free spectrum (informational)")
    ap.add_argument("--write", metavar="JSON", help="write the reference record")
    ap.add_argument("--check", action="store_true", help="compare with `nlrom modes`")
    ap.add_argument("--nlrom", default="target/release/nlrom", help="nlrom executable (default %(default)s)")
    ap.add_argument("--reference", metavar="JSON", help="--check against this record instead of running skfem")
    ap.add_argument("--tol", type=float, default=1e-6, help="--check relative tolerance (default %(default)g)")
    ap.add_argument("--no-dofs-check", action="store_true", help="--check: do not fail on a DOF-count mismatch")
    ap.add_argument("--case-degree", type=int, metavar="D",
                    help="--check: quadrature degree written to the case file (default: the degree of "
                         "skfem's rule at --intorder, or the reference's quadrature_degree)")
    ap.add_argument("--keep-case", metavar="TOML", help="--check: also save the case file here")
    ap.add_argument("--timeout", type=float, default=600.0, help="--check: nlrom timeout in s")
    args = ap.parse_args()

    mesh_arg = Path(args.mesh)
    mesh_abs = (mesh_arg if mesh_arg.is_absolute() else (REPO / mesh_arg if (REPO / mesh_arg).exists() else mesh_arg.resolve())).resolve()
    try:
        mesh_rel = str(mesh_abs.relative_to(REPO))
    except ValueError:
        mesh_rel = str(mesh_abs)

    if args.check and args.reference:
        ref = json.loads(Path(args.reference).read_text())
        if "total_dofs" not in ref:
            ref["total_dofs"] = None
        ref_mesh = Path(ref["mesh"])
        ref_mesh = ref_mesh if ref_mesh.is_absolute() else REPO / ref_mesh
        return run_check(args, ref, ref_mesh.resolve())

    import skfem
    t_all = time.perf_counter()
    model = Model(mesh_abs, DEFAULT_CLAMP)
    v = model.verify_import()
    print(f"mesh {mesh_rel}: {v['nodes']} nodes, {v['elements']} tetra10, "
          f"{len(model.clamp_nodes)} clamped nodes ({', '.join(DEFAULT_CLAMP)}); import {model.t_import:.2f} s, "
          f"verification {v['seconds']:.2f} s")
    print(f"  volume numpy (raw Gmsh order, Stroud degree 7) {v['volume_numpy']:.15e} m^3")
    print(f"  volume skfem (MeshTet2, meshio order)          {v['volume_skfem']:.15e} m^3  "
          f"rel. diff {v['volume_rel_diff']:.1e}, max per element {v['element_volume_max_rel_diff']:.1e}")
    print(f"  min det J: numpy {v['min_detJ_numpy']:.3e}, skfem {v['min_detJ_skfem']:.3e}; "
          f"max mid-node offset from chord midpoint {v['max_midnode_offset_over_chord']:.3f} x chord")
    print(f"  for information: straight-sided volume {v['volume_straight_sided']:.9e} "
          f"(rel. {v['volume_straight_sided'] / v['volume_numpy'] - 1:+.1e}); "
          f"wrong node order (8<->9 swapped) {v['volume_wrong_order']:.9e} "
          f"(rel. {v['volume_wrong_order'] / v['volume_numpy'] - 1:+.1e}, min det J {v['min_detJ_wrong_order']:.2e}); "
          f"skfem given the raw Gmsh order: {v['skfem_wrong_order']}")

    material = dict(DEFAULT_MATERIAL)
    r = compute(model, material, args.intorder, args.num, free_free=args.free)
    print(f"intorder {args.intorder}: {r['quadrature_points']}-point rule, exact to degree "
          f"{r['quadrature_degree']}; free DOF {r['dofs']} of {r['total_dofs']} "
          f"({r['clamped_dofs']} clamped); total mass {r['mass']:.9e} kg (M check {r['mass_rel_err']:.1e}); "
          f"assembly {r['seconds_assembly']:.2f} s, eigsh {r['seconds_eigsh']:.2f} s")
    print(f"{'mode':>4} {'frequency Hz':>20} {'residual':>10}")
    for i, (f, e) in enumerate(zip(r["frequencies_hz"], r["residuals"])):
        print(f"{i + 1:>4} {f:>20.10f} {e:>10.1e}")
    if args.free:
        ff = r["free_free"]
        print(f"free-free ({ff['dofs']} DOF, shift {ff['sigma']:.3g}; eigsh {ff['seconds_eigsh']:.2f} s):")
        for i, (f, e) in enumerate(zip(ff["frequencies_hz"], ff["residuals"])):
            print(f"{i + 1:>4} {f:>20.10f} {e:>10.1e}")

    conv = None
    if args.convergence:
        orders = [int(x) for x in args.orders.split(",")]
        runs = {}
        for n in orders:
            try:
                rule_info(n)
            except NotImplementedError:
                print(f"intorder {n}: not available in skfem {skfem.__version__}")
                continue
            runs[n] = r if n == args.intorder else compute(model, material, n, args.num)
        top = max(runs)
        ftop = np.array(runs[top]["frequencies_hz"])
        print(f"\nquadrature convergence (relative differences to intorder {top}):")
        print(f"{'intorder':>8} {'points':>6} {'degree':>6} {'max |rel|':>10} {'mean |rel|':>10}  "
              f"{'f1 Hz':>16} {'f20 Hz':>16} {'asm s':>6}")
        conv = {}
        for n in sorted(runs):
            f = np.array(runs[n]["frequencies_hz"])
            rel = np.abs(f - ftop) / ftop
            conv[n] = rel
            print(f"{n:>8} {runs[n]['quadrature_points']:>6} {runs[n]['quadrature_degree']:>6} "
                  f"{rel.max():>10.2e} {rel.mean():>10.2e}  {f[0]:>16.9f} {f[-1]:>16.9f} "
                  f"{runs[n]['seconds_assembly']:>6.2f}")
        print("\nper mode, relative difference to intorder", top)
        print(f"{'mode':>4} {'f Hz (' + str(top) + ')':>18} " + " ".join(f"{'n=' + str(n):>9}" for n in sorted(runs) if n != top))
        for i in range(len(ftop)):
            print(f"{i + 1:>4} {ftop[i]:>18.9f} " + " ".join(f"{conv[n][i]:>9.1e}" for n in sorted(runs) if n != top))

    if args.write:
        rec = {
            "mesh": mesh_rel, "material": material, "clamp": DEFAULT_CLAMP,
            "intorder": r["intorder"], "quadrature_degree": r["quadrature_degree"],
            "quadrature_points": r["quadrature_points"],
            "frequencies_hz": r["frequencies_hz"], "residuals": r["residuals"], "dofs": r["dofs"],
            "total_dofs": r["total_dofs"], "clamped_nodes": r["clamped_nodes"],
            "skfem_version": skfem.__version__,
            "volume": v["volume_numpy"], "mass": r["mass"],
            "note": "tools/validation/skfem_compare.py: scikit-fem MeshTet2 (isoparametric tetra10), "
                    "ElementVector(ElementTetP2), consistent mass, eigsh shift-invert at 0",
        }
        if conv is not None:
            top = max(conv)
            rec["rule_convergence"] = {"reference_intorder": top,
                                       "max_rel_diff": {str(n): float(c.max()) for n, c in conv.items() if n != top}}
        if args.free:
            rec["free_free"] = {k: r["free_free"][k] for k in ("frequencies_hz", "residuals", "dofs")}
        out = Path(args.write)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(rec, indent=1) + "\n")
        print(f"wrote {out}")

    print(f"total {time.perf_counter() - t_all:.2f} s")

    if args.check:
        ref = {"mesh": mesh_rel, "material": material, "clamp": DEFAULT_CLAMP,
               "intorder": r["intorder"], "quadrature_degree": r["quadrature_degree"],
               "frequencies_hz": r["frequencies_hz"], "dofs": r["dofs"], "total_dofs": r["total_dofs"],
               "skfem_version": skfem.__version__}
        return run_check(args, ref, mesh_abs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
