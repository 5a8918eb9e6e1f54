//! Orthogonal projection onto the row space of a sparse complex matrix, for the face-normal
//! constraint (docs/method.md §Face-normal condition): `P x = C⁺C x`, the part of `x` that the
//! least-norm change
//! `x′ = x − P x` with `C x′ = 0` removes.
//!
//! Method and why:
//! - `P x = Cᴴ y` for the least-squares solution `y` of `min ‖Cᴴ y − x‖`; the residual
//!   `r = x − Cᴴ y` is the projected vector. `y` is found by LSQR (Paige & Saunders 1982), i.e.
//!   Golub–Kahan bidiagonalization of `Cᴴ` started from `x` — the same process a dense SVD
//!   begins with, so the condition number is that of `C`, not of `CCᴴ` (no normal equations).
//!   An SVD or a complete orthogonal decomposition would do (docs/method.md §Departures); those are
//!   dense and
//!   cost `O(rows²·cols)`, which for Td grows like `N⁷` (≈ 8 minutes at N = 64), while LSQR
//!   costs a few hundred sparse products (`O(N³)` each). See docs/ARCHITECTURE.md.
//! - `C` is rank-deficient (rows of lines related by a face symmetry are proportional): LSQR
//!   started from `y = 0` stays in the row space of `Cᴴ`'s transpose, and the residual it
//!   converges to is still `x − P x`, whatever the null space.
//! - Steps cost two sparse products; no reorthogonalization (its cost grows with the step
//!   count times the rows, more than the steps it saves on these matrices). Iterations grow
//!   with the condition number: ~600 at N = 64, ~3,500 at N = 128 for Td.
//! - Convergence is checked on the quantity that matters, `‖C r‖` (the constraint violated by
//!   the result), computed exactly at the end; if LSQR's estimate was optimistic, the solve is
//!   restarted from the residual (refinement) a few times before giving up.
//!
//! Invariants: the returned vector is `x − r` with `‖C r‖ ≤ tol·‖C‖_F·‖x‖`, or an error.

use rustfft::num_complex::Complex64;

/// A real sparse matrix in compressed rows, with its transpose (both products are row sweeps).
struct Csr {
    starts: Vec<usize>,
    index: Vec<usize>,
    value: Vec<f64>,
}

impl Csr {
    fn from_triplets(rows: usize, cols: usize, mut t: Vec<(usize, usize, f64)>) -> (Csr, Csr) {
        let build = |t: &[(usize, usize, f64)], rows: usize| {
            let mut starts = vec![0; rows + 1];
            for &(i, _, _) in t {
                starts[i + 1] += 1;
            }
            for i in 0..rows {
                starts[i + 1] += starts[i];
            }
            Csr {
                starts,
                index: t.iter().map(|e| e.1).collect(),
                value: t.iter().map(|e| e.2).collect(),
            }
        };
        t.sort_unstable_by_key(|e| (e.0, e.1));
        let forward = build(&t, rows);
        let mut tt: Vec<(usize, usize, f64)> = t.iter().map(|&(i, j, v)| (j, i, v)).collect();
        tt.sort_unstable_by_key(|e| (e.0, e.1));
        (forward, build(&tt, cols))
    }

    fn rows(&self) -> usize {
        self.starts.len() - 1
    }

    /// `out = M x`.
    fn apply_into(&self, x: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            let r = self.starts[i]..self.starts[i + 1];
            *o = self.index[r.clone()]
                .iter()
                .zip(&self.value[r])
                .map(|(&j, &v)| v * x[j])
                .sum();
        }
    }
}

/// The constraint block `C` (complex, `rows × cols`) as the real matrix that acts on real
/// vectors: `C` itself when every entry is real (the real and imaginary parts of `x` are then
/// projected separately), otherwise the embedding `[[Re C, −Im C], [Im C, Re C]]` acting on
/// `[Re x; Im x]`. The row space of a complex matrix is a complex subspace, so its Hermitian
/// orthogonal projection is the real orthogonal projection onto the embedding's row space.
pub(crate) struct SparseRows {
    rows: usize,
    cols: usize,
    real: bool,
    c: Csr,
    c_t: Csr,
}

