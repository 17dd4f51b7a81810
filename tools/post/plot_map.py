#!/usr/bin/env python3
"""Stick–slip–separation map of a friction strip from an nlrom results file.

    python3 tools/post/plot_map.py RESULT.h5 [--strip NAME] [--map K] [--out DIR]

Reads (h5py only, through tools/post/nlrom_results.py) `/contact/<name>/map/<k>` written by
`nlrom solve` for a `[[strip]]` with `map = N` (docs/results-file.md) and draws, as Cigeroglu,
An & Menq (2007) Figs 4–8 and 14–15, the map over (position along the strip, phase angle of the excitation):
colour f/(μn) (+1 positive slip, −1 negative slip, in between stick), separation in grey, and the
exact transition angles of every point as black dots (the stick–slip boundaries). Writes
`map_<name>_<k>.png` into DIR.

Also checks the stored samples against the stored transitions (the state at τ_j is the state
entered at the last transition at or before τ_j) and prints, as JSON, the number of points, angles,
transitions and of samples that disagree (0 for a consistent file; a sample within 1e-9 rad of a
transition may be either state and is not counted).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import nlrom_results  # noqa: E402


def states_from_transitions(phase, angles, states, default):
    """The state at each τ in `phase` of a point with transitions (angles, states entered)."""
    if len(angles) == 0:
        return np.full(len(phase), default)
    order = np.argsort(angles)
    angles, states = np.asarray(angles)[order], np.asarray(states)[order]
    k = np.searchsorted(angles, phase, side="right") - 1  # last transition at or before τ
    return np.where(k >= 0, states[k], states[-1])


def check(m):
    """Samples of `state` that disagree with the transitions (away from a transition)."""
    phase, state = m["phase"], m["state"]
    off = m["transition_offsets"].astype(np.int64)
    ang, sta = m["transition_angles"], m["transition_states"]
    bad = 0
    for e in range(state.shape[0]):
        a, s = ang[off[e]:off[e + 1]], sta[off[e]:off[e + 1]]
        want = states_from_transitions(phase, a, s, state[e, 0])
        near = np.zeros(len(phase), dtype=bool)
        for t in a:
            d = np.abs((phase - t + np.pi) % (2 * np.pi) - np.pi)
            near |= d < 1e-9
        bad += int(np.sum((want != state[e]) & ~near))
    return bad


def plot(m, name, k, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    x, phase = m["position"], np.degrees(m["phase"])
    ratio = np.array(m["friction_ratio"], dtype=float)
    fig, ax = plt.subplots(figsize=(7, 5))
    mesh = ax.pcolormesh(x, phase, ratio.T, cmap="coolwarm", vmin=-1, vmax=1, shading="nearest")
    separated = np.ma.masked_where(m["state"].T != 2, np.ones_like(ratio.T))
    ax.pcolormesh(x, phase, separated, cmap=ListedColormap(["0.6"]), shading="nearest")
    off, ang = m["transition_offsets"].astype(np.int64), m["transition_angles"]
    xs = np.repeat(x, np.diff(off))
    ax.plot(xs, np.degrees(ang), "k.", ms=1.5, label="transition angles")
    fig.colorbar(mesh, ax=ax, label="f/(μn)")
    ax.set_xlabel("position along the strip (m)")
    ax.set_ylabel("phase angle of the excitation τ (deg)")
    ax.set_ylim(0, 360)
    freq = m["attrs"]["omega"] / (2 * np.pi)
    curve = m["attrs"].get("curve", k)
    ax.set_title(f"{name}, curve {curve}, {freq:.6g} Hz (grey: separated)")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    path = out / f"map_{name}_{k}.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results")
    ap.add_argument("--strip", help="strip name (default: the first with a map)")
    ap.add_argument("--map", type=int, default=0, help="the map k of the strip (default 0)")
    ap.add_argument("--out", default=".")
    args = ap.parse_args(argv)
    tree = nlrom_results.load(args.results)
    names = list(tree["contact"].get("attrs", {}).get("maps", []))
    if not names:
        raise SystemExit("the file has no stick–slip–separation maps (a [[strip]] with `map`)")
    name = args.strip or names[0]
    if name not in names:
        raise SystemExit(f"no map of strip {name!r}; the file has {names}")
    maps = tree["contact"][name]["map"]
    if str(args.map) not in maps:
        raise SystemExit(f"strip {name!r} has no map {args.map}; it has {sorted(maps)}")
    m = maps[str(args.map)]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = plot(m, name, args.map, out)
    report = {
        "png": str(path),
        "points": int(m["state"].shape[0]),
        "angles": int(m["state"].shape[1]),
        "transitions": int(len(m["transition_angles"])),
        "disagreeing_samples": check(m),
    }
    print(json.dumps(report))


if __name__ == "__main__":
    main()
