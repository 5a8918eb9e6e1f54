//! The two numeric options of a Cesogen command line (paper §4.2), as text to values:
//! samples (`-s`) and an explicit box (`-b`).
//!
//! Samples: "one component or three comma-separated components; in the former case, the value
//! is a total number of samples distributed as uniformly as possible along all dimensions, and
//! in the latter, the number of samples along each dimension." So `-s 130^3` is 2 197 000
//! samples, 130 per axis. A total that is not a cube is spread as evenly as possible without
//! exceeding it: every axis gets `n = ⌊∛total⌋`, then x, y and z in turn get `n + 1` while the
//! product stays within the total (2000 → 13 × 12 × 12).
//!
//! Box: six comma-separated numbers, the lower corner then the upper one.
//!
//! Invariants: components are numbers in the language of numeric arguments (`args.rs`);
//! sample counts are whole numbers from 2 to [`MAX_SAMPLES_PER_AXIS`] per axis (the limit a
//! manifest's `samples` has too; a total is checked by the counts it spreads to, so `100001^3`
//! is refused for its 100001 per axis, not for its size); a box has `min < max` on every axis.

use super::args;
use super::bounds::Aabb;

/// A problem with a `-s` or `-b` value.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OptionError {
    #[error("{0}")]
    NotANumber(String),
    #[error(
        "`{text}` has {count} components; give one total (`130^3`) or three counts (`100,50,50`)"
    )]
    SampleComponents { text: String, count: usize },
    #[error("`{text}` is not a whole number of samples")]
    NotWhole { text: String },
    #[error("`{text}` gives fewer than 2 samples along an axis; a grid needs at least 2")]
    TooFewSamples { text: String },
    #[error(
        "`{text}` gives {count} samples along {}; an axis has at most {MAX_SAMPLES_PER_AXIS}",
        ["x", "y", "z"][*axis]
    )]
    TooManySamples {
        text: String,
        axis: usize,
        /// The count asked for, as shown: whole, or in exponent form when huge.
        count: String,
    },
    #[error("`{text}` has {count} components; a box needs six: x0,y0,z0,x1,y1,z1")]
    BoxComponents { text: String, count: usize },
    #[error("`{text}`: the lower corner must be below the upper one on every axis")]
    InvertedBox { text: String },
}

/// Most samples along one axis, as documented for `-s` and a manifest's `samples`: 100000³
/// is already far beyond any memory, and the limit keeps every count and product well
/// inside `usize`.
pub const MAX_SAMPLES_PER_AXIS: usize = 100_000;

/// A count as a message shows it: whole, or in exponent form past what `f64` holds exactly.
fn count_text(count: f64) -> String {
    if count < 1e15 {
        format!("{count}")
    } else {
        format!("{count:e}")
    }
}

/// Samples per axis from `-s` text: one total, or three counts.
pub fn parse_samples(text: &str) -> Result<[usize; 3], OptionError> {
    let values = args::constants(text).map_err(OptionError::NotANumber)?;
    let whole = |v: f64| -> Result<f64, OptionError> {
        if v != v.trunc() || v < 0.0 {
            return Err(OptionError::NotWhole {
                text: text.to_string(),
            });
        }
        Ok(v)
    };
    let too_many = |axis: usize, count: f64| OptionError::TooManySamples {
        text: text.to_string(),
        axis,
        count: count_text(count),
    };
    let counts: [f64; 3] = match values.as_slice() {
        [total] => {
            let total = whole(*total)?;
            // A total whose cube root alone is past the limit is refused before it could
            // saturate the integer arithmetic of the spread.
            let root = total.cbrt().floor();
            if root > MAX_SAMPLES_PER_AXIS as f64 {
                return Err(too_many(0, root));
            }
            spread_samples(total as u64).map(|n| n as f64)
        }
        [a, b, c] => [whole(*a)?, whole(*b)?, whole(*c)?],
        _ => {
            return Err(OptionError::SampleComponents {
                text: text.to_string(),
                count: values.len(),
            });
        }
    };
    if let Some(axis) = (0..3).find(|&a| counts[a] > MAX_SAMPLES_PER_AXIS as f64) {
        return Err(too_many(axis, counts[axis]));
    }
    // Each count is now a whole number within the limit, so exact as `usize`.
    let counts = counts.map(|n| n as usize);
    if counts.iter().any(|&n| n < 2) {
        return Err(OptionError::TooFewSamples {
            text: text.to_string(),
        });
    }
    Ok(counts)
}

