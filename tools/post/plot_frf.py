#!/usr/bin/env python3
"""Plot nlrom frequency responses: FRFs and the performance curves of the SAMA paper.

    python3 tools/post/plot_frf.py RESULT.h5 [RESULT2.h5 ...] --out DIR [--labels A B ...] [--dof R]
        [--log]

writes, into DIR (created if needed):
  <stem>_frf.png          per result file: first-harmonic amplitude vs frequency, one curve per
                          sweep value (the SAMA paper's Figs 19-20); points that Hill's method
                          marks unstable (`nlrom solve --stability`) as crosses; --log: logarithmic
                          amplitude axis
  frf_compare.png         with several files: all their curves in one plot, one line style per file
                          (Figs 21-22, 26-27: conforming vs non-conforming / misaligned)
  performance.png         when the files have a one-parameter sweep: resonance frequency, amplitude
                          at resonance and Q-factor vs the sweep value, one line per file
                          (Figs 23-25, 28-30)
and prints the table of those numbers. Only h5py, numpy and matplotlib (loading: nlrom_results.py).

Definitions (the same as `nlrom solve`'s summary, src/pipeline): the response DOF is the one with
the largest first-harmonic amplitude over the curve (or --dof R); the resonance is the point of
maximum first-harmonic amplitude of that DOF; the Q-factor is f_r / (f_2 - f_1), f_1 < f_r < f_2
the half-power frequencies where the amplitude crosses peak/sqrt(2), found by linear interpolation
along the path on each side of the peak (None when the curve does not drop that low on both sides).
"""

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import nlrom_results  # noqa: E402


def response_dof(frf, dof=None):
    """Index of the response DOF the metrics use: `dof` if given, else the DOF with the largest
    first-harmonic amplitude over the curve."""
    amp = frf["amplitude"]
    if dof is not None:
        if not 0 <= dof < amp.shape[1]:
            raise ValueError(f"response DOF {dof} out of range (the file has {amp.shape[1]})")
        return dof
    return int(np.unravel_index(np.argmax(amp), amp.shape)[1])


def half_power_crossing(freq, amp, start, step, level):
    """Walks from index `start` in direction `step` (+1/-1) until amp drops below `level`;
    returns the linearly interpolated frequency of the crossing, or None."""
    i = start
    while 0 <= i + step < len(amp):
        j = i + step
        if amp[j] < level:
            t = (amp[i] - level) / (amp[i] - amp[j])
            return freq[i] + t * (freq[j] - freq[i])
        i = j
    return None


def metrics(frf, dof=None):
    """(resonance frequency Hz, peak first-harmonic amplitude m, Q-factor or None, dof) of a curve."""
    r = response_dof(frf, dof)
    freq = np.asarray(frf["frequency_hz"], dtype=float)
    amp = np.asarray(frf["amplitude"][:, r], dtype=float)
    p = int(np.argmax(amp))
    level = amp[p] / math.sqrt(2.0)
    f1 = half_power_crossing(freq, amp, p, -1, level)
    f2 = half_power_crossing(freq, amp, p, +1, level)
    q = None
    if f1 is not None and f2 is not None and f2 > f1:
        q = freq[p] / (f2 - f1)
    return float(freq[p]), float(amp[p]), q, r


def sweep_label(frf):
    names = frf["attrs"].get("sweep_parameters", [])
    if isinstance(names, str):
        names = [names]
    return ", ".join(f"{n.split('.')[-1]} = {frf['attrs'][n]:g}" for n in names)


def sweep_value(frf):
    """The value of the (first) sweep parameter of a curve, or None without a sweep."""
    names = frf["attrs"].get("sweep_parameters", [])
    if isinstance(names, str):
        names = [names]
    return (names[0], float(frf["attrs"][names[0]])) if names else (None, None)


def segments(frf):
    """Slices of a curve's points between the jumps of its sweep (`/frf/<i>/jumps`): the points
    either side of a jump lie on different branches and are not joined by a line."""
    bounds = [0] + [int(j) for j in frf.get("jumps", [])] + [len(frf["frequency_hz"])]
    return [slice(a, b) for a, b in zip(bounds, bounds[1:])]


def unstable_points(frf):
    """Indices of the points Hill's method marks unstable (`/frf/<i>/stable` = 0; none without
    the stability data)."""
    stable = frf.get("stable")
    if stable is None:
        return np.array([], dtype=int)
    return np.flatnonzero(np.asarray(stable) == 0)


