#!/usr/bin/env python3
"""Time `nlrom mesh info` against meshio and Gmsh's own reader on a large mesh, all four MSH variants.

    python3 tools/meshes/make_large_mesh.py tools/large/box          # once: ~1.7 M tetra10, ~1 GB (not committed)
    cargo build --release
    python3 tools/benchmarks/bench_mesh_info.py tools/large/box [--repeat 3] [--nlrom target/release/nlrom]

For each of PREFIX.{v41-binary,v41-ascii,v22-binary,v22-ascii}.msh it measures the wall time of
  * nlrom:  `nlrom mesh info FILE --json` (the whole command: read, parse, group sets, summary),
  * meshio: `meshio.read(FILE)` in a fresh Python process,
  * gmsh:   `gmsh.open(FILE)` in a fresh Python process (Gmsh's C++ reader through its Python API),
and the peak resident memory of each process (`/usr/bin/time -f %M`). The best of --repeat runs is
reported, after one warm-up read so that the file is in the page cache for everyone. It prints a
Markdown table with throughput (MB/s of file) and the ratios peer/nlrom, as in docs/performance.md.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

VARIANTS = ["v41-binary", "v41-ascii", "v22-binary", "v22-ascii"]

MESHIO = "import meshio, sys; m = meshio.read(sys.argv[1]); print(len(m.points))"
GMSH = (
    "import gmsh, sys; gmsh.initialize(readConfigFiles=False); gmsh.option.setNumber('General.Terminal', 0); "
    "gmsh.open(sys.argv[1]); print(len(gmsh.model.mesh.getNodes()[0])); gmsh.finalize()"
)


def timed(cmd: list[str]) -> tuple[float, float]:
    """Wall seconds and peak RSS (MB) of one run of cmd, via GNU time."""
    with tempfile.NamedTemporaryFile(mode="r", suffix=".time") as t:
        full = ["/usr/bin/time", "-f", "%e %M", "-o", t.name] + cmd
        r = subprocess.run(full, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed: {r.stderr[-2000:]}")
        wall, kb = t.read().split()[-2:]
        return float(wall), float(kb) / 1024.0


def best(cmd: list[str], repeat: int) -> tuple[float, float]:
    runs = [timed(cmd) for _ in range(repeat)]
    return min(r[0] for r in runs), max(r[1] for r in runs)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("prefix", type=Path)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--nlrom", default="target/release/nlrom")
    ap.add_argument("--skip-peers", action="store_true", help="time nlrom only")
    args = ap.parse_args()
    py = sys.executable
    rows = []
    for v in VARIANTS:
        f = Path(f"{args.prefix}.{v}.msh")
        if not f.exists():
            print(f"missing {f}: run tools/meshes/make_large_mesh.py first", file=sys.stderr)
            return 2
        size_mb = f.stat().st_size / 1e6
        with open(f, "rb") as fh:  # warm the page cache
            while fh.read(1 << 24):
                pass
        t_n, m_n = best([args.nlrom, "mesh", "info", str(f), "--json"], args.repeat)
        if args.skip_peers:
            t_m = m_m = t_g = m_g = float("nan")
        else:
            t_m, m_m = best([py, "-c", MESHIO, str(f)], max(1, args.repeat - 1))
            t_g, m_g = best([py, "-c", GMSH, str(f)], max(1, args.repeat - 1))
        rows.append((v, size_mb, t_n, m_n, t_m, m_m, t_g, m_g))
        print(f"{v}: nlrom {t_n:.2f} s, meshio {t_m:.2f} s, gmsh {t_g:.2f} s", file=sys.stderr, flush=True)

    print(f"\nFile: {args.prefix}.*.msh, {os.cpu_count()} cores\n")
    print("| variant | size (MB) | nlrom (s) | nlrom GB/s | nlrom peak (MB) | meshio (s) | meshio peak (MB) "
          "| gmsh (s) | gmsh peak (MB) | meshio / nlrom | gmsh / nlrom |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for v, size, t_n, m_n, t_m, m_m, t_g, m_g in rows:
        print(f"| {v} | {size:.0f} | {t_n:.2f} | {size / 1e3 / t_n:.2f} | {m_n:.0f} | {t_m:.2f} | {m_m:.0f} "
              f"| {t_g:.2f} | {m_g:.0f} | {t_m / t_n:.1f}x | {t_g / t_n:.1f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
