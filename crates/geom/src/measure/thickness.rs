//! Local thickness of one phase (solid or void) of a voxelised mesh, with sub-voxel ridges.
//!
//! The local thickness at a point is the diameter of the largest ball that lies in the phase
//! and contains the point (Hildebrand and Rüegsegger 1997). Here the points are the phase's
//! voxel centres and the balls are centred on the phase's ridge (medial surface), found
//! between voxels and sized from the mesh itself, not from voxel distances: a voxel answer
//! is quantised to about one voxel (a slab whose mid-plane falls between samples reads
//! `W − Δ`).
//!
//! Method and invariants:
//! 1. Feature transform ([`super::edt`]): each phase voxel's nearest voxel of the other
//!    phase (its grid feature).
//! 2. Ridge candidates: phase voxels with a 6-neighbour whose grid feature lies on a wall
//!    facing theirs (the vectors from feature to voxel make an obtuse angle: the two sides
//!    of a wall or pore), and voxels whose grid
//!    distance is a local maximum (the centre of a ball or strut, where features scatter).
//!    For each, the exact nearest mesh point `c` ([`Surface::nearest`], hinted at the grid
//!    feature) gives the normal `n` from the surface through the voxel; the chord from `c`
//!    along `n` to where the line leaves the phase (marched over the voxels, then the exact
//!    crossing among the triangles there) spans the wall or pore, and its midpoint is on
//!    the ridge — exactly for a slab at any angle, a spherical shell, a cylinder or a ball,
//!    whose normal lines pass through the medial surface, curve or point; to second order
//!    in the voxel's offset elsewhere. The ball centred there, with its exact distance to
//!    the mesh as radius, lies in the phase whatever the shape (it is dropped if its centre
//!    falls in the other phase, or the chord leaves the grid).
//!    The candidate's own ball (its exact distance, at its centre) is a ball too: it fills
//!    in where the ridge is not a chord's midpoint (the bisector where two faces meet).
//! 3. Painting: a phase voxel's thickness is twice the largest radius `R` of the balls whose
//!    centre lies within `R + Δ/2` of it (the ball meets the voxel's inscribed sphere: ridge
//!    points are one per grid edge, so without the half voxel a voxel beside a face, between
//!    two ridge points, could fall between their balls). Planes run in parallel, each taking
//!    the balls that reach it.
//! 4. A voxel no ball reaches (a corner, a blob too small to have a ridge pair) takes its own
//!    ball: twice its exact distance to the mesh.
//!
//! The statistics are over the voxels `counted` accepts; `None` when it accepts none, or the
//! phase has no wall (no voxel of the other phase anywhere: an unbounded pore).

use rayon::prelude::*;

use super::Stats;
use super::edt::{self, NONE};
use super::surface::Surface;
use super::voxel::Grid;

/// A ball of the phase's ridge: centre and radius, in model units.
#[derive(Clone, Copy, Debug)]
struct Ball {
    centre: [f64; 3],
    radius: f64,
}

/// The local thickness of every voxel of `phase` (`inside[i] == phase`), in model units (0
/// elsewhere); see the module docs.
pub fn local_thickness(grid: &Grid, inside: &[bool], phase: bool, surface: &Surface) -> Vec<f32> {
    let n = grid.len();
    if inside.len() != n {
        return vec![0.0; inside.len()];
    }
    let dims = grid.dims;
    let seeds: Vec<bool> = inside.iter().map(|&s| s != phase).collect();
    let feature = edt::feature_transform(dims, &seeds);
    drop(seeds);
    if feature.first().is_none_or(|&f| f == NONE) {
        return vec![0.0; n];
    }
    let strides = [1, dims[0], dims[0] * dims[1]];
    // Exact distance and direction for a voxel, hinted at its grid feature.
    let exact = |i: usize| -> Option<(f64, [f64; 3], [f64; 3])> {
        let p = grid.centre(i);
        // The segment to the nearest voxel of the other phase crosses the mesh.
        let upper = edt::distance2(dims, i, feature[i] as usize).sqrt() * grid.spacing;
        let hint = grid.centre(feature[i] as usize);
        let (d, c) = surface.nearest(p, upper * (1.0 + 1e-9), Some(hint))?;
        (d > 0.0).then(|| (d, std::array::from_fn(|a| (p[a] - c[a]) / d), c))
    };
    // 2. Ridge balls, per z-plane of candidate voxels.
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
    let balls: Vec<Ball> = (0..dims[2])
        .into_par_iter()
        .flat_map_iter(|z| {
            (z * plane..(z + 1) * plane)
                .filter(|&i| candidate(i))
                .filter_map(|i| Some((grid.centre(i), exact(i)?)))
                .flat_map(|(p, e)| {
                    // The voxel's own ball too: where the ridge is not a chord's midpoint
                    // (the bisector of a slab's rim, where two faces meet), it is what
                    // reaches the voxels near the edge.
                    let own = Ball {
                        centre: p,
                        radius: e.0,
                    };
                    let chord = chord_ball(grid, inside, phase, surface, e);
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
            *t = exact(i).map_or(0.0, |(d, _, _)| (2.0 * d) as f32);
        });
    thickness
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

/// The ball on the chord through voxel `i` (see the module docs, step 2): from the nearest
/// mesh point `c` along the normal `n` (from the surface through the voxel, which lies at
/// `c + D·n`) to where the line leaves the phase, centred halfway, with its exact distance
/// to the mesh as radius, so it never leaves the phase whatever the shape. `None` when the
/// line leaves the grid first (an unbounded pore) or the centre falls in the other phase.
fn chord_ball(
    grid: &Grid,
    inside: &[bool],
    phase: bool,
    surface: &Surface,
    (d, n, c): (f64, [f64; 3], [f64; 3]),
) -> Option<Ball> {
    let h = grid.spacing;
    let voxel = |x: [f64; 3]| -> Option<usize> {
        (0..3).try_fold(0usize, |acc, a| {
            let k = ((x[a] - grid.origin[a]) / h).round();
            (k >= 0.0 && k < grid.dims[a] as f64).then(|| {
                let stride: usize = grid.dims[..a].iter().product();
                acc + k as usize * stride
            })
        })
    };
    let at = |t: f64| -> [f64; 3] { std::array::from_fn(|a| c[a] + t * n[a]) };
    // March from the voxel in half steps to the first voxel of the other phase, then find
    // the crossing among the triangles there.
    let mut t = d;
    let chord = loop {
        t += 0.5 * h;
        let x = at(t);
        if inside[voxel(x)?] != phase {
            break surface
                .hit_near(c, n, x, 0.01 * h)
                .filter(|&hit| hit <= t + 2.0 * h)
                .unwrap_or(t - 0.25 * h);
        }
    };
    let centre = at(0.5 * chord);
    let home = voxel(centre)?;
    if inside[home] != phase {
        return None;
    }
    // Both ends of the chord are on the mesh, so no ball there is wider than half of it.
    let half = 0.5 * chord;
    // (The far end is an estimate when no triangle was found where the march left the
    // phase, so the search reaches a voxel further.)
    let radius = surface
        .nearest(centre, half + grid.spacing, Some(c))?
        .0
        .min(half);
    (radius.is_finite() && radius > 0.0).then_some(Ball { centre, radius })
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
