//! `nlrom modes`: natural frequencies (Hz) of the model at a stage of the reduction — the full
//! clamped model (sparse shift-invert Lanczos, [`crate::eigen`]), the Craig–Bampton model, CB +
//! the cyclic constraint of harmonic index K, or CB + CS + GSI (dense, [`crate::reduction`]) —
//! with the residual of every mode, as a table or one JSON object.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::ValueEnum;
use serde_json::{json, Value};

use super::Reporter;
use crate::case::Case;
use crate::eigen::hermitian_modes;
use crate::eigen::{lowest_modes, EigenOptions};
use crate::error::{Error, Result};
use crate::model;
use crate::reduction::Sector;

/// The stage of the pipeline whose model `modes` solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Stage {
    /// The assembled or imported model with clamps.
    Full,
    /// The Craig–Bampton model.
    Cb,
    /// Craig–Bampton + cyclic constraint for harmonic index K.
    Cs,
    /// After Gram–Schmidt interface reduction.
    Gsi,
}

/// What `nlrom modes` computes.
#[derive(Clone, Debug, PartialEq)]
pub struct ModesOptions {
    /// The case file.
    pub case: PathBuf,
    /// The stage of the reduction.
    pub stage: Stage,
    /// Harmonic index K (stages cs and gsi).
    pub harmonic: Option<usize>,
    /// Number of modes.
    pub num: usize,
    /// Shift of the eigensolver −(2π·F)², F in Hz (a model without clamp).
    pub shift_hz: Option<f64>,
}

/// `nlrom modes`: natural frequencies of the model at a stage.
pub fn modes_command(a: &ModesOptions, rep: &Reporter, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let stage = match a.stage {
        Stage::Full => "full",
        Stage::Cb | Stage::Cs | Stage::Gsi => return reduced_modes(a, rep, as_json, start),
    };
    let shift = match a.shift_hz {
        Some(f) if f.is_finite() && f > 0.0 => -(2.0 * std::f64::consts::PI * f).powi(2),
        Some(f) => {
            return Err(Error::input(format!(
                "--shift-hz {f}: give a positive frequency in Hz"
            )))
        }
        None => 0.0,
    };
    let case = Case::load(&a.case)?;
    let model = model::build(&case, &mut |l| rep.detail(l))?;
    let n = model.free.n_free();
    if a.num == 0 || a.num >= n {
        return Err(Error::input(format!(
            "--num {}: ask for 1 to {} modes (the model has {n} free DOF)",
            a.num,
            n.saturating_sub(1)
        )));
    }
    let opts = EigenOptions {
        shift,
        ..EigenOptions::default()
    };
    let t = Instant::now();
    let modes = lowest_modes(model.free.k.as_ref(), model.free.m.as_ref(), a.num, &opts).map_err(|e| {
        if shift == 0.0 && model.free.n_free() == model.n_dofs {
            Error::Compute(format!(
                "{e}\nThe model has no clamp: for a free–free model pass --shift-hz F (e.g. a tenth of the first elastic frequency), or clamp a group in [model] clamp"
            ))
        } else {
            e
        }
    })?;
    rep.info(&format!(
        "{} modes in {:.2} s",
        modes.len(),
        t.elapsed().as_secs_f64()
    ));
    let report = ModesReport {
        stage,
        harmonic: a.harmonic,
        frequencies_hz: modes.frequencies_hz(),
        residuals: modes.residuals.clone(),
        dofs: n,
        extra: json!({}),
    };
    report.print(&a.case, as_json, start);
    Ok(())
}

/// What `nlrom modes` reports (the JSON keys of `docs/user-guide.md`).
struct ModesReport {
    stage: &'static str,
    harmonic: Option<usize>,
    frequencies_hz: Vec<f64>,
    residuals: Vec<f64>,
    dofs: usize,
    /// More keys for the JSON object (e.g. the GSI report).
    extra: Value,
}

