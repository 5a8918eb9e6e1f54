//! Frequency orbits, canonical representatives and band-limited frequency sets.
//!
//! Conventions (METHOD.md §3–§4):
//! - Frequencies are integer vectors in the group's frame (skew for D3); `Q` acts on them by
//!   its transpose, `f ↦ Qᵀ f`. 2D frequencies carry a zero third component.
//! - The representative of an orbit is its lexicographically largest member. For the named
//!   groups this is exactly METHOD.md's choice: Oh `fx ≥ fy ≥ fz ≥ 0`, Td `fx ≥ fy ≥ |fz|`,
//!   D4 `fx ≥ fy ≥ 0`, D3 `f1 ≥ f2 ≥ 0`; named groups enumerate those inequalities directly.
//! - Band: a representative is kept for grid size `N` only if every member `k` of its orbit
//!   has `|k_i| < N/2` on every axis (the Nyquist frequency is dropped). For the cubic groups
//!   that is `max |f_i| ≤ N/2 − 1`; D3's band is hexagonal in skew coordinates, so every orbit
//!   member is tested.
//! - Td and D3 do not contain −I: `f` and `−f` can lie in different orbits. The orbit of `−f`
//!   is `f`'s conjugate partner; for real input `c_partner = conj(c_f)`.

use rayon::prelude::*;

use super::group::{Group, ReferenceElement, mat_vec};

impl Group {
    /// Every `Qᵀ k`, one per element (with repetitions), in element order.
    pub fn images(&self, k: [i32; 3]) -> impl Iterator<Item = [i32; 3]> + '_ {
        self.transposes().iter().map(move |t| mat_vec(t, k))
    }

    /// The distinct members of the orbit of `k`, sorted.
    pub fn orbit(&self, k: [i32; 3]) -> Vec<[i32; 3]> {
        let mut o: Vec<[i32; 3]> = self.images(k).collect();
        o.sort_unstable();
        o.dedup();
        o
    }

    /// `|Stab k|`: how many elements fix `k`.
    pub fn stabilizer_order(&self, k: [i32; 3]) -> usize {
        self.images(k).filter(|&q| q == k).count()
    }

    /// The canonical representative of `k`'s orbit: its lexicographically largest member.
    pub fn representative(&self, k: [i32; 3]) -> [i32; 3] {
        self.images(k).max().unwrap_or(k)
    }

    /// Whether `k` is the representative of its orbit; stops at the first larger image.
    pub fn is_representative(&self, k: [i32; 3]) -> bool {
        self.images(k).all(|q| q <= k)
    }

    /// The representative of the orbit of `−f`. Equals `f` for groups containing −I.
    pub fn partner(&self, f: [i32; 3]) -> [i32; 3] {
        self.representative([-f[0], -f[1], -f[2]])
    }

    /// `K_f = 1/√(|S|·|Stab f|)`, which makes `φ_f` unit-norm on the domain.
    pub fn normalization(&self, f: [i32; 3]) -> f64 {
        1.0 / ((self.order() * self.stabilizer_order(f)) as f64).sqrt()
    }

    /// Whether the whole orbit of `f` lies strictly inside the band of an `n`-point grid:
    /// `|k_i| < n/2` on each of the group's axes for every member `k`.
    pub fn in_band(&self, f: [i32; 3], n: usize) -> bool {
        let d = self.dimension();
        self.images(f)
            .all(|k| k[..d].iter().all(|&c| 2 * (c.unsigned_abs() as usize) < n))
    }

    /// The representatives of all orbits inside the band of an `n`-point grid, sorted.
    pub fn frequency_set(&self, n: usize) -> Vec<[i32; 3]> {
        // Largest |component| any in-band frequency can have (n/2 − 1 for even n).
        let h = (n.saturating_sub(1) / 2) as i32;
        let mut out = Vec::new();
        match self.reference_element() {
            Some(ReferenceElement::Cube) => {
                for a in 0..=h {
                    for b in 0..=a {
                        for c in 0..=b {
                            out.push([a, b, c]);
                        }
                    }
                }
            }
            Some(ReferenceElement::Tetrahedron) => {
                for a in 0..=h {
                    for b in 0..=a {
                        for c in -b..=b {
                            out.push([a, b, c]);
                        }
                    }
                }
            }
            Some(ReferenceElement::Square) => {
                for a in 0..=h {
                    for b in 0..=a {
                        out.push([a, b, 0]);
                    }
                }
            }
            Some(ReferenceElement::Triangle) => {
                for a in 0..=h {
                    for b in 0..=a {
                        if self.in_band([a, b, 0], n) {
                            out.push([a, b, 0]);
                        }
                    }
                }
            }
            None => {
                // Any group: scan the box.
                let d = self.dimension();
                let zr = if d == 3 { h } else { 0 };
                out = (-h..=h)
                    .into_par_iter()
                    .flat_map_iter(|a| {
                        (-h..=h).flat_map(move |b| (-zr..=zr).map(move |c| [a, b, c]))
                    })
                    .filter(|&k| self.is_representative(k) && self.in_band(k, n))
                    .collect();
            }
        }
        out.sort_unstable();
        out
    }
}
