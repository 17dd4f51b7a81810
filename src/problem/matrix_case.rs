//! A model on matrix rows ([`crate::case::CaseKind::Matrix`]; `docs/case-file.md`: `[model]
//! stiffness/mass/damping`, `[excitation] dofs/force`, `[response] dofs`, `[[element]]` on DOF
//! combinations): dense K, M, C over the free rows, the excitation on harmonic 1, the nonlinear
//! rows (every row an element reads) and the output rows.
//!
//! Damping ([`crate::model::damping`]): `matrix` (read, same size as K), `rayleigh = [α, β]`
//! (C = αM + βK) or `modal = ζ` (C = M Φ diag(2ζω_j) Φᵀ M over all modes of the dense problem, Φ
//! mass-normalised).
//!
//! One map from case rows to free rows ([`free_row`]) and one damping builder
//! ([`damping_matrix`]) serve both solvers: the harmonic balance ([`matrix_setup`],
//! [`matrix_elements`]) and the time march ([`matrix_march`]).

use std::collections::HashMap;
use std::path::Path;

use faer::{Mat, MatRef};

use crate::case::{
    Case, Damping, ElementKind, ExcitationLoad, FrictionElement, Strip, WeightedDofs,
};
use crate::contact::grounded::DofElements;
use crate::error::{Error, Result};
use crate::fe::quadrature::gauss_legendre;
use crate::hbm::LinearModel;
use crate::march::element::{Direction, Element};
use crate::march::law::FrictionParams;
use crate::march::signal::Harmonic;
use crate::march::{InitialCondition, MarchSystem};
use crate::matrix_io::{read_real_matrix, DofMap};
use crate::model::{damping, StructuralModel};

use super::face_strip;

/// Largest number of free DOF a matrix-defined case may have (the harmonic balance condenses
/// densely per frequency).
pub const MAX_DENSE_DOFS: usize = 4000;

/// The rows a matrix-defined case's harmonic balance refers to, and its excitation.
#[derive(Clone, Debug)]
pub struct MatrixRows {
    /// Free-row indices of the nonlinear DOFs (every row an element reads), ascending: the DOF
    /// order of the nonlinear force.
    pub nonlinear_rows: Vec<usize>,
    /// Free-row indices of the output DOFs.
    pub output_rows: Vec<usize>,
    /// Matrix rows (as written in the case, before clamping) of the output DOFs.
    pub output_case_rows: Vec<usize>,
    /// The excitation amplitude per free row (N), f = force·cos(ωt) (times `force_scale`).
    pub force: Vec<f64>,
}

/// The nonlinear rows, output rows and excitation of `case` on `model` (errors name the key of
/// a clamped or out-of-range row).
pub fn matrix_rows(case: &Case, model: &StructuralModel) -> Result<MatrixRows> {
    let free_of = free_row_map(model);
    let force = excitation(case, model, &free_of)?;
    let mut nonlinear_rows = Vec::new();
    for (name, e) in &case_elements(case, model)? {
        let mut rows = vec![(format!("{name}.tangential.dofs"), &e.tangential.dofs)];
        if let Some(nrm) = &e.normal {
            rows.push((format!("{name}.normal.dofs"), &nrm.dofs));
        }
        for (key, dofs) in rows {
            for &d in dofs {
                nonlinear_rows.push(free_row(case, &free_of, &key, d)?);
            }
        }
    }
    nonlinear_rows.sort_unstable();
    nonlinear_rows.dedup();
    let output_case_rows = output_rows(case, model)?;
    let output_rows = output_case_rows
        .iter()
        .map(|&d| free_row(case, &free_of, "response.dofs", d))
        .collect::<Result<Vec<_>>>()?;
    Ok(MatrixRows {
        nonlinear_rows,
        output_rows,
        output_case_rows,
        force,
    })
}

/// The linear part of a matrix-defined case and the rows it refers to.
#[derive(Clone, Debug)]
pub struct MatrixSetup {
    /// The linear model condensed on `nonlinear_rows`.
    pub linear: LinearModel,
    /// Free-row indices of the nonlinear DOFs, ascending: the DOF order of the nonlinear force.
    pub nonlinear_rows: Vec<usize>,
    /// Free-row indices of the output DOFs.
    pub output_rows: Vec<usize>,
    /// Matrix rows (as written in the case, before clamping) of the output DOFs.
    pub output_case_rows: Vec<usize>,
}

