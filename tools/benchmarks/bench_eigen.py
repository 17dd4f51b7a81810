#!/usr/bin/env python3
"""Compare nlrom's sparse eigensolver with scipy's ARPACK (shift-invert) on a Matrix Market pencil.

    python3 tools/benchmarks/bench_eigen.py [DIR] [--n 20] [--sigma 0] [--grid 50 50 48] [--arpack-tol 1e-10]
                                 [--skip-superlu] [--skip-cholmod]

DIR holds K.mtx and M.mtx (symmetric Matrix Market, as `nlrom export` writes them). Without DIR the
3-D lattice of tests/eigen.rs and benches/eigen.rs is used: 7-point Laplacian stiffness (springs of
1e6 N/m, clamped outside neighbours) and lumped masses of 0.5 kg on a --grid NX NY NZ grid (default
50×50×48 = 120 000 DOF), generated with scipy and written to tools/large/lattice/ (git-ignored; kept
and reused if present with the same size). Its eigenvalues are known in closed form,
λ = (k/m) Σ_d 2(1 − cos(i_d π/(n_d + 1))), and every solver is compared with them too.

Solvers, each in a fresh process under `/usr/bin/time -f "%e %U %S %M"` (process wall time, CPU
time user + sys, peak RSS):
  * nlrom:          `target/release/examples/eigen_mtx DIR N SIGMA` (built first with
                    `cargo build --release --example eigen_mtx`): sparse Cholesky of K − σM (faer) +
                    block Krylov–Schur, residual tolerance 1e-8.
  * scipy-superlu:  `scipy.sparse.linalg.eigsh(K, N, M, sigma=SIGMA, which='LM', tol=ARPACK_TOL)`:
                    ARPACK shift-invert mode with SuperLU of K − σM (scipy's default path).
  * scipy-cholmod:  the same eigsh call with `OPinv` = a LinearOperator solving with CHOLMOD's
                    Cholesky of K − σM (scikit-sparse; skipped if it does not import). On Debian 12:
                    `apt-get install libsuitesparse-dev` and `pip install scikit-sparse==0.4.16`
                    (0.5 needs SuiteSparse 7, Debian 12 has 5.12).
"solve s" is measured inside each process around factorisation + eigensolver (file reading
excluded); "process s" and "peak MB" cover the whole process, reading included. The eigenvalue
columns give the largest relative difference to nlrom's eigenvalues and to the closed form. A
Markdown table with the ratios peer/nlrom is printed at the end.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import scipy.io
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[2]
SPRING = 1.0e6  # N/m
MASS = 0.5  # kg

# Runs in a fresh Python process: argv = DIR N SIGMA TOL MODE (superlu | cholmod); prints JSON.
PEER = r"""
import json, sys, time
import numpy as np, scipy.io, scipy.sparse.linalg as sla
d, n, sigma, tol, mode = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
K = scipy.io.mmread(d + "/K.mtx").tocsc()
M = scipy.io.mmread(d + "/M.mtx").tocsc()
t0 = time.perf_counter()
if mode == "superlu":
    w = sla.eigsh(K, n, M, sigma=sigma, which="LM", tol=tol, return_eigenvectors=False)
else:
    from sksparse.cholmod import cholesky
    f = cholesky((K - sigma * M).tocsc())
    op = sla.LinearOperator(K.shape, matvec=f, dtype=float)
    w = sla.eigsh(K, n, M, sigma=sigma, which="LM", tol=tol, OPinv=op, return_eigenvectors=False)
