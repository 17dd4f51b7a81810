//! The march's view of the time-discrete friction law of [`crate::contact::law`] (the same law and
//! parameters as the harmonic balance; `docs/theory.md`, "The friction contact element"): one
//! tangential direction with normal load variation, and the contact state of Gastaldi & Berruti
//! 2018 Table 1 (lift-off, stick, slip with its sign) that the piecewise-linear schemes predict and
//! verify.

use crate::contact::law::{normal_force, tangential_1d, Regime};

/// Friction parameters k_t (N/m), k_n (N/m), μ, n0 (N) — the contact module's.
pub use crate::contact::law::ContactParams as FrictionParams;

/// Direction of slip.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sign {
    /// f_t = +μ f_n.
    Positive,
    /// f_t = −μ f_n.
    Negative,
}

impl Sign {
    /// +1 or −1.
    pub fn value(self) -> f64 {
        match self {
            Sign::Positive => 1.0,
            Sign::Negative => -1.0,
        }
    }
}

/// The contact state of an element in one sample (paper Table 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ContactState {
    /// Lift-off: no force.
    Separated,
    /// Stick: f_t = k_t (u_t − w).
    Stick,
    /// Slip: f_t = ±μ f_n.
    Slip(Sign),
}

impl ContactState {
    /// Integer code stored in the results: 0 separated, 1 stick, 2 slip +, 3 slip −.
    pub fn code(self) -> u8 {
        match self {
            ContactState::Separated => 0,
            ContactState::Stick => 1,
            ContactState::Slip(Sign::Positive) => 2,
            ContactState::Slip(Sign::Negative) => 3,
        }
    }
}

/// The law's output for one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LawSample {
    /// Friction force f_t (N, internal-force sign: a stuck element is the spring k_t (u_t − w)).
    pub f_t: f64,
    /// Normal force f_n ≥ 0 (N).
    pub f_n: f64,
    /// The state the sample is in.
    pub state: ContactState,
    /// The slider position after the sample (m).
    pub slider: f64,
}

/// One sample of the law at tangential displacement `ut` (m), normal approach `v` (m; `None`:
/// constant normal load max(n0, 0)) and slider `w` (m) from the previous sample:
/// f_n = max(n0 + k_n v, 0), then [`tangential_1d`] with the limit μ f_n.
pub fn sample(p: &FrictionParams, ut: f64, v: Option<f64>, w: f64) -> LawSample {
    let f_n = normal_force(p, v.unwrap_or(0.0));
    let (f_t, slider, regime) = tangential_1d(p.kt, p.mu * f_n, f_n <= 0.0, ut, w);
    let state = match regime {
        Regime::Separation => ContactState::Separated,
        Regime::Stick => ContactState::Stick,
        Regime::Slip if f_t.is_sign_negative() => ContactState::Slip(Sign::Negative),
        Regime::Slip => ContactState::Slip(Sign::Positive),
    };
    LawSample {
        f_t,
        f_n,
        state,
        slider,
    }
}
