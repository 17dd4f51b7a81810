#!/usr/bin/env python3
"""The blade-casing march with and without the thermal coupling (the expansion set to zero).

    python3 tools/validation/thermal_coupling.py [CASE] [--step H] [--periods P] [--modes M]
        [--nlrom PATH] [--plot coupling.png] [--keep DIR]

The comparison of Thorin et al. (ASME GT2018-75959, 2018, Figs 6-7): CASE (default
`cases/blade_casing.toml`, which needs `[thermal]`) is marched by `nlrom march --scheme
moreau-jean` at step H for P excitation periods (with `--modes M` on its Craig-Bampton model,
the contact nodes as masters), once as it is and once with `expansion = 0`: the same load and
frictional heating, but the temperature no longer expands the blade. For each run and each
contact node (in the order of `/march/element_names`): the contact force λ/h of the last step
(N), the temperature rise at the end (K), the largest contact force over the run (N) and the
largest penetration max(0, -g) (m).

JSON on stdout: {"nodes": [...], "step": h, "periods": P, "coupled": {"force_end": [...],
"temperature_end": [...], "force_max": [...], "penetration_max": [...]}, "uncoupled": {...}}.
`--plot` draws the contact force and the temperature of the node with the largest end force
over time, and every node's end force and temperature, for both runs.
"""
import argparse
import json
import os
import re
import sys
import tempfile

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from step_study import case_text, march, remove_work  # noqa: E402


def uncoupled_text(text):
    """The case text with the `[thermal]` expansion coefficient set to zero."""
    out, n = re.subn(r"^(\s*expansion\s*=\s*)[^#\n]*", r"\g<1>0.0 ", text, flags=re.M)
    if n != 1:
        sys.exit("thermal_coupling.py: the case needs exactly one `expansion` key ([thermal])")
    return out


def node_table(path):
    """Per contact node: names, λ/h over time, temperature rise over time (None without
    `[thermal]` output for the node), the time."""
    with h5py.File(path, "r") as f:
        m = f["march"]
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in m["element_names"][:]]
        step = float(m.attrs["time_step"])
        force = m["impulse"][:] / step
        gap = m["gap"][:]
        time = m["time"][:]
        temps = np.full(force.shape, np.nan)
        if "temperature" in m:
            tags = list(m["temperature_nodes"][:])
            theta = m["temperature"][:]
            for i, name in enumerate(names):
                tag = int(name.rsplit(":", 1)[-1]) if ":" in name else None
                if tag in tags:
                    temps[:, i] = theta[:, tags.index(tag)]
    return {"names": names, "time": time, "force": force, "temperature": temps, "gap": gap}


def summary(table):
    return {
        "force_end": table["force"][-1].tolist(),
        "temperature_end": table["temperature"][-1].tolist(),
        "force_max": table["force"].max(axis=0).tolist(),
        "penetration_max": np.maximum(0.0, -table["gap"]).max(axis=0).tolist(),
    }


def plot(runs, out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    coupled = runs["coupled"]
    node = int(np.argmax(coupled["force"][-1]))
    fig, axes = plt.subplots(2, 2, figsize=(11, 7))
    for label, t in runs.items():
        axes[0, 0].plot(t["time"][1:], t["force"][1:, node], label=label)
        axes[1, 0].plot(t["time"], t["temperature"][:, node], label=label)
        x = np.arange(len(t["names"]))
        axes[0, 1].plot(x, t["force"][-1], "o-", label=label)
        axes[1, 1].plot(x, t["temperature"][-1], "o-", label=label)
    axes[0, 0].set_ylabel(f"λ/h at {coupled['names'][node]} (N)")
    axes[1, 0].set_ylabel("θ rise (K)")
    axes[1, 0].set_xlabel("t (s)")
    axes[0, 1].set_ylabel("λ/h at the end (N)")
    axes[1, 1].set_ylabel("θ rise at the end (K)")
    names = coupled["names"]
    axes[1, 1].set_xticks(np.arange(len(names)), names, rotation=30, fontsize=8)
    axes[0, 1].set_xticks(np.arange(len(names)), [""] * len(names))
    axes[0, 0].legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default=os.path.join(ROOT, "cases", "blade_casing.toml"))
    ap.add_argument("--step", type=float, default=1e-5)
    ap.add_argument("--periods", type=int, default=5)
    ap.add_argument("--modes", type=int, default=None)
    ap.add_argument("--nlrom", default=os.path.join(ROOT, "target", "release", "nlrom"))
    ap.add_argument("--plot", default=None)
    ap.add_argument("--keep", default=None, help="keep the case and result files in this folder")
    args = ap.parse_args()
    if not args.step > 0:
        sys.exit(f"thermal_coupling.py: --step must be positive, got {args.step}")
    work = args.keep or tempfile.mkdtemp(prefix="nlrom_thermal_coupling_")
    os.makedirs(work, exist_ok=True)
    text = case_text(args.case, args.step, args.periods, args.modes, None)
    runs = {}
    for label, case in [("coupled", text), ("uncoupled", uncoupled_text(text))]:
        path, _ = march(args.nlrom, case, label, work)
        runs[label] = node_table(path)
    result = {
        "nodes": runs["coupled"]["names"],
        "step": args.step,
        "periods": args.periods,
    }
    result.update({label: summary(t) for label, t in runs.items()})
    print(json.dumps(result))
    if args.plot:
        plot(runs, args.plot)
    remove_work(work, args.keep)


if __name__ == "__main__":
    main()
