//! # nlrom — nonlinear reduced-order models of structures with friction contacts
//!
//! One pipeline in four stages; data flows one way through the modules:
//!
//! | stage | module | what it holds |
//! |---|---|---|
//! | 1 import | [`mesh`] | Gmsh MSH 2.2/4.1 reader, physical groups, boundary faces |
//! | 1 import | [`matrix_io`] | Matrix Market matrices and the DOF map (`dofs.csv`) |
//! | — | [`case`] | the TOML case file of `interface.md` |
//! | — | [`cli`] | the command line |
//!
//! Later stages (FE assembly, sparse eigen, Craig–Bampton reduction, cyclic symmetry, contact,
//! SAMA, harmonic balance, continuation, time stepping, HDF5 output) get one module each as they
//! land; the README's status table says what works today.

pub mod case;
pub mod cli;
pub mod error;
pub mod matrix_io;
pub mod mesh;

pub use error::{Error, Result};