impl MatrixSetup {
    /// Position of free row `row` among the nonlinear DOFs.
    pub fn nonlinear_position(&self, row: usize) -> Option<usize> {
        self.nonlinear_rows.binary_search(&row).ok()
    }
}

/// Builds the linear part of `case` on `model` with H harmonics.
pub fn matrix_setup(case: &Case, model: &StructuralModel) -> Result<MatrixSetup> {
    let name = case.path.display();
    let n = model.free.n_free();
    if n > MAX_DENSE_DOFS {
        return Err(Error::input(format!(
            "{name}: the model has {n} free DOF; the harmonic balance of a matrix-defined case is dense and handles up to {MAX_DENSE_DOFS}; on a mesh model, give `[reduction] interface_modes = N` to solve it on its Craig–Bampton model"
        )));
    }
    let k = model.free.k.to_dense();
    let m = model.free.m.to_dense();
    let c = damping_matrix(case, model, k.as_ref(), m.as_ref())?;
    let MatrixRows {
        nonlinear_rows,
        output_rows,
        output_case_rows,
        force,
    } = matrix_rows(case, model)?;
    let linear = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        c.as_ref().map(|c| c.as_ref()),
        &force,
        nonlinear_rows.clone(),
        output_rows.clone(),
        case.harmonic_balance.harmonics,
    )?;
    Ok(MatrixSetup {
        linear,
        nonlinear_rows,
        output_rows,
        output_case_rows,
    })
}

/// Matrix row (before clamping) → free row, `None` for a clamped row.
pub fn free_row_map(model: &StructuralModel) -> Vec<Option<usize>> {
    let mut map = vec![None; model.n_dofs];
    for (i, &row) in model.free.free_dofs.iter().enumerate() {
        if row < map.len() {
            map[row] = Some(i);
        }
    }
    map
}

/// The free row of case row `d` named at `key` (`free_of` from [`free_row_map`]), or an input
/// error naming the key, the row and why (clamped, or out of range).
pub fn free_row(case: &Case, free_of: &[Option<usize>], key: &str, d: usize) -> Result<usize> {
    match free_of.get(d) {
        Some(Some(r)) => Ok(*r),
        Some(None) => Err(Error::input(format!(
            "{}: key '{key}': row {d} is clamped; a clamped DOF cannot carry a force, an element or a response",
            case.path.display()
        ))),
        None => Err(Error::input(format!(
            "{}: key '{key}': row {d} is out of range; the matrices have {} rows (0-based rows 0..{})",
            case.path.display(),
            free_of.len(),
            free_of.len().saturating_sub(1)
        ))),
    }
}

/// The output rows as written in the case: `[response] dofs`, else the x, y, z rows of the
/// nodes of the `[response] groups` (a mesh model), else the excitation rows (or the excitation
/// group's nodes).
fn output_rows(case: &Case, model: &StructuralModel) -> Result<Vec<usize>> {
    if let Some(r) = case.response.as_ref().filter(|r| !r.dofs.is_empty()) {
        return Ok(r.dofs.clone());
    }
    let groups: Vec<(String, &str)> =
        match (&case.response, case.excitation.as_ref().map(|e| &e.load)) {
            (Some(r), _) if !r.groups.is_empty() => r
                .groups
                .iter()
                .enumerate()
                .map(|(i, g)| (format!("response.groups[{i}]"), g.as_str()))
                .collect(),
            (_, Some(ExcitationLoad::Dofs { dofs, .. })) => return Ok(dofs.clone()),
            (_, Some(ExcitationLoad::Group { group, .. })) => {
                vec![("excitation.group".to_string(), group.as_str())]
            }
            _ => Vec::new(),
        };
    if groups.is_empty() {
        return Err(Error::input(format!(
            "{}: key 'response': a matrix-defined case needs `[response] dofs = [...]` (or `groups` on a mesh model) or an `[excitation]`",
            case.path.display()
        )));
    }
    let mut rows = Vec::new();
    for (key, g) in groups {
        for node in group_rows(case, model, &key, g)? {
            for r in node {
                if !rows.contains(&r) {
                    rows.push(r);
                }
            }
        }
    }
    Ok(rows)
}

