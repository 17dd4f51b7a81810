//! Helpers shared by the integration tests (`mod support;` in a test file): the CLI runner, the
//! batch test cases,
//! Python (h5py) runner, deterministic random generators, the contact-law checks, the cyclic
//! full-annulus reference, the harmonic balance test nonlinearities and small models.
#![allow(dead_code)]

pub mod batch;
pub mod chain;
pub mod cli;
pub mod contact;
pub mod cyclic;
pub mod hbm;
pub mod python;
pub mod random;
pub mod sector_hb;
pub mod springs;
