#!/usr/bin/env python3
"""nlrom beside NLvib (Krack & Gross 2019; MATLAB code run in GNU Octave) and pyHarm on the
matrix cases of cases/nlvib/: each peer's model is written from the nlrom case file (matrices,
Rayleigh damping, force, [[element]] list, H, N_t, frequency range), each tool traces the
frequency response, and the script reports per curve and tool: whole curve traced, points,
CPU time per continuation point, peak amplitude A1 = |Q1| (first harmonic) of the reported DOF
and its frequency, and
the ratios to nlrom. The speed-ups use nlrom's whole process; its continuation alone (the CPU
time of the thread that traced the curve, `cpu_seconds` of `nlrom solve --json`) is reported
beside.

NLvib is not part of nlrom: give the path of a checkout (the folder holding SRC/) with --nlvib
or the NLVIB environment variable. pyHarm is the PyPI package `pyharm-os`
(tools/peers/pyharm_run.py runs it; --no-pyharm skips it).

    NLVIB=/path/to/NLvib python3 tools/peers/nlvib_compare.py [CASE.toml ...] \
        [--nlrom target/release/nlrom] [--markdown table.md] [--json out.json]

Without case arguments: cases/nlvib/chain07_jenkins.toml, chain07.toml, sdof_jenkins.toml
(all four force levels) and beam_tanh.toml.

The peak is taken over the points of each traced curve and refined by the parabola through the
largest point and its two neighbours in (ω, |Q1|), the same way for every tool. CPU time is the
user + system time of the tool's process (nlrom: the whole `nlrom solve` process, all threads;
NLvib: Octave's cputime around solve_and_continue, so model setup and Octave start-up are
excluded; pyHarm: the continuation after a warm-up run, see pyharm_run.py).
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import h5py
import numpy as np
import scipy.io

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_CASES = ["chain07_jenkins", "chain07", "sdof_jenkins", "beam_tanh"]


# --------------------------------------------------------------------------------------------
# The case as plain numbers
# --------------------------------------------------------------------------------------------

def load_case(path):
    """The case's matrices and settings, one dict per sweep point (force scale only)."""
    case = tomllib.loads(Path(path).read_text())
    base = Path(path).parent
    model = case["model"]
    K = scipy.io.mmread(base / model["stiffness"]).toarray()
    M = scipy.io.mmread(base / model["mass"]).toarray()
    alpha, beta = model.get("damping", {}).get("rayleigh", [0.0, 0.0])
    D = alpha * M + beta * K
    n = K.shape[0]
    exc = case["excitation"]
    f = np.zeros(n)
    for d, v in zip(exc["dofs"], exc["force"]):
        f[d] += v
    f *= exc.get("force_scale", 1.0)
    hb = case.get("harmonic_balance", {})
    cont = case["continuation"]
    response = case.get("response", {}).get("dofs", exc["dofs"])
    scales = case.get("sweep", {}).get("excitation.force_scale", [1.0])
    other = [k for k in case.get("sweep", {}) if k != "excitation.force_scale"]
    if other:
        sys.exit(f"{path}: only excitation.force_scale sweeps are supported here (found {other})")
    points = []
    for i, s in enumerate(scales):
        points.append(dict(
            name=Path(path).stem + (f"[F×{s:g}]" if len(scales) > 1 else ""),
            sweep_point=i, K=K, M=M, D=D, f=f * s, n=n, elements=case.get("element", []),
            H=hb.get("harmonics", 1), N=hb.get("time_samples"),
            start=cont["start_rad_s"], end=cont["end_rad_s"], step=cont["step_rad_s"],
            dof=response[0]))
    return points


def direction(e, n):
    key = "tangential" if "tangential" in e else "displacement"
    w = np.zeros(n)
    for d, x in zip(e[key]["dofs"], e[key]["weights"]):
        w[d] += x
    return w


def stuck_stiffness(p):
    """K of the stuck friction elements (for the linear start guess, as NLvib's examples)."""
    dK = np.zeros_like(p["K"])
    for e in p["elements"]:
        if e["kind"] == "friction":
            w = direction(e, p["n"])
            dK += e["kt"] * np.outer(w, w)
    return dK


