//! Parallel evaluation of many contact elements and the summation of their node-space results
//! (force coefficients, ∂F/∂n0, Jacobian blocks; SAMA paper eq. 26 with each element's kinematic
//! map) into harmonic-major vectors and a dense or block-stored Jacobian — the loop shared by
//! [`super::pairs::PairSet`] and [`super::grounded::DofElements`].
//!
//! Elements are processed in blocks (bounded memory for the per-element Jacobians):
//! 1. the block's elements are evaluated in parallel, in contiguous chunks of at least
//!    [`MIN_CHUNK`] elements with one set of buffers per chunk, into flat per-element slots
//!    ([`Slot`]);
//! 2. the slots are added into the outputs in parallel over disjoint ranges of the outputs
//!    (entries of the vectors, columns of the Jacobian) when the sums have at least
//!    [`PARALLEL_SUM_ENTRIES`] entries; every range visits the elements in their order. No two threads write the same entry (no false sharing of a summed output) and
//!    the sums do not depend on the number of threads.

use std::sync::Mutex;

use faer::prelude::ReborrowMut;
use faer::MatMut;
use rayon::prelude::*;

use crate::error::Result;
use crate::harmonics::{BlockJacobian, JacobianMut, JacobianSink};

/// Most f64 entries of per-element Jacobians held at once (16 MB).
const JACOBIAN_BUDGET: usize = 1 << 21;

/// Fewest elements in one parallel task: an element of N_t = 1024 samples costs 10–30 µs, and
/// a task handed to a sleeping rayon worker costs about as much in wake-ups, so that two
/// elements (NLvib's chain of `cases/nlvib/chain07_jenkins.toml`) are evaluated on the calling
/// thread.
const MIN_CHUNK: usize = 4;

/// Fewest entries added (node-space entries of all slots for a vector, their squares for the
/// Jacobian) for the sums to run in parallel over ranges of the outputs: every range visits
/// every slot, so smaller sums are cheaper on the calling thread.
const PARALLEL_SUM_ENTRIES: usize = 1 << 15;

/// Width in bytes of the column ranges of the dense Jacobian filled at a time (one range of a
/// large matrix fits in a core's L2 cache).
const COLUMN_TILE_BYTES: usize = 1 << 18;

/// The outputs one evaluation adds into (each optional).
pub struct Outputs<'a> {
    /// Harmonic force vector.
    pub force: Option<&'a mut [f64]>,
    /// ∂F/∂p vector.
    pub dn0: Option<&'a mut [f64]>,
    /// Jacobian (square, the length of the harmonic vector), dense or block-stored.
    pub jacobian: Option<JacobianMut<'a>>,
}

/// Where one element writes its node-space results. `len` entries are used; the element sets
/// it. `dn0` and `jacobian` are only meaningful when the evaluation asked for them.
pub struct Slot<'a> {
    /// Global (harmonic-major) index of each node-space entry.
    pub index: &'a mut [usize],
    /// Number of node-space entries used (≤ the capacity).
    pub len: &'a mut usize,
    /// Force coefficient of each entry.
    pub force: &'a mut [f64],
    /// ∂(force)/∂p of each entry (scaled by the element's parameter rate).
    pub dn0: &'a mut [f64],
    /// Node-space Jacobian, column-major `len × len` (entry (r, c) at `c·len + r`).
    pub jacobian: &'a mut [f64],
}

/// What the outputs ask for.
#[derive(Clone, Copy, Debug)]
pub struct Wanted {
    /// ∂F/∂p.
    pub dn0: bool,
    /// The Jacobian.
    pub jacobian: bool,
}

/// Reusable slot storage (kept by the force between evaluations; a concurrent evaluation that
/// finds it busy allocates its own).
#[derive(Default)]
pub struct SlotStorage(Mutex<Storage>);

#[derive(Default)]
struct Storage {
    index: Vec<usize>,
    len: Vec<usize>,
    force: Vec<f64>,
    dn0: Vec<f64>,
    jacobian: Vec<f64>,
}

/// One chunk of elements of a block with its slots.
struct Job<'a, S> {
    first: usize,
    states: &'a mut [S],
    index: &'a mut [usize],
    len: &'a mut [usize],
    force: &'a mut [f64],
    dn0: &'a mut [f64],
    jacobian: &'a mut [f64],
}

