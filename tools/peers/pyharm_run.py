#!/usr/bin/env python3
"""Runs one nlrom matrix case in pyHarm (PyPI `pyharm-os`, Safran's harmonic-balance code) for
tools/peers/nlvib_compare.py: SPEC.json (written by that script: K, M, C = D, force, the
[[element]] list, H, N_t, frequency range, reported DOF) in, OUT.json (ω and |Q1| of the DOF per
point, CPU seconds of the continuation, or an error saying what pyHarm cannot express) out.

The matrices become one pyHarm substructure with one DOF per node; each element becomes a
node-to-node connector: `friction` → Jenkins (k = k_t, mu, N0 = n0), `cubic_spring` →
CubicSpring, `unilateral_spring` → PenaltyUnilateralGap. A combination must be a single DOF
(to the ground) or two DOFs with weights −1, +1 (slave − master). The continuation is pyHarm's
default (tangent predictor, arc-length corrector, scipy root) from the start to the end
frequency. The CPU time is that of the continuation after a warm-up run on the first 2 % of the
range (pyHarm compiles its element functions just in time in every new process).

    python3 tools/peers/pyharm_run.py SPEC.json OUT.json
"""
import json
import sys
import time

import numpy as np


def connect(e):
    key = "tangential" if "tangential" in e else "displacement"
    dofs, w = e[key]["dofs"], e[key]["weights"]
    if len(dofs) == 1 and w[0] == 1.0:
        return {"sub1": [dofs[0]]}  # to the ground
    if len(dofs) == 2 and sorted(w) == [-1.0, 1.0]:
        slave = dofs[w.index(1.0)]
        master = dofs[w.index(-1.0)]
        return [("sub1", [slave]), ("sub1", [master])]
    raise ValueError(f"pyHarm's node-to-node connectors take one DOF or a (+1, −1) pair, not {e[key]}")


def connector(e):
    k = e["kind"]
    base = {"connect": connect(e), "dirs": [0]}
    if k == "friction":
        if "normal" in e:
            raise ValueError("the normal load variation of a friction element has no 1-D pyHarm Jenkins equivalent")
        return base | {"type": "Jenkins", "mu": e["mu"], "N0": e["n0"], "k": e["kt"]}
    if k == "cubic_spring":
        return base | {"type": "CubicSpring", "k": e["k3"]}
    if k == "unilateral_spring":
        return base | {"type": "PenaltyUnilateralGap", "k": e["k"], "g": e.get("gap", 0.0)}
    raise ValueError(f"pyHarm has no built-in element for kind = {k!r} "
                     "(its regularised friction exists only as a user plugin in its tutorials)")


def main():
    spec = json.load(open(sys.argv[1]))
    out_path = sys.argv[2]
    try:
        connectors = {f"e{i}": connector(e) for i, e in enumerate(spec["elements"])}
    except ValueError as err:
        json.dump({"error": str(err)}, open(out_path, "w"))
        return
    import pyHarm

    n = len(spec["K"])
    f = np.array(spec["f"])
    forced = [i for i in range(n) if f[i] != 0.0]
    for i in forced:
        connectors[f"load{i}"] = {"type": "CosinusForcing", "connect": {"sub1": [i]},
                                  "dirs": [0], "amp": float(f[i])}
    span = abs(spec["end"] - spec["start"])
    inp = {
        "system": {"type": "Base", "nh": spec["H"], "nti": spec["N"]},
        "substructures": {"sub1": {"matrix": {"M": np.array(spec["M"]), "K": np.array(spec["K"]),
                                              "C": np.array(spec["D"])}, "ndofs": 1}},
        "connectors": connectors,
        "analysis": {"frf": {"study": "frf", "puls_inf": min(spec["start"], spec["end"]),
                             "puls_sup": max(spec["start"], spec["end"]),
                             "sign_ds": 1 if spec["end"] > spec["start"] else -1,
                             "ds0": spec["step"], "ds_min": 1e-6 * span, "ds_max": 0.05 * span,
                             "verbose": False}},
    }
    # Warm-up on the first 2 % of the range, so that the timed run below does not include the
    # just-in-time compilation (numba, JAX) a fresh pyHarm process does on its first evaluations.
    warm = json.loads(json.dumps(inp, default=lambda a: a.tolist()))
    warm["substructures"]["sub1"]["matrix"] = inp["substructures"]["sub1"]["matrix"]
    lo = min(spec["start"], spec["end"])
    warm["analysis"]["frf"]["puls_sup"] = lo + 0.02 * span
    pyHarm.Maestro(warm).operate()
    t0 = time.process_time()
    m = pyHarm.Maestro(inp)
    m.operate()
    cpu = time.process_time() - t0
    analysis = m.nls["frf"]
    sols = [s for s in analysis.SolList if getattr(s, "flag_accepted", True)]
    edf = m.system.expl_dofs
    dof = spec["dof"]
    sel = edf[(edf["sub"] == "sub1") & (edf["node_num"] == dof) & (edf["dof_num"] == 0)]
    idx = {int(h): i for h, i in zip(sel["harm"], sel.index)} if "harm" in sel else None
    omega, amp = [], []
    for s in sols:
        x = np.asarray(s.x)
        omega.append(float(x[-1]))
        rows = sel.index.to_numpy()
        # rows: the DOF's coefficients [0, cos 1, sin 1, ...] in harmonic order
        amp.append(float(np.hypot(x[rows[1]], x[rows[2]])))
    json.dump({"omega": omega, "amp": amp, "cpu": cpu, "harm_index": bool(idx)}, open(out_path, "w"))


if __name__ == "__main__":
    main()
