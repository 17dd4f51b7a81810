//! Line-based reading of the large ASCII blocks of an MSH file (`$Nodes` and `$Elements`
//! records) in parallel: the block is cut at line boundaries into chunks of whole records, one
//! record per line as Gmsh writes them, and each chunk is read by its own rayon task (a block
//! of one chunk, fewer than [`CHUNK_LINES`] records, on the calling thread).
//!
//! The readers here are strict: a record must sit on one line, with tokens separated by blanks
//! (space, tab, CR). They return `None` on anything else — a malformed token, a record spread
//! over several lines, a missing line — and never an error: the caller then reads the block again
//! with the sequential token reader of [`super::msh`], which accepts any white-space layout and
//! produces the error message naming the line. So a valid file reads the same either way and a
//! broken one gives the same error.

use rayon::prelude::*;

/// Records per parallel task: chunks smaller than this are not worth a task.
pub const CHUNK_LINES: usize = 1 << 13;

/// Bytes per step of the newline count of [`line_chunks`].
const COUNT_BLOCK: usize = 4096;

/// The number of `\n` bytes in `b`: 16 bytes at a time with SSE2 on x86-64 (a byte compare
/// subtracted into per-byte counters, summed every 255 steps), elsewhere
/// [`count_newlines_swar`].
pub fn count_newlines(b: &[u8]) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{
            __m128i, _mm_cmpeq_epi8, _mm_cvtsi128_si64, _mm_loadu_si128, _mm_sad_epu8,
            _mm_set1_epi8, _mm_setzero_si128, _mm_sub_epi8, _mm_unpackhi_epi64,
        };
        let mut total = 0usize;
        let mut runs = b.chunks(16 * 255);
        for run in &mut runs {
            let mut blocks = run.chunks_exact(16);
            // SAFETY: SSE2 is part of the x86-64 baseline, so these instructions exist on every
            // x86-64 CPU; `_mm_loadu_si128` reads exactly the 16 bytes of a block of `b`, with
            // no alignment requirement.
            total += unsafe {
                let newline = _mm_set1_epi8(b'\n' as i8);
                let mut acc = _mm_setzero_si128();
                for block in &mut blocks {
                    let v = _mm_loadu_si128(block.as_ptr().cast::<__m128i>());
                    // A match is 0xFF (-1): subtracting it counts one per byte lane.
                    acc = _mm_sub_epi8(acc, _mm_cmpeq_epi8(v, newline));
                }
                let sums = _mm_sad_epu8(acc, _mm_setzero_si128());
                (_mm_cvtsi128_si64(sums) + _mm_cvtsi128_si64(_mm_unpackhi_epi64(sums, sums)))
                    as usize
            };
            total += blocks.remainder().iter().filter(|&&c| c == b'\n').count();
        }
        total
    }
    #[cfg(not(target_arch = "x86_64"))]
    count_newlines_swar(b)
}

/// The number of `\n` bytes in `b`, eight bytes at a time (SWAR: a byte of the word XOR
/// `0x0A…0A` is zero exactly where the input holds `\n`, and its high bit after adding `0x7F` to
/// the low seven bits tells which), with per-byte counters summed every 255 words before they can
/// overflow.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn count_newlines_swar(b: &[u8]) -> usize {
    const LO: u64 = 0x0101_0101_0101_0101;
    const LOW7: u64 = 0x7F * LO;
    // The sum of the eight byte counters (each at most 255).
    let sum_bytes = |acc: u64| {
        let pairs = (acc & 0x00FF_00FF_00FF_00FF) + ((acc >> 8) & 0x00FF_00FF_00FF_00FF);
        (pairs.wrapping_mul(0x0001_0001_0001_0001) >> 48) as usize
    };
    let mut total = 0usize;
    let mut runs = b.chunks(8 * 255);
    for run in &mut runs {
        let mut acc = 0u64;
        let mut words = run.chunks_exact(8);
        for w in &mut words {
            let x = u64::from_le_bytes(w.try_into().expect("8 bytes")) ^ (b'\n' as u64 * LO);
            let nonzero = ((x & LOW7) + LOW7) | x;
            acc += (!nonzero >> 7) & LO;
        }
        total += sum_bytes(acc) + words.remainder().iter().filter(|&&c| c == b'\n').count();
    }
    total
}

/// The chunks of the next `n` lines of `i` (`i` starts at the first byte of the first line):
/// (byte offset of the chunk's first line, number of lines), `per` lines per chunk, and the
/// offset just after the n-th line's `\n`. `None` if `i` has fewer than `n` complete lines.
///
/// Newlines are counted ([`count_newlines`]) [`COUNT_BLOCK`] bytes at a time, then 64 bytes at
/// a time, up to the block that holds the next chunk boundary, which is then scanned byte by
/// byte.
pub fn line_chunks(i: &[u8], n: usize, per: usize) -> Option<(Vec<(usize, usize)>, usize)> {
    if n == 0 {
        return Some((Vec::new(), 0));
    }
    let per = per.max(1);
    let mut chunks = Vec::with_capacity(n / per + 1);
    chunks.push((0, per.min(n)));
    let (mut count, mut pos) = (0usize, 0usize);
    loop {
        let target = ((count / per + 1) * per).min(n);
        while let Some(block) = i.get(pos..pos + COUNT_BLOCK) {
            let c = count_newlines(block);
            if count + c >= target {
                break;
            }
            count += c;
            pos += COUNT_BLOCK;
        }
        while let Some(block) = i.get(pos..pos + 64) {
            let c = count_newlines(block);
            if count + c >= target {
                break;
            }
            count += c;
            pos += 64;
        }
        while count < target {
            let b = *i.get(pos)?;
            pos += 1;
            count += usize::from(b == b'\n');
        }
        if count == n {
            return Some((chunks, pos));
        }
        chunks.push((pos, per.min(n - count)));
    }
}

