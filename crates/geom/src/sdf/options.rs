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
//! sample counts are whole numbers of at least 2 per axis; a box has `min < max` on every axis.

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
    #[error("`{text}` has {count} components; a box needs six: x0,y0,z0,x1,y1,z1")]
    BoxComponents { text: String, count: usize },
    #[error("`{text}`: the lower corner must be below the upper one on every axis")]
    InvertedBox { text: String },
}

/// Largest sample count accepted along one axis or in total, far beyond any memory.
const MAX_SAMPLES: f64 = 1e15;

/// Samples per axis from `-s` text: one total, or three counts.
pub fn parse_samples(text: &str) -> Result<[usize; 3], OptionError> {
    let values = args::constants(text).map_err(OptionError::NotANumber)?;
    let whole = |v: f64| -> Result<u64, OptionError> {
        if v != v.trunc() || !(0.0..=MAX_SAMPLES).contains(&v) {
            return Err(OptionError::NotWhole {
                text: text.to_string(),
            });
        }
        Ok(v as u64)
    };
    let counts = match values.as_slice() {
        [total] => spread_samples(whole(*total)?),
        [a, b, c] => [whole(*a)?, whole(*b)?, whole(*c)?].map(|v| v as usize),
        _ => {
            return Err(OptionError::SampleComponents {
                text: text.to_string(),
                count: values.len(),
            });
        }
    };
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
