//! Linear heat conduction and thermoelastic coupling on the volume elements of [`super::shape`]:
//! the temperature rise θ (K, above the stress-free reference temperature) is interpolated with
//! the same shape functions Nₐ as the displacement, one temperature DOF per node. The matrices
//! of the semi-discrete thermoelastic model of Thorin, Guérin, Legrand, Thouverez & Almeida (ASME
//! GT2018-75959, 2018, eqs 1 and 4; their ANSYS SOLID226 element uses the same interpolation):
//!
//! - heat capacity C^θθ_ab = ∫ ρ c_p Nₐ N_b dV (J/K), the scalar consistent mass with ρ → ρc_p;
//! - conductance K^θθ_ab = ∫ k ∇Nₐ·∇N_b dV (W/K);
//! - coupling K^uθ_(a,i),b = −∫ β ∂ᵢNₐ N_b dV (N/K), β = (3λ + 2μ) α_th = E α_th/(1 − 2ν) (Pa/K),
//!   from σ = D(ε − α_th θ I): the mechanical equation is M ü + C u̇ + K u + K^uθ θ = f, so a
//!   uniform θ > 0 expands a free body by ε = α_th θ I with zero stress.
//!
//! Quadrature: the mass rule of the type for C^θθ and K^uθ (integrand degrees 2p and 2p − 1 on
//! affine elements) and the stiffness rule for K^θθ (degree 2p − 2), so all three are exact on
//! straight-sided elements.
//!
//! [`Capacity::Lumped`] replaces each element's C^θθ by its HRZ diagonal (Hinton, Rock &
//! Zienkiewicz, Earthquake Eng. Struct. Dyn. 4, 1976): C_aa ← C_aa · ρc_pV_e / Σ_b C_bb, which
//! keeps the element's total ρc_pV_e and is positive on every element type (the row sums of the
//! serendipity hexa20, prism15 and pyramid13 are negative at the corner nodes). A nodal heat
//! input Q then raises its node at Q/C_aa and no other node, so a heated node is never cooled
//! by the capacity coupling (the consistent C^θθ of a quadratic element pulls the neighbours of
//! a heated corner node below zero and concentrates the rise on that corner).

use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use super::element::{bad_element, gradients, mass_scalar, table, Tabulated};
use super::material::Materials;
use super::Quadrature;
pub use crate::case::Capacity;
use crate::error::{Error, Result};
use crate::mesh::{ElementType, Mesh};

/// Thermal properties of an isotropic material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThermalMaterial {
    /// Conductivity k (W/(m·K)), ≥ 0.
    pub conductivity: f64,
    /// Specific heat c_p (J/(kg·K)), > 0.
    pub specific_heat: f64,
    /// Linear expansion coefficient α_th (1/K).
    pub expansion: f64,
    /// The capacity matrix C^θθ: consistent or HRZ-lumped (module doc).
    pub capacity: Capacity,
}

impl ThermalMaterial {
    /// Checks the ranges; `what` names the material in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        if !(self.conductivity >= 0.0 && self.conductivity.is_finite()) {
            return Err(Error::input(format!(
                "{what}: conductivity must be ≥ 0 W/(m K) (found {})",
                self.conductivity
            )));
        }
        if !(self.specific_heat > 0.0 && self.specific_heat.is_finite()) {
            return Err(Error::input(format!(
                "{what}: specific_heat must be > 0 J/(kg K) (found {})",
                self.specific_heat
            )));
        }
        if !self.expansion.is_finite() {
            return Err(Error::input(format!(
                "{what}: expansion must be finite (found {})",
                self.expansion
            )));
        }
        Ok(())
    }
}

/// The thermal matrices of one element (node-major, Gmsh node order).
#[derive(Clone, Debug)]
pub struct ThermalElement {
    /// Conductance K^θθ (nn × nn, W/K).
    pub conductance: Mat<f64>,
    /// Capacity C^θθ (nn × nn, J/K).
    pub capacity: Mat<f64>,
    /// Coupling K^uθ (3nn × nn, N/K), row 3a + i.
    pub coupling: Mat<f64>,
}

/// ∫ ∇Nₐ·∇N_b dV (nn × nn) and ∫ ∂ᵢNₐ N_b dV (3nn × nn) with the rules `ts` (stiffness) and
/// `tm` (mass).
fn integrals(
    ts: &Tabulated,
    tm: &Tabulated,
    xs: &[[f64; 3]],
) -> std::result::Result<(Vec<f64>, Vec<f64>), super::element::BadJacobian> {
    let nn = ts.nn;
    let mut grads = vec![[0.0; 3]; nn];
    let mut lap = vec![0.0; nn * nn];
    for q in 0..ts.nq() {
        let w = ts.weights[q] * gradients(ts, q, xs, &mut grads)?;
        for a in 0..nn {
            for b in 0..nn {
                let g = grads[a][0] * grads[b][0]
                    + grads[a][1] * grads[b][1]
                    + grads[a][2] * grads[b][2];
                lap[a * nn + b] += w * g;
            }
        }
    }
    let mut div = vec![0.0; 3 * nn * nn];
    for q in 0..tm.nq() {
        let w = tm.weights[q] * gradients(tm, q, xs, &mut grads)?;
        let n = &tm.n[q * nn..(q + 1) * nn];
        for a in 0..nn {
            for i in 0..3 {
                let wg = w * grads[a][i];
                for b in 0..nn {
                    div[(3 * a + i) * nn + b] += wg * n[b];
                }
            }
        }
    }
    Ok((lap, div))
}

