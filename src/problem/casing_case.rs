//! A mesh case with `[[casing]]` (and optionally `[thermal]`) tables as the model of the
//! nonsmooth schemes: the blade–casing contact of Thorin, Guérin, Legrand, Thouverez & Almeida
//! (ASME GT2018-75959, 2018, eqs 1–7).
//!
//! The generalised coordinates are x = [u; θ]: the free displacement DOF of the structural model
//! (m), then, with `[thermal]`, the temperature rise of every node not in `thermal.fixed` (K).
//! K^uu, M^uu and C^uu are the clamped model's (C from `model.damping`); C^θθ, K^θθ and K^uθ are
//! assembled by [`crate::fe::thermal`] (the same shape functions for u and θ).
//!
//! Each node i of a casing group becomes one obstacle ([`Obstacle`]): with the axis a (unit),
//! the node's initial position p_i, its radial vector r_i = (p_i − o) − ((p_i − o)·a) a, radius
//! r_i = |r_i| and e_r = r_i/r_i (taken at the initial position, so the gap holds for any tip shape
//! under small displacements):
//!
//! - gap g_i = g0_i − e_r·u_i (m), g0_i = R − r_i or the given `gap` (one value, or one per
//!   node); G_i = −e_rᵀ on the node's free displacement DOF;
//! - friction along t_i = −sgn(Ω) e_φ, e_φ = a × e_r: the casing slides past the blade at −RΩ e_φ
//!   and the sliding never reverses (the paper's eq. 3 prints the entry −μRΩ, which is not a
//!   force; the Coulomb force μλ is used);
//! - heat α λ_i into the node's temperature row (W for a force, J for an impulse).
//!
//! The load is `[excitation]`'s force per node of its group times cos ωt. The matrices are
//! gathered as sparse rows ([`CasingModel`]); the model marched without `[reduction]` is dense
//! (n ≤ [`MAX_DENSE_DOF`]). With `[reduction]` the rows are projected on a Craig–Bampton basis
//! ([`super::casing_rom`]) without forming a dense n × n matrix, so the size limit is that of
//! the reduced model and of the dense conduction modes of the temperature rows.

use std::collections::HashMap;

use super::matrix_case::damping_matrix;
use super::nonsmooth_case::{march_settings, NonsmoothCase};
use crate::case::{Case, Damping, ExcitationLoad};
use crate::error::{Error, Result};
use crate::fe::thermal::{assemble_thermal, ThermalMaterial};
use crate::fe::{Materials, Quadrature};
use crate::march::obstacle::{NonsmoothSystem, Obstacle};
use crate::march::signal::Harmonic;
use crate::mesh::Mesh;
use crate::model::StructuralModel;
use crate::output::ResponseDof;
use crate::vec3::{cross, dot, norm, scale, sub};

/// The largest number of DOF (displacements and temperatures) of the dense nonsmooth model.
pub const MAX_DENSE_DOF: usize = 6000;

/// The unit radial vector e_r and the radius r of point `p` about the axis through `o` along the
/// unit vector `a`; `None` on the axis.
pub fn radial(p: [f64; 3], o: [f64; 3], a: [f64; 3]) -> Option<([f64; 3], f64)> {
    let d = sub(p, o);
    let r = sub(d, scale(dot(d, a), a));
    let len = norm(r);
    (len > 0.0).then(|| (r.map(|x| x / len), len))
}

/// The full casing model of a case as sparse rows: the nonsmooth case whose system has empty
/// matrices, and M, C, K (n × n) as rows of (column, value) pairs (repeated columns add).
/// [`CasingModel::dense`] makes it the dense model the schemes march; a `[reduction]` projects the
/// rows without forming them ([`super::casing_rom::reduce_casing`]).
pub struct CasingModel {
    /// The case; `system.mass`, `damping` and `stiffness` are empty.
    pub case: NonsmoothCase,
    /// M.
    pub mass: Vec<Vec<(usize, f64)>>,
    /// C.
    pub damping: Vec<Vec<(usize, f64)>>,
    /// K.
    pub stiffness: Vec<Vec<(usize, f64)>>,
}

impl CasingModel {
    /// The dense model (n ≤ [`MAX_DENSE_DOF`]; `file` names the case in errors).
    pub fn dense(self, file: &str) -> Result<NonsmoothCase> {
        let CasingModel {
            mut case,
            mass,
            damping,
            stiffness,
        } = self;
        let (n, nm) = (case.system.n, case.system.n_mech);
        if n > MAX_DENSE_DOF {
            return Err(Error::input(format!(
                "{file}: the nonsmooth model has {n} DOF ({nm} displacements, {} temperatures); the dense schemes take at most {MAX_DENSE_DOF}: add a [reduction] table or use a coarser mesh",
                n - nm
            )));
        }
        let dense = |rows: &[Vec<(usize, f64)>]| {
            let mut a = vec![0.0; n * n];
            for (i, row) in rows.iter().enumerate() {
                for &(j, v) in row {
                    a[i * n + j] += v;
                }
            }
            a
        };
        case.system.mass = dense(&mass);
        case.system.damping = dense(&damping);
        case.system.stiffness = dense(&stiffness);
        case.system.validate(file)?;
        Ok(case)
    }
}

