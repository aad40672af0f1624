//! The observation as the GPU backend keeps it on the device and reads it back: each row without
//! its entity records' one-hot floats ([`ONE_HOT`] a record).
//!
//! Those floats are a function of the per-type counts that every observation column has beside
//! it (`obs_count`, `final_obs_count`): 1.0 at the type's place ([`one_hot::OF_ENTITY`]) in the
//! first `count` records of a type, 0.0 elsewhere and in every padding record (noise is added to
//! the other floats only). So the device never stores them, a step reads back
//! [`ObsLayout::payload_dim`] floats a row (exp2: 401 of 695; padded: 81 of 135), and the host
//! writes them while it copies each row into its outputs ([`expand`]). The robot record stays
//! whole: its one-hot float is 1.0 in a written row and 0.0 in one never written (a `final_obs`
//! before any episode ended), which no count tells apart. The host's outputs hold whole rows, as
//! the CPU backend writes them.
//!
//! Payload word `j` of a row is row float `i`: the robot record first, whole, then each entity
//! record's floats from [`ONE_HOT`] on, in row order (`obs_payload_index` in
//! `shaders/observation.wgsl` is the same map, the other way).

use rayon::prelude::*;

use crate::outputs::Outputs;
use crate::spec::{ONE_HOT, ObsLayout, RECORD, one_hot};
use crate::state::columns::Elem;

/// The output columns of observation rows (their counts: [`observation_mut`]).
pub const OBSERVATION_COLUMNS: [&str; 2] = ["obs", "final_obs"];

/// Payload floats of an entity record.
const PAYLOAD: usize = RECORD - ONE_HOT;

/// Rows an expansion hands each thread at once.
const ROWS_PER_TASK: usize = 512;

/// Whether output column `name` holds observation rows.
pub fn is_observation(name: &str) -> bool {
    OBSERVATION_COLUMNS.contains(&name)
}

/// The GPU's output columns: the host's, each observation column [`ObsLayout::payload_dim`]
/// floats wide.
pub fn device_columns(out: &Outputs) -> Vec<(&'static str, Elem, usize)> {
    let payload = out.strides.layout.payload_dim();
    out.columns()
        .into_iter()
        .map(|(name, elem, stride)| {
            let stride = if is_observation(name) {
                payload
            } else {
                stride
            };
            (name, elem, stride)
        })
        .collect()
}

/// The device's output tables from the host's outputs: `Outputs::pack` with each observation row
/// stripped of its one-hot floats.
pub fn pack(out: &Outputs, f32s: &mut Vec<f32>, u32s: &mut Vec<u32>) {
    let layout = &out.strides.layout;
    let mut payload = vec![0; layout.payload_dim()];
    for (name, elem, _) in out.columns() {
        let words = column(out, name);
        let mut push = |w: &[u32]| match elem {
            Elem::F32 => f32s.extend(w.iter().map(|&v| f32::from_bits(v))),
            Elem::U32 => u32s.extend_from_slice(w),
        };
        if is_observation(name) {
            for row in words.chunks_exact(layout.dim) {
                strip_row(layout, row, &mut payload);
                push(&payload);
            }
        } else {
            push(words);
        }
    }
}

/// The inverse of [`pack`]: the host's outputs from the device's tables, each observation row
/// with its one-hot floats written from its counts.
pub fn unpack(out: &mut Outputs, f32s: &[f32], u32s: &[u32]) {
    let columns = device_columns(out);
    let mut at = [0usize; 2];
    let mut observations = Vec::new();
    for (name, elem, stride) in columns {
        let len = out.n_envs * stride;
        let k = usize::from(elem == Elem::U32);
        let words: &[u32] = match elem {
            Elem::F32 => bytemuck::cast_slice(&f32s[at[0]..at[0] + len]),
            Elem::U32 => &u32s[at[1]..at[1] + len],
        };
        at[k] += len;
        if is_observation(name) {
            // After every counts column is in place.
            observations.push((name, words));
        } else {
            column_mut(out, name).copy_from_slice(words);
        }
    }
    let layout = out.strides.layout;
    for (name, words) in observations {
        if let Some((counts, rows)) = observation_mut(out, name) {
            expand(&layout, 0, words, counts, rows, None);
        }
    }
}

