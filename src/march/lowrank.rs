//! Step matrices of a contact state as a low-rank change of the all-stick one (Sherman–Morrison–
//! Woodbury), for models with many elements (a sector's shroud pairs meet thousands of state
//! combinations; inverting each n × n step matrix dominated the march).
//!
//! Against full stick, an element's linear piece (paper Table 1, [`Element::add_linear_piece`])
//! changes the step matrix A = A_stick + Σ u vᵀ by
//! - slip with sign s: u = g_t, v = s μ k_n g_n − k_t g_t (the normal terms are the same);
//! - separation: u = g_t, v = −k_t g_t and, when it applies its normal force, u = g_n, v = −k_n g_n.
//!
//! With U, V of the r such columns and Z = A_stick⁻¹ U, A⁻¹ b = y − Z (I + VᵀZ)⁻¹ Vᵀ y with
//! y = A_stick⁻¹ b: O(n·r + r³) to factor a state instead of O(n³).
//!
//! A state that differs from the factored one in a few elements is reached by removing and adding
//! their columns one at a time ([`LowRank::update`]), each in O(r²) with the bordered inverse of the
//! capacitance matrix C = I + VᵀZ (B = C⁻¹ = [[B₁₁, b₁₂], [b₂₁, β]]):
//! - removing the last column: (C₁₁)⁻¹ = B₁₁ − b₁₂ b₂₁ / β;
//! - adding a column (u, v) with z = A_stick⁻¹ u, p_a = v_aᵀ z, q_a = vᵀ z_a, d = 1 + vᵀ z and the
//!   Schur complement s = d − qᵀ B p: [[B + B p qᵀ B / s, −B p / s], [−qᵀ B / s, 1 / s]].
//!
//! A pivot β or s that cancels to below 1e-8 of its terms, or more updates than the rank of the
//! last full build (rounding accumulates), asks for a new full build. So does a change of many
//! columns: each update makes several passes over the r × r inverse and one column of Z, and a
//! new build costs about as much as r updates, so beyond [`UPDATE_FRACTION`] · r changed columns
//! (removed plus added) the factors are built anew (the crossover is measured by
//! `cargo bench --bench lowrank`).

use super::dense;
use super::element::{Direction, Element};
use super::law::ContactState;

/// Sparse vector: (index, value) pairs.
pub type Sparse = Vec<(usize, f64)>;

/// One column pair (u, v) of the change U Vᵀ, with the element it belongs to.
#[derive(Clone, Debug)]
pub struct Column {
    /// Index of the element.
    pub owner: usize,
    /// Whether u is the element's normal direction g_n (a separated element that applies its
    /// normal force), rather than its tangential one g_t.
    pub normal: bool,
    /// u (sparse).
    pub u: Sparse,
    /// v (sparse).
    pub v: Sparse,
}

/// Pivots that cancel to below this fraction of their terms ask for a full build.
const PIVOT_TOLERANCE: f64 = 1e-8;

/// Most changed columns (removed plus added), as a fraction of the larger of the two ranks, that
/// [`LowRank::update`] makes by column updates; a larger change is built anew ([`LowRank::new`]).
/// One: on 2312 coordinates a build costs as much as 1.0 r (r = 700) to 4 r (r = 100) column
/// updates.
pub const UPDATE_FRACTION: f64 = 1.0;

/// The factors of one state: Z = A_stick⁻¹ U (n × r, column-major: column a is
/// `z[a n..(a + 1) n]`), B = (I + VᵀZ)⁻¹ (r × r, row-major), the sparse columns of V and the
/// element of each column, and the states they stand for.
#[derive(Clone, Debug)]
pub struct LowRank {
    n: usize,
    z: Vec<f64>,
    capacitance_inverse: Vec<f64>,
    v: Vec<Sparse>,
    owner: Vec<usize>,
    /// Per column: whether it is its element's normal direction ([`Column::normal`]).
    normal: Vec<bool>,
    states: Vec<ContactState>,
    /// Columns removed or added since the last full build, and the most allowed.
    updates: usize,
    max_updates: usize,
    /// Scratch of the updates (B p, qᵀ B, p, q).
    bp: Vec<f64>,
    qb: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}

