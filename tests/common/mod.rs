//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod cli;
pub mod python;
pub mod sector_hb;
pub mod springs;
