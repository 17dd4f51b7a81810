#!/usr/bin/env python3
"""Contact plots from an nlrom results file: hysteresis loops and a contact-state map.

    python3 tools/post/plot_contact.py RESULT.h5 [--interface NAME] [--curve I] [--point P]
                                  [--pairs E1,E2,...] [--out DIR]

Reads (h5py only, through tools/post/nlrom_results.py) `/contact/<name>/elements/<i>/` of a sector
case solved by `nlrom solve|run` (docs/results-file.md):
- loops.png: the tangential hysteresis loops f1(u1) of chosen elements (default: the four with the
  largest dissipated energy) at the point where the loops were recorded (`loop_point`, the
  resonance peak of the curve), with the energy per cycle of each element in the legend;
- state_map.png: the contact face seen along the mean normal, one marker per contact node at its
  virtual node t_v, coloured by the weighted slip fraction of its elements (SAMA eq. 29 weights)
  at point --point (default: `loop_point`), with separated nodes drawn as crosses.
Also prints, per plotted element, the dissipated energy stored by nlrom next to the loop area
∮ f1 du1 + ∮ f2 du2 computed here from the samples (they agree for a converged loop).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import nlrom_results  # noqa: E402


def loop_area(u: np.ndarray, f: np.ndarray) -> float:
    """∮ f du over one closed periodic loop of samples (trapezoidal, wrapping around)."""
    du = np.roll(u, -1) - u
    return float(np.sum(0.5 * (f + np.roll(f, -1)) * du))


def element_curve(tree: dict, interface: str | None, curve: int):
    contacts = {k: v for k, v in tree["contact"].items() if isinstance(v, dict) and "pairs" in v}
    if not contacts:
        raise SystemExit("the file has no contact interfaces (a sector case solved by nlrom)")
    name = interface or next(iter(contacts))
    if name not in contacts:
        raise SystemExit(f"no interface {name!r}; the file has {sorted(contacts)}")
    c = contacts[name]
    elements = c.get("elements", {})
    if str(curve) not in elements:
        raise SystemExit(f"interface {name!r} has no per-element data for curve {curve} "
                         f"(written by nlrom solve for sector cases)")
    return name, c, elements[str(curve)]


def plot_loops(c: dict, d: dict, pairs: list[int] | None, out: Path, title: str) -> list[str]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    point = int(d["attrs"]["loop_point"])
    energy = d["dissipated_energy"][point]
    chosen = pairs if pairs else list(np.argsort(energy)[::-1][:4])
    u, f = d["loop_u"], d["loop_force"]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    lines = []
    for e in chosen:
        area = loop_area(u[e, :, 0], f[e, :, 0]) + loop_area(u[e, :, 1], f[e, :, 1])
        node = int(c["pairs"]["contact_node"][e])
        uu = np.append(u[e, :, 0], u[e, 0, 0])
        ff = np.append(f[e, :, 0], f[e, 0, 0])
        ax.plot(uu * 1e6, ff, marker=".", ms=3, label=f"element {e} (node {node}): W = {energy[e]:.3g} J")
        lines.append(f"element {e} (contact node {node}): dissipated energy {energy[e]:.6g} J, "
                     f"loop area {area:.6g} J")
    ax.set_xlabel("tangential relative displacement u1 (µm)")
    ax.set_ylabel("tangential force f1 (N)")
    ax.set_title(title, fontsize="medium")
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return lines


def node_states(c: dict, d: dict, point: int):
    """Per contact node: position (its virtual node), weighted slip and separation fractions."""
    nodes = c["pairs"]["contact_node"]
    w = c["weights"]
    frac = d["fractions"][point]  # [E, 3]
    out = {}
    for e, node in enumerate(nodes):
        slot = out.setdefault(int(node), [c["virtual_points"][e], 0.0, 0.0, 0.0])
        slot[1] += w[e] * frac[e, 1]
        slot[2] += w[e] * frac[e, 2]
        slot[3] += w[e]
    xyz = np.array([v[0] for v in out.values()])
    slip = np.array([v[1] / v[3] for v in out.values()])
    sep = np.array([v[2] / v[3] for v in out.values()])
    return xyz, slip, sep


def plot_state_map(c: dict, d: dict, point: int, out: Path, title: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    xyz, slip, sep = node_states(c, d, point)
    frames = c["frames"]  # [E, 3, 3]: rows t1, t2, n
    t1 = frames[:, 0, :].mean(axis=0)
    n = frames[:, 2, :].mean(axis=0)
    n /= np.linalg.norm(n)
    t1 -= n * (t1 @ n)
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(n, t1)
    a, b = (xyz - xyz.mean(axis=0)) @ t1, (xyz - xyz.mean(axis=0)) @ t2
    fig, ax = plt.subplots(figsize=(6.5, 5))
    sc = ax.scatter(a * 1e3, b * 1e3, c=slip, cmap="viridis", vmin=0.0, vmax=1.0, s=60,
                    edgecolors="k", linewidths=0.4)
    open_ = sep > 0.5
    if open_.any():
        ax.scatter(a[open_] * 1e3, b[open_] * 1e3, marker="x", c="red", s=50,
                   label="separated > half the period")
        ax.legend(fontsize="small")
    fig.colorbar(sc, ax=ax, label="fraction of the period in slip")
    ax.set_xlabel("along t1 (mm)")
    ax.set_ylabel("along t2 (mm)")
    ax.set_aspect("equal")
    ax.set_title(title, fontsize="medium")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file")
    ap.add_argument("--interface")
    ap.add_argument("--curve", type=int, default=0, help="the FRF (sweep point) index")
    ap.add_argument("--point", type=int, help="point of the state map (default: the loops' point)")
    ap.add_argument("--pairs", help="comma-separated element indices for the loops")
    ap.add_argument("--out", default=".", help="folder for loops.png and state_map.png")
    a = ap.parse_args(argv)
    tree = nlrom_results.load(a.file)
    name, c, d = element_curve(tree, a.interface, a.curve)
    frf = tree["frf"][a.curve]
    point = int(d["attrs"]["loop_point"]) if a.point is None else a.point
    if not 0 <= point < len(frf["frequency_hz"]):
        raise SystemExit(f"--point {point}: the curve has {len(frf['frequency_hz'])} points")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    pairs = [int(x) for x in a.pairs.split(",")] if a.pairs else None
    hz = frf["frequency_hz"][int(d["attrs"]["loop_point"])]
    for line in plot_loops(c, d, pairs, out / "loops.png",
                           f"{name}: hysteresis loops at {hz:.3f} Hz (curve {a.curve})"):
        print(line)
    plot_state_map(c, d, point, out / "state_map.png",
                   f"{name}: slip fraction at {frf['frequency_hz'][point]:.3f} Hz (curve {a.curve})")
    print(f"wrote {out / 'loops.png'} and {out / 'state_map.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
