//! The fan pass's fast path: a vertex inside a closed surface, decided from its corners alone.
//!
//! A vertex's corners are links (`next | prev << 32`, see `link`): corner `i` has the outgoing
//! side `v → next[i]` and the incoming side `prev[i] → v`. The fast path succeeds when every
//! edge `{v, w}` at the vertex is used exactly twice in opposite directions: no side leads
//! back to `v`, and every outgoing end `next[i]` equals exactly one incoming end `prev[σ(i)]`,
//! the matching `σ` being a permutation of the corners. Going from a corner to its match
//! crosses an edge of the fan, so the fan's pieces are the cycles of `σ`.
//!
//! Invariants:
//! - [`closed_fan`] either returns `false` and records nothing, or records exactly what the
//!   general fan check records for the same corners (each edge counted from its lower end, a
//!   fan of several pieces as one non-manifold vertex).
//! - The SSE2 matching (x86-64, where SSE2 is always present) and the portable one give the
//!   same `σ`, or both none, for every fan; a test holds them to it.
//!
//! Why SIMD by hand: each outgoing end is compared with every incoming end at once, which
//! makes the comparisons independent of each other. A table of incoming ends (the earlier
//! method) made a chain of dependent loads per corner; the compiler does not turn the
//! portable loop's per-lane booleans into a lane mask by itself.

use super::{FanSums, SMALL_FAN, unlink};

/// Records the edges and fan pieces of `vertex` and returns `true` when its `k` corners,
/// `window[..k]`, make a closed fan (see the module documentation); else returns `false`,
/// recording nothing. `window` runs on past the fan (to the end of the links, so the corners
/// load four at a time without a copy); `1 <= k <= SMALL_FAN`.
#[inline]
pub(super) fn closed_fan(window: &[u64], k: usize, vertex: u32, sums: &mut FanSums) -> bool {
    debug_assert!((1..=SMALL_FAN).contains(&k) && k <= window.len());
    let Some(sigma) = matching(window, k, vertex) else {
        return false;
    };
    // Almost always σ is one cycle: the walk from corner 0 comes back after exactly k steps.
    let step = |corner: usize| ((sigma >> (4 * corner)) & 0xf) as usize;
    let mut corner = step(0);
    let mut length = 1;
    while corner != 0 && length < k {
        corner = step(corner);
        length += 1;
    }
    let one_cycle = corner == 0 && length == k;
    // Each edge {v, w} appears once among the outgoing ends; count it from its lower end.
    sums.edges += window[..k]
        .iter()
        .filter(|&&link| link as u32 > vertex)
        .count();
    if !one_cycle {
        // Several pieces: the vertex is a pinch.
        sums.nonmanifold_vertices += 1;
    }
    true
}

/// `σ` packed a corner per nibble (SMALL_FAN = 16 corners fill the 64 bits, and following
/// it is then a shift and a mask in registers), or `None` when a side leads back to the
/// vertex or `σ` is not a permutation.
#[inline]
fn matching(window: &[u64], k: usize, vertex: u32) -> Option<u64> {
    #[cfg(target_arch = "x86_64")]
    {
        sse2::matching(window, k, vertex)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        portable_matching(&window[..k], vertex)
    }
}

/// [`matching`] one comparison at a time: the reference for the SSE2 path, and the path
/// elsewhere.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn portable_matching(fan: &[u64], vertex: u32) -> Option<u64> {
    if fan.iter().any(|&link| {
        let (next, prev) = unlink(link);
        next == vertex || prev == vertex
    }) {
        return None;
    }
    let mut sigma = 0u64;
    let mut image = 0u32;
    for (i, &outgoing) in fan.iter().enumerate() {
        let (w, _) = unlink(outgoing);
        let mut matches = 0u32;
        for (j, &incoming) in fan.iter().enumerate() {
            matches |= u32::from(unlink(incoming).1 == w) << j;
        }
        if !matches.is_power_of_two() || image & matches != 0 {
            return None;
        }
        image |= matches;
        sigma |= u64::from(matches.trailing_zeros()) << (4 * i);
    }
    Some(sigma)
}

#[cfg(target_arch = "x86_64")]
mod sse2 {
    use super::SMALL_FAN;
    use std::arch::x86_64::{
        __m128i, _mm_castps_si128, _mm_castsi128_ps, _mm_cmpeq_epi32, _mm_movemask_ps,
        _mm_or_si128, _mm_set_epi64x, _mm_set1_epi32, _mm_setzero_si128, _mm_shuffle_ps,
    };

