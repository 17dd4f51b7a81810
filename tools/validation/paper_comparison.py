#!/usr/bin/env python3
"""The SAMA paper's experiment (Battiato 2021, §6.2) on the bundled shrouded sector, in one command.

    python3 tools/validation/paper_comparison.py [--modes m1 m2] [--harmonics H] [--skip-solve] [--out results/paper] [--figures docs/paper]

Modes (default: both): M1 = the first stuck-shroud mode of harmonic index 3 (bending, 791 Hz fully
stuck), M2 = the first torsional blade mode of harmonic index 3 (5126 Hz fully stuck); see
`cargo run --release --example stuck_frequencies -- cases/paper/m1_conforming.toml 1 6000 --shapes`.
For every mode (cases/paper/<mode>_{conforming,nonconforming,misaligned}.toml) it runs
`nlrom solve` (release build; one FRF per preload n0 of Table 3, one model at a time), then
  - prints and writes <out>/comparison.md (comparison_<modes>.md for a subset): per mode and
    preload the resonance frequency, peak amplitude and Q-factor of each model, the differences of
    the non-conforming (SAMA) and misaligned models relative to the conforming (node-to-node)
    benchmark and a path column ('folds' where the frequency turns back, 'stops at F Hz' where
    the continuation failed), with the acceptance check per mode (SAMA vs conforming:
    resonance within 0.5 %, amplitude within 3 %);
  - plots <out>/<mode>_*_frf.png (FRFs per preload, Figs 19-20), <out>/<mode>_frf_compare.png
    (Figs 21-22 / 26-27 at n0 = 113 N) and <out>/<mode>_performance.png (Figs 23-25 / 28-30),
    using tools/post/plot_frf.py (same metric definitions as `nlrom solve`);
  - copies the comparison table and the PNGs to --figures (default docs/paper/, committed: the
    README shows them).
With --harmonics H (other than the cases' H = 1) every case is solved with H harmonics instead (a
copy of the case with `harmonics = H`, written beside it and removed after the run); the results,
the table (comparison_h<H>.md) and the figures go to results/paper_h<H> and docs/paper/h<H>.
Exit status 1 when, in any mode, a SAMA-vs-conforming difference exceeds the tolerance, a
conforming or SAMA path stops inside the window (its peak is then unknown), there are no
conforming results, or a case differs from m1's in [model], [cyclic], [reduction] or [[contact]]
(every mode runs on the same models).
"""

import argparse
import os
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "post"))
import nlrom_results  # noqa: E402
import plot_frf  # noqa: E402

VARIANTS = ["conforming", "nonconforming", "misaligned"]
MODES = {"m1": "M1, bending (791 Hz fully stuck)", "m2": "M2, first torsion (5126 Hz fully stuck)"}
FREQ_TOL = 0.5e-2
AMP_TOL = 3e-2


def with_harmonics(case, harmonics):
    """`case` (a path under ROOT) itself when `harmonics` is None, else a copy beside it (the same
    relative mesh paths) whose [harmonic_balance] asks for `harmonics` harmonics."""
    if harmonics is None:
        return case
    lines = open(os.path.join(ROOT, case)).read().splitlines()
    found = [i for i, line in enumerate(lines) if line.strip().startswith("harmonics =")]
    if len(found) != 1:
        raise SystemExit(f"{case}: expected one 'harmonics =' line, found {len(found)}")
    lines[found[0]] = f"harmonics = {harmonics}"
    head, name = os.path.split(case)
    copy = os.path.join(head, f".h{harmonics}_{name}")
    with open(os.path.join(ROOT, copy), "w") as f:
        f.write("\n".join(lines) + "\n")
    return copy


def solve(case, out, harmonics=None):
    case = with_harmonics(case, harmonics)
    exe = os.path.join(ROOT, "target", "release", "nlrom")
    cmd = [exe] if os.path.exists(exe) else ["cargo", "run", "--release", "-q", "--"]
    cmd += ["solve", case, "-o", out, "--quiet"]
    print("$", " ".join(cmd), flush=True)
    done = subprocess.run(cmd, cwd=ROOT)
    if harmonics is not None:
        os.remove(os.path.join(ROOT, case))
    if done.returncode != 0:
        print(f"nlrom solve {case} exited {done.returncode} (the converged points are kept)")