/// The counts and the rows (as words) of observation column `name` of `out` (one of the
/// [`OBSERVATION_COLUMNS`]); `None` for any other column.
pub fn observation_mut<'a>(out: &'a mut Outputs, name: &str) -> Option<(&'a [u32], &'a mut [u32])> {
    let (counts, rows) = match name {
        "obs" => (&out.obs_count, &mut out.obs),
        "final_obs" => (&out.final_obs_count, &mut out.final_obs),
        _ => return None,
    };
    Some((counts, bytemuck::cast_slice_mut(rows)))
}

#[expect(
    clippy::expect_used,
    reason = "the names come from the table's own column list"
)]
fn column<'a>(out: &'a Outputs, name: &str) -> &'a [u32] {
    out.column_words(name).expect("a column of the table")
}

#[expect(
    clippy::expect_used,
    reason = "the names come from the table's own column list"
)]
fn column_mut<'a>(out: &'a mut Outputs, name: &str) -> &'a mut [u32] {
    out.column_words_mut(name).expect("a column of the table")
}

/// Write the payload of observation row `row` (`layout.dim` words) into `payload`
/// (`layout.payload_dim()` words).
pub fn strip_row(layout: &ObsLayout, row: &[u32], payload: &mut [u32]) {
    payload[..layout.robot].copy_from_slice(&row[..layout.robot]);
    let records = row[layout.robot..].chunks_exact(RECORD);
    for (dst, src) in payload[layout.robot..]
        .chunks_exact_mut(PAYLOAD)
        .zip(records)
    {
        dst.copy_from_slice(&src[ONE_HOT..]);
    }
}

/// Write into `rows` (an observation column of the host, `layout.dim` words an environment) the
/// payload words `part` of the device's column, which start at its word `first`, and the one-hot
/// floats of every record whose payload starts among them, from `counts` (the column's counts,
/// already in place: 5 an environment). Whole rows are split over `pool`'s threads.
pub fn expand(
    layout: &ObsLayout,
    first: usize,
    part: &[u32],
    counts: &[u32],
    rows: &mut [u32],
    pool: Option<&rayon::ThreadPool>,
) {
    let width = layout.payload_dim();
    if part.is_empty() || width == 0 {
        return;
    }
    let end = first + part.len();
    // Environments whose rows `part` holds whole: from `whole_from` to `whole_to`.
    let whole_from = first.div_ceil(width);
    let whole_to = (end / width).max(whole_from);
    let partial = |e: usize, rows: &mut [u32]| {
        let (lo, hi) = (first.max(e * width), end.min((e + 1) * width));
        if lo < hi {
            expand_row_part(
                layout,
                lo - e * width,
                &part[lo - first..hi - first],
                &counts[5 * e..5 * e + 5],
                &mut rows[e * layout.dim..(e + 1) * layout.dim],
            );
        }
    };
    if !first.is_multiple_of(width) {
        partial(first / width, rows);
    }
    let body = &mut rows[whole_from * layout.dim..whole_to * layout.dim];
    let task = |(k, chunk): (usize, &mut [u32])| {
        let e0 = whole_from + k * ROWS_PER_TASK;
        for (j, row) in chunk.chunks_exact_mut(layout.dim).enumerate() {
            let e = e0 + j;
            let src = &part[e * width - first..(e + 1) * width - first];
            expand_row(layout, src, &counts[5 * e..5 * e + 5], row);
        }
    };
    match pool {
        Some(pool) if whole_to - whole_from > ROWS_PER_TASK => {
            pool.install(|| {
                body.par_chunks_mut(ROWS_PER_TASK * layout.dim)
                    .enumerate()
                    .for_each(task);
            });
        }
        _ => body
            .chunks_mut(ROWS_PER_TASK * layout.dim)
            .enumerate()
            .for_each(task),
    }
    if !end.is_multiple_of(width) && end / width >= whole_to {
        partial(end / width, rows);
    }
}

