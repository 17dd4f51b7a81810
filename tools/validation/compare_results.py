#!/usr/bin/env python3
"""Compare two nlrom HDF5 files (results or ROM) dataset by dataset.

    python3 tools/validation/compare_results.py A.h5 B.h5 [--rtol 1e-12] [--quiet]

Every dataset and attribute present in both files is compared: numbers (real, complex and the
numeric fields of compound records) by the largest difference relative to the dataset's largest
magnitude, max|a - b| / max|a| <= rtol; strings, enums and integers exactly. The attributes
`created`, `version` and `wall_seconds` (the clock, the program version, a timing) are not
compared. Datasets or attributes present in one file only are listed and count as differences
unless --allow-extra names them (a substring of their path).

Exit status 0 when the files agree, 1 otherwise. The last line reports the number of datasets and
attributes compared and the largest relative difference found.
"""

import argparse
import sys

import h5py
import numpy as np

SKIP_ATTRS = {"created", "version", "wall_seconds"}


def walk(f):
    """Every dataset path and every (object path, attribute name) of an open file."""
    datasets, attrs = {}, {}

    def visit(name, obj):
        for k, v in obj.attrs.items():
            if k not in SKIP_ATTRS:
                attrs[(name, k)] = v
        if isinstance(obj, h5py.Dataset):
            datasets[name] = obj[()]

    for k, v in f.attrs.items():
        if k not in SKIP_ATTRS:
            attrs[("/", k)] = v
    f.visititems(visit)
    return datasets, attrs


def rel_diff(a, b):
    """Largest |a - b| relative to max|a| (0 for two empty arrays); None when not comparable."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return None
    if a.dtype.names:
        if a.dtype.names != b.dtype.names:
            return None
        worst = 0.0
        for name in a.dtype.names:
            d = rel_diff(a[name], b[name])
            if d is None:
                return None
            worst = max(worst, d)
        return worst
    if a.dtype.kind in "fc":
        if a.size == 0:
            return 0.0
        scale = np.max(np.abs(a))
        both_nan = np.isnan(a) & np.isnan(b)
        diff = np.where(both_nan, 0.0, np.abs(a - b))
        if np.any(np.isnan(diff)):
            return float("inf")
        worst = float(np.max(diff))
        return worst / scale if scale > 0 else worst
    return 0.0 if np.array_equal(a, b) else float("inf")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--rtol", type=float, default=1e-12)
    ap.add_argument("--allow-extra", nargs="*", default=[],
                    help="substrings of paths that may exist in one file only")
    ap.add_argument("--quiet", action="store_true", help="print only the summary line")
    args = ap.parse_args()
    with h5py.File(args.a, "r") as fa, h5py.File(args.b, "r") as fb:
        da, aa = walk(fa)
        db, ab = walk(fb)
    bad, worst, compared = [], 0.0, 0
    for kind, xa, xb in (("dataset", da, db), ("attribute", aa, ab)):
        for key in sorted(set(xa) | set(xb), key=str):
            label = key if kind == "dataset" else f"{key[0]}@{key[1]}"
            if key not in xa or key not in xb:
                side = "B" if key not in xa else "A"
                if not any(s in str(label) for s in args.allow_extra):
                    bad.append(f"{kind} {label}: only in {side}")
                elif not args.quiet:
                    print(f"{kind} {label}: only in {side} (allowed)")
                continue
            compared += 1
            d = rel_diff(xa[key], xb[key])
            if d is None or d > args.rtol:
                bad.append(f"{kind} {label}: relative difference {d}")
            else:
                worst = max(worst, d)
    for line in bad:
        print(line)
    print(f"{args.a} vs {args.b}: {compared} datasets and attributes compared, "
          f"{len(bad)} differ (rtol {args.rtol:g}); largest relative difference of the rest "
          f"{worst:.3e}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
