//! The face-normal constraint (docs/method.md §Face-normal condition): the smallest change of the
//! coefficients that
//! makes `∇Φ·n = 0` on the faces of the reference element.
//!
//! Conventions and math:
//! - Faces are those of the group's reference element: the square's edges (D4), the cube's
//!   faces (Oh), the tetrahedron's faces `n_i·x = ½` (Td) and the triangle's edges (D3). The
//!   condition is imposed on ONE face; the group carries it to the others
//!   (`∇Φ(Qx)·Qn = ∇Φ(x)·n` for a symmetric `Φ`). Residuals are measured on all of them.
//! - A face is written in the group's frame (skew for D3) as `{s : ℓ·s = c}` with an integer
//!   covector `ℓ` pointing outwards. With the Gram matrix `G = BᵀB` of the frame,
//!   `n·∇ₓΦ = (B⁻¹n)·∇ₛΦ ∝ ν·∇ₛΦ` with `ν ∝ G⁻¹ℓ` (integer here), so the normal derivative
//!   of a plane wave `exp(2πi k·s)` is `2πi (ν·k) exp(2πi k·s)` up to a constant factor.
//! - On the face plane `s = b + A y`, `exp(2πi k·s) = exp(2πi k·b) exp(2πi (Aᵀk)·y)`, and
//!   `Aᵀk = Aᵀk'` iff `k − k'` is a multiple of `ℓ`. So `∂ₙΦ` restricted to the plane is a
//!   trigonometric polynomial in `y` with one coefficient per LINE `{k₀ + tℓ}` of frequency
//!   space, and it vanishes on the plane iff every such coefficient vanishes:
//!   `Σ_f c_f [K_f Σ_{k∈orbit(f) on the line} m_k (ν·k) exp(2πi k·b)] = 0` — one complex row
//!   per line. (`2πi` is dropped: rows may be scaled freely.)
//! - Real part. `Φ = Re Σ c_f φ_f` depends only on the Hermitian part
//!   `c̃_f = ½(c_f + conj c_{partner(f)})`, for which `Σ c̃_f φ_f` is real; the rows are
//!   imposed on `c̃`. For fitted cells (real input) `c̃ = c`. The anti-Hermitian part is
//!   invisible in `Φ` and left alone, which is the least change.
//! - Objective: `min ‖c′ − c‖²` with the HERMITIAN norm (`qᴴq`, conjugate transpose) subject
//!   to `C c̃′ = 0`, i.e. `c′ = c − C⁺C c̃`: remove from `c̃` its component in the row space
//!   of `C`. A plain transpose would project `conj(c)` instead.
//! - Solver: `C` is rank-deficient (rows of lines that a symmetry of the face maps onto each
//!   other are proportional) and, after merging those, has a tail of small singular values
//!   from frequencies near the corner of the band (σ_min/σ_max ≈ 3e-3, 5e-4, 6e-5 at N = 16,
//!   32, 64 for Td), so forming `CCᴴ` (normal / KKT equations) would square that condition
//!   number. An SVD or a complete orthogonal decomposition would do (docs/method.md §Departures);
//!   for Td
//!   those are dense and grow like `N⁷` (8 minutes at N = 64). `row_space.rs` computes the
//!   same projection with LSQR (Golub–Kahan bidiagonalization of `Cᴴ`, the process an SVD
//!   starts with; no normal equations), checked against a dense projection in its tests and
//!   here against an independent SVD at small N.
//! - Size: rows are kept only for one line per orbit of the face's stabiliser
//!   `{Q : Qᵀℓ = ℓ}` (for symmetric `Φ` the others are the same condition times a unit
//!   phase), rows are normalised, and the system is split into connected components of
//!   its row–column graph, each projected on its own. Td rows are real
//!   (`exp(2πi k·b) = ±1` with `b = (½,0,0)`), so the real and imaginary parts of Td
//!   coefficients are projected separately, in parallel.
//! - Structure kept: the projector commutes with the group (the constraint set is
//!   symmetric: it lives in the symmetric basis) and with the conjugate-partner map
//!   `J c = conj(c_partner)` (the constraint set is invariant under it), so conjugate
//!   partners stay conjugate; the correction is symmetrised under `J` afterwards so that holds
//!   to the last bit. Oh and D4 coefficients stay real (their rows all vanish).
//! - For Oh and D4 the faces are mirror planes of the periodic extension, so every row is zero
//!   and nothing happens; the same for mirrored D3 input, whose coefficients already satisfy
//!   the rows. Because `Φ` is a trigonometric polynomial the condition holds on the whole face
//!   plane and its periodic images, which cut through the cell: expect the cell to change
//!   (see [`ConstraintReport::delta_norm`]).
//! - Residuals are in the Cartesian reference frame: `max |∇Φ·n|` with the unit outward
//!   normal, over a [`FACE_SAMPLES`]² grid on every face (barycentric on triangles, bilinear on
//!   squares, `FACE_SAMPLES²` points along an edge in 2D), evaluated from the full coefficient
//!   set (no pruning).

