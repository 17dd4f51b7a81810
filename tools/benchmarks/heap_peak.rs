//! A counting global allocator for `hbm_speed`: the bytes live on the heap, their high-water
//! mark since [`reset`], and (with `HBM_SPEED_HEAP` set) the allocations of at least [`LARGE`]
//! bytes live at that mark with the call stack that made each, printed by [`report`].
//!
//! Every allocation and free adds to or subtracts from one atomic counter (the system
//! allocator, glibc's malloc, does the work). With `HBM_SPEED_HEAP` set, each allocation of
//! [`LARGE`] bytes or more also captures its stack (unresolved, `std::backtrace`) into a table
//! of live allocations, and whenever the live bytes exceed the last recorded mark by
//! [`SNAPSHOT_STEP`], the table is copied: the copy at the end is what was live within
//! [`SNAPSHOT_STEP`] of the peak. The recorder's own allocations (the table, the stacks) are
//! made with a thread-local flag set and are neither counted nor recorded.

use std::alloc::{GlobalAlloc, Layout, System};
use std::backtrace::Backtrace;
use std::cell::Cell;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

/// Allocations of at least this many bytes are recorded with their call stack.
pub const LARGE: usize = 256 * 1024;

/// The live bytes must exceed the last copy's by this much before the table is copied again.
pub const SNAPSHOT_STEP: usize = 1 << 20;

/// The counting allocator (install with `#[global_allocator]`).
pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static TRACE: AtomicBool = AtomicBool::new(false);

thread_local! {
    /// Set while the recorder itself allocates (its allocations are not counted).
    static INSIDE: Cell<bool> = const { Cell::new(false) };
}

/// One live allocation of at least [`LARGE`] bytes: its address, size and call stack (an index
/// into [`Table::stacks`]).
#[derive(Clone, Copy)]
struct Record {
    address: usize,
    size: usize,
    stack: usize,
}

/// The recorded stacks (never freed), the live large allocations and their copy at the mark.
struct Table {
    stacks: Vec<Backtrace>,
    live: Vec<Record>,
    at_peak: Vec<Record>,
    /// Live bytes when `at_peak` was copied.
    peak_bytes: usize,
}

static TABLE: Mutex<Table> = Mutex::new(Table {
    stacks: Vec::new(),
    live: Vec::new(),
    at_peak: Vec::new(),
    peak_bytes: 0,
});

/// Whether this thread is inside the recorder (or is being torn down).
fn inside() -> bool {
    INSIDE.try_with(Cell::get).unwrap_or(true)
}

/// Runs `f` on the table with the recorder's flag set.
fn with_table(f: impl FnOnce(&mut Table)) {
    let _ = INSIDE.try_with(|c| c.set(true));
    if let Ok(mut table) = TABLE.lock() {
        f(&mut table);
    }
    let _ = INSIDE.try_with(|c| c.set(false));
}

/// Counts `size` bytes allocated at `address` (and records them when large).
fn added(address: usize, size: usize) {
    if inside() {
        return;
    }
    let live = LIVE.fetch_add(size, Ordering::Relaxed) + size;
    let peak = PEAK.fetch_max(live, Ordering::Relaxed).max(live);
    if !TRACE.load(Ordering::Relaxed) {
        return;
    }
    let stack = (size >= LARGE).then(|| {
        let _ = INSIDE.try_with(|c| c.set(true));
        let s = Backtrace::force_capture();
        let _ = INSIDE.try_with(|c| c.set(false));
        s
    });
    let at_mark = live == peak;
    if stack.is_none() && !at_mark {
        return;
    }
    with_table(|t| {
        if let Some(s) = stack {
            t.stacks.push(s);
            let index = t.stacks.len() - 1;
            t.live.push(Record {
                address,
                size,
                stack: index,
            });
        }
        if at_mark && live >= t.peak_bytes + SNAPSHOT_STEP {
            t.at_peak = t.live.clone();
            t.peak_bytes = live;
        }
    });
}

/// Counts `size` bytes at `address` freed (and forgets their record when large).
fn removed(address: usize, size: usize) {
    if inside() {
        return;
    }
    LIVE.fetch_sub(size, Ordering::Relaxed);
    if size >= LARGE && TRACE.load(Ordering::Relaxed) {
        with_table(|t| {
            if let Some(i) = t
                .live
                .iter()
                .position(|r| r.address == address && r.size == size)
            {
                t.live.swap_remove(i);
            }
        });
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            added(p as usize, layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            added(p as usize, layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        removed(p as usize, layout.size());
        unsafe { System.dealloc(p, layout) }
    }

    unsafe fn realloc(&self, p: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, layout, new_size) };
        if !q.is_null() {
            // the new block is counted before the old one is released: a moved block holds
            // both for a moment
            added(q as usize, new_size);
            removed(p as usize, layout.size());
        }
        q
    }
}

