#!/usr/bin/env python3
"""Load nlrom HDF5 files (results and ROM) into plain Python dicts of numpy arrays.

Only h5py and numpy: the files need no custom HDF5 code (docs/results-file.md documents the layout
dataset by dataset). Complex datasets come back as complex128, compound datasets as numpy
structured arrays, strings as str.

    import sys; sys.path.insert(0, "tools/post")
    import nlrom_results
    r = nlrom_results.load("results/shroud.h5")
    r["attrs"]["title"]                       # root attributes
    frf = r["frf"][0]                         # sweep point 0 (a list, in sweep order)
    frf["frequency_hz"], frf["amplitude"]     # [P], [P, R]
    frf["harmonics"]                          # complex128 [P, R, H+1]
    frf["units"]["omega"]                     # "rad/s"
    r["contact"]["shroud"]["state_fractions"]["0"]   # [P, 3]: stick, slip, separation
    r["march"]["response"]                    # [T, R] (None without a march)

Command line: `python3 tools/post/nlrom_results.py FILE.h5 [--plot FRF.png]` prints a summary (and plots
the first-harmonic amplitude of every FRF against the frequency).
"""

import argparse
import sys

import h5py
import numpy as np


def plain(value):
    """An attribute value as a Python str / number / numpy array."""
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.ndarray) and value.dtype.kind in "OS":
        return [plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        return value.item()
    return value


def read_dataset(ds):
    """The values of a dataset as a numpy array (strings as a list of str)."""
    if h5py.check_string_dtype(ds.dtype) is not None:
        return [plain(v) for v in ds.asstr()[()].tolist()] if ds.shape else ds.asstr()[()]
    return ds[()]


def read_group(group):
    """A group as a dict: datasets as arrays, sub-groups as dicts, plus "attrs" (the group's
    attributes), "units" and "descriptions" (per dataset)."""
    out = {"attrs": {k: plain(v) for k, v in group.attrs.items()}, "units": {}, "descriptions": {}}
    for name, obj in group.items():
        if isinstance(obj, h5py.Group):
            out[name] = read_group(obj)
        else:
            out[name] = read_dataset(obj)
            out["units"][name] = plain(obj.attrs.get("unit", ""))
            out["descriptions"][name] = plain(obj.attrs.get("description", ""))
    return out


def load(path):
    """The whole file as a dict. For a results file, "frf" is a list in sweep order and "contact"
    and "march" are present (None / {} when absent)."""
    with h5py.File(path, "r") as f:
        tree = read_group(f)
    if tree["attrs"].get("program") != "nlrom":
        raise ValueError(f"{path}: not an nlrom file (no root attribute program = 'nlrom')")
    if tree["attrs"].get("file_kind") == "results":
        frf = tree.get("frf", {})
        tree["frf"] = [frf[k] for k in sorted((k for k in frf if k.isdigit()), key=int)]
        tree.setdefault("contact", {})
        tree.setdefault("march", None)
    return tree


def summary(tree):
    """A few lines describing a loaded file."""
    attrs = tree["attrs"]
    lines = [f"nlrom {attrs.get('file_kind')} file, version {attrs.get('version')}, "
             f"created {attrs.get('created')}: {attrs.get('title')!r}"]
    for i, frf in enumerate(tree.get("frf", [])):
        amp = frf["amplitude"]
        sweep = {k: frf["attrs"][k] for k in frf["attrs"].get("sweep_parameters", [])}
        if amp.size:
            p, r = np.unravel_index(np.argmax(amp), amp.shape)
            lines.append(f"frf {i} {sweep}: {amp.shape[0]} points, max amplitude {amp[p, r]:.4g} m "
                         f"at {frf['frequency_hz'][p]:.6g} Hz (response DOF {r})")
        else:
            lines.append(f"frf {i} {sweep}: no points")
    for name, c in tree.get("contact", {}).items():
        if isinstance(c, dict) and "pairs" in c:
            lines.append(f"contact {name}: {c['attrs'].get('model')}, {len(c['pairs'])} elements")
    march = tree.get("march")
    if march:
        lines.append(f"march: {march['attrs'].get('scheme')}, {len(march['time'])} instants, "
                     f"{march['attrs'].get('wall_seconds'):.3g} s")
    return "\n".join(lines)


def plot(tree, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, frf in enumerate(tree["frf"]):
        sweep = ", ".join(f"{k}={frf['attrs'][k]:g}" for k in frf["attrs"].get("sweep_parameters", []))
        for r in range(frf["amplitude"].shape[1]):
            ax.semilogy(frf["frequency_hz"], frf["amplitude"][:, r], label=f"{i} {sweep} dof {r}")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("first-harmonic amplitude (m)")
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(out, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("file")
    parser.add_argument("--plot", metavar="PNG", help="plot the FRF amplitudes to this file")
    args = parser.parse_args()
    tree = load(args.file)
    print(summary(tree))
    if args.plot:
        plot(tree, args.plot)
        print(f"plot: {args.plot}")


if __name__ == "__main__":
    sys.exit(main())
