//! Volume fraction against level: the table `V(level)` of a cell's field, from which a target
//! volume fraction `φ` is turned into the level (or the half wall) that gives it.
//!
//! Invariants:
//! - A [`LevelTable`] holds [`QUANTILES`]` + 1` values `q_0 ≤ … ≤ q_Q` of a sampled quantity
//!   (the field for `inside`/`outside`, `|h|` of the distance field for shells): the fraction
//!   of samples below `q_i` is `i / Q`. Between entries it is linear, so `V` is continuous and
//!   non-decreasing, and [`LevelTable::level_for`] inverts it by bisection over the entries.
//! - Samples are the field at the midpoints of an `n`-per-axis grid over one period (or a
//!   reference element): the midpoint rule for the solid's volume, whose error for a smooth
//!   surface is far below 0.002 at `n = 128`. NaN samples are left out; a table of no sample
//!   is an error, not a table.
//! - Reachable fractions are the open interval `(0, 1)`: the levels below every sample and
//!   above every sample give empty and full solids, which no target asks for.

use rayon::prelude::*;

use crate::contour2d::Element2;
use crate::element::Element3;
use crate::field::{Grid, ScalarField};
use crate::symmetric::{Frame, ReferenceElement};

/// Intervals of the table (entries minus one).
pub const QUANTILES: usize = 4096;

/// The distribution of a sampled quantity, as quantiles.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelTable {
    pub quantiles: Vec<f64>,
}

/// What [`LevelTable::level_for`] solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solved {
    pub level: f64,
    /// Bisection steps over the table.
    pub iterations: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum TableError {
    #[error("the field is not a number at any sample")]
    NoSamples,
    #[error("a volume fraction of {0} cannot be reached: fractions strictly between 0 and 1 can")]
    Unreachable(f64),
}

impl LevelTable {
    /// The table of `samples` (consumed; NaN values dropped).
    pub fn from_samples(mut samples: Vec<f64>) -> Result<LevelTable, TableError> {
        samples.retain(|v| !v.is_nan());
        if samples.is_empty() {
            return Err(TableError::NoSamples);
        }
        samples.sort_unstable_by(f64::total_cmp);
        let last = (samples.len() - 1) as f64;
        // Entry i is the empirical quantile i/Q, interpolated between order statistics.
        let quantiles = (0..=QUANTILES)
            .map(|i| {
                let at = last * i as f64 / QUANTILES as f64;
                let below = at.floor() as usize;
                let above = (below + 1).min(samples.len() - 1);
                let t = at - below as f64;
                samples[below] + t * (samples[above] - samples[below])
            })
            .collect();
        Ok(LevelTable { quantiles })
    }

    /// The fraction of the sampled volume where the quantity is below `level`.
    pub fn fraction_below(&self, level: f64) -> f64 {
        let q = &self.quantiles;
        if level <= q[0] {
            return 0.0;
        }
        if level >= q[QUANTILES] {
            return 1.0;
        }
        // The last entry ≤ level: entries are sorted.
        let i = q.partition_point(|&v| v <= level) - 1;
        let step = q[i + 1] - q[i];
        let t = if step > 0.0 {
            (level - q[i]) / step
        } else {
            0.0
        };
        (i as f64 + t) / QUANTILES as f64
    }

    /// The level below which the fraction `phi` of the volume lies: bisection over the
    /// table's entries for the interval holding `phi`, then the linear piece within it (exact
    /// for the table's `V`, whatever its range: a few `±FAR` samples do not blur it).
    pub fn level_for(&self, phi: f64) -> Result<Solved, TableError> {
        if !(phi > 0.0 && phi < 1.0) {
            return Err(TableError::Unreachable(phi));
        }
        let at = phi * QUANTILES as f64;
        let (mut lo, mut hi) = (0usize, QUANTILES);
        let mut iterations = 0;
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if (mid as f64) <= at {
                lo = mid;
            } else {
                hi = mid;
            }
            iterations += 1;
        }
        let t = at - lo as f64;
        Ok(Solved {
            level: self.quantiles[lo] + t * (self.quantiles[hi] - self.quantiles[lo]),
            iterations,
        })
    }

    /// The level at fraction `phi` read off the table directly (the inverse
    /// [`LevelTable::level_for`] bisects for), with `phi` clamped into the table.
    pub fn level_at(&self, phi: f64) -> f64 {
        let at = if phi.is_nan() {
            0.5
        } else {
            phi.clamp(0.0, 1.0)
        } * QUANTILES as f64;
        let below = (at.floor() as usize).min(QUANTILES - 1);
        let t = at - below as f64;
        self.quantiles[below] + t * (self.quantiles[below + 1] - self.quantiles[below])
    }

    /// The table as bytes: the entries, `f64` little-endian.
    pub fn to_bytes(&self) -> Vec<u8> {
        self.quantiles
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    /// The table from [`LevelTable::to_bytes`]; `None` for bytes of another length.
    pub fn from_bytes(bytes: &[u8]) -> Option<LevelTable> {
        if bytes.len() != 8 * (QUANTILES + 1) {
            return None;
        }
        let quantiles: Vec<f64> = bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect();
        quantiles
            .windows(2)
            .all(|w| w[0] <= w[1])
            .then_some(LevelTable { quantiles })
    }
}

