//! Parallel assembly of the global stiffness and mass matrices.
//!
//! 1. The sparsity pattern is built once from the node adjacency (two nodes are adjacent when an
//!    element holds both). K stores a dense 3×3 block per adjacent node pair: column 3j + c holds
//!    rows 3i, 3i+1, 3i+2 of every node i adjacent to j (i ascending). The consistent mass is
//!    M = M̃ ⊗ I₃, so M stores only the entries with equal components (row 3i + c in column 3j + c):
//!    its pattern is the subset of K's with row ≡ column (mod 3), a third of the entries.
//! 2. Elements are ordered by their smallest node index (so consecutive elements touch nearby
//!    columns), cut into chunks of [`CHUNK`] consecutive elements, and the chunks coloured greedily
//!    so that no two chunks of one colour share a node.
//! 3. Colour by colour, chunks run in parallel (rayon); each computes its element matrices one by one
//!    and adds them straight into the value arrays. Chunks of one colour write disjoint entries, so
//!    there are no locks and no triplet list (a million-DOF tetra10 model would need ~5 GB of
//!    triplets). The summation order of every entry is fixed by the schedule, so the result does
//!    not depend on the thread count.
//!
//! Memory: the two matrices (8-byte values and 8-byte row indices per entry) plus the node adjacency
//! and the element schedule (a few bytes per node and element).

use std::ops::Range;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;

use super::element::{self, default_degrees, BadJacobian, Scratch, Tabulated};
use super::material::{block_group_names, describe_groups, Materials};
use super::Quadrature;
use crate::error::{Error, Result};
use crate::matrix_io::DofMap;
use crate::mesh::{ElementBlock, ElementType, Mesh};

/// The assembled structural matrices over all 3·n_nodes DOF (DOF 3i + c, `docs/conventions.md` §1),
/// both stored with both triangles (full symmetric storage). M's pattern is the subset of K's with
/// row ≡ column (mod 3) (see the module documentation); K − σM has K's pattern.
#[derive(Clone, Debug)]
pub struct Assembled {
    /// Stiffness K (N/m).
    pub k: SparseColMat<usize, f64>,
    /// Consistent mass M (kg).
    pub m: SparseColMat<usize, f64>,
}

impl Assembled {
    /// Number of DOF (rows of K and M).
    pub fn n_dofs(&self) -> usize {
        self.k.nrows()
    }

    /// The DOF map of the full matrices: row 3i + c is component c of node index i.
    pub fn dof_map(&self, mesh: &Mesh) -> DofMap {
        DofMap::structural(&mesh.node_tags)
    }
}

/// Assembles K = Σ Kₑ and M = Σ Mₑ over every volume (3-D) element of `mesh`; 0-, 1- and 2-D
/// blocks are ignored. Each volume element takes the material of its volume group if
/// `materials.by_group` lists it, else `materials.default`. Quadrature per [`Quadrature`].
///
/// Nodes that belong to no volume element get empty rows and columns (zero diagonal): clamp them
/// or they make K and M singular.
///
/// Errors ([`Error::Input`]): no volume element; an unsupported element type (pyramid14); an
/// invalid material or one given for a missing or non-volume group; volume elements without a
/// material; a node index out of range; a non-positive Jacobian determinant at a quadrature point
/// (the message names the first such element's tag and the mesh file).
pub fn assemble(mesh: &Mesh, materials: &Materials, quad: &Quadrature) -> Result<Assembled> {
    materials.validate(mesh)?;
    let (tables, volumes) = prepare(mesh, materials, quad)?;
    let elems = Elements::new(volumes)?;
    let target = Target::new(Adjacency::new(&elems, mesh.num_nodes()));
    let schedule = Schedule::new(&elems, mesh.num_nodes());
    let ctx = Ctx {
        mesh,
        elems: &elems,
        tables: &tables,
    };
    let bad = compute(&ctx, &schedule, &target);
    if let Some(first) = bad.first() {
        return Err(bad_jacobian_error(
            mesh,
            &elems,
            &tables,
            first,
            bad.count(),
        ));
    }
    Ok(target.into_matrices())
}