use std::collections::HashMap;

use rayon::prelude::*;
use rustfft::num_complex::Complex64;

use super::basis::{cis_fraction, cis_turns};
use super::fit::{Coefficient, FitError, FittedCell};
use super::group::{Frame, Group, ReferenceElement, TETRAHEDRON_FACE_NORMALS, mat_vec};
use super::row_space::{SparseRows, project};

/// Sample points per face side for the residual (a `FACE_SAMPLES × FACE_SAMPLES` grid).
pub const FACE_SAMPLES: usize = 32;

/// The constraint counts as already satisfied when every normalised row applied to the
/// coefficients, or the computed correction, is at most this times `‖c‖`.
pub const CONSTRAINT_TOLERANCE: f64 = 1e-12;

/// What [`FittedCell::constrain_normal_to_faces`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstraintReport {
    /// Whether the coefficients changed (false when the conditions already held).
    pub applied: bool,
    /// `‖c′ − c‖` (Hermitian norm over all coefficients).
    pub delta_norm: f64,
    /// `max |∇Φ·n|` on all faces after the constraint (Cartesian, unit normals).
    pub max_face_residual: f64,
    /// The same before.
    pub max_face_residual_before: f64,
}

/// One face `{s : ℓ·s = c}` of the reference element, in the group's frame.
#[derive(Clone, Debug)]
struct Face {
    /// Outward integer covector; lines of equal projected frequency run along it.
    ell: [i32; 3],
    /// `c = c_num / den`; also the denominator of `b`.
    c_num: i64,
    den: i64,
    /// A point of the face, `b_num / den`.
    b_num: [i64; 3],
    /// Integer `ν ∝ G⁻¹ℓ`: `n·∇ₓΦ = nu_scale · ν·∇ₛΦ`.
    nu: [i32; 3],
    nu_scale: f64,
    /// An axis with `|ℓ_a| = 1`: a line's canonical point has `k_a = 0`.
    pivot: usize,
    /// Cartesian vertices: 2 (edge), 3 (triangle) or 4 (square, in cyclic order).
    vertices: Vec<[f64; 3]>,
}

impl Face {
    fn new(
        frame: Frame,
        ell: [i32; 3],
        (c_num, den): (i64, i64),
        b_num: [i64; 3],
        vertices: Vec<[f64; 3]>,
    ) -> Face {
        // ν = 3·G⁻¹ℓ/2 for the hexagonal frame (G⁻¹ = ⅔[[2,−1],[−1,2]]), ℓ for Cartesian.
        let nu = match frame {
            Frame::Cartesian => ell,
            Frame::Hexagonal => [2 * ell[0] - ell[1], 2 * ell[1] - ell[0], ell[2]],
        };
        let n = unit(frame.gradient_to_cartesian(ell.map(f64::from)));
        let bn = frame.from_cartesian(n);
        let nuf = nu.map(f64::from);
        let nu_scale = dot(bn, nuf) / dot(nuf, nuf);
        let pivot = (0..3).find(|&a| ell[a].abs() == 1).unwrap_or(0);
        Face {
            ell,
            c_num,
            den,
            b_num,
            nu,
            nu_scale,
            pivot,
            vertices,
        }
    }

