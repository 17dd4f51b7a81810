#!/usr/bin/env python3
"""The SAMA paper's experiment (seed 004, §6.2) on the bundled shrouded sector, in one command.

    python3 tools/paper_comparison.py [--modes m1] [--skip-solve] [--out results/paper]

For every mode (cases/paper/<mode>_{conforming,nonconforming,misaligned}.toml) it runs
`nlrom solve` (release build; one FRF per preload n0 of Table 3), then
  - prints and writes <out>/comparison.md: per preload the resonance frequency, peak amplitude and
    Q-factor of each model and the differences of the non-conforming (SAMA) and misaligned models
    relative to the conforming (node-to-node) benchmark, with the acceptance check of issue 8
    (SAMA vs conforming: resonance within 0.5 %, amplitude within 3 %);
  - plots <out>/<mode>_*_frf.png (FRFs per preload, Figs 19-20), <out>/<mode>_frf_compare.png
    (Figs 21-22 / 26-27 at n0 = 113 N) and <out>/<mode>_performance.png (Figs 23-25 / 28-30),
    using tools/plot_frf.py (same metric definitions as `nlrom solve`).
Exit status 1 when a SAMA-vs-conforming difference exceeds the tolerance.
"""

import argparse
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import nlrom_results  # noqa: E402
import plot_frf  # noqa: E402

VARIANTS = ["conforming", "nonconforming", "misaligned"]
FREQ_TOL = 0.5e-2
AMP_TOL = 3e-2


def solve(case, out):
    exe = os.path.join(ROOT, "target", "release", "nlrom")
    cmd = [exe] if os.path.exists(exe) else ["cargo", "run", "--release", "-q", "--"]
    cmd += ["solve", case, "-o", out, "--quiet"]
    print("$", " ".join(cmd), flush=True)
    done = subprocess.run(cmd, cwd=ROOT)
    if done.returncode != 0:
        print(f"nlrom solve {case} exited {done.returncode} (the converged points are kept)")


def table_of(path):
    rows = {}
    tree = nlrom_results.load(path)
    for frf in tree["frf"]:
        if not len(frf["frequency_hz"]):
            continue
        _, n0 = plot_frf.sweep_value(frf)
        f_r, a_r, q, _ = plot_frf.metrics(frf)
        rows[n0] = (f_r, a_r, q)
    return tree, rows


def pct(a, b):
    return None if a is None or b is None else 100.0 * (a - b) / b


def fmt(x, spec):
    return "-" if x is None else format(x, spec)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--modes", nargs="+", default=["m1"])
    parser.add_argument("--skip-solve", action="store_true", help="reuse existing result files")
    parser.add_argument("--out", default=os.path.join(ROOT, "results", "paper"))
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lines = ["| mode | n0 (N) | model | resonance (Hz) | peak amplitude (m) | Q | Δf vs conforming | ΔA vs conforming | ΔQ vs conforming |",
             "|---|---|---|---|---|---|---|---|---|"]
    failures = []
    for mode in args.modes:
        files, trees, tables = {}, {}, {}
        for v in VARIANTS:
            case = os.path.join("cases", "paper", f"{mode}_{v}.toml")
            if not os.path.exists(os.path.join(ROOT, case)):
                continue
            out = os.path.join(args.out, f"{mode}_{v}.h5")
            if not args.skip_solve:
                solve(case, out)
            if os.path.exists(out):
                files[v] = out
                trees[v], tables[v] = table_of(out)
        if "conforming" not in tables:
            print(f"{mode}: no conforming results")
            continue
        for n0, (f_c, a_c, q_c) in sorted(tables["conforming"].items()):
            for v in VARIANTS:
                if v not in tables or n0 not in tables[v]:
                    continue
                f, a, q = tables[v][n0]
                df, da, dq = pct(f, f_c), pct(a, a_c), pct(q, q_c)
                lines.append(f"| {mode} | {n0:g} | {v} | {f:.3f} | {a:.4e} | {fmt(q, '.1f')} | "
                             f"{fmt(df, '+.3f')} % | {fmt(da, '+.2f')} % | {fmt(dq, '+.2f')} % |")
                if v == "nonconforming" and (abs(df) > 100 * FREQ_TOL or abs(da) > 100 * AMP_TOL):
                    failures.append(f"{mode} n0 = {n0:g}: Δf {df:+.3f} %, ΔA {da:+.2f} %")
        labels = [v for v in VARIANTS if v in trees]
        for v in labels:
            plot_frf.plot_file(plt, trees[v], os.path.join(args.out, f"{mode}_{v}_frf.png"),
                               f"{mode} {v}", None)
        ref = [{**{"frf": [f for f in trees[v]["frf"]
                           if plot_frf.sweep_value(f)[1] == 113.0]}} for v in labels]
        plot_frf.plot_compare(plt, ref, labels, os.path.join(args.out, f"{mode}_frf_compare.png"),
                              None)
        perf = []
        for v in labels:
            for n0, (f, a, q) in sorted(tables[v].items()):
                perf.append({"label": v, "parameter": "n0 (N)", "value": n0, "resonance_hz": f,
                             "peak_amplitude": a, "q_factor": q})
        plot_frf.plot_performance(plt, perf, labels, os.path.join(args.out, f"{mode}_performance.png"))
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(args.out, "comparison.md"), "w") as f:
        f.write(text + "\n")
    if failures:
        print("SAMA vs conforming outside the tolerance (0.5 % resonance, 3 % amplitude):")
        print("\n".join("  " + x for x in failures))
        return 1
    print("SAMA vs conforming: every preload within 0.5 % (resonance) and 3 % (amplitude)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
