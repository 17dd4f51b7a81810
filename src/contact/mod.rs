//! Friction contact elements with normal load variation (SAMA paper, Battiato 2021, §3), their
//! evaluation on harmonic vectors by the alternating frequency/time method, and analytic
//! Jacobians.
//!
//! * [`law`]: the single-sample time-discrete law (normal force, stick/slip/separation with slider
//!   memory, 1-D and 2-D variants) and its partial derivatives.
//! * [`aft`]: realfft transforms between the real harmonic layout and time samples.
//! * [`element`]: one element over a period — periodic marching, forces, the analytic Jacobian,
//!   stick/slip/separation fractions, dissipated energy, hysteresis loop.
//! * [`kinematics`]: relative harmonics of a pair with the inter-sector rotation and phase.
//! * [`pairs`]: [`pairs::PairSet`], node-to-node pairs on physical DOFs as a
//!   [`HarmonicForce`](crate::harmonics::HarmonicForce) (parallel over pairs).
//! * [`grounded`]: [`grounded::DofElements`], the `[[element]]` friction elements on DOF
//!   combinations of a matrix model as a `HarmonicForce`.
//! * [`memoryless`]: springs, dampers and regularised friction whose force is a function of one
//!   coordinate's value and rate (cubic, polynomial, unilateral with gap, quadratic damper, tanh
//!   friction), used by [`grounded::DofElements`] next to the friction elements.
//! * `assembly`: the parallel evaluate-and-sum loop shared by the two.
//! * [`slip_map`]: stick–slip–separation maps of a set of points from their exact cycles.
//! * [`mapped`]: [`mapped::LinearMap`], elements reading linear combinations of the solved DOFs
//!   (SAMA's interpolated virtual target nodes).

pub mod aft;
pub(crate) mod assembly;
pub mod element;
pub mod grounded;
pub mod kinematics;
pub mod law;
pub mod mapped;
pub mod memoryless;
pub mod microslip;
pub mod pairs;
pub mod slip_map;
