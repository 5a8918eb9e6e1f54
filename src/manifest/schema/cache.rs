//! `[cache] max_size`: how much the stage cache of this manifest may keep.
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariants:
//! - `max_size` is a whole number of bytes ≥ 0, or a string of a number and a unit (`"4GB"`,
//!   `"1.5 GiB"`, `"500MB"`; units of 1000 and of 1024, case-insensitive); anything else is an
//!   error at the value naming the forms accepted.
//! - The default is [`DEFAULT_MAX_SIZE`].

use toml::de::DeValue;

use super::keys::CACHE_KEYS;
use super::{Checker, Value};

/// `[cache] max_size` when not given: 4 GB (four full-size tiled meshes).
pub(crate) const DEFAULT_MAX_SIZE: u64 = 4_000_000_000;

/// The units `max_size` accepts, with their bytes.
const UNITS: [(&str, u64); 9] = [
    ("b", 1),
    ("kb", 1_000),
    ("mb", 1_000_000),
    ("gb", 1_000_000_000),
    ("tb", 1_000_000_000_000),
    ("kib", 1 << 10),
    ("mib", 1 << 20),
    ("gib", 1 << 30),
    ("tib", 1 << 40),
];

/// Bytes of a size written `NUMBER UNIT` (`"4GB"`, `"1.5 GiB"`); `None` if it is not one.
pub(crate) fn parse_size(text: &str) -> Option<u64> {
    let text = text.trim();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(split);
    let number: f64 = number.parse().ok()?;
    let unit = unit.trim().to_ascii_lowercase();
    let (_, bytes) = UNITS.iter().find(|(name, _)| *name == unit)?;
    let size = number * *bytes as f64;
    (size.is_finite() && size < u64::MAX as f64).then(|| size.round() as u64)
}

impl Checker<'_, '_, '_> {
    /// `[cache]`: the size limit in bytes (`None` where invalid).
    pub(super) fn cache(&mut self, value: &Value<'_>) -> Option<u64> {
        let table = self.table("cache", value, "write it as a `[cache]` table")?;
        let fields = self.fields(table, &CACHE_KEYS, "in `[cache]`");
        let Some((_, value)) = fields.get("max_size") else {
            return Some(DEFAULT_MAX_SIZE);
        };
        let size = match value.get_ref() {
            DeValue::Integer(int) => i64::from_str_radix(int.as_str(), int.radix())
                .ok()
                .and_then(|n| u64::try_from(n).ok()),
            DeValue::String(text) => parse_size(text),
            _ => {
                self.wrong_type(
                    "cache.max_size",
                    value,
                    "a number of bytes or a size string",
                    Some("write `max_size = \"4GB\"` or `max_size = 4000000000`"),
                );
                return None;
            }
        };
        if size.is_none() {
            let shown = self.raw(value);
            self.error(
                value.span(),
                "`cache.max_size` is not a size",
                &format!("found `{shown}`"),
                Some(
                    "write a whole number of bytes (≥ 0) or a number and a unit: \"500MB\", \
                     \"4GB\", \"1.5GiB\" (B, kB, MB, GB, TB, KiB, MiB, GiB, TiB)",
                ),
            );
        }
        size
    }
}

#[cfg(test)]
mod tests {
    use super::parse_size;

    #[test]
    fn sizes_are_a_number_and_a_unit_of_1000_or_1024() {
        assert_eq!(parse_size("4GB"), Some(4_000_000_000));
        assert_eq!(parse_size("1.5 GiB"), Some(1_610_612_736));
        assert_eq!(parse_size("500mb"), Some(500_000_000));
        assert_eq!(parse_size("0B"), Some(0));
        assert_eq!(parse_size("12 kib"), Some(12 * 1024));
        for bad in ["", "GB", "4", "4 GBs", "-1GB", "1e3GB", "4 G B", "1.2.3MB"] {
            assert_eq!(parse_size(bad), None, "{bad}");
        }
    }
}