/// A total number of samples spread over three axes as evenly as possible, never exceeding it.
pub fn spread_samples(total: u64) -> [usize; 3] {
    let mut n = (total as f64).cbrt().round() as u64;
    while n > 0 && n.saturating_pow(3) > total {
        n -= 1;
    }
    while (n + 1).saturating_pow(3) <= total {
        n += 1;
    }
    let mut counts = [n; 3];
    for axis in 0..3 {
        let mut trial = counts;
        trial[axis] += 1;
        if trial
            .iter()
            .try_fold(1u64, |p, &c| p.checked_mul(c))
            .is_some_and(|p| p <= total)
        {
            counts = trial;
        }
    }
    counts.map(|c| c as usize)
}

/// The box of `-b` text: `x0,y0,z0,x1,y1,z1`.
pub fn parse_box(text: &str) -> Result<Aabb, OptionError> {
    let values = args::constants(text).map_err(OptionError::NotANumber)?;
    let [x0, y0, z0, x1, y1, z1] =
        <[f64; 6]>::try_from(values.as_slice()).map_err(|_| OptionError::BoxComponents {
            text: text.to_string(),
            count: values.len(),
        })?;
    let b = Aabb {
        min: [x0, y0, z0],
        max: [x1, y1, z1],
    };
    if (0..3).any(|a| b.min[a] >= b.max[a]) {
        return Err(OptionError::InvertedBox {
            text: text.to_string(),
        });
    }
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn totals_spread_evenly() {
        assert_eq!(parse_samples("130^3"), Ok([130; 3]));
        assert_eq!(parse_samples("60^3"), Ok([60; 3]));
        assert_eq!(parse_samples("1000000"), Ok([100; 3]));
        assert_eq!(spread_samples(2000), [13, 12, 12]);
        assert_eq!(spread_samples(2196), [13, 13, 12]);
        assert_eq!(spread_samples(800u64.pow(3)), [800; 3]);
        assert_eq!(spread_samples(7), [2, 2, 1]);
        assert_eq!(parse_samples("100,50,20"), Ok([100, 50, 20]));
    }

    #[test]
    fn bad_samples_are_explained() {
        assert_eq!(
            parse_samples("7").unwrap_err().to_string(),
            "`7` gives fewer than 2 samples along an axis; a grid needs at least 2"
        );
        assert_eq!(
            parse_samples("10.5").unwrap_err().to_string(),
            "`10.5` is not a whole number of samples"
        );
        assert!(matches!(
            parse_samples("1,2"),
            Err(OptionError::SampleComponents { count: 2, .. })
        ));
        assert!(matches!(
            parse_samples("many"),
            Err(OptionError::NotANumber(_))
        ));
    }

    #[test]
    fn an_axis_has_at_most_100000_samples_and_the_message_says_so() {
        assert_eq!(parse_samples("100000^3"), Ok([100_000; 3]));
        assert_eq!(parse_samples("100000,2,2"), Ok([100_000, 2, 2]));
        assert_eq!(
            parse_samples("100001^3").unwrap_err().to_string(),
            "`100001^3` gives 100001 samples along x; an axis has at most 100000"
        );
        // A total just short of 100001 × 100000² still spreads to 100000 per axis.
        assert_eq!(parse_samples("100001*100000^2-1"), Ok([100_000; 3]));
        assert_eq!(
            parse_samples("100001*100000^2").unwrap_err().to_string(),
            "`100001*100000^2` gives 100001 samples along x; an axis has at most 100000"
        );
        assert_eq!(
            parse_samples("200000,3,3").unwrap_err().to_string(),
            "`200000,3,3` gives 200000 samples along x; an axis has at most 100000"
        );
        assert_eq!(
            parse_samples("3,3,4294967297").unwrap_err().to_string(),
            "`3,3,4294967297` gives 4294967297 samples along z; an axis has at most 100000"
        );
        // Far past u64: refused by its cube root, shown in exponent form.
        assert_eq!(
            parse_samples("1e300").unwrap_err().to_string(),
            "`1e300` gives 1e100 samples along x; an axis has at most 100000"
        );
    }

    #[test]
    fn boxes() {
        assert_eq!(
            parse_box("-4,-4,-4,4,4,4"),
            Ok(Aabb {
                min: [-4.0; 3],
                max: [4.0; 3]
            })
        );
        assert!(matches!(
            parse_box("0,0,0,1,1"),
            Err(OptionError::BoxComponents { count: 5, .. })
        ));
        assert!(matches!(
            parse_box("0,0,0,1,-1,1"),
            Err(OptionError::InvertedBox { .. })
        ));
    }
}
