#!/usr/bin/env python3
"""Craig–Bampton reduction written with scipy: reference numbers and a speed/memory comparison.

    python3 tools/benchmarks/bench_reduce.py mesh [DIR] [--size 0.0066]   (DIR defaults to tools/large/reduce)
    python3 tools/benchmarks/bench_reduce.py reference DIR [--modes 100] [--out FILE.json]
    python3 tools/benchmarks/bench_reduce.py bench DIR [--modes 100] [--block 128] [--solver cholmod|superlu]
                                  [--nlrom "COMMAND ..."]

DIR holds K.mtx and M.mtx (the free, clamped model as `nlrom export` writes them) and masters.txt
(one 0-based row of K per line: the master DOF b; all other rows are interior i). The Rust tests
write such a directory for the bundled sector with
`NLROM_CB_DUMP=DIR cargo test --release --test reduction_cb cb_frequencies`; `benches/reduce.rs`
writes one for the large generated sector (`NLROM_REDUCE_DUMP=DIR`).

mesh: writes DIR/block.msh (gmsh, 10-node tetrahedra of uniform size --size, a 0.124 × 0.4 × 0.03 m
  block standing in for a blade sector: x = 0 face "hub" (clamped), y = 0 face "low", y = 0.4 face
  "high" (the frontiers, ~3 000 master DOF at the default size, ~115 000 free DOF), DIR/case.toml
  (steel, hub clamped, [reduction] interface_modes = 100, keep = ["low", "high"]; no [cyclic]
  table, so the CB of the sector is all that is computed) and DIR/master_tags.txt (node tags of
  low and high). gmsh meshes with 2 threads, so the node count varies slightly between runs.
  Then `nlrom export DIR/case.toml --dir DIR` writes K.mtx, M.mtx and dofs.csv, and `bench DIR`
  maps the master tags to rows (masters.txt), runs scipy and, with --nlrom, the given nlrom
  command (e.g. `nlrom reduce DIR/case.toml -o DIR/rom.h5`, the same reduction) and prints the
  ratios.

reference: the lowest --modes eigenvalues λ (rad²/s²) of the fixed-interface problem
  K_ii φ = λ M_ii φ by ARPACK shift-invert (σ = 0, tol 1e-14) with CHOLMOD's (or SuperLU's)
  factor of K_ii, written as JSON (tests/data/sector_interior_modes.json is made this way).

bench: runs the same reduction as `nlrom::reduction::craig_bampton` in a fresh Python process under
  `/usr/bin/time -f "%e %U %S %M"`: one factorisation of K_ii, the --modes fixed-interface modes
  (eigsh, shift-invert with that factor), static modes Ψ = −K_ii⁻¹K_ib in blocks of --block
  columns streamed into K_cb = K_bb + K_ibᵀΨ and M_cb = M_bb + M_ibᵀΨ + Ψᵀ(M_ib + M_iiΨ),
  (M_bi + ΨᵀM_ii)Φ (Ψ never stored whole, as in nlrom). With --nlrom the given command (e.g.
  `target/release/nlrom modes CASE --stage cb --num 10`) is timed the same way and the ratios
  scipy/nlrom of wall time, CPU time (user+sys) and peak RSS are printed.
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

# Runs in a fresh process: argv = DIR MODES BLOCK SOLVER; prints one JSON line.
PEER = r"""
import json, sys, time
import numpy as np, scipy.io, scipy.sparse as sp, scipy.sparse.linalg as sla
d, n_m, block, solver = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
K = scipy.io.mmread(d + '/K.mtx').tocsc(); M = scipy.io.mmread(d + '/M.mtx').tocsc()
b = np.loadtxt(d + '/masters.txt', dtype=np.int64, ndmin=1)
t0 = time.perf_counter()
mask = np.ones(K.shape[0], bool); mask[b] = False; i = np.nonzero(mask)[0]
Kii = K[i][:, i].tocsc(); Mii = M[i][:, i].tocsc()
Kib = K[i][:, b].tocsc(); Mib = M[i][:, b].tocsc()
Kbb = K[b][:, b].toarray(); Mbb = M[b][:, b].toarray()
if solver == 'cholmod':
    from sksparse.cholmod import cholesky
    f = cholesky(Kii)
    solve = lambda x: f(x)
