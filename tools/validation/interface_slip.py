#!/usr/bin/env python3
"""Two models of one contact interface compared where it slips: the peaks, the energy the
interface dissipates per cycle and its stick and separation shares at equal response amplitude,
and the pairs' relative tangential motion per unit amplitude (docs/validation.md, the SAMA
paper's experiment, M2 at 50 N).

    python3 tools/validation/interface_slip.py REFERENCE.h5 OTHER.h5 [--sweep I] [--dof D] [--contact NAME]

REFERENCE and OTHER are `nlrom solve` result files of the same mode and contact (e.g. the
conforming and non-conforming cases of tools/validation/paper_comparison.py). For sweep point I
(default 0) and response DOF D (default 1, the one paper_comparison reads) it prints
  - each path's largest point and the peak of the parabola through it and its two neighbours
    (how far the sampling of the path can move the peak);
  - at amplitudes between 60 % and 98 % of the smaller peak, on the rising side of each path
    (linear interpolation between points): the energy dissipated per cycle by the whole
    interface (`dissipated_energy` summed over the pairs) and the shares of the period in stick
    and separation (`state_fractions`);
  - the half peak-to-peak magnitude of each pair's relative tangential displacement over the
    period stored at the peak (`loop_u`) divided by the response amplitude there: the median
    over the pairs of OTHER / REFERENCE (pairs matched by their contact point,
    `virtual_points`).
"""

import argparse
import sys

import h5py
import numpy as np


def load(path, sweep, dof, contact):
    """The path's frequencies (Hz), amplitudes (m), dissipated energy per cycle (J), state
    fractions [P, 3], the pairs' relative tangential motion per unit amplitude at the stored
    point and their contact points."""
    f = h5py.File(path, "r")
    frf = f[f"frf/{sweep}"]
    freq = frf["frequency_hz"][()]
    amp = frf["amplitude"][()][:, dof]
    c = f[f"contact/{contact}"]
    el = c[f"elements/{sweep}"]
    energy = el["dissipated_energy"][()].sum(axis=1)
    fractions = c[f"state_fractions/{sweep}"][()]
    point = int(el["loop_u"].attrs["point"])
    u = el["loop_u"][()]
    motion = np.sqrt(((u.max(axis=1) - u.min(axis=1)) ** 2).sum(axis=1)) / 2 / amp[point]
    return freq, amp, energy, fractions, motion, c["virtual_points"][()]


def located_peak(freq, amp):
    """The largest point and the vertex of the parabola through it and its neighbours."""
    i = int(np.argmax(amp))
    if i == 0 or i == len(amp) - 1:
        return (freq[i], amp[i]), (freq[i], amp[i])
    c = np.polyfit(freq[i - 1:i + 2], amp[i - 1:i + 2], 2)
    f = -c[1] / (2 * c[0])
    return (freq[i], amp[i]), (f, np.polyval(c, f))


def at_amplitude(amp, values, target):
    """`values` interpolated where the path first rises through `target`."""
    j = np.where((amp[:-1] < target) & (amp[1:] >= target))[0]
    if len(j) == 0:
        return None
    j = j[0]
    t = (target - amp[j]) / (amp[j + 1] - amp[j])
    return values[j] + t * (values[j + 1] - values[j])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("reference")
    parser.add_argument("other")
    parser.add_argument("--sweep", type=int, default=0)
    parser.add_argument("--dof", type=int, default=1)
    parser.add_argument("--contact", default="shroud")
    args = parser.parse_args()
    ref = load(args.reference, args.sweep, args.dof, args.contact)
    oth = load(args.other, args.sweep, args.dof, args.contact)
    peaks = []
    for name, (freq, amp, energy, fr, _, _) in (("reference", ref), ("other", oth)):
        (f0, a0), (f1, a1) = located_peak(freq, amp)
        i = int(np.argmax(amp))
        peaks.append(a1)
        print(
            f"{name}: largest point {a0:.5e} m at {f0:.3f} Hz, parabola {a1:.5e} m at {f1:.3f} Hz "
            f"({100 * (a1 / a0 - 1):+.3f} %); at the largest point {energy[i]:.3e} J per cycle, "
            f"stick {fr[i, 0]:.3f}, slip {fr[i, 1]:.3f}, separation {fr[i, 2]:.3f}"
        )
    print(f"peak of other / reference: {100 * (peaks[1] / peaks[0] - 1):+.2f} %")
    print("amplitude (m)  energy ref (J)  energy other (J)  ratio  stick ref  stick other  sep ref  sep other")
    for share in (0.6, 0.7, 0.8, 0.9, 0.98):
        target = share * min(peaks)
        e = [at_amplitude(m[1], m[2], target) for m in (ref, oth)]
        s = [at_amplitude(m[1], m[3], target) for m in (ref, oth)]
        if any(v is None for v in e + s):
            continue
        ratio = f"{e[1] / e[0]:.3f}" if e[0] > 0 else "  -  "
        print(
            f"{target:.3e}      {e[0]:.3e}       {e[1]:.3e}        {ratio}  "
            f"{s[0][0]:.3f}      {s[1][0]:.3f}        {s[0][2]:.3f}    {s[1][2]:.3f}"
        )
    match = [int(np.argmin(((oth[5] - p) ** 2).sum(axis=1))) for p in ref[5]]
    distance = max(np.sqrt(((oth[5][match] - ref[5]) ** 2).sum(axis=1)))
    if distance > 1e-9:
        sys.exit(f"the pairs' contact points differ by up to {distance:.3e} m: not the same contact face")
    ratio = oth[4][match] / ref[4]
    print(
        f"relative tangential motion per unit amplitude at the stored points: median ratio "
        f"other / reference {np.median(ratio):.3f} (pairs: {len(ratio)}, range "
        f"{ratio.min():.2f}-{ratio.max():.2f})"
    )


if __name__ == "__main__":
    main()
