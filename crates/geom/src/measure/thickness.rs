//! Local thickness of one phase (solid or void) of a voxelised mesh, with sub-voxel ridges.
//!
//! The local thickness at a point is the diameter of the largest ball that lies in the phase
//! and contains the point (Hildebrand and Rüegsegger 1997). Here the points are the phase's
//! voxel centres and the balls are centred on the phase's ridge (medial surface), found
//! between voxels and sized from the mesh's tangent planes, not from voxel distances: a
//! voxel answer is quantised to about one voxel (a slab whose mid-plane falls between
//! samples reads `W − Δ`).
//!
//! Method and invariants:
//! 1. Feature transform ([`super::edt`], given): each phase voxel's nearest voxel of the
//!    other phase (its grid feature), which always borders the phase, so it has a
//!    [`Patch`]: the mesh's nearest point to it and that triangle's normal (the caller's
//!    `patches`). A point's distance to the surface is its height over its feature's
//!    tangent plane: exact for planes, and for curved walls off by the square of the angle
//!    between the true and the grid direction (about `(Δ/D)²/2` at depth `D`).
//! 2. Ridge candidates: phase voxels with a 6-neighbour whose grid feature lies on a wall
//!    facing theirs (the vectors from feature to voxel make an obtuse angle: the two sides
//!    of a wall or pore), and voxels whose grid distance is a local maximum (the centre of
//!    a ball or strut, where features scatter). From each, the normal `n` of its feature's
//!    plane through the voxel, from the surface point `c` below it, runs to where the line
//!    leaves the phase (marched over the voxels, then crossed with the tangent plane of the
//!    first voxel of the other phase): that chord spans the wall or pore, and its midpoint
//!    is on the ridge — exactly for a slab at any angle, a spherical shell, a cylinder or a
//!    ball, whose normal lines pass through the medial surface, curve or point; to second
//!    order in the voxel's offset elsewhere. The ball centred there takes as radius the
//!    least of half the chord and the centre's own distance (over its own feature's plane,
//!    so a third wall nearer the centre bounds it); it is dropped if its centre falls in the
//!    other phase or the chord leaves the grid. The candidate's own ball (its distance, at
//!    its centre) is a ball too: it fills in where the ridge is not a chord's midpoint (the
//!    bisector where two faces meet).
//! 3. Painting: a phase voxel's thickness is twice the largest radius `R` of the balls whose
//!    centre lies within `R + Δ/2` of it (the ball meets the voxel's inscribed sphere: ridge
//!    points are one per grid edge, so without the half voxel a voxel beside a face, between
//!    two ridge points, could fall between their balls). Planes run in parallel, each taking
//!    the balls that reach it.
//! 4. A voxel no ball reaches (a corner, a blob too small to have a ridge pair) takes its own
//!    ball: twice its distance.
//!
//! Only the boundary voxels' patches touch the mesh (one search of eight bins each), so the
//! cost is linear in the voxels plus the painting.
//!
//! The statistics are over the voxels `counted` accepts; `None` when it accepts none, or the
//! phase has no wall (no voxel of the other phase anywhere: an unbounded pore).

use rayon::prelude::*;

use super::Stats;
use super::edt::{self, NONE};
use super::surface::Patch;
use super::voxel::Grid;
use crate::vec3::{dot, norm, sub};

/// The radius, in voxels, of the disc of tangent plane a boundary voxel's patch stands for.
const DISC: f64 = 0.7;

/// A ball of the phase's ridge: centre and radius, in model units.
#[derive(Clone, Copy, Debug)]
struct Ball {
    centre: [f64; 3],
    radius: f64,
}

/// The tangent planes of a voxelised mesh's boundary voxels (those with a 6-neighbour of
/// the other phase): `slot[i]` indexes `patches`, or is [`NONE`].
pub struct Patches {
    pub slot: Vec<u32>,
    pub patches: Vec<Patch>,
}

/// What the chord and ball steps need of one phase.
struct Phase<'a> {
    grid: &'a Grid,
    inside: &'a [bool],
    phase: bool,
    feature: &'a [u32],
    patches: &'a Patches,
}

