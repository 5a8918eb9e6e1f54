//! Oriented point clouds as cell sources: points with outward normals (a PLY with `nx ny nz`,
//! or text with six columns `x y z nx ny nz`), and the periodic field that tells inside from
//! outside at any point from them.
//!
//! The field at `x` is the inverse-distance-weighted mean, over the [`K`] nearest points `p`,
//! of `(x − p)·n`: each point's tangent plane's signed distance (Hoppe et al., "Surface
//! reconstruction from unorganized points"). The nearest point alone decides near a clean
//! surface, as its weight dominates; several vote where the nearest is ambiguous (near an
//! edge, between two sheets) or has a noisy normal. Negative inside, as every field here.
//!
//! Invariants:
//! - The cloud lies in the cell `[-½, ½]³` and repeats with period 1: neighbours are searched
//!   among the points and their copies shifted by one period, so the field is periodic.
//! - Every point and normal is finite and every normal is non-zero (unit length once read);
//!   an error names the point's index (from 0, in file order).
//! - Nearest neighbours come from a uniform grid of buckets, searched ring by ring until no
//!   unsearched bucket can hold a nearer point: exact, and the same for any thread count.

use thiserror::Error;

use crate::field::ScalarField;
use crate::mesh_read::{self, MeshReadError};

/// How many nearest points vote.
pub const K: usize = 8;

/// Why a point cloud could not be read; the caller names the file.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum PointCloudError {
    #[error(transparent)]
    Ply(#[from] MeshReadError),
    #[error("the PLY vertices have no normals: a point cloud needs `nx`, `ny`, `nz` properties")]
    NoNormals,
    #[error("line {line}: expected 6 numbers `x y z nx ny nz`, found {found}")]
    Columns { line: usize, found: String },
    #[error("point {index} has a zero normal: inside and outside are unknown there")]
    ZeroNormal { index: usize },
    #[error("point {index} has a non-finite coordinate or normal ({value})")]
    NonFinite { index: usize, value: f64 },
    #[error("the file holds no points")]
    Empty,
}

/// Points with unit outward normals.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCloud {
    pub positions: Vec<[f64; 3]>,
    pub normals: Vec<[f64; 3]>,
}

impl PointCloud {
    /// Checks and normalises the normals (see the module's invariants).
    pub fn new(
        positions: Vec<[f64; 3]>,
        mut normals: Vec<[f64; 3]>,
    ) -> Result<PointCloud, PointCloudError> {
        if positions.is_empty() {
            return Err(PointCloudError::Empty);
        }
        for (index, (p, n)) in positions.iter().zip(normals.iter_mut()).enumerate() {
            if let Some(&value) = p.iter().chain(n.iter()).find(|v| !v.is_finite()) {
                return Err(PointCloudError::NonFinite { index, value });
            }
            let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if length == 0.0 || !length.is_finite() {
                return Err(PointCloudError::ZeroNormal { index });
            }
            *n = n.map(|c| c / length);
        }
        Ok(PointCloud { positions, normals })
    }

    /// A PLY file's vertices and their normals.
    pub fn read_ply(bytes: &[u8]) -> Result<PointCloud, PointCloudError> {
        let (positions, normals) = mesh_read::read_ply_vertices(bytes)?;
        if normals.len() != positions.len() {
            return Err(PointCloudError::NoNormals);
        }
        PointCloud::new(positions, normals)
    }