/// Builds the nonsmooth march of the mesh `case` with `[[casing]]` on its structural model `sm`
/// (module doc): dense, or reduced with `[reduction]`.
pub fn casing_case(case: &Case, sm: &StructuralModel) -> Result<NonsmoothCase> {
    let file = case.path.display().to_string();
    let model = casing_model(case, sm)?;
    match &case.reduction {
        Some(red) => super::casing_rom::reduce_casing(
            case,
            sm,
            red,
            model,
            super::casing_rom::Projection::Sparse,
        ),
        None => model.dense(&file),
    }
}

/// The full model of the mesh `case` with `[[casing]]` on its structural model `sm` as sparse
/// rows (module doc).
pub fn casing_model(case: &Case, sm: &StructuralModel) -> Result<CasingModel> {
    let file = case.path.display().to_string();
    let mesh = sm.mesh.as_ref().ok_or_else(|| {
        Error::input(format!(
            "{file}: key 'casing': a casing acts on mesh node groups; give `[model] mesh`"
        ))
    })?;
    if !case.element.is_empty() || !case.obstacle.is_empty() {
        return Err(Error::input(format!(
            "{file}: key 'casing': a mesh case with `[[casing]]` takes no `[[element]]` or `[[obstacle]]` on matrix rows"
        )));
    }
    let omega = case.march.as_ref().map_or(0.0, |m| m.omega());
    // Free displacement DOF of each (node index, component).
    let map = sm.free_dof_map().ok_or_else(|| {
        Error::input(format!(
            "{file}: the model has no DOF map relating its rows to the mesh nodes"
        ))
    })?;
    let index_of_tag: HashMap<u64, usize> = mesh
        .node_tags
        .iter()
        .enumerate()
        .map(|(i, &t)| (t, i))
        .collect();
    let mut mech_of: HashMap<(usize, usize), usize> = HashMap::new();
    for e in &map.entries {
        if let Some(&i) = index_of_tag.get(&e.node_tag) {
            mech_of.insert((i, e.component as usize), e.row);
        }
    }
    let nm = sm.free.n_free();
    // Thermal DOF.
    let thermal = match &case.thermal {
        Some(t) => Some(thermal_rows(case, sm, mesh, t)?),
        None => None,
    };
    let nt = thermal.as_ref().map_or(0, |t| t.nodes.len());
    let n = nm + nt;
    let mut stiffness = vec![Vec::new(); n];
    let mut mass = vec![Vec::new(); n];
    let mut damping = vec![Vec::new(); n];
    let push = |rows: &mut Vec<Vec<(usize, f64)>>,
                a: faer::sparse::SparseColMatRef<'_, usize, f64>,
                scale: f64| {
        for j in 0..a.ncols() {
            for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                rows[i].push((j, scale * v));
            }
        }
    };
    push(&mut stiffness, sm.free.k.as_ref(), 1.0);
    push(&mut mass, sm.free.m.as_ref(), 1.0);
    match case.model.damping.as_ref() {
        None => {}
        Some(Damping::Rayleigh { alpha, beta }) => {
            push(&mut damping, sm.free.m.as_ref(), *alpha);
            push(&mut damping, sm.free.k.as_ref(), *beta);
        }
        Some(_) => {
            if nm > MAX_DENSE_DOF {
                return Err(Error::input(format!(
                    "{file}: key 'model.damping': modal or matrix damping of a casing model is formed dense, for at most {MAX_DENSE_DOF} displacements ({nm} here): use Rayleigh damping"
                )));
            }
            let k = sm.free.k.to_dense();
            let m = sm.free.m.to_dense();
            if let Some(c) = damping_matrix(case, sm, k.as_ref(), m.as_ref())? {
                for (i, row) in damping.iter_mut().enumerate().take(nm) {
                    row.extend(
                        (0..nm)
                            .filter(|&j| c[(i, j)] != 0.0)
                            .map(|j| (j, c[(i, j)])),
                    );
                }
            }
        }
    }
    let mut theta_of: HashMap<usize, usize> = HashMap::new();
    if let Some(t) = &thermal {
        for (a, &node) in t.nodes.iter().enumerate() {
            theta_of.insert(node, nm + a);
        }
        for (a, row) in t.conductance.iter().enumerate() {
            stiffness[nm + a].extend(row.iter().map(|&(b, v)| (nm + b, v)));
        }
        for (a, row) in t.capacity.iter().enumerate() {
            damping[nm + a].extend(row.iter().map(|&(b, v)| (nm + b, v)));
        }
        for (i, &p) in sm.free.free_dofs.iter().enumerate() {
            stiffness[i].extend(t.coupling[p].iter().map(|&(b, v)| (nm + b, v)));
        }
    }
    let mut dof_names: Vec<String> = sm
        .free
        .free_dofs
        .iter()
        .map(|p| format!("row {p}"))
        .collect();
    for e in &map.entries {
        dof_names[e.row] = format!(
            "node {} {}",
            e.node_tag,
            ["x", "y", "z"][e.component as usize % 3]
        );
    }
    if let Some(t) = &thermal {
        dof_names.extend(
            t.nodes
                .iter()
                .map(|&i| format!("node {} theta", mesh.node_tags[i])),
        );
    }
    let mut sys = NonsmoothSystem {
        n,
        n_mech: nm,
        mass: Vec::new(),
        damping: Vec::new(),
        stiffness: Vec::new(),
        force: vec![Harmonic::default(); n],
        omega,
        obstacles: Vec::new(),
        dof_names,
        x0: vec![0.0; n],
        v0: vec![0.0; n],
        heat_weights: Vec::new(),
    };
    if let Some(e) = &case.excitation {
        match &e.load {
            ExcitationLoad::Group { group, force } => {
                for node in mesh.nodes_of(group)? {
                    for (comp, &f) in force.iter().enumerate() {
                        if let Some(&row) = mech_of.get(&(node as usize, comp)) {
                            sys.force[row].cos += f * e.force_scale;
                        }
                    }
                }
            }
            ExcitationLoad::Dofs { .. } => {
                return Err(Error::input(format!(
                    "{file}: key 'excitation.dofs': a mesh case with `[[casing]]` is loaded by `group` and `force = [fx, fy, fz]` per node"
                )))
            }
        }
    }
    // Casings: one obstacle per contact node.
    let mut contact_nodes = Vec::new();
    for (ci, cs) in case.casing.iter().enumerate() {
        let key = format!("casing[{ci}]");
        let d = cs.axis.direction;
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let a = [d[0] / len, d[1] / len, d[2] / len];
        let sense = cs.speed_rpm.map_or(1.0, f64::signum);
        let nodes = mesh.nodes_of(&cs.group)?;
        let mut tags: Vec<u64> = nodes.iter().map(|&i| mesh.node_tags[i as usize]).collect();
        tags.sort_unstable();
        for node in nodes {
            let i = node as usize;
            let tag = mesh.node_tags[i];
            let (er, r) = radial(mesh.coords[i], cs.axis.origin, a).ok_or_else(|| {
                Error::input(format!(
                    "{file}: key '{key}.group': node {tag} lies on the rotation axis, so it has no radial direction"
                ))
            })?;
            let ephi = cross(a, er);
            let combination = |v: [f64; 3], scale: f64| -> Vec<(usize, f64)> {
                (0..3)
                    .filter_map(|comp| {
                        let w = scale * v[comp];
                        let row = mech_of.get(&(i, comp))?;
                        (w != 0.0).then_some((*row, w))
                    })
                    .collect()
            };
            let normal = combination(er, -1.0);
            if normal.is_empty() {
                return Err(Error::input(format!(
                    "{file}: key '{key}.group': node {tag} cannot move radially (clamped), so it cannot touch the casing"
                )));
            }
            let g0 = cs.initial_gap(tag, r, &tags).ok_or_else(|| {
                Error::input(format!(
                    "{file}: key '{key}.gap': no initial gap for node {tag} of group '{}'",
                    cs.group
                ))
            })?;
            let mut o = Obstacle::new(
                &format!("{}:{tag}", cs.label(ci)),
                normal,
                g0,
                cs.restitution,
            );
            if cs.mu > 0.0 {
                o.mu = cs.mu;
                o.tangential = combination(ephi, -sense);
            }
            if cs.heating > 0.0 {
                if let Some(&row) = theta_of.get(&i) {
                    o.heating = cs.heating;
                    o.heated = vec![(row, 1.0)];
                }
            }
            sys.obstacles.push(o);
            if !contact_nodes.contains(&i) {
                contact_nodes.push(i);
            }
        }
    }
    // Recorded DOF: the response groups (else the contact nodes), then the temperatures of the
    // contact nodes and of the other response nodes (nodes with a prescribed temperature have
    // none).
    let response_nodes: Vec<usize> = match case.response.as_ref().filter(|r| !r.groups.is_empty()) {
        Some(r) => {
            let mut nodes = Vec::new();
            for g in &r.groups {
                for node in mesh.nodes_of(g)? {
                    if !nodes.contains(&(node as usize)) {
                        nodes.push(node as usize);
                    }
                }
            }
            nodes
        }
        None => contact_nodes.clone(),
    };
    let mut record = Vec::new();
    let mut response = Vec::new();
    for &i in &response_nodes {
        for comp in 0..3 {
            if let Some(&row) = mech_of.get(&(i, comp)) {
                record.push(row);
                response.push(ResponseDof::Node {
                    tag: mesh.node_tags[i],
                    component: comp as u8,
                });
            }
        }
    }
    let mut temperature_nodes = Vec::new();
    let others = response_nodes.iter().filter(|i| !contact_nodes.contains(i));
    for &i in contact_nodes.iter().chain(others) {
        if let Some(&row) = theta_of.get(&i) {
            record.push(row);
            temperature_nodes.push(mesh.node_tags[i]);
        }
    }
    Ok(CasingModel {
        case: NonsmoothCase {
            system: sys,
            settings: march_settings(case, record)?,
            response,
            temperature_nodes,
            reference_temperature: case.thermal.as_ref().map(|t| t.reference_temperature),
        },
        mass,
        damping,
        stiffness,
    })
}