def refined_peak(omega, amp):
    """(ω, A) of the largest amplitude, refined by the parabola through it and its neighbours."""
    omega, amp = np.asarray(omega), np.asarray(amp)
    i = int(np.argmax(amp))
    if 0 < i < len(amp) - 1:
        w, a = omega[i - 1:i + 2], amp[i - 1:i + 2]
        if len(set(w)) == 3 and np.all(np.diff(w) > 0) or np.all(np.diff(w) < 0):
            c = np.polyfit(w, a, 2)
            if c[0] < 0:
                wp = -c[1] / (2 * c[0])
                if min(w) <= wp <= max(w):
                    return float(wp), float(np.polyval(c, wp))
    return float(omega[i]), float(amp[i])


def reached(p, last_omega):
    """Whether the last point is at the end of the range (to 1e-9 relative)."""
    lo, hi = sorted((p["start"], p["end"]))
    tol = 1e-9 * hi
    return last_omega >= p["end"] - tol if p["end"] > p["start"] else last_omega <= p["end"] + tol


# --------------------------------------------------------------------------------------------
# nlrom
# --------------------------------------------------------------------------------------------

def run_nlrom(exe, case_path, workdir):
    out = Path(workdir) / (Path(case_path).stem + ".h5")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([exe, "solve", str(case_path), "-o", str(out), "--json", "-q"],
                          capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    report = json.loads(proc.stdout) if proc.stdout.strip() else {"frf": []}
    curves = []
    with h5py.File(out, "r") as h5:
        for rep in report["frf"]:
            g = h5[f"frf/{rep['sweep_point']}"]
            curves.append(dict(omega=g["omega"][()], harmonics=g["harmonics"][()],
                               end=rep["end"], error=rep.get("error"),
                               cpu=rep.get("cpu_seconds")))
    total = sum(len(c["omega"]) for c in curves)
    return curves, cpu, total


def nlrom_curve(c, p):
    """ω and |Q1| of the case's first response DOF."""
    h = c["harmonics"]  # points × R × (H+1), complex; R in the order of [response] dofs
    return c["omega"], np.abs(h[:, 0, 1])


# --------------------------------------------------------------------------------------------
# NLvib in Octave
# --------------------------------------------------------------------------------------------

def mat(a):
    a = np.atleast_2d(a)
    return "[" + ";".join(" ".join(f"{x:.17g}" for x in r) for r in a) + "]"


def nlvib_script(p, nlvib, result):
    n = p["n"]
    lines = [
        f"addpath('{nlvib}/SRC'); addpath('{nlvib}/SRC/MechanicalSystems');",
        f"M = {mat(p['M'])}; D = {mat(p['D'])}; K = {mat(p['K'])}; Fex1 = {mat(p['f'].reshape(-1, 1))};",
        "nonlinear_elements = {};",
    ]
    for i, e in enumerate(p["elements"], start=1):
        w = mat(direction(e, n).reshape(-1, 1))
        k = e["kind"]
        if k == "friction":
            if "normal" in e:
                sys.exit("NLvib's elasticDryFriction has no normal load variation")
            s = (f"struct('type','elasticDryFriction','stiffness',{e['kt']!r},"
                 f"'friction_limit_force',{e['mu'] * e['n0']!r},'ishysteretic',true,"
                 f"'force_direction',{w})")
        elif k == "cubic_spring":
            s = f"struct('type','cubicSpring','stiffness',{e['k3']!r},'force_direction',{w})"
        elif k == "unilateral_spring":
            s = (f"struct('type','unilateralSpring','stiffness',{e['k']!r},"
                 f"'gap',{e.get('gap', 0.0)!r},'force_direction',{w})")
        elif k == "tanh_friction":
            s = (f"struct('type','tanhDryFriction','friction_limit_force',"
                 f"{e['mu'] * e['n0']!r},'eps',{e['eps']!r},'force_direction',{w})")
        else:
            sys.exit(f"{p['name']}: NLvib has no element matching kind = {k!r}")
        lines.append(f"nonlinear_elements{{{i}}} = {s};")
    dK = stuck_stiffness(p)
    H, N = p["H"], p["N"]
    ds = p["step"]
    sopt = "struct()"
    if any(e["kind"] == "tanh_friction" for e in p["elements"]):
        # As NLvib's example 08: sequential continuation with a fixed step, scaled unknowns.
        sopt = (f"struct('flag',0,'stepadapt',0,'Dscale',[1e-7*ones((2*{H}+1)*{n},1);"
                f"{p['start']!r}])")
    lines += [
        "sys = MechanicalSystem(M,D,K,nonlinear_elements,Fex1);",
        f"H = {H}; N = {N}; Om_s = {p['start']!r}; Om_e = {p['end']!r}; ds = {ds!r};",
        f"dK = {mat(dK)};",
        "Q1 = (-Om_s^2*M + 1i*Om_s*D + K + dK)\\Fex1;",
        "n = length(M); x0 = zeros((2*H+1)*n,1); x0(n+(1:2*n)) = [real(Q1);-imag(Q1)];",
        "ok = 1;",
        # NLvib's own fsolve options; given explicitly since Octave's optimset takes no
        # function handle (optimset(@fsolve) in solve_and_continue).
        "Solopt = optimset(optimset('fsolve'),'Display','off','Jacobian','on','MaxIter',50);",
        "t0 = cputime;",
        "try",
        f"  X = solve_and_continue(x0, @(X) HB_residual(X,sys,H,N,'FRF'), Om_s, Om_e, ds, {sopt}, {{}}, Solopt);",
        "catch err",
        "  disp(err.message); ok = 0; X = zeros((2*H+1)*n+1,0);",
        "end",
        "cpu = cputime - t0;",
        f"save('-v7', '{result}', 'X', 'cpu', 'ok');",
    ]
    return "\n".join(lines) + "\n"


def run_nlvib(p, nlvib, workdir):
    result = Path(workdir) / f"nlvib_{abs(hash(p['name']))}.mat"
    script = Path(workdir) / f"nlvib_{abs(hash(p['name']))}.m"
    script.write_text(nlvib_script(p, nlvib, result))
    proc = subprocess.run(["octave-cli", "--no-gui", "--quiet", str(script)],
                          capture_output=True, text=True, cwd=workdir)
    if not result.exists():
        return dict(error=(proc.stderr or proc.stdout)[-500:])
    r = scipy.io.loadmat(result)
    X = r["X"]
    n = p["n"]
    if X.shape[1] == 0:
        return dict(error="no point converged", points=0, cpu=float(r["cpu"].squeeze()))
    omega = X[-1, :]
    d = p["dof"]
    amp = np.hypot(X[n + d, :], X[2 * n + d, :])
    return dict(omega=omega, amp=amp, cpu=float(r["cpu"].squeeze()), points=X.shape[1],
                whole=bool(reached(p, omega[-1])), log=proc.stdout[-300:])


# --------------------------------------------------------------------------------------------
# pyHarm
# --------------------------------------------------------------------------------------------

def run_pyharm(p, workdir):
    """pyHarm in its own process (tools/peers/pyharm_run.py), fed the case as JSON."""
    spec = Path(workdir) / f"pyharm_{abs(hash(p['name']))}.json"
    out = Path(workdir) / f"pyharm_{abs(hash(p['name']))}_out.json"
    spec.write_text(json.dumps(dict(
        name=p["name"], K=p["K"].tolist(), M=p["M"].tolist(), D=p["D"].tolist(),
        f=p["f"].tolist(), elements=p["elements"], H=p["H"], N=p["N"], start=p["start"],
        end=p["end"], step=p["step"], dof=p["dof"])))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([sys.executable, str(Path(__file__).with_name("pyharm_run.py")),
                           str(spec), str(out)], capture_output=True, text=True, cwd=workdir)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if not out.exists():
        return dict(error=(proc.stderr or proc.stdout)[-800:])
    r = json.loads(out.read_text())
    if "error" in r:
        return r
    omega, amp = np.array(r["omega"]), np.array(r["amp"])
    cpu = r.get("cpu", (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime))
    return dict(omega=omega, amp=amp, cpu=cpu, points=len(omega),
                whole=bool(len(omega) and reached(p, omega[-1])))


# --------------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--nlvib", default=os.environ.get("NLVIB"),
                    help="NLvib checkout (the folder holding SRC/); default $NLVIB")
    ap.add_argument("--nlrom", default=str(ROOT / "target/release/nlrom"))
    ap.add_argument("--no-pyharm", action="store_true")
    ap.add_argument("--no-nlvib", action="store_true")
    ap.add_argument("--peer-results", type=Path, nargs="*", default=[],
                    help="rows of an earlier run (its --json file or its printed JSON lines): "
                         "peers found there are not run again (nlrom always is)")
    ap.add_argument("--markdown", type=Path)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    if not args.no_nlvib and not args.peer_results and not (args.nlvib and (Path(args.nlvib) / "SRC/HB_residual.m").exists()):
        sys.exit("give the NLvib checkout with --nlvib PATH or NLVIB=PATH (the folder holding SRC/HB_residual.m)")
    cases = args.cases or [str(ROOT / f"cases/nlvib/{c}.toml") for c in DEFAULT_CASES]
    earlier = {}
    for path in args.peer_results:
        text = path.read_text().strip()
        found = json.loads(text) if text.startswith("[") else [
            json.loads(line) for line in text.splitlines() if line.startswith("{")]
        for r in found:
            if r["tool"] != "nlrom":
                earlier[(r["case"], r["tool"])] = r
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for case in cases:
            points = load_case(case)
            curves, cpu, total = run_nlrom(args.nlrom, case, work)
            per_point = cpu / max(total, 1)
            for p, c in zip(points, curves):
                om, amp = nlrom_curve(c, p)
                tools = {"nlrom": dict(omega=om, amp=amp, points=len(om),
                                       whole=c["end"] == "reached_end", cpu_per_point=per_point,
                                       error=c["error"])}
                if c["cpu"] is not None and len(om):
                    # the continuation alone: CPU time of the thread that traced this curve
                    tools["nlrom"]["continuation_cpu_per_point"] = c["cpu"] / len(om)
                if (p["name"], "NLvib") in earlier:
                    tools["NLvib"] = earlier[(p["name"], "NLvib")]
                elif not args.no_nlvib:
                    r = run_nlvib(p, args.nlvib, work)
                    if "cpu" in r:
                        r["cpu_per_point"] = r["cpu"] / max(r.get("points", 0), 1)
                    tools["NLvib"] = r
                if (p["name"], "pyHarm") in earlier:
                    tools["pyHarm"] = earlier[(p["name"], "pyHarm")]
                elif not args.no_pyharm:
                    r = run_pyharm(p, work)
                    if "cpu" in r:
                        r["cpu_per_point"] = r["cpu"] / max(r.get("points", 0), 1)
                    tools["pyHarm"] = r
                for name, t in tools.items():
                    if "omega" in t and len(t["omega"]):
                        t["peak_omega"], t["peak_amp"] = refined_peak(t["omega"], t["amp"])
                    rows.append(dict(case=p["name"], tool=name,
                                     **{k: v for k, v in t.items()
                                        if k not in ("omega", "amp", "log", "case", "tool")}))
                print_rows(rows[-len(tools):])
    table = markdown(rows)
    print(table)
    if args.markdown:
        args.markdown.write_text(table)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=float))


