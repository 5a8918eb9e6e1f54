//! The periodic surface (PS) model of Wang's loci-surface paper (eq. 2):
//!
//! ```text
//! ψ(r) = Σ_t μ_t cos(2π κ_t (p_t · r)),   r = [x, y, z, 1],  p_t = [a, b, c, θ]
//! ```
//!
//! one term per (moment μ, scale κ, basis vector p); the constant is the term with
//! `p = [0, 0, 0, 0]`. Coordinates are cell coordinates (fractional for crystals): with integer
//! `a, b, c` the model has period 1 on every axis, like the TPMS library.
//!
//! Invariants:
//! - Transforms act on the basis vectors only (Lemmas 2–4): for a point map `r ↦ T r` the
//!   transformed model is `ψ(T⁻¹ r)`, obtained by `p ↦ T⁻ᵀ p`; moments and scales never change.
//! - The Chebyshev form (eq. 4) regroups the same terms by basis vector,
//!   `ψ = c + Σ_m Σ_κ μ_κm T_κ(s_m)` with `s_m = cos(2π p_m · r)`: it exists exactly when every
//!   scale is a natural number, and then equals the cosine form to rounding
//!   (`T_κ(cos φ) = cos κφ`).
//! - Evaluation at points and on grids uses the same terms; the grid sampler factors every
//!   term over the axes (`cos(α+β+γ) = Re e^{iα} e^{iβ} e^{iγ}`) from exact per-axis tables,
//!   so a plane's values are a pure function of its index and agree with direct evaluation to
//!   rounding.

use std::f64::consts::TAU;
use std::ops::Range;

use crate::field::{Grid, PlaneSampler, ScalarField};

/// One term `μ cos(2π κ (p · r))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PsTerm {
    pub moment: f64,
    pub scale: f64,
    /// `[a, b, c, θ]`: the basis plane `a x + b y + c z + θ w = 0`.
    pub vector: [f64; 4],
}

impl PsTerm {
    /// The phase `2π κ (p · r)` at `(x, y, z)`, in radians.
    #[inline]
    pub fn phase(&self, x: f64, y: f64, z: f64) -> f64 {
        let [a, b, c, theta] = self.vector;
        TAU * self.scale * (a * x + b * y + c * z + theta)
    }

    /// Whether the term is the constant (a zero direction): `μ cos(2π κ θ)`.
    pub fn is_constant(&self) -> bool {
        self.vector[..3].iter().all(|&v| v == 0.0)
    }
}

/// A PS model: a sum of terms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PsModel {
    pub terms: Vec<PsTerm>,
}

impl PsModel {
    pub fn new(terms: Vec<PsTerm>) -> PsModel {
        PsModel { terms }
    }

    /// ψ at one point.
    pub fn value(&self, p: [f64; 3]) -> f64 {
        self.terms
            .iter()
            .map(|t| t.moment * t.phase(p[0], p[1], p[2]).cos())
            .sum()
    }

