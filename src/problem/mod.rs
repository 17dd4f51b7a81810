//! A case as a solvable problem: the one layer that reads the case schema ([`crate::case`]) and
//! joins the stages below it (model, reduction, contact interfaces, harmonic balance, time
//! marching) into the systems the solvers take. The commands ([`crate::commands`]) call it.
//!
//! | module | what |
//! |---|---|
//! | [`rom_store`] | the ROM of a sector case: read from a ROM file whose key matches, else reduced (and cached) |
//! | [`matrix_case`] | a model on matrix rows: free rows, dense K, M, C, excitation, output rows, `[[element]]` elements |
//! | [`modal_case`] | a matrix case's harmonic balance on the modal coordinates of its lowest modes (`[harmonic_balance] modes`) |
//! | [`matrix_rom`] | the Craig–Bampton model of a matrix case on a mesh with `[reduction]` (face strips beyond the dense limit) |
//! | [`face_strip`] | the integration points of a `[[strip]]` on a mesh face group |
//! | [`sector`] | the harmonic balance problem of a reduced sector with its contact interfaces |
//! | [`sector_march`] | the ROM of a sector as a time-marching model (no cyclic symmetry, k = 0, k = N/2, travelling waves) |
//! | [`travelling_wave`] | a travelling wave as the real model of the sectors of one wave period |
//! | [`damper`] | the underplatform damper of a `[damper]` table as a time-marching model |
//! | [`nonsmooth_case`] | a matrix case with `[[obstacle]]` contacts as the model of the nonsmooth schemes |
//! | [`casing_case`] | a mesh case with `[[casing]]` (and `[thermal]`) as the thermoelastic model of the nonsmooth schemes |
//! | [`casing_rom`] | the Craig–Bampton reduced casing model (`[reduction]`) |
//! | [`march_case`] | any case as a time-marching model, by [`crate::case::Case::kind`] |
//! | [`settings`] | the solver settings of a case's `[continuation]` table |
//!
//! Every command dispatches on [`crate::case::Case::kind`]: a `[damper]`, a model on matrix rows
//! (no mesh, or `[[element]]`), or a reduced sector.

pub mod casing_case;
pub mod casing_rom;
pub mod damper;
pub mod face_strip;
pub mod march_case;
pub mod matrix_case;
pub mod matrix_rom;
pub mod modal_case;
pub mod nonsmooth_case;
pub mod rom_store;
pub mod sector;
pub mod sector_march;
pub mod settings;
pub mod travelling_wave;

/// Where a problem builder's messages go: lines about what was read, reused or written
/// (`info`), problems the user must see (`warn`) and the stages' own logs (`detail`). The
/// commands' `Reporter` implements it with `--quiet` and `-v`.
pub trait Log {
    /// What was read, reused or written.
    fn info(&self, line: &str);
    /// A warning.
    fn warn(&self, line: &str);
    /// A stage's detailed log line.
    fn detail(&self, line: &str);
}

/// Returns the free pages of the process heap to the system: glibc's `malloc_trim`, which
/// releases free pages anywhere in the heap, not only at its top (elsewhere this does nothing).
/// The setup of a sector problem (model, reduction, interfaces) frees far more than the problem
/// keeps, in blocks below glibc's (adaptive) mmap threshold, whose pages glibc otherwise keeps
/// resident for the whole continuation.
pub fn release_free_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only hands free pages of the allocator back to the kernel; it takes
    // the allocator's locks and is safe to call from any thread.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Keeps the whole process heap in glibc's main arena (`mallopt(M_ARENA_MAX, 1)`; elsewhere
/// this does nothing). Call it before other threads allocate (at the start of `main`). By
/// default glibc gives threads that allocate at the same time arenas of their own; blocks
/// freed below the (adaptive, up to 32 MB) mmap threshold stay in the arena that held them,
/// and a thread's arena gives memory back only from its top. The continuation of a large
/// harmonic balance problem allocates and frees block storage and factors of 4–25 MB from the
/// calling thread and the rayon workers, and the extra arenas kept 0.12–0.15 GB of them
/// resident on the bundled sector at H = 3 (docs/performance.md).
pub fn use_one_heap_arena() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes an allocator parameter; M_ARENA_MAX takes effect for arenas
    // created after the call.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

/// A [`Log`] that drops every line.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Log for Silent {
    fn info(&self, _: &str) {}
    fn warn(&self, _: &str) {}
    fn detail(&self, _: &str) {}
}