/// Computes and adds every element's matrices into `target`, colour by colour, the chunks of a
/// colour in parallel. Elements with a bad Jacobian are skipped and recorded.
fn compute(ctx: &Ctx, schedule: &Schedule, target: &Target) -> BadTracker {
    let bad = BadTracker::default();
    let max_nn = ctx.tables.iter().map(|t| t.1.nn).max().unwrap_or(0);
    for colour in &schedule.colours {
        colour.par_iter().for_each_init(
            || Work::new(max_nn),
            |w, chunk| {
                for &e in &schedule.order[chunk.clone()] {
                    match ctx.element_matrices(e as usize, w) {
                        Ok(()) => target.scatter(ctx.elems.nodes(e as usize), w),
                        Err(_) => bad.record(e as usize),
                    }
                }
            },
        );
    }
    bad
}

/// The matrices being assembled: node adjacency, the layouts of K and M and their values.
struct Target {
    adj: Adjacency,
    k_layout: Layout,
    m_layout: Layout,
    kv: Vec<AtomicU64>,
    mv: Vec<AtomicU64>,
}

impl Target {
    fn new(adj: Adjacency) -> Target {
        let k_layout = Layout::new(&adj, 3);
        let m_layout = Layout::new(&adj, 1);
        let kv = zeros(k_layout.nnz());
        let mv = zeros(m_layout.nnz());
        Target {
            adj,
            k_layout,
            m_layout,
            kv,
            mv,
        }
    }

    /// Adds the element matrices in `w` (element nodes `nodes`) into K and M. Only called for
    /// chunks of one colour at a time, so no two threads touch the same entry.
    fn scatter(&self, nodes: &[u32], w: &Work) {
        let nn = nodes.len();
        for (a, &j) in nodes.iter().enumerate() {
            let j = j as usize;
            let nbrs = self.adj.of(j);
            for (b, &i) in nodes.iter().enumerate() {
                // Present by construction: the adjacency was built from these elements.
                let Ok(pos) = nbrs.binary_search(&i) else {
                    continue;
                };
                let blk = &w.ke[(b * nn + a) * 9..(b * nn + a + 1) * 9];
                let mass = w.me[b * nn + a];
                for c in 0..3 {
                    let base = self.k_layout.at(j, c, pos);
                    for r in 0..3 {
                        add(&self.kv[base + r], blk[3 * r + c]);
                    }
                    add(&self.mv[self.m_layout.at(j, c, pos)], mass);
                }
            }
        }
    }

    /// K and M as CSC matrices.
    fn into_matrices(self) -> Assembled {
        let k_rows = self.k_layout.row_idx(&self.adj);
        let k = self.k_layout.into_matrix(k_rows, self.kv);
        let m_rows = self.m_layout.row_idx(&self.adj);
        let m = self.m_layout.into_matrix(m_rows, self.mv);
        Assembled { k, m }
    }
}

/// A zeroed value array that threads can share (see [`add`]).
fn zeros(n: usize) -> Vec<AtomicU64> {
    (0..n).into_par_iter().map(|_| AtomicU64::new(0)).collect()
}

/// One element type's tabulated stiffness and mass rules.
type Tables = (ElementType, Tabulated, Tabulated);

/// A volume block with its material data and the index of its tables.
#[derive(Clone, Copy)]
struct Volume<'m> {
    block: &'m ElementBlock,
    /// Lamé constants (λ, μ), Pa.
    lame: (f64, f64),
    /// Density, kg/m³.
    rho: f64,
    table: usize,
}

