//! Nested-dissection fill-reducing ordering of a symmetric sparsity pattern, for the sparse
//! Cholesky factorisation of K − σM (handed to faer as `SymmetricOrdering::Custom`).
//!
//! # Method (George, SIAM J. Numer. Anal. 10 (1973) 345; level-structure separators as in
//! George & Liu, "Computer Solution of Large Sparse Positive Definite Systems", 1981, ch. 8)
//! 1. **Compression.** DOFs whose closed neighbourhoods (column patterns, diagonal included) are
//!    identical — the 3 displacement components of a finite-element node — are merged into one
//!    graph vertex of weight = number of DOFs. The graph of an FE model shrinks ~3× in vertices
//!    and ~9× in edges; the ordering keeps the DOFs of a vertex consecutive.
//! 2. **Recursive bisection with vertex separators.** For a connected vertex set: a
//!    pseudo-peripheral vertex (repeated breadth-first search from the last level's vertex of
//!    smallest degree until the eccentricity stops growing), its level structure L_0..L_h, and as
//!    separator S the lightest level L_l among those leaving at least 30 % of the weight on either
//!    side (the weighted median level if none does). Every vertex of S without a neighbour in
//!    L_{l+1} is moved to the lower part (it does not separate anything), which thins S. The
//!    parts A = L_0..L_{l−1} ∪ moved and B = L_{l+1}..L_h are ordered first (recursively), S last.
//!    Disconnected sets are split into their components first.
//! 3. **Leaves** of at most [`LEAF_WEIGHT`] DOFs are numbered in their given order.
//!
//! In a separator-last ordering no fill joins A and B, so the factor of a d-dimensional mesh with
//! separators of size n^((d−1)/d) has O(n^{4/3}) nonzeros in 3-D instead of the larger fill of a
//! local (minimum-degree) ordering; the level sets of a breadth-first search are the cheapest
//! separators that need no node coordinates (K − σM carries none). Cost: O(nnz · log n) time,
//! O(nnz / 9 + n) memory for an FE pattern.

use faer::sparse::SymbolicSparseColMatRef;

/// Largest number of DOFs of a part that is not dissected further.
pub(super) const LEAF_WEIGHT: usize = 64;

/// Smallest fraction of the weight a separator must leave on each side to be preferred over the
/// weighted median level.
const MIN_SIDE_FRACTION: f64 = 0.3;

/// Largest number of breadth-first searches spent looking for a pseudo-peripheral vertex.
const PERIPHERAL_SEARCHES: usize = 5;

/// A vertex-weighted undirected graph in compressed sparse row form (no self loops).
struct Graph {
    /// Start of the neighbours of vertex v in `adj`: `adj[ptr[v]..ptr[v + 1]]`.
    ptr: Vec<usize>,
    adj: Vec<usize>,
    /// Number of DOFs merged into each vertex.
    weight: Vec<usize>,
}

impl Graph {
    fn neighbours(&self, v: usize) -> &[usize] {
        &self.adj[self.ptr[v]..self.ptr[v + 1]]
    }

    fn len(&self) -> usize {
        self.weight.len()
    }
}

/// The nested-dissection ordering of the symmetric pattern `a` (both triangles stored, square):
/// `order[new] = old`, a permutation of `0..n` (see the module documentation).
pub(super) fn nested_dissection(a: SymbolicSparseColMatRef<'_, usize>) -> Vec<usize> {
    let (groups, graph) = compress(a);
    let vertex_order = dissect(&graph);
    let mut order = Vec::with_capacity(a.ncols());
    for v in vertex_order {
        order.extend_from_slice(&groups[v]);
    }
    order
}

/// The inverse of a permutation `order[new] = old`: `inv[old] = new`.
pub(super) fn inverse(order: &[usize]) -> Vec<usize> {
    let mut inv = vec![0; order.len()];
    for (new, &old) in order.iter().enumerate() {
        inv[old] = new;
    }
    inv
}