impl SparseRows {
    /// Rows given as `(column, value)` lists; every column index must be `< cols`.
    pub(crate) fn new<'a>(
        rows: impl IntoIterator<Item = &'a [(usize, Complex64)]>,
        cols: usize,
    ) -> SparseRows {
        let rows: Vec<&[(usize, Complex64)]> = rows.into_iter().collect();
        let real = rows.iter().all(|r| r.iter().all(|e| e.1.im == 0.0));
        let m = rows.len();
        let mut t = Vec::new();
        for (i, row) in rows.iter().enumerate() {
            for &(j, v) in *row {
                debug_assert!(j < cols);
                t.push((i, j, v.re));
                if !real {
                    t.push((i, j + cols, -v.im));
                    t.push((i + m, j, v.im));
                    t.push((i + m, j + cols, v.re));
                }
            }
        }
        t.retain(|e| e.2 != 0.0);
        let (rr, cc) = if real { (m, cols) } else { (2 * m, 2 * cols) };
        let (c, c_t) = Csr::from_triplets(rr, cc, t);
        SparseRows {
            rows: m,
            cols,
            real,
            c,
            c_t,
        }
    }

    fn frobenius(&self) -> f64 {
        let f = self.c.value.iter().map(|v| v * v).sum::<f64>().sqrt();
        // The embedding holds every entry twice.
        if self.real { f } else { f / 2f64.sqrt() }
    }
}

/// Why a projection failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NotConverged {
    pub rows: usize,
    pub cols: usize,
    /// `‖C r‖ / (‖C‖_F ‖x‖)` reached.
    pub relative: f64,
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|z| z * z).sum::<f64>().sqrt()
}

/// Relative size of `‖C r‖` accepted as converged.
const TOLERANCE: f64 = 1e-15;
/// LSQR restarts from the residual at most this many times.
const REFINEMENTS: usize = 4;

/// `P x`, the orthogonal projection of `x` onto the row space of `c` (see the module docs).
pub(crate) fn project(c: &SparseRows, x: &[Complex64]) -> Result<Vec<Complex64>, NotConverged> {
    let n = c.cols;
    let parts: Vec<Vec<f64>> = if c.real {
        vec![
            x.iter().map(|z| z.re).collect(),
            x.iter().map(|z| z.im).collect(),
        ]
    } else {
        vec![
            x.iter()
                .map(|z| z.re)
                .chain(x.iter().map(|z| z.im))
                .collect(),
        ]
    };
    let c_norm = c.frobenius();
    let scale = c_norm * x.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
    let project_part = |b: &Vec<f64>| project_real(&c.c, &c.c_t, b, scale);
    let done: Vec<Result<Vec<f64>, f64>> = if parts.len() == 2 {
        let (a, b) = rayon::join(|| project_part(&parts[0]), || project_part(&parts[1]));
        vec![a, b]
    } else {
        vec![project_part(&parts[0])]
    };
    let mut out = Vec::new();
    for d in done {
        out.push(d.map_err(|relative| NotConverged {
            rows: c.rows,
            cols: c.cols,
            relative,
        })?);
    }
    Ok(if c.real {
        (0..n)
            .map(|j| Complex64::new(out[0][j], out[1][j]))
            .collect()
    } else {
        (0..n)
            .map(|j| Complex64::new(out[0][j], out[0][j + n]))
            .collect()
    })
}