/// The case rows (x, y, z) of every node of the mesh group `group` (named at `key`), through
/// the model's DOF map: an error naming the key when the model has no mesh or DOF map, or a
/// node has no row.
fn group_rows(
    case: &Case,
    model: &StructuralModel,
    key: &str,
    group: &str,
) -> Result<Vec<[usize; 3]>> {
    let name = case.path.display();
    let (Some(mesh), Some(map)) = (&model.mesh, &model.dofs) else {
        return Err(Error::input(format!(
            "{name}: key '{key}': the group '{group}' needs a mesh model with a DOF map; a model on matrices alone names matrix rows (`dofs`)"
        )));
    };
    let rows = dof_rows(map);
    mesh.nodes_of(group)?
        .into_iter()
        .map(|i| {
            let tag = mesh.node_tags[i as usize];
            let mut r = [0; 3];
            for (c, slot) in r.iter_mut().enumerate() {
                *slot = *rows.get(&(tag, c as u8)).ok_or_else(|| {
                    Error::input(format!(
                        "{name}: key '{key}': node {tag} of group '{group}' has no row for component {c} in the DOF map"
                    ))
                })?;
            }
            Ok(r)
        })
        .collect()
}

/// (node tag, component) → case row of a DOF map.
fn dof_rows(map: &DofMap) -> HashMap<(u64, u8), usize> {
    map.entries
        .iter()
        .map(|e| ((e.node_tag, e.component), e.row))
        .collect()
}

/// The excitation amplitude per free row (N), f = force·cos(ωt) (times `force_scale`).
fn excitation(case: &Case, model: &StructuralModel, free_of: &[Option<usize>]) -> Result<Vec<f64>> {
    let mut f = vec![0.0; model.free.n_free()];
    let Some(e) = &case.excitation else {
        return Err(Error::input(format!(
            "{}: key 'excitation': a forced response needs `[excitation] dofs = [...]` and `force = [...]`",
            case.path.display()
        )));
    };
    match &e.load {
        ExcitationLoad::Dofs { dofs, force } => {
            for (&d, &v) in dofs.iter().zip(force) {
                f[free_row(case, free_of, "excitation.dofs", d)?] += v * e.force_scale;
            }
        }
        ExcitationLoad::Group { group, force } => {
            for node in group_rows(case, model, "excitation.group", group)? {
                for (&d, &v) in node.iter().zip(force) {
                    f[free_row(case, free_of, "excitation.group", d)?] += v * e.force_scale;
                }
            }
        }
    }
    Ok(f)
}

/// The dense damping matrix C over the free rows of `model` (K and M dense over the same rows),
/// `None` when undamped ([`crate::model::damping`]): Rayleigh αM + βK, modal damping ζ on every
/// mode of (K, M), or an external matrix restricted to the free rows.
pub fn damping_matrix(
    case: &Case,
    model: &StructuralModel,
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
) -> Result<Option<Mat<f64>>> {
    let n = k.nrows();
    let external = |path: &Path| -> Result<Mat<f64>> {
        let c = read_real_matrix(path)?;
        if c.nrows() != model.n_dofs || c.ncols() != model.n_dofs {
            return Err(Error::input(format!(
                "{}: a {}×{} damping matrix for K of {} rows (key 'model.damping.matrix' of {})",
                path.display(),
                c.nrows(),
                c.ncols(),
                model.n_dofs,
                case.path.display()
            )));
        }
        let full = c.to_dense();
        let rows = &model.free.free_dofs;
        Ok(Mat::from_fn(n, n, |i, j| full[(rows[i], rows[j])]))
    };
    let spec = case.model.damping.as_ref();
    damping::damping_matrix(spec, k, m, external).map_err(|e| match spec {
        Some(Damping::Modal(_)) => Error::input(format!(
            "{}: key 'model.damping.modal': {e}",
            case.path.display()
        )),
        _ => e,
    })
}