/// Lines per chunk for `n` records: at least [`CHUNK_LINES`], and about 4 chunks per thread so
/// that uneven chunks balance.
pub fn lines_per_chunk(n: usize) -> usize {
    let tasks = 4 * rayon::current_num_threads().max(1);
    n.div_ceil(tasks).max(CHUNK_LINES)
}

/// Asks the kernel to back the memory `[start, start + bytes)` with transparent huge pages
/// (Linux, `madvise(MADV_HUGEPAGE)` on the whole 4 KiB pages it spans; elsewhere nothing). The
/// readers write every slot of their large outputs once, and the first touch of fresh memory is
/// a page fault per page: with 2 MiB pages there are 512 times fewer. Only for spans of at least
/// 4 MiB; the advice is a hint (ignored where huge pages are disabled) and changes no contents.
fn advise_huge_pages(start: usize, bytes: usize) {
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        if bytes < 4 << 20 {
            return;
        }
        let lo = start.next_multiple_of(PAGE);
        let hi = (start + bytes) / PAGE * PAGE;
        // SAFETY: the caller passes memory of one allocation it owns; MADV_HUGEPAGE only changes
        // how the kernel backs those pages, not their contents, and a failure is harmless.
        unsafe {
            libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (start, bytes);
}

/// The spare capacity of `v` backed by huge pages where possible ([`advise_huge_pages`]).
pub fn huge_pages<T>(v: &mut Vec<T>) {
    let len = std::mem::size_of_val(v.as_slice());
    let bytes = v.capacity() * std::mem::size_of::<T>() - len;
    advise_huge_pages(v.as_mut_ptr() as usize + len, bytes);
}

/// `n` zero values (`T::default()` of an integer, a float or an array of them) in fresh memory:
/// the allocator hands out large zeroed blocks without writing them (`calloc`), so a reader's
/// write is their first touch, and no pass of `memset` precedes it; backed by huge pages where
/// possible ([`advise_huge_pages`]).
pub fn zeroed<T: Clone + Default>(n: usize) -> Vec<T> {
    let mut v = vec![T::default(); n];
    advise_huge_pages(v.as_mut_ptr() as usize, std::mem::size_of_val(v.as_slice()));
    v
}

/// Skips blanks within the line (space, tab, CR).
#[inline(always)]
fn blank(i: &[u8]) -> &[u8] {
    let mut k = 0;
    while k < i.len() && matches!(i[k], b' ' | b'\t' | b'\r') {
        k += 1;
    }
    &i[k..]
}

/// Whether a token may end before `i` (end of input or white space).
#[inline(always)]
fn ends_token(i: &[u8]) -> bool {
    i.first().is_none_or(|c| c.is_ascii_whitespace())
}

/// The end of the line: blanks, then `\n`; returns the input after the `\n`.
#[inline(always)]
pub fn line_end(i: &[u8]) -> Option<&[u8]> {
    let i = blank(i);
    match i.first() {
        Some(b'\n') => Some(&i[1..]),
        _ => None,
    }
}

/// The value of eight decimal digit values (0–9, one per byte) read as a little-endian `u64`
/// (first digit in the lowest byte), by three multiplications instead of eight (Lemire's SWAR
/// method, as in fast_float).
#[inline(always)]
fn eight_digit_values(v: u64) -> u64 {
    const MASK: u64 = 0x0000_00FF_0000_00FF;
    const MUL1: u64 = 0x000F_4240_0000_0064;
    const MUL2: u64 = 0x0000_2710_0000_0001;
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    let v1 = (v & MASK).wrapping_mul(MUL1);
    let v2 = ((v >> 16) & MASK).wrapping_mul(MUL2);
    u64::from((v1.wrapping_add(v2) >> 32) as u32)
}

/// The leading digits of the 8 bytes `x` (little-endian, first byte lowest): their number `n`
/// (0–8) and the bytes minus `'0'`.
///
/// After subtracting `'0'` from every byte, the digits are the bytes below 10. A borrow only
/// runs from a byte below `'0'` into the bytes after it, so the bytes up to and including the
/// first non-digit are exact; adding `0x76` sets the high bit of every exact byte of 10 or more
/// (without a carry out of the digit bytes), and the byte's own high bit catches those above
/// `0x89`. The first byte with a high bit set is the first non-digit.
#[inline(always)]
fn leading_digits(x: u64) -> (usize, u64) {
    let v = x.wrapping_sub(0x3030_3030_3030_3030);
    let non_digit = (v.wrapping_add(0x7676_7676_7676_7676) | v) & 0x8080_8080_8080_8080;
    ((non_digit.trailing_zeros() / 8) as usize, v)
}

/// An unsigned decimal integer of at most 19 digits on the current line.
///
/// A number of 1–7 digits followed by a blank or line end (every tag of a mesh below ten
/// million) is read 8 bytes at a time ([`leading_digits`]): its digit values are shifted into
/// the high bytes, zeros below, and converted by [`eight_digit_values`]; others digit by digit.
#[inline(always)]
pub fn uint(i: &[u8]) -> Option<(&[u8], u64)> {
    let i = blank(i);
    if let Some(word) = i.get(..8) {
        let (n, v) = leading_digits(u64::from_le_bytes(word.try_into().expect("8 bytes")));
        if (1..8).contains(&n) && i[n].is_ascii_whitespace() {
            return Some((&i[n..], eight_digit_values(v << (64 - 8 * n as u32))));
        }
    }
    let mut value: u64 = 0;
    let mut n = 0;
    while n < i.len() && n < 19 {
        let d = i[n].wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        value = value * 10 + u64::from(d);
        n += 1;
    }
    (n > 0 && ends_token(&i[n..])).then(|| (&i[n..], value))
}

/// An unsigned decimal integer at `i[*p..]` on the current line, `*p` moved past it (and past
/// one following space): [`uint`] for a position instead of a slice, with the usual token of
/// 1–7 digits and its separator taken from one 8-byte word ([`leading_digits`]).
#[inline(always)]
fn uint_at(i: &[u8], p: &mut usize) -> Option<u64> {
    if let Some(word) = i.get(*p..*p + 8) {
        let x = u64::from_le_bytes(word.try_into().expect("8 bytes"));
        let (n, v) = leading_digits(x);
        if (1..8).contains(&n) {
            let sep = (x >> (8 * n)) as u8;
            let value = eight_digit_values(v << (64 - 8 * n as u32));
            return match sep {
                b' ' => {
                    *p += n + 1;
                    Some(value)
                }
                c if c.is_ascii_whitespace() => {
                    *p += n;
                    Some(value)
                }
                _ => None,
            };
        }
    }
    let rest = &i[*p..];
    let (r, v) = uint(rest)?;
    *p += rest.len() - r.len();
    Some(v)
}

/// The end of the line at `i[p..]` (blanks, then `\n`): the position after the `\n`.
#[inline(always)]
fn line_end_at(i: &[u8], p: usize) -> Option<usize> {
    if i.get(p) == Some(&b'\n') {
        return Some(p + 1);
    }
    Some(i.len() - line_end(&i[p..])?.len())
}

/// Where [`element_records`] puts the element tags.
pub enum TagsOut<'t> {
    /// Nowhere: the tags must be `first, first + 1, …` (Gmsh's numbering within a block), which
    /// is checked.
    Run(u64),
    /// Into the slice, one per record.
    Store(&'t mut [u64]),
}

/// A run of element records for [`element_chunk`]: the offset of its first line, its element
/// tags (stored into the slice, or checked to run on from the number), its connectivity slots.
type ElementRun<'t, 'c> = (usize, Option<&'t mut [u64]>, u64, &'c mut [u32]);

/// The `k`-th element tag of a run: stored into `tags`, or (without it) checked to be `*next`,
/// which then moves on.
#[inline(always)]
fn element_tag(tags: &mut Option<&mut [u64]>, next: &mut u64, k: usize, tag: u64) -> Option<()> {
    match tags {
        Some(t) => t[k] = tag,
        None if tag != *next => return None,
        None => *next = next.wrapping_add(1),
    }
    Some(())
}

/// The records of a run from its `k0`-th on, one at a time (what [`element_chunk`] has left
/// after the records it reads side by side): the offset after the run's last line.
#[inline(always)]
fn element_rest<const NN: usize>(
    i: &[u8],
    (mut p, mut tags, mut next, conn): ElementRun<'_, '_>,
    k0: usize,
    nn: usize,
    index: &impl Fn(u64) -> Option<u32>,
) -> Option<usize> {
    let nn = if NN > 0 { NN } else { nn };
    for (k, nodes) in conn[k0 * nn..].chunks_exact_mut(nn).enumerate() {
        let tag = uint_at(i, &mut p)?;
        for c in nodes.iter_mut() {
            *c = index(uint_at(i, &mut p)?)?;
        }
        p = line_end_at(i, p)?;
        element_tag(&mut tags, &mut next, k0 + k, tag)?;
    }
    Some(p)
}

/// Two neighbouring runs of element records `tag node_1 … node_nn` (one per line) read side by
/// side, one field of each in turn: each integer's position depends on the one before it, so
/// a single run is a chain of dependent loads; two independent chains keep the core busy. The
/// node tags are mapped by `index` into the runs' slots, `conn.len() / nn` records each; the
/// records of the longer run past the shorter one's are read alone ([`element_rest`]). Returns
/// the offsets after the last lines of the runs. `NN` is `nn` as a constant for the common
/// element sizes (the node loop unrolled), 0 otherwise.
#[inline(always)]
fn element_chunk<const NN: usize>(
    i: &[u8],
    (mut pa, mut tags_a, mut next_a, conn_a): ElementRun<'_, '_>,
    (mut pb, mut tags_b, mut next_b, conn_b): ElementRun<'_, '_>,
    nn: usize,
    index: &impl Fn(u64) -> Option<u32>,
) -> Option<(usize, usize)> {
    let nn = if NN > 0 { NN } else { nn };
    let paired = conn_a.len().min(conn_b.len()) / nn;
    let records = conn_a.chunks_exact_mut(nn).zip(conn_b.chunks_exact_mut(nn));
    for (k, (nodes_a, nodes_b)) in records.enumerate() {
        let tag_a = uint_at(i, &mut pa)?;
        let tag_b = uint_at(i, &mut pb)?;
        for j in 0..nn {
            nodes_a[j] = index(uint_at(i, &mut pa)?)?;
            nodes_b[j] = index(uint_at(i, &mut pb)?)?;
        }
        pa = line_end_at(i, pa)?;
        pb = line_end_at(i, pb)?;
        element_tag(&mut tags_a, &mut next_a, k, tag_a)?;
        element_tag(&mut tags_b, &mut next_b, k, tag_b)?;
    }
    let end_a = element_rest::<NN>(i, (pa, tags_a, next_a, conn_a), paired, nn, index)?;
    let end_b = element_rest::<NN>(i, (pb, tags_b, next_b, conn_b), paired, nn, index)?;
    Some((end_a, end_b))
}

/// The halves of a block of `n` element records whose tags run on from `first` (one record per
/// line, the tag first), about `per` records each, found without counting the block's lines: a
/// guessed offset (`per` records on from the previous half's start, at the bytes per record
/// seen so far) is moved on to the next line start, where the line's tag names the index of
/// its record. Returns (offset, number of records) per half, or `None` when a guess does not
/// land on a later line of the run (a guess past the block, tags that do not run on, lines of
/// very uneven length): the caller then counts the lines ([`line_chunks`]). Reading the halves
/// checks the rest: each must end exactly where the next one starts.
fn run_halves(i: &[u8], n: usize, per: usize, first: u64) -> Option<Vec<(usize, usize)>> {
    let first_line = i.iter().position(|&c| c == b'\n')? + 1;
    let most = 2 * n.div_ceil(per) + 2;
    let mut starts: Vec<(usize, usize)> = vec![(0, 0)];
    let mut bytes_per_record = first_line as f64;
    while let Some(&(at, k)) = starts.last() {
        if k + per >= n {
            break;
        }
        if starts.len() == most {
            return None;
        }
        let guess = at + (per as f64 * bytes_per_record) as usize;
        let line = guess + i.get(guess..)?.iter().position(|&c| c == b'\n')? + 1;
        let tag = uint(i.get(line..)?)?.1;
        let idx = usize::try_from(tag.checked_sub(first)?).ok()?;
        if idx <= k || idx >= n {
            return None;
        }
        starts.push((line, idx));
        bytes_per_record = line as f64 / idx as f64;
    }
    let ends = starts.iter().skip(1).map(|s| s.1).chain([n]);
    Some(
        starts
            .iter()
            .zip(ends)
            .map(|(&(at, k), end)| (at, end - k))
            .collect(),
    )
}

/// Reads `n` element records `tag node_1 … node_nn` starting at `i`, one per line, in parallel:
/// the block is cut into halves of whole lines — by the tags where they run on
/// ([`run_halves`]), else by counting lines ([`line_chunks`]) — and each task reads two halves
/// side by side ([`element_chunk`]). Node tags are mapped to indices by `index` into `conn`
/// (`nn` per record), element tags go where `tags` says. Returns the input after the n-th
/// line, or `None` if a record is not exactly one such line, names a node `index` does not
/// know, or (with [`TagsOut::Run`]) breaks the run of tags.
pub fn element_records<'a>(
    i: &'a [u8],
    n: usize,
    tags: TagsOut<'_>,
    conn: &mut [u32],
    nn: usize,
    index: impl Fn(u64) -> Option<u32> + Sync,
) -> Option<&'a [u8]> {
    debug_assert_eq!(conn.len(), n * nn);
    if nn == 0 || n == 0 {
        return None;
    }
    let half = lines_per_chunk(n).div_ceil(2);
    let halves = match tags {
        TagsOut::Run(first) => run_halves(i, n, half, first),
        TagsOut::Store(_) => None,
    };
    let halves = match halves {
        Some(h) => h,
        None => line_chunks(i, n, half)?.0,
    };
    let end = element_halves(i, &halves, tags, conn, nn, &index)?;
    Some(&i[end..])
}

