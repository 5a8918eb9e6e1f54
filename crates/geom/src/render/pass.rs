//! Which triangles a view can pass over without drawing them: most of a tiling of tens of
//! millions, which are far smaller than a pixel.
//!
//! Each vertex gets a number, its [`pass_key`]: the cells between pixel centres it lies in
//! across and down ([`Raster::cells`]) and its side of the section's plane. A triangle whose
//! corners' keys agree on either axis covers no pixel centre, and one whose corners are on
//! one side does not meet the plane: it adds nothing to the picture, and that is seen from
//! three loads and a few bit operations ([`Keyed::look_at`]).
//!
//! Invariants:
//! - Passing over never changes the picture: a triangle is passed over only if
//!   [`Raster::covers`] would find no pixel centre in its box and the section would not cut
//!   it. Keys come from the same `f32` screen positions the raster uses ([`Raster::screen`]),
//!   and a vertex whose cell is in doubt (on a centre's line, NaN, past the key's 14 bits)
//!   gets none, which agrees with nothing.
//! - Keys are worked out once per vertex of a chunk; nothing else is kept per vertex (the
//!   corners of the few triangles looked at are projected again, to the same bits).

use std::collections::HashMap;

use rayon::prelude::*;

use super::raster::Raster;

/// Triangles looked through in one go ([`Keyed::look_at`]); also the run one parallel task
/// takes, so the thread pool's cost per task is small against it.
pub const RUN: usize = 4096;

/// A [`pass_key`] half's flag for a vertex in no cell (cells are below it: previews are at
/// most 8192 pixels a side).
const NO_CELL: u32 = 1 << 14;

/// A number per vertex such that a triangle whose corners' numbers agree on either half
/// neither covers a pixel centre nor meets the section's plane. The low half is the cell
/// across (bits 0–13; bit 14 set when there is none, or it does not fit) and the side of the
/// plane (bit 15); the high half the same down. Each half holds the side, so a half that
/// agrees is on one side.
#[inline(always)]
fn pass_key([across, down]: [Option<u32>; 2], above: bool) -> u32 {
    let half = |cell: Option<u32>| {
        let cell = cell.filter(|&c| c < NO_CELL).unwrap_or(NO_CELL);
        cell | u32::from(above) << 15
    };
    half(across) | half(down) << 16
}

/// The [`pass_key`] of model point `p` in `view`, with the section's plane at `z0` (NaN:
/// none).
#[inline(always)]
fn vertex_key(view: &Raster, z0: f64, p: [f32; 3]) -> u32 {
    pass_key(view.cells(view.screen(p)), f64::from(p[2]) >= z0)
}

/// The [`vertex_key`]s of `points` into `keys`, the same numbers. The points are read into
/// arrays of each coordinate first, a block at a time, so that the arithmetic is done for
/// several points at once (four per instruction on the baseline x86-64 target).
fn key_run(view: &Raster, z0: f64, points: &[[f32; 3]], keys: &mut [u32]) {
    const BLOCK: usize = 64;
    let above = Above::new(z0);
    for (points, keys) in points.chunks(BLOCK).zip(keys.chunks_mut(BLOCK)) {
        let mut xyz = [[0.0f32; BLOCK]; 3];
        for (i, p) in points.iter().enumerate() {
            for a in 0..3 {
                xyz[a][i] = p[a];
            }
        }
        for (i, key) in keys.iter_mut().enumerate().take(points.len()) {
            let p = [xyz[0][i], xyz[1][i], xyz[2][i]];
            *key = pass_key(view.cells(view.screen(p)), above.of(p[2]));
        }
    }
}

/// `f64::from(z) >= z0` for an `f32` height `z`, as one `f32` comparison: with the least
/// `f32` at or above `z0`, the two agree for every `z` (NaN, no plane, is below nothing).
struct Above(f32);

impl Above {
    fn new(z0: f64) -> Above {
        let t = z0 as f32;
        Above(if f64::from(t) < z0 { t.next_up() } else { t })
    }

    #[inline(always)]
    fn of(&self, z: f32) -> bool {
        z >= self.0
    }
}

/// Whether a triangle of corners with these [`pass_key`]s may be passed over.
#[inline(always)]
fn passed_over(a: u32, b: u32, c: u32) -> bool {
    let differ = (a ^ b) | (a ^ c);
    // Bitwise, not `&&`/`||`: which way it goes is random, and a branch would guess wrong.
    let agree = |half: u32| (differ & half == 0) & (a & half & (NO_CELL | NO_CELL << 16) == 0);
    agree(0xffff) | agree(0xffff_0000)
}

