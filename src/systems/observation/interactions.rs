//! The interactions of 0.1.1's `info["interactions"]` (docs/spec.md 5.2) as index pairs into the
//! observation's records: for every group, its members' ordered pairs, (i, j) then (j, i) for each
//! i < j in member order (0.1.1's order); for the k-th laptop user, (its `humans` index, its
//! laptop's `laptops` index).
//!
//! With a limited field of view or range the indices are those of the visible, compacted records,
//! as 0.1.1's `PartialObservations` recomputes them: a group contributes the pairs of its visible
//! members, a laptop user a pair only when both the human and the laptop are visible.
//!
//! Relies on the state's slot order (`crate::state`): humans are in observation order and a
//! group's members are consecutive slots, groups in slot order.

use super::Frame;
use crate::state::StateChunk;
use crate::state::columns::zero;

/// Write the pairs of environment `e` into `hh` (human-human) and `hl` (human-laptop), zero the
/// rest of both, and return the pair counts.
pub(super) fn write_interactions<const W: bool, const P: bool>(
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    hh: &mut [u32],
    hl: &mut [u32],
) -> [u32; 2] {
    let n_hh = human_human(s, e, f, hh);
    zero(&mut hh[2 * n_hh..]);
    let n_hl = human_laptop(s, e, f, hl);
    zero(&mut hl[2 * n_hl..]);
    [n_hh as u32, n_hl as u32]
}

/// Whether the sensor sees human slot `slot` of environment `e`.
#[inline]
fn human_seen<const W: bool, const P: bool>(
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    slot: usize,
) -> bool {
    let i = e * s.strides.humans + slot;
    f.sees_point(s.h_x[i], s.h_y[i])
}

/// Whether the sensor sees laptop slot `slot` of environment `e`.
#[inline]
fn laptop_seen<const W: bool, const P: bool>(
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    slot: usize,
) -> bool {
    let i = e * s.strides.laptops + slot;
    f.sees_point(s.l_x[i], s.l_y[i])
}

/// How many of the human slots `slots` the sensor sees.
fn humans_seen<const W: bool, const P: bool>(
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    slots: std::ops::Range<usize>,
) -> u32 {
    slots.map(|k| u32::from(human_seen(s, e, f, k))).sum()
}

fn human_human<const W: bool, const P: bool>(
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [u32],
) -> usize {
    let gb = e * s.strides.groups;
    let mut n = 0;
    // The slots before `slot` are counted: `seen` of them are visible.
    let mut slot = 0usize;
    let mut seen = 0u32;
    for g in gb..gb + s.n_groups[e] as usize {
        let first = s.g_first[g] as usize;
        let end = first + s.g_count[g] as usize;
        assert!(
            first >= slot,
            "group {} starts at human slot {first}, before the end {slot} of the group before it",
            g - gb
        );
        // The record indices of the group's visible members: start..stop.
        let (start, stop) = if P {
            let start = seen + humans_seen(s, e, f, slot..first);
            seen = start + humans_seen(s, e, f, first..end);
            (start, seen)
        } else {
            (first as u32, end as u32)
        };
        slot = end;
        let members = (stop - start) as usize;
        assert!(
            2 * (n + members * members.saturating_sub(1)) <= out.len(),
            "group {} of {members} members overflows the {} human-human pairs of the layout",
            g - gb,
            out.len() / 2
        );
        for a in start..stop {
            for b in a + 1..stop {
                out[2 * n..2 * n + 4].copy_from_slice(&[a, b, b, a]);
                n += 2;
            }
        }
    }
    n
}

fn human_laptop<const W: bool, const P: bool>(
    s: &StateChunk,
    e: usize,
    f: &Frame<W, P>,
    out: &mut [u32],
) -> usize {
    let ub = e * s.strides.laptop_users;
    let mut n = 0;
    for u in ub..ub + s.n_laptop_users[e] as usize {
        let (human, laptop) = (s.lu_human[u] as usize, s.lu_laptop[u] as usize);
        let pair = if P {
            if !human_seen(s, e, f, human) || !laptop_seen(s, e, f, laptop) {
                continue;
            }
            // Record indices among the visible: the visible slots before each.
            let h = (0..human).filter(|&k| human_seen(s, e, f, k)).count();
            let l = (0..laptop).filter(|&k| laptop_seen(s, e, f, k)).count();
            [h as u32, l as u32]
        } else {
            [human as u32, laptop as u32]
        };
        out[2 * n..2 * n + 2].copy_from_slice(&pair);
        n += 1;
    }
    n
}