/// Checks the volume blocks (supported type, material, node indices) and tabulates the rules.
fn prepare<'m>(
    mesh: &'m Mesh,
    materials: &Materials,
    quad: &Quadrature,
) -> Result<(Vec<Tables>, Vec<Volume<'m>>)> {
    if mesh.coords.len() != mesh.num_nodes() {
        return Err(Error::input(format!(
            "{}: the mesh has {} node tags but {} coordinates",
            mesh.source_name(),
            mesh.num_nodes(),
            mesh.coords.len()
        )));
    }
    let mut tables: Vec<Tables> = Vec::new();
    let volumes = mesh
        .blocks
        .iter()
        .filter(|b| b.kind.dim() == 3 && !b.is_empty())
        .map(|block| prepare_block(mesh, block, materials, quad, &mut tables))
        .collect::<Result<Vec<_>>>()?;
    if volumes.is_empty() {
        return Err(Error::input(format!(
            "{}: the mesh has no volume (3-D) elements to assemble; mesh the volume in Gmsh (Mesh > 3D) and save its physical volume group",
            mesh.source_name()
        )));
    }
    Ok((tables, volumes))
}

/// One volume block: its type is supported, its material resolved, its node indices in range, and
/// the rules of its type tabulated (once per type, in `tables`).
fn prepare_block<'m>(
    mesh: &Mesh,
    block: &'m ElementBlock,
    materials: &Materials,
    quad: &Quadrature,
    tables: &mut Vec<Tables>,
) -> Result<Volume<'m>> {
    let describe = || {
        format!(
            "{}: volume entity {} ({})",
            mesh.source_name(),
            block.entity,
            describe_groups(&block_group_names(mesh, block))
        )
    };
    let (ds, dm) = default_degrees(block.kind).ok_or_else(|| {
        Error::input(format!(
            "{}: {}",
            describe(),
            element::unsupported(block.kind)
        ))
    })?;
    let material = materials.for_block(mesh, block)?;
    check_indices(mesh, block, &describe)?;
    let table = match tables.iter().position(|t| t.0 == block.kind) {
        Some(t) => t,
        None => {
            let s = Tabulated::for_degree(block.kind, quad.stiffness_degree.unwrap_or(ds))
                .map_err(|e| key_error("stiffness_degree", e))?;
            let m = Tabulated::for_degree(block.kind, quad.mass_degree.unwrap_or(dm))
                .map_err(|e| key_error("mass_degree", e))?;
            tables.push((block.kind, s, m));
            tables.len() - 1
        }
    };
    Ok(Volume {
        block,
        lame: material.lame(),
        rho: material.density,
        table,
    })
}

/// Prefixes a quadrature error with the setting it comes from.
fn key_error(key: &str, e: Error) -> Error {
    Error::input(format!("quadrature {key}: {e}"))
}

/// Errors if a node index of `block` is out of range.
fn check_indices(mesh: &Mesh, block: &ElementBlock, describe: &dyn Fn() -> String) -> Result<()> {
    let n = mesh.num_nodes();
    match block
        .connectivity
        .par_iter()
        .position_any(|&i| i as usize >= n)
    {
        None => Ok(()),
        Some(p) => Err(Error::input(format!(
            "{}: element {} refers to node index {}, but the mesh has {n} nodes",
            describe(),
            block.tags.at(p / block.kind.num_nodes()),
            block.connectivity[p]
        ))),
    }
}

/// All volume elements, numbered 0.. across the volume blocks in order.
struct Elements<'m> {
    volumes: Vec<Volume<'m>>,
    /// `offsets[b]` is the number of the first element of volume block b; last entry the total.
    offsets: Vec<usize>,
}

impl<'m> Elements<'m> {
    fn new(volumes: Vec<Volume<'m>>) -> Result<Self> {
        let mut offsets = vec![0];
        for v in &volumes {
            offsets.push(offsets[offsets.len() - 1] + v.block.len());
        }
        if offsets[offsets.len() - 1] > u32::MAX as usize {
            return Err(Error::input(
                "more than 2³² volume elements: the mesh is too large",
            ));
        }
        Ok(Elements { volumes, offsets })
    }

    fn len(&self) -> usize {
        self.offsets[self.offsets.len() - 1]
    }

    /// (volume block, element within it) of element `e`.
    fn locate(&self, e: usize) -> (usize, usize) {
        let b = self.offsets.partition_point(|&o| o <= e) - 1;
        (b, e - self.offsets[b])
    }

