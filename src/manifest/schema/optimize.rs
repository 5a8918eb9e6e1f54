//! The `optimize` table of a symmetric cell (docs/manifest.md, "Optimising a symmetric
//! cell"): the target volume fraction and the solver's limits.
//!
//! Invariants: a checked [`Optimize`] has `0 < volume_fraction < 1` (the reachable range),
//! `1 ≤ max_iterations ≤` [`MAX_ITERATIONS`] and a tolerance in `(0, 0.01]`; anything else is
//! reported at its value.

use toml::de::DeValue;

use super::super::model::Optimize;
use super::keys::OPTIMIZE_KEYS;
use super::{Checker, Value};

/// Defaults and limits of the solver's keys.
pub(super) const DEFAULT_MAX_ITERATIONS: usize = 30;
pub(super) const MAX_ITERATIONS: i64 = 1000;
pub(super) const DEFAULT_TOLERANCE: f64 = 1e-4;
const MAX_TOLERANCE: f64 = 0.01;

impl Checker<'_, '_, '_> {
    /// `optimize = { volume_fraction = φ, max_iterations = K, tolerance = T }`.
    pub(super) fn optimize(&mut self, cell: &str, value: &Value<'_>) -> Option<Optimize> {
        let key = format!("cells.{cell}.optimize");
        let help = "write `optimize = { volume_fraction = 0.3 }`";
        let table = self.table(&key, value, help)?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &OPTIMIZE_KEYS, &within);
        let before = self.report.len();
        let fraction = match fields.get("volume_fraction") {
            None => {
                let label = "missing `volume_fraction`";
                self.missing(
                    &fields,
                    &value.span(),
                    "volume_fraction",
                    &within,
                    label,
                    help,
                );
                None
            }
            Some((_, v)) => self.optimized_fraction(&format!("{key}.volume_fraction"), v),
        };
        let max_iterations = match fields.get("max_iterations") {
            None => Some(DEFAULT_MAX_ITERATIONS),
            Some((_, v)) => self.iteration_count(&format!("{key}.max_iterations"), v),
        };
        let tolerance = match fields.get("tolerance") {
            None => Some(DEFAULT_TOLERANCE),
            Some((_, v)) => self.fraction_tolerance(&format!("{key}.tolerance"), v),
        };
        if self.report.len() > before {
            return None;
        }
        Some(Optimize {
            volume_fraction: fraction?,
            max_iterations: max_iterations?,
            tolerance: tolerance?,
        })
    }

    fn optimized_fraction(&mut self, key: &str, value: &Value<'_>) -> Option<f64> {
        let n = self.number(key, value, "a number")?;
        if n > 0.0 && n < 1.0 {
            return Some(n);
        }
        let shown = self.raw(value);
        self.error(
            value.span(),
            &format!("`{key}` cannot be reached"),
            &format!("found `{shown}`; the reachable range is 0 < volume_fraction < 1"),
            Some("give the solid's share of the reference element, e.g. `volume_fraction = 0.3`"),
        );
        None
    }

    fn iteration_count(&mut self, key: &str, value: &Value<'_>) -> Option<usize> {
        let DeValue::Integer(int) = value.get_ref() else {
            self.wrong_type(key, value, "an integer", None);
            return None;
        };
        match i64::from_str_radix(int.as_str(), int.radix()) {
            Ok(n) if (1..=MAX_ITERATIONS).contains(&n) => usize::try_from(n).ok(),
            _ => {
                let shown = self.raw(value);
                self.error(
                    value.span(),
                    &format!("`{key}` must be between 1 and {MAX_ITERATIONS}"),
                    &format!("found `{shown}`"),
                    Some("the default, 30, is enough for the runs measured"),
                );
                None
            }
        }
    }

    fn fraction_tolerance(&mut self, key: &str, value: &Value<'_>) -> Option<f64> {
        let t = self.positive_number(key, value, "a number")?;
        if t <= MAX_TOLERANCE {
            return Some(t);
        }
        let shown = self.raw(value);
        self.error(
            value.span(),
            &format!("`{key}` must be at most {MAX_TOLERANCE}"),
            &format!("found `{shown}`"),
            Some("it is the allowed error of the volume fraction, like `tolerance = 1e-4`"),
        );
        None
    }
}