    /// The canonical point `k − tℓ` (with `k_pivot = 0`) of `k`'s line, and `t`.
    #[inline]
    fn line(&self, k: [i32; 3]) -> ([i32; 3], i32) {
        let t = k[self.pivot] * self.ell[self.pivot];
        (std::array::from_fn(|a| k[a] - t * self.ell[a]), t)
    }

    /// `exp(2πi k·b)`, exact for the fractions used here.
    #[inline]
    fn phase(&self, k: [i32; 3]) -> Complex64 {
        let kb: i64 = (0..3).map(|a| i64::from(k[a]) * self.b_num[a]).sum();
        cis_fraction(kb, self.den)
    }

    /// Cartesian sample points on the face.
    fn samples(&self) -> Vec<[f64; 3]> {
        let m = FACE_SAMPLES.max(2);
        let step = 1.0 / (m - 1) as f64;
        let v = &self.vertices;
        let lerp = |a: [f64; 3], b: [f64; 3], t: f64| -> [f64; 3] {
            std::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
        };
        let mut out = Vec::new();
        match v.len() {
            2 => {
                let mm = m * m;
                for i in 0..mm {
                    out.push(lerp(v[0], v[1], i as f64 / (mm - 1) as f64));
                }
            }
            3 => {
                for i in 0..m {
                    for j in 0..m - i {
                        let (u, w) = (i as f64 * step, j as f64 * step);
                        out.push(std::array::from_fn(|a| {
                            v[0][a] + u * (v[1][a] - v[0][a]) + w * (v[2][a] - v[0][a])
                        }));
                    }
                }
            }
            _ => {
                for i in 0..m {
                    for j in 0..m {
                        let (u, w) = (i as f64 * step, j as f64 * step);
                        out.push(lerp(lerp(v[0], v[1], u), lerp(v[3], v[2], u), w));
                    }
                }
            }
        }
        out
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|v| v / l)
}

/// Every face of the reference element; face 0 carries the constraint.
fn faces(group: &Group) -> Result<Vec<Face>, FitError> {
    let frame = group.frame();
    let Some(element) = group.reference_element() else {
        return Err(FitError::NoReferenceElement {
            group: group.name().to_string(),
        });
    };
    let mut out = Vec::new();
    match element {
        ReferenceElement::Square | ReferenceElement::Cube => {
            let d = if element == ReferenceElement::Square {
                2
            } else {
                3
            };
            for a in 0..d {
                for sign in [1, -1] {
                    let mut ell = [0; 3];
                    ell[a] = sign;
                    let mut b_num = [0i64; 3];
                    b_num[a] = i64::from(sign);
                    // The other axes, cycled for a square face's corners in order.
                    let others: Vec<usize> = (0..d).filter(|&o| o != a).collect();
                    let corner = |u: f64, w: f64| {
                        let mut x = [0.0; 3];
                        x[a] = 0.5 * f64::from(sign);
                        x[others[0]] = u;
                        if let Some(&o) = others.get(1) {
                            x[o] = w;
                        }
                        x
                    };
                    let vertices = if d == 2 {
                        vec![corner(-0.5, 0.0), corner(0.5, 0.0)]
                    } else {
                        vec![
                            corner(-0.5, -0.5),
                            corner(0.5, -0.5),
                            corner(0.5, 0.5),
                            corner(-0.5, 0.5),
                        ]
                    };
                    out.push(Face::new(frame, ell, (1, 2), b_num, vertices));
                }
            }
        }
        ReferenceElement::Tetrahedron => {
            let v = element.vertices();
            for (i, n) in TETRAHEDRON_FACE_NORMALS.iter().enumerate() {
                let ell = n.map(|x| x as i32);
                // b = (n_x/2, 0, 0): n·b = ½, and exp(2πi k·b) = (±1)^k_x is real.
                let b_num = [i64::from(ell[0]), 0, 0];
                let vertices = (0..4).filter(|&j| j != i).map(|j| v[j]).collect();
                out.push(Face::new(frame, ell, (1, 2), b_num, vertices));
            }
        }
        ReferenceElement::Triangle => {
            // Skew coordinates: T = {s1 ≥ -⅓, s2 ≥ -⅓, s1 + s2 ≤ ⅓}.
            let sv = [
                [-1.0 / 3.0, -1.0 / 3.0],
                [2.0 / 3.0, -1.0 / 3.0],
                [-1.0 / 3.0, 2.0 / 3.0],
            ];
            let cart = |i: usize| frame.to_cartesian([sv[i][0], sv[i][1], 0.0]);
            let edges: [([i32; 3], [i64; 3], [usize; 2]); 3] = [
                ([1, 1, 0], [1, 0, 0], [1, 2]),
                ([-1, 0, 0], [-1, 0, 0], [0, 2]),
                ([0, -1, 0], [0, -1, 0], [0, 1]),
            ];
            for (ell, b_num, [p, q]) in edges {
                out.push(Face::new(frame, ell, (1, 3), b_num, vec![cart(p), cart(q)]));
            }
        }
    }
    Ok(out)
}

