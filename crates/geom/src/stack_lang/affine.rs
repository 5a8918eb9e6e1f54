//! Affine maps of points, `q = M p + t`: the point transformations of the language composed
//! from the root of a tree down to each leaf, and the rotation matrices of eq. 5 and `orient`.
//!
//! Conventions: a transformation node evaluates its child at `T(x)` (eq. 2–5), so the map
//! from world coordinates to a leaf's own coordinates is the composition of the `T`s on the
//! path, outermost first: `leaf = T_leafward ∘ … ∘ T_root`.
//!
//! Invariants:
//! - Rotation matrices are built from the unit axis by Rodrigues' formula, and entries smaller
//!   than [`SNAP`] are set to exactly 0, so quarter turns (`orient 1,0,0`, `rotate 0,0,1 pi/2`)
//!   give exact signed permutations; that keeps axis-aligned leaves separable.
//! - Images of boxes are computed by interval arithmetic and contain every image point; an
//!   infinite side times an exact zero entry contributes nothing, never NaN.

use super::bounds::Aabb;

/// Matrix entries of a rotation below this magnitude are taken to be exactly 0: they come
/// from `cos(π/2)` evaluated at the nearest double to π/2, not from a meant angle.
pub const SNAP: f64 = 1e-15;

/// `q = m p + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    pub m: [[f64; 3]; 3],
    pub t: [f64; 3],
}

impl Affine {
    pub const IDENTITY: Affine = Affine {
        m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        t: [0.0; 3],
    };

    pub fn linear(m: [[f64; 3]; 3]) -> Affine {
        Affine { m, t: [0.0; 3] }
    }

    pub fn translation(t: [f64; 3]) -> Affine {
        Affine {
            m: Affine::IDENTITY.m,
            t,
        }
    }

    pub fn diagonal(d: [f64; 3]) -> Affine {
        let mut m = [[0.0; 3]; 3];
        for (a, row) in m.iter_mut().enumerate() {
            row[a] = d[a];
        }
        Affine::linear(m)
    }

    /// `self ∘ inner`: first `inner`, then `self`.
    pub fn after(&self, inner: &Affine) -> Affine {
        let m = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| self.m[i][k] * inner.m[k][j]).sum())
        });
        let t = std::array::from_fn(|i| {
            self.t[i] + (0..3).map(|j| self.m[i][j] * inner.t[j]).sum::<f64>()
        });
        Affine { m, t }
    }

    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| {
            self.m[i][0] * p[0] + self.m[i][1] * p[1] + self.m[i][2] * p[2] + self.t[i]
        })
    }

    pub fn transpose_linear(&self) -> Affine {
        Affine::linear(std::array::from_fn(|i| {
            std::array::from_fn(|j| self.m[j][i])
        }))
    }

    pub fn is_identity(&self) -> bool {
        *self == Affine::IDENTITY
    }

    /// A box containing the image of `b`.
    pub fn image(&self, b: &Aabb) -> Aabb {
        if b.is_empty() {
            return *b;
        }
        let mut out = Aabb {
            min: self.t,
            max: self.t,
        };
        for i in 0..3 {
            for j in 0..3 {
                let c = self.m[i][j];
                if c == 0.0 {
                    continue;
                }
                let (lo, hi) = if c > 0.0 {
                    (c * b.min[j], c * b.max[j])
                } else {
                    (c * b.max[j], c * b.min[j])
                };
                out.min[i] += lo;
                out.max[i] += hi;
            }
        }
        out
    }

    /// Rodrigues' rotation matrix `R = cos θ I + sin θ [v]× + (1 − cos θ) v vᵀ` about the unit
    /// vector along `axis` (eq. 5). `axis` must not be zero.
    pub fn rotation(axis: [f64; 3], angle: f64) -> Affine {
        let v = unit(axis);
        let (s, c) = angle.sin_cos();
        let cross = [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]];
        let m = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let identity = if i == j { c } else { 0.0 };
                snap(identity + s * cross[i][j] + (1.0 - c) * v[i] * v[j])
            })
        });
        Affine::linear(m)
    }

    /// The rotation taking e3 to the direction of `v`: about `e3 × v` by `arccos(v3/|v|)`.
    /// `v` must not lie on the negative z half-axis (where `e3 × v = 0` and the angle is π).
    pub fn turning_z_to(v: [f64; 3]) -> Affine {
        let u = unit(v);
        if u[0] == 0.0 && u[1] == 0.0 {
            return Affine::IDENTITY;
        }
        let angle = u[2].clamp(-1.0, 1.0).acos();
        Affine::rotation([-u[1], u[0], 0.0], angle)
    }
}

/// `v / |v|`, with the norm computed without overflow or underflow.
pub fn unit(v: [f64; 3]) -> [f64; 3] {
    let scale = v.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let w = v.map(|c| c / scale);
    let norm = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    w.map(|c| c / norm)
}

fn snap(x: f64) -> f64 {
    if x.abs() < SNAP { 0.0 } else { x }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12)
    }

    #[test]
    fn rodrigues_matches_the_right_hand_rule_on_points() {
        // R about z by +90° takes x to y.
        let r = Affine::rotation([0.0, 0.0, 2.0], FRAC_PI_2);
        assert_eq!(r.apply([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]);
        let r = Affine::rotation([1.0, 1.0, 1.0], 2.0 * PI / 3.0);
        assert!(close(r.apply([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]));
        // Orthogonal: Rᵀ R = I.
        let p = r.transpose_linear().after(&r);
        for i in 0..3 {
            assert!(close(p.m[i], Affine::IDENTITY.m[i]));
        }
    }

    #[test]
    fn turning_z_takes_e3_to_the_direction() {
        for v in [
            [1.0, 0.0, 0.0],
            [1.0, 2.0, 3.0],
            [0.0, -1.0, -5.0],
            [0.0, 0.0, 4.0],
        ] {
            let q = Affine::turning_z_to(v).apply([0.0, 0.0, 1.0]);
            assert!(close(q, unit(v)), "{v:?} → {q:?}");
        }
        // A quarter turn snaps to an exact signed permutation.
        assert_eq!(
            Affine::turning_z_to([1.0, 0.0, 0.0]).m,
            [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]
        );
    }

    #[test]
    fn images_of_boxes_contain_images_of_points() {
        let a =
            Affine::rotation([1.0, 2.0, 0.5], 0.7).after(&Affine::translation([1.0, -2.0, 0.0]));
        let b = Aabb {
            min: [-1.0, 0.0, 2.0],
            max: [0.5, 3.0, 2.5],
        };
        let image = a.image(&b);
        for corner in 0..8 {
            let p = std::array::from_fn(|i| {
                if corner >> i & 1 == 0 {
                    b.min[i]
                } else {
                    b.max[i]
                }
            });
            let q = a.apply(p);
            assert!((0..3).all(|i| image.min[i] <= q[i] + 1e-12 && q[i] <= image.max[i] + 1e-12));
        }
        // Infinite sides and zero entries.
        let image = Affine::turning_z_to([1.0, 0.0, 0.0]).image(&Aabb {
            min: [-1.0, -1.0, f64::NEG_INFINITY],
            max: [1.0, 1.0, f64::INFINITY],
        });
        assert_eq!(image.min, [f64::NEG_INFINITY, -1.0, -1.0]);
        assert_eq!(image.max, [f64::INFINITY, 1.0, 1.0]);
    }
}
