//! Friction contact elements with normal load variation (SAMA paper, Battiato 2021, §3), their
//! evaluation on harmonic vectors by the alternating frequency/time method, and analytic
//! Jacobians.
//!
//! * [`law`]: the single-sample time-discrete law (normal force, stick/slip/separation with slider
//!   memory, 1-D and 2-D variants) and its partial derivatives.

pub mod law;
