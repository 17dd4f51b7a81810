#!/usr/bin/env python3
"""Batch speed-up of `nlrom batch`: the same cases with --jobs 1 and --jobs 2 (goal: ≥ 1.7×).

    python3 tools/benchmarks/bench_batch.py [--case cases/demo.toml] [--copies 8] [--rounds 2]
                                 [--nlrom target/release/nlrom] [--keep DIR]

Writes --copies copies of the case into a temporary directory (every relative path in the case that
names an existing file is made absolute, so the copies read the same mesh or matrices), then runs
`nlrom batch COPIES --jobs J --out DIR -q` for J = 1 and J = 2, alternating, --rounds times each,
under `/usr/bin/time` (wall, user+sys CPU, peak RSS). Prints one line per run, the median wall time
per J, the ratio wall(J=1)/wall(J=2), the machine's load average before and after (the ratio is only
meaningful on an otherwise idle machine), and exits 1 when a batch fails. `nlrom batch` shares the
ROM of cases with the same mesh bytes and reduction settings (its content-addressed ROM cache), so
each copy of a mesh case reads its own copy of the mesh, made distinct by a `$Comments` section
that the reader skips, and every run starts from an empty output directory: each job reduces and
solves, as a first batch over new meshes would.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def absolutise(text: str, case_dir: Path) -> str:
    """Every quoted string that names an existing file relative to the case's folder → absolute."""

    def repl(m: re.Match) -> str:
        s = m.group(1)
        p = case_dir / s
        if not os.path.isabs(s) and ("/" in s or "." in s) and p.is_file():
            return '"' + str(p.resolve()) + '"'
        return m.group(0)

    return re.sub(r'"([^"\n]+)"', repl, text)


def drop_output_table(text: str) -> str:
    """`nlrom batch` names the results itself; an [output] file in the copies would be ignored."""
    return re.sub(r"(?ms)^\[output\].*?(?=^\[|\Z)", "", text)


def run_batch(nlrom: str, cases: list[Path], jobs: int, out: Path) -> tuple[float, float, int]:
    if out.exists():
        shutil.rmtree(out)
    cmd = ["/usr/bin/time", "-f", "TIME %e %U %S %M", nlrom, "batch", *map(str, cases),
           "--jobs", str(jobs), "--out", str(out), "-q"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    line = [x for x in p.stderr.splitlines() if x.startswith("TIME ")]
    if p.returncode != 0 or not line:
        sys.stderr.write(p.stderr)
        raise SystemExit(f"batch with --jobs {jobs} failed (exit {p.returncode})")
    wall, user, sys_, rss = line[-1].split()[1:]
    return float(wall), float(user) + float(sys_), int(rss)


def load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(ROOT / "cases" / "demo.toml"))
    ap.add_argument("--copies", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--nlrom", default=str(ROOT / "target" / "release" / "nlrom"))
    ap.add_argument("--keep", help="write the copies and results here instead of a temporary folder")
    a = ap.parse_args(argv)
    case = Path(a.case).resolve()
    text = drop_output_table(absolutise(case.read_text(), case.parent))
    work = Path(a.keep) if a.keep else Path(tempfile.mkdtemp(prefix="nlrom_bench_batch_"))
    work.mkdir(parents=True, exist_ok=True)
    mesh = re.search(r'(?m)^mesh\s*=\s*"([^"]+)"', text)
    cases = []
    for i in range(a.copies):
        c = work / f"{case.stem}_{i + 1}.toml"
        copy_text = text
        if mesh and Path(mesh.group(1)).is_file():
            m = work / f"mesh_{i + 1}.msh"
            data = Path(mesh.group(1)).read_bytes()
            if not data.endswith(b"\n"):
                data += b"\n"
            m.write_bytes(data + f"$Comments\ncopy {i + 1}\n$EndComments\n".encode())
            copy_text = text.replace(mesh.group(0), f'mesh = "{m}"')
        c.write_text(copy_text)
        cases.append(c)
    print(f"{a.copies} copies of {case} in {work}; load average before: {load()}")
    walls: dict[int, list[float]] = {1: [], 2: []}
    for r in range(a.rounds):
        for jobs in (1, 2):
            wall, cpu, rss = run_batch(a.nlrom, cases, jobs, work / f"out_j{jobs}")
            walls[jobs].append(wall)
            print(f"round {r + 1}  --jobs {jobs}: wall {wall:7.2f} s  CPU {cpu:7.2f} s  "
                  f"peak RSS {rss / 1024:6.1f} MB")
    w1, w2 = statistics.median(walls[1]), statistics.median(walls[2])
    print(f"median wall: --jobs 1 {w1:.2f} s, --jobs 2 {w2:.2f} s; speed-up {w1 / w2:.2f}x "
          f"(goal 1.7x); load average after: {load()}")
    if not a.keep:
        shutil.rmtree(work)
    return 0


if __name__ == "__main__":
    sys.exit(main())