/// Where a table's samples are taken (cell or reference coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Region {
    /// One period `[0, 1)^d` in the frame's coordinates (skew for the hexagonal frame).
    Period { frame: Frame, dimension: usize },
    /// The reference element.
    Element(ReferenceElement),
}

/// Which points of a box belong to a region.
type Keep<'a> = &'a (dyn Fn([f64; 3]) -> bool + Sync);

/// The field at the midpoints of `n` intervals per axis over `region` (NaN kept; the table
/// drops it).
pub fn sample(field: &dyn ScalarField, region: Region, n: usize) -> Vec<f64> {
    let n = n.max(2);
    let step = 1.0 / n as f64;
    let midpoints = |lo: f64, hi: f64| -> (f64, f64) {
        let spacing = (hi - lo) / n as f64;
        (lo + 0.5 * spacing, spacing)
    };
    let (box_lo, box_hi, dimension, keep): ([f64; 3], [f64; 3], usize, Option<Keep>) = match region
    {
        Region::Period {
            frame: Frame::Hexagonal,
            dimension,
        } => {
            // Skew coordinates: evaluated point by point, a row at a time.
            let k_count = if dimension == 3 { n } else { 1 };
            return (0..k_count)
                .into_par_iter()
                .flat_map_iter(|k| {
                    let mut plane = vec![0.0; n * n];
                    let z = if dimension == 3 {
                        (k as f64 + 0.5) * step
                    } else {
                        0.0
                    };
                    for (j, row) in plane.chunks_mut(n).enumerate() {
                        let points: Vec<[f64; 3]> = (0..n)
                            .map(|i| {
                                let s = [(i as f64 + 0.5) * step, (j as f64 + 0.5) * step, z];
                                Frame::Hexagonal.to_cartesian(s)
                            })
                            .collect();
                        let [xs, ys, zs] = std::array::from_fn(|a| {
                            points.iter().map(|p| p[a]).collect::<Vec<f64>>()
                        });
                        field.eval_points(&xs, &ys, &zs, row);
                    }
                    plane
                })
                .collect();
        }
        Region::Period { dimension, .. } => ([0.0; 3], [1.0; 3], dimension, None),
        Region::Element(ReferenceElement::Cube) => ([-0.5; 3], [0.5; 3], 3, None),
        Region::Element(ReferenceElement::Square) => ([-0.5; 3], [0.5; 3], 2, None),
        Region::Element(ReferenceElement::Tetrahedron) => (
            [-0.5; 3],
            [0.5; 3],
            3,
            Some(&|p: [f64; 3]| Element3::Tetrahedron.signed_distance(p) < 0.0),
        ),
        Region::Element(ReferenceElement::Triangle) => {
            let (lo, hi) = Element2::Triangle.bbox();
            (
                [lo[0], lo[1], 0.0],
                [hi[0], hi[1], 0.0],
                2,
                Some(&|p: [f64; 3]| Element2::Triangle.signed_distance([p[0], p[1]]) < 0.0),
            )
        }
    };
    let axes: [(f64, f64); 3] = std::array::from_fn(|a| midpoints(box_lo[a], box_hi[a]));
    let grid = Grid {
        origin: std::array::from_fn(|a| if a < dimension { axes[a].0 } else { 0.0 }),
        spacing: std::array::from_fn(|a| if a < dimension { axes[a].1 } else { 0.0 }),
        counts: std::array::from_fn(|a| if a < dimension { n } else { 1 }),
    };
    let sampler = field.sampler(&grid);
    (0..grid.counts[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut plane = vec![0.0; grid.plane_len()];
            sampler.sample_plane(k, &mut plane);
            match keep {
                None => plane,
                Some(keep) => plane
                    .into_iter()
                    .enumerate()
                    .filter(|&(at, _)| {
                        let (i, j) = (at % n, at / n);
                        keep([grid.coord(0, i), grid.coord(1, j), grid.coord(2, k)])
                    })
                    .map(|(_, v)| v)
                    .collect(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_samples_give_their_own_quantiles_and_invert_exactly() {
        // x at the midpoints of 10_000 cells of [0, 1): V(c) = c.
        let n = 10_000;
        let samples = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
        let table = LevelTable::from_samples(samples).expect("samples");
        for phi in [0.01, 0.2, 0.5, 0.731, 0.99] {
            let solved = table.level_for(phi).expect("reachable");
            assert!((solved.level - phi).abs() < 1e-4, "{phi}: {solved:?}");
            assert!((table.fraction_below(solved.level) - phi).abs() < 1e-9);
            assert_eq!(solved.iterations, 12);
            assert!((table.level_at(phi) - solved.level).abs() < 1e-9);
        }
    }

    #[test]
    fn a_cosine_has_the_arccos_distribution() {
        // f = cos(2πx) over a period: V(c) = 1 − arccos(c)/π.
        let n = 200_000;
        let samples = (0..n)
            .map(|i| (std::f64::consts::TAU * (i as f64 + 0.5) / n as f64).cos())
            .collect();
        let table = LevelTable::from_samples(samples).expect("samples");
        for c in [-0.9f64, -0.3, 0.0, 0.4, 0.8] {
            let exact = 1.0 - c.acos() / std::f64::consts::PI;
            assert!((table.fraction_below(c) - exact).abs() < 1e-3, "{c}");
        }
    }

    /// `f = x + y + z` in cell coordinates.
    struct Sum;

    impl ScalarField for Sum {
        fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
            for (((o, x), y), z) in out.iter_mut().zip(xs).zip(ys).zip(zs) {
                *o = x + y + z;
            }
        }
    }

    #[test]
    fn regions_hold_their_share_of_points_and_their_own_values() {
        let n = 40;
        let period = sample(
            &Sum,
            Region::Period {
                frame: Frame::Cartesian,
                dimension: 3,
            },
            n,
        );
        assert_eq!(period.len(), n * n * n);
        // Mean of x + y + z over [0, 1)³ is 1.5.
        let mean = period.iter().sum::<f64>() / period.len() as f64;
        assert!((mean - 1.5).abs() < 1e-9);
        // The regular tetrahedron of edge √2 fills a third of the unit cube.
        let tet = sample(&Sum, Region::Element(ReferenceElement::Tetrahedron), n);
        let share = tet.len() as f64 / (n * n * n) as f64;
        assert!((share - 1.0 / 3.0).abs() < 0.02, "{share}");
        let triangle = sample(&Sum, Region::Element(ReferenceElement::Triangle), n);
        // The triangle fills half its bounding box.
        assert!((triangle.len() as f64 / (n * n) as f64 - 0.5).abs() < 0.03);
        let rhombus = sample(
            &Sum,
            Region::Period {
                frame: Frame::Hexagonal,
                dimension: 2,
            },
            n,
        );
        assert_eq!(rhombus.len(), n * n);
    }

    #[test]
    fn fractions_outside_the_open_interval_and_empty_tables_are_errors() {
        let table = LevelTable::from_samples(vec![1.0, 2.0, f64::NAN]).expect("two samples");
        for phi in [0.0, 1.0, -0.1, 1.5, f64::NAN] {
            assert!(matches!(
                table.level_for(phi),
                Err(TableError::Unreachable(_))
            ));
        }
        assert_eq!(
            LevelTable::from_samples(vec![f64::NAN]),
            Err(TableError::NoSamples)
        );
        let bytes = table.to_bytes();
        assert_eq!(LevelTable::from_bytes(&bytes), Some(table));
        assert_eq!(LevelTable::from_bytes(&bytes[1..]), None);
    }
}
