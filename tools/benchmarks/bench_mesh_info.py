#!/usr/bin/env python3
"""Time `nlrom mesh info` against meshio and Gmsh's own reader on large meshes, all four MSH variants.

    python3 tools/meshes/make_large_mesh.py tools/large/lin --order 1 --tets 1000000   # once, not committed
    python3 tools/meshes/make_large_mesh.py tools/large/quad --order 2 --tets 350000
    cargo build --release
    python3 tools/benchmarks/bench_mesh_info.py tools/large/lin tools/large/quad [--repeat 3]
        [--variants v41-ascii,v22-ascii] [--nlrom target/release/nlrom] [--baseline OTHER_NLROM]

For each PREFIX and each of PREFIX.{v41-binary,v41-ascii,v22-binary,v22-ascii}.msh it measures
  * nlrom:  `nlrom mesh info FILE --json` (the whole command: read, parse, group sets, summary),
  * meshio: `meshio.read(FILE)` in a fresh Python process,
  * gmsh:   `gmsh.open(FILE)` in a fresh Python process (Gmsh's C++ reader through its Python API),
  * with --baseline, a second nlrom binary (e.g. an older build) on the same file,
the CPU time (user + system, all threads, from the child's resource usage), the wall time and the
peak resident memory of each process. Python's start-up and imports are part of the peers' times,
as they are part of a user's. The runs of one file are interleaved (nlrom, meshio, gmsh, nlrom, ...)
after one warm-up read, so that the file is in the page cache for everyone and a load change on a
shared machine hits all of them alike; the best of --repeat runs is reported. On a shared machine
the CPU time is the comparable number: it does not count the time spent waiting for a core. The
Markdown table printed at the end is the one in docs/performance.md.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

VARIANTS = ["v41-binary", "v41-ascii", "v22-binary", "v22-ascii"]

MESHIO = "import meshio, sys; m = meshio.read(sys.argv[1]); print(len(m.points))"
GMSH = (
    "import gmsh, sys; gmsh.initialize(readConfigFiles=False); gmsh.option.setNumber('General.Terminal', 0); "
    "gmsh.open(sys.argv[1]); print(len(gmsh.model.mesh.getNodes()[0])); gmsh.finalize()"
)


def timed(cmd: list[str]) -> tuple[float, float, float]:
    """CPU seconds (user + system), wall seconds and peak RSS (MB) of one run of cmd."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    err = p.stderr.read().decode(errors="replace") if p.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed: {err[-2000:]}")
    return ru.ru_utime + ru.ru_stime, wall, ru.ru_maxrss / 1024.0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("prefixes", type=Path, nargs="+")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--variants", default=",".join(VARIANTS), help="comma-separated subset of " + ",".join(VARIANTS))
    ap.add_argument("--nlrom", default="target/release/nlrom")
    ap.add_argument("--baseline", help="a second nlrom binary to time on the same files")
    ap.add_argument("--skip-peers", action="store_true", help="time nlrom (and --baseline) only")
    args = ap.parse_args()
    py = sys.executable
    tools = {"nlrom": lambda f: [args.nlrom, "mesh", "info", f, "--json"]}
    if args.baseline:
        tools["baseline"] = lambda f: [args.baseline, "mesh", "info", f, "--json"]
    if not args.skip_peers:
        tools["meshio"] = lambda f: [py, "-c", MESHIO, f]
        tools["gmsh"] = lambda f: [py, "-c", GMSH, f]
    rows = []
    load_start = os.getloadavg()[0]
    for prefix in args.prefixes:
        for v in args.variants.split(","):
            f = Path(f"{prefix}.{v}.msh")
            if not f.exists():
                print(f"missing {f}: run tools/meshes/make_large_mesh.py first", file=sys.stderr)
                return 2
            with open(f, "rb") as fh:  # warm the page cache
                while fh.read(1 << 24):
                    pass
            runs: dict[str, list[tuple[float, float, float]]] = {k: [] for k in tools}
            for _ in range(args.repeat):
                for k, cmd in tools.items():
                    runs[k].append(timed(cmd(str(f))))
            best = {k: (min(r[0] for r in rs), min(r[1] for r in rs), max(r[2] for r in rs)) for k, rs in runs.items()}
            rows.append((prefix.name, v, f.stat().st_size / 1e6, best))
            print(f"{prefix.name} {v}: " + ", ".join(f"{k} {b[0]:.2f} s CPU" for k, b in best.items()),
                  file=sys.stderr, flush=True)

    load = f"load (1-min average) {load_start:.1f} at the start, {os.getloadavg()[0]:.1f} at the end"
    print(f"\n{os.cpu_count()} cores, {load}; best of {args.repeat} interleaved runs; "
          "CPU = user + system of all threads\n")
    peers = [k for k in tools if k != "nlrom"]
    head = "| mesh | variant | size (MB) | nlrom CPU (s) | nlrom wall (s) | nlrom peak (MB) |"
    head += "".join(f" {k} CPU (s) | {k} wall (s) |" for k in peers)
    head += "".join(f" {k} / nlrom CPU | {k} / nlrom wall |" for k in peers)
    print(head)
    print("|" + "---|" * (6 + 4 * len(peers)))
    for name, v, size, b in rows:
        n = b["nlrom"]
        line = f"| {name} | {v} | {size:.0f} | {n[0]:.3f} | {n[1]:.3f} | {n[2]:.0f} |"
        line += "".join(f" {b[k][0]:.2f} | {b[k][1]:.2f} |" for k in peers)
        line += "".join(f" {b[k][0] / n[0]:.1f}× | {b[k][1] / n[1]:.1f}× |" for k in peers)
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
