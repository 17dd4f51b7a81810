//! Independent assembly of linear contact springs for reference solutions.

use faer::{c64, Mat};

/// K_c += Lᴴ G L for one spring: `l` lists (matrix row, the 3 global components of the relative
/// displacement r that a unit value of that row produces), `g(a, b)` is the spring's global
/// 3×3 stiffness Fᵀ diag(k) F (N/m).
pub fn add_spring(kc: &mut Mat<c64>, l: &[(usize, [c64; 3])], g: impl Fn(usize, usize) -> f64) {
    for &(ri, li) in l {
        for &(rj, lj) in l {
            let mut v = c64::new(0.0, 0.0);
            for (a, la) in li.iter().enumerate() {
                for (b, lb) in lj.iter().enumerate() {
                    v += la.conj() * g(a, b) * lb;
                }
            }
            kc[(ri, rj)] += v;
        }
    }
}