impl Phase<'_> {
    /// The distance from `p` to the surface near grid feature `f`, and the unit direction
    /// from the surface to `p`: the least height of `p` over the tangent planes of `f` and
    /// its 6-neighbours (the least, so that near a convex edge the nearer face's plane wins
    /// over a grid feature quantised onto the other face), where `p` is on the phase's side
    /// of a plane; the distance to the patch's point where it is not.
    fn depth(&self, p: [f64; 3], f: u32) -> Option<(f64, [f64; 3])> {
        let mut best: Option<(f64, [f64; 3])> = None;
        for v in self.star(f as usize) {
            let Some(patch) = self.patch(v) else {
                continue;
            };
            // Outward normals point out of the solid: into the void.
            let n = if self.phase {
                patch.normal.map(|c| -c)
            } else {
                patch.normal
            };
            // The patch stands for a disc of its tangent plane round its point: the surface
            // a boundary voxel owns. Its distance is the height over the plane where `p`
            // stands over the disc, and grows towards its rim beyond.
            let away = sub(p, patch.point);
            let h = dot(away, n);
            let found = if h > 0.0 {
                let lateral: [f64; 3] = std::array::from_fn(|a| away[a] - h * n[a]);
                let l = norm(lateral);
                let past = l - DISC * self.grid.spacing;
                if past <= 0.0 {
                    (h, n)
                } else {
                    let to: [f64; 3] = std::array::from_fn(|a| away[a] - lateral[a] * past / l);
                    let d = norm(to);
                    (d, to.map(|c| c / d))
                }
            } else {
                let d = norm(away);
                if d <= 0.0 {
                    continue;
                }
                (d, away.map(|c| c / d))
            };
            if best.is_none_or(|(b, _)| found.0 < b) {
                best = Some(found);
            }
        }
        best
    }

    /// The voxel holding `x`, if in the grid.
    fn voxel(&self, x: [f64; 3]) -> Option<usize> {
        let g = self.grid;
        (0..3).try_fold(0usize, |acc, a| {
            let k = ((x[a] - g.origin[a]) / g.spacing).round();
            (k >= 0.0 && k < g.dims[a] as f64).then(|| {
                let stride: usize = g.dims[..a].iter().product();
                acc + k as usize * stride
            })
        })
    }

    /// The ball on the chord through a voxel at depth `d` along `n` from surface point `c`
    /// (see the module docs, step 2); `None` when the line leaves the grid first or the
    /// centre falls in the other phase.
    fn chord_ball(&self, d: f64, n: [f64; 3], c: [f64; 3]) -> Option<Ball> {
        let h = self.grid.spacing;
        let at = |t: f64| -> [f64; 3] { std::array::from_fn(|a| c[a] + t * n[a]) };
        // March in half steps to the first voxel of the other phase, then cross its plane.
        let mut t = d;
        let mut last = self.voxel(at(t))?;
        let chord = loop {
            t += 0.5 * h;
            let out = self.voxel(at(t))?;
            if self.inside[out] == self.phase {
                last = out;
                continue;
            }
            // The plane of the voxel the line left to, or of the last one inside (a diagonal
            // step can land on a voxel of the other phase that borders none of this one).
            let crossing = [out, last].into_iter().find_map(|v| {
                let patch = self.patch(v)?;
                let facing = dot(n, patch.normal);
                let s = dot(sub(patch.point, c), patch.normal) / facing;
                (facing.abs() > 0.2 && s > t - 2.0 * h && s <= t + h).then_some(s)
            });
            break crossing.unwrap_or(t - 0.25 * h);
        };
        let half = 0.5 * chord;
        let centre = at(half);
        let home = self.voxel(centre)?;
        if self.inside[home] != self.phase {
            return None;
        }
        // The centre's distance from the features of the eight voxels round it: the one
        // voxel it rounds to can have its feature on a face farther from the centre itself.
        let radius = self
            .depth_at(centre, self.cell_round(centre))
            .map_or(half, |(d, _)| half.min(d));
        (radius.is_finite() && radius > 0.0).then_some(Ball { centre, radius })
    }

    /// The least [`Phase::depth`] of `x` over the features of `voxels` (voxels round `x`:
    /// the voxel it rounds to can have its feature on a face farther from `x` than another
    /// face, where grid distances tie to within the quantisation).
    fn depth_at(
        &self,
        x: [f64; 3],
        voxels: impl Iterator<Item = usize>,
    ) -> Option<(f64, [f64; 3])> {
        voxels
            .filter_map(|v| self.depth(x, *self.feature.get(v)?))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// Voxel `i` and its 6-neighbours.
    fn star(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let dims = self.grid.dims;
        let c = edt::coords(dims, i);
        let strides = [1, dims[0], dims[0] * dims[1]];
        std::iter::once(Some(i))
            .chain((0..3).flat_map(move |a| {
                [
                    (c[a] + 1 < dims[a]).then(|| i + strides[a]),
                    (c[a] > 0).then(|| i - strides[a]),
                ]
            }))
            .flatten()
    }

    /// The (up to eight) voxels at the corners of the grid cell holding `x`.
    fn cell_round(&self, x: [f64; 3]) -> impl Iterator<Item = usize> + '_ {
        let g = self.grid;
        let low: [f64; 3] = std::array::from_fn(|a| ((x[a] - g.origin[a]) / g.spacing).floor());
        (0..8).filter_map(move |corner: usize| {
            (0..3).try_fold(0usize, |acc, a| {
                let k = low[a] + ((corner >> a) & 1) as f64;
                (k >= 0.0 && k < g.dims[a] as f64).then(|| {
                    let stride: usize = g.dims[..a].iter().product();
                    acc + k as usize * stride
                })
            })
        })
    }

    fn patch(&self, i: usize) -> Option<&Patch> {
        let slot = *self.patches.slot.get(i)?;
        self.patches.patches.get(slot as usize)
    }
}

