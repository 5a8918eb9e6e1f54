//! Frequency orbits, canonical representatives and band-limited frequency sets.
//!
//! Conventions (docs/method.md §Frequency sets, §Conjugation):
//! - Frequencies are integer vectors in the group's frame (skew for D3); `Q` acts on them by
//!   its transpose, `f ↦ Qᵀ f`. 2D frequencies carry a zero third component.
//! - The representative of an orbit is its lexicographically largest member. For the named
//!   groups this is docs/method.md's (§Frequency sets): Oh `fx ≥ fy ≥ fz ≥ 0`, Td `fx ≥ fy ≥ |fz|`,
//!   D4 `fx ≥ fy ≥ 0`, D3 `f1 ≥ f2 ≥ 0`; named groups enumerate those inequalities directly.
//! - Band: a representative is kept for grid size `N` only if every member `k` of its orbit
//!   has `|k_i| < N/2` on every axis (the Nyquist frequency is dropped). For the cubic groups
//!   that is `max |f_i| ≤ N/2 − 1`; D3's band is hexagonal in skew coordinates, so every orbit
//!   member is tested.
//! - Td and D3 do not contain −I: `f` and `−f` can lie in different orbits. The orbit of `−f`
//!   is `f`'s conjugate partner; for real input `c_partner = conj(c_f)`.

use rayon::prelude::*;

use super::group::{Group, ReferenceElement, mat_vec};

#[inline]
fn sort3_desc(a: &mut [i32; 3]) {
    if a[0] < a[1] {
        a.swap(0, 1);
    }
    if a[1] < a[2] {
        a.swap(1, 2);
    }
    if a[0] < a[1] {
        a.swap(0, 1);
    }
}

/// Finds a frequency in a sorted list of representatives: a dense table of the ranges of
/// each first component (2D) or first two components (3D), then a binary search inside the
/// short range. Small enough to stay in cache where a hash map would not.
#[derive(Clone, Debug)]
pub(crate) struct FrequencyIndex {
    dim: usize,
    h: i32,
    ranges: Vec<(u32, u32)>,
    tail: Vec<i32>,
    /// For the complete band-limited set of a cubic group or D4, the position follows from
    /// counting the representatives before `f` in lexicographic order; no table is read.
    closed: Option<ReferenceElement>,
}

impl FrequencyIndex {
    /// The index of `group.frequency_set(n)` itself (or of any list equal to it): closed
    /// form for Oh, Td and D4, tables otherwise.
    pub(crate) fn complete(group: &Group, reps: &[[i32; 3]], n: usize) -> FrequencyIndex {
        match group.reference_element() {
            Some(
                e @ (ReferenceElement::Cube
                | ReferenceElement::Tetrahedron
                | ReferenceElement::Square),
            ) if reps.len() == group.frequency_set(n).len() => FrequencyIndex {
                dim: group.dimension(),
                h: (n.saturating_sub(1) / 2) as i32,
                ranges: Vec::new(),
                tail: Vec::new(),
                closed: Some(e),
            },
            _ => FrequencyIndex::new(group.dimension(), reps.iter().copied()),
        }
    }

    /// `reps` must be sorted and unique.
    pub(crate) fn new(dim: usize, reps: impl ExactSizeIterator<Item = [i32; 3]> + Clone) -> Self {
        let h = reps
            .clone()
            .map(|f| f[0].abs().max(f[1].abs()).max(f[2].abs()))
            .max()
            .unwrap_or(0);
        let side = (2 * h + 1) as usize;
        let len = if dim == 3 { side * side } else { side };
        let mut ranges = vec![(0u32, 0u32); len];
        let mut tail = Vec::with_capacity(reps.len());
        let key = |f: [i32; 3]| {
            let a = (f[0] + h) as usize;
            if dim == 3 {
                a * side + (f[1] + h) as usize
            } else {
                a
            }
        };
        for (i, f) in reps.enumerate() {
            let r = &mut ranges[key(f)];
            if r.1 == 0 {
                r.0 = i as u32;
            }
            r.1 += 1;
            tail.push(if dim == 3 { f[2] } else { f[1] });
        }
        FrequencyIndex {
            dim,
            h,
            ranges,
            tail,
            closed: None,
        }
    }

    /// Position of `f` in the list, if present.
    #[inline]
    pub(crate) fn find(&self, f: [i32; 3]) -> Option<usize> {
        let h = self.h;
        if f[0].abs() > h || f[1].abs() > h || f[2].abs() > h {
            return None;
        }
        if let Some(e) = self.closed {
            // `f` is a representative (a ≥ b ≥ |c|); count the ones sorted before it.
            let (a, b, c) = (f[0] as usize, f[1] as usize, f[2] as i64);
            return Some(match e {
                ReferenceElement::Cube => a * (a + 1) * (a + 2) / 6 + b * (b + 1) / 2 + c as usize,
                ReferenceElement::Tetrahedron => {
                    a * (a + 1) * (2 * a + 1) / 6 + b * b + (c + b as i64) as usize
                }
                _ => a * (a + 1) / 2 + b,
            });
        }
        let side = (2 * h + 1) as usize;
        let a = (f[0] + h) as usize;
        let (key, t) = if self.dim == 3 {
            (a * side + (f[1] + h) as usize, f[2])
        } else {
            (a, f[1])
        };
        let (start, len) = self.ranges[key];
        let (start, len) = (start as usize, len as usize);
        self.tail[start..start + len]
            .binary_search(&t)
            .ok()
            .map(|i| start + i)
    }
}

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

    /// [`representative`](Self::representative) by closed forms for the named groups
    /// (sorting absolute values), which FFT passes call once per grid frequency.
    #[inline]
    pub(crate) fn representative_fast(&self, k: [i32; 3]) -> [i32; 3] {
        match self.reference_element() {
            Some(ReferenceElement::Cube) | Some(ReferenceElement::Tetrahedron) => {
                let mut a = [k[0].abs(), k[1].abs(), k[2].abs()];
                sort3_desc(&mut a);
                if self.reference_element() == Some(ReferenceElement::Tetrahedron)
                    && a[2] != 0
                    && (k[0] < 0) ^ (k[1] < 0) ^ (k[2] < 0)
                {
                    // Td keeps the sign of the product: odd negatives stay on the smallest.
                    a[2] = -a[2];
                }
                a
            }
            Some(ReferenceElement::Square) => {
                let (a, b) = (k[0].abs(), k[1].abs());
                [a.max(b), a.min(b), 0]
            }
            _ => self.representative(k),
        }
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