/// The element records of [`element_records`] cut into `halves` (offset of the first line,
/// number of records): task `c` reads halves `2c` and `2c + 1` side by side into its slots and
/// checks that each half ends where the next one starts. Returns the offset after the last
/// half.
fn element_halves(
    i: &[u8],
    halves: &[(usize, usize)],
    tags: TagsOut<'_>,
    conn: &mut [u32],
    nn: usize,
    index: &(impl Fn(u64) -> Option<u32> + Sync),
) -> Option<usize> {
    // The slots of each task, and the number of records before it.
    let (mut conn_rest, mut before) = (conn, 0u64);
    let mut tags_rest: Option<&mut [u64]> = None;
    let first = match tags {
        TagsOut::Run(first) => first,
        TagsOut::Store(t) => {
            tags_rest = Some(t);
            0
        }
    };
    let mut tasks = Vec::with_capacity(halves.len().div_ceil(2));
    for pair in halves.chunks(2) {
        let records: usize = pair.iter().map(|h| h.1).sum();
        let (c, rest) = std::mem::take(&mut conn_rest).split_at_mut(records * nn);
        conn_rest = rest;
        let t = match tags_rest.take() {
            Some(t) => {
                let (t, rest) = t.split_at_mut(records);
                tags_rest = Some(rest);
                Some(t)
            }
            None => None,
        };
        tasks.push((pair, t, before, c));
        before += records as u64;
    }
    // The offset where the half after `pair` (task `c`) starts, if there is one.
    let next_start = |c: usize| halves.get(2 * c + 2).map(|h| h.0);
    type Task<'h, 't, 'c> = (
        &'h [(usize, usize)],
        Option<&'t mut [u64]>,
        u64,
        &'c mut [u32],
    );
    let task = |c: usize, (pair, tags, before, conn): Task<'_, '_, '_>| {
        let (start_a, len_a) = pair[0];
        let start_b = pair.get(1).map_or(start_a, |h| h.0);
        let (conn_a, conn_b) = conn.split_at_mut(len_a * nn);
        let (tags_a, tags_b) = match tags {
            Some(t) => {
                let (a, b) = t.split_at_mut(len_a);
                (Some(a), Some(b))
            }
            None => (None, None),
        };
        let first = first.wrapping_add(before);
        let a = (start_a, tags_a, first, conn_a);
        let b = (start_b, tags_b, first.wrapping_add(len_a as u64), conn_b);
        let (end_a, end_b) = match nn {
            3 => element_chunk::<3>(i, a, b, nn, index),
            4 => element_chunk::<4>(i, a, b, nn, index),
            6 => element_chunk::<6>(i, a, b, nn, index),
            8 => element_chunk::<8>(i, a, b, nn, index),
            10 => element_chunk::<10>(i, a, b, nn, index),
            _ => element_chunk::<0>(i, a, b, nn, index),
        }?;
        let end = if pair.len() == 2 {
            (end_a == start_b).then_some(end_b)?
        } else {
            end_a
        };
        next_start(c).is_none_or(|s| s == end).then_some(end)
    };
    let ends: Vec<usize> = if tasks.len() == 1 {
        // One task: on the calling thread.
        let one = tasks.pop().expect("one task");
        vec![task(0, one)?]
    } else {
        tasks
            .into_par_iter()
            .enumerate()
            .map(|(c, t)| task(c, t))
            .collect::<Option<Vec<usize>>>()?
    };
    ends.last().copied()
}