/// Sparse a·x + b·y of two directions' weights.
fn combine(a: f64, x: &Direction, b: f64, y: Option<&Direction>) -> Sparse {
    let mut out: Sparse = x.weights.iter().map(|&(i, w)| (i, a * w)).collect();
    for &(i, w) in y.map_or(&[][..], |d| &d.weights[..]) {
        match out.iter_mut().find(|(j, _)| *j == i) {
            Some(e) => e.1 += b * w,
            None => out.push((i, b * w)),
        }
    }
    out
}

/// The (u, v) columns of element `e` (index `index`) in state `s` (module documentation), passed
/// to `out`.
fn element_columns(index: usize, e: &Element, s: ContactState, out: &mut impl FnMut(Column)) {
    let (p, gt) = (&e.params, &e.tangential);
    match s {
        ContactState::Stick => {}
        ContactState::Slip(sign) => {
            let v = combine(-p.kt, gt, sign.value() * p.mu * p.kn, e.normal.as_ref());
            out(Column {
                owner: index,
                normal: false,
                u: gt.weights.clone(),
                v,
            });
        }
        ContactState::Separated => {
            out(Column {
                owner: index,
                normal: false,
                u: gt.weights.clone(),
                v: combine(-p.kt, gt, 0.0, None),
            });
            if let Some(gn) = e.normal.as_ref().filter(|_| e.applies_normal) {
                out(Column {
                    owner: index,
                    normal: true,
                    u: gn.weights.clone(),
                    v: combine(-p.kn, gn, 0.0, None),
                });
            }
        }
    }
}

/// The (u, v) columns of the states' change from full stick (module documentation).
pub fn columns(elements: &[Element], states: &[ContactState]) -> Vec<Column> {
    let mut out = Vec::new();
    for (i, (e, &s)) in elements.iter().zip(states).enumerate() {
        element_columns(i, e, s, &mut |c| out.push(c));
    }
    out
}

/// The number of (u, v) columns of element `e` in state `s` (module documentation).
fn element_rank(e: &Element, s: ContactState) -> usize {
    match s {
        ContactState::Stick => 0,
        ContactState::Slip(_) => 1,
        ContactState::Separated => 1 + usize::from(e.normal.is_some() && e.applies_normal),
    }
}

/// The largest number of (u, v) columns any combination of the elements' states can have (every
/// element separated): when it is below the number of DOF, every state's step matrix is a
/// low-rank change of the all-stick one.
pub fn max_rank(elements: &[Element]) -> usize {
    elements
        .iter()
        .map(|e| element_rank(e, ContactState::Separated))
        .sum()
}

/// The number of (u, v) columns of the states' change from full stick.
pub fn rank(elements: &[Element], states: &[ContactState]) -> usize {
    elements
        .iter()
        .zip(states)
        .map(|(e, &s)| element_rank(e, s))
        .sum()
}

/// z = A⁻¹ u for sparse u, given A⁻¹ (n × n, row-major).
pub fn solve_sparse(inverse: &[f64], n: usize, u: &[(usize, f64)], z: &mut [f64]) {
    for (zj, row) in z.iter_mut().zip(inverse.chunks_exact(n)) {
        *zj = u.iter().map(|&(i, w)| w * row[i]).sum();
    }
}

/// vᵀ x for sparse v.
fn sparse_dot(v: &[(usize, f64)], x: &[f64]) -> f64 {
    v.iter().map(|&(i, c)| c * x[i]).sum()
}