/// Merges columns with identical row patterns (diagonal included) into weighted vertices;
/// returns the DOFs of every vertex and the quotient graph.
fn compress(a: SymbolicSparseColMatRef<'_, usize>) -> (Vec<Vec<usize>>, Graph) {
    let n = a.ncols();
    let closed = |j: usize| -> Vec<usize> {
        let mut rows: Vec<usize> = a.row_idx_of_col(j).chain(std::iter::once(j)).collect();
        rows.sort_unstable();
        rows.dedup();
        rows
    };
    let mut keyed: Vec<(u64, usize)> = (0..n).map(|j| (pattern_hash(&closed(j)), j)).collect();
    keyed.sort_unstable();
    let mut vertex_of = vec![usize::MAX; n];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut start = 0;
    while start < keyed.len() {
        let mut end = start + 1;
        while end < keyed.len() && keyed[end].0 == keyed[start].0 {
            end += 1;
        }
        // Equal hashes: split into truly identical patterns.
        let mut reps: Vec<(Vec<usize>, usize)> = Vec::new();
        for &(_, j) in &keyed[start..end] {
            let p = closed(j);
            match reps.iter().find(|(q, _)| *q == p) {
                Some(&(_, g)) => {
                    groups[g].push(j);
                    vertex_of[j] = g;
                }
                None => {
                    groups.push(vec![j]);
                    vertex_of[j] = groups.len() - 1;
                    reps.push((p, groups.len() - 1));
                }
            }
        }
        start = end;
    }
    for g in &mut groups {
        g.sort_unstable();
    }
    let mut ptr = Vec::with_capacity(groups.len() + 1);
    ptr.push(0);
    let mut adj = Vec::new();
    for (v, g) in groups.iter().enumerate() {
        let first = adj.len();
        adj.extend(
            a.row_idx_of_col(g[0])
                .map(|r| vertex_of[r])
                .filter(|&u| u != v),
        );
        adj[first..].sort_unstable();
        let mut unique = first;
        for k in first..adj.len() {
            if k == first || adj[k] != adj[unique - 1] {
                adj[unique] = adj[k];
                unique += 1;
            }
        }
        adj.truncate(unique);
        ptr.push(adj.len());
    }
    let weight = groups.iter().map(Vec::len).collect();
    (groups, Graph { ptr, adj, weight })
}