    fn nodes(&self, e: usize) -> &'m [u32] {
        let (b, i) = self.locate(e);
        self.volumes[b].block.element(i)
    }
}

/// Scratch buffers of one worker thread.
struct Work {
    xs: Vec<[f64; 3]>,
    scratch: Scratch,
    /// Stiffness blocks (see `element::stiffness_blocks`).
    ke: Vec<f64>,
    /// Scalar mass (nn × nn).
    me: Vec<f64>,
}

impl Work {
    fn new(max_nn: usize) -> Self {
        Work {
            xs: vec![[0.0; 3]; max_nn],
            scratch: Scratch::new(max_nn),
            ke: vec![0.0; max_nn * max_nn * 9],
            me: vec![0.0; max_nn * max_nn],
        }
    }
}

/// What the element computation needs.
struct Ctx<'a, 'm> {
    mesh: &'m Mesh,
    elems: &'a Elements<'m>,
    tables: &'a [Tables],
}

impl Ctx<'_, '_> {
    /// Kₑ and Mₑ of element `e` into `w`.
    fn element_matrices(&self, e: usize, w: &mut Work) -> std::result::Result<(), BadJacobian> {
        let (b, i) = self.elems.locate(e);
        let vol = &self.elems.volumes[b];
        let nodes = vol.block.element(i);
        let (_, ts, tm) = &self.tables[vol.table];
        for (x, &n) in w.xs.iter_mut().zip(nodes) {
            *x = self.mesh.coords[n as usize];
        }
        let xs = &w.xs[..nodes.len()];
        element::stiffness_blocks(ts, xs, vol.lame, &mut w.scratch, &mut w.ke)?;
        element::mass_scalar(tm, xs, vol.rho, &mut w.me)
    }
}

/// The first (lowest-numbered) element with a bad Jacobian and the number of such elements.
#[derive(Default)]
struct BadTracker {
    first: AtomicUsize,
    count: AtomicUsize,
}

impl BadTracker {
    fn record(&self, e: usize) {
        // `first` stores e + 1 so that the default 0 means "none".
        self.count.fetch_add(1, Ordering::Relaxed);
        let _ = self
            .first
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |f| {
                (f == 0 || e + 1 < f).then_some(e + 1)
            });
    }

    fn first(&self) -> Option<usize> {
        self.first.load(Ordering::Relaxed).checked_sub(1)
    }

    fn count(&self) -> usize {
        self.count.load(Ordering::Relaxed)
    }
}

/// The error for element `e` (recomputed serially for the details).
fn bad_jacobian_error(
    mesh: &Mesh,
    elems: &Elements,
    tables: &[Tables],
    e: usize,
    count: usize,
) -> Error {
    let (b, i) = elems.locate(e);
    let vol = &elems.volumes[b];
    let nodes = vol.block.element(i);
    let xs: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n as usize]).collect();
    let (_, ts, tm) = &tables[vol.table];
    let detail = element::volume_of(ts, &xs)
        .and_then(|_| element::volume_of(tm, &xs))
        .err()
        .map(|b| b.describe())
        .unwrap_or_default();
    let others = if count > 1 {
        format!(" ({} more elements are too)", count - 1)
    } else {
        String::new()
    };
    Error::input(format!(
        "{}: {} element {} (volume entity {}) has a non-positive Jacobian determinant ({detail}): it is inverted or degenerate{others}; check its node order and regenerate or repair the mesh",
        mesh.source_name(),
        vol.block.kind,
        vol.block.tags.at(i),
        vol.block.entity
    ))
}

/// Elements per chunk of the schedule.
pub const CHUNK: usize = 32;

/// The order in which elements are processed: chunks of consecutive elements (in `order`),
/// grouped by colour.
struct Schedule {
    /// Element numbers sorted by smallest node index.
    order: Vec<u32>,
    /// Per colour, the ranges of `order` that form its chunks; no two chunks of a colour share a node.
    colours: Vec<Vec<Range<usize>>>,
}