    /// ψ and ∇ψ at one point.
    pub fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let mut value = 0.0;
        let mut gradient = [0.0; 3];
        for t in &self.terms {
            let (sin, cos) = t.phase(p[0], p[1], p[2]).sin_cos();
            value += t.moment * cos;
            let d = -t.moment * TAU * t.scale * sin;
            for (g, v) in gradient.iter_mut().zip(&t.vector[..3]) {
                *g += d * v;
            }
        }
        (value, gradient)
    }

    /// ψ, ∇ψ and the Hessian at one point (for refining maxima).
    pub fn value_gradient_hessian(&self, p: [f64; 3]) -> (f64, [f64; 3], [[f64; 3]; 3]) {
        let (value, gradient) = self.value_gradient(p);
        let mut hessian = [[0.0; 3]; 3];
        for t in &self.terms {
            let w = TAU * t.scale;
            let d = -t.moment * w * w * t.phase(p[0], p[1], p[2]).cos();
            for (i, row) in hessian.iter_mut().enumerate() {
                for (j, h) in row.iter_mut().enumerate() {
                    *h += d * t.vector[i] * t.vector[j];
                }
            }
        }
        (value, gradient, hessian)
    }

    /// The model of the point map `r ↦ T r` with `T = [linear | translation]`: its value at
    /// `r` is this model's value at `T⁻¹ r`. `None` when `linear` is singular.
    pub fn transformed(&self, linear: [[f64; 3]; 3], translation: [f64; 3]) -> Option<PsModel> {
        let inverse = invert3(linear)?;
        // T⁻¹ = [L⁻¹ | −L⁻¹ t]; p' = T⁻ᵀ p, so (a', b', c') = L⁻ᵀ (a, b, c) and
        // θ' = θ + (−L⁻¹ t) · (a, b, c).
        let shift: [f64; 3] =
            std::array::from_fn(|i| -(0..3).map(|j| inverse[i][j] * translation[j]).sum::<f64>());
        let terms = self
            .terms
            .iter()
            .map(|t| {
                let [a, b, c, theta] = t.vector;
                let abc = [a, b, c];
                let mut vector = [0.0; 4];
                for (j, v) in vector.iter_mut().take(3).enumerate() {
                    *v = (0..3).map(|i| inverse[i][j] * abc[i]).sum();
                }
                vector[3] = theta + (0..3).map(|i| shift[i] * abc[i]).sum::<f64>();
                PsTerm { vector, ..*t }
            })
            .collect();
        Some(PsModel { terms })
    }

    /// Rotated by the orthogonal matrix `rotation` about the origin (Lemma 2).
    pub fn rotated(&self, rotation: [[f64; 3]; 3]) -> Option<PsModel> {
        self.transformed(rotation, [0.0; 3])
    }

    /// Translated by `t` (Lemma 3: only the phases change).
    pub fn translated(&self, t: [f64; 3]) -> PsModel {
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        self.transformed(identity, t)
            .unwrap_or_else(|| self.clone())
    }

    /// Scaled by `s` per axis about the origin (Lemma 4); `None` for a zero factor.
    pub fn scaled(&self, s: [f64; 3]) -> Option<PsModel> {
        self.transformed(
            [[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]],
            [0.0; 3],
        )
    }

    /// Reflected in the plane through the origin with normal `n` (Lemma 4); `None` for `n = 0`.
    pub fn reflected(&self, n: [f64; 3]) -> Option<PsModel> {
        let len2: f64 = n.iter().map(|v| v * v).sum();
        if len2 <= 0.0 || !len2.is_finite() {
            return None;
        }
        let h: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| f64::from(u8::from(i == j)) - 2.0 * n[i] * n[j] / len2)
        });
        self.transformed(h, [0.0; 3])
    }

    /// The model with every moment multiplied by `factor`.
    pub fn times(&self, factor: f64) -> PsModel {
        PsModel {
            terms: self
                .terms
                .iter()
                .map(|t| PsTerm {
                    moment: t.moment * factor,
                    ..*t
                })
                .collect(),
        }
    }
}

/// The largest scale the Chebyshev form takes (its polynomials' degree).
pub const CHEBYSHEV_MAX_DEGREE: usize = 1024;

/// The Chebyshev (polynomial in cosines) form of a model, eq. 4.
#[derive(Clone, Debug, PartialEq)]
pub struct ChebyshevForm {
    /// The constant terms summed (`μ cos(2π κ θ)` for each zero direction).
    pub constant: f64,
    /// One polynomial per distinct basis vector, in the order of first appearance.
    pub planes: Vec<ChebyshevPlane>,
}

/// `Σ_κ coefficients[κ] T_κ(s)` in `s = cos(2π p · r)`.
#[derive(Clone, Debug, PartialEq)]
pub struct ChebyshevPlane {
    /// `p = [a, b, c, θ]`.
    pub vector: [f64; 4],
    /// By degree: `coefficients[κ]` multiplies `T_κ` (`coefficients[0]` is 0).
    pub coefficients: Vec<f64>,
}

impl PsModel {
    /// The Chebyshev form, or `None` when a scale is not a natural number up to
    /// [`CHEBYSHEV_MAX_DEGREE`] (the form is defined for natural scales only).
    pub fn chebyshev(&self) -> Option<ChebyshevForm> {
        let mut form = ChebyshevForm {
            constant: 0.0,
            planes: Vec::new(),
        };
        for t in &self.terms {
            if t.is_constant() {
                form.constant += t.moment * (TAU * t.scale * t.vector[3]).cos();
                continue;
            }
            let degree = t.scale;
            if !(degree >= 1.0 && degree.fract() == 0.0 && degree <= CHEBYSHEV_MAX_DEGREE as f64) {
                return None;
            }
            let degree = degree as usize;
            let index = match form.planes.iter().position(|p| p.vector == t.vector) {
                Some(i) => i,
                None => {
                    form.planes.push(ChebyshevPlane {
                        vector: t.vector,
                        coefficients: vec![0.0],
                    });
                    form.planes.len() - 1
                }
            };
            let c = &mut form.planes[index].coefficients;
            if c.len() <= degree {
                c.resize(degree + 1, 0.0);
            }
            c[degree] += t.moment;
        }
        Some(form)
    }
}

impl ChebyshevForm {
    /// ψ at one point: each `s_m`, then its polynomial by Clenshaw's recurrence.
    pub fn value(&self, p: [f64; 3]) -> f64 {
        self.constant
            + self
                .planes
                .iter()
                .map(|plane| {
                    let [a, b, c, theta] = plane.vector;
                    let s = (TAU * (a * p[0] + b * p[1] + c * p[2] + theta)).cos();
                    clenshaw(&plane.coefficients, s)
                })
                .sum::<f64>()
    }
}