/// `P b` for a real matrix `c` (with transpose `c_t`): LSQR, restarted from the residual until
/// `‖c r‖ ≤ TOLERANCE·scale`. Err: the relative violation reached.
fn project_real(c: &Csr, c_t: &Csr, b: &[f64], scale: f64) -> Result<Vec<f64>, f64> {
    let mut residual = b.to_vec();
    let mut cr = vec![0.0; c.rows()];
    let mut cty = vec![0.0; b.len()];
    let mut relative = 0.0;
    for _ in 0..=REFINEMENTS {
        c.apply_into(&residual, &mut cr);
        let violation = norm(&cr);
        relative = violation / scale.max(f64::MIN_POSITIVE);
        if relative <= TOLERANCE || violation == 0.0 {
            return Ok(b.iter().zip(&residual).map(|(a, r)| a - r).collect());
        }
        let y = lsqr(c, c_t, &residual, TOLERANCE * scale);
        c_t.apply_into(&y, &mut cty);
        residual.iter_mut().zip(&cty).for_each(|(r, d)| *r -= d);
    }
    Err(relative)
}

/// LSQR (Paige & Saunders 1982) for `min ‖cᵀ y − b‖` from `y = 0`, stopped when the estimate
/// of `‖c r‖` falls below `target`, the bidiagonalization breaks down (the Krylov space is
/// exhausted: the solution is exact), or after an iteration budget. No reorthogonalization:
/// it would cost `O(iterations × rows)` per step, more than the extra steps it saves here.
fn lsqr(c: &Csr, c_t: &Csr, b: &[f64], target: f64) -> Vec<f64> {
    let (m, n) = (c.rows(), c_t.rows());
    let mut y = vec![0.0; m];
    let mut u = b.to_vec();
    let mut beta = norm(&u);
    if beta == 0.0 {
        return y;
    }
    u.iter_mut().for_each(|e| *e /= beta);
    let mut v = vec![0.0; m];
    c.apply_into(&u, &mut v);
    let mut alpha = norm(&v);
    if alpha == 0.0 {
        return y;
    }
    v.iter_mut().for_each(|e| *e /= alpha);
    let mut w = v.clone();
    let (mut phi_bar, mut rho_bar) = (beta, alpha);
    let mut a_norm2 = alpha * alpha;
    let mut scratch_n = vec![0.0; n];
    let mut scratch_m = vec![0.0; m];
    for _ in 0..20 * m + 100 {
        // β u ← cᵀ v − α u
        c_t.apply_into(&v, &mut scratch_n);
        u.iter_mut()
            .zip(&scratch_n)
            .for_each(|(ui, si)| *ui = si - *ui * alpha);
        beta = norm(&u);
        if beta > 0.0 {
            u.iter_mut().for_each(|e| *e /= beta);
        }
        // α v ← c u − β v
        c.apply_into(&u, &mut scratch_m);
        scratch_m
            .iter_mut()
            .zip(&v)
            .for_each(|(si, vi)| *si -= beta * vi);
        alpha = norm(&scratch_m);
        a_norm2 += alpha * alpha + beta * beta;

        let rho = rho_bar.hypot(beta);
        let (cs, sn) = (rho_bar / rho, beta / rho);
        let theta = sn * alpha;
        rho_bar = -cs * alpha;
        let phi = cs * phi_bar;
        phi_bar *= sn;
        y.iter_mut()
            .zip(&w)
            .for_each(|(yi, wi)| *yi += (phi / rho) * wi);

        // ‖c r‖ ≈ φ̄ α |cos|.
        let converged = phi_bar * alpha * cs.abs() <= 0.1 * target;
        if beta == 0.0 || alpha <= f64::EPSILON * a_norm2.sqrt() || converged {
            break;
        }
        scratch_m.iter_mut().for_each(|e| *e /= alpha);
        std::mem::swap(&mut v, &mut scratch_m);
        w.iter_mut()
            .zip(&v)
            .for_each(|(wi, vi)| *wi = vi - *wi * (theta / rho));
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    fn norm(v: &[Complex64]) -> f64 {
        v.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt()
    }

    fn inner(a: &[Complex64], b: &[Complex64]) -> Complex64 {
        a.iter().zip(b).map(|(x, y)| x.conj() * y).sum()
    }

    fn sub_scaled(a: &mut [Complex64], s: Complex64, b: &[Complex64]) {
        a.iter_mut().zip(b).for_each(|(x, y)| *x -= s * y);
    }

    fn apply(rows: &[Vec<(usize, Complex64)>], x: &[Complex64]) -> Vec<Complex64> {
        rows.iter()
            .map(|r| r.iter().map(|&(j, v)| v * x[j]).sum())
            .collect()
    }

    /// A small dense reference: projection by Gram–Schmidt on the rows (exact for tiny,
    /// well-conditioned matrices).
    fn reference(rows: &[Vec<(usize, Complex64)>], cols: usize, x: &[Complex64]) -> Vec<Complex64> {
        let mut q: Vec<Vec<Complex64>> = Vec::new();
        for r in rows {
            // Row as a vector of conj entries: (C x)_i = Σ c_ij x_j = ⟨conj(c_i), x⟩.
            let mut v = vec![Complex64::new(0.0, 0.0); cols];
            for &(j, z) in r {
                v[j] += z.conj();
            }
            for _ in 0..2 {
                for b in &q {
                    let h = inner(b, &v);
                    sub_scaled(&mut v, h, b);
                }
            }
            let n = norm(&v);
            if n > 1e-10 {
                v.iter_mut().for_each(|z| *z /= n);
                q.push(v);
            }
        }
        let mut p = vec![Complex64::new(0.0, 0.0); cols];
        for b in &q {
            let h = inner(b, x);
            sub_scaled(&mut p, -h, b);
        }
        p
    }

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    #[test]
    fn matches_a_dense_projection_on_a_rank_deficient_matrix() {
        rank_deficient_case(false);
    }

    #[test]
    fn a_real_matrix_projects_complex_vectors_the_same_way() {
        rank_deficient_case(true);
    }

    fn rank_deficient_case(real: bool) {
        let mut seed = 7;
        let cols = 40;
        let mut rows: Vec<Vec<(usize, Complex64)>> = (0..12)
            .map(|_| {
                let mut row = Vec::new();
                for j in 0..cols {
                    if lcg(&mut seed) > 0.3 {
                        let im = if real { 0.0 } else { lcg(&mut seed) };
                        row.push((j, Complex64::new(lcg(&mut seed), im)));
                    }
                }
                row
            })
            .collect();
        // Two dependent rows: a copy times a phase, and a sum of two rows.
        let phase = if real {
            Complex64::new(-0.8, 0.0)
        } else {
            Complex64::new(0.6, 0.8)
        };
        rows.push(rows[0].iter().map(|&(j, z)| (j, z * phase)).collect());
        let mut sum: Vec<(usize, Complex64)> = rows[1].clone();
        sum.extend(rows[2].iter().copied());
        rows.push(sum);
        let x: Vec<Complex64> = (0..cols)
            .map(|_| Complex64::new(lcg(&mut seed), lcg(&mut seed)))
            .collect();
        let c = SparseRows::new(rows.iter().map(|r| r.as_slice()), cols);
        assert_eq!(c.real, real);
        let p = project(&c, &x).unwrap();
        let want = reference(&rows, cols, &x);
        let err = norm(&p.iter().zip(&want).map(|(a, b)| a - b).collect::<Vec<_>>());
        assert!(err <= 1e-12 * norm(&x), "‖P x − reference‖ = {err}");
        // x − P x satisfies the rows.
        let r: Vec<Complex64> = x.iter().zip(&p).map(|(a, b)| a - b).collect();
        assert!(norm(&apply(&rows, &r)) <= 1e-13 * norm(&x));
    }

    #[test]
    fn zero_rows_and_zero_input_project_to_zero() {
        let c = SparseRows::new([[(0usize, Complex64::new(1.0, 0.0))].as_slice()], 3);
        let x = vec![Complex64::new(0.0, 0.0); 3];
        assert_eq!(project(&c, &x).unwrap(), x);
        let x = vec![
            Complex64::new(0.0, 0.0),
            Complex64::new(2.0, 1.0),
            Complex64::new(0.0, 0.0),
        ];
        assert_eq!(project(&c, &x).unwrap(), vec![Complex64::new(0.0, 0.0); 3]);
    }
}