/// A signed integer that fits an `i32`, on the current line.
#[inline(always)]
pub fn int32(i: &[u8]) -> Option<(&[u8], i32)> {
    let i = blank(i);
    let (neg, digits) = match i.first() {
        Some(b'-') => (true, &i[1..]),
        Some(b'+') => (false, &i[1..]),
        _ => (false, i),
    };
    if digits.first().is_none_or(|c| !c.is_ascii_digit()) {
        return None;
    }
    let (rest, v) = uint(digits)?;
    let v = if neg { -(v as i128) } else { v as i128 };
    Some((rest, i32::try_from(v).ok()?))
}

/// The powers of ten that are exact in an `f64` (10^22 < 2^53 · 2^22).
const EXACT_POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Whether the 8 bytes `w` are all ASCII digits.
#[inline(always)]
fn all_digits(w: u64) -> bool {
    ((w & 0xF0F0_F0F0_F0F0_F0F0)
        | ((w.wrapping_add(0x0606_0606_0606_0606) & 0xF0F0_F0F0_F0F0_F0F0) >> 4))
        == 0x3333_3333_3333_3333
}

/// The decimal digits at `i[p..]`, at most `max` of them, appended to `value`: the position
/// after them and the value.
#[inline(always)]
fn digit_run(i: &[u8], mut p: usize, max: usize, mut value: u64) -> (usize, u64) {
    let start = p;
    while let Some(&c) = i.get(p) {
        let d = c.wrapping_sub(b'0');
        if d > 9 || p - start == max {
            break;
        }
        value = value * 10 + u64::from(d);
        p += 1;
    }
    (p, value)
}

