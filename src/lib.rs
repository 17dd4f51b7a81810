//! # nlrom — nonlinear reduced-order models of structures with friction contacts
//!
//! One pipeline in four stages; data flows one way through the modules:
//!
//! | stage | module | what it holds |
//! |---|---|---|
//! | 1 import | [`mesh`] | Gmsh MSH 2.2/4.1 reader, physical groups, boundary faces |
//! | 1 import | [`matrix_io`] | Matrix Market matrices and the DOF map (`dofs.csv`) |
//! | 1 model | [`fe`] | 3-D elasticity: shape functions, quadrature, parallel assembly of K and M, clamping |
//! | 1 model | [`model`] | the structural model of a case: assembled or imported K, M after clamping |
//! | 1–2 modal | [`eigen`] | sparse shift-invert eigensolver K φ = λ M φ (lowest modes), reusable factorisation |
//! | 2 cyclic | [`cyclic`] | cyclic-symmetry geometry: sector rotation R_α, frontier node pairing, harmonic indices k_n |
//! | 2 reduction | [`reduction`] | Craig–Bampton (streamed static modes), cyclic transform per k, GSI, the ROM of a case |
//! | 2 ROM | [`rom`] | the reduced-order model per harmonic index: matrices and reduced-DOF description |
//! | 3 contact | [`contact`] | friction contact law, AFT evaluation, analytic Jacobians, contact pairs |
//! | — | [`march`] | time marching: Newmark, adaptive step, piecewise-linear Newmark, quasi-static (Gastaldi & Berruti 2018) |
//! | 3 contact | [`sama`] | contact pairs: target placement, projection, SAMA weights (eqs 28–32), node-to-node |
//! | 3–4 | [`harmonics`] | real harmonic layout (conventions §4) and the `HarmonicForce` interface |
//! | 5 output | [`output`] | HDF5 files: the ROM file and the results file (atomic writes, h5py-readable) |
//! | 4 | [`hbm`] | harmonic balance: per-harmonic dynamic stiffness, condensation on the nonlinear DOFs, residual, Newton |
//! | 4 | [`continuation`] | pseudo-arc-length continuation in ω (or the excitation level) through folds |
//! | 4–5 | [`pipeline`] | the commands `reduce`, `solve`, `run`, `batch`, `demo`: ROM reuse, sweeps in parallel, results file, summary (resonance, Q) |
//! | 4 | [`solve`] | the harmonic balance problem of a reduced sector: ROM per k_n, contact pairs, engine-order excitation |
//! | — | [`case`] | the TOML case file (`docs/case-file.md`) |
//! | — | [`cli`] | the command line |
//!
//! The user documentation (case file, results file, theory, validation) is in `docs/`.

pub mod case;
pub mod cli;
pub mod contact;
pub mod continuation;
pub mod cyclic;
pub mod eigen;
pub mod error;
pub mod fe;
pub mod harmonics;
pub mod hbm;
pub mod march;
pub mod matrix_io;
pub mod mesh;
pub mod model;
pub mod nonlinear;
pub mod output;
pub mod pipeline;
pub mod reduction;
pub mod rom;
pub mod sama;
pub mod solve;

pub use error::{Error, Result};
