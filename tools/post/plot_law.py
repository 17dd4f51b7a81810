#!/usr/bin/env python3
"""Plot the hysteresis loop written by `nlrom law --loop LOOP.csv`.

    python3 tools/post/plot_law.py LOOP.csv [-o loop.png] [--title TEXT]

Left: the friction force f against the tangential displacement u, coloured by state
(stick, +slip, -slip, separation). Right: u, v, f and the normal force n over the period τ.
Prints the loop area (the energy per cycle ∮ f du, trapezoidal) on stdout.
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STATES = {0: ("stick", "tab:blue"), 1: ("+slip", "tab:red"), -1: ("-slip", "tab:orange"),
          2: ("separation", "tab:gray")}


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    cols = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    cols["state"] = cols["state"].astype(int)
    return cols


def loop_area(c):
    u = np.append(c["u"], c["u"][0])
    f = np.append(c["f"], c["f"][0])
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--out", default="law_loop.png")
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    c = load(a.csv)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    u = np.append(c["u"], c["u"][0])
    f = np.append(c["f"], c["f"][0])
    ax1.plot(u, f, color="k", lw=0.6)
    for code, (name, color) in STATES.items():
        m = c["state"] == code
        if m.any():
            ax1.plot(c["u"][m], c["f"][m], ".", ms=3, color=color, label=name)
    ax1.set_xlabel("u (m)")
    ax1.set_ylabel("f (N)")
    ax1.legend(loc="best", fontsize=8)
    ax1.grid(alpha=0.3)
    t = np.degrees(c["tau_rad"])
    ax2.plot(t, c["f"], label="f (N)")
    ax2.plot(t, c["n"], label="n (N)")
    ax3 = ax2.twinx()
    ax3.plot(t, c["u"], "--", color="tab:green", label="u (m)")
    ax3.plot(t, c["v"], ":", color="tab:purple", label="v (m)")
    ax2.set_xlabel("τ (deg)")
    ax2.set_ylabel("force (N)")
    ax3.set_ylabel("displacement (m)")
    h1, l1 = ax2.get_legend_handles_labels()
    h2, l2 = ax3.get_legend_handles_labels()
    ax2.legend(h1 + h2, l1 + l2, loc="best", fontsize=8)
    ax2.grid(alpha=0.3)
    if a.title:
        fig.suptitle(a.title)
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"{loop_area(c):.12e}")


if __name__ == "__main__":
    main()
