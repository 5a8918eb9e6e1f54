//! `f64::floor` as an integer without libm.
//!
//! On the baseline x86-64 target (no SSE4.1 rounding instruction) `floor` is a library call;
//! per corner of tens of millions of triangles it was a tenth of the page's decimation
//! (`watch --serve`). Truncation toward zero is one instruction, and a comparison corrects it.

/// `v.floor() as i64`, for every input: NaN gives 0 and values beyond `i64`'s range saturate,
/// as the cast does.
#[inline]
pub fn floor_i64(v: f64) -> i64 {
    let toward_zero = v as i64;
    toward_zero.saturating_sub(i64::from(toward_zero as f64 > v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_without_libm_is_floor() {
        let values = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999_999_999_999_999_6,
            -2.000_000_000_000_000_4,
            1e-300,
            -1e-300,
            4.5e15,
            -4.5e15 - 0.5,
            9.3e18,
            -9.3e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for v in values {
            assert_eq!(floor_i64(v), v.floor() as i64, "{v}");
        }
    }
}
