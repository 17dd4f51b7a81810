#!/usr/bin/env python3
"""Compare nonsmooth marches (`nlrom march --scheme moreau-jean | carpenter`) of one obstacle.

    python3 tools/post/plot_nonsmooth.py REF.h5 OTHER.h5 [...] [-o nonsmooth.png]
        [--obstacle NAME] [--labels A B ...]

The figures of Thorin et al. (ASME GT2018-75959, 2018, Figs 2-3 and 6-9): the gap g (the radial
displacement of a casing contact node up to its sign and initial gap), the temperature rise of the
node (with `[thermal]`) and the mean contact force over each step λ/h, for every file, overlaid.
The default obstacle is the one with the largest total impulse in REF.

Prints, for each further file, the relative L1 errors of eq. (19) against REF on the file's own
time grid: the gap and the temperature with REF interpolated linearly, the force as the sum of
REF's impulses in each step of the file divided by that step (impulses, not point values, so
that impacts compare across step sizes). JSON on stdout: {"label": {"gap": e, "temperature": e,
"force": e}}.
"""
import argparse
import json

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path, obstacle=None):
    with h5py.File(path, "r") as f:
        m = f["march"]
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in m["element_names"][:]]
        impulse = m["impulse"][:]
        i = names.index(obstacle) if obstacle else int(np.argmax(impulse.sum(axis=0)))
        out = {
            "name": names[i],
            "scheme": m.attrs["scheme"].decode() if isinstance(m.attrs["scheme"], bytes) else str(m.attrs["scheme"]),
            "time": m["time"][:],
            "gap": m["gap"][:, i],
            "impulse": impulse[:, i],
            "step": float(m.attrs["time_step"]),
            "temperature": None,
        }
        if "temperature" in m:
            node = int(names[i].rsplit(":", 1)[-1]) if ":" in names[i] else None
            tags = list(m["temperature_nodes"][:])
            if node in tags:
                out["temperature"] = m["temperature"][:, tags.index(node)]
    return out


def eta(a, ref):
    """Eq. (19): sum |a - ref| / sum |ref| on a common grid."""
    den = np.sum(np.abs(ref))
    return float(np.sum(np.abs(a - ref)) / den) if den > 0 else float("nan")


def errors(run, ref):
    t = run["time"]
    out = {"gap": eta(run["gap"], np.interp(t, ref["time"], ref["gap"]))}
    if run["temperature"] is not None and ref["temperature"] is not None:
        out["temperature"] = eta(run["temperature"], np.interp(t, ref["time"], ref["temperature"]))
    # Reference impulses summed over each step (t_{k-1}, t_k] of the run.
    cum = np.concatenate([[0.0], np.cumsum(ref["impulse"][1:])])
    at = np.interp(t, ref["time"], cum)
    ref_force = np.diff(at) / run["step"]
    out["force"] = eta(run["impulse"][1:] / run["step"], ref_force)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("-o", "--out", default="nonsmooth.png")
    ap.add_argument("--obstacle", default=None)
    ap.add_argument("--labels", nargs="*", default=None)
    args = ap.parse_args()
    ref = load(args.files[0], args.obstacle)
    runs = [ref] + [load(p, ref["name"]) for p in args.files[1:]]
    labels = args.labels or [f"{r['scheme']} h={r['step']:.2e}" for r in runs]
    thermal = ref["temperature"] is not None
    fig, axes = plt.subplots(3 if thermal else 2, 1, figsize=(9, 8), sharex=True)
    for r, lab in zip(runs, labels):
        axes[0].plot(r["time"], 1e6 * r["gap"], label=lab)
        axes[-1].step(r["time"][1:], r["impulse"][1:] / r["step"], where="pre", label=lab)
        if thermal and r["temperature"] is not None:
            axes[1].plot(r["time"], r["temperature"], label=lab)
    axes[0].set_ylabel("gap (µm)")
    if thermal:
        axes[1].set_ylabel("θ rise (K)")
    axes[-1].set_ylabel("λ/h (N)")
    axes[-1].set_xlabel("t (s)")
    axes[0].set_title(f"obstacle {ref['name']}")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    report = {lab: errors(r, ref) for r, lab in zip(runs[1:], labels[1:])}
    print(json.dumps(report))


if __name__ == "__main__":
    main()