/// One whole row: `payload` (`layout.payload_dim()` words) and the one-hot floats from `counts`
/// (5 words) into `row` (`layout.dim` words).
fn expand_row(layout: &ObsLayout, payload: &[u32], counts: &[u32], row: &mut [u32]) {
    row[..layout.robot].copy_from_slice(&payload[..layout.robot]);
    let mut records = row[layout.robot..].chunks_exact_mut(RECORD);
    let mut payloads = payload[layout.robot..].chunks_exact(PAYLOAD);
    for (t, &capacity) in layout.capacity.iter().enumerate() {
        let place = one_hot::OF_ENTITY[t];
        for k in 0..capacity {
            let (Some(dst), Some(src)) = (records.next(), payloads.next()) else {
                return;
            };
            write_one_hot(
                &mut dst[..ONE_HOT],
                (k < counts[t] as usize).then_some(place),
            );
            dst[ONE_HOT..].copy_from_slice(src);
        }
    }
}

/// Part of a row: payload words `from..from + src.len()` of it, with the one-hot floats of the
/// entity records whose payload starts among them.
fn expand_row_part(layout: &ObsLayout, from: usize, src: &[u32], counts: &[u32], row: &mut [u32]) {
    let to = from + src.len();
    let robot = from.min(layout.robot)..to.min(layout.robot);
    row[robot.clone()].copy_from_slice(&src[..robot.len()]);
    for slot in 0..layout.entity_records() {
        // The slot's payload starts at payload word `p0`, its record at row float `at`.
        let p0 = layout.robot + slot * PAYLOAD;
        let at = layout.robot + slot * RECORD;
        let (lo, hi) = (p0.max(from), (p0 + PAYLOAD).min(to));
        if lo < hi {
            row[at + ONE_HOT + lo - p0..at + ONE_HOT + hi - p0]
                .copy_from_slice(&src[lo - from..hi - from]);
        }
        if (from..to).contains(&p0) {
            write_one_hot(
                &mut row[at..at + ONE_HOT],
                slot_one_hot(layout, slot, counts),
            );
        }
    }
}

/// The one-hot place of entity slot `slot` (in row order) with these counts: its type's, or
/// `None` for a padding record.
fn slot_one_hot(layout: &ObsLayout, mut slot: usize, counts: &[u32]) -> Option<usize> {
    for (t, &capacity) in layout.capacity.iter().enumerate() {
        if slot < capacity {
            return (slot < counts[t] as usize).then_some(one_hot::OF_ENTITY[t]);
        }
        slot -= capacity;
    }
    None
}

/// The one-hot floats of each place (as words), then of none: whole-array copies instead of a
/// comparison per float.
const ONE_HOTS: [[u32; ONE_HOT]; ONE_HOT + 1] = {
    let mut table = [[0; ONE_HOT]; ONE_HOT + 1];
    let mut k = 0;
    while k < ONE_HOT {
        table[k][k] = 1.0f32.to_bits();
        k += 1;
    }
    table
};