/// Evaluates `element(i, state_i, buffers, slot)` for every element i (state `states[i]`, up
/// to `capacity` node-space entries) and adds the results into `outputs`; `buffers()` makes one
/// set of per-thread buffers per chunk.
pub fn assemble<S, B, MakeBuffers, Element>(
    states: &mut [S],
    capacity: usize,
    outputs: Outputs<'_>,
    storage: &SlotStorage,
    buffers: MakeBuffers,
    element: Element,
) -> Result<()>
where
    S: Send,
    MakeBuffers: Fn() -> B + Sync,
    Element: Fn(usize, &mut S, &mut B, Wanted, Slot<'_>) -> Result<()> + Sync,
{
    let n = states.len();
    if n == 0 || capacity == 0 {
        return Ok(());
    }
    let Outputs {
        mut force,
        mut dn0,
        mut jacobian,
    } = outputs;
    let wanted = Wanted {
        dn0: dn0.is_some(),
        jacobian: jacobian.is_some(),
    };
    let dn0_cap = if wanted.dn0 { capacity } else { 1 };
    let jac_cap = if wanted.jacobian {
        capacity * capacity
    } else {
        1
    };
    let block = if wanted.jacobian {
        (JACOBIAN_BUDGET / jac_cap).clamp(1, n)
    } else {
        n
    };
    let threads = rayon::current_num_threads().max(1);
    // A few chunks per thread for balance; one chunk (no task overhead) on one thread.
    let chunk = if threads == 1 {
        block
    } else {
        block.div_ceil(4 * threads).max(MIN_CHUNK)
    };
    let mut guard = storage.0.try_lock().ok();
    let mut own = Storage::default();
    let st: &mut Storage = match guard.as_deref_mut() {
        Some(s) => s,
        None => &mut own,
    };
    resize(&mut st.index, block * capacity, 0);
    resize(&mut st.len, block, 0);
    resize(&mut st.force, block * capacity, 0.0);
    resize(&mut st.dn0, block * dn0_cap, 0.0);
    resize(&mut st.jacobian, block * jac_cap, 0.0);
    for (b, block_states) in states.chunks_mut(block).enumerate() {
        let count = block_states.len();
        let mut jobs = Vec::with_capacity(count.div_ceil(chunk));
        let mut rest = (
            block_states,
            &mut st.index[..count * capacity],
            &mut st.len[..count],
            &mut st.force[..count * capacity],
            &mut st.dn0[..count * dn0_cap],
            &mut st.jacobian[..count * jac_cap],
        );
        let mut first = b * block;
        while !rest.0.is_empty() {
            let k = chunk.min(rest.0.len());
            let (s, s2) = std::mem::take(&mut rest.0).split_at_mut(k);
            let (i, i2) = std::mem::take(&mut rest.1).split_at_mut(k * capacity);
            let (l, l2) = std::mem::take(&mut rest.2).split_at_mut(k);
            let (f, f2) = std::mem::take(&mut rest.3).split_at_mut(k * capacity);
            let (d, d2) = std::mem::take(&mut rest.4).split_at_mut(k * dn0_cap);
            let (j, j2) = std::mem::take(&mut rest.5).split_at_mut(k * jac_cap);
            jobs.push(Job {
                first,
                states: s,
                index: i,
                len: l,
                force: f,
                dn0: d,
                jacobian: j,
            });
            rest = (s2, i2, l2, f2, d2, j2);
            first += k;
        }
        let run_job = |job: Job<'_, S>| -> Result<()> {
            let mut buf = buffers();
            for (k, state) in job.states.iter_mut().enumerate() {
                let slot = Slot {
                    index: &mut job.index[k * capacity..(k + 1) * capacity],
                    len: &mut job.len[k],
                    force: &mut job.force[k * capacity..(k + 1) * capacity],
                    dn0: &mut job.dn0[k * dn0_cap..(k + 1) * dn0_cap],
                    jacobian: &mut job.jacobian[k * jac_cap..(k + 1) * jac_cap],
                };
                element(job.first + k, state, &mut buf, wanted, slot)?;
            }
            Ok(())
        };
        if jobs.len() == 1 {
            jobs.into_iter().try_for_each(run_job)?;
        } else {
            jobs.into_par_iter().try_for_each(run_job)?;
        }
        let slots = Slots {
            count,
            capacity,
            index: &st.index,
            len: &st.len,
        };
        let sum_threads = |entries: usize| {
            if entries < PARALLEL_SUM_ENTRIES {
                1
            } else {
                threads
            }
        };
        let vector_threads = sum_threads(count * capacity);
        if let Some(f) = force.as_deref_mut() {
            slots.add_vector(&st.force, capacity, f, vector_threads);
        }
        if let Some(d) = dn0.as_deref_mut() {
            slots.add_vector(&st.dn0, dn0_cap, d, vector_threads);
        }
        match jacobian.as_mut() {
            Some(JacobianMut::Dense(j)) => {
                let matrix_threads = sum_threads(count * jac_cap);
                slots.add_matrix(&st.jacobian, jac_cap, j.rb_mut(), matrix_threads)
            }
            Some(JacobianMut::Blocks(j)) => slots.add_patches(&st.jacobian, jac_cap, j),
            Some(JacobianMut::Sink(j)) => slots.add_to_sink(&st.jacobian, jac_cap, &mut **j),
            None => {}
        }
    }
    Ok(())
}