impl LowRank {
    /// The factors of `states` of `elements`, given A_stick⁻¹ (n × n, row-major); `None` when
    /// I + VᵀZ is singular (the state's step matrix is).
    pub fn new(
        stick_inverse: &[f64],
        n: usize,
        elements: &[Element],
        states: &[ContactState],
    ) -> Option<Self> {
        let cols = columns(elements, states);
        let r = cols.len();
        let mut z = vec![0.0; n * r];
        for (col, za) in cols.iter().zip(z.chunks_exact_mut(n)) {
            solve_sparse(stick_inverse, n, &col.u, za);
        }
        let mut c = vec![0.0; r * r];
        for (a, col) in cols.iter().enumerate() {
            for (b, zb) in z.chunks_exact(n).enumerate() {
                c[a * r + b] = f64::from(u8::from(a == b)) + sparse_dot(&col.v, zb);
            }
        }
        let capacitance_inverse = dense::inverse(&c, r)?;
        Some(LowRank {
            n,
            z,
            capacitance_inverse,
            owner: cols.iter().map(|c| c.owner).collect(),
            normal: cols.iter().map(|c| c.normal).collect(),
            v: cols.into_iter().map(|c| c.v).collect(),
            states: states.to_vec(),
            updates: 0,
            max_updates: r.max(64),
            bp: Vec::new(),
            qb: Vec::new(),
            p: Vec::new(),
            q: Vec::new(),
        })
    }

    /// The states the factors stand for.
    pub fn states(&self) -> &[ContactState] {
        &self.states
    }

    /// The rank r of the change from full stick.
    pub fn rank(&self) -> usize {
        self.v.len()
    }

    /// The number of elements whose state differs from `states`.
    pub fn differences(&self, states: &[ContactState]) -> usize {
        self.states
            .iter()
            .zip(states)
            .filter(|(a, b)| a != b)
            .count()
    }

    /// The number of columns removed and added to move the factors to `states`.
    pub fn changed_columns(&self, elements: &[Element], states: &[ContactState]) -> usize {
        elements
            .iter()
            .zip(self.states.iter().zip(states))
            .filter(|(_, (a, b))| a != b)
            .map(|(e, (&a, &b))| element_rank(e, a) + element_rank(e, b))
            .sum()
    }

    /// Moves the factors to `states` by removing and adding the columns of the elements whose
    /// state changed (module documentation). Returns false when the change is better built anew
    /// (more than [`UPDATE_FRACTION`] of the rank in changed columns, or more updates since the
    /// last full build than its rank), leaving the factors unchanged, or when a pivot cancels,
    /// leaving them unusable: the caller then builds them anew ([`LowRank::new`]).
    pub fn update(
        &mut self,
        stick_inverse: &[f64],
        elements: &[Element],
        states: &[ContactState],
    ) -> bool {
        let changed = self.changed_columns(elements, states);
        let r_new = rank(elements, states);
        if changed as f64 > UPDATE_FRACTION * self.rank().max(r_new) as f64
            || self.updates + changed > self.max_updates
        {
            return false;
        }
        self.update_columns(stick_inverse, elements, states)
    }

    /// [`LowRank::update`] by column updates whatever the number of changed columns.
    fn update_columns(
        &mut self,
        stick_inverse: &[f64],
        elements: &[Element],
        states: &[ContactState],
    ) -> bool {
        for i in 0..states.len() {
            if self.states[i] == states[i] {
                continue;
            }
            // remove the element's columns (from the end, so the indices stay valid)
            let mut a = self.owner.len();
            while a > 0 {
                a -= 1;
                if self.owner[a] == i && !self.remove(a) {
                    return false;
                }
            }
            let mut ok = true;
            element_columns(i, &elements[i], states[i], &mut |c| {
                ok = ok && self.add(stick_inverse, c);
            });
            if !ok {
                return false;
            }
            self.states[i] = states[i];
        }
        true
    }