/// The common short form of a coordinate, `[±]digits[.digits][(e|E)[±]digits]` with at most 19
/// significant digits ending at white space or the end of input, when its value is exact by
/// Clinger's fast path (Clinger 1990, "How to read floating point numbers accurately"): the
/// decimal significand m ≤ 2^53 and the power of ten 10^|e| with |e| ≤ 22 are both exact
/// doubles, so m · 10^e or m / 10^-e is a single correctly rounded operation — the same double
/// as any correct parser. Fraction digits are read 8 at a time. `None` for anything else (more
/// digits, larger exponents, `inf`, `nan`, a malformed token), which [`float`] hands to the
/// general parser.
#[inline(always)]
fn float_exact(i: &[u8]) -> Option<(&[u8], f64)> {
    let (neg, p) = match i.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    let int_start = p;
    let (mut p, mut m) = digit_run(i, p, 19, 0);
    let int_digits = p - int_start;
    let mut frac = 0;
    if i.get(p) == Some(&b'.') {
        p += 1;
        let frac_start = p;
        while int_digits + (p - frac_start) + 8 <= 19 {
            match i.get(p..p + 8) {
                Some(w) => {
                    let w = u64::from_le_bytes(w.try_into().expect("8 bytes"));
                    if !all_digits(w) {
                        break;
                    }
                    m = m * 100_000_000 + eight_digit_values(w.wrapping_sub(0x3030_3030_3030_3030));
                    p += 8;
                }
                None => break,
            }
        }
        (p, m) = digit_run(i, p, 19 - int_digits - (p - frac_start), m);
        frac = p - frac_start;
    }
    if int_digits + frac == 0 {
        return None;
    }
    let mut e = -(frac as i32);
    if matches!(i.get(p), Some(b'e' | b'E')) {
        p += 1;
        let neg_e = i.get(p) == Some(&b'-');
        if neg_e || i.get(p) == Some(&b'+') {
            p += 1;
        }
        let start = p;
        let x;
        (p, x) = digit_run(i, p, 4, 0);
        if p == start {
            return None;
        }
        let x = x as i32;
        e += if neg_e { -x } else { x };
    }
    if !ends_token(&i[p..]) || m > 1 << 53 || !(-22..=22).contains(&e) {
        return None;
    }
    let v = if e < 0 {
        m as f64 / EXACT_POW10[e.unsigned_abs() as usize]
    } else {
        m as f64 * EXACT_POW10[e as usize]
    };
    Some((&i[p..], if neg { -v } else { v }))
}

/// A finite floating-point number on the current line: the exact short form
/// ([`float_exact`]), else `fast-float2` (Eisel–Lemire) on the bytes.
#[inline(always)]
pub fn float(i: &[u8]) -> Option<(&[u8], f64)> {
    let i = blank(i);
    if let Some(r) = float_exact(i) {
        return Some(r);
    }
    let (v, n) = fast_float2::parse_partial::<f64, _>(i).ok()?;
    (n > 0 && v.is_finite() && ends_token(&i[n..])).then(|| (&i[n..], v))
}