/// The thermal matrices restricted to the free temperature rows, as sparse rows.
struct ThermalRows {
    /// Mesh node index of each temperature row.
    nodes: Vec<usize>,
    /// K^θθ rows: (column among `nodes`, value) (W/K).
    conductance: Vec<Vec<(usize, f64)>>,
    /// C^θθ rows (J/K).
    capacity: Vec<Vec<(usize, f64)>>,
    /// K^uθ rows per global displacement DOF 3i + c: (column among `nodes`, value) (N/K).
    coupling: Vec<Vec<(usize, f64)>>,
}

/// Assembles the thermal matrices of `mesh` and drops the rows of `thermal.fixed` (θ = 0) and
/// of nodes outside every volume element.
fn thermal_rows(
    case: &Case,
    sm: &StructuralModel,
    mesh: &Mesh,
    t: &crate::case::ThermalTable,
) -> Result<ThermalRows> {
    let file = case.path.display().to_string();
    if case.model.stiffness.is_some() {
        return Err(Error::input(format!(
            "{file}: key 'thermal': the heat matrices are assembled from the mesh, which needs the displacement matrices assembled from it too (no `stiffness`/`mass` files)"
        )));
    }
    let th = ThermalMaterial {
        conductivity: t.conductivity,
        specific_heat: t.specific_heat,
        expansion: t.expansion,
        capacity: t.capacity,
    };
    let quad = Quadrature {
        stiffness_degree: case.model.quadrature.stiffness,
        mass_degree: case.model.quadrature.mass,
    };
    let asm = assemble_thermal(mesh, &Materials::from_case(&case.model), &th, &quad)
        .map_err(|e| Error::input(format!("{file}: key 'thermal': {e}")))?;
    let nn = mesh.num_nodes();
    let mut fixed = vec![false; nn];
    for g in &t.fixed {
        for node in mesh.nodes_of(g)? {
            fixed[node as usize] = true;
        }
    }
    let cap = &asm.capacity;
    let mut has_capacity = vec![false; nn];
    for j in 0..cap.ncols() {
        for (i, &v) in cap.row_idx_of_col(j).zip(cap.val_of_col(j)) {
            if i == j && v > 0.0 {
                has_capacity[i] = true;
            }
        }
    }
    let nodes: Vec<usize> = (0..nn).filter(|&i| !fixed[i] && has_capacity[i]).collect();
    let mut col_of = vec![None; nn];
    for (a, &i) in nodes.iter().enumerate() {
        col_of[i] = Some(a);
    }
    let rows_of = |mat: &faer::sparse::SparseColMat<usize, f64>,
                   nrows: usize,
                   keep_row: &dyn Fn(usize) -> Option<usize>| {
        let mut rows = vec![Vec::new(); nrows];
        for (j, b) in col_of.iter().enumerate().take(mat.ncols()) {
            let Some(b) = *b else { continue };
            for (i, &v) in mat.row_idx_of_col(j).zip(mat.val_of_col(j)) {
                if let Some(r) = keep_row(i) {
                    rows[r].push((b, v));
                }
            }
        }
        rows
    };
    let by_node = |i: usize| col_of[i];
    let conductance = rows_of(&asm.conductance, nodes.len(), &by_node);
    let capacity = rows_of(&asm.capacity, nodes.len(), &by_node);
    let coupling = rows_of(&asm.coupling, sm.n_dofs.max(3 * nn), &|p| Some(p));
    Ok(ThermalRows {
        nodes,
        conductance,
        capacity,
        coupling,
    })
}