    /// Text of six numbers per line, `x y z nx ny nz` (blank lines and `#` comments skipped).
    pub fn read_xyz(bytes: &[u8]) -> Result<PointCloud, PointCloudError> {
        let text = String::from_utf8_lossy(bytes);
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or_default().trim();
            if line.is_empty() {
                continue;
            }
            let numbers: Vec<f64> = line
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|t| !t.is_empty())
                .map_while(|t| t.parse().ok())
                .collect();
            let fields = line.split(|c: char| c.is_whitespace() || c == ',');
            if numbers.len() != 6 || fields.filter(|t| !t.is_empty()).count() != 6 {
                return Err(PointCloudError::Columns {
                    line: n + 1,
                    found: format!("`{}`", line.chars().take(60).collect::<String>()),
                });
            }
            positions.push([numbers[0], numbers[1], numbers[2]]);
            normals.push([numbers[3], numbers[4], numbers[5]]);
        }
        PointCloud::new(positions, normals)
    }
}

/// The inside/outside field of a cloud repeated with period 1 (see the module's comment).
pub struct PointCloudField {
    /// The points and their copies within [`MARGIN`] of the cell, bucketed.
    points: Vec<([f64; 3], [f64; 3])>,
    /// `starts[b]..starts[b + 1]` are bucket `b`'s points.
    starts: Vec<usize>,
    buckets: usize,
    size: f64,
}

/// How far beyond the cell copies are kept: half a period, so any point of the cell has every
/// point within ½ among them.
const MARGIN: f64 = 0.5;
const LOW: f64 = -0.5 - MARGIN;