/// Reads `n` one-line records starting at `i` in parallel into `out` (`width` values per
/// record): `record(line, values)` reads one record from the start of its line into its `width`
/// slots and returns the input after the record (before the line's end). Returns the input after
/// the n-th line, or `None` if any record fails or a line holds more than its record.
pub fn read_records<'a, T: Send>(
    i: &'a [u8],
    n: usize,
    width: usize,
    out: &mut [T],
    record: impl Fn(&'a [u8], &mut [T]) -> Option<&'a [u8]> + Sync,
) -> Option<&'a [u8]> {
    debug_assert_eq!(out.len(), n * width);
    let per = lines_per_chunk(n);
    let (chunks, end) = line_chunks(i, n, per)?;
    let chunk = |out: &mut [T], &(start, lines): &(usize, usize)| {
        let mut r = &i[start..];
        for slots in out.chunks_exact_mut(width).take(lines) {
            match record(r, slots).and_then(line_end) {
                Some(rest) => r = rest,
                None => return false,
            }
        }
        true
    };
    let ok = match chunks.as_slice() {
        [one] => chunk(out, one),
        _ => out
            .par_chunks_mut(per * width)
            .zip(chunks.par_iter())
            .all(|(out, c)| chunk(out, c)),
    };
    ok.then(|| &i[end..])
}