def path_note(freq, start, end):
    """'' for a path from `start` to `end` (Hz) in one direction; 'folds' when the frequency turns
    back on the way (a turning point: the resonance is still the largest amplitude, the Q-factor's
    half-power walk along the path may mislead); 'stops at F Hz' when it does not reach `end`."""
    freq = np.asarray(freq, dtype=float)
    if abs(freq[-1] - end) > 1e-9 * abs(end):
        return f"stops at {freq[-1]:.1f} Hz"
    return "folds" if np.any(np.diff(freq) * np.sign(end - start) < 0) else ""


def table_of(path):
    """The results tree of `path` and {n0: (f_r, A_r, Q, path note)} per FRF."""
    import tomllib
    rows = {}
    tree = nlrom_results.load(path)
    window = tomllib.loads(tree["attrs"]["case_text"])["continuation"]
    for frf in tree["frf"]:
        if not len(frf["frequency_hz"]):
            continue
        _, n0 = plot_frf.sweep_value(frf)
        f_r, a_r, q, _ = plot_frf.metrics(frf)
        note = path_note(frf["frequency_hz"], window["start_hz"], window["end_hz"])
        rows[n0] = (f_r, a_r, q, note)
    return tree, rows


def pct(a, b):
    return None if a is None or b is None else 100.0 * (a - b) / b


def fmt(x, spec):
    return "-" if x is None else format(x, spec)


HEADER = ["| n0 (N) | model | resonance (Hz) | peak amplitude (m) | Q | Δf vs conforming | "
          "ΔA vs conforming | ΔQ vs conforming | path |",
          "|---|---|---|---|---|---|---|---|---|"]


SHARED = ["model", "cyclic", "reduction", "contact"]


def same_model_as_m1(mode):
    """Where <mode>_<variant>.toml differs from m1_<variant>.toml in a table that defines the model
    ([model], [cyclic], [reduction], [[contact]]): every mode must use the same models."""
    import tomllib
    problems = []
    for v in VARIANTS:
        paths = [os.path.join(ROOT, "cases", "paper", f"{m}_{v}.toml") for m in ("m1", mode)]
        if mode == "m1" or not all(os.path.exists(p) for p in paths):
            continue
        m1, other = (tomllib.load(open(p, "rb")) for p in paths)
        problems += [f"cases/paper/{mode}_{v}.toml: [{key}] differs from m1_{v}.toml"
                     for key in SHARED if m1.get(key) != other.get(key)]
    return problems


def run_mode(mode, out_dir, skip_solve, harmonics):
    """Solves (unless `skip_solve`) and loads the variants of `mode`: ({variant: tree},
    {variant: {n0: (f_r, A_r, Q)}})."""
    trees, tables = {}, {}
    for v in VARIANTS:
        case = os.path.join("cases", "paper", f"{mode}_{v}.toml")
        if not os.path.exists(os.path.join(ROOT, case)):
            continue
        out = os.path.join(out_dir, f"{mode}_{v}.h5")
        if not skip_solve:
            solve(case, out, harmonics)
        if os.path.exists(out):
            trees[v], tables[v] = table_of(out)
    return trees, tables


def compare(mode, tables):
    """The comparison.md rows of one mode and the SAMA-vs-conforming failures (the acceptance): a
    difference beyond the tolerance, or a conforming or SAMA path that stops inside the window."""
    lines, failures = [], []
    worst = {}
    for n0, (f_c, a_c, q_c, note_c) in sorted(tables["conforming"].items()):
        for v in VARIANTS:
            if v not in tables or n0 not in tables[v]:
                continue
            f, a, q, note = tables[v][n0]
            df, da, dq = pct(f, f_c), pct(a, a_c), pct(q, q_c)
            lines.append(f"| {n0:g} | {v} | {f:.3f} | {a:.4e} | {fmt(q, '.1f')} | "
                         f"{fmt(df, '+.3f')} % | {fmt(da, '+.2f')} % | {fmt(dq, '+.2f')} % | "
                         f"{note} |")
            if v != "conforming":
                w = worst.setdefault(v, [0.0, 0.0])
                w[0], w[1] = max(w[0], abs(df)), max(w[1], abs(da))
            if v != "nonconforming":
                continue
            if abs(df) > 100 * FREQ_TOL or abs(da) > 100 * AMP_TOL:
                failures.append(f"{mode} n0 = {n0:g}: Δf {df:+.3f} %, ΔA {da:+.2f} %")
            for which, why in (("conforming", note_c), ("nonconforming", note)):
                if why.startswith("stops"):
                    failures.append(f"{mode} n0 = {n0:g}: the {which} path {why}, not compared")
    summary = [f"{v}: max |Δf| {w[0]:.3f} %, max |ΔA| {w[1]:.2f} %" for v, w in worst.items()]
    verdict = "not all preloads" if failures else "every preload"
    head = [f"## {MODES.get(mode, mode)}", "",
            f"SAMA vs conforming: {verdict} within 0.5 % (resonance) / 3 % (amplitude); "
            + "; ".join(summary), ""]
    return head + HEADER + lines + [""], failures


