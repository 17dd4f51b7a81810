#!/usr/bin/env python3
"""Error and residual penetration of the Moreau-Jean march against the time step.

    python3 tools/validation/step_study.py [CASE] [--steps H ...] [--reference H]
        [--reference-scheme moreau-jean|carpenter] [--periods P] [--modes M] [--gap G]
        [--nlrom PATH] [--plot study.png] [--keep DIR]

The convergence study of Thorin et al. (ASME GT2018-75959, 2018, Fig. 5, and Fig. 4 for the
penetration): CASE (default `cases/blade_casing.toml`) is marched with `nlrom march --scheme
moreau-jean` at each step H and at the reference step, for P excitation periods; with `--modes M`
on its Craig-Bampton model (`[reduction] interface_modes = M`, the contact nodes as masters),
with `--gap G` from an initial gap G (m) at every casing instead of the case's. For every step:
the relative L1 errors of eq. (19) against the reference at the contact node with the largest
total impulse (the gap, i.e. the radial displacement up to sign and initial gap, its temperature
and its contact force, as `tools/post/plot_nonsmooth.py` computes them), the largest
penetration max(0, -g) over nodes and time, and the march's wall time; then the observed order
of each error, the least-squares slope of log(error) against log(h). With `--reference-scheme
carpenter` the reference is Carpenter's explicit scheme at the reference step (below its
stability limit 2/omega_max, which `nlrom march --json` reports): Moreau-Jean at that same step
and at larger ones against it (the paper's "the two schemes agree").

JSON on stdout: {"steps": [...], "reference": h, "reference_scheme": s, "node": name,
"errors": {"gap": [...], "temperature": [...], "force": [...]}, "penetration": [...],
"reference_penetration": p, "reference_stability_limit": 2/omega_max (s, carpenter, else null),
"order": {...}, "wall_seconds": [...]}.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "post"))
from plot_nonsmooth import errors, load  # noqa: E402


def case_text(path, step, periods, modes, gap, scheme="moreau-jean"):
    """The case at `path` with the step, the period count, the scheme, optionally a
    `[reduction]` and a uniform initial gap; relative paths made absolute."""
    text = open(path).read()
    base = os.path.dirname(os.path.abspath(path))
    text = re.sub(
        r'^(\s*mesh\s*=\s*")([^"]+)"',
        lambda m: m.group(1) + os.path.normpath(os.path.join(base, m.group(2))) + '"',
        text,
        flags=re.M,
    )
    text = re.sub(r"^\s*(time_step_s|periods|scheme)\s*=.*\n", "", text, flags=re.M)
    text = text.replace(
        "[march]\n",
        f'[march]\ntime_step_s = {step!r}\nperiods = {periods}\nscheme = "{scheme}"\n',
    )
    if gap is not None:
        text = re.sub(r"^\s*(gap|radius)\s*=.*\n", f"gap = {gap!r}\n", text, flags=re.M)
    if modes is not None:
        text += f"\n[reduction]\ninterface_modes = {modes}\n"
    return text


def march(nlrom, text, name, work):
    """Writes the case `text` to WORK/NAME.toml and marches it into WORK/NAME.h5: the results
    path and the JSON report of `nlrom march`."""
    path = os.path.join(work, name + ".toml")
    with open(path, "w") as f:
        f.write(text)
    out = os.path.join(work, name + ".h5")
    proc = subprocess.run(
        [nlrom, "march", path, "-o", out, "--json", "-q"], capture_output=True, text=True
    )
    if proc.returncode != 0:
        sys.exit(f"nlrom march failed on {path}: {proc.stderr}")
    return out, json.loads(proc.stdout)


def remove_work(work, keep):
    """Removes the temporary folder `work` of the cases and results unless they are kept."""
    if not keep:
        shutil.rmtree(work)


def run(nlrom, case, step, args, work, scheme="moreau-jean"):
    text = case_text(case, step, args.periods, args.modes, args.gap, scheme)
    return march(nlrom, text, f"{scheme}_h{step:.3e}", work)


def order(hs, es):
    """Least-squares slope of log(e) against log(h) over the positive errors."""
    pts = [(np.log(h), np.log(e)) for h, e in zip(hs, es) if e > 0]
    if len(pts) < 2:
        return float("nan")
    x, y = np.array(pts).T
    return float(np.polyfit(x, y, 1)[0])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default=os.path.join(ROOT, "cases", "blade_casing.toml"))
    ap.add_argument("--steps", nargs="+", type=float, default=[1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6])
    ap.add_argument("--reference", type=float, default=5e-7)
    ap.add_argument("--reference-scheme", choices=["moreau-jean", "carpenter"], default="moreau-jean")
    ap.add_argument("--periods", type=int, default=1)
    ap.add_argument("--modes", type=int, default=None)
    ap.add_argument("--gap", type=float, default=None)
    ap.add_argument("--nlrom", default=os.path.join(ROOT, "target", "release", "nlrom"))
    ap.add_argument("--plot", default=None)
    ap.add_argument("--keep", default=None, help="keep the case and result files in this folder")
    args = ap.parse_args()
    work = args.keep or tempfile.mkdtemp(prefix="nlrom_step_study_")
    os.makedirs(work, exist_ok=True)
    ref_path, ref_report = run(
        args.nlrom, args.case, args.reference, args, work, args.reference_scheme
    )
    ref = load(ref_path)
    steps = sorted(args.steps, reverse=True)
    result = {
        "steps": steps,
        "reference": args.reference,
        "reference_scheme": args.reference_scheme,
        "node": ref["name"],
        "errors": {"gap": [], "temperature": [], "force": []},
        "penetration": [],
        "reference_penetration": ref_report["max_penetration_m"],
        "reference_stability_limit": ref_report.get("stability_limit_s"),
        "wall_seconds": [],
    }
    for h in steps:
        path, report = run(args.nlrom, args.case, h, args, work)
        e = errors(load(path, ref["name"]), ref)
        for key in result["errors"]:
            result["errors"][key].append(e.get(key, float("nan")))
        result["penetration"].append(report["max_penetration_m"])
        result["wall_seconds"].append(report["march_wall_seconds"])
    result["order"] = {k: order(steps, v) for k, v in result["errors"].items()}
    result["order"]["penetration"] = order(steps, result["penetration"])
    print(json.dumps(result))
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
        for key, style in [("gap", "-o"), ("force", "--s"), ("temperature", ":^")]:
            a.loglog(steps, result["errors"][key], style, label=key)
        a.set_xlabel("h (s)")
        a.set_ylabel("error (eq. 19)")
        a.set_title(f"node {ref['name']}, reference h = {args.reference:.1e} s")
        a.legend()
        b.loglog(steps, result["penetration"], "-o")
        b.set_xlabel("h (s)")
        b.set_ylabel("max penetration (m)")
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
    remove_work(work, args.keep)


if __name__ == "__main__":
    main()
