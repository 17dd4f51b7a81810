#!/usr/bin/env python3
"""The bundled demo sector under normal load variation: does every frequency response reach its end?

    python3 tools/validation/sector_corpus.py [--kn 0 1e6 1e7 1e8 1e9] [--forces 1 3 10 30 100]
        [--window 880 960] [--harmonics 1] [--out results/sector_corpus] [--exe PATH]

`cases/demo.toml` (the N = 8 shrouded sector, node-to-node shroud contact, n0 = 100 N, μ = 0.3,
k_t = 1e8 N/m) with the normal contact stiffness k_n of `--kn` (0: constant normal load; from 1e6
N/m on the pairs' normal load varies and they may separate) and the axial excitation of `--forces`
(N, 1 N in the demo: the `excitation.force_scale` sweep), over the window of `--window` (Hz; the
stuck-shroud bending mode of harmonic index 3 with the normal stiffness, 880–960 Hz). One
`nlrom solve --json` per k_n, the forces as the case's sweep; the result files go to `--out`.

Prints one row per curve: k_n, force, whether it reached the end of the window, the jumps of the
sweep (`/frf/<i>/jumps`), the points, the Newton iterations, the largest accepted scaled residual
(every one at most the Newton tolerance) and the CPU seconds of the curve, then the totals. Exit
status 1 when a curve does not reach its end or an accepted residual exceeds the tolerance.
"""

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "post"))
import nlrom_results  # noqa: E402

TOLERANCE = 1e-8  # the Newton tolerance of the case (the default of [harmonic_balance])


def replace_once(text, old, new):
    """`text` with the one occurrence of `old` replaced by `new`; an error if it is not there once."""
    if text.count(old) != 1:
        raise SystemExit(f"cases/demo.toml: expected one '{old}', found {text.count(old)}")
    return text.replace(old, new)


def case_text(kn, forces, window, harmonics, output):
    """The demo case with k_n = `kn`, the window `window` (Hz), H = `harmonics`, the force sweep
    `forces` (N, as factors on the demo's 1 N) and its results written to `output`."""
    text = open(os.path.join(ROOT, "cases", "demo.toml")).read()
    mesh = os.path.join(ROOT, "meshes", "sector8.msh")
    text = replace_once(text, 'mesh = "../meshes/sector8.msh"', f'mesh = "{mesh}"')
    text = replace_once(text, "kn = 0.0", f"kn = {kn:e}")
    text = replace_once(text, "harmonics = 1", f"harmonics = {harmonics}")
    text = replace_once(text, "start_hz = 150.0", f"start_hz = {window[0]}")
    text = replace_once(text, "end_hz = 175.0", f"end_hz = {window[1]}")
    values = ", ".join(f"{f:.6g}" for f in forces)
    text += f'\n[sweep]\n"excitation.force_scale" = [{values}]\n'
    text += f'\n[output]\nfile = "{output}"\n'
    return text


def curve_rows(kn, forces, window, summary, path):
    """One row per force: the JSON summary of `nlrom solve` and the curve read from `path`."""
    tree = nlrom_results.load(path) if os.path.exists(path) else None
    rows = []
    for entry in summary["frf"]:
        i = entry["sweep_point"]
        row = {"kn": kn, "force": forces[i], "end": entry["end"], "error": entry["error"],
               "points": entry.get("points", 0), "cpu": entry.get("cpu_seconds", float("nan")),
               "jumps": [], "iterations": 0, "residual": float("nan"), "last_hz": float("nan")}
        frfs = tree["frf"] if tree is not None else []
        frf = frfs[i] if i < len(frfs) else None
        if frf is not None:
            row["jumps"] = [int(j) for j in frf.get("jumps", [])]
            row["iterations"] = int(sum(frf["newton_iterations"]))
            row["residual"] = float(max(frf["residual"]))
            row["last_hz"] = float(frf["frequency_hz"][-1])
        rows.append(row)
    return rows


def reached(row, window):
    """Whether the curve of `row` ends at the window's end (within 1e-9 relative)."""
    return row["end"] == "reached_end" and abs(row["last_hz"] - window[1]) <= 1e-9 * window[1]


def print_table(rows, window):
    print("| k_n (N/m) | force (N) | end | jumps | points | Newton iterations | max residual | CPU s |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        end = "reached" if reached(r, window) else f"{r['end']} at {r['last_hz']:.3f} Hz"
        jumps = ", ".join(str(j) for j in r["jumps"]) or "–"
        print(f"| {r['kn']:.0e} | {r['force']:g} | {end} | {jumps} | {r['points']} | "
              f"{r['iterations']} | {r['residual']:.1e} | {r['cpu']:.1f} |")
    done = sum(reached(r, window) for r in rows)
    jumped = sum(bool(r["jumps"]) for r in rows)
    worst = max(r["residual"] for r in rows)
    print(f"\n{done} of {len(rows)} curves reach {window[1]} Hz, {jumped} with jumps; "
          f"largest accepted residual {worst:.2e}; CPU {sum(r['cpu'] for r in rows):.1f} s in all")
    return done == len(rows) and worst <= TOLERANCE


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kn", type=float, nargs="+", default=[0.0, 1e6, 1e7, 1e8, 1e9])
    parser.add_argument("--forces", type=float, nargs="+", default=[1.0, 3.0, 10.0, 30.0, 100.0])
    parser.add_argument("--window", type=float, nargs=2, default=[880.0, 960.0])
    parser.add_argument("--harmonics", type=int, default=1)
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "sector_corpus"))
    parser.add_argument("--exe", default=os.path.join(ROOT, "target", "release", "nlrom"))
    args = parser.parse_args()
    if not os.path.exists(args.exe):
        raise SystemExit(f"{args.exe} not found: build it with `cargo build --release`")
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for kn in args.kn:
        stem = os.path.join(args.out, f"demo_kn{kn:.0e}_h{args.harmonics}")
        result = os.path.abspath(stem + ".h5")
        with open(stem + ".toml", "w") as f:
            f.write(case_text(kn, args.forces, args.window, args.harmonics, result))
        done = subprocess.run([args.exe, "solve", stem + ".toml", "--json", "-q"],
                              capture_output=True, text=True)
        if not done.stdout.strip():
            print(f"k_n = {kn:.0e}: nlrom exited {done.returncode}: {done.stderr.strip()}")
            rows += [{"kn": kn, "force": f, "end": "failed", "error": done.stderr, "points": 0,
                      "cpu": float("nan"), "jumps": [], "iterations": 0,
                      "residual": float("inf"), "last_hz": float("nan")} for f in args.forces]
            continue
        rows += curve_rows(kn, args.forces, args.window, json.loads(done.stdout), result)
        print(f"k_n = {kn:.0e}: done ({done.returncode})", flush=True)
    ok = print_table(rows, args.window)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
