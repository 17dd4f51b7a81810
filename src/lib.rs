//! # nlrom — nonlinear reduced-order models of structures with friction contacts
//!
//! The modules are layered: each may use only the modules listed above it in this table (the one
//! exception: [`error`] wraps the mesh reader's error type). `tests/layering.rs` checks every
//! `crate::` path of the compiled code against this order.
//!
//! | layer | module | what it holds |
//! |---|---|---|
//! | foundation | [`error`] | the error type, exit codes |
//! | foundation | [`vec3`] | 3-vector and 3×3-matrix helpers on plain arrays |
//! | foundation | [`mesh`] | Gmsh MSH 2.2/4.1 reader, physical groups, boundary faces |
//! | foundation | [`matrix_io`] | Matrix Market matrices and the DOF map (`dofs.csv`) |
//! | foundation | [`harmonics`] | real harmonic layout and the `HarmonicForce` interface |
//! | schema | [`case`] | the TOML case file: tables, validation, group checks, sweeps, [`case::Case::kind`] |
//! | model | [`cyclic`] | cyclic-symmetry geometry: sector rotation R_α, frontier node pairing, harmonic indices k_n |
//! | model | [`rom`] | the reduced-order model per harmonic index: matrices and reduced-DOF description |
//! | model | [`output`] | HDF5 files: the ROM file and the results file (atomic writes, h5py-readable) |
//! | model | [`fe`] | 3-D elasticity: shape functions, quadrature, parallel assembly of K and M, clamping |
//! | model | [`eigen`] | sparse shift-invert eigensolver K φ = λ M φ (lowest modes), reusable factorisation; dense eigenproblems and pencils |
//! | model | [`model`] | the structural model of a case: assembled or imported K, M after clamping; the damping matrix of a dense model |
//! | model | [`reduction`] | Craig–Bampton (streamed static modes), cyclic transform per k, GSI, the ROM of a case |
//! | contact | [`contact`] | friction contact law, AFT evaluation, analytic Jacobians, contact pairs |
//! | contact | [`interface`] | contact interfaces: target placement, projection, SAMA weights (Battiato 2021, eqs 28–32), node-to-node |
//! | solvers | [`nonlinear`] | r(x, λ) = 0: `ParameterSystem`, Newton |
//! | solvers | [`continuation`] | pseudo-arc-length continuation in ω (or the excitation level) through folds |
//! | solvers | [`hbm`] | harmonic balance: per-harmonic dynamic stiffness, condensation on the nonlinear DOFs, residual, stability |
//! | solvers | [`march`] | time marching: Newmark, adaptive step, piecewise-linear Newmark, quasi-static (Gastaldi & Berruti 2018) |
//! | problem | [`problem`] | a case as a solvable problem: ROM store, matrix case, reduced sector, damper, march of a case |
//! | commands | [`commands`] | one module per command (`mesh info`, `modes`, `export`, `reduce`, `contact`, `solve`/`run`, `march`, `batch`, `demo`), one `Reporter` (`-q`, `-v`), `--json` reports |
//! | commands | [`cli`] | the command line: clap definitions and the dispatch to [`commands`] |
//!
//! The user documentation (case file, results file, theory, validation) is in `docs/`.

pub mod case;
pub mod cli;
pub mod commands;
pub mod contact;
pub mod continuation;
pub mod cyclic;
pub mod eigen;
pub mod error;
pub mod fe;
pub mod harmonics;
pub mod hbm;
pub mod interface;
pub mod march;
pub mod matrix_io;
pub mod mesh;
pub mod model;
pub mod nonlinear;
pub mod output;
pub mod problem;
pub mod reduction;
pub mod rom;
pub mod vec3;

pub use error::{Error, Result};
