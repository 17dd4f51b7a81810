//! `nlrom law`: one friction contact point (the 1-D law with normal load variation) under a
//! prescribed periodic relative motion, evaluated exactly (`analytic`, the single-harmonic cycle
//! of Cigeroglu, An & Menq 2007) or by the time-discrete law over N_t samples (`aft`): force and
//! normal-force harmonics, energy per cycle, regime, transition angles and the hysteresis loop,
//! as text or one JSON object (`docs/user-guide.md`).
//!
//! The motion is u(τ) = U0 + Σ_n (Re Uₙ cos nτ − Im Uₙ sin nτ) and likewise v (the layout of
//! `docs/conventions.md` §4), given as the lists `[U0, Re U1, Im U1, Re U2, …]`.

use std::f64::consts::TAU;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Deserialize;
use serde_json::{json, Value};

use super::Reporter;
use crate::case::Evaluation;
use crate::contact::aft::Aft;
use crate::contact::element::{evaluate_as, HysteresisLoop, LocalElement, Workspace};
use crate::contact::law::{ContactParams, Regime, Variant};
use crate::contact::microslip;
use crate::error::{Error, Result};
use crate::harmonics::HarmonicLayout;

/// The law and the motion, from a TOML file (`--input`) and the command line (which wins).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawInput {
    /// Tangential stiffness k_t (N/m).
    pub kt: Option<f64>,
    /// Normal stiffness k_n (N/m); default 0.
    pub kn: Option<f64>,
    /// Friction coefficient μ.
    pub mu: Option<f64>,
    /// Static normal load n0 (N); negative: initial gap −n0/k_n.
    pub n0: Option<f64>,
    /// Tangential motion [U0, Re U1, Im U1, …] (m).
    pub u: Option<Vec<f64>>,
    /// Normal approach [V0, Re V1, Im V1, …] (m); default none (v ≡ 0).
    pub v: Option<Vec<f64>>,
    /// Slider position at τ = 0 before the first period (m); default 0.
    pub slider: Option<f64>,
    /// `analytic` (default, H = 1) or `aft`.
    pub evaluation: Option<Evaluation>,
    /// AFT samples per period N_t; default 1024.
    pub time_samples: Option<usize>,
}

impl LawInput {
    /// Reads a TOML file; unknown keys are an error naming the file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        toml::from_str(&text).map_err(|e| {
            Error::input(format!(
                "{}: {} (keys: kt, kn, mu, n0, u, v, slider, evaluation, time_samples)",
                path.display(),
                e.message()
            ))
        })
    }

    /// `self` with every value of `over` that is given.
    pub fn overridden_by(self, over: LawInput) -> LawInput {
        LawInput {
            kt: over.kt.or(self.kt),
            kn: over.kn.or(self.kn),
            mu: over.mu.or(self.mu),
            n0: over.n0.or(self.n0),
            u: over.u.or(self.u),
            v: over.v.or(self.v),
            slider: over.slider.or(self.slider),
            evaluation: over.evaluation.or(self.evaluation),
            time_samples: over.time_samples.or(self.time_samples),
        }
    }
}

/// Options of `nlrom law` besides the input.
#[derive(Clone, Debug, Default)]
pub struct LawOptions {
    /// Where the hysteresis loop samples go (CSV), if anywhere.
    pub loop_csv: Option<PathBuf>,
    /// Samples of the loop in the JSON report and the CSV (default 256).
    pub loop_samples: Option<usize>,
}

/// The evaluated law.
#[derive(Clone, Debug)]
pub struct LawReport {
    /// The evaluation used.
    pub evaluation: Evaluation,
    /// Harmonics H and samples N_t (N_t of the AFT; of the loop for the analytic evaluation).
    pub layout: HarmonicLayout,
    /// Friction force harmonics [F0, Re F1, Im F1, …] (N).
    pub friction: Vec<f64>,
    /// Normal force harmonics (N).
    pub normal: Vec<f64>,
    /// Energy dissipated per cycle (J).
    pub energy: f64,
    /// Fractions of the period (stick, slip, separation).
    pub fractions: [f64; 3],
    /// Regime name (analytic: the paper's; AFT: from the fractions).
    pub regime: String,
    /// Transitions (τ in rad, name).
    pub transitions: Vec<(f64, String)>,
    /// Slider at τ = 0 of the periodic cycle (m).
    pub slider: f64,
    /// The loop samples.
    pub hysteresis: HysteresisLoop,
}

fn required(v: Option<f64>, key: &str) -> Result<f64> {
    v.ok_or_else(|| {
        Error::input(format!(
            "nlrom law: `{key}` is missing (give --{key} or `{key} = …` in the --input file)"
        ))
    })
}

