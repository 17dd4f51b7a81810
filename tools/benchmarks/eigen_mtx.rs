//! The lowest modes of a pencil read from Matrix Market files, for `tools/benchmarks/bench_eigen.py`.
//!
//! Usage: `cargo run --release --example eigen_mtx -- DIR [N] [SHIFT]` reads `DIR/K.mtx` (N/m)
//! and `DIR/M.mtx` (kg), computes the lowest N modes (default 20) with the shift SHIFT (rad²/s²,
//! default 0) and prints one JSON object: `eigenvalues` (λ = ω², rad²/s²), `residuals`,
//! `wall_seconds` (factorisation + eigensolver, without reading the files), `factor_seconds`,
//! `n_dof`, `factor_values`, `operator_applications`. Exit status 1 with the message on stderr
//! on failure.

use std::path::PathBuf;
use std::time::Instant;

use nlrom::eigen::{EigenOptions, ShiftInvert};
use nlrom::matrix_io::read_real_matrix;

/// Parses the command line and runs; errors are messages for stderr.
fn run() -> Result<serde_json::Value, String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = PathBuf::from(args.first().ok_or("usage: eigen_mtx DIR [N] [SHIFT]")?);
    let n: usize = match args.get(1) {
        Some(s) => s.parse().map_err(|e| format!("N = {s:?}: {e}"))?,
        None => 20,
    };
    let shift: f64 = match args.get(2) {
        Some(s) => s.parse().map_err(|e| format!("SHIFT = {s:?}: {e}"))?,
        None => 0.0,
    };
    let k = read_real_matrix(&dir.join("K.mtx")).map_err(|e| e.to_string())?;
    let m = read_real_matrix(&dir.join("M.mtx")).map_err(|e| e.to_string())?;
    let start = Instant::now();
    let si = ShiftInvert::new(k.as_ref(), m.as_ref(), shift).map_err(|e| e.to_string())?;
    let factor_seconds = start.elapsed().as_secs_f64();
    let opts = EigenOptions {
        shift,
        ..EigenOptions::default()
    };
    let modes = si.lowest_modes(n, &opts).map_err(|e| e.to_string())?;
    Ok(serde_json::json!({
        "eigenvalues": modes.eigenvalues,
        "residuals": modes.residuals,
        "wall_seconds": start.elapsed().as_secs_f64(),
        "factor_seconds": factor_seconds,
        "n_dof": si.n_dof(),
        "factor_values": si.factor_len(),
        "operator_applications": modes.operator_applications,
    }))
}

fn main() {
    match run() {
        Ok(json) => println!("{json}"),
        Err(msg) => {
            eprintln!("eigen_mtx: {msg}");
            std::process::exit(1);
        }
    }
}