/// The thermal matrices of one element with node coordinates `xs` (m), density ρ (kg/m³),
/// β = E α_th/(1 − 2ν) (Pa/K) and the thermal material `th` (module doc).
pub fn element_thermal(
    kind: ElementType,
    xs: &[[f64; 3]],
    density: f64,
    beta: f64,
    th: &ThermalMaterial,
    quad: &Quadrature,
) -> Result<ThermalElement> {
    th.validate("element thermal material")?;
    let ts = table(kind, xs, quad.stiffness_degree, true)?;
    let tm = table(kind, xs, quad.mass_degree, false)?;
    let nn = ts.nn;
    let (lap, div) = integrals(&ts, &tm, xs).map_err(|b| bad_element(kind, b))?;
    let mut cap = vec![0.0; nn * nn];
    mass_scalar(&tm, xs, density * th.specific_heat, &mut cap).map_err(|b| bad_element(kind, b))?;
    if th.capacity == Capacity::Lumped {
        lump_hrz(&mut cap, nn);
    }
    Ok(ThermalElement {
        conductance: Mat::from_fn(nn, nn, |a, b| th.conductivity * lap[a * nn + b]),
        capacity: Mat::from_fn(nn, nn, |a, b| cap[a * nn + b]),
        coupling: Mat::from_fn(3 * nn, nn, |r, b| -beta * div[r * nn + b]),
    })
}

/// Replaces the symmetric nn × nn matrix `c` (row-major) by its HRZ diagonal: c_aa · Σ_ab c_ab /
/// Σ_b c_bb, zero off the diagonal (module doc).
fn lump_hrz(c: &mut [f64], nn: usize) {
    let total: f64 = c[..nn * nn].iter().sum();
    let trace: f64 = (0..nn).map(|a| c[a * nn + a]).sum();
    let diagonal: Vec<f64> = (0..nn).map(|a| c[a * nn + a] * total / trace).collect();
    c[..nn * nn].fill(0.0);
    for (a, d) in diagonal.into_iter().enumerate() {
        c[a * nn + a] = d;
    }
}

/// The assembled thermal matrices over all nodes (temperature DOF i = node index i; mechanical
/// DOF 3i + c as in [`super::assemble`]).
#[derive(Clone, Debug)]
pub struct ThermalAssembled {
    /// Conductance K^θθ (n × n, W/K).
    pub conductance: SparseColMat<usize, f64>,
    /// Capacity C^θθ (n × n, J/K).
    pub capacity: SparseColMat<usize, f64>,
    /// Coupling K^uθ (3n × n, N/K).
    pub coupling: SparseColMat<usize, f64>,
}

/// Assembles K^θθ, C^θθ and K^uθ over every volume element of `mesh`, with the elastic material
/// of each volume from `materials` (E, ν, ρ) and the thermal properties `th` everywhere.
/// Errors as [`super::assemble`] (no volume element, unsupported type, missing material,
/// non-positive Jacobian), and invalid thermal data.
pub fn assemble_thermal(
    mesh: &Mesh,
    materials: &Materials,
    th: &ThermalMaterial,
    quad: &Quadrature,
) -> Result<ThermalAssembled> {
    th.validate(&format!("{}: thermal material", mesh.source_name()))?;
    materials.validate(mesh)?;
    let n = mesh.num_nodes();
    let (mut kt, mut ct, mut ku) = (Vec::new(), Vec::new(), Vec::new());
    let mut volumes = 0;
    for block in mesh.blocks.iter().filter(|b| b.kind.dim() == 3) {
        let mat = materials.for_block(mesh, block)?;
        let beta = mat.young * th.expansion / (1.0 - 2.0 * mat.poisson);
        for e in 0..block.len() {
            let nodes = block.element(e);
            let xs: Vec<[f64; 3]> = nodes
                .iter()
                .map(|&i| mesh.coords.get(i as usize).copied())
                .collect::<Option<_>>()
                .ok_or_else(|| {
                    Error::input(format!(
                        "{}: element {} has a node index out of range",
                        mesh.source_name(),
                        block.tags.at(e)
                    ))
                })?;
            let el =
                element_thermal(block.kind, &xs, mat.density, beta, th, quad).map_err(|err| {
                    Error::input(format!(
                        "{}: element {}: {err}",
                        mesh.source_name(),
                        block.tags.at(e)
                    ))
                })?;
            for (a, &i) in nodes.iter().enumerate() {
                for (b, &j) in nodes.iter().enumerate() {
                    let (i, j) = (i as usize, j as usize);
                    kt.push(Triplet::new(i, j, el.conductance[(a, b)]));
                    ct.push(Triplet::new(i, j, el.capacity[(a, b)]));
                    for c in 0..3 {
                        ku.push(Triplet::new(3 * i + c, j, el.coupling[(3 * a + c, b)]));
                    }
                }
            }
            volumes += 1;
        }
    }
    if volumes == 0 {
        return Err(Error::input(format!(
            "{}: the mesh has no volume (3-D) elements to assemble",
            mesh.source_name()
        )));
    }
    let build = |rows: usize, t: &[Triplet<usize, usize, f64>]| {
        SparseColMat::try_new_from_triplets(rows, n, t)
            .map_err(|e| Error::Compute(format!("thermal assembly: {e:?}")))
    };
    Ok(ThermalAssembled {
        conductance: build(n, &kt)?,
        capacity: build(n, &ct)?,
        coupling: build(3 * n, &ku)?,
    })
}
