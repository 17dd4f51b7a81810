//! The local input of the contact element benchmark, shared by `benches/contact.rs` and
//! `examples/contact_cost.rs`.

/// Local input of a 3-D element: u1, u2 of amplitude ~0.1 (stick limit 0.05), v of 0.01.
pub fn input(h: usize) -> Vec<f64> {
    let m = 2 * h + 1;
    let mut x = vec![0.0; 3 * m];
    for (c, a) in [0.1, 0.08, 0.01].into_iter().enumerate() {
        x[c * m + 1] = a;
        x[c * m + 2] = 0.3 * a * (c as f64 - 1.0);
        for n in 2..=h {
            x[c * m + 2 * n - 1] = 0.1 * a / n as f64;
        }
    }
    x
}