/// Plane waves `(k, w_k)` of `Φ = Re Σ w_k exp(2πi k·s)`, from the full coefficient set.
fn plane_waves(group: &Group, coefficients: &[Coefficient]) -> Vec<([i32; 3], Complex64)> {
    coefficients
        .par_iter()
        .flat_map_iter(|c| {
            group
                .basis_terms(c.f)
                .into_iter()
                .map(move |(k, w)| (k, c.c * w))
        })
        .collect()
}

/// `max |∇Φ·n|` over the sample points of one face: `∂ₙΦ` restricted to the face plane is
/// summed line by line (`exp(2πi k·s) = exp(2πi k₀·s)·exp(2πi t c)` on the plane), then
/// evaluated at each point with per-axis tables.
fn face_residual(face: &Face, frame: Frame, waves: &[([i32; 3], Complex64)]) -> f64 {
    let mut lines: HashMap<[i32; 3], Complex64> = HashMap::new();
    for &(k, w) in waves {
        let nk: i32 = (0..3).map(|a| face.nu[a] * k[a]).sum();
        if nk == 0 {
            continue;
        }
        let (k0, t) = face.line(k);
        let e = cis_fraction(i64::from(t) * face.c_num, face.den);
        *lines.entry(k0).or_default() += w * e * f64::from(nk);
    }
    // In a fixed order: the sum below must not follow the map's per-process random order.
    let mut lines: Vec<([i32; 3], Complex64)> = lines.into_iter().collect();
    lines.sort_unstable_by_key(|&(k, _)| k);
    let kmax = lines
        .iter()
        .flat_map(|(k, _)| k.iter().map(|v| v.unsigned_abs() as usize))
        .max()
        .unwrap_or(0);
    let scale = std::f64::consts::TAU * face.nu_scale;
    face.samples()
        .par_iter()
        .map(|&x| {
            let s = frame.from_cartesian(x);
            // tables[a][m + kmax] = exp(2πi m s_a)
            let tables: Vec<Vec<Complex64>> = (0..3)
                .map(|a| {
                    (0..=2 * kmax)
                        .map(|m| cis_turns((m as f64 - kmax as f64) * s[a]))
                        .collect()
                })
                .collect();
            let mut sum = Complex64::new(0.0, 0.0);
            for &(k, a) in &lines {
                let e = tables[0][(k[0] + kmax as i32) as usize]
                    * tables[1][(k[1] + kmax as i32) as usize]
                    * tables[2][(k[2] + kmax as i32) as usize];
                sum += a * e;
            }
            // Re(2πi z) = −2π Im z.
            (scale * sum.im).abs()
        })
        .reduce(|| 0.0, f64::max)
}

impl FittedCell {
    /// `max |∇Φ·n|` over a [`FACE_SAMPLES`]² grid on every face of the reference element,
    /// Cartesian reference frame, unit outward normals, from the full coefficient set.
    pub fn max_face_normal_derivative(&self) -> Result<f64, FitError> {
        let faces = faces(&self.group)?;
        let waves = plane_waves(&self.group, &self.coefficients);
        let frame = self.group.frame();
        Ok(faces
            .iter()
            .map(|f| face_residual(f, frame, &waves))
            .fold(0.0, f64::max))
    }

