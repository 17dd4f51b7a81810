#!/usr/bin/env python3
"""Writes the 16-DOF clamped-free Euler-Bernoulli beam of NLvib's example 08 (Krack & Gross 2019,
"beam with tanh dry friction") as an nlrom matrix case: cases/nlvib/beam/{K,M}.mtx and
cases/nlvib/beam_tanh.toml.

The beam (length 2 m, height 0.1 m, thickness 0.3 m, E = 185 GPa, rho = 7830 kg/m^3) has 9
equidistant nodes with a deflection and a slope each; node 1 is clamped, so the 16 unknowns are
(w_2, w'_2, ..., w_9, w'_9) (rows 2(i-2), 2(i-2)+1 for node i). The element matrices are the
cubic Hermite (consistent) ones: k = EI/l^3 [[12, 6l, -12, 6l], ...], m = rho A l/420 [[156, 22l,
54, -13l], ...]. A tanh friction element (slip force 1.5 N) acts on the deflection of node 4,
a force 0.2 N on the tip deflection (node 9). As the example: stiffness-proportional damping
beta = 0.02/omega_fixed,1 (omega_fixed: the beam with node 4 held), regularising velocity
eps = omega_free,1 * |w_4| of the linear free beam at the start frequency, H = 7, N_t = 128,
from 1.5 omega_fixed,1 down to 0.9 omega_free,1.

    python3 tools/peers/make_beam_case.py [--root .]
"""
import argparse
from pathlib import Path

import numpy as np
import scipy.linalg as sla

LENGTH, HEIGHT = 2.0, 0.1
THICK = 3 * HEIGHT
E, RHO = 185e9, 7830.0
NODES = 9
FRICTION_NODE, FORCE_NODE = 4, 9
SLIP_FORCE, FORCE = 1.5, 0.2


def beam_matrices():
    ei = E * THICK * HEIGHT**3 / 12
    rho_a = RHO * THICK * HEIGHT
    n_full = 2 * NODES
    K = np.zeros((n_full, n_full))
    M = np.zeros((n_full, n_full))
    le = LENGTH / (NODES - 1)
    l = le
    ke = ei / l**3 * np.array([[12, 6 * l, -12, 6 * l],
                               [6 * l, 4 * l * l, -6 * l, 2 * l * l],
                               [-12, -6 * l, 12, -6 * l],
                               [6 * l, 2 * l * l, -6 * l, 4 * l * l]])
    me = rho_a * l / 420 * np.array([[156, 22 * l, 54, -13 * l],
                                     [22 * l, 4 * l * l, 13 * l, -3 * l * l],
                                     [54, 13 * l, 156, -22 * l],
                                     [-13 * l, -3 * l * l, -22 * l, 4 * l * l]])
    for e in range(NODES - 1):
        idx = np.arange(2 * e, 2 * e + 4)
        K[np.ix_(idx, idx)] += ke
        M[np.ix_(idx, idx)] += me
    free = np.arange(2, n_full)  # node 1 clamped
    return K[np.ix_(free, free)], M[np.ix_(free, free)]


def row(node):
    """Deflection row of 1-based node `node` among the free DOFs."""
    return 2 * (node - 2)


def derived(K, M):
    n = K.shape[0]
    om_free = np.sqrt(np.sort(sla.eigh(K, M, eigvals_only=True)))
    keep = [i for i in range(n) if i != row(FRICTION_NODE)]
    om_fixed = np.sqrt(np.sort(sla.eigh(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)],
                                        eigvals_only=True)))
    beta = 2e-2 / om_fixed[0]
    om_s, om_e = 1.5 * om_fixed[0], 0.9 * om_free[0]
    f = np.zeros(n)
    f[row(FORCE_NODE)] = FORCE
    q1 = np.linalg.solve(-om_s**2 * M + 1j * om_s * beta * K + K, f)
    eps = om_free[0] * abs(q1[row(FRICTION_NODE)])
    return dict(beta=beta, om_s=om_s, om_e=om_e, eps=eps, om_free=om_free[0],
                om_fixed=om_fixed[0])


def write_mtx(path, A, comment):
    n = A.shape[0]
    entries = [(i, j, A[i, j]) for j in range(n) for i in range(j, n) if A[i, j] != 0.0]
    with open(path, "w") as f:
        f.write("%%MatrixMarket matrix coordinate real symmetric\n")
        f.write(f"% {comment}\n")
        f.write(f"{n} {n} {len(entries)}\n")
        for i, j, v in entries:
            f.write(f"{i + 1} {j + 1} {v:.17e}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=Path(__file__).resolve().parents[2], type=Path)
    args = ap.parse_args()
    K, M = beam_matrices()
    d = derived(K, M)
    out = args.root / "cases/nlvib"
    (out / "beam").mkdir(parents=True, exist_ok=True)
    note = "16-DOF clamped-free Hermite beam (NLvib example 08 geometry); rows (w, w') of nodes 2..9"
    write_mtx(out / "beam/K.mtx", K, "stiffness (N/m, N, N m): " + note)
    write_mtx(out / "beam/M.mtx", M, "mass (kg, kg m, kg m^2): " + note)
    text = f'''# NLvib's example 08 (Krack & Gross 2019): a clamped-free Euler-Bernoulli beam (2 m, 9 nodes,
# 16 DOF; written by tools/peers/make_beam_case.py) with a tanh-regularised Coulomb friction element
# on the deflection of node 4 (slip force 1.5 N, eps = omega_free,1 |w_4| of the linear free beam at
# the start) and a force 0.2 N on the tip; C = beta K with beta = 0.02/omega_fixed,1;
# H = 7, N_t = 128, from 1.5 omega_fixed,1 down to 0.9 omega_free,1
# (omega_fixed,1 = {d["om_fixed"]:.6f}, omega_free,1 = {d["om_free"]:.6f} rad/s).
#   nlrom solve cases/nlvib/beam_tanh.toml -o beam_tanh.h5 --json
title = "NLvib example 08 beam, tanh friction"

[model]
stiffness = "beam/K.mtx"
mass = "beam/M.mtx"
damping = {{ rayleigh = [0.0, {d["beta"]:.17e}] }}

[excitation]
dofs = [{row(FORCE_NODE)}]
force = [{FORCE}]

[response]
dofs = [{row(FORCE_NODE)}, {row(FRICTION_NODE)}]

[[element]]
kind = "tanh_friction"
displacement = {{ dofs = [{row(FRICTION_NODE)}], weights = [1.0] }}
mu = 1.0
n0 = {SLIP_FORCE}
eps = {d["eps"]:.17e}

[harmonic_balance]
harmonics = 7
time_samples = 128

[continuation]
start_rad_s = {d["om_s"]:.17e}
end_rad_s = {d["om_e"]:.17e}
step_rad_s = 5.0
'''
    (out / "beam_tanh.toml").write_text(text)
    print(f"wrote {out / 'beam_tanh.toml'} and beam/K.mtx, beam/M.mtx: {d}")


if __name__ == "__main__":
    main()