    /// Removes column `j`: the bordered inverse with j moved last (module documentation), then
    /// the last column moved into j.
    fn remove(&mut self, j: usize) -> bool {
        self.updates += 1;
        let r = self.rank();
        let b = &mut self.capacitance_inverse;
        let beta = b[j * r + j];
        let row_max = b[j * r..(j + 1) * r]
            .iter()
            .fold(0.0, |m: f64, x| m.max(x.abs()));
        if self.updates > self.max_updates || beta.abs() <= PIVOT_TOLERANCE * row_max {
            return false;
        }
        // B₁₁ − b₁₂ b₂₁ / β over every entry (row and column j become unused)
        self.bp.clear();
        self.bp.extend((0..r).map(|a| b[a * r + j] / beta));
        self.qb.clear();
        self.qb.extend_from_slice(&b[j * r..(j + 1) * r]);
        for (a, &ca) in self.bp.iter().enumerate() {
            if a != j {
                for (x, &rb) in b[a * r..(a + 1) * r].iter_mut().zip(&self.qb) {
                    *x -= ca * rb;
                }
            }
        }
        // the last index into j, then stride r → r − 1
        let last = r - 1;
        if j != last {
            for a in 0..r {
                b[a * r + j] = b[a * r + last];
            }
            b.copy_within(last * r..last * r + r, j * r);
            b[j * r + j] = b[last * r + last];
            let n = self.n;
            self.z.copy_within(last * n..r * n, j * n);
        }
        for a in 1..last {
            b.copy_within(a * r..a * r + last, a * last);
        }
        b.truncate(last * last);
        self.z.truncate(last * self.n);
        self.v.swap_remove(j);
        self.owner.swap_remove(j);
        self.normal.swap_remove(j);
        true
    }

    /// Adds the column `col` (module documentation).
    fn add(&mut self, stick_inverse: &[f64], col: Column) -> bool {
        let Column {
            owner,
            normal,
            u,
            v,
        } = col;
        self.updates += 1;
        if self.updates > self.max_updates {
            return false;
        }
        let (n, r) = (self.n, self.rank());
        self.z.resize((r + 1) * n, 0.0);
        let (old, new) = self.z.split_at_mut(r * n);
        solve_sparse(stick_inverse, n, &u, new);
        self.p.clear();
        self.p.extend(self.v.iter().map(|va| sparse_dot(va, new)));
        self.q.clear();
        self.q
            .extend(old.chunks_exact(n).map(|zb| sparse_dot(&v, zb)));
        let d = 1.0 + sparse_dot(&v, new);
        let b = &mut self.capacitance_inverse;
        self.bp.clear();
        self.bp.resize(r, 0.0);
        dense::matvec(b, &self.p, &mut self.bp);
        self.qb.clear();
        self.qb.resize(r, 0.0);
        for (a, &qa) in self.q.iter().enumerate() {
            for (x, &bij) in self.qb.iter_mut().zip(&b[a * r..(a + 1) * r]) {
                *x += qa * bij;
            }
        }
        let qbp: f64 = self.q.iter().zip(&self.bp).map(|(a, b)| a * b).sum();
        let s = d - qbp;
        if s.abs() <= PIVOT_TOLERANCE * d.abs().max(qbp.abs()) {
            return false;
        }
        // stride r → r + 1 (rows from the last), then the bordered inverse
        let m = r + 1;
        b.resize(m * m, 0.0);
        for a in (1..r).rev() {
            b.copy_within(a * r..a * r + r, a * m);
        }
        for a in 0..r {
            let c = self.bp[a] / s;
            let row = &mut b[a * m..a * m + m];
            for (x, &qb) in row[..r].iter_mut().zip(&self.qb) {
                *x += c * qb;
            }
            row[r] = -c;
        }
        for (x, &qb) in b[r * m..r * m + r].iter_mut().zip(&self.qb) {
            *x = -qb / s;
        }
        b[r * m + r] = 1.0 / s;
        self.v.push(v);
        self.owner.push(owner);
        self.normal.push(normal);
        true
    }