print(json.dumps({"eigenvalues": sorted(float(x) for x in w), "wall_seconds": time.perf_counter() - t0}))
"""


def lattice(nx: int, ny: int, nz: int) -> tuple[sp.csc_matrix, sp.csc_matrix]:
    """K and M of the lattice, DOF index i + nx (j + ny k) as in tests/eigen.rs."""

    def t(n: int) -> sp.csc_matrix:
        e = np.ones(n)
        return sp.diags([-e[:-1], 2 * e, -e[:-1]], [-1, 0, 1], format="csc")

    ix, iy, iz = (sp.identity(n, format="csc") for n in (nx, ny, nz))
    k = sp.kron(iz, sp.kron(iy, t(nx))) + sp.kron(iz, sp.kron(t(ny), ix)) + sp.kron(t(nz), sp.kron(iy, ix))
    n = nx * ny * nz
    return (SPRING * k).tocsc(), (MASS * sp.identity(n, format="csc")).tocsc()


def lattice_eigenvalues(nx: int, ny: int, nz: int, count: int) -> list[float]:
    """The lowest `count` closed-form eigenvalues (rad²/s²) of the lattice."""
    axes = [2 * (1 - np.cos(np.arange(1, min(n, count) + 1) * np.pi / (n + 1))) for n in (nx, ny, nz)]
    s = axes[0][:, None, None] + axes[1][None, :, None] + axes[2][None, None, :]
    return sorted((SPRING / MASS * s).ravel())[:count]


def write_lattice(d: Path, grid: tuple[int, int, int]) -> None:
    """Writes K.mtx and M.mtx of the lattice to d unless files of that size are there."""
    n = grid[0] * grid[1] * grid[2]
    if (d / "K.mtx").exists() and (d / "M.mtx").exists():
        if scipy.io.mminfo(str(d / "K.mtx"))[0] == n:
            return
    d.mkdir(parents=True, exist_ok=True)
    k, m = lattice(*grid)
    scipy.io.mmwrite(str(d / "K.mtx"), k, symmetry="symmetric", precision=17)
    scipy.io.mmwrite(str(d / "M.mtx"), m, symmetry="symmetric", precision=17)


def timed_json(cmd: list[str]) -> tuple[dict, tuple[float, float], float]:
    """JSON printed by cmd, its process (wall s, CPU s = user + sys) and peak RSS (MB), via GNU
    time."""
    with tempfile.NamedTemporaryFile(mode="r", suffix=".time") as t:
        full = ["/usr/bin/time", "-f", "%e %U %S %M", "-o", t.name] + cmd
        r = subprocess.run(full, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed: {r.stderr[-2000:]}")
        wall, user, system, kb = t.read().split()[-4:]
        return (json.loads(r.stdout.strip().splitlines()[-1]), (float(wall), float(user) + float(system)),
                float(kb) / 1024.0)


def max_rel(a: list[float], b: list[float]) -> float:
    """Largest |a − b| / |b| (rigid-body modes: relative to the largest |b|)."""
    scale = max(abs(x) for x in b)
    return max(abs(x - y) / max(abs(y), 1e-6 * scale) for x, y in zip(a, b))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir", type=Path, nargs="?", help="directory with K.mtx and M.mtx")
    ap.add_argument("--n", type=int, default=20, help="number of modes (default 20)")
    ap.add_argument("--sigma", type=float, default=0.0, help="shift σ in rad²/s² (default 0)")
    ap.add_argument("--grid", type=int, nargs=3, default=[50, 50, 48], metavar=("NX", "NY", "NZ"))
    ap.add_argument("--arpack-tol", type=float, default=1e-10, help="ARPACK tol (relative Ritz residual)")
    ap.add_argument("--skip-superlu", action="store_true")
    ap.add_argument("--skip-cholmod", action="store_true")
    args = ap.parse_args()

    exact = None
    d = args.dir
    if d is None:
        d = ROOT / "tools" / "large" / "lattice"
        write_lattice(d, tuple(args.grid))
        exact = lattice_eigenvalues(*args.grid, args.n)
    subprocess.run(["cargo", "build", "--release", "--quiet", "--example", "eigen_mtx"], cwd=ROOT, check=True)
    exe = str(ROOT / "target" / "release" / "examples" / "eigen_mtx")
    n_sigma = [str(args.n), repr(args.sigma)]

    rows = []
    ours, proc, peak = timed_json([exe, str(d)] + n_sigma)
    print(f"nlrom: {ours['n_dof']} DOF, factor {ours['factor_seconds']:.2f} s, total {ours['wall_seconds']:.2f} s, "
          f"{ours['operator_applications']} applications, max residual {max(ours['residuals']):.1e}", file=sys.stderr)
    rows.append(("nlrom (faer Cholesky + block Krylov–Schur)", ours, proc, peak))
    peers = [("superlu", "scipy eigsh + SuperLU", args.skip_superlu), ("cholmod", "scipy eigsh + CHOLMOD", args.skip_cholmod)]
    for mode, name, skip in peers:
        if skip:
            continue
        if mode == "cholmod" and subprocess.run([sys.executable, "-c", "import sksparse.cholmod"]).returncode != 0:
            print("scikit-sparse does not import: CHOLMOD skipped", file=sys.stderr)
            continue
        res, proc, peak = timed_json([sys.executable, "-c", PEER, str(d)] + n_sigma + [repr(args.arpack_tol), mode])
        print(f"{name}: {res['wall_seconds']:.2f} s", file=sys.stderr)
        rows.append((name, res, proc, peak))

    base = rows[0]
    print(f"\n{ours['n_dof']} DOF, lowest {args.n} modes, σ = {args.sigma:g}; ARPACK tol = {args.arpack_tol:g}\n")
    head = ("| solver | solve s | process s | process CPU s (user+sys) | peak MB | solve ratio | CPU ratio | "
            "peak ratio | max rel. diff. to nlrom |")
    if exact is not None:
        head += " max rel. error vs closed form |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for name, res, proc, peak in rows:
        line = (f"| {name} | {res['wall_seconds']:.2f} | {proc[0]:.2f} | {proc[1]:.2f} | {peak:.0f} | "
                f"{res['wall_seconds'] / base[1]['wall_seconds']:.2f} | {proc[1] / base[2][1]:.2f} | "
                f"{peak / base[3]:.2f} | "
                f"{max_rel(res['eigenvalues'], ours['eigenvalues']):.1e} |")
        if exact is not None:
            line += f" {max_rel(res['eigenvalues'], exact):.1e} |"
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