impl PointCloudField {
    pub fn new(cloud: &PointCloud) -> PointCloudField {
        let mut copies = Vec::new();
        for (p, n) in cloud.positions.iter().zip(&cloud.normals) {
            // Into the cell first, so a cloud given one period off still lies in it.
            let p = p.map(|c| c - (c + 0.5).floor());
            for shift in 0..27 {
                let d = [shift % 3, shift / 3 % 3, shift / 9].map(|s| s as f64 - 1.0);
                let q = [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
                if q.iter().all(|c| (LOW..=-LOW).contains(c)) {
                    copies.push((q, *n));
                }
            }
        }
        // About two points a bucket.
        let buckets = ((copies.len() as f64 / 2.0).cbrt().floor() as usize).clamp(1, 128);
        let size = (-2.0 * LOW) / buckets as f64;
        let bucket_of = |q: &[f64; 3]| -> usize {
            let index = |c: f64| (((c - LOW) / size) as usize).min(buckets - 1);
            (index(q[2]) * buckets + index(q[1])) * buckets + index(q[0])
        };
        copies.sort_by_key(|(q, _)| bucket_of(q));
        let mut starts = vec![0; buckets * buckets * buckets + 1];
        for (q, _) in &copies {
            starts[bucket_of(q) + 1] += 1;
        }
        for b in 1..starts.len() {
            starts[b] += starts[b - 1];
        }
        PointCloudField {
            points: copies,
            starts,
            buckets,
            size,
        }
    }

    /// The field at `x` (any point: it is wrapped into the cell).
    pub fn value(&self, x: [f64; 3]) -> f64 {
        let x = x.map(|c| c - (c + 0.5).floor());
        let centre = x.map(|c| (((c - LOW) / self.size) as usize).min(self.buckets - 1) as i64);
        // The K nearest so far, as (squared distance, index), sorted.
        let mut best: Vec<(f64, usize)> = Vec::with_capacity(K + 1);
        let last = self.buckets as i64 - 1;
        for ring in 0..=self.buckets as i64 {
            for dz in -ring..=ring {
                for dy in -ring..=ring {
                    for dx in -ring..=ring {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != ring {
                            continue;
                        }
                        let b = [centre[0] + dx, centre[1] + dy, centre[2] + dz];
                        if b.iter().any(|&c| c < 0 || c > last) {
                            continue;
                        }
                        let id = ((b[2] * (last + 1) + b[1]) * (last + 1) + b[0]) as usize;
                        for i in self.starts[id]..self.starts[id + 1] {
                            let q = self.points[i].0;
                            let d2 = (0..3).map(|a| (x[a] - q[a]).powi(2)).sum::<f64>();
                            if best.len() < K || d2 < best[best.len() - 1].0 {
                                let at = best.partition_point(|(e, j)| (*e, *j) < (d2, i));
                                best.insert(at, (d2, i));
                                best.truncate(K);
                            }
                        }
                    }
                }
            }
            // Every unsearched bucket is at least `ring` buckets away.
            let reach = ring as f64 * self.size;
            if best.len() == K && best[K - 1].0 <= reach * reach {
                break;
            }
        }
        let (mut sum, mut weights) = (0.0, 0.0);
        for &(d2, i) in &best {
            let (q, n) = self.points[i];
            let w = 1.0 / (d2.sqrt() + 1e-9);
            sum += w * ((x[0] - q[0]) * n[0] + (x[1] - q[1]) * n[1] + (x[2] - q[2]) * n[2]);
            weights += w;
        }
        sum / weights
    }
}

impl ScalarField for PointCloudField {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (n, v) in out.iter_mut().enumerate() {
            *v = self.value([xs[n], ys[n], zs[n]]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `count` points spread over a sphere (a Fibonacci lattice) with outward normals.
    pub(crate) fn sphere(centre: [f64; 3], radius: f64, count: usize) -> PointCloud {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        for i in 0..count {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
            let r = (1.0 - z * z).sqrt();
            let n = [
                r * (golden * i as f64).cos(),
                r * (golden * i as f64).sin(),
                z,
            ];
            positions.push([0, 1, 2].map(|a| centre[a] + radius * n[a]));
            normals.push(n);
        }
        PointCloud::new(positions, normals).expect("cloud")
    }

    /// Away from the surface (farther than the points' spacing), inside and outside are the
    /// ball's, for a ball crossing the cell's +x face (so its copy's points decide there).
    #[test]
    fn inside_and_outside_are_the_analytic_balls_away_from_the_surface() {
        let (centre, radius) = ([0.3, 0.05, -0.1], 0.3);
        let field = PointCloudField::new(&sphere(centre, radius, 3000));
        let spacing = (4.0 * std::f64::consts::PI * radius * radius / 3000.0).sqrt();
        let mut state = 7u64;
        let mut random = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut checked = 0;
        for _ in 0..4000 {
            let x = [random(), random(), random()];
            let distance = (-1..=1)
                .map(|s| {
                    let d = [
                        x[0] - centre[0] - s as f64,
                        x[1] - centre[1],
                        x[2] - centre[2],
                    ];
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() - radius
                })
                .fold(f64::INFINITY, f64::min);
            if distance.abs() < spacing {
                continue;
            }
            checked += 1;
            let value = field.value(x);
            assert_eq!(value < 0.0, distance < 0.0, "{x:?}: {value} vs {distance}");
            let shifted = field.value([x[0] + 1.0, x[1] - 1.0, x[2]]);
            assert!((shifted - value).abs() < 1e-12);
        }
        assert!(checked > 3000, "{checked}");
    }

    #[test]
    fn bad_points_are_named_by_index() {
        let e = PointCloud::new(vec![[0.0; 3]; 3], vec![[0.0, 0.0, 1.0], [0.0; 3], [1.0; 3]]);
        assert_eq!(e, Err(PointCloudError::ZeroNormal { index: 1 }));
        let e = PointCloud::read_xyz(b"0 0 0 0 0 1\n# note\n\n0 0 0 1 0\n").expect_err("5");
        assert_eq!(
            e.to_string(),
            "line 4: expected 6 numbers `x y z nx ny nz`, found `0 0 0 1 0`"
        );
        let ply = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                    property float z\nend_header\n0 0 0\n1 1 1\n";
        assert_eq!(PointCloud::read_ply(ply), Err(PointCloudError::NoNormals));
        let ply = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
                    property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                    end_header\n0 0 0 0 0 2\n1 1 1 0 0 -1\n";
        let cloud = PointCloud::read_ply(ply).expect("ply");
        assert_eq!(cloud.normals, vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]);
    }
}
