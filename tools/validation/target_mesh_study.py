#!/usr/bin/env python3
"""Target-face mesh study of the SAMA experiment (docs/validation.md, "The SAMA paper's experiment").

How far the non-conforming (SAMA, ``coupling = "interpolated"``) model of mode M1 lies from the
conforming node-to-node benchmark, as a function of the size of the target-face mesh relative to
the (fixed, structured) contact face. For every size factor the sector is meshed again with
``tools/meshes/make_meshes.py`` (contact face identical to the conforming model's, asserted), and

* the fully stuck k = 3 frequency of the ROM + one spring per contact node on the interpolated
  target point (``tools/validation/stuck_frequencies.rs``, independent of the harmonic balance), and
* at each requested preload, the FRF of ``cases/paper/m1_nonconforming.toml`` with the mesh
  replaced (``nlrom solve``): resonance frequency and peak amplitude,

are compared with the conforming case (``cases/paper/m1_conforming.toml``, same preloads).

Usage::

    cargo build --release --examples
    python3 tools/validation/target_mesh_study.py                       # factors 0.6 ... 2, n0 = 113 and 250 N
    python3 tools/validation/target_mesh_study.py --factors 0.6 2 --preloads 50 113 300 --stuck-only

Prints a Markdown table and writes it with the raw numbers (JSON) to --out.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tools" / "meshes"))

import make_meshes  # noqa: E402  (tools/ is not a package)

PAPER = REPO / "cases" / "paper"


def case_text(template: Path, mesh: Path, n0: float, result: Path) -> str:
    """The template case with its mesh, its preload (one value, no sweep) and its output replaced."""
    text = template.read_text()
    text = re.sub(r'(?m)^mesh = ".*"$', f'mesh = "{mesh}"', text)
    text = re.sub(r"(?ms)^\[sweep\]\n.*?(?=^\[|\Z)", "", text)
    text = re.sub(r"(?m)^n0 = .*$", f"n0 = {n0}", text)
    text = re.sub(r'(?m)^file = ".*"$', f'file = "{result}"', text)
    return text


def write_case(out: Path, name: str, template: Path, mesh: Path, n0: float) -> Path:
    path = out / f"{name}_n0_{n0:g}.toml"
    path.write_text(case_text(template, mesh.resolve(), n0, (out / f"{name}_n0_{n0:g}.h5").resolve()))
    return path


def stuck_frequency(example: Path, case: Path) -> float:
    """The lowest stuck frequency (Hz) of the `shape-interpolated` coupling (or of the node-to-node
    pairs on a conforming mesh, where all couplings coincide)."""
    run = subprocess.run([str(example), str(case)], capture_output=True, text=True, check=True)
    for line in run.stdout.splitlines():
        if line.startswith("shape-interpolated"):
            return float(line.split("[")[1].split(",")[0].rstrip("]"))
    raise RuntimeError(f"no 'shape-interpolated' line in the output of {example} {case}")


def resonance(nlrom: Path, case: Path) -> tuple[float, float]:
    """(resonance frequency in Hz, peak amplitude in m) of `nlrom solve CASE --json`."""
    run = subprocess.run([str(nlrom), "solve", str(case), "--json", "-q"], capture_output=True,
                         text=True)
    if run.returncode != 0:
        raise RuntimeError(f"nlrom solve {case} failed:\n{run.stderr}")
    frf = json.loads(run.stdout)["frf"][0]
    return frf["resonance_hz"], frf["peak_amplitude"]


def mesh_sector(out: Path, factor: float | None, reference):
    """Mesh the conforming sector (factor None) or a non-conforming one; returns (path, contact
    face coordinates, number of target nodes)."""
    if factor is None:
        name, params = "conforming", make_meshes.sector_params("conforming")
    else:
        name = f"target_{factor:g}"
        params = make_meshes.sector_params("nonconforming", target_size_factor=factor)
    contact, info = make_meshes.make_sector(name, params, out, reference)
    return out / f"{name}.msh", contact, info["target_nodes"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--factors", type=float, nargs="+", default=[0.6, 0.8, 1.0, 1.3, 1.6, 2.0],
                    help="target-face mesh size / contact-face mesh size (default: 0.6 ... 2)")
    ap.add_argument("--preloads", type=float, nargs="+", default=[113.0, 250.0],
                    help="total preloads n0 (N) of the FRF comparison (default: 113 250)")
    ap.add_argument("--stuck-only", action="store_true", help="only the fully stuck frequencies")
    ap.add_argument("--out", type=Path, default=REPO / "results" / "paper" / "target_study")
    ap.add_argument("--nlrom", type=Path, default=REPO / "target" / "release" / "nlrom")
    ap.add_argument("--example", type=Path,
                    default=REPO / "target" / "release" / "examples" / "stuck_frequencies")
    args = ap.parse_args(argv)
    for exe in (args.nlrom, args.example):
        if not exe.exists():
            sys.exit(f"{exe} not found: run `cargo build --release --examples` first")
    args.out.mkdir(parents=True, exist_ok=True)
    preloads = [] if args.stuck_only else args.preloads

    conf_mesh, contact, _ = mesh_sector(args.out, None, None)
    rows = []
    reference = {"stuck_hz": stuck_frequency(
        args.example, write_case(args.out, "conforming", PAPER / "m1_conforming.toml", conf_mesh, 113.0))}
    for n0 in preloads:
        case = write_case(args.out, "conforming", PAPER / "m1_conforming.toml", conf_mesh, n0)
        reference[n0] = resonance(args.nlrom, case)
    for factor in args.factors:
        mesh, _, n_target = mesh_sector(args.out, factor, contact)
        name = f"target_{factor:g}"
        template = PAPER / "m1_nonconforming.toml"
        row = {"factor": factor, "target_nodes": n_target, "contact_nodes": len(contact),
               "stuck_hz": stuck_frequency(args.example, write_case(args.out, name, template, mesh, 113.0))}
        for n0 in preloads:
            row[n0] = resonance(args.nlrom, write_case(args.out, name, template, mesh, n0))
        rows.append(row)
        print(f"factor {factor:g}: done", file=sys.stderr)

    head = "| target size / contact size | target nodes | stuck k = 3 (Hz) | Δ stuck |"
    rule = "|---|---|---|---|"
    for n0 in preloads:
        head += f" Δf at {n0:g} N | ΔA at {n0:g} N |"
        rule += "---|---|"
    lines = [head, rule]
    line = f"| conforming (node-to-node) | {len(contact)} | {reference['stuck_hz']:.2f} | |"
    for n0 in preloads:
        f, a = reference[n0]
        line += f" {f:.3f} Hz | {a:.4e} m |"
    lines.append(line)
    for row in rows:
        d_stuck = 100.0 * (row["stuck_hz"] / reference["stuck_hz"] - 1.0)
        line = f"| {row['factor']:g} | {row['target_nodes']} | {row['stuck_hz']:.2f} | {d_stuck:+.3f} % |"
        for n0 in preloads:
            (f, a), (f0, a0) = row[n0], reference[n0]
            line += f" {100.0 * (f / f0 - 1.0):+.3f} % | {100.0 * (a / a0 - 1.0):+.2f} % |"
        lines.append(line)
    table = "\n".join(lines)
    print(table)
    (args.out / "target_study.md").write_text(table + "\n")
    raw = {"reference": {str(k): v for k, v in reference.items()},
           "rows": [{str(k): v for k, v in r.items()} for r in rows]}
    (args.out / "target_study.json").write_text(json.dumps(raw, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