    /// The lane mask of the 32-bit lanes of `a` equal to those of `b`.
    /// [`super::matching`] in two registers of corners, or four past eight corners.
    #[inline]
    pub(super) fn matching(window: &[u64], k: usize, vertex: u32) -> Option<u64> {
        // SAFETY: SSE2, the only feature these need, is part of the x86-64 baseline.
        unsafe {
            if k <= 8 {
                matching_in::<2>(window, k, vertex)
            } else {
                matching_in::<4>(window, k, vertex)
            }
        }
    }

    #[inline]
    #[target_feature(enable = "sse2")]
    fn equal(a: __m128i, b: __m128i) -> u32 {
        _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(a, b))) as u32
    }

    /// [`super::matching`] for `k <= 4 * GROUPS` corners, four to a register. Lanes past `k`
    /// hold whatever follows the fan and are masked off.
    #[inline]
    #[target_feature(enable = "sse2")]
    fn matching_in<const GROUPS: usize>(window: &[u64], k: usize, vertex: u32) -> Option<u64> {
        let mut padded = [0u64; SMALL_FAN];
        let links = match window.get(..4 * GROUPS) {
            Some(links) => links,
            // The last fans of the links: copied out, the rest left zero (masked off below).
            None => {
                let n = window.len().min(4 * GROUPS);
                padded[..n].copy_from_slice(&window[..n]);
                &padded[..4 * GROUPS]
            }
        };
        let all = u32::MAX >> (32 - k);
        let at_vertex = _mm_set1_epi32(vertex as i32);
        let mut prev = [_mm_setzero_si128(); GROUPS];
        let mut loops = 0u32;
        for (g, (quad, prev)) in links.chunks_exact(4).zip(&mut prev).enumerate() {
            // [n0 p0 n1 p1] and [n2 p2 n3 p3], split into the ends [n0 n1 n2 n3], [p0 p1 p2 p3].
            let low = _mm_castsi128_ps(_mm_set_epi64x(quad[1] as i64, quad[0] as i64));
            let high = _mm_castsi128_ps(_mm_set_epi64x(quad[3] as i64, quad[2] as i64));
            let next = _mm_castps_si128(_mm_shuffle_ps::<0b10_00_10_00>(low, high));
            *prev = _mm_castps_si128(_mm_shuffle_ps::<0b11_01_11_01>(low, high));
            let back = _mm_or_si128(
                _mm_cmpeq_epi32(next, at_vertex),
                _mm_cmpeq_epi32(*prev, at_vertex),
            );
            loops |= (_mm_movemask_ps(_mm_castsi128_ps(back)) as u32) << (4 * g);
        }
        if loops & all != 0 {
            return None;
        }
        let mut sigma = 0u64;
        let mut image = 0u32;
        let mut single = true;
        for (i, &link) in links[..k].iter().enumerate() {
            let outgoing = _mm_set1_epi32(link as u32 as i32);
            let mut matches = 0u32;
            for (g, &prev) in prev.iter().enumerate() {
                matches |= equal(prev, outgoing) << (4 * g);
            }
            matches &= all;
            single &= matches != 0 && matches & (matches - 1) == 0;
            image |= matches;
            sigma |= u64::from(matches.trailing_zeros() & 0xf) << (4 * i);
        }
        // One match each and every corner matched: σ is a permutation.
        (single && image == all).then_some(sigma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn sse2_matching_equals_the_portable_one() {
        let mut state = 7u64;
        let mut below = |n: u32| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 33) as u32) % n
        };
        let vertex = 40;
        let mut found = 0;
        for round in 0..200_000 {
            let k = 1 + below(SMALL_FAN as u32) as usize;
            // A shuffled ring half the time (a closed fan), else ends from a small range; a
            // window that stops at the fan or runs on past it.
            let mut fan: Vec<u64> = if round % 2 == 0 {
                let ring: Vec<u64> = (0..k as u64).map(|i| 100 + i).collect();
                (0..k).map(|i| ring[i] | ring[(i + 1) % k] << 32).collect()
            } else {
                (0..k)
                    .map(|_| u64::from(below(48)) | u64::from(below(48)) << 32)
                    .collect()
            };
            for i in (1..fan.len()).rev() {
                fan.swap(i, below(i as u32 + 1) as usize);
            }
            let tail = below(20) as usize;
            let window: Vec<u64> = fan
                .iter()
                .copied()
                .chain((0..tail).map(|_| u64::from(vertex) | u64::from(below(48)) << 32))
                .collect();
            let expected = portable_matching(&fan, vertex);
            let got = sse2::matching(&window, k, vertex);
            assert_eq!(got, expected, "fan {fan:x?}, window {window:x?}");
            found += usize::from(expected.is_some());
        }
        assert!(found > 90_000, "closed fans matched: {found}");
    }
}