/// 1.0 at `place`, 0.0 elsewhere (everywhere without one) into `dst` ([`ONE_HOT`] words).
fn write_one_hot(dst: &mut [u32], place: Option<usize>) {
    dst.copy_from_slice(&ONE_HOTS[place.unwrap_or(ONE_HOT).min(ONE_HOT)]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::RECORD;

    fn layout(robot: usize, capacity: [usize; 5]) -> ObsLayout {
        let mut offset = [0; 5];
        let mut at = robot;
        for (o, n) in offset.iter_mut().zip(capacity) {
            *o = at;
            at += n * RECORD;
        }
        ObsLayout {
            robot,
            capacity,
            offset,
            dim: at,
            pairs: [0, 0],
        }
    }

    /// A row as the observation writer makes it: one-hots from `counts`, payload floats
    /// numbered from 1 (distinct, non-zero), zero payload in padding records.
    fn row_of(l: &ObsLayout, counts: [u32; 5]) -> Vec<u32> {
        let mut row = vec![0u32; l.dim];
        row[one_hot::ROBOT] = 1.0f32.to_bits();
        let mut next = 1u32;
        for v in &mut row[ONE_HOT..l.robot] {
            *v = next;
            next += 1;
        }
        for t in 0..5 {
            for k in 0..l.capacity[t] {
                let at = l.offset[t] + k * RECORD;
                if k < counts[t] as usize {
                    row[at + one_hot::OF_ENTITY[t]] = 1.0f32.to_bits();
                    for v in &mut row[at + ONE_HOT..at + RECORD] {
                        *v = next;
                        next += 1;
                    }
                }
            }
        }
        row
    }

    #[test]
    fn a_row_stripped_then_expanded_is_the_row_in_any_pieces() {
        let l = layout(9, [3, 1, 2, 0, 4]);
        assert_eq!(l.payload_dim(), l.dim - 6 * 10);
        let counts = [
            [3, 0, 1, 0, 4],
            [1, 1, 2, 0, 0],
            [0, 0, 0, 0, 0],
            [0, 0, 0, 0, 0],
        ];
        let mut rows: Vec<u32> = counts[..3].iter().flat_map(|&c| row_of(&l, c)).collect();
        // A row never written (a `final_obs` before any episode ended) stays all zeros.
        rows.extend(vec![0; l.dim]);
        let flat_counts: Vec<u32> = counts.iter().flatten().copied().collect();
        let w = l.payload_dim();
        let mut payload = vec![0; 4 * w];
        for (src, dst) in rows.chunks_exact(l.dim).zip(payload.chunks_exact_mut(w)) {
            strip_row(&l, src, dst);
        }
        // Cuts of the column into two or three parts (the first at every word), expanded in
        // order, give the rows.
        for a in 0..=4 * w {
            for b in (a..=4 * w).step_by(7) {
                let mut out = vec![7u32; rows.len()];
                for part in [0..a, a..b, b..4 * w] {
                    expand(
                        &l,
                        part.start,
                        &payload[part.clone()],
                        &flat_counts,
                        &mut out,
                        None,
                    );
                }
                assert_eq!(out, rows, "cut at {a} and {b}");
            }
        }
    }

    #[test]
    fn the_threads_expand_what_one_thread_does() {
        let l = layout(16, [2, 0, 1, 1, 0]);
        let n = 3 * ROWS_PER_TASK + 5;
        let counts: Vec<u32> = (0..n)
            .flat_map(|e| [(e % 3) as u32, 0, 1, (e % 2) as u32, 0])
            .collect();
        let rows: Vec<u32> = counts
            .chunks_exact(5)
            .flat_map(|c| row_of(&l, [c[0], c[1], c[2], c[3], c[4]]))
            .collect();
        let mut payload = vec![0; n * l.payload_dim()];
        for (src, dst) in rows
            .chunks_exact(l.dim)
            .zip(payload.chunks_exact_mut(l.payload_dim()))
        {
            strip_row(&l, src, dst);
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let mut out = vec![0u32; rows.len()];
        // From the middle of a row to the middle of another, most rows whole.
        let cut = l.payload_dim() / 2;
        expand(&l, 0, &payload[..cut], &counts, &mut out, Some(&pool));
        expand(&l, cut, &payload[cut..], &counts, &mut out, Some(&pool));
        assert_eq!(out, rows);
    }
}
