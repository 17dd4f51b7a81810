//! Stage 4 on a mesh case: the harmonic balance problem of one reduced sector with its friction
//! interfaces (SAMA paper, Battiato 2021, §2 eqs 10–12 and §5 eqs 33–34).
//!
//! [`sector::SectorProblem`] ties the ROM of every harmonic index k_n = n·m mod N
//! ([`crate::rom::Rom`]), the contact pairs of every `[[contact]]` ([`crate::sama`]) and the
//! engine-order excitation into the [`crate::hbm::LinearModel`] + [`crate::contact::pairs::PairSet`]
//! that [`crate::hbm::HbmSystem`] and [`crate::continuation`] solve.

pub mod sector;

pub use sector::{DofLabel, SectorProblem};