else:
    lu = sla.splu(Kii)
    solve = lambda x: lu.solve(np.asarray(x))
t_factor = time.perf_counter() - t0
op = sla.LinearOperator(Kii.shape, matvec=solve, dtype=float)
lam, phi = sla.eigsh(Kii, n_m, Mii, sigma=0.0, which='LM', OPinv=op, tol=1e-10)
order = np.argsort(lam); lam = lam[order]; phi = phi[:, order]
t_modes = time.perf_counter() - t0
n_b = len(b)
Kcb = Kbb.copy(); Mcb = Mbb.copy(); Mmb = np.zeros((n_m, n_b))
for s in range(0, n_b, block):
    e = min(n_b, s + block)
    X = -solve(Kib[:, s:e].toarray())
    Kcb[:, s:e] += Kib.T @ X
    Y = Mib[:, s:e].toarray() + Mii @ X
    Mmb[:, s:e] = phi.T @ Y
    Mcb[:, s:e] += Mib.T @ X
    Mcb[:, s:e] -= Kib.T @ solve(Y)
t_total = time.perf_counter() - t0
print(json.dumps({'factor_s': t_factor, 'modes_s': t_modes - t_factor, 'total_s': t_total,
                  'n_i': int(len(i)), 'n_b': int(n_b), 'lambda_last': float(lam[-1]),
                  'kcb_trace': float(np.trace(Kcb)), 'mcb_trace': float(np.trace(Mcb))}))
"""

REFERENCE = r"""
import json, sys
import numpy as np, scipy.io, scipy.sparse.linalg as sla
d, n_m, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
K = scipy.io.mmread(d + '/K.mtx').tocsc(); M = scipy.io.mmread(d + '/M.mtx').tocsc()
b = np.loadtxt(d + '/masters.txt', dtype=np.int64, ndmin=1)
mask = np.ones(K.shape[0], bool); mask[b] = False; i = np.nonzero(mask)[0]
Kii = K[i][:, i].tocsc(); Mii = M[i][:, i].tocsc()
try:
    from sksparse.cholmod import cholesky
    f = cholesky(Kii); solver = 'cholmod'
    op = sla.LinearOperator(Kii.shape, matvec=lambda x: f(x), dtype=float)
except ImportError:
    lu = sla.splu(Kii); solver = 'superlu'
    op = sla.LinearOperator(Kii.shape, matvec=lambda x: lu.solve(x), dtype=float)
lam, _ = sla.eigsh(Kii, n_m, Mii, sigma=0.0, which='LM', OPinv=op, tol=1e-14)
lam = np.sort(lam)
json.dump({'source': 'tools/benchmarks/bench_reduce.py reference (scipy eigsh shift-invert sigma=0, tol 1e-14, '
                     + solver + ')',
           'n_interior': int(len(i)), 'n_masters': int(len(b)),
           'eigenvalues': [float(x) for x in lam]}, open(out, 'w'), indent=1)
print(f'wrote {out}: {n_m} eigenvalues, interior {len(i)} DOF, {len(b)} masters ({solver})')
"""


def timed(cmd: list[str]) -> tuple[dict, str]:
    """Runs cmd under /usr/bin/time; returns wall s, user+sys s, peak MB and the stdout."""
    with tempfile.NamedTemporaryFile("r", suffix=".time") as tf:
        p = subprocess.run(["/usr/bin/time", "-o", tf.name, "-f", "%e %U %S %M", *cmd],
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
        wall, user, sys_s, kb = tf.read().split()[-4:]
    return {"wall_s": float(wall), "cpu_s": float(user) + float(sys_s), "peak_mb": int(kb) / 1024}, p.stdout


CASE = """# Generated by tools/benchmarks/bench_reduce.py mesh: CB reduction benchmark.
title = "block sector, CB with 100 interface modes"

[model]
mesh = "block.msh"
material = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}
clamp = ["hub"]

