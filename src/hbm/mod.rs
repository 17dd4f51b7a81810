//! Multi-harmonic balance (stage 4): the linear part per harmonic condensed on the nonlinear
//! DOFs, the residual and its Jacobian in the real layout, Newton, and the recovery of the
//! response at the output DOFs.
//!
//! Source: SAMA paper (Battiato 2021) §2–3, eqs. 10–27; `docs/theory.md` "Harmonic balance" and
//! "Continuation"; real layout `docs/conventions.md` §4.
//!
//! - [`linear`]: [`LinearModel`] — per harmonic n the dynamic stiffness D⁽ⁿ⁾(ω) of its harmonic
//!   index, condensed per frequency (eqs. 15–18), with its ω-derivative;
//! - [`system`]: [`HbmSystem`] — r(Q, ω) = D̄(ω) Q − F̄_e(ω) + F_nl(Q) (eq. 19) and ∂r/∂Q (eq. 21),
//!   and the [`ParameterSystem`](crate::nonlinear::ParameterSystem) views [`FrequencyPath`]
//!   (λ = ω), [`FixedFrequencyPath`] (λ = excitation level, or the factor on the nonlinear
//!   force, at fixed ω) and [`PreloadPath`] (λ = the force's parameter, e.g. the preload n0, at
//!   fixed ω);
//! - [`modal`]: [`modal::ModalModel`] and [`modal::ModalForce`] — the linear part given by m
//!   modes and the contact force projected on them, the m(2H + 1) modal harmonics as unknowns;
//! - [`response`]: harmonics, amplitude and peak of the output DOFs at a solution;
//! - [`frf`]: a frequency response (continuation + recovery);
//! - [`stability`]: Hill's method on the uncondensed model — Floquet exponents and a `stable`
//!   flag per solution point;
//! - [`preload`]: [`preload::FromStaticEquilibrium`] — contact forces measured from the preloaded
//!   static equilibrium (the balancing static load of the uncoupled approach, SAMA paper §6.1).
//!
//! The generic [`ParameterSystem`](crate::nonlinear::ParameterSystem) and Newton are in
//! [`crate::nonlinear`], path following in [`crate::continuation`].

pub mod frf;
pub mod linear;
pub mod modal;
pub mod preload;
pub mod response;
pub mod stability;
pub mod system;

pub use linear::{Condensed, LinearModel, MatrixBlock, Uncondensed};
pub use response::{OutputResponse, ResponseOptions};
pub use system::{
    FixedFrequencyParameter, FixedFrequencyPath, FrequencyPath, HbmSystem, PreloadPath,
};