/// Evaluates the law of `input` (see the module documentation); `loop_samples` sets N_t of the
/// loop of the analytic evaluation.
pub fn evaluate_law(input: &LawInput, loop_samples: usize) -> Result<LawReport> {
    let p = ContactParams::new(
        required(input.kt, "kt")?,
        input.kn.unwrap_or(0.0),
        required(input.mu, "mu")?,
        required(input.n0, "n0")?,
        "nlrom law",
    )?;
    let u = input.u.clone().ok_or_else(|| {
        Error::input("nlrom law: `u` is missing (give --u U0,ReU1,ImU1 or `u = [U0, ReU1, ImU1]` in the --input file)")
    })?;
    let evaluation = input.evaluation.unwrap_or(Evaluation::Analytic);
    let m = u.len();
    if m < 3 || m % 2 == 0 {
        return Err(Error::input(format!(
            "nlrom law: `u` has {m} values; give [U0, Re U1, Im U1, Re U2, Im U2, …] (2H + 1 values, H ≥ 1)"
        )));
    }
    let h = (m - 1) / 2;
    if let Some(v) = &input.v {
        if v.len() != m {
            return Err(Error::input(format!(
                "nlrom law: `v` has {} values and `u` {m}; give both with the same harmonics",
                v.len()
            )));
        }
    }
    for (name, list) in [("u", Some(&u)), ("v", input.v.as_ref())] {
        if let Some(x) = list.and_then(|l| l.iter().find(|x| !x.is_finite())) {
            return Err(Error::input(format!(
                "nlrom law: `{name}` holds {x}, not a finite number"
            )));
        }
    }
    if evaluation == Evaluation::Analytic && h != 1 {
        return Err(Error::input(format!(
            "nlrom law: evaluation = analytic is the exact single-harmonic cycle; `u` has H = {h} harmonics: give 3 values or use --evaluation aft"
        )));
    }
    let n_t = match evaluation {
        Evaluation::Aft => input.time_samples.unwrap_or(1024),
        Evaluation::Analytic => loop_samples,
    };
    let layout = HarmonicLayout::new(h, n_t)?;
    let aft = Aft::new(layout)?;
    let mut ws = Workspace::new(&aft);
    let element = LocalElement {
        params: p,
        variant: Variant::OneD,
        tangential: 1,
        normal: input.v.is_some(),
    };
    let mut x = u.clone();
    if let Some(v) = &input.v {
        x.extend_from_slice(v);
    }
    let mut force = vec![0.0; x.len()];
    let mut slider = [input.slider.unwrap_or(0.0), 0.0];
    let marching = evaluate_as(
        evaluation,
        &element,
        &aft,
        &x,
        &mut slider,
        &mut force,
        false,
        &mut ws,
    )?;
    let report = ws.report();
    let hysteresis = ws.hysteresis();
    let (regime, transitions) = match evaluation {
        Evaluation::Analytic => {
            let v = input.v.as_ref().map_or([0.0; 3], |v| [v[0], v[1], v[2]]);
            let cycle = microslip::cycle(&p, [u[0], u[1], u[2]], v, input.slider.unwrap_or(0.0))?;
            let t = cycle
                .transitions()
                .into_iter()
                .map(|(a, n)| (a, n.to_string()))
                .collect();
            (cycle.regime.name().to_string(), t)
        }
        Evaluation::Aft => {
            if !marching.converged {
                return Err(Error::Compute(format!(
                    "nlrom law: the slider state did not repeat after {} periods",
                    marching.periods
                )));
            }
            let regime = if report.separation >= 1.0 {
                "always separated"
            } else if report.separation > 0.0 {
                "separation"
            } else if report.slip > 0.0 {
                "stick-slip"
            } else {
                "complete stick"
            };
            (regime.to_string(), sampled_transitions(&hysteresis))
        }
    };
    let (friction, normal) = match input.v {
        Some(_) => (force[..m].to_vec(), force[m..].to_vec()),
        None => {
            let mut n = vec![0.0; m];
            n[0] = p.n0.max(0.0);
            (force, n)
        }
    };
    Ok(LawReport {
        evaluation,
        layout,
        friction,
        normal,
        energy: report.dissipated_energy,
        fractions: [report.stick, report.slip, report.separation],
        regime,
        transitions,
        slider: slider[0],
        hysteresis,
    })
}

/// The state code of a loop sample: 0 stick, ±1 slip (sign of the force), 2 separation.
fn code(l: &HysteresisLoop, j: usize) -> i8 {
    match l.regime[j][0] {
        Regime::Stick => 0,
        Regime::Separation => 2,
        Regime::Slip => {
            if l.ft[0][j] >= 0.0 {
                1
            } else {
                -1
            }
        }
    }
}

/// Transitions of the sampled loop: the sample where the state changes, named as the analytic
/// ones (`StP`, `P`, `StN`, `N`, `Sp1`, `Sp2`; a stick after a re-contact is not told apart).
fn sampled_transitions(l: &HysteresisLoop) -> Vec<(f64, String)> {
    let n = l.regime.len();
    let mut out = Vec::new();
    for j in 0..n {
        let (a, b) = (code(l, (j + n - 1) % n), code(l, j));
        if a == b {
            continue;
        }
        let name = match (a, b) {
            (_, 2) => "Sp1",
            (2, _) => "Sp2",
            (1, _) => "P",
            (-1, _) => "N",
            (_, 1) => "StP",
            _ => "StN",
        };
        out.push((TAU * j as f64 / n as f64, name.to_string()));
    }
    out
}