[reduction]
interface_modes = {modes}
keep = ["low", "high"]
"""


def make_mesh(out: Path, size: float, modes: int) -> None:
    """The block mesh, case and master node tags (see the module documentation)."""
    import gmsh

    lx, ly, lz = 0.124, 0.4, 0.03
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 2)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.add("block")
    box = gmsh.model.occ.addBox(0, 0, 0, lx, ly, lz)
    gmsh.model.occ.synchronize()
    faces = {}
    for _, f in gmsh.model.getEntities(2):
        b = gmsh.model.getBoundingBox(2, f)
        if abs(b[3] - b[0]) < 1e-6 and abs(b[0]) < 1e-6:
            faces["hub"] = f
        elif abs(b[4] - b[1]) < 1e-6:
            faces["low" if abs(b[1]) < 1e-6 else "high"] = f
    gmsh.model.addPhysicalGroup(3, [box], name="volume")
    for name, f in faces.items():
        gmsh.model.addPhysicalGroup(2, [f], name=name)
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), size)
    gmsh.model.mesh.generate(3)
    out.mkdir(parents=True, exist_ok=True)
    gmsh.write(str(out / "block.msh"))
    tags = set()
    for name in ("low", "high"):
        for dim, tag in gmsh.model.getPhysicalGroups(2):
            if gmsh.model.getPhysicalName(dim, tag) == name:
                tags.update(int(t) for t in gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)[0])
    hub = set()
    for dim, tag in gmsh.model.getPhysicalGroups(2):
        if gmsh.model.getPhysicalName(dim, tag) == "hub":
            hub.update(int(t) for t in gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)[0])
    n_nodes = len(gmsh.model.mesh.getNodes()[0])
    gmsh.finalize()
    tags -= hub  # clamped nodes have no DOF
    (out / "master_tags.txt").write_text("\n".join(str(t) for t in sorted(tags)))
    (out / "case.toml").write_text(CASE.format(modes=modes))
    print(f"{out / 'block.msh'}: {n_nodes} nodes (~{3 * (n_nodes - len(hub))} free DOF), "
          f"{len(tags)} master nodes ({3 * len(tags)} DOF)")


def master_rows(d: Path) -> None:
    """masters.txt (0-based rows) from dofs.csv (`row,node_tag,component`) and master_tags.txt."""
    tags = {int(t) for t in (d / "master_tags.txt").read_text().split()}
    rows = []
    for line in (d / "dofs.csv").read_text().splitlines()[1:]:
        row, tag, _ = line.split(",")
        if int(tag) in tags:
            rows.append(int(row))
    (d / "masters.txt").write_text("\n".join(str(r) for r in sorted(rows)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["mesh", "reference", "bench"])
    ap.add_argument("dir", type=Path, nargs="?", default=Path("tools/large/reduce"))
    ap.add_argument("--size", type=float, default=0.0066)
    ap.add_argument("--modes", type=int, default=100)
    ap.add_argument("--out", type=Path, default=Path("sector_interior_modes.json"))
    ap.add_argument("--block", type=int, default=128)
    ap.add_argument("--solver", choices=["cholmod", "superlu"], default="cholmod")
    ap.add_argument("--nlrom", help="nlrom command line to time for the comparison")
    args = ap.parse_args(argv)
    if args.what == "mesh":
        make_mesh(args.dir, args.size, args.modes)
        return 0
    if args.what == "reference":
        subprocess.run([sys.executable, "-c", REFERENCE, str(args.dir), str(args.modes), str(args.out)], check=True)
        return 0
    if (args.dir / "master_tags.txt").exists() and (args.dir / "dofs.csv").exists():
        master_rows(args.dir)
    rows = []
    peer, out = timed([sys.executable, "-c", PEER, str(args.dir), str(args.modes), str(args.block), args.solver])
    info = json.loads(out.strip().splitlines()[-1])
    print(f"scipy-{args.solver}: {info}")
    rows.append((f"scipy ({args.solver})", peer))
    if args.nlrom:
        mine, out = timed(shlex.split(args.nlrom))
        print(out)
        rows.append(("nlrom", mine))
    print("| solver | wall s | CPU s (user+sys) | peak MB |")
    print("|---|---|---|---|")
    for name, r in rows:
        print(f"| {name} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | {r['peak_mb']:.0f} |")
    if args.nlrom:
        s, n = rows[0][1], rows[1][1]
        print(f"ratios scipy/nlrom: wall {s['wall_s'] / n['wall_s']:.2f}, CPU {s['cpu_s'] / n['cpu_s']:.2f}, "
              f"peak memory {s['peak_mb'] / n['peak_mb']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
