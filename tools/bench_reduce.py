#!/usr/bin/env python3
"""Craig–Bampton reduction written with scipy: reference numbers and a speed/memory comparison.

    python3 tools/bench_reduce.py reference DIR [--modes 100] [--out FILE.json]
    python3 tools/bench_reduce.py bench DIR [--modes 100] [--block 128] [--solver cholmod|superlu]
                                  [--nlrom "COMMAND ..."]

DIR holds K.mtx and M.mtx (the free, clamped model as `nlrom export` writes them) and masters.txt
(one 0-based row of K per line: the master DOF b; all other rows are interior i). The Rust tests
write such a directory for the bundled sector with
`NLROM_CB_DUMP=DIR cargo test --release --test reduction_cb cb_frequencies`; `benches/reduce.rs`
writes one for the large generated sector (`NLROM_REDUCE_DUMP=DIR`).

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
json.dump({'source': 'tools/bench_reduce.py reference (scipy eigsh shift-invert sigma=0, tol 1e-14, '
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["reference", "bench"])
    ap.add_argument("dir", type=Path)
    ap.add_argument("--modes", type=int, default=100)
    ap.add_argument("--out", type=Path, default=Path("sector_interior_modes.json"))
    ap.add_argument("--block", type=int, default=128)
    ap.add_argument("--solver", choices=["cholmod", "superlu"], default="cholmod")
    ap.add_argument("--nlrom", help="nlrom command line to time for the comparison")
    args = ap.parse_args(argv)
    if args.what == "reference":
        subprocess.run([sys.executable, "-c", REFERENCE, str(args.dir), str(args.modes), str(args.out)], check=True)
        return 0
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