impl ModesReport {
    /// Prints the report as one JSON object or as a table.
    fn print(&self, case: &Path, as_json: bool, start: Instant) {
        if as_json {
            let mut report = json!({
                "stage": self.stage,
                "harmonic": self.harmonic,
                "frequencies_hz": self.frequencies_hz,
                "residuals": self.residuals,
                "dofs": self.dofs,
            });
            if let (Some(obj), Some(extra)) = (report.as_object_mut(), self.extra.as_object()) {
                obj.extend(extra.clone());
            }
            report["wall_seconds"] = json!(start.elapsed().as_secs_f64());
            println!("{report}");
            return;
        }
        let harmonic = self
            .harmonic
            .map(|k| format!(", harmonic index {k}"))
            .unwrap_or_default();
        let what = if self.stage == "full" {
            "free DOF"
        } else {
            "reduced coordinates"
        };
        println!(
            "{} modes of {} (stage {}{harmonic}, {} {what})",
            self.frequencies_hz.len(),
            case.display(),
            self.stage,
            self.dofs
        );
        println!("{:>5} {:>16} {:>12}", "mode", "frequency (Hz)", "residual");
        for (i, (f, r)) in self.frequencies_hz.iter().zip(&self.residuals).enumerate() {
            println!("{:>5} {:>16.6} {:>12.2e}", i + 1, f, r);
        }
    }
}

/// `nlrom modes --stage cb|cs|gsi`: the Craig–Bampton model, CB + cyclic constraint for harmonic
/// index K, or CB + CS + GSI (`nlrom::reduction`). Residual: ‖Kx − λMx‖/‖Kx‖ of the dense
/// reduced problem.
fn reduced_modes(a: &ModesOptions, rep: &Reporter, as_json: bool, start: Instant) -> Result<()> {
    let case = Case::load(&a.case)?;
    let (stage, harmonic) = match a.stage {
        Stage::Cb => {
            if let Some(k) = a.harmonic {
                return Err(Error::input(format!(
                    "--harmonic {k}: the cb stage has no cyclic constraint; use --stage cs --harmonic {k}"
                )));
            }
            ("cb", None)
        }
        Stage::Cs => ("cs", Some(required_harmonic(a, &case, "cs")?)),
        _ => ("gsi", Some(required_harmonic(a, &case, "gsi")?)),
    };
    let gsi_modes = if stage == "gsi" {
        Some(
            case.reduction
                .as_ref()
                .and_then(|r| r.gsi_modes)
                .ok_or_else(|| {
                    Error::input(format!(
                        "{}: --stage gsi needs `[reduction] gsi_modes = N` in the case",
                        a.case.display()
                    ))
                })?,
        )
    } else {
        None
    };
    let model = model::build(&case, &mut |l| rep.detail(l))?;
    let sector = Sector::build(&case, &model, &mut |l| rep.detail(l))?;
    let h = match harmonic {
        None => sector.cb_model(),
        Some(k) => sector.harmonic(k, gsi_modes)?,
    };
    let n = h.dofs.len();
    if a.num == 0 || a.num > n {
        return Err(Error::input(format!(
            "--num {}: ask for 1 to {n} modes (the {stage} model has {n} coordinates)",
            a.num
        )));
    }
    let modes = hermitian_modes(h.stiffness.as_ref(), h.mass.as_ref(), h.real)?;
    let extra = match &h.gsi {
        Some(g) => {
            json!({"gsi": {"modes_used": g.modes_used, "retained": g.retained, "dropped": g.dropped}})
        }
        None => json!({}),
    };
    if let Some(g) = &h.gsi {
        rep.info(&format!(
            "GSI: {} of {} frontier vectors retained, dropped {:?}",
            g.retained, g.modes_used, g.dropped
        ));
    }
    let report = ModesReport {
        stage,
        harmonic,
        frequencies_hz: modes.frequencies_hz(a.num),
        residuals: modes.residuals(h.stiffness.as_ref(), h.mass.as_ref(), a.num),
        dofs: n,
        extra,
    };
    report.print(&a.case, as_json, start);
    Ok(())
}

/// `--harmonic K` for the cs and gsi stages, which need a `[cyclic]` table.
fn required_harmonic(a: &ModesOptions, case: &Case, stage: &str) -> Result<usize> {
    if case.cyclic.is_none() {
        return Err(Error::input(format!(
            "{}: --stage {stage} needs a cyclic model (a [cyclic] table in the case)",
            a.case.display()
        )));
    }
    a.harmonic.ok_or_else(|| {
        Error::input(format!(
            "--stage {stage} needs --harmonic K (the harmonic index, 0 ≤ K < N)"
        ))
    })
}