/// `Σ c[k] T_k(s)` by Clenshaw's recurrence `b_k = c_k + 2 s b_{k+1} − b_{k+2}`.
fn clenshaw(c: &[f64], s: f64) -> f64 {
    let (mut b1, mut b2) = (0.0, 0.0);
    for &ck in c.iter().skip(1).rev() {
        let b0 = ck + 2.0 * s * b1 - b2;
        b2 = b1;
        b1 = b0;
    }
    c.first().copied().unwrap_or(0.0) + s * b1 - b2
}

fn invert3(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let cof =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let det = m[0][0] * cof(1, 2, 1, 2) - m[0][1] * cof(1, 2, 0, 2) + m[0][2] * cof(1, 2, 0, 1);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let adj = [
        [cof(1, 2, 1, 2), -cof(0, 2, 1, 2), cof(0, 1, 1, 2)],
        [-cof(1, 2, 0, 2), cof(0, 2, 0, 2), -cof(0, 1, 0, 2)],
        [cof(1, 2, 0, 1), -cof(0, 2, 0, 1), cof(0, 1, 0, 1)],
    ];
    Some(adj.map(|row| row.map(|v| v / det)))
}

impl ScalarField for PsModel {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (n, o) in out.iter_mut().enumerate() {
            *o = self.value([xs[n], ys[n], zs[n]]);
        }
    }

    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        Box::new(PsSampler::new(self, grid))
    }
}

/// Per-axis tables `e^{i 2π κ a x_i}` (x), `e^{i 2π κ b y_j}` (y) and `μ e^{i 2π κ (c z_k + θ)}`
/// (z) for every term: a sample is `Re Σ_t X_t[i] Y_t[j] Z_t[k]`, two products per term and no
/// transcendental function.
pub struct PsSampler {
    grid: Grid,
    terms: usize,
    /// `(re, im)` per `[axis table][index * terms + t]`.
    x: Vec<(f64, f64)>,
    y: Vec<(f64, f64)>,
    z: Vec<(f64, f64)>,
}

impl PsSampler {
    pub fn new(model: &PsModel, grid: &Grid) -> PsSampler {
        let terms = model.terms.len();
        let table = |axis: usize, weight: &dyn Fn(&PsTerm) -> (f64, f64)| {
            let mut out = Vec::with_capacity(grid.counts[axis] * terms);
            for i in 0..grid.counts[axis] {
                let s = grid.coord(axis, i);
                for t in &model.terms {
                    let (sin, cos) = (TAU * t.scale * t.vector[axis] * s).sin_cos();
                    let (wr, wi) = weight(t);
                    out.push((wr * cos - wi * sin, wr * sin + wi * cos));
                }
            }
            out
        };
        let one = |_: &PsTerm| (1.0, 0.0);
        let z_weight = |t: &PsTerm| {
            let (sin, cos) = (TAU * t.scale * t.vector[3]).sin_cos();
            (t.moment * cos, t.moment * sin)
        };
        PsSampler {
            grid: *grid,
            terms,
            x: table(0, &one),
            y: table(1, &one),
            z: table(2, &z_weight),
        }
    }
}

impl PlaneSampler for PsSampler {
    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn sample_rows(&self, k: usize, rows: Range<usize>, out: &mut [f64]) {
        let (nx, n) = (self.grid.counts[0], self.terms);
        let z = &self.z[k * n..(k + 1) * n];
        let mut w = vec![(0.0, 0.0); n];
        for (j, row) in rows.zip(out.chunks_mut(nx)) {
            let y = &self.y[j * n..(j + 1) * n];
            for ((w, &(yr, yi)), &(zr, zi)) in w.iter_mut().zip(y).zip(z) {
                *w = (yr * zr - yi * zi, yr * zi + yi * zr);
            }
            for (i, o) in row.iter_mut().enumerate() {
                let x = &self.x[i * n..(i + 1) * n];
                *o = x
                    .iter()
                    .zip(&w)
                    .map(|(&(xr, xi), &(wr, wi))| xr * wr - xi * wi)
                    .sum();
            }
        }
    }
}

/// The 13 directions of the paper's eq. (3): 3 axes, 6 face diagonals, 4 body diagonals, in
/// the paper's order (`x−y`, `z−x`, `y−z`; `x−y+z`, `y+z−x`, `x+y−z`).
pub const DIRECTIONS_13: [[f64; 3]; 13] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 0.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [1.0, -1.0, 0.0],
    [-1.0, 0.0, 1.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, -1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
];