/// The local thickness of every voxel of `phase` (`inside[i] == phase`), in model units (0
/// elsewhere); see the module docs. `feature` is the feature transform of the other phase
/// (each voxel's nearest voxel of it).
pub fn local_thickness(
    grid: &Grid,
    inside: &[bool],
    phase: bool,
    patches: &Patches,
    feature: &[u32],
) -> Vec<f32> {
    let n = grid.len();
    if inside.len() != n || feature.len() != n || patches.slot.len() != n {
        return vec![0.0; inside.len()];
    }
    let dims = grid.dims;
    if feature.first().is_none_or(|&f| f == NONE) {
        return vec![0.0; n];
    }
    let this = Phase {
        grid,
        inside,
        phase,
        feature,
        patches,
    };
    let strides = [1, dims[0], dims[0] * dims[1]];
    let plane = dims[0] * dims[1];
    let depth = |i: usize| edt::distance2(dims, i, feature[i] as usize);
    // Whether the grid features of `i` and `j` lie on walls that face each other: the
    // vectors from the features to the voxels make an obtuse angle.
    let facing = |i: usize, j: usize| -> bool {
        let (a, b) = (edt::coords(dims, i), edt::coords(dims, j));
        let (fa, fb) = (
            edt::coords(dims, feature[i] as usize),
            edt::coords(dims, feature[j] as usize),
        );
        let dot: f64 = (0..3)
            .map(|k| (a[k] as f64 - fa[k] as f64) * (b[k] as f64 - fb[k] as f64))
            .sum();
        dot < 0.0
    };
    let candidate = |i: usize| -> bool {
        if inside[i] != phase {
            return false;
        }
        let c = edt::coords(dims, i);
        let own = depth(i);
        let mut peak = true;
        for a in 0..3 {
            for (ok, j) in [
                (c[a] + 1 < dims[a], i.wrapping_add(strides[a])),
                (c[a] > 0, i.wrapping_sub(strides[a])),
            ] {
                if !ok || inside[j] != phase {
                    continue;
                }
                if facing(i, j) {
                    return true;
                }
                peak &= depth(j) <= own;
            }
        }
        peak
    };
    // 2. Ridge balls, per z-plane of candidate voxels.
    let balls: Vec<Ball> = (0..dims[2])
        .into_par_iter()
        .flat_map_iter(|z| {
            let this = &this;
            (z * plane..(z + 1) * plane)
                .filter(|&i| candidate(i))
                .filter_map(move |i| {
                    let p = grid.centre(i);
                    let (d, n) = this.depth_at(p, this.star(i))?;
                    Some((p, d, n))
                })
                .flat_map(move |(p, d, n)| {
                    // The voxel's own ball too: where the ridge is not a chord's midpoint
                    // (the bisector of a slab's rim, where two faces meet), it is what
                    // reaches the voxels near the edge.
                    let own = Ball {
                        centre: p,
                        radius: d,
                    };
                    let c = std::array::from_fn(|a| p[a] - d * n[a]);
                    let chord = this.chord_ball(d, n, c);
                    // A ball inside the chord's adds nothing but painting time.
                    let inner = chord.is_some_and(|b| {
                        let gap: f64 = (0..3).map(|a| (b.centre[a] - p[a]).powi(2)).sum();
                        gap.sqrt() + own.radius <= b.radius
                    });
                    [(!inner).then_some(own), chord]
                })
                .flatten()
                .collect::<Vec<_>>()
        })
        .collect();
    // 3. Painting, plane by plane.
    let mut balls = balls;
    balls.sort_by(|a, b| a.centre[2].total_cmp(&b.centre[2]));
    let reach_max = balls.iter().map(|b| b.radius).fold(0.0, f64::max) + 0.5 * grid.spacing;
    let mut thickness = vec![0.0f32; n];
    let h = grid.spacing;
    thickness
        .par_chunks_mut(plane)
        .enumerate()
        .for_each(|(z, out)| {
            let zc = grid.origin[2] + z as f64 * h;
            let from = balls.partition_point(|b| b.centre[2] < zc - reach_max);
            for ball in balls[from..]
                .iter()
                .take_while(|b| b.centre[2] <= zc + reach_max)
            {
                paint(grid, inside, phase, z, zc, ball, out);
            }
        });
    // 4. Voxels no ball reached.
    thickness
        .par_iter_mut()
        .enumerate()
        .filter(|(i, t)| inside[*i] == phase && **t == 0.0)
        .for_each(|(i, t)| {
            *t = this
                .depth_at(grid.centre(i), this.star(i))
                .map_or(0.0, |(d, _)| (2.0 * d) as f32);
        });
    thickness
}