/// [`read_records`] with two outputs per record (`width_a` values into `out_a`, `width_b` into
/// `out_b`), e.g. an element's tag and its nodes.
pub fn read_records2<'a, A: Send, B: Send>(
    i: &'a [u8],
    n: usize,
    (out_a, width_a): (&mut [A], usize),
    (out_b, width_b): (&mut [B], usize),
    record: impl Fn(&'a [u8], &mut [A], &mut [B]) -> Option<&'a [u8]> + Sync,
) -> Option<&'a [u8]> {
    debug_assert_eq!(out_a.len(), n * width_a);
    debug_assert_eq!(out_b.len(), n * width_b);
    let per = lines_per_chunk(n);
    let (chunks, end) = line_chunks(i, n, per)?;
    let chunk = |a: &mut [A], b: &mut [B], &(start, lines): &(usize, usize)| {
        let mut r = &i[start..];
        for (sa, sb) in a
            .chunks_exact_mut(width_a)
            .zip(b.chunks_exact_mut(width_b))
            .take(lines)
        {
            match record(r, sa, sb).and_then(line_end) {
                Some(rest) => r = rest,
                None => return false,
            }
        }
        true
    };
    let ok = match chunks.as_slice() {
        [one] => chunk(out_a, out_b, one),
        _ => out_a
            .par_chunks_mut(per * width_a)
            .zip(out_b.par_chunks_mut(per * width_b))
            .zip(chunks.par_iter())
            .all(|((a, b), c)| chunk(a, b, c)),
    };
    ok.then(|| &i[end..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_cover_the_lines_exactly() {
        let text = b"1 a\n2 b\n3 c\n4 d\n5 e\nrest";
        let (chunks, end) = line_chunks(text, 5, 2).unwrap();
        assert_eq!(chunks, vec![(0, 2), (8, 2), (16, 1)]);
        assert_eq!(&text[end..], b"rest");
        assert!(line_chunks(text, 6, 2).is_none());
        // Lines of 1 to 150 bytes: the chunk starts are the line starts after every `per` lines.
        let mut long = Vec::new();
        let mut starts = vec![0];
        for k in 0..2000usize {
            long.extend(std::iter::repeat_n(b'x', (k * 37) % 150));
            long.push(b'\n');
            starts.push(long.len());
        }
        long.extend_from_slice(b"tail");
        for (n, per) in [(2000, 7), (2000, 2000), (1999, 64), (1, 5), (640, 1)] {
            let (chunks, end) = line_chunks(&long, n, per).unwrap();
            let want: Vec<(usize, usize)> = (0..n)
                .step_by(per)
                .map(|l| (starts[l], per.min(n - l)))
                .collect();
            assert_eq!(chunks, want, "n {n} per {per}");
            assert_eq!(end, starts[n]);
        }
        assert!(line_chunks(&long, 2001, 100).is_none());
    }

    #[test]
    fn newlines_counted_in_blocks_equal_the_byte_count() {
        // Every byte value next to newlines, runs of newlines long enough to fill the per-byte
        // counters of both counts (255 words of 8, 255 blocks of 16), lengths that leave every
        // remainder of the words and blocks.
        let mut text: Vec<u8> = (0..=255u8).flat_map(|b| [b, b'\n', b ^ 0x0A]).collect();
        text.extend(std::iter::repeat_n(b'\n', 300 * 8 + 5));
        text.extend(std::iter::repeat_n(b'\n', 2 * 255 * 16 + 3));
        text.extend((0..5000u32).map(|k| if k % 7 == 0 { b'\n' } else { (k % 251) as u8 }));
        for start in [0, 1, 3, 8] {
            for end in [
                text.len(),
                text.len() - 1,
                text.len() - 7,
                9000,
                2048,
                2049,
                17,
            ] {
                let b = &text[start..end];
                let want = b.iter().filter(|&&c| c == b'\n').count();
                assert_eq!(count_newlines(b), want, "{start}..{end}");
                assert_eq!(count_newlines_swar(b), want, "{start}..{end}");
            }
        }
        assert_eq!(count_newlines(b""), 0);
    }

    #[test]
    fn integers_read_eight_bytes_at_a_time_equal_the_digit_loop() {
        for v in [
            0u64,
            7,
            10,
            99,
            12_345,
            1_000_000,
            9_999_999,
            10_000_000,
            123_456_789_012,
        ] {
            for tail in [" 5\n", "\n", "\r\n", "\t", " ", ""] {
                let text = format!("{v}{tail}");
                let (rest, got) = uint(text.as_bytes()).unwrap();
                assert_eq!(got, v, "{text:?}");
                assert_eq!(rest, tail.as_bytes());
            }
            assert!(uint(format!("{v}x").as_bytes()).is_none());
            assert!(uint(format!("{v}.5 ").as_bytes()).is_none());
        }
        assert!(uint(b"-12345678").is_none());
        assert!(uint(b"x2345678").is_none());
        assert_eq!(uint(b"  00042  ").map(|r| r.1), Some(42));
    }

    #[test]
    fn floats_by_the_exact_short_form_equal_the_standard_parser_bit_for_bit() {
        // Gmsh's %.16g coordinates and the forms around the fast path's limits: 19 and 20
        // significant digits, 2^53 ± 1, exponents ±22 and ±23, signs, leading and trailing dots.
        let mut tokens: Vec<String> = [
            "0",
            "-0",
            "+0",
            "0.25",
            "-0.2230769230769225",
            "1e-05",
            "1E+22",
            "1e22",
            "1e23",
            "1e-22",
            "1e-23",
            "5.",
            ".5",
            "+.5",
            "-5.e3",
            "9007199254740992",
            "9007199254740993",
            "9007199254740991.5",
            "1234567890123456789",
            "12345678901234567890",
            "0.1234567890123456789",
            "0.00000000000000000001",
            "123.456e-7",
            "1.7976931348623157e308",
            "4.9e-324",
            "0.30000000000000004",
            "1e0000",
            "7e-0022",
        ]
        .iter()
        .map(|t| t.to_string())
        .collect();
        // Pseudo-random coordinates as Gmsh writes them (shortest round trip, %.16g, %.17e).
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = (x >> 11) as f64 / (1u64 << 53) as f64 * 10f64.powi((x % 13) as i32 - 6) - 0.5;
            tokens.push(format!("{v}"));
            tokens.push(format!("{v:.16}"));
            tokens.push(format!("{v:.17e}"));
            tokens.push(format!("{:.3}", v * 1e3));
        }
        let mut exact = 0;
        for t in &tokens {
            let want: f64 = t.parse().unwrap();
            let text = format!("{t} \n");
            let (rest, got) = float(text.as_bytes()).unwrap();
            assert_eq!(got.to_bits(), want.to_bits(), "{t}");
            assert_eq!(rest, b" \n", "{t}");
            exact += usize::from(float_exact(t.as_bytes()).is_some());
            // The digits read 8 bytes at a time (room after the token) and byte by byte (the
            // token at the end of the input) give the same value.
            let padded = format!("{t}        \n");
            let bits = |r: Option<(&[u8], f64)>| r.map(|(_, v)| v.to_bits());
            assert_eq!(
                bits(float_exact(padded.as_bytes())),
                bits(float_exact(t.as_bytes())),
                "{t}"
            );
            assert_eq!(bits(float(t.as_bytes())), Some(want.to_bits()), "{t}");
        }
        // Most of them take the exact path; the others (long or huge) the general parser.
        assert!(exact > tokens.len() / 2, "{exact} of {}", tokens.len());
        assert!(float_exact(b"12345678901234567890").is_none());
        assert!(float_exact(b"1e23").is_none());
        assert!(float_exact(b"9007199254740993").is_none());
        for bad in [
            "1.5.2 ", "1e ", "1e+ ", ". ", "- ", "inf ", "1x ", "1,5 ", "0x10 ",
        ] {
            assert!(float(bad.as_bytes()).is_none(), "{bad}");
        }
    }

    #[test]
    fn tokens_must_end_at_white_space() {
        assert_eq!(uint(b" 12 x").map(|r| r.1), Some(12));
        assert!(uint(b"12x").is_none());
        assert!(uint(b"\n12").is_none()); // a record does not continue on the next line
        assert_eq!(int32(b"-7\n").map(|r| r.1), Some(-7));
        assert!(int32(b"-\n").is_none());
        assert_eq!(float(b"\t-1.5e-3\r\n").map(|r| r.1), Some(-1.5e-3));
        assert!(float(b"1.5.2 ").is_none());
        assert!(float(b"inf ").is_none());
        assert!(float(b"nan ").is_none());
        assert_eq!(line_end(b" \r\nnext"), Some(&b"next"[..]));
        assert!(line_end(b" 3\n").is_none());
    }

    #[test]
    fn element_records_check_a_run_of_tags_or_store_them() {
        // Several chunks of records `tag n1 .. nn`, nn = 4 (unrolled) and 5 (generic), with the
        // separators Gmsh and other writers use (trailing blank, tab, CR).
        for (nn, tail) in [(4usize, " "), (5, ""), (4, "\t\r")] {
            let n = 3 * CHUNK_LINES + 17;
            let node = |k: usize, j: usize| ((k * 7 + j * 13) % 1000 + 1) as u64;
            let text = |tag: &dyn Fn(usize) -> u64| {
                let mut t = String::new();
                for k in 0..n {
                    t += &tag(k).to_string();
                    for j in 0..nn {
                        t += &format!(" {}", node(k, j));
                    }
                    t += tail;
                    t += "\n";
                }
                t + "$End"
            };
            let index = |tag: u64| (tag <= 1000).then(|| tag as u32 - 1);
            let mut conn = vec![0u32; n * nn];
            let run = text(&|k| 41 + k as u64);
            let rest =
                element_records(run.as_bytes(), n, TagsOut::Run(41), &mut conn, nn, index).unwrap();
            assert_eq!(rest, b"$End");
            for k in 0..n {
                for j in 0..nn {
                    assert_eq!(u64::from(conn[k * nn + j]), node(k, j) - 1);
                }
            }
            // A run that starts elsewhere: refused. One tag off the run in the first or the
            // second half of a task or in a last, lone half (tasks read two halves of
            // CHUNK_LINES / 2 lines side by side): refused; stored instead.
            assert!(
                element_records(run.as_bytes(), n, TagsOut::Run(40), &mut conn, nn, index)
                    .is_none()
            );
            let mut tags = vec![0u64; n];
            for at in [
                CHUNK_LINES / 2 + 3,
                2 * CHUNK_LINES + 1,
                3 * CHUNK_LINES + 2,
            ] {
                let jump = |k: usize| 41 + k as u64 + if k == at { 5 } else { 0 };
                let broken = text(&jump);
                assert!(
                    element_records(broken.as_bytes(), n, TagsOut::Run(41), &mut conn, nn, index)
                        .is_none(),
                    "break at {at}"
                );
                let rest = element_records(
                    broken.as_bytes(),
                    n,
                    TagsOut::Store(&mut tags),
                    &mut conn,
                    nn,
                    index,
                )
                .unwrap();
                assert_eq!(rest, b"$End");
                assert!((0..n).all(|k| tags[k] == jump(k)), "break at {at}");
                assert!((0..n * nn).all(|c| u64::from(conn[c]) == node(c / nn, c % nn) - 1));
            }
            // A record over two lines, an unknown node, a missing node: refused, in either
            // half of a task.
            let store = |text: &str, tags: &mut [u64], conn: &mut [u32]| {
                let run = element_records(text.as_bytes(), n, TagsOut::Run(41), conn, nn, index);
                let stored =
                    element_records(text.as_bytes(), n, TagsOut::Store(tags), conn, nn, index);
                run.is_some() || stored.is_some()
            };
            for k in [5, CHUNK_LINES / 2 + 7, 2 * CHUNK_LINES] {
                let line = |k: usize| format!("\n{} {} ", 41 + k, node(k, 0));
                let two_lines =
                    run.replacen(&line(k), &format!("\n{}\n{} ", 41 + k, node(k, 0)), 1);
                assert_ne!(two_lines, run);
                assert!(!store(&two_lines, &mut tags, &mut conn), "line {k}");
                let unknown = run.replacen(&line(k), &format!("\n{} 1001 ", 41 + k), 1);
                assert_ne!(unknown, run);
                assert!(!store(&unknown, &mut tags, &mut conn), "line {k}");
                let last = format!(" {}{tail}\n{} ", node(k, nn - 1), 42 + k);
                let missing = run.replacen(&last, &format!("\n{} ", 42 + k), 1);
                assert_ne!(missing, run);
                assert!(!store(&missing, &mut tags, &mut conn), "line {k}");
            }
        }
    }

    #[test]
    fn element_halves_found_by_the_tags_end_exactly_at_the_block_end() {
        // Lines of very uneven length (the first ones short, later ones padded with up to 60
        // blanks), and after the block the next one's header and records, whose tags run on:
        // the run's halves are found by guessed offsets, and the block ends at its n-th line.
        let nn = 4;
        let n = 5 * CHUNK_LINES + 3;
        let node = |k: usize, j: usize| ((k * 11 + j * 5) % 700 + 1) as u64;
        let mut text = String::new();
        for k in 0..n + 50 {
            if k == n {
                text += "3 1 4 50\n";
            }
            text += &(7 + k).to_string();
            for j in 0..nn {
                text += &format!(" {}", node(k, j));
            }
            text += &" ".repeat(k * 60 / n);
            text += "\n";
        }
        text += "$EndElements";
        let halves = run_halves(text.as_bytes(), n, CHUNK_LINES, 7).unwrap();
        assert!(halves.len() >= 5, "{} halves", halves.len());
        assert_eq!(halves.iter().map(|h| h.1).sum::<usize>(), n);
        let index = |tag: u64| (tag <= 700).then(|| tag as u32 - 1);
        let mut conn = vec![0u32; n * nn];
        let rest = element_records(text.as_bytes(), n, TagsOut::Run(7), &mut conn, nn, index);
        assert!(rest.unwrap().starts_with(b"3 1 4 50\n"));
        assert!((0..n * nn).all(|c| u64::from(conn[c]) == node(c / nn, c % nn) - 1));
        // More records than the block holds: refused (the next block's header is not a
        // record of the run). Fewer: the rest starts at the first record not asked for.
        let mut more = vec![0u32; (n + 20) * nn];
        assert!(element_records(
            text.as_bytes(),
            n + 20,
            TagsOut::Run(7),
            &mut more,
            nn,
            index
        )
        .is_none());
        let mut conn = vec![0u32; (n - 1) * nn];
        let rest = element_records(
            text.as_bytes(),
            n - 1,
            TagsOut::Run(7),
            &mut conn,
            nn,
            index,
        );
        assert!(rest
            .unwrap()
            .starts_with(format!("{} ", 7 + n - 1).as_bytes()));
    }

    #[test]
    fn records_read_in_parallel_equal_the_sequential_values() {
        let n = 3 * CHUNK_LINES + 17;
        let mut text = String::new();
        for k in 0..n {
            text += &format!("{} {:.17e}\n", k + 1, (k as f64).sqrt() - 3.25);
        }
        text += "$End";
        let mut out = vec![0.0; 2 * n];
        let rest = read_records(text.as_bytes(), n, 2, &mut out, |line, slots| {
            let (r, tag) = uint(line)?;
            let (r, x) = float(r)?;
            slots[0] = tag as f64;
            slots[1] = x;
            Some(r)
        })
        .unwrap();
        assert_eq!(rest, b"$End");
        for k in 0..n {
            assert_eq!(out[2 * k], (k + 1) as f64);
            let want: f64 = format!("{:.17e}", (k as f64).sqrt() - 3.25)
                .parse()
                .unwrap();
            assert_eq!(out[2 * k + 1], want);
        }
        // A record spread over two lines: refused.
        let broken = text.replacen("1 ", "1\n", 1);
        assert!(
            read_records(broken.as_bytes(), n, 2, &mut out, |line, slots| {
                let (r, _) = uint(line)?;
                let (r, x) = float(r)?;
                slots[0] = x;
                Some(r)
            })
            .is_none()
        );
    }
}