    /// x = A⁻¹ b for A = A_stick + U Vᵀ, given A_stick⁻¹ (n × n).
    pub fn solve(&self, stick_inverse: &[f64], b: &[f64], x: &mut [f64]) {
        self.solve_with(stick_inverse, b, x, &mut Vec::new());
    }

    /// [`LowRank::solve`] with caller-held scratch of 2r entries (no allocation once its
    /// capacity holds the rank).
    pub fn solve_with(
        &self,
        stick_inverse: &[f64],
        b: &[f64],
        x: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        dense::matvec(stick_inverse, b, x);
        self.add_correction(x, scratch, |_, _| 0.0);
    }

    /// x = A⁻¹ (b + U δ) for A = A_stick + U Vᵀ, given y₀ = A_stick⁻¹ b and the coefficient
    /// δ_a of each column a from `delta(owner, normal)` (its element and whether it is the
    /// element's normal column): x = y₀ + Z B (δ − Vᵀ y₀), since A⁻¹ U = Z B (the Woodbury formula,
    /// Hager 1989). No product with an n × n matrix: O(n r + r²). `scratch` as in
    /// [`LowRank::solve_with`].
    pub fn solve_shifted(
        &self,
        y0: &[f64],
        delta: impl Fn(usize, bool) -> f64,
        x: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        x.copy_from_slice(y0);
        self.add_correction(x, scratch, delta);
    }

    /// x ← x + Z B (δ − Vᵀ x) with δ_a = `delta(owner, normal)` of column a.
    fn add_correction(
        &self,
        x: &mut [f64],
        scratch: &mut Vec<f64>,
        delta: impl Fn(usize, bool) -> f64,
    ) {
        let n = self.n;
        let parts = Parts {
            capacitance_inverse: &self.capacitance_inverse,
            v: &self.v,
            owner: &self.owner,
            normal: &self.normal,
        };
        parts.add_correction(x, scratch, delta, |a| &self.z[a * n..(a + 1) * n]);
    }

    /// The factors without Z, for a cache of many states: the columns of Z are A_stick⁻¹ g_t or
    /// A_stick⁻¹ g_n of their elements whatever the state, held once in a [`ColumnTable`].
    pub fn compact(&self) -> CompactLowRank {
        CompactLowRank {
            capacitance_inverse: self.capacitance_inverse.clone(),
            v: self.v.clone(),
            owner: self.owner.clone(),
            normal: self.normal.clone(),
        }
    }

    /// Memory of the factors (f64 entries).
    pub fn len(&self) -> usize {
        self.z.len() + self.capacitance_inverse.len()
    }

    /// Whether the factors are empty (the all-stick state).
    pub fn is_empty(&self) -> bool {
        self.v.is_empty()
    }
}

/// The parts of a state's factors that the correction reads besides Z: B = (I + VᵀZ)⁻¹ (r × r,
/// row-major), the sparse columns of V and each column's element and direction.
struct Parts<'a> {
    capacitance_inverse: &'a [f64],
    v: &'a [Sparse],
    owner: &'a [usize],
    normal: &'a [bool],
}

impl Parts<'_> {
    /// x ← x + Z B (δ − Vᵀ x) with δ_a = `delta(owner, normal)` and z_a = `column(a)` of column
    /// a (the Woodbury correction, module documentation); `scratch` holds 2r entries.
    fn add_correction<'z>(
        &self,
        x: &mut [f64],
        scratch: &mut Vec<f64>,
        delta: impl Fn(usize, bool) -> f64,
        column: impl Fn(usize) -> &'z [f64],
    ) {
        let r = self.v.len();
        if r == 0 {
            return;
        }
        scratch.clear();
        scratch.resize(2 * r, 0.0);
        let (w, s) = scratch.split_at_mut(r);
        for (a, (wi, v)) in w.iter_mut().zip(self.v).enumerate() {
            *wi = delta(self.owner[a], self.normal[a]) - sparse_dot(v, x);
        }
        dense::matvec(self.capacitance_inverse, w, s);
        dense::add_scaled_columns(x, s, column);
    }
}