/// The tangent plane ([`Patch`]) of every voxel with a 6-neighbour of the other phase.
pub fn patches(grid: &Grid, inside: &[bool], surface: &super::surface::Surface) -> Patches {
    let n = grid.len();
    let dims = grid.dims;
    let strides = [1, dims[0], dims[0] * dims[1]];
    let plane = dims[0] * dims[1];
    let border = |i: usize| -> bool {
        let c = edt::coords(dims, i);
        (0..3).any(|a| {
            (c[a] + 1 < dims[a] && inside[i + strides[a]] != inside[i])
                || (c[a] > 0 && inside[i - strides[a]] != inside[i])
        })
    };
    let found: Vec<(usize, Patch)> = (0..dims[2])
        .into_par_iter()
        .flat_map_iter(|z| {
            (z * plane..(z + 1) * plane)
                .filter(|&i| inside.len() == n && border(i))
                .filter_map(|i| Some((i, surface.patch(grid.centre(i), grid.spacing)?)))
                .collect::<Vec<_>>()
        })
        .collect();
    let mut slot = vec![NONE; n];
    let mut patches = Vec::with_capacity(found.len());
    for (i, patch) in found {
        slot[i] = patches.len() as u32;
        patches.push(patch);
    }
    Patches { slot, patches }
}

/// Raises the voxels of plane `z` (at height `zc`) within reach of `ball` to its diameter.
fn paint(
    grid: &Grid,
    inside: &[bool],
    phase: bool,
    z: usize,
    zc: f64,
    ball: &Ball,
    out: &mut [f32],
) {
    let h = grid.spacing;
    let reach = ball.radius + 0.5 * h;
    let dz = zc - ball.centre[2];
    let disc2 = reach * reach - dz * dz;
    if disc2 < 0.0 {
        return;
    }
    let disc = disc2.sqrt();
    let diameter = (2.0 * ball.radius) as f32;
    let [nx, ny, _] = grid.dims;
    let index = |v: f64, a: usize| (v - grid.origin[a]) / h;
    let y0 = index(ball.centre[1] - disc, 1).ceil().max(0.0);
    let y1 = index(ball.centre[1] + disc, 1).floor().min((ny - 1) as f64);
    if y1 < y0 {
        return;
    }
    for y in y0 as usize..=y1 as usize {
        let dy = grid.origin[1] + y as f64 * h - ball.centre[1];
        let row2 = disc2 - dy * dy;
        if row2 < 0.0 {
            continue;
        }
        let row = row2.sqrt();
        let x0 = index(ball.centre[0] - row, 0).ceil().max(0.0);
        let x1 = index(ball.centre[0] + row, 0).floor().min((nx - 1) as f64);
        if x1 < x0 {
            continue;
        }
        let base = nx * y;
        let offset = z * nx * ny + base;
        for x in x0 as usize..=x1 as usize {
            if inside[offset + x] == phase && out[base + x] < diameter {
                out[base + x] = diameter;
            }
        }
    }
}

/// `{min, p05, median, max}` of `values` at the voxels `counted` accepts; `None` for none.
pub fn stats(values: &[f32], counted: impl Fn(usize) -> bool + Sync) -> Option<Stats> {
    let mut v: Vec<f32> = values
        .par_iter()
        .enumerate()
        .filter(|(i, _)| counted(*i))
        .map(|(_, &t)| t)
        .collect();
    if v.is_empty() {
        return None;
    }
    let last = v.len() - 1;
    let mut at = |rank: usize| -> f64 {
        let (_, x, _) = v.select_nth_unstable_by(rank, f32::total_cmp);
        f64::from(*x)
    };
    // Lower ranks first: each selection leaves the ranks above it to the right.
    let min = at(0);
    let p05 = at(last / 20);
    let median = at(last / 2);
    let max = at(last);
    Some(Stats {
        min,
        p05,
        median,
        max,
    })
}