/// The `[[element]]` friction elements of a matrix case on its nonlinear rows
/// (`nonlinear_rows`, ascending free-row indices, [`MatrixRows::nonlinear_rows`]): every case
/// row is mapped to its free row, then to its position among `nonlinear_rows`.
pub fn matrix_elements(
    case: &Case,
    model: &StructuralModel,
    nonlinear_rows: &[usize],
) -> Result<DofElements> {
    let free_of = free_row_map(model);
    let position = |key: &str, d: usize| -> Result<usize> {
        let r = free_row(case, &free_of, key, d)?;
        nonlinear_rows.binary_search(&r).ok().ok_or_else(|| {
            Error::input(format!(
                "{}: key '{key}': row {d} is not a nonlinear row of the model",
                case.path.display()
            ))
        })
    };
    let remap = |key: String, w: &WeightedDofs| -> Result<WeightedDofs> {
        Ok(WeightedDofs {
            dofs: w
                .dofs
                .iter()
                .map(|&d| position(&key, d))
                .collect::<Result<_>>()?,
            weights: w.weights.clone(),
        })
    };
    let elements = case_elements(case, model)?
        .into_iter()
        .map(|(name, e)| {
            Ok(FrictionElement {
                tangential: remap(format!("{name}.tangential.dofs"), &e.tangential)?,
                normal: e
                    .normal
                    .as_ref()
                    .map(|n| remap(format!("{name}.normal.dofs"), n))
                    .transpose()?,
                ..e
            })
        })
        .collect::<Result<Vec<_>>>()?;
    DofElements::from_case(&elements, nonlinear_rows.len())
}

/// The nonlinear elements of a matrix case with the names its messages use: the `[[element]]`
/// entries (`element[i]`), then the points of every `[[strip]]` (`strip[s].point[p]`,
/// [`strip_points`]).
pub fn case_elements(
    case: &Case,
    model: &StructuralModel,
) -> Result<Vec<(String, FrictionElement)>> {
    let mut out: Vec<(String, FrictionElement)> = case
        .element
        .iter()
        .enumerate()
        .map(|(i, e)| (format!("element[{i}]"), e.clone()))
        .collect();
    for s in 0..case.strip.len() {
        out.extend(
            strip_points(case, s, model)?
                .into_iter()
                .enumerate()
                .map(|(p, (_, e))| (format!("strip[{s}].point[{p}]"), e)),
        );
    }
    Ok(out)
}

/// The integration points of the validated strip `case.strip[s]` on `model` with their
/// positions s (m): [`line_strip_points`] for a strip on matrix rows, [`face_strip_points`] for
/// one on a face group.
pub fn strip_points(
    case: &Case,
    s: usize,
    model: &StructuralModel,
) -> Result<Vec<(f64, FrictionElement)>> {
    let strip = &case.strip[s];
    if strip.face.is_some() {
        face_strip_points(case, s, model)
    } else {
        Ok(line_strip_points(strip))
    }
}

