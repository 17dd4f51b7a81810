//! Finite elements for 3-D linear isotropic elasticity: shape functions, quadrature, element
//! matrices, parallel sparse assembly of K and M, and clamped boundary conditions.
//!
//! The weak form of elastodynamics, discretised with isoparametric Lagrange/serendipity elements,
//! gives M q̈ + K q = f with
//! K = Σₑ ∫ Bᵀ D B dV (N/m) and M = Σₑ ∫ ρ Nᵀ N dV (kg) (consistent mass), D the isotropic
//! elasticity matrix of [`Material`] (Lamé λ, μ). DOF are those of `docs/conventions.md` §1: node index
//! i in ascending Gmsh tag order, DOF 3i + c (c = x, y, z), global Cartesian frame. The geometry is
//! interpolated from all nodes, so Gmsh's curved second-order elements stay curved (`docs/theory.md`,
//! "Finite elements").
//!
//! | module | what it holds |
//! |---|---|
//! | [`shape`] | shape functions and reference derivatives (Gmsh node order) |
//! | [`quadrature`] | Gauss–Legendre, Gauss–Jacobi, collapsed and symmetric simplex rules |
//! | [`element`] | element stiffness, mass and volume |
//! | [`material`] | [`Material`], [`Materials`] (per volume group) |
//! | [`assembly`] | [`assemble`] → [`Assembled`] (faer CSC, full symmetric storage) |
//! | [`bc`] | [`clamp`] → [`FreeModel`] (clamped DOF eliminated) |
//! | [`checks`] | mesh volume, total mass, rigid-body modes |
//! | [`structured`] | structured box meshes for tests and benchmarks |
//! | [`thermal`] | heat capacity, conductance and thermoelastic coupling (same shape functions) |
//!
//! ## Default quadrature
//!
//! Degree p means: exact for polynomials of total degree p on tetrahedra, of degree p in each
//! coordinate on hexahedra, p in (u, v) × p in w on prisms, p in each collapsed coordinate on
//! pyramids ([`quadrature::rule`]). The defaults are exact for the consistent mass (degree
//! 2 × order) and for the stiffness on straight-sided elements (tetrahedra and prisms with affine
//! geometry, parallelepiped hexahedra); on tetra10 both use the 14-point degree-5 rule to be safe on
//! curved elements (the integrand is then rational; a 4-point stiffness rule differs by ~1e-5 in
//! frequency on a coarse curved sector, `docs/theory.md`).
//!
//! | type | stiffness: degree, points | mass: degree, points |
//! |---|---|---|
//! | tetra4 | 1, 1 | 2, 4 |
//! | tetra10 | 5, 14 (Walkington) | 5, 14 |
//! | hexa8 | 2, 2×2×2 Gauss | 2, 2×2×2 |
//! | hexa20, hexa27 | 4, 3×3×3 Gauss | 4, 3×3×3 |
//! | prism6 | 2, 3-point triangle × 2 Gauss = 6 | 2, 6 |
//! | prism15, prism18 | 4, 7-point triangle × 3 Gauss = 21 | 4, 21 |
//! | pyramid5 | 2, collapsed 2×2×2 = 8 | 2, 8 |
//! | pyramid13 | 4, collapsed 3×3×3 = 27 | 4, 27 |
//!
//! [`Quadrature`] overrides the degree of either matrix for every element type, e.g.
//! `stiffness_degree: Some(2)` gives the 4-point tetra10 stiffness rule that many codes use.
//!
//! ## Typical use
//!
//! ```no_run
//! use nlrom::fe::{assemble, clamp, Material, Materials, Quadrature};
//! let mesh = nlrom::mesh::msh::read_msh("meshes/bar_tet10.msh".as_ref())?;
//! let steel = Material { young: 210e9, poisson: 0.3, density: 7800.0 };
//! let full = assemble(&mesh, &Materials::uniform(steel), &Quadrature::default())?;
//! let free = clamp(&full, &mesh, &["clamp".to_string()])?;
//! let dofs = free.dof_map(&mesh); // row → (node tag, component)
//! # Ok::<(), nlrom::Error>(())
//! ```

pub mod assembly;
pub mod bc;
pub mod checks;
pub mod element;
pub mod material;
pub mod quadrature;
pub mod shape;
pub mod structured;
pub mod thermal;

pub use assembly::{assemble, Assembled};
pub use bc::{clamp, eliminate, FreeModel};
pub use checks::{mesh_volume, rigid_body_modes, total_mass};
pub use element::{element_mass, element_stiffness, element_volume};
pub use material::{Material, Materials};

/// Quadrature degrees for the element matrices, for every element type; `None` keeps the default
/// of the type (see the table in the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Quadrature {
    /// Polynomial degree of the stiffness rule.
    pub stiffness_degree: Option<u32>,
    /// Polynomial degree of the mass rule.
    pub mass_degree: Option<u32>,
}