/// A_stick⁻¹ g_t and A_stick⁻¹ g_n (when the element applies its normal force) of every element
/// (n each): the columns of Z of every state ([`LowRank::compact`]), the same values as
/// [`LowRank`]'s ([`solve_sparse`] on the same weights).
#[derive(Clone, Debug)]
pub struct ColumnTable {
    n: usize,
    /// Per element: the index of its tangential column (its normal one, if any, next).
    first: Vec<usize>,
    /// The columns, column-major (column c is `z[c n..(c + 1) n]`).
    z: Vec<f64>,
}

impl ColumnTable {
    /// The columns of `elements` given A_stick⁻¹ (n × n, row-major).
    pub fn new(stick_inverse: &[f64], n: usize, elements: &[Element]) -> Self {
        let mut first = Vec::with_capacity(elements.len());
        let mut z = Vec::new();
        for e in elements {
            first.push(z.len() / n.max(1));
            let normal = e.normal.as_ref().filter(|_| e.applies_normal);
            for d in std::iter::once(&e.tangential).chain(normal) {
                let at = z.len();
                z.resize(at + n, 0.0);
                solve_sparse(stick_inverse, n, &d.weights, &mut z[at..]);
            }
        }
        ColumnTable { n, first, z }
    }

    /// The column of element `owner` (its normal direction when `normal`).
    fn column(&self, owner: usize, normal: bool) -> &[f64] {
        let c = self.first[owner] + usize::from(normal);
        &self.z[c * self.n..(c + 1) * self.n]
    }

    /// Memory of the columns (f64 entries).
    pub fn len(&self) -> usize {
        self.z.len()
    }

    /// Whether there are no columns (no elements).
    pub fn is_empty(&self) -> bool {
        self.z.is_empty()
    }
}

/// The factors of one state with Z read from a [`ColumnTable`] ([`LowRank::compact`]): O(r²)
/// entries instead of O(n r), the same solutions to the last bit.
#[derive(Clone, Debug)]
pub struct CompactLowRank {
    capacitance_inverse: Vec<f64>,
    v: Vec<Sparse>,
    owner: Vec<usize>,
    normal: Vec<bool>,
}

