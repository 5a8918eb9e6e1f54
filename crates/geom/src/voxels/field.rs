//! [`VoxelField`]: an image's samples at voxel centres, interpolated trilinearly with period 1.
//!
//! Invariants: voxel `i` of `n` along an axis sits at `(i + ½)/n − ½`; between the last centre
//! and the first one of the next period the field interpolates across the cell face, so it
//! repeats with period 1 and is continuous everywhere; at a voxel centre it is the voxel's
//! value exactly.

use crate::field::ScalarField;

/// Samples at voxel centres over the cell `[-½, ½]³`, repeated with period 1.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelField {
    shape: [usize; 3],
    /// `values[(k · ny + j) · nx + i]`.
    values: Vec<f64>,
}

impl VoxelField {
    /// `values.len()` must be the product of `shape`, each at least 1.
    pub fn new(shape: [usize; 3], values: Vec<f64>) -> VoxelField {
        debug_assert_eq!(values.len(), shape.iter().product::<usize>());
        VoxelField { shape, values }
    }

    pub fn shape(&self) -> [usize; 3] {
        self.shape
    }

    /// The sample of voxel `(i, j, k)`.
    pub fn sample(&self, voxel: [usize; 3]) -> f64 {
        let [nx, ny, _] = self.shape;
        self.values[(voxel[2] * ny + voxel[1]) * nx + voxel[0]]
    }

    /// The value at a point of cell coordinates.
    pub fn value(&self, p: [f64; 3]) -> f64 {
        // Per axis: the two voxels around `p` (wrapped) and the weight of the second.
        let axis = |a: usize| -> (usize, usize, f64) {
            let n = self.shape[a];
            let u = (p[a] + 0.5) * n as f64 - 0.5;
            let floor = u.floor();
            let t = u - floor;
            let lo = (floor as i64).rem_euclid(n as i64) as usize;
            (lo, (lo + 1) % n, t)
        };
        let (x0, x1, tx) = axis(0);
        let (y0, y1, ty) = axis(1);
        let (z0, z1, tz) = axis(2);
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let row = |y: usize, z: usize| lerp(self.sample([x0, y, z]), self.sample([x1, y, z]), tx);
        let plane = |z: usize| lerp(row(y0, z), row(y1, z), ty);
        lerp(plane(z0), plane(z1), tz)
    }
}

impl ScalarField for VoxelField {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (n, v) in out.iter_mut().enumerate() {
            *v = self.value([xs[n], ys[n], zs[n]]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A field linear in each coordinate within a period is reproduced exactly by trilinear
    /// interpolation between centres (away from the wrap), equals the samples at centres, and
    /// repeats with period 1.
    #[test]
    fn trilinear_between_centres_exact_at_centres_and_periodic() {
        let shape = [4, 5, 6];
        let centre = |a: usize, i: usize| (i as f64 + 0.5) / shape[a] as f64 - 0.5;
        let f = |x: f64, y: f64, z: f64| 1.0 + 2.0 * x - 3.0 * y + 0.5 * z + x * y * z;
        let mut values = Vec::new();
        for k in 0..6 {
            for j in 0..5 {
                for i in 0..4 {
                    values.push(f(centre(0, i), centre(1, j), centre(2, k)));
                }
            }
        }
        let field = VoxelField::new(shape, values);
        for (i, j, k) in [(0, 0, 0), (3, 4, 5), (1, 2, 3)] {
            let p = [centre(0, i), centre(1, j), centre(2, k)];
            assert!((field.value(p) - field.sample([i, j, k])).abs() < 1e-12);
        }
        for p in [[0.1, -0.2, 0.3], [-0.3, 0.3, -0.25], [0.2, 0.0, 0.0]] {
            let want = f(p[0], p[1], p[2]);
            assert!((field.value(p) - want).abs() < 1e-12, "{p:?}");
            let shifted = field.value([p[0] + 1.0, p[1] - 2.0, p[2] + 3.0]);
            assert!((shifted - field.value(p)).abs() < 1e-12);
        }
        // On the +x face, halfway between the last centre and the first (wrapped).
        let face = field.value([0.5, centre(1, 2), centre(2, 3)]);
        let half = 0.5 * (field.sample([3, 2, 3]) + field.sample([0, 2, 3]));
        assert!((face - half).abs() < 1e-12);
        assert!((face - field.value([-0.5, centre(1, 2), centre(2, 3)])).abs() < 1e-12);
    }
}
