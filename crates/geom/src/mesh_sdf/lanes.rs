//! Four `f32` lanes, the bounds of one nearest-triangle search step (`nearest.rs`): one SSE
//! register on x86_64, a plain array elsewhere.
//!
//! Why explicit: written as arrays, the compiler vectorised the box tests well or turned a lane
//! maximum into four unpredictable branches depending on code far away (measured: 30 % slower
//! searches after an unrelated edit). Here every operation is one instruction.
//!
//! Invariant: both implementations compute the same values lane by lane: `max`/`min` are
//! `if a > b { a } else { b }` / `if a < b { a } else { b }` (so a NaN in `a` yields `b`, as
//! `maxps`/`minps` do), and arithmetic is plain IEEE `f32` without fused operations.

use std::ops::{Add, Mul, Sub};

/// Lanes per register.
pub(super) const LANES: usize = 4;

#[cfg(target_arch = "x86_64")]
mod imp {
    use super::LANES;
    use std::arch::x86_64::*;

    #[derive(Clone, Copy)]
    pub(in super::super) struct F4(pub(super) __m128);

    impl F4 {
        #[inline(always)]
        pub fn splat(x: f32) -> F4 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            F4(unsafe { _mm_set1_ps(x) })
        }

        #[inline(always)]
        pub fn new(a: [f32; LANES]) -> F4 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            F4(unsafe { _mm_setr_ps(a[0], a[1], a[2], a[3]) })
        }

        /// `a` in one load (`new` may assemble it lane by lane).
        #[inline(always)]
        pub fn load(a: &[f32; LANES]) -> F4 {
            // SAFETY: reads the 16 bytes of `a`; no alignment needed.
            F4(unsafe { _mm_loadu_ps(a.as_ptr()) })
        }

        /// `a` where `pick`, else `b`, without a branch.
        #[inline(always)]
        pub fn select(pick: bool, a: F4, b: F4) -> F4 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            unsafe {
                let mask = _mm_castsi128_ps(_mm_set1_epi32(-i32::from(pick)));
                F4(_mm_or_ps(_mm_and_ps(mask, a.0), _mm_andnot_ps(mask, b.0)))
            }
        }

        #[inline(always)]
        pub fn max(self, b: F4) -> F4 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            F4(unsafe { _mm_max_ps(self.0, b.0) })
        }

        /// Bit `i` set where lane `i` of `self` is below that of `b`.
        #[inline(always)]
        pub fn lt_mask(self, b: F4) -> u32 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            (unsafe { _mm_movemask_ps(_mm_cmplt_ps(self.0, b.0)) }) as u32
        }

        /// The least lane among those below `b`'s; `INFINITY` when there is none.
        #[inline(always)]
        pub fn min_where_lt(self, b: F4) -> f32 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            unsafe {
                let open = _mm_cmplt_ps(self.0, b.0);
                let m = _mm_or_ps(
                    _mm_and_ps(open, self.0),
                    _mm_andnot_ps(open, _mm_set1_ps(f32::INFINITY)),
                );
                let m = _mm_min_ps(m, _mm_movehl_ps(m, m));
                let m = _mm_min_ss(m, _mm_shuffle_ps::<0b01>(m, m));
                _mm_cvtss_f32(m)
            }
        }

        #[inline(always)]
        pub(super) fn add(self, b: F4) -> F4 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            F4(unsafe { _mm_add_ps(self.0, b.0) })
        }

        #[inline(always)]
        pub(super) fn sub(self, b: F4) -> F4 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            F4(unsafe { _mm_sub_ps(self.0, b.0) })
        }

        #[inline(always)]
        pub(super) fn mul(self, b: F4) -> F4 {
            // SAFETY: SSE is part of the x86_64 baseline; no memory is touched.
            F4(unsafe { _mm_mul_ps(self.0, b.0) })
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod imp {
    use super::LANES;

    #[derive(Clone, Copy)]
    pub(in super::super) struct F4(pub(super) [f32; LANES]);

    impl F4 {
        #[inline(always)]
        pub fn splat(x: f32) -> F4 {
            F4([x; LANES])
        }

        #[inline(always)]
        pub fn new(a: [f32; LANES]) -> F4 {
            F4(a)
        }

        #[inline(always)]
        pub fn load(a: &[f32; LANES]) -> F4 {
            F4(*a)
        }

        /// `a` where `pick`, else `b`.
        #[inline(always)]
        pub fn select(pick: bool, a: F4, b: F4) -> F4 {
            if pick { a } else { b }
        }

        #[inline(always)]
        pub fn max(self, b: F4) -> F4 {
            F4(std::array::from_fn(|i| {
                if self.0[i] > b.0[i] {
                    self.0[i]
                } else {
                    b.0[i]
                }
            }))
        }

        /// Bit `i` set where lane `i` of `self` is below that of `b`.
        #[inline(always)]
        pub fn lt_mask(self, b: F4) -> u32 {
            (0..LANES).fold(0, |m, i| m | (u32::from(self.0[i] < b.0[i]) << i))
        }

        /// The least lane among those below `b`'s; `INFINITY` when there is none.
        #[inline(always)]
        pub fn min_where_lt(self, b: F4) -> f32 {
            (0..LANES).fold(f32::INFINITY, |m, i| {
                let v = if self.0[i] < b.0[i] {
                    self.0[i]
                } else {
                    f32::INFINITY
                };
                if v < m { v } else { m }
            })
        }

        #[inline(always)]
        pub(super) fn add(self, b: F4) -> F4 {
            F4(std::array::from_fn(|i| self.0[i] + b.0[i]))
        }

        #[inline(always)]
        pub(super) fn sub(self, b: F4) -> F4 {
            F4(std::array::from_fn(|i| self.0[i] - b.0[i]))
        }

        #[inline(always)]
        pub(super) fn mul(self, b: F4) -> F4 {
            F4(std::array::from_fn(|i| self.0[i] * b.0[i]))
        }
    }
}

pub(super) use imp::F4;

impl Add for F4 {
    type Output = F4;
    #[inline(always)]
    fn add(self, b: F4) -> F4 {
        F4::add(self, b)
    }
}

impl Sub for F4 {
    type Output = F4;
    #[inline(always)]
    fn sub(self, b: F4) -> F4 {
        F4::sub(self, b)
    }
}

impl Mul for F4 {
    type Output = F4;
    #[inline(always)]
    fn mul(self, b: F4) -> F4 {
        F4::mul(self, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The register and the array agree with the scalar definitions, NaN included.
    #[test]
    fn lane_operations_match_their_scalar_definitions() {
        let a = [1.0, f32::NAN, -2.0, 5.0];
        let b = [0.5, 3.0, -1.0, f32::INFINITY];
        assert_eq!(F4::new(a).lt_mask(F4::new(b)), 0b1100);
        assert_eq!(F4::new(b).lt_mask(F4::new(a)), 0b0001);
        assert_eq!(F4::new(a).min_where_lt(F4::new(b)), -2.0);
        assert_eq!(F4::new(b).min_where_lt(F4::new(a)), 0.5);
        assert_eq!(F4::new(a).min_where_lt(F4::splat(-3.0)), f32::INFINITY);
        // max: a NaN first operand yields the second; arithmetic lane by lane.
        let lanes = |v: F4| -> [f32; LANES] {
            let mut out = [0.0; LANES];
            for (i, o) in out.iter_mut().enumerate() {
                let mut onehot = [f32::NEG_INFINITY; LANES];
                onehot[i] = f32::INFINITY;
                // The lane's value is the only finite minimum below +∞ where it is kept.
                *o = v.min_where_lt(F4::new(onehot));
            }
            out
        };
        assert_eq!(
            lanes(F4::select(true, F4::new(b), F4::new(a)))[..3],
            [0.5, 3.0, -1.0]
        );
        assert_eq!(
            lanes(F4::select(false, F4::new(b), F4::new(a)))[2..],
            [-2.0, 5.0]
        );
        assert_eq!(lanes(F4::load(&[4.0, 3.0, 2.0, 1.0])), [4.0, 3.0, 2.0, 1.0]);
        let m = F4::new(a).max(F4::new(b));
        assert_eq!(lanes(m)[..3], [1.0, 3.0, -1.0]);
        let s = (F4::new([1.0, 2.0, 3.0, 4.0]) * F4::splat(2.0) - F4::splat(1.0))
            + F4::new([0.25; LANES]);
        assert_eq!(lanes(s), [1.25, 3.25, 5.25, 7.25]);
    }
}