impl CompactLowRank {
    fn parts(&self) -> Parts<'_> {
        Parts {
            capacitance_inverse: &self.capacitance_inverse,
            v: &self.v,
            owner: &self.owner,
            normal: &self.normal,
        }
    }

    /// [`LowRank::solve_with`] with the columns of `table`.
    pub fn solve_with(
        &self,
        stick_inverse: &[f64],
        table: &ColumnTable,
        b: &[f64],
        x: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        dense::matvec(stick_inverse, b, x);
        let column = |a: usize| table.column(self.owner[a], self.normal[a]);
        self.parts().add_correction(x, scratch, |_, _| 0.0, column);
    }

    /// [`LowRank::solve_shifted`] with the columns of `table`.
    pub fn solve_shifted(
        &self,
        table: &ColumnTable,
        y0: &[f64],
        delta: impl Fn(usize, bool) -> f64,
        x: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        x.copy_from_slice(y0);
        let column = |a: usize| table.column(self.owner[a], self.normal[a]);
        self.parts().add_correction(x, scratch, delta, column);
    }

    /// Memory of the factors (f64 entries; the sparse columns of V not counted, as in
    /// [`LowRank::len`]).
    pub fn len(&self) -> usize {
        self.capacitance_inverse.len()
    }

    /// Whether the factors are empty (the all-stick state).
    pub fn is_empty(&self) -> bool {
        self.v.is_empty()
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::march::law::{FrictionParams, Sign};
    use crate::march::signal::Harmonic;

    fn dir(w: &[(usize, f64)]) -> Direction {
        Direction {
            weights: w.to_vec(),
            prescribed: Harmonic::default(),
        }
    }

    const ALL: [ContactState; 4] = [
        ContactState::Stick,
        ContactState::Slip(Sign::Positive),
        ContactState::Slip(Sign::Negative),
        ContactState::Separated,
    ];

    /// `count` elements on n = count + 2 DOF (every second one sharing its normal force with the
    /// one before) and a diagonally dominant structural part.
    fn fixture(count: usize) -> (usize, Vec<Element>, Vec<f64>) {
        let n = count + 2;
        let params = FrictionParams {
            kt: 3.0,
            kn: 2.0,
            mu: 0.4,
            n0: 0.5,
        };
        let elements = (0..count)
            .map(|e| Element {
                name: format!("e{e}"),
                tangential: dir(&[(e, 1.0), (e + 1, -0.5 - 0.1 * e as f64)]),
                normal: Some(dir(&[(e / 2 * 2 + 1, 0.8), (e / 2 * 2 + 2, 0.3)])),
                params,
                applies_normal: e % 2 == 0,
            })
            .collect();
        let base = (0..n * n)
            .map(|ij| {
                let (i, j) = (ij / n, ij % n);
                if i == j {
                    10.0 + i as f64
                } else {
                    0.3 / (1.0 + (i + j) as f64)
                }
            })
            .collect();
        (n, elements, base)
    }

    /// The inverse of the all-stick step matrix of `elements` on `base`.
    fn stick_inverse(n: usize, elements: &[Element], base: &[f64]) -> Vec<f64> {
        let mut stick = base.to_vec();
        for e in elements {
            e.add_stiffness(ContactState::Stick, &mut stick, n);
        }
        dense::inverse(&stick, n).unwrap()
    }

    /// Pseudo-random draws in 0..m (a linear congruential sequence from `seed`).
    fn draws(mut seed: u64) -> impl FnMut(usize) -> usize {
        move |m| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as usize % m
        }
    }

    /// The direct solve of A_stick + ΔK_c(states) against the low-rank one.
    fn check(
        n: usize,
        elements: &[Element],
        base: &[f64],
        states: &[ContactState],
        stick_inverse: &[f64],
        lr: &LowRank,
        tolerance: f64,
    ) {
        let mut k = base.to_vec();
        for (e, &s) in elements.iter().zip(states) {
            e.add_stiffness(s, &mut k, n);
        }
        let b: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * i as f64).collect();
        let mut x = vec![0.0; n];
        lr.solve(stick_inverse, &b, &mut x);
        let direct = dense::inverse(&k, n).unwrap();
        let mut y = vec![0.0; n];
        dense::matvec(&direct, &b, &mut y);
        for (a, e) in x.iter().zip(&y) {
            assert!(
                (a - e).abs() < tolerance * e.abs().max(1.0),
                "{states:?}: {a} vs {e}"
            );
        }
    }

    /// A(state)⁻¹ b by the low-rank factors equals the direct solve of A_stick + ΔK_c(state) for
    /// every state of three elements (one sharing its normal force).
    #[test]
    fn low_rank_solve_equals_the_direct_one() {
        let (n, elements, base) = fixture(3);
        let stick_inverse = stick_inverse(n, &elements, &base);
        for code in 0..64 {
            let states = [ALL[code % 4], ALL[(code / 4) % 4], ALL[code / 16]];
            let lr = LowRank::new(&stick_inverse, n, &elements, &states).unwrap();
            assert_eq!(lr.rank(), rank(&elements, &states));
            check(n, &elements, &base, &states, &stick_inverse, &lr, 1e-12);
        }
    }

    /// Factors moved from state to state by column updates (400 random changes of one to three
    /// of 12 elements, whatever their share of the rank) solve like the direct inverse of each
    /// state (1e-10), and the updates are used (a full build only after the allowed number of
    /// updates).
    #[test]
    fn updated_factors_solve_like_the_direct_inverse() {
        let (n, elements, base) = fixture(12);
        let stick_inverse = stick_inverse(n, &elements, &base);
        let mut states = vec![ContactState::Stick; elements.len()];
        let mut lr = LowRank::new(&stick_inverse, n, &elements, &states).unwrap();
        let mut next = draws(12345);
        let (mut updated, mut built) = (0, 0);
        for _ in 0..400 {
            for _ in 0..1 + next(3) {
                let e = next(elements.len());
                states[e] = ALL[next(4)];
            }
            let changed = lr.differences(&states);
            if lr.update_columns(&stick_inverse, &elements, &states) {
                updated += usize::from(changed > 0);
            } else {
                lr = LowRank::new(&stick_inverse, n, &elements, &states).unwrap();
                built += 1;
            }
            assert_eq!(lr.states(), &states[..]);
            assert_eq!(lr.rank(), rank(&elements, &states));
            check(n, &elements, &base, &states, &stick_inverse, &lr, 1e-10);
        }
        assert!(
            updated > 300 && built < 40,
            "{updated} updates, {built} builds"
        );
    }

    /// A change of many columns is refused by [`LowRank::update`] (the factors stay those of the
    /// old state) and built anew; moving the factors there by column updates instead gives the
    /// same solve as the new build and the direct inverse (1e-10), for changes of 2 to 6 of 40
    /// elements and of all 40 drawn anew. A change of at most [`UPDATE_FRACTION`] of the rank is
    /// made by updates.
    #[test]
    fn many_changed_columns_are_built_anew_with_the_same_solve() {
        let (n, elements, base) = fixture(40);
        let stick_inverse = stick_inverse(n, &elements, &base);
        let mut next = draws(987);
        let b: Vec<f64> = (0..n).map(|i| 1.0 - 0.3 * i as f64).collect();
        let (mut refused, mut accepted) = (0, 0);
        for round in 0..60 {
            let old: Vec<ContactState> = (0..elements.len()).map(|_| ALL[next(4)]).collect();
            let lr = LowRank::new(&stick_inverse, n, &elements, &old).unwrap();
            // even rounds: two to six elements change; odd rounds: every element is drawn anew
            let mut states = old.clone();
            if round % 2 == 0 {
                for _ in 0..2 + round % 5 {
                    let e = next(elements.len());
                    states[e] = ALL[next(4)];
                }
            } else {
                states.iter_mut().for_each(|s| *s = ALL[next(4)]);
            }
            let changed = lr.changed_columns(&elements, &states);
            let limit = UPDATE_FRACTION * lr.rank().max(rank(&elements, &states)) as f64;
            // the rule
            let mut ruled = lr.clone();
            if ruled.update(&stick_inverse, &elements, &states) {
                assert!(
                    changed as f64 <= limit,
                    "{changed} columns updated, limit {limit}"
                );
                accepted += 1;
            } else if changed as f64 > limit {
                assert_eq!(ruled.states(), &old[..]);
                check(n, &elements, &base, &old, &stick_inverse, &ruled, 1e-10);
                refused += 1;
            }
            // both paths to the new state
            let mut updated = lr.clone();
            updated.max_updates = usize::MAX;
            assert!(updated.update_columns(&stick_inverse, &elements, &states));
            let built = LowRank::new(&stick_inverse, n, &elements, &states).unwrap();
            let (mut x_u, mut x_b) = (vec![0.0; n], vec![0.0; n]);
            updated.solve(&stick_inverse, &b, &mut x_u);
            built.solve(&stick_inverse, &b, &mut x_b);
            let scale = dense::norm_inf(&x_b);
            for (u, v) in x_u.iter().zip(&x_b) {
                assert!(
                    (u - v).abs() < 1e-10 * scale,
                    "{u} vs {v} ({changed} columns)"
                );
            }
            check(
                n,
                &elements,
                &base,
                &states,
                &stick_inverse,
                &updated,
                1e-10,
            );
        }
        assert!(
            refused > 20 && accepted > 20,
            "{refused} refused, {accepted} accepted"
        );
    }
}