    /// The face-normal constraint of docs/method.md §Face-normal condition (see the module docs):
    /// the cell with the
    /// least Hermitian change `‖c′ − c‖` such that `∇Φ·n = 0` on the faces of the
    /// reference element, and a report. Returns the cell unchanged (`applied == false`) when
    /// the conditions already hold (D4, Oh, mirrored D3).
    ///
    /// Errors: the group has no reference element; the projection did not converge.
    pub fn constrain_normal_to_faces(&self) -> Result<(FittedCell, ConstraintReport), FitError> {
        let group = &self.group;
        let faces = faces(group)?;
        let before = self.max_face_normal_derivative()?;
        let unchanged = |residual: f64| {
            Ok((
                self.clone(),
                ConstraintReport {
                    applied: false,
                    delta_norm: 0.0,
                    max_face_residual: residual,
                    max_face_residual_before: residual,
                },
            ))
        };

        // Unknowns: the coefficients and their conjugate partners (which carry the Hermitian
        // part of c when a cell was built without them).
        let mut fs: Vec<[i32; 3]> = self.coefficients.iter().map(|c| c.f).collect();
        fs.extend(self.coefficients.iter().map(|c| group.partner(c.f)));
        fs.sort_unstable();
        fs.dedup();
        let col: HashMap<[i32; 3], usize> = fs.iter().enumerate().map(|(i, &f)| (f, i)).collect();
        let c: Vec<Complex64> = fs.iter().map(|&f| self.coefficient(f)).collect();
        let partner: Vec<usize> = fs.iter().map(|&f| col[&group.partner(f)]).collect();
        // Hermitian part c̃ = (c + Jc)/2.
        let herm: Vec<Complex64> = (0..fs.len())
            .map(|j| (c[j] + c[partner[j]].conj()) * 0.5)
            .collect();
        let c_norm = norm(&c);

        let rows = build_rows(group, &faces[0], &fs);
        if rows.is_empty() {
            return unchanged(before);
        }
        let herm_norm = norm(&herm);
        let worst = rows
            .iter()
            .map(|r| {
                r.iter()
                    .map(|&(j, v)| v * herm[j])
                    .sum::<Complex64>()
                    .norm()
            })
            .fold(0.0, f64::max);
        if worst <= CONSTRAINT_TOLERANCE * herm_norm {
            return unchanged(before);
        }

        // Row-space component of c̃, component by component.
        let mut delta = vec![Complex64::new(0.0, 0.0); fs.len()];
        for (rs, cs) in components(&rows, fs.len()) {
            project_block(&rows, &rs, &cs, &herm, &mut delta)?;
        }
        // Exact-arithmetic no-op (the projector commutes with J); removes rounding so that
        // conjugate partners stay conjugate to the last bit.
        let delta: Vec<Complex64> = (0..fs.len())
            .map(|j| (delta[j] + delta[partner[j]].conj()) * 0.5)
            .collect();
        let delta_norm = norm(&delta);
        if delta_norm <= CONSTRAINT_TOLERANCE * c_norm {
            return unchanged(before);
        }
        let coefficients: Vec<Coefficient> = fs
            .iter()
            .zip(c.iter().zip(&delta))
            .filter(|(f, (cj, dj))| {
                // Keep every original coefficient; add partners only where they became
                // non-zero.
                *cj != *dj || self.coefficients.binary_search_by_key(*f, |x| x.f).is_ok()
            })
            .map(|(&f, (&cj, &dj))| Coefficient {
                f,
                c: cj - dj,
                k_f: group.normalization(f),
            })
            .collect();
        let cell = FittedCell::new_unchecked(group.clone(), self.n, coefficients);
        let after = cell.max_face_normal_derivative()?;
        Ok((
            cell,
            ConstraintReport {
                applied: true,
                delta_norm,
                max_face_residual: after,
                max_face_residual_before: before,
            },
        ))
    }
}

fn norm(v: &[Complex64]) -> f64 {
    v.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt()
}

