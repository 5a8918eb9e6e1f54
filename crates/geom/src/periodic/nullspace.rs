//! The moments of a loci surface: the right singular vectors of the smallest singular value of
//! `A[n, t] = cos(2π κ_t p_t · r_n)` (Wang §5), and a canonical choice among them when that
//! value is repeated.
//!
//! When the smallest singular value is repeated, every unit vector of its singular subspace is
//! an equally good surface, and which one a decomposition returns depends on the order of the
//! rows — on how the file happens to list its atoms. The subspace itself does not: permuting
//! or repeating rows leaves `AᵀA`'s eigenspaces unchanged. So the choice here is made from the
//! subspace's orthogonal projector `P`, never from the decomposition's basis.
//!
//! Invariants:
//! - Singular values within `DEGENERATE * σ_max` of the smallest are one repeated value; the
//!   subspace is spanned by all their vectors ([`Moments::multiplicity`] counts them).
//! - The representative is `P e_j / |P e_j|` for the basis term `j` with the largest `P_jj`
//!   (the single term the subspace reproduces best), ties (within `DEGENERATE`) to the
//!   earliest term; [`Moments::canonical_basis`] continues the same rule by Gram–Schmidt, so
//!   both are functions of the point set and the basis order only.

use nalgebra::{DMatrix, DVector};

/// Relative gap below which two singular values count as one repeated value.
pub const DEGENERATE: f64 = 1e-9;

/// The smallest singular value's subspace of `A`.
#[derive(Clone, Debug)]
pub struct Moments {
    /// An orthonormal basis of the subspace (columns), in canonical order: the first column is
    /// the representative.
    pub canonical_basis: DMatrix<f64>,
    /// How many singular values are the smallest (1: the surface is unique up to scale).
    pub multiplicity: usize,
}

impl Moments {
    /// The representative moments (unit length).
    pub fn representative(&self) -> Vec<f64> {
        self.canonical_basis.column(0).iter().copied().collect()
    }
}

/// The subspace of the smallest singular value of `A`, `None` when the decomposition fails.
/// Rows of zeros pad `A` to at least as many rows as columns, so that the thin decomposition
/// holds every right singular vector (with fewer points than terms the null space is exact).
pub fn smallest_subspace(a: &DMatrix<f64>) -> Option<Moments> {
    let columns = a.ncols();
    let padded = if a.nrows() < columns {
        let mut p = DMatrix::<f64>::zeros(columns, columns);
        p.view_mut((0, 0), (a.nrows(), columns)).copy_from(a);
        p
    } else {
        a.clone()
    };
    let svd = padded.try_svd_unordered(false, true, f64::EPSILON, 0)?;
    let v_t = svd.v_t.as_ref()?;
    let values = &svd.singular_values;
    let largest = values.iter().copied().fold(0.0, f64::max);
    let smallest = values.iter().copied().fold(f64::INFINITY, f64::min);
    if !smallest.is_finite() {
        return None;
    }
    let cluster: Vec<usize> = (0..values.len())
        .filter(|&i| values[i] - smallest <= DEGENERATE * largest)
        .collect();
    let mut projector = DMatrix::<f64>::zeros(columns, columns);
    for &i in &cluster {
        let v = v_t.row(i).transpose();
        projector += &v * v.transpose();
    }
    Some(Moments {
        canonical_basis: canonical_basis(&projector, cluster.len()),
        multiplicity: cluster.len(),
    })
}

/// `rank` orthonormal vectors spanning the range of the projector `p`: its columns taken in
/// order of decreasing diagonal (ties to the earlier column), each orthogonalised against
/// those before and kept when a substantial part remains.
fn canonical_basis(p: &DMatrix<f64>, rank: usize) -> DMatrix<f64> {
    let n = p.ncols();
    let mut order: Vec<usize> = (0..n).collect();
    // A stable sort on diagonals rounded to the tie tolerance: ties keep the basis order.
    let bucket = |j: usize| (p[(j, j)] / DEGENERATE).round() as i64;
    order.sort_by_key(|&j| std::cmp::Reverse(bucket(j)));
    let mut basis: Vec<DVector<f64>> = Vec::with_capacity(rank);
    for j in order {
        if basis.len() == rank {
            break;
        }
        let mut v: DVector<f64> = p.column(j).into_owned();
        for b in &basis {
            let d = b.dot(&v);
            v.axpy(-d, b, 1.0);
        }
        let norm = v.norm();
        // A projector's column has norm √P_jj ≤ 1; a remainder this small is a combination
        // of the columns already taken.
        if norm > 1e-6 {
            basis.push(v / norm);
        }
    }
    let mut out = DMatrix::<f64>::zeros(n, basis.len().max(1));
    for (c, b) in basis.iter().enumerate() {
        out.set_column(c, b);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A` for NaCl's eight ions (rows in `order`) on the 6 face and 4 body diagonals.
    fn rows(order: &[usize]) -> DMatrix<f64> {
        let ions = [
            [0.0, 0.0, 0.0],
            [0.0, 0.5, 0.5],
            [0.5, 0.0, 0.5],
            [0.5, 0.5, 0.0],
            [0.5, 0.5, 0.5],
            [0.5, 0.0, 0.0],
            [0.0, 0.5, 0.0],
            [0.0, 0.0, 0.5],
        ];
        // The 6 face and 4 body diagonals: the paper's 13 directions after the 3 axes.
        let dirs = &crate::periodic::model::DIRECTIONS_13[3..];
        DMatrix::from_fn(order.len(), dirs.len(), |n, t| {
            let p = ions[order[n]];
            let d = dirs[t];
            (std::f64::consts::TAU * (d[0] * p[0] + d[1] * p[1] + d[2] * p[2])).cos()
        })
    }

    #[test]
    fn the_representative_does_not_depend_on_the_row_order() {
        let a = smallest_subspace(&rows(&[0, 1, 2, 3, 4, 5, 6, 7])).expect("svd");
        let b = smallest_subspace(&rows(&[6, 3, 7, 0, 5, 2, 4, 1, 3, 0])).expect("svd");
        assert_eq!(a.multiplicity, b.multiplicity);
        // cos(2π(x+y)) − cos(2π(x−y)) = −2 sin 2πx sin 2πy vanishes on every ion, and so do
        // the body diagonals summing to zero: three plus three dimensions.
        assert_eq!(a.multiplicity, 6);
        let (ra, rb) = (a.representative(), b.representative());
        for (x, y) in ra.iter().zip(&rb) {
            assert!((x - y).abs() < 1e-12, "{ra:?} vs {rb:?}");
        }
        // The body diagonal's column (P_jj = 3/4) beats the face diagonals' (1/2):
        // (3/4, −1/4, −1/4, −1/4) / |·|.
        let norm = (0.75f64 * 0.75 + 3.0 * 0.0625).sqrt();
        let want = [0.75, -0.25, -0.25, -0.25].map(|v| v / norm);
        for (x, w) in ra[6..].iter().zip(want) {
            assert!((x - w).abs() < 1e-12, "{ra:?}");
        }
        assert!(ra[..6].iter().all(|v| v.abs() < 1e-12), "{ra:?}");
    }
}