/// A term written the way the paper's tables do: `0.40246 cos(4π(x+y−z))`, `-0.53909`.
pub fn describe_term(t: &PsTerm) -> String {
    if t.is_constant() && t.vector[3] == 0.0 {
        return format!("{:+.6}", t.moment);
    }
    let mut plane = String::new();
    for (v, name) in t.vector[..3].iter().zip(["x", "y", "z"]) {
        if *v == 0.0 {
            continue;
        }
        let sign = if *v < 0.0 {
            "-"
        } else if plane.is_empty() {
            ""
        } else {
            "+"
        };
        let magnitude = v.abs();
        if magnitude == 1.0 {
            plane.push_str(&format!("{sign}{name}"));
        } else {
            plane.push_str(&format!("{sign}{magnitude}{name}"));
        }
    }
    if t.vector[3] != 0.0 {
        plane.push_str(&format!("{:+}", t.vector[3]));
    }
    let factor = 2.0 * t.scale;
    let factor = if factor == 1.0 {
        String::new()
    } else {
        format!("{factor}")
    };
    format!("{:+.6} cos({factor}π({plane}))", t.moment)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> PsModel {
        PsModel::new(vec![
            PsTerm {
                moment: 0.3,
                scale: 1.0,
                vector: [0.0, 0.0, 0.0, 0.0],
            },
            PsTerm {
                moment: -0.7,
                scale: 2.0,
                vector: [1.0, -1.0, 1.0, 0.1],
            },
            PsTerm {
                moment: 0.2,
                scale: 4.0,
                vector: [0.0, 1.0, 1.0, 0.0],
            },
        ])
    }

    #[test]
    fn grid_sampler_matches_direct_evaluation() {
        let m = model();
        let grid = Grid::spanning([-0.3, 0.1, 0.2], [1.1, 0.9, 1.7], [7, 5, 6]);
        let sampler = m.sampler(&grid);
        let mut plane = vec![0.0; grid.plane_len()];
        for k in 0..grid.counts[2] {
            sampler.sample_plane(k, &mut plane);
            for j in 0..grid.counts[1] {
                for i in 0..grid.counts[0] {
                    let p = [grid.coord(0, i), grid.coord(1, j), grid.coord(2, k)];
                    assert!((plane[i + 7 * j] - m.value(p)).abs() < 1e-13);
                }
            }
        }
    }

    #[test]
    fn gradient_matches_central_differences() {
        let m = model();
        let p = [0.21, -0.43, 0.77];
        let (_, g) = m.value_gradient(p);
        let h = 1e-6;
        for a in 0..3 {
            let mut hi = p;
            let mut lo = p;
            hi[a] += h;
            lo[a] -= h;
            let fd = (m.value(hi) - m.value(lo)) / (2.0 * h);
            assert!((fd - g[a]).abs() < 1e-6 * (1.0 + g[a].abs()), "axis {a}");
        }
    }

    /// T_κ(cos φ) = cos κφ: the polynomial form equals the cosine form, here against the
    /// terms summed directly, at points spread over two cells.
    #[test]
    fn chebyshev_form_equals_the_cosine_form() {
        let mut m = model();
        // A second scale on the same plane and a phased constant join existing polynomials.
        m.terms.push(PsTerm {
            moment: 0.35,
            scale: 8.0,
            vector: [1.0, -1.0, 1.0, 0.1],
        });
        m.terms.push(PsTerm {
            moment: 0.5,
            scale: 2.0,
            vector: [0.0, 0.0, 0.0, 0.125],
        });
        let form = m.chebyshev().expect("natural scales");
        assert_eq!(form.planes.len(), 2);
        assert_eq!(form.planes[0].coefficients.len(), 9);
        for i in 0..200 {
            let p = [
                i as f64 * 0.0137,
                (i * 7 % 23) as f64 * 0.087,
                -(i as f64) * 0.0091,
            ];
            let direct: f64 = m
                .terms
                .iter()
                .map(|t| {
                    let [a, b, c, th] = t.vector;
                    t.moment * (TAU * t.scale * (a * p[0] + b * p[1] + c * p[2] + th)).cos()
                })
                .sum();
            assert!((form.value(p) - direct).abs() < 1e-12, "{p:?}");
        }
        m.terms[1].scale = 1.5;
        assert!(m.chebyshev().is_none());
    }

    #[test]
    fn terms_read_like_the_paper() {
        let t = PsTerm {
            moment: 0.40246,
            scale: 2.0,
            vector: [1.0, 1.0, -1.0, 0.0],
        };
        assert_eq!(describe_term(&t), "+0.402460 cos(4π(x+y-z))");
        let c = PsTerm {
            moment: -0.53909,
            scale: 1.0,
            vector: [0.0; 4],
        };
        assert_eq!(describe_term(&c), "-0.539090");
    }
}
