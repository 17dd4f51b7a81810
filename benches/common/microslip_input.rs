//! The element and motions of the microslip benchmarks, shared by `benches/microslip.rs` and
//! `tools/benchmarks/contact_cost.rs`.

use nlrom::contact::element::LocalElement;
use nlrom::contact::law::{ContactParams, Variant};

/// The element: k_t = 2, k_n = 5, μ = 0.4, n0 = 0.7, one tangential direction and the normal
/// (1-D law).
pub fn microslip_element() -> LocalElement {
    LocalElement {
        params: ContactParams::new(2.0, 5.0, 0.4, 0.7, "bench").unwrap(),
        variant: Variant::OneD,
        tangential: 1,
        normal: true,
    }
}

/// The regimes of the benchmarks (Cigeroglu, An & Menq 2007, §2.2), each with its local input
/// `[U0, U1, U2, V0, V1, V2]` at H = 1: u = a sin τ, v = 0.01 + b sin(τ + 2) with (a, b) =
/// (0.1, 0) complete stick (a below μ n0 / k_t = 0.14), (0.7, 0) stick–slip at constant load
/// (Jenkins), (0.7, 0.084) stick–slip with normal load variation (k_n b = 0.42 below
/// n0 + k_n V0 = 0.75: contact kept) and (0.7, 0.224) stick–slip–separation (k_n b = 1.12).
pub fn microslip_motions() -> [(&'static str, [f64; 6]); 4] {
    let motion = |a: f64, b: f64| [0.0, 0.0, -a, 0.01, b * 2f64.sin(), -b * 2f64.cos()];
    [
        ("stick", motion(0.1, 0.0)),
        ("jenkins", motion(0.7, 0.0)),
        ("stickslip", motion(0.7, 0.084)),
        ("separation", motion(0.7, 0.224)),
    ]
}
