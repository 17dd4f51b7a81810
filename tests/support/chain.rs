//! Fixed–free spring chains of unit masses (node j = 1..n, spring k between neighbours and to
//! the fixed end), whose modes are known in closed form: φ_r(j) = 2/√(2n+1) sin((2r − 1)πj/(2n+1))
//! (mass-normalised) and ω_r² = 4k sin²((2r − 1)π/(2(2n+1))); and the Matrix Market and TOML
//! text of the matrix cases built on them.

use std::f64::consts::PI;
use std::path::Path;

/// Mass-normalised mode r ≥ 1 of a chain of n nodes at node j ∈ 1..=n.
pub fn mode(n: usize, r: usize, j: usize) -> f64 {
    let m = (2 * n + 1) as f64;
    2.0 / m.sqrt() * ((2 * r - 1) as f64 * PI * j as f64 / m).sin()
}

/// ω_r² (rad²/s²) of a chain of n nodes with springs k.
pub fn omega2(n: usize, k: f64, r: usize) -> f64 {
    let s = ((2 * r - 1) as f64 * PI / (2 * (2 * n + 1)) as f64).sin();
    4.0 * k * s * s
}

/// The spring k of a chain of n nodes whose first mode is at `w1` (rad/s).
pub fn spring_for(n: usize, w1: f64) -> f64 {
    let s = (PI / (2 * (2 * n + 1)) as f64).sin();
    (w1 / (2.0 * s)).powi(2)
}

/// The stiffness entries (row, column, value; lower triangle, 0-based) of a chain of n nodes with
/// springs k on rows `offset..offset + n`.
pub fn stiffness(n: usize, k: f64, offset: usize) -> Vec<(usize, usize, f64)> {
    let mut out = Vec::new();
    for j in 0..n {
        let row = offset + j;
        out.push((row, row, if j + 1 < n { 2.0 * k } else { k }));
        if j + 1 < n {
            out.push((row + 1, row, -k));
        }
    }
    out
}

/// Writes a symmetric n × n Matrix Market file of the lower-triangle `entries` (0-based).
pub fn write_mtx(path: &Path, n: usize, entries: &[(usize, usize, f64)]) {
    let mut t = format!(
        "%%MatrixMarket matrix coordinate real symmetric\n{n} {n} {}\n",
        entries.len()
    );
    for (i, j, v) in entries {
        t.push_str(&format!("{} {} {v:e}\n", i + 1, j + 1));
    }
    std::fs::write(path, t).unwrap();
}

/// A TOML array of the items.
pub fn list(v: impl IntoIterator<Item = String>) -> String {
    format!("[{}]", v.into_iter().collect::<Vec<_>>().join(", "))
}
