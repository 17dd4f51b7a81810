//! The single-sample time-discrete friction law used by the march (`methods.md`, "Node-to-node
//! contact element with normal load variation"; Gastaldi & Berruti 2018 §3, Table 1).
//!
//! f_n = max(n0 + k_n v, 0). If f_n = 0: separation, f_t = 0, slider w ← u_t. Else the trial force
//! f_tr = k_t (u_t − w): stick if |f_tr| ≤ μ f_n (f_t = f_tr, w unchanged), otherwise slip with
//! f_t = μ f_n sgn(f_tr) and w ← u_t − f_t/k_t.

/// Friction parameters of one element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionParams {
    /// Tangential contact stiffness k_t (N/m).
    pub kt: f64,
    /// Normal contact stiffness k_n (N/m).
    pub kn: f64,
    /// Friction coefficient μ.
    pub mu: f64,
    /// Static normal load n0 (N); negative: initial gap −n0/k_n.
    pub n0: f64,
}

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
    /// Friction force f_t (N).
    pub f_t: f64,
    /// Normal force f_n ≥ 0 (N).
    pub f_n: f64,
    /// The state the sample is in.
    pub state: ContactState,
    /// The slider position after the sample (m).
    pub slider: f64,
}

/// One sample of the law at tangential displacement `ut` (m), normal approach `v` (m; `None`:
/// constant normal load n0) and slider `w` (m) from the previous sample.
pub fn sample(p: &FrictionParams, ut: f64, v: Option<f64>, w: f64) -> LawSample {
    let f_n = match v {
        Some(v) => (p.n0 + p.kn * v).max(0.0),
        None => p.n0.max(0.0),
    };
    if f_n <= 0.0 {
        return LawSample {
            f_t: 0.0,
            f_n: 0.0,
            state: ContactState::Separated,
            slider: ut,
        };
    }
    let trial = p.kt * (ut - w);
    let limit = p.mu * f_n;
    if trial.abs() <= limit {
        return LawSample {
            f_t: trial,
            f_n,
            state: ContactState::Stick,
            slider: w,
        };
    }
    let sign = if trial > 0.0 {
        Sign::Positive
    } else {
        Sign::Negative
    };
    let f_t = sign.value() * limit;
    LawSample {
        f_t,
        f_n,
        state: ContactState::Slip(sign),
        slider: ut - f_t / p.kt,
    }
}