impl Schedule {
    fn new(elems: &Elements, n_nodes: usize) -> Schedule {
        let mut keyed: Vec<(u32, u32)> = (0..elems.len())
            .into_par_iter()
            .map(|e| (elems.nodes(e).iter().copied().min().unwrap_or(0), e as u32))
            .collect();
        keyed.par_sort_unstable();
        let order: Vec<u32> = keyed.into_iter().map(|(_, e)| e).collect();
        let chunks: Vec<Range<usize>> = (0..order.len())
            .step_by(CHUNK)
            .map(|s| s..(s + CHUNK).min(order.len()))
            .collect();
        let nodes_of = |c: &Range<usize>| {
            order[c.clone()]
                .iter()
                .flat_map(|&e| elems.nodes(e as usize))
        };
        let colours = colour(&chunks, nodes_of, n_nodes);
        Schedule { order, colours }
    }
}

/// Greedy colouring of `items` (by the nodes each touches) so that no two items of one colour share
/// a node. Colours are assigned 64 at a time with one bit mask per node; each colour keeps the
/// items in their original order.
fn colour<'a, T: Clone, I: Iterator<Item = &'a u32>>(
    items: &[T],
    nodes_of: impl Fn(&T) -> I,
    n_nodes: usize,
) -> Vec<Vec<T>> {
    let mut colours: Vec<Vec<T>> = Vec::new();
    let mut pending: Vec<usize> = (0..items.len()).collect();
    let mut masks = vec![0u64; n_nodes];
    while !pending.is_empty() {
        let base = colours.len();
        colours.extend((0..64).map(|_| Vec::new()));
        let mut next = Vec::new();
        for &k in &pending {
            let used = nodes_of(&items[k]).fold(0u64, |m, &n| m | masks[n as usize]);
            if used == u64::MAX {
                next.push(k);
                continue;
            }
            let c = used.trailing_ones();
            for &n in nodes_of(&items[k]) {
                masks[n as usize] |= 1 << c;
            }
            colours[base + c as usize].push(items[k].clone());
        }
        masks.fill(0);
        pending = next;
    }
    colours.retain(|c| !c.is_empty());
    colours
}

/// Node adjacency in CSR form: the nodes sharing an element with node j (j included), ascending.
struct Adjacency {
    ptr: Vec<usize>,
    nodes: Vec<u32>,
}

impl Adjacency {
    fn new(elems: &Elements, n_nodes: usize) -> Adjacency {
        let (inc_ptr, inc) = incidence(elems, n_nodes);
        let lists: Vec<Vec<u32>> = (0..n_nodes)
            .into_par_iter()
            .map(|j| {
                let mut v = vec![j as u32];
                for &e in &inc[inc_ptr[j]..inc_ptr[j + 1]] {
                    v.extend_from_slice(elems.nodes(e as usize));
                }
                v.sort_unstable();
                v.dedup();
                v
            })
            .collect();
        let mut ptr = Vec::with_capacity(n_nodes + 1);
        ptr.push(0);
        for l in &lists {
            ptr.push(ptr[ptr.len() - 1] + l.len());
        }
        let nodes: Vec<u32> = lists.into_par_iter().flatten().collect();
        Adjacency { ptr, nodes }
    }

    fn of(&self, j: usize) -> &[u32] {
        &self.nodes[self.ptr[j]..self.ptr[j + 1]]
    }

    fn n_nodes(&self) -> usize {
        self.ptr.len() - 1
    }
}

/// Node → element incidence in CSR form.
fn incidence(elems: &Elements, n_nodes: usize) -> (Vec<usize>, Vec<u32>) {
    let mut ptr = vec![0usize; n_nodes + 1];
    for e in 0..elems.len() {
        for &n in elems.nodes(e) {
            ptr[n as usize + 1] += 1;
        }
    }
    for j in 0..n_nodes {
        ptr[j + 1] += ptr[j];
    }
    let mut fill = ptr.clone();
    let mut inc = vec![0u32; ptr[n_nodes]];
    for e in 0..elems.len() {
        for &n in elems.nodes(e) {
            inc[fill[n as usize]] = e as u32;
            fill[n as usize] += 1;
        }
    }
    (ptr, inc)
}