/// The points of the strip `case.strip[s]` on a face group of the mesh of `model`
/// ([`face_strip::face_points`], whose documentation gives the kinematics and the quadrature):
/// per Gauss point, the tangential combination Σ_a N_a t_c q(row(a, c)) and, when kn > 0, the
/// normal one Σ_a N_a n_c q(row(a, c)), with k_t = k_u dA, k_n = k_v dA and
/// n0 = P q(s) dA / Σ q dA. Rows of clamped nodes are left out of the combinations (they do not
/// move); a point whose nodes are all clamped is left out, its share of the preload included in
/// the normalisation. Points are ordered by position s (stable).
///
/// Errors ([`Error::Input`], naming the case file and `strip[s]`): the model has no mesh or DOF
/// map, a face node without rows, and the errors of [`face_strip::face_points`].
pub fn face_strip_points(
    case: &Case,
    s: usize,
    model: &StructuralModel,
) -> Result<Vec<(f64, FrictionElement)>> {
    let strip = &case.strip[s];
    let name = case.path.display();
    let key = format!("strip[{s}].face");
    let (Some(mesh), Some(map), Some(group), Some(direction)) =
        (&model.mesh, &model.dofs, &strip.face, strip.direction)
    else {
        return Err(Error::input(format!(
            "{name}: key '{key}': a strip on a face group needs a mesh model with a DOF map and `direction`"
        )));
    };
    let fp = face_strip::face_points(mesh, group, direction, strip.gauss)
        .map_err(|e| Error::input(format!("{name}: key '{key}': {e}")))?;
    let rows = dof_rows(map);
    let free_of = free_row_map(model);
    let total: f64 = fp
        .points
        .iter()
        .map(|p| strip.shape_on(p.position, 0.0, fp.length) * p.area)
        .sum();
    let mut points = Vec::with_capacity(fp.points.len());
    for p in &fp.points {
        let combination = |dir: [f64; 3]| -> Result<WeightedDofs> {
            let mut w = WeightedDofs::default();
            for &(node, value) in &p.nodes {
                let tag = mesh.node_tags[node as usize];
                for (c, &dc) in dir.iter().enumerate() {
                    let row = *rows.get(&(tag, c as u8)).ok_or_else(|| {
                        Error::input(format!(
                            "{name}: key '{key}': node {tag} of group '{group}' has no row for component {c} in the DOF map"
                        ))
                    })?;
                    let weight = value * dc;
                    if weight != 0.0 && free_of.get(row).is_some_and(Option::is_some) {
                        w.dofs.push(row);
                        w.weights.push(weight);
                    }
                }
            }
            Ok(w)
        };
        let tangential = combination(p.tangent)?;
        let normal = if strip.kn > 0.0 {
            Some(combination(p.normal)?)
        } else {
            None
        };
        // a combination needs a row: an empty one (every weight 0 or clamped) reads another
        // row of the point with weight 0; a point with no free row at all is left out
        let Some(&any) = tangential
            .dofs
            .first()
            .or_else(|| normal.as_ref().and_then(|n| n.dofs.first()))
        else {
            continue;
        };
        let fill = |mut w: WeightedDofs| {
            if w.dofs.is_empty() {
                w.dofs.push(any);
                w.weights.push(0.0);
            }
            w
        };
        let tangential = fill(tangential);
        let normal = normal.map(fill);
        let e = FrictionElement {
            kind: ElementKind::Friction,
            tangential,
            normal,
            kt: Some(strip.kt * p.area),
            kn: strip.kn * p.area,
            mu: Some(strip.mu),
            n0: Some(strip.preload * strip.shape_on(p.position, 0.0, fp.length) * p.area / total),
            evaluation: strip.evaluation,
            ..FrictionElement::default()
        };
        points.push((p.position, e));
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(points)
}

/// The integration points of a validated strip on matrix rows (`docs/case-file.md`,
/// `[[strip]]`) as friction elements, with their positions s (m): per segment [s_j, s_j+1] of length h the
/// Gauss–Legendre points s = s_j + h(1 + x_g)/2 of weight dA = h w_g/2, the station weights
/// interpolated linearly (η = (1 + x_g)/2), k_t = k_u dA, k_n = k_v dA and
/// n0 = P q(s) dA / Σ q dA (P the total preload, so the points' preloads add up to P exactly).
/// Weights that interpolate to exactly 0 are left out of a point's combination.
pub fn line_strip_points(strip: &Strip) -> Vec<(f64, FrictionElement)> {
    let (xg, wg) = gauss_legendre(strip.gauss);
    let st = &strip.stations;
    let mut points = Vec::new();
    for j in 0..st.len().saturating_sub(1) {
        let h = st[j + 1] - st[j];
        for (x, w) in xg.iter().zip(&wg) {
            let eta = 0.5 * (1.0 + x);
            points.push((j, eta, st[j] + h * eta, 0.5 * h * w));
        }
    }
    let total: f64 = points
        .iter()
        .map(|&(_, _, s, da)| strip.shape(s) * da)
        .sum();
    let combination = |table: &[Vec<f64>], j: usize, eta: f64| {
        let mut c = WeightedDofs::default();
        for (k, &d) in strip.dofs.iter().enumerate() {
            let w = (1.0 - eta) * table[j][k] + eta * table[j + 1][k];
            if w != 0.0 {
                c.dofs.push(d);
                c.weights.push(w);
            }
        }
        if c.dofs.is_empty() {
            c.dofs.push(strip.dofs[0]);
            c.weights.push(0.0);
        }
        c
    };
    points
        .into_iter()
        .map(|(j, eta, s, da)| {
            let e = FrictionElement {
                kind: ElementKind::Friction,
                tangential: combination(&strip.tangential, j, eta),
                normal: strip.normal.as_ref().map(|t| combination(t, j, eta)),
                kt: Some(strip.kt * da),
                kn: strip.kn * da,
                mu: Some(strip.mu),
                n0: Some(strip.preload * strip.shape(s) * da / total),
                evaluation: strip.evaluation,
                ..FrictionElement::default()
            };
            (s, e)
        })
        .collect()
}

/// The march system of a matrix-defined case: dense K, M, C over the free rows (row-major), the
/// excitation f = force·cos ωt on its rows (none without `[excitation]`), the `[[element]]`
/// friction elements; starts at rest. Returns the system and the reported free rows:
/// `[response] dofs`, else the excitation rows, else the first three rows.
pub fn matrix_march(case: &Case, sm: &StructuralModel) -> Result<(MarchSystem, Vec<usize>)> {
    let file = case.path.display().to_string();
    let n = sm.free.n_free();
    let free_of = free_row_map(sm);
    let row = |r: usize, key: &str| free_row(case, &free_of, key, r);
    let k = sm.free.k.to_dense();
    let m = sm.free.m.to_dense();
    let c = damping_matrix(case, sm, k.as_ref(), m.as_ref())?;
    let row_major =
        |a: &Mat<f64>| -> Vec<f64> { (0..n * n).map(|ij| a[(ij / n, ij % n)]).collect() };
    let mut force = vec![Harmonic::default(); n];
    let mut response = Vec::new();
    if let Some(e) = &case.excitation {
        match &e.load {
            ExcitationLoad::Dofs { dofs, force: f } => {
                for (&d, &fv) in dofs.iter().zip(f) {
                    let i = row(d, "excitation.dofs")?;
                    force[i].cos += fv * e.force_scale;
                    response.push(i);
                }
            }
            ExcitationLoad::Group { .. } => {
                return Err(Error::input(format!(
                    "{file}: excitation.group is not marched: `nlrom march` of a matrix case takes `excitation.dofs` and `force` (on a mesh the rows 3·node + component)"
                )))
            }
        }
    }
    if let Some(r) = &case.response {
        if !r.dofs.is_empty() {
            response = r
                .dofs
                .iter()
                .map(|&d| row(d, "response.dofs"))
                .collect::<Result<_>>()?;
        }
    }
    let direction = |w: &WeightedDofs, key: &str| -> Result<Direction> {
        Ok(Direction {
            weights: w
                .dofs
                .iter()
                .zip(&w.weights)
                .map(|(&d, &x)| Ok((row(d, key)?, x)))
                .collect::<Result<_>>()?,
            prescribed: Harmonic::default(),
        })
    };
    let mut elements = Vec::new();
    for (name, e) in case_elements(case, sm)? {
        if e.kind != ElementKind::Friction {
            return Err(Error::input(format!(
                "{file}: {name}: kind = \"{}\" is computed by the harmonic balance (`nlrom solve`); time marching takes `friction` elements only",
                e.kind.name()
            )));
        }
        let value = |v: Option<f64>| v.unwrap_or(0.0);
        elements.push(Element {
            tangential: direction(&e.tangential, &format!("{name}.tangential"))?,
            normal: e
                .normal
                .as_ref()
                .map(|w| direction(w, &format!("{name}.normal")))
                .transpose()?,
            params: FrictionParams::new(
                value(e.kt),
                e.kn,
                value(e.mu),
                value(e.n0),
                &format!("{file}: {name}"),
            )?,
            name,
            applies_normal: true,
        });
    }
    if response.is_empty() {
        response = (0..n.min(3)).collect();
    }
    let mut sys = MarchSystem {
        n,
        mass: row_major(&m),
        damping: match &c {
            Some(c) => row_major(c),
            None => vec![0.0; n * n],
        },
        stiffness: row_major(&k),
        force,
        damping_force: Vec::new(),
        elements,
        dof_names: sm
            .free
            .free_dofs
            .iter()
            .map(|d| format!("row {d}"))
            .collect(),
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    sys.displacement_scale = sys.default_displacement_scale();
    sys.validate(&file)?;
    Ok((sys, response))
}