/// Live heap bytes now.
pub fn live_bytes() -> usize {
    LIVE.load(Ordering::Relaxed)
}

/// The high-water mark of the live heap bytes since the last [`reset`].
pub fn peak_bytes() -> usize {
    PEAK.load(Ordering::Relaxed)
}

/// Starts recording large allocations with their stacks when `HBM_SPEED_HEAP` is set.
pub fn trace_from_env() {
    TRACE.store(
        std::env::var_os("HBM_SPEED_HEAP").is_some(),
        Ordering::Relaxed,
    );
}

/// Stops recording large allocations (those recorded stay in the table).
pub fn stop() {
    TRACE.store(false, Ordering::Relaxed);
}

/// Sets the high-water mark to the live bytes now and forgets the copy at the last mark.
pub fn reset() {
    let live = LIVE.load(Ordering::Relaxed);
    PEAK.store(live, Ordering::Relaxed);
    with_table(|t| {
        t.at_peak = t.live.clone();
        t.peak_bytes = live;
    });
}

/// The functions of the crate `nlrom` (and of this benchmark) on a resolved stack, innermost
/// first, at most `depth` of them, joined by " < ".
fn site(stack: &Backtrace, depth: usize) -> String {
    let text = format!("{stack}");
    let names: Vec<String> = text
        .lines()
        .filter_map(|l| l.trim().split_once(": ").map(|(_, name)| name.to_string()))
        .filter(|name| {
            (name.starts_with("nlrom::") || name.starts_with("hbm_speed::"))
                && !name.starts_with("hbm_speed::heap_peak")
        })
        .map(|name| match name.rfind("::h") {
            Some(i) if name.len() - i == 19 => name[..i].to_string(),
            _ => name,
        })
        .collect();
    names
        .into_iter()
        .take(depth)
        .collect::<Vec<_>>()
        .join(" < ")
}

/// Prints the high-water mark since [`reset`] (MB above `base` bytes) and, when recorded, the
/// large allocations live at it grouped by call site (the innermost `depth` functions of the
/// crate), largest first.
pub fn report(base: usize, depth: usize) {
    let mb = |b: usize| b as f64 / 1e6;
    eprintln!(
        "heap: {:.1} MB live before, high-water mark {:.1} MB (+{:.1} MB), {:.1} MB live now",
        mb(base),
        mb(peak_bytes()),
        mb(peak_bytes().saturating_sub(base)),
        mb(live_bytes())
    );
    if !TRACE.load(Ordering::Relaxed) {
        return;
    }
    let _ = INSIDE.try_with(|c| c.set(true));
    if let Ok(t) = TABLE.lock() {
        let mut by_site: BTreeMap<String, (usize, usize)> = BTreeMap::new();
        for r in &t.at_peak {
            let e = by_site.entry(site(&t.stacks[r.stack], depth)).or_default();
            e.0 += r.size;
            e.1 += 1;
        }
        let large: usize = t.at_peak.iter().map(|r| r.size).sum();
        eprintln!(
            "heap at the mark ({:.1} MB live): {:.1} MB in {} allocations of {} kB or more made since the reset, {:.1} MB in the others",
            mb(t.peak_bytes),
            mb(large),
            t.at_peak.len(),
            LARGE / 1024,
            mb(t.peak_bytes.saturating_sub(large))
        );
        let mut rows: Vec<(String, (usize, usize))> = by_site.into_iter().collect();
        rows.sort_by_key(|r| std::cmp::Reverse(r.1 .0));
        for (name, (bytes, count)) in rows {
            eprintln!("  {:8.1} MB in {count:4}: {name}", mb(bytes));
        }
        if std::env::var_os("HBM_SPEED_HEAP_LIST").is_some() {
            let mut list = t.at_peak.clone();
            list.sort_by_key(|r| r.stack);
            for r in list {
                eprintln!(
                    "    #{:5} {:7.2} MB {}",
                    r.stack,
                    mb(r.size),
                    site(&t.stacks[r.stack], 3)
                );
            }
        }
    }
    let _ = INSIDE.try_with(|c| c.set(false));
}