/// Nodes per parallel task when filling the row indices.
const NODE_GROUP: usize = 2048;

/// The CSC layout of one matrix on the node adjacency: `width` rows per adjacent node in each
/// column — 3 for K (rows 3i, 3i+1, 3i+2), 1 for M (row 3i + c in column 3j + c).
struct Layout {
    width: usize,
    /// Column pointers (3·n_nodes + 1).
    col_ptr: Vec<usize>,
}

impl Layout {
    fn new(adj: &Adjacency, width: usize) -> Layout {
        let n = adj.n_nodes();
        // Node j's three columns each hold width·deg(j) rows, from 3·width·adj.ptr[j].
        let mut col_ptr = Vec::with_capacity(3 * n + 1);
        for j in 0..n {
            let deg = adj.ptr[j + 1] - adj.ptr[j];
            col_ptr.extend((0..3).map(|c| width * (3 * adj.ptr[j] + c * deg)));
        }
        col_ptr.push(3 * width * adj.ptr[n]);
        Layout { width, col_ptr }
    }

    fn nnz(&self) -> usize {
        self.col_ptr[self.col_ptr.len() - 1]
    }

    /// Index in the value array of the first entry of adjacent node number `pos` in column 3j + c.
    fn at(&self, j: usize, c: usize, pos: usize) -> usize {
        self.col_ptr[3 * j + c] + self.width * pos
    }

    /// The row indices, filled in parallel by groups of nodes.
    fn row_idx(&self, adj: &Adjacency) -> Vec<usize> {
        let n = adj.n_nodes();
        let mut rows = vec![0usize; self.nnz()];
        let bounds: Vec<usize> = (0..n)
            .step_by(NODE_GROUP)
            .chain([n])
            .map(|j| self.col_ptr[3 * j])
            .collect();
        split_at_bounds(&mut rows, &bounds)
            .into_par_iter()
            .enumerate()
            .for_each(|(g, piece)| {
                let mut out = piece.iter_mut();
                for j in g * NODE_GROUP..((g + 1) * NODE_GROUP).min(n) {
                    for c in 0..3 {
                        for &i in adj.of(j) {
                            let rows = if self.width == 3 { 0..3 } else { c..c + 1 };
                            for r in rows {
                                if let Some(slot) = out.next() {
                                    *slot = 3 * i as usize + r;
                                }
                            }
                        }
                    }
                }
            });
        rows
    }

    /// The assembled matrix from the row indices and the values.
    fn into_matrix(self, row_idx: Vec<usize>, vals: Vec<AtomicU64>) -> SparseColMat<usize, f64> {
        let n = self.col_ptr.len() - 1;
        let vals: Vec<f64> = vals
            .into_iter()
            .map(|a| f64::from_bits(a.into_inner()))
            .collect();
        SparseColMat::new(
            SymbolicSparseColMat::new_checked(n, n, self.col_ptr, None, row_idx),
            vals,
        )
    }
}

/// `slot += x`. Not an atomic read-modify-write: the schedule guarantees exclusive access to the
/// entry; the atomic type only makes the shared array `Sync` without `unsafe` (a relaxed load and
/// store compile to plain moves).
fn add(slot: &AtomicU64, x: f64) {
    let v = f64::from_bits(slot.load(Ordering::Relaxed)) + x;
    slot.store(v.to_bits(), Ordering::Relaxed);
}

/// Splits `data` into the consecutive pieces `data[bounds[k] - bounds[0]..bounds[k+1] - bounds[0]]`.
pub(crate) fn split_at_bounds<'a, T>(data: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
    let mut pieces = Vec::with_capacity(bounds.len().saturating_sub(1));
    let mut rest = data;
    for w in bounds.windows(2) {
        let (head, tail) = rest.split_at_mut(w[1] - w[0]);
        pieces.push(head);
        rest = tail;
    }
    pieces
}