def print_rows(rows):
    for r in rows:
        print(json.dumps(r, default=float), flush=True)


def markdown(rows):
    out = ["| case | tool | whole curve | points | CPU ms/point | nlrom speed-up | peak A1 | "
           "peak ω (rad/s) | Δ amplitude vs nlrom | Δ ω vs nlrom | continuation alone |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    ref = {r["case"]: r for r in rows if r["tool"] == "nlrom"}
    for r in rows:
        n = ref[r["case"]]
        if "error" in r and r.get("points") is None:
            out.append(f"| {r['case']} | {r['tool']} | no: {str(r['error'])[:80]} | | | | | | | | |")
            continue
        cpu = r.get("cpu_per_point")
        speed = (f"{cpu / n['cpu_per_point']:.0f}×" if r["tool"] != "nlrom" and cpu
                 and n.get("cpu_per_point") else "")
        da = dw = ""
        if r["tool"] != "nlrom" and "peak_amp" in r and "peak_amp" in n:
            da = f"{100 * (r['peak_amp'] / n['peak_amp'] - 1):+.3f} %"
            dw = f"{100 * (r['peak_omega'] / n['peak_omega'] - 1):+.3f} %"
        alone = r.get("continuation_cpu_per_point")
        alone = f"{1e3 * alone:.3g} ms/point" if alone is not None else ""
        out.append(
            f"| {r['case']} | {r['tool']} | {'yes' if r.get('whole') else 'no'} | "
            f"{r.get('points', '')} | {1e3 * cpu:.3g} | {speed} | "
            f"{r.get('peak_amp', float('nan')):.6g} | {r.get('peak_omega', float('nan')):.6g} | "
            f"{da} | {dw} | {alone} |" if cpu is not None else
            f"| {r['case']} | {r['tool']} | {'yes' if r.get('whole') else 'no'} | | | | | | | | |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
