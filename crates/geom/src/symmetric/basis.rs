//! The symmetric basis `φ_f`.
//!
//! `φ_f(s) = K_f Σ_{Q∈S} exp(2πi fᵀ Q s) = K_f Σ_{k ∈ orbit(f)} m_k exp(2πi k·s)`, with
//! `m_k = |Stab f|` for every `k` in the orbit and `K_f = 1/√(|S|·|Stab f|)`. The point `s` is
//! in the group's frame (skew coordinates for D3), and the `φ_f` are orthonormal on the
//! sampling domain for the lattice measure `ds` (unit volume), not the Cartesian one.
//! `|φ_f(s)| ≤ K_f |S|` everywhere, which bounds what dropping a term can change.

use rustfft::num_complex::Complex64;

use super::group::Group;

/// `exp(2πi t)` for a real `t`, reducing `t` modulo 1 first so large frequencies keep their
/// phase accuracy.
#[inline]
pub(crate) fn cis_turns(t: f64) -> Complex64 {
    let r = t - t.round();
    let (s, c) = (std::f64::consts::TAU * r).sin_cos();
    Complex64::new(c, s)
}

/// `exp(2πi p/q)` for a fraction, exact for `q ∈ {1, 2, 4}` and correctly rounded otherwise.
pub(crate) fn cis_fraction(p: i64, q: i64) -> Complex64 {
    let r = p.rem_euclid(q);
    match (q, r) {
        (_, 0) => Complex64::new(1.0, 0.0),
        (2, 1) => Complex64::new(-1.0, 0.0),
        (4, 1) => Complex64::new(0.0, 1.0),
        (4, 3) => Complex64::new(0.0, -1.0),
        (3, 1) => Complex64::new(-0.5, 0.75f64.sqrt()),
        (3, 2) => Complex64::new(-0.5, -(0.75f64.sqrt())),
        _ => cis_turns(r as f64 / q as f64),
    }
}

impl Group {
    /// `φ_f(s)` by its definition, summing over every element (`s` in the group's frame).
    pub fn basis_value(&self, f: [i32; 3], s: [f64; 3]) -> Complex64 {
        let d = self.dimension();
        let sum: Complex64 = self
            .images(f)
            .map(|k| cis_turns((0..d).map(|a| k[a] as f64 * s[a]).sum()))
            .sum();
        sum * self.normalization(f)
    }

    /// The expansion of `φ_f` in plain Fourier modes: each distinct `k` of the orbit with its
    /// weight `K_f · m_k`.
    pub fn basis_terms(&self, f: [i32; 3]) -> Vec<([i32; 3], f64)> {
        let w = self.normalization(f) * self.stabilizer_order(f) as f64;
        self.orbit(f).into_iter().map(|k| (k, w)).collect()
    }
}
