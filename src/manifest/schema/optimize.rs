//! The `optimize` table of a symmetric cell (docs/manifest.md, "Optimising a symmetric
//! cell"): the target volume fraction and/or surface-area density, and the solver's limits.
//!
//! Invariants: a checked [`Optimize`] has at least one target, `0 < volume_fraction < 1` (the
//! reachable range), a finite `surface_area > 0`, `1 ≤ max_iterations ≤` [`MAX_ITERATIONS`]
//! and a tolerance in `(0, 0.01]`; anything else is reported at its value.

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
    /// `optimize = { volume_fraction = φ, surface_area = S, max_iterations = K, tolerance = T }`.
    pub(super) fn optimize(&mut self, cell: &str, value: &Value<'_>) -> Option<Optimize> {
        let key = format!("cells.{cell}.optimize");
        let help = "write `optimize = { volume_fraction = 0.3 }`";
        let table = self.table(&key, value, help)?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &OPTIMIZE_KEYS, &within);
        let before = self.report.len();
        let fraction = match fields.get("volume_fraction") {
            None => Some(None),
            Some((_, v)) => self
                .optimized_fraction(&format!("{key}.volume_fraction"), v)
                .map(Some),
        };
        let area = match fields.get("surface_area") {
            None => Some(None),
            Some((_, v)) => self
                .optimized_area(&format!("{key}.surface_area"), v)
                .map(Some),
        };
        if fields.get("volume_fraction").is_none() && fields.get("surface_area").is_none() {
            let label = "missing `volume_fraction` or `surface_area`";
            self.missing(
                &fields,
                &value.span(),
                "volume_fraction",
                &within,
                label,
                help,
            );
        }
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
            surface_area: area?,
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

    /// A surface-area density: area of the level set in the element per element volume.
    fn optimized_area(&mut self, key: &str, value: &Value<'_>) -> Option<f64> {
        let n = self.number(key, value, "a number")?;
        if n > 0.0 && n.is_finite() {
            return Some(n);
        }
        let shown = self.raw(value);
        self.error(
            value.span(),
            &format!("`{key}` cannot be reached"),
            &format!("found `{shown}`; a surface area is positive"),
            Some(
                "give the area of the surface per volume of the reference element; \
                 `latticebuild cell` prints the cell's own, e.g. `surface_area = 2.4`",
            ),
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
            Some(
                "it is the allowed error of the volume fraction (relative for the surface area), \
                 like `tolerance = 1e-4`",
            ),
        );
        None
    }
}