/// The pixel columns and rows whose centres the box of a triangle holds, from its corners'
/// [`pass_key`]s: `[min, max)` of their cells on each axis, which is what [`Raster::covers`]
/// finds from their screen positions (`None` from it where a range is empty). `None` when a
/// corner has no cell (the caller then asks [`Raster::covers`]).
#[inline(always)]
pub fn centres(keys: [u32; 3]) -> Option<((u32, u32), (u32, u32))> {
    let [a, b, c] = keys;
    if (a | b | c) & (NO_CELL | NO_CELL << 16) != 0 {
        return None;
    }
    let range = |shift: u32| {
        let [a, b, c] = [a, b, c].map(|k| k >> shift & (NO_CELL - 1));
        (a.min(b).min(c), a.max(b).max(c))
    };
    Some((range(0), range(16)))
}

/// The keys of a chunk's vertices, kept from one chunk to the next: a tiling's hundreds of
/// chunks would otherwise each fault fresh pages in for them.
#[derive(Default)]
pub struct Keys {
    own: Vec<u32>,
    borrowed: Vec<u32>,
    /// Where each borrowed id is in the chunk's borrowed list: a few percent of a tiling's
    /// triangles use one, too many for a binary search each.
    borrowed_at: HashMap<u32, u32, IdHasher>,
}

/// A chunk's vertices with their keys: ids from `first` index `own`, smaller ones `borrowed`.
pub struct Keyed<'a> {
    first: u32,
    own: &'a [[f32; 3]],
    own_keys: &'a [u32],
    borrowed: &'a [(u32, [f32; 3])],
    borrowed_keys: &'a [u32],
    borrowed_at: &'a HashMap<u32, u32, IdHasher>,
}

impl Keys {
    /// Keys the vertices of a chunk (`own` from id `first`, and `borrowed`, sorted by id) for
    /// `view` and the section's plane at `z0`.
    pub fn key<'a>(
        &'a mut self,
        view: &Raster,
        z0: Option<f64>,
        first: u32,
        own: &'a [[f32; 3]],
        borrowed: &'a [(u32, [f32; 3])],
    ) -> Keyed<'a> {
        let z0 = z0.unwrap_or(f64::NAN);
        self.borrowed.clear();
        self.borrowed
            .extend(borrowed.iter().map(|b| vertex_key(view, z0, b.1)));
        self.borrowed_at.clear();
        self.borrowed_at
            .extend(borrowed.iter().enumerate().map(|(at, b)| (b.0, at as u32)));
        self.own.resize(own.len(), 0);
        self.own
            .par_chunks_mut(RUN)
            .zip(own.par_chunks(RUN))
            .for_each(|(keys, points)| key_run(view, z0, points, keys));
        Keyed {
            first,
            own,
            own_keys: &self.own,
            borrowed,
            borrowed_keys: &self.borrowed,
            borrowed_at: &self.borrowed_at,
        }
    }
}

impl Keyed<'_> {
    /// Vertex `id`'s model position and key, if the chunk has it.
    #[inline(always)]
    pub fn corner(&self, id: u32) -> Option<([f32; 3], u32)> {
        match id.checked_sub(self.first) {
            Some(own) => {
                let own = own as usize;
                Some((*self.own.get(own)?, *self.own_keys.get(own)?))
            }
            None => {
                let at = *self.borrowed_at.get(&id)? as usize;
                Some((self.borrowed[at].1, self.borrowed_keys[at]))
            }
        }
    }

    /// Vertex `id`'s key, if the chunk has it.
    fn key(&self, id: u32) -> Option<u32> {
        match id.checked_sub(self.first) {
            Some(own) => self.own_keys.get(own as usize).copied(),
            None => Some(self.borrowed_keys[*self.borrowed_at.get(&id)? as usize]),
        }
    }

    /// The triangles of `run` (at most [`RUN`]) to look at further, by index in the run, and
    /// how many: those not passed over, and any with a corner the chunk does not have (an
    /// error, for the caller to find). Branch-free for the chunk's own corners, as most
    /// triangles are passed over at random.
    // Not inlined: in a function of its own the loop keeps everything in registers.
    #[inline(never)]
    pub fn look_at(&self, run: &[[u32; 3]]) -> ([u32; RUN], usize) {
        let (first, keys) = (self.first, self.own_keys);
        let own = keys.len().min(u32::MAX as usize) as u32;
        let mut looked_at = [0u32; RUN];
        let mut count = 0;
        for (k, t) in run.iter().enumerate().take(RUN) {
            let [a, b, c] = t.map(|id| id.wrapping_sub(first));
            let look = if a < own && b < own && c < own {
                !passed_over(keys[a as usize], keys[b as usize], keys[c as usize])
            } else {
                match t.map(|id| self.key(id)) {
                    [Some(a), Some(b), Some(c)] => !passed_over(a, b, c),
                    _ => true,
                }
            };
            // `count ≤ k < RUN`: the mask only spares a bounds check.
            looked_at[count % RUN] = k as u32;
            count += usize::from(look);
        }
        (looked_at, count)
    }
}