/// The report as JSON (`docs/user-guide.md`, `nlrom law`).
pub fn law_json(r: &LawReport) -> Value {
    let l = &r.hysteresis;
    let n = l.v.len();
    let states: Vec<i8> = (0..n).map(|j| code(l, j)).collect();
    json!({
        "evaluation": r.evaluation.name(),
        "harmonics": r.layout.harmonics,
        "time_samples": r.layout.time_samples,
        "regime": r.regime,
        "friction": r.friction,
        "normal": r.normal,
        "energy_per_cycle": r.energy,
        "fractions": {"stick": r.fractions[0], "slip": r.fractions[1], "separation": r.fractions[2]},
        "transitions": r.transitions.iter().map(|(t, name)| json!({
            "name": name,
            "tau_rad": t,
            "tau_deg": t.to_degrees(),
        })).collect::<Vec<_>>(),
        "slider": r.slider,
        "loop": {
            "tau": (0..n).map(|j| TAU * j as f64 / n as f64).collect::<Vec<_>>(),
            "u": l.u[0],
            "v": l.v,
            "f": l.ft[0],
            "n": l.fnormal,
            "w": l.w[0],
            "state": states,
        },
    })
}

/// The report as text.
pub fn law_text(r: &LawReport) -> String {
    let mut s = String::new();
    let harmonics = |x: &[f64]| {
        let mut t = format!("{:.6e}", x[0]);
        for (n, pair) in x[1..].chunks(2).enumerate() {
            t.push_str(&format!(
                "; n = {}: {:.6e} {:+.6e}i",
                n + 1,
                pair[0],
                pair[1]
            ));
        }
        t
    };
    s.push_str(&format!(
        "evaluation: {} (H = {}{})\n",
        r.evaluation.name(),
        r.layout.harmonics,
        if r.evaluation == Evaluation::Aft {
            format!(", N_t = {}", r.layout.time_samples)
        } else {
            String::new()
        }
    ));
    s.push_str(&format!("regime: {}\n", r.regime));
    s.push_str(&format!(
        "friction force harmonics (N): {}\n",
        harmonics(&r.friction)
    ));
    s.push_str(&format!(
        "normal force harmonics (N): {}\n",
        harmonics(&r.normal)
    ));
    s.push_str(&format!("energy per cycle (J): {:.9e}\n", r.energy));
    s.push_str(&format!(
        "fractions of the period: stick {:.6}, slip {:.6}, separation {:.6}\n",
        r.fractions[0], r.fractions[1], r.fractions[2]
    ));
    if r.transitions.is_empty() {
        s.push_str("transitions: none\n");
    } else {
        let list: Vec<String> = r
            .transitions
            .iter()
            .map(|(t, n)| format!("{n} {:.4}°", t.to_degrees()))
            .collect();
        s.push_str(&format!("transitions (τ): {}\n", list.join(", ")));
    }
    s.push_str(&format!("slider at τ = 0 (m): {:.9e}\n", r.slider));
    s
}

/// Writes the loop samples as CSV: tau_rad, u, v, f, n, w, state.
pub fn write_loop_csv(path: &Path, r: &LawReport) -> Result<()> {
    let l = &r.hysteresis;
    let mut text = String::from("tau_rad,u,v,f,n,w,state\n");
    let n = l.v.len();
    for j in 0..n {
        text.push_str(&format!(
            "{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{}\n",
            TAU * j as f64 / n as f64,
            l.u[0][j],
            l.v[j],
            l.ft[0][j],
            l.fnormal[j],
            l.w[0][j],
            code(l, j)
        ));
    }
    let mut f = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    f.write_all(text.as_bytes()).map_err(|e| Error::io(path, e))
}

/// `nlrom law`: evaluates, prints text or JSON, writes the loop CSV if asked.
pub fn law_command(
    file: Option<&Path>,
    over: LawInput,
    opts: &LawOptions,
    rep: &Reporter,
    as_json: bool,
) -> Result<()> {
    let start = Instant::now();
    let input = match file {
        Some(f) => LawInput::load(f)?.overridden_by(over),
        None => over,
    };
    let samples = opts.loop_samples.unwrap_or(256);
    if samples < 4 {
        return Err(Error::input(format!(
            "nlrom law: --loop-samples {samples} is too small (at least 4)"
        )));
    }
    let report = evaluate_law(&input, samples)?;
    if let Some(path) = &opts.loop_csv {
        write_loop_csv(path, &report)?;
        rep.info(&format!("hysteresis loop written to {}", path.display()));
    }
    if as_json {
        let mut v = law_json(&report);
        v["wall_seconds"] = json!(start.elapsed().as_secs_f64());
        println!("{v}");
    } else {
        print!("{}", law_text(&report));
    }
    Ok(())
}