fn resize<T: Clone>(v: &mut Vec<T>, n: usize, value: T) {
    if v.len() < n {
        v.resize(n, value);
    }
}

/// The filled slots of one block.
struct Slots<'a> {
    count: usize,
    capacity: usize,
    index: &'a [usize],
    len: &'a [usize],
}

impl Slots<'_> {
    /// Global indices of element e's entries.
    fn indices(&self, e: usize) -> &[usize] {
        &self.index[e * self.capacity..e * self.capacity + self.len[e]]
    }

    /// `out`[index] += values of every slot (slot e's values at `values[e·stride ..]`), in
    /// parallel over ranges of `out`.
    fn add_vector(&self, values: &[f64], stride: usize, out: &mut [f64], threads: usize) {
        let part = out.len().div_ceil(threads).max(1);
        let add = |(p, range): (usize, &mut [f64])| {
            let lo = p * part;
            let hi = lo + range.len();
            for e in 0..self.count {
                let v = &values[e * stride..];
                for (k, &g) in self.indices(e).iter().enumerate() {
                    if (lo..hi).contains(&g) {
                        range[g - lo] += v[k];
                    }
                }
            }
        };
        if threads == 1 {
            add((0, out));
        } else {
            out.par_chunks_mut(part).enumerate().for_each(add);
        }
    }

    /// Adds every slot's column-major block into the block-stored `out`, element by element
    /// (the entries of each position summed in the order of the elements, as
    /// [`Slots::add_matrix`]).
    fn add_patches(&self, values: &[f64], stride: usize, out: &mut BlockJacobian) {
        for e in 0..self.count {
            let idx = self.indices(e);
            let l = idx.len();
            out.add_patch(idx, &values[e * stride..e * stride + l * l]);
        }
    }

    /// Hands every slot's column-major block to `out`, element by element in their order.
    fn add_to_sink(&self, values: &[f64], stride: usize, out: &mut dyn JacobianSink) {
        for e in 0..self.count {
            let idx = self.indices(e);
            let l = idx.len();
            out.add_patch(idx, &values[e * stride..e * stride + l * l]);
        }
    }

    /// `out`[(index_r, index_c)] += every slot's column-major block, in parallel over ranges of
    /// columns of `out`. The ranges are narrow enough ([`COLUMN_TILE_BYTES`]) for their part of
    /// a large dense `out` to stay in cache while all slots are added into it.
    fn add_matrix(&self, values: &[f64], stride: usize, out: MatMut<'_, f64>, threads: usize) {
        let tile = (COLUMN_TILE_BYTES / (8 * out.nrows().max(1))).max(1);
        let part = out.ncols().div_ceil(threads).clamp(1, tile);
        let add = |(p, mut cols): (usize, MatMut<'_, f64>)| {
            let lo = p * part;
            let hi = lo + cols.ncols();
            for e in 0..self.count {
                let idx = self.indices(e);
                let l = idx.len();
                let block = &values[e * stride..e * stride + l * l];
                for (c, &gc) in idx.iter().enumerate() {
                    if !(lo..hi).contains(&gc) {
                        continue;
                    }
                    let src = &block[c * l..(c + 1) * l];
                    let mut col = cols.rb_mut().col_mut(gc - lo);
                    if col.row_stride() == 1 {
                        let col = col
                            .try_as_col_major_mut()
                            .expect("unit row stride")
                            .as_slice_mut();
                        for (&gr, v) in idx.iter().zip(src) {
                            col[gr] += v;
                        }
                    } else {
                        for (&gr, v) in idx.iter().zip(src) {
                            *col.rb_mut().get_mut(gr) += v;
                        }
                    }
                }
            }
        };
        if part >= out.ncols() {
            add((0, out));
        } else {
            out.par_col_chunks_mut(part)
                .enumerate()
                .for_each(|(p, c)| add((p, c)));
        }
    }
}