def plot_file(plt, tree, path, label, dof, log=False):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    marked = False
    for frf in tree["frf"]:
        if not len(frf["frequency_hz"]):
            continue
        r = response_dof(frf, dof)
        line = None
        for part in segments(frf):
            line, = ax.plot(frf["frequency_hz"][part], frf["amplitude"][part, r],
                            color=line.get_color() if line else None,
                            label=None if line else (sweep_label(frf) or label))
        bad = unstable_points(frf)
        if len(bad):
            ax.plot(np.asarray(frf["frequency_hz"])[bad], np.asarray(frf["amplitude"])[bad, r],
                    "x", color=line.get_color(), markersize=4,
                    label=None if marked else "unstable (Hill)")
            marked = True
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("first-harmonic amplitude (m)")
    ax.set_title(label)
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_compare(plt, trees, labels, path, dof):
    styles = ["-", "--", ":", "-."]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (tree, label) in enumerate(zip(trees, labels)):
        for i, frf in enumerate(tree["frf"]):
            if not len(frf["frequency_hz"]):
                continue
            r = response_dof(frf, dof)
            for n, part in enumerate(segments(frf)):
                ax.plot(frf["frequency_hz"][part], frf["amplitude"][part, r],
                        styles[k % len(styles)], color=colors[i % len(colors)],
                        label=None if n else f"{label} {sweep_label(frf)}")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("first-harmonic amplitude (m)")
    ax.legend(fontsize="x-small", ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_performance(plt, table, labels, path):
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    titles = ["resonance frequency (Hz)", "amplitude at resonance (m)", "Q-factor"]
    param = None
    for label in labels:
        rows = [row for row in table if row["label"] == label and row["value"] is not None]
        if not rows:
            continue
        param = rows[0]["parameter"]
        x = [row["value"] for row in rows]
        for ax, key in zip(axes, ["resonance_hz", "peak_amplitude", "q_factor"]):
            y = [row[key] if row[key] is not None else np.nan for row in rows]
            ax.plot(x, y, "o-", label=label)
    for ax, title in zip(axes, titles):
        ax.set_title(title)
        ax.set_xlabel(param or "sweep value")
        ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("files", nargs="+", help="nlrom results files (HDF5)")
    parser.add_argument("--out", default=".", help="directory for the PNG files (default: .)")
    parser.add_argument("--labels", nargs="+", help="one label per file (default: file stem)")
    parser.add_argument("--dof", type=int, help="response DOF index for the metrics and plots")
    parser.add_argument("--no-plots", action="store_true", help="only print the table")
    parser.add_argument("--log", action="store_true", help="logarithmic amplitude axis")
    args = parser.parse_args()
    labels = args.labels or [os.path.splitext(os.path.basename(f))[0] for f in args.files]
    if len(labels) != len(args.files):
        parser.error("give one --labels entry per file")
    trees = [nlrom_results.load(f) for f in args.files]
    table = []
    for tree, label in zip(trees, labels):
        for i, frf in enumerate(tree["frf"]):
            if not len(frf["frequency_hz"]):
                continue
            f_r, a_r, q, r = metrics(frf, args.dof)
            name, value = sweep_value(frf)
            table.append({"label": label, "frf": i, "parameter": name, "value": value,
                          "resonance_hz": f_r, "peak_amplitude": a_r, "q_factor": q, "dof": r})
    print(f"{'case':<28} {'frf':>3} {'sweep value':>12} {'resonance (Hz)':>15} "
          f"{'peak amplitude (m)':>19} {'Q-factor':>9}")
    for row in table:
        value = "-" if row["value"] is None else f"{row['value']:g}"
        q = "-" if row["q_factor"] is None else f"{row['q_factor']:.2f}"
        print(f"{row['label']:<28} {row['frf']:>3} {value:>12} {row['resonance_hz']:>15.4f} "
              f"{row['peak_amplitude']:>19.6e} {q:>9}")
    if args.no_plots:
        return 0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(args.out, exist_ok=True)
    written = []
    for tree, label, f in zip(trees, labels, args.files):
        path = os.path.join(args.out, os.path.splitext(os.path.basename(f))[0] + "_frf.png")
        plot_file(plt, tree, path, label, args.dof, args.log)
        written.append(path)
    if len(trees) > 1:
        path = os.path.join(args.out, "frf_compare.png")
        plot_compare(plt, trees, labels, path, args.dof)
        written.append(path)
    if any(row["value"] is not None for row in table):
        path = os.path.join(args.out, "performance.png")
        plot_performance(plt, table, labels, path)
        written.append(path)
    for path in written:
        print(f"plot: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
