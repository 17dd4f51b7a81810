#!/usr/bin/env python3
"""Plot the /march/ group of nlrom results files (`nlrom march CASE -o RESULT.h5`).

    python3 tools/post/plot_march.py RESULT.h5 [MORE.h5 ...] [-o march.png] [--last-period]

One figure with four panels, every file overlaid (label = its `scheme` attribute):
  1. the reported DOF against time;
  2. hysteresis loops f_t against u_t of every contact element (Gastaldi & Berruti 2018, Fig. 6);
  3. normal forces f_n against time (Fig. 7b);
  4. histogram of corrector iterations per step (Fig. 5).
The contact states (0 separated, 1 stick, 2 slip +, 3 slip -) of the first file are printed as a
sequence of changes for the last period.
"""
import argparse

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STATE = {0: "sep", 1: "stick", 2: "slip+", 3: "slip-"}


def read(path):
    with h5py.File(path, "r") as f:
        g = f["march"]
        data = {k: g[k][()] for k in g.keys()}
        data["attrs"] = dict(g.attrs)
    for key in ("response_names", "element_names"):
        data[key] = [s.decode() if isinstance(s, bytes) else str(s) for s in data[key]]
    return data


def last_period_mask(d):
    omega = d["attrs"]["omega"]
    period = 2 * np.pi / omega
    t = d["time"]
    return t >= t[-1] - period * (1 + 1e-9)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("-o", "--output", default="march.png")
    ap.add_argument("--last-period", action="store_true", help="plot only the last excitation period")
    a = ap.parse_args()
    runs = [(p, read(p)) for p in a.files]
    fig, ax = plt.subplots(2, 2, figsize=(13, 9))
    for path, d in runs:
        label = d["attrs"].get("scheme", path)
        m = last_period_mask(d) if a.last_period else slice(None)
        t = d["time"][m] * 1e3
        for j, name in enumerate(d["response_names"]):
            ax[0, 0].plot(t, d["response"][m, j], label=f"{label}: {name}")
        for e, name in enumerate(d["element_names"]):
            ax[0, 1].plot(d["contact_displacement"][m, e, 0] * 1e6, d["contact_force"][m, e, 0], label=f"{label}: {name}")
            ax[1, 0].plot(t, d["contact_force"][m, e, 1], label=f"{label}: {name}")
        hist = d["iteration_histogram"]
        ax[1, 1].bar(np.arange(len(hist)) + 0.1 * len(ax[1, 1].patches) / max(len(hist), 1), hist, width=0.4, alpha=0.6, label=label)
    ax[0, 0].set(xlabel="time (ms)", ylabel="response (m or rad)", title="reported DOF")
    ax[0, 1].set(xlabel="u_t (µm)", ylabel="f_t (N)", title="hysteresis loops")
    ax[1, 0].set(xlabel="time (ms)", ylabel="f_n (N)", title="normal forces")
    ax[1, 1].set(xlabel="iterations per step", ylabel="steps", title="iterations per step (Fig. 5)")
    for x in ax.flat:
        x.legend(fontsize=6)
        x.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.output, dpi=120)
    path, d = runs[0]
    m = last_period_mask(d)
    states = d["contact_state"][m]
    seq = [tuple(states[0])]
    for s in states[1:]:
        if tuple(s) != seq[-1]:
            seq.append(tuple(s))
    names = d["element_names"]
    print(f"{path}: {len(seq) - 1} state changes in the last period")
    for s in seq:
        print("  " + ", ".join(f"{n}={STATE[int(c)]}" for n, c in zip(names, s)))
    print(f"wrote {a.output}")


if __name__ == "__main__":
    main()