/// FNV-1a hash of a row pattern.
fn pattern_hash(rows: &[usize]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &r in rows {
        for byte in (r as u64).to_le_bytes() {
            h ^= u64::from(byte);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// Work items of the iterative dissection: a vertex set to dissect, or one to emit as is.
enum Task {
    Dissect(Vec<usize>),
    Emit(Vec<usize>),
}

/// Scratch state of the dissection: per-vertex stamps for set membership and visits, and the
/// breadth-first level of each vertex.
struct Scratch {
    member: Vec<u32>,
    visited: Vec<u32>,
    level: Vec<usize>,
    stamp: u32,
}

impl Scratch {
    fn new(n: usize) -> Self {
        Scratch {
            member: vec![0; n],
            visited: vec![0; n],
            level: vec![0; n],
            stamp: 0,
        }
    }

    fn next_stamp(&mut self) -> u32 {
        self.stamp += 1;
        self.stamp
    }
}

/// The nested-dissection order of the vertices of `g` (separators after the parts they split).
fn dissect(g: &Graph) -> Vec<usize> {
    let mut order = Vec::with_capacity(g.len());
    let mut scratch = Scratch::new(g.len());
    let mut tasks = vec![Task::Dissect((0..g.len()).collect())];
    while let Some(task) = tasks.pop() {
        match task {
            Task::Emit(vs) => order.extend(vs),
            Task::Dissect(vs) => split(g, vs, &mut scratch, &mut tasks),
        }
    }
    order
}

/// Pushes the tasks that order `vs`: its components, or parts A, B and separator S (popped in
/// the order A, B, S), or `vs` itself when it is a leaf or cannot be split.
fn split(g: &Graph, vs: Vec<usize>, s: &mut Scratch, tasks: &mut Vec<Task>) {
    let total: usize = vs.iter().map(|&v| g.weight[v]).sum();
    if total <= LEAF_WEIGHT {
        tasks.push(Task::Emit(vs));
        return;
    }
    let member = s.next_stamp();
    for &v in &vs {
        s.member[v] = member;
    }
    let component = bfs(g, vs[0], member, s);
    if component.iter().map(|l| l.len()).sum::<usize>() < vs.len() {
        push_components(g, &vs, member, s, tasks);
        return;
    }
    let levels = pseudo_peripheral_levels(g, vs[0], member, s, component);
    let Some(l) = separator_level(g, &levels, total) else {
        tasks.push(Task::Emit(vs));
        return;
    };
    let (mut a, mut sep) = (Vec::new(), Vec::new());
    for level in &levels[..l] {
        a.extend_from_slice(level);
    }
    for &v in &levels[l] {
        let separates = g
            .neighbours(v)
            .iter()
            .any(|&u| s.member[u] == member && s.level[u] == l + 1);
        if separates {
            sep.push(v);
        } else {
            a.push(v);
        }
    }
    let b: Vec<usize> = levels[l + 1..].concat();
    tasks.push(Task::Emit(sep));
    tasks.push(Task::Dissect(b));
    tasks.push(Task::Dissect(a));
}

/// Splits the members of `vs` (stamped `member`) into connected components, one task each.
fn push_components(g: &Graph, vs: &[usize], member: u32, s: &mut Scratch, tasks: &mut Vec<Task>) {
    let seen = s.next_stamp();
    for &root in vs {
        if s.member[root] != member || s.visited[root] == seen {
            continue;
        }
        let mut comp = vec![root];
        s.visited[root] = seen;
        let mut head = 0;
        while head < comp.len() {
            let v = comp[head];
            head += 1;
            for &u in g.neighbours(v) {
                if s.member[u] == member && s.visited[u] != seen {
                    s.visited[u] = seen;
                    comp.push(u);
                }
            }
        }
        tasks.push(Task::Dissect(comp));
    }
}

/// Breadth-first level structure from `root` over the vertices stamped `member`; sets
/// `s.level` of every reached vertex.
fn bfs(g: &Graph, root: usize, member: u32, s: &mut Scratch) -> Vec<Vec<usize>> {
    let seen = s.next_stamp();
    s.visited[root] = seen;
    s.level[root] = 0;
    let mut levels = vec![vec![root]];
    loop {
        let mut next = Vec::new();
        for &v in levels.last().expect("non-empty") {
            for &u in g.neighbours(v) {
                if s.member[u] == member && s.visited[u] != seen {
                    s.visited[u] = seen;
                    s.level[u] = levels.len();
                    next.push(u);
                }
            }
        }
        if next.is_empty() {
            return levels;
        }
        levels.push(next);
    }
}

/// The level structure of a pseudo-peripheral vertex of the connected member set (starting from
/// the structure `levels` rooted at `start`).
fn pseudo_peripheral_levels(
    g: &Graph,
    start: usize,
    member: u32,
    s: &mut Scratch,
    mut levels: Vec<Vec<usize>>,
) -> Vec<Vec<usize>> {
    let mut root = start;
    for _ in 0..PERIPHERAL_SEARCHES {
        let last = levels.last().expect("non-empty");
        let candidate = *last
            .iter()
            .min_by_key(|&&v| g.neighbours(v).len())
            .expect("non-empty");
        if candidate == root {
            break;
        }
        let trial = bfs(g, candidate, member, s);
        if trial.len() <= levels.len() {
            // Restore the levels of the kept structure.
            levels = bfs(g, root, member, s);
            break;
        }
        levels = trial;
        root = candidate;
    }
    levels
}

/// The separator level: the lightest level with at least [`MIN_SIDE_FRACTION`] of the weight on
/// either side, else the weighted median level; `None` with fewer than 3 levels.
fn separator_level(g: &Graph, levels: &[Vec<usize>], total: usize) -> Option<usize> {
    if levels.len() < 3 {
        return None;
    }
    let weights: Vec<usize> = levels
        .iter()
        .map(|l| l.iter().map(|&v| g.weight[v]).sum())
        .collect();
    let min_side = (MIN_SIDE_FRACTION * total as f64) as usize;
    let mut below = weights[0];
    let mut best: Option<(usize, usize)> = None;
    let mut median = None;
    for (l, &w_l) in weights.iter().enumerate().take(levels.len() - 1).skip(1) {
        let above = total - below - w_l;
        if median.is_none() && below + w_l >= total / 2 {
            median = Some(l);
        }
        if below >= min_side && above >= min_side && best.is_none_or(|(w, _)| w_l < w) {
            best = Some((w_l, l));
        }
        below += w_l;
    }
    best.map(|(_, l)| l).or(median).or(Some(levels.len() / 2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::SymbolicSparseColMat;

    /// The pattern (both triangles, diagonal) of a 7-point stencil on an nx × ny × nz grid with
    /// `dofs` DOFs per grid point (all DOFs of neighbouring points coupled).
    fn grid_pattern(nx: usize, ny: usize, nz: usize, dofs: usize) -> SymbolicSparseColMat<usize> {
        let id = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        let n = nx * ny * nz * dofs;
        let mut col_ptr = vec![0];
        let mut rows = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let mut pts = vec![id(i, j, k)];
                    if i > 0 {
                        pts.push(id(i - 1, j, k));
                    }
                    if i + 1 < nx {
                        pts.push(id(i + 1, j, k));
                    }
                    if j > 0 {
                        pts.push(id(i, j - 1, k));
                    }
                    if j + 1 < ny {
                        pts.push(id(i, j + 1, k));
                    }
                    if k > 0 {
                        pts.push(id(i, j, k - 1));
                    }
                    if k + 1 < nz {
                        pts.push(id(i, j, k + 1));
                    }
                    let mut col: Vec<usize> = pts
                        .iter()
                        .flat_map(|&p| (0..dofs).map(move |d| p * dofs + d))
                        .collect();
                    col.sort_unstable();
                    for _ in 0..dofs {
                        rows.extend_from_slice(&col);
                        col_ptr.push(rows.len());
                    }
                }
            }
        }
        SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows)
    }

    fn is_permutation(order: &[usize], n: usize) -> bool {
        let mut seen = vec![false; n];
        order.len() == n
            && order
                .iter()
                .all(|&o| o < n && !std::mem::replace(&mut seen[o], true))
    }

    // The ordering is a permutation and keeps the 3 DOFs of a grid point together (compressed
    // into one vertex of weight 3). Its fill is compared with AMD in `shift_invert`'s tests.
    #[test]
    fn ordering_is_a_permutation_with_compressed_nodes() {
        let p = grid_pattern(9, 7, 5, 3);
        let order = nested_dissection(p.as_ref());
        assert!(is_permutation(&order, p.ncols()));
        for chunk in order.chunks(3) {
            assert_eq!(chunk[0] / 3, chunk[2] / 3, "{chunk:?}");
        }
        let (groups, graph) = compress(p.as_ref());
        assert_eq!(groups.len(), 9 * 7 * 5);
        assert!(graph.weight.iter().all(|&w| w == 3));
    }

    // Disconnected patterns (two grids side by side) and tiny ones are ordered too.
    #[test]
    fn disconnected_and_small_patterns() {
        let a = grid_pattern(6, 6, 6, 1);
        let n = a.ncols();
        let mut col_ptr = vec![0];
        let mut rows = Vec::new();
        for copy in 0..2 {
            for j in 0..n {
                rows.extend(a.row_idx_of_col(j).map(|r| r + copy * n));
                col_ptr.push(rows.len());
            }
        }
        let two = SymbolicSparseColMat::new_checked(2 * n, 2 * n, col_ptr, None, rows);
        assert!(is_permutation(&nested_dissection(two.as_ref()), 2 * n));
        let one = grid_pattern(1, 1, 1, 1);
        assert_eq!(nested_dissection(one.as_ref()), vec![0]);
    }
}