def plot_mode(plt, mode, trees, tables, out_dir):
    """FRFs per variant, the three models at n0 = 113 N and the performance curves of `mode`."""
    labels = [v for v in VARIANTS if v in trees]
    title = MODES.get(mode, mode)
    for v in labels:
        plot_frf.plot_file(plt, trees[v], os.path.join(out_dir, f"{mode}_{v}_frf.png"),
                           f"{title}: {v}", None)
    ref = [{"frf": [f for f in trees[v]["frf"] if plot_frf.sweep_value(f)[1] == 113.0]}
           for v in labels]
    plot_frf.plot_compare(plt, ref, labels, os.path.join(out_dir, f"{mode}_frf_compare.png"), None)
    perf = [{"label": v, "parameter": "n0 (N)", "value": n0, "resonance_hz": f,
             "peak_amplitude": a, "q_factor": q}
            for v in labels for n0, (f, a, q, _) in sorted(tables[v].items())]
    plot_frf.plot_performance(plt, perf, labels, os.path.join(out_dir, f"{mode}_performance.png"))


def publish(out_dir, figures_dir, modes, table):
    """Copy the figures of `modes` and the comparison table to `figures_dir` (for the README)."""
    os.makedirs(figures_dir, exist_ok=True)
    names = [os.path.basename(table)]
    for mode in modes:
        names += [f"{mode}_frf_compare.png", f"{mode}_performance.png"]
        names += [f"{mode}_{v}_frf.png" for v in VARIANTS]
    for name in names:
        src = os.path.join(out_dir, name)
        if os.path.exists(src):
            shutil.copyfile(src, os.path.join(figures_dir, name))
    print(f"figures and table copied to {figures_dir}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--modes", nargs="+", default=list(MODES),
                        help="modes to run (default: m1 m2), e.g. --modes m2")
    parser.add_argument("--harmonics", type=int, default=None,
                        help="solve every case with this many harmonics (default: the cases' H = 1)")
    parser.add_argument("--skip-solve", action="store_true", help="reuse existing result files")
    parser.add_argument("--out", default=None, help="default: results/paper (results/paper_h<H>)")
    parser.add_argument("--figures", default=None,
                        help="where the README's copies of the PNGs and comparison.md go "
                             "(default: docs/paper, committed; docs/paper/h<H> with --harmonics)")
    args = parser.parse_args()
    harmonics = None if args.harmonics in (None, 1) else args.harmonics
    suffix = "" if harmonics is None else f"_h{harmonics}"
    if args.out is None:
        args.out = os.path.join(ROOT, "results", "paper" + suffix)
    if args.figures is None:
        args.figures = os.path.join(ROOT, "docs", "paper", *([f"h{harmonics}"] if harmonics else []))
    os.makedirs(args.out, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    title = "# SAMA paper §6.2 on the bundled sector (tools/validation/paper_comparison.py"
    title += ")" if harmonics is None else f" --harmonics {harmonics}; H = {harmonics})"
    lines = [title, ""]
    failures = []
    for mode in args.modes:
        failures += same_model_as_m1(mode)
        trees, tables = run_mode(mode, args.out, args.skip_solve, harmonics)
        if "conforming" not in tables:
            print(f"{mode}: no conforming results")
            failures.append(f"{mode}: no conforming results")
            continue
        rows, bad = compare(mode, tables)
        lines += rows
        failures += bad
        plot_mode(plt, mode, trees, tables, args.out)
    text = "\n".join(lines)
    print(text)
    # comparison.md holds every mode; a subset (--modes m2) goes to comparison_m2.md
    name = "comparison" + suffix
    name += "" if args.modes == list(MODES) else "_" + "_".join(args.modes)
    path = os.path.join(args.out, name + ".md")
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)
    publish(args.out, args.figures, args.modes, path)
    if failures:
        print("failed (SAMA vs conforming outside 0.5 % resonance / 3 % amplitude, a path that "
              "stops inside the window, or the modes' cases differ in their models):")
        print("\n".join("  " + x for x in failures))
        return 1
    print("SAMA vs conforming: every preload of every mode within 0.5 % (resonance) and 3 % "
          "(amplitude)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