/// Sparse, unit-norm rows `(column, value)` of the constraint on `face`, one per line of
/// frequency space that is canonical under the face's stabiliser; zero rows dropped.
fn build_rows(group: &Group, face: &Face, fs: &[[i32; 3]]) -> Vec<Vec<(usize, Complex64)>> {
    let stab: Vec<_> = group
        .transposes()
        .iter()
        .filter(|t| mat_vec(t, face.ell) == face.ell)
        .copied()
        .collect();
    // Canonical line: the smallest canonical point over the stabiliser's images. The other
    // lines of the orbit give the same condition times a unit phase (module docs).
    let canonical = |k: [i32; 3]| -> bool {
        let (k0, _) = face.line(k);
        stab.iter().all(|t| face.line(mat_vec(t, k)).0 >= k0)
    };
    let entries: Vec<([i32; 3], usize, Complex64, f64)> = fs
        .par_iter()
        .enumerate()
        .flat_map_iter(|(j, &f)| {
            group
                .basis_terms(f)
                .into_iter()
                .filter_map(move |(k, w)| {
                    let nk: i32 = (0..3).map(|a| face.nu[a] * k[a]).sum();
                    if nk == 0 || !canonical(k) {
                        return None;
                    }
                    let v = face.phase(k) * (w * f64::from(nk));
                    Some((face.line(k).0, j, v, v.norm()))
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let mut row_of: HashMap<[i32; 3], usize> = HashMap::new();
    let mut acc: Vec<HashMap<usize, (Complex64, f64)>> = Vec::new();
    for (k0, j, v, a) in entries {
        let r = *row_of.entry(k0).or_insert_with(|| {
            acc.push(HashMap::new());
            acc.len() - 1
        });
        let e = acc[r].entry(j).or_default();
        e.0 += v;
        e.1 += a;
    }
    let mut rows = Vec::new();
    for row in acc {
        // Entries that cancel to rounding (Oh, D4: ±k pairs) are zero.
        let mut r: Vec<(usize, Complex64)> = row
            .into_iter()
            .filter(|(_, (v, a))| v.norm() > 64.0 * f64::EPSILON * a)
            .map(|(j, (v, _))| (j, v))
            .collect();
        if r.is_empty() {
            continue;
        }
        r.sort_by_key(|e| e.0);
        let l = r.iter().map(|e| e.1.norm_sqr()).sum::<f64>().sqrt();
        for e in &mut r {
            e.1 /= l;
        }
        rows.push(r);
    }
    rows
}

/// Connected components of the bipartite row–column graph: `(rows, columns)` each.
fn components(rows: &[Vec<(usize, Complex64)>], ncols: usize) -> Vec<(Vec<usize>, Vec<usize>)> {
    let mut parent: Vec<usize> = (0..ncols).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for r in rows {
        let a = find(&mut parent, r[0].0);
        for &(j, _) in &r[1..] {
            let b = find(&mut parent, j);
            if a != b {
                parent[b] = a;
            }
        }
    }
    let mut by_root: HashMap<usize, (Vec<usize>, Vec<usize>)> = HashMap::new();
    for (i, r) in rows.iter().enumerate() {
        let root = find(&mut parent, r[0].0);
        by_root.entry(root).or_default().0.push(i);
    }
    for j in 0..ncols {
        let root = find(&mut parent, j);
        if let Some(e) = by_root.get_mut(&root) {
            e.1.push(j);
        }
    }
    let mut out: Vec<_> = by_root.into_values().collect();
    out.sort();
    out
}

/// Adds to `delta` the projection of `x` onto the row space of the block (`rs` × `cs`).
fn project_block(
    rows: &[Vec<(usize, Complex64)>],
    rs: &[usize],
    cs: &[usize],
    x: &[Complex64],
    delta: &mut [Complex64],
) -> Result<(), FitError> {
    let local: HashMap<usize, usize> = cs.iter().enumerate().map(|(i, &j)| (j, i)).collect();
    let block_rows: Vec<Vec<(usize, Complex64)>> = rs
        .iter()
        .map(|&r| rows[r].iter().map(|&(j, v)| (local[&j], v)).collect())
        .collect();
    let c = SparseRows::new(block_rows.iter().map(Vec::as_slice), cs.len());
    let xs: Vec<Complex64> = cs.iter().map(|&j| x[j]).collect();
    let p = project(&c, &xs).map_err(|e| FitError::ConstraintNotConverged {
        rows: e.rows,
        cols: e.cols,
        relative: e.relative,
    })?;
    for (i, &j) in cs.iter().enumerate() {
        delta[j] += p[i];
    }
    Ok(())
}
