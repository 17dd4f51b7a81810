//! Time marching for systems with friction contacts (Gastaldi & Berruti, "Competitive time marching
//! solution methods for systems with friction-induced nonlinearities", Appl. Sci. 2018).
//!
//! M q̈ + C q̇ + K q = f_e(t) + f_c(q, t) (eq. 1) is marched by
//! - standard Newmark-β (β = 1/4, γ = 1/2) with the predictor–corrector of Appendix A.3;
//! - the same with the time step adapted to the contact state (§4.2, eq. 8);
//! - piecewise-linear Newmark (§4.3, Appendix A.4), optionally with the adaptive step;
//! - the quasi-static method (§5.2, eq. 10, Appendix B).
//!
//! | module | what |
//! |---|---|
//! | [`signal`] | static + first-harmonic signals (forces, prescribed motions) |
//! | [`law`] | the time-discrete friction law of one sample |
//! | [`element`] | friction elements on DOF combinations and their piecewise-linear form (Table 1) |
//! | [`system`] | the marched model (dense M, C, K, forces, elements), shortest period (eq. 8) |
//! | [`schemes`] | one step of each scheme |
//! | [`lowrank`] | a state's step matrix as a low-rank change of the all-stick one |
//! | [`adaptive`] | the adaptive step (eq. 8): the states' shortest periods, the step ladder |
//! | [`integrate`] | the time loop, records, counts |
//! | [`periodic`] | steady-state detection and harmonics of the last period |
//! | [`dense`] | small dense linear algebra |
//! | [`obstacle`] | rigid obstacles with unilateral contact, the nonsmooth (thermo-mechanical) model, records |
//! | [`lcp`] | the per-step linear complementarity problem: Lemke, enumeration |
//! | [`moreau_jean`] | the Moreau–Jean θ-method (Thorin et al. 2018, eqs 12–18) |
//! | [`carpenter`] | Carpenter's explicit forward-increment Lagrange multiplier scheme (Carpenter et al. 1991) |
//! | [`reduced`] | the nonsmooth model projected on a (Craig–Bampton) basis |
//!
//! The march of a case file (a `[damper]`, a model on matrix rows, a reduced sector) is built by
//! [`crate::problem::march_case`].

pub mod adaptive;
pub mod carpenter;
pub mod dense;
pub mod element;
pub mod integrate;
pub mod law;
pub mod lcp;
pub mod lowrank;
pub mod moreau_jean;
pub mod obstacle;
pub mod periodic;
pub mod reduced;
pub mod schemes;
pub mod signal;
pub mod system;

pub use integrate::{march, MarchHistory, MarchOutcome, MarchSettings, Marcher, PeriodSummary};
pub use system::{InitialCondition, MarchSystem};
