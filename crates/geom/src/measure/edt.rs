//! Exact Euclidean feature transform of a 3D grid: for every voxel, the nearest seed voxel.
//!
//! Invariants:
//! - Layout: voxel `(x, y, z)` of a grid of `dims = [nx, ny, nz]` is at `x + nx·(y + ny·z)`.
//! - The result holds, per voxel, the index of a seed at the least Euclidean distance (in
//!   voxel units, exact: squared distances are integers well inside `f64`'s exact range), or
//!   [`NONE`] when the grid has no seed. Ties go to either seed; the distance is exact.
//!
//! Method: Felzenszwalb and Huttenlocher's lower envelope of parabolas, applied per axis
//! (x, then y, then z). After the passes over the axes before `a`, a voxel's feature is the
//! nearest seed among those that share its coordinates on the axes not yet passed, so along a
//! line of axis `a` the distance to the seed found at line point `k` is `d²(k) + (i − k)²`: a
//! 1D distance transform of the values `d²(k)`. Linear time per line; lines run in parallel.

use rayon::prelude::*;

/// No seed anywhere (an empty seed set).
pub const NONE: u32 = u32::MAX;

/// The coordinates of voxel `index`.
#[inline]
pub fn coords(dims: [usize; 3], index: usize) -> [usize; 3] {
    let x = index % dims[0];
    let rest = index / dims[0];
    [x, rest % dims[1], rest / dims[1]]
}

/// The squared distance, in voxel units, between voxels `a` and `b`.
#[inline]
pub fn distance2(dims: [usize; 3], a: usize, b: usize) -> f64 {
    let (p, q) = (coords(dims, a), coords(dims, b));
    (0..3).map(|k| (p[k] as f64 - q[k] as f64).powi(2)).sum()
}

/// The nearest seed of every voxel (see the module docs). `seed.len()` must be the grid's
/// voxel count; a mismatched slice gives all [`NONE`] rather than a panic.
pub fn feature_transform(dims: [usize; 3], seed: &[bool]) -> Vec<u32> {
    let n = dims[0] * dims[1] * dims[2];
    if seed.len() != n || n == 0 || n >= NONE as usize {
        return vec![NONE; seed.len()];
    }
    let mut feature: Vec<u32> = seed
        .iter()
        .enumerate()
        .map(|(i, &s)| if s { i as u32 } else { NONE })
        .collect();
    let [nx, ny, nz] = dims;
    // x: contiguous rows.
    feature
        .par_chunks_mut(nx)
        .enumerate()
        .for_each(|(row, line)| {
            let mut work = Work::new(nx);
            let at = |i: usize| row * nx + i;
            pass_line(dims, line.len(), &at, |i| line[i], &mut work);
            for (i, slot) in line.iter_mut().enumerate() {
                *slot = work.result[i];
            }
        });
    // y: lines inside one z-plane; planes in parallel.
    feature
        .par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(z, plane)| {
            let mut work = Work::new(ny);
            for x in 0..nx {
                let at = |i: usize| x + nx * (i + ny * z);
                pass_line(dims, ny, &at, |i| plane[x + nx * i], &mut work);
                for i in 0..ny {
                    plane[x + nx * i] = work.result[i];
                }
            }
        });
    // z: lines cross every plane, so each y-slab of lines is computed into its own buffer
    // (x-major) and copied back; safe code at the cost of one transient copy.
    let old = &feature;
    let slabs: Vec<Vec<u32>> = (0..ny)
        .into_par_iter()
        .map(|y| {
            let mut work = Work::new(nz);
            let mut out = vec![NONE; nx * nz];
            for x in 0..nx {
                let at = |i: usize| x + nx * (y + ny * i);
                pass_line(dims, nz, &at, |i| old[at(i)], &mut work);
                out[x * nz..(x + 1) * nz].copy_from_slice(&work.result[..nz]);
            }
            out
        })
        .collect();
    for (y, slab) in slabs.iter().enumerate() {
        for x in 0..nx {
            for z in 0..nz {
                feature[x + nx * (y + ny * z)] = slab[x * nz + z];
            }
        }
    }
    feature
}

/// Scratch space for one line, reused along a pass.
struct Work {
    value: Vec<f64>,
    vertex: Vec<usize>,
    bound: Vec<f64>,
    result: Vec<u32>,
}

impl Work {
    fn new(len: usize) -> Work {
        Work {
            value: vec![0.0; len],
            vertex: vec![0; len],
            bound: vec![0.0; len + 1],
            result: vec![NONE; len],
        }
    }
}

/// One line of a pass: `at(i)` is the grid index of line point `i`, `feature(i)` its current
/// feature. Leaves the new features in `work.result[..len]`.
fn pass_line(
    dims: [usize; 3],
    len: usize,
    at: &dyn Fn(usize) -> usize,
    feature: impl Fn(usize) -> u32,
    work: &mut Work,
) {
    for i in 0..len {
        let f = feature(i);
        work.value[i] = if f == NONE {
            f64::INFINITY
        } else {
            distance2(dims, at(i), f as usize)
        };
    }
    let chosen = lower_envelope(&work.value[..len], &mut work.vertex, &mut work.bound);
    for i in 0..len {
        work.result[i] = match chosen {
            true => feature(work.vertex[i]),
            false => NONE,
        };
    }
}

/// The 1D distance transform of `f` (infinite where there is no seed): overwrites
/// `vertex[i]` with the line point `k` minimising `f(k) + (i − k)²`. Returns false when every
/// `f` is infinite (nothing to choose).
fn lower_envelope(f: &[f64], vertex: &mut [usize], bound: &mut [f64]) -> bool {
    let n = f.len();
    let Some(first) = f.iter().position(|v| v.is_finite()) else {
        return false;
    };
    // The envelope: parabolas `hull[0..=k]`, parabola `j` lowest on `[z[j], z[j+1])`.
    let mut hull: Vec<usize> = Vec::with_capacity(n);
    hull.push(first);
    bound[0] = f64::NEG_INFINITY;
    bound[1] = f64::INFINITY;
    for q in first + 1..n {
        if !f[q].is_finite() {
            continue;
        }
        let qf = q as f64;
        loop {
            let k = hull.len() - 1;
            let p = hull[k];
            let pf = p as f64;
            // Where the parabolas of `p` and `q` meet.
            let s = ((f[q] + qf * qf) - (f[p] + pf * pf)) / (2.0 * (qf - pf));
            if s <= bound[k] && k > 0 {
                hull.pop();
                continue;
            }
            hull.push(q);
            bound[k + 1] = s;
            bound[k + 2] = f64::INFINITY;
            break;
        }
    }
    let mut k = 0;
    for (i, slot) in vertex.iter_mut().enumerate().take(n) {
        while bound[k + 1] < i as f64 {
            k += 1;
        }
        *slot = hull[k];
    }
    true
}