/// Hashes a vertex id by one multiplication: ids are distinct, and the table reads the
/// hash's high bits, which the multiplication fills.
#[derive(Clone, Copy, Default)]
struct IdHasher;

struct IdHash(u64);

impl std::hash::BuildHasher for IdHasher {
    type Hasher = IdHash;
    fn build_hasher(&self) -> IdHash {
        IdHash(0)
    }
}

impl std::hash::Hasher for IdHash {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01B3);
        }
    }
    fn write_u32(&mut self, id: u32) {
        self.0 = u64::from(id).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::raster::Camera;
    use crate::render::xorshift;

    #[test]
    fn a_triangle_passed_over_covers_no_centre_and_meets_no_plane_and_keys_give_its_box() {
        let (size, bbox) = ((120, 90), [[0.0; 3], [1.0; 3]]);
        let camera = Camera::fit([1.0, -1.0, 1.0], [0.0, 0.0, 1.0], bbox, size, 0.9);
        let view = Raster::new(camera, size, [0; 3]);
        let z0 = 0.5;
        let mut random = xorshift(0x2545_f491_4f6c_dd1d);
        let mut unit = || (random() >> 11) as f32 / (1u64 << 53) as f32;
        let (mut passed, mut boxed, rounds) = (0, 0, 200_000);
        for round in 0..rounds {
            // Corners a fraction of a pixel apart (a pixel is ~1/100 of the box here), some
            // exactly on the plane, some far off the panel.
            let centre = [unit(), unit(), if round % 7 == 0 { 0.5 } else { unit() }];
            let spread = [0.002, 0.01, 0.05][round % 3];
            let far = if round % 11 == 0 { 40.0 } else { 1.0 };
            let corners: [[f32; 3]; 3] = std::array::from_fn(|_| {
                std::array::from_fn(|a| {
                    (centre[a] + (unit() - 0.5) * spread) * if a == 0 { far } else { 1.0 }
                })
            });
            let keys = corners.map(|p| vertex_key(&view, z0, p));
            let screen = corners.map(|p| view.screen(p));
            if let Some((cols, rows)) = centres(keys) {
                boxed += 1;
                let some = cols.0 < cols.1 && rows.0 < rows.1;
                assert_eq!(
                    some.then_some((cols, rows)),
                    view.covers(screen),
                    "{corners:?}"
                );
            }
            if passed_over(keys[0], keys[1], keys[2]) {
                passed += 1;
                assert_eq!(view.covers(screen), None, "{corners:?}");
                let above = corners.map(|p| f64::from(p[2]) >= z0);
                assert!(above.iter().all(|&a| a == above[0]), "{corners:?}");
            }
        }
        // Most such triangles are passed over, and most have their box from their keys.
        assert!(passed > rounds / 3, "{passed} of {rounds}");
        assert!(boxed > rounds / 2, "{boxed} of {rounds}");
    }

    #[test]
    fn keys_made_a_block_at_a_time_are_each_points_key() {
        let (size, bbox) = ((64, 48), [[0.0; 3], [1.0; 3]]);
        let camera = Camera::fit([1.0, -1.0, 1.0], [0.0, 0.0, 1.0], bbox, size, 0.9);
        let view = Raster::new(camera, size, [0; 3]);
        let z0 = 0.3f64;
        let just_below = (z0 as f32).next_down();
        let special = [
            0.3,
            z0 as f32,
            just_below,
            0.0,
            -0.0,
            1e30,
            -1e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut next = xorshift(0x853c_49e6_748f_ea9b);
        let points: Vec<[f32; 3]> = (0..5000)
            .map(|_| {
                std::array::from_fn(|_| match next() % 4 {
                    0 => special[(next() % special.len() as u64) as usize],
                    _ => (next() % 10_000) as f32 / 8000.0 - 0.1,
                })
            })
            .collect();
        for z0 in [z0, f64::NAN, 1e300, -1e300] {
            let mut keys = vec![0; points.len()];
            key_run(&view, z0, &points, &mut keys);
            for (p, key) in points.iter().zip(keys) {
                assert_eq!(key, vertex_key(&view, z0, *p), "{p:?} at z0 = {z0}");
            }
        }
    }

    #[test]
    fn a_cell_past_the_key_is_no_cell() {
        let key = pass_key([Some(NO_CELL + 3), Some(5)], true);
        assert_eq!(key & 0x7fff, NO_CELL);
        assert_eq!(key >> 16 & 0x7fff, 5);
        // Two such corners agree on nothing across.
        assert!(!passed_over(key, key ^ 1 << 16, key ^ 1 << 17));
        assert!(passed_over(key, key, key));
    }
}
