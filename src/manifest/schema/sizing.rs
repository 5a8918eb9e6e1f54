//! Solids sized in the user's terms: `wall` (shells) and `grow` (inside/outside) in model
//! units, and `volume_fraction`, for plain and tiled outputs alike.
//!
//! Invariants:
//! - At most one of `wall`, `grow`, `volume_fraction` is given, and never beside the field
//!   value it replaces (`thickness` for shells, `offset` for inside/outside); an eccentric
//!   shell's `offset` stays the field level its sheet is centred on.
//! - `wall` applies to shells only, `grow` to inside/outside only; without `solid`, `wall`
//!   means `solid = "shell"`.
//! - Uniform values are checked here: `wall > 0`, `grow` finite, `0 < volume_fraction < 1`
//!   (the reachable range). Graded ones (strings) are expressions in x, y, z — or, on a
//!   scaffold read from a file, `nodedata:NAME` — checked as `thickness`/`offset` are; their
//!   range is checked where they are evaluated.

use latticebuild_geom::field::Solid;
use toml::de::DeValue;

use super::super::expression;
use super::super::model::{NodalValue, Sizing, Target};
use super::keys::SIZING_KEYS;
use super::{Checker, Fields, Value};

/// Where a graded value may come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum GradedFrom {
    /// A plain output: expressions in x, y, z only.
    Block,
    /// A tiled output; node data too unless the scaffold is a generated grid.
    Scaffold { is_grid: bool },
}

impl Checker<'_, '_, '_> {
    /// The solid and its sizing when `wall`, `grow` or `volume_fraction` is given; `None`
    /// when none is (the field-valued keys then size the solid), `Some(None)` when something
    /// was reported.
    pub(super) fn sized_solid(
        &mut self,
        output: &str,
        fields: &Fields<'_, '_>,
        from: GradedFrom,
    ) -> Option<Option<(Solid, Sizing)>> {
        let given: Vec<(&str, &Value<'_>)> = SIZING_KEYS
            .iter()
            .filter_map(|k| fields.get(k).map(|(_, v)| (*k, *v)))
            .collect();
        let (&(key, value), rest) = given.split_first()?;
        let path = |k: &str| format!("outputs.{output}.{k}");
        let mut ok = true;
        for (other, v) in rest {
            self.error(
                v.span(),
                &format!("both `{key}` and `{other}` given in output `{output}`"),
                "one value sizes the solid",
                Some(&format!("remove `{other}` or `{key}`")),
            );
            ok = false;
        }
        let kind = match fields.get("solid") {
            None if key == "wall" => Some("shell"),
            None => Some("inside"),
            Some((_, v)) => self.solid_kind(&path("solid"), v),
        };
        let Some(kind) = kind else {
            return Some(None);
        };
        let shell = kind == "shell" || kind == "eccentric_shell";
        let misplaced = match key {
            "wall" if !shell => Some(format!(
                "`wall` is a shell's thickness, but `solid` is `{kind}`: use `grow` to move \
                 the surface of an `{kind}` solid"
            )),
            "grow" if shell => Some(format!(
                "`grow` moves the surface of an inside or outside solid, but `solid` is \
                 `{kind}`: use `wall` for the shell's thickness"
            )),
            _ => None,
        };
        if let Some(help) = misplaced {
            self.error(
                value.span(),
                &format!("`{}` does not apply to `solid = \"{kind}\"`", path(key)),
                "wrong solid for this key",
                Some(&help),
            );
            ok = false;
        }
        // The field value the key replaces.
        let replaced = if shell { "thickness" } else { "offset" };
        if let Some((_, v)) = fields.get(replaced) {
            self.error(
                v.span(),
                &format!("both `{key}` and `{replaced}` given in output `{output}`"),
                &format!(
                    "`{key}` sizes the solid in the user's terms, `{replaced}` in field values"
                ),
                Some(&format!("remove `{replaced}`")),
            );
            ok = false;
        }
        if kind == "shell"
            && let Some((_, v)) = fields.get("offset")
        {
            self.error(
                v.span(),
                &format!("`{}` does not apply to `solid = \"shell\"`", path("offset")),
                "a shell is centred on the surface",
                Some("use `solid = \"eccentric_shell\"` for a shell around an offset level set"),
            );
            ok = false;
        }
        let level = match (kind, fields.get("offset")) {
            ("eccentric_shell", Some((_, v))) => self.finite_number(&path("offset"), v),
            ("eccentric_shell", None) => {
                self.error(
                    value.span(),
                    &format!(
                        "`solid = \"eccentric_shell\"` in output `{output}` needs an `offset`"
                    ),
                    "the field level the sheet is centred on",
                    Some("add `offset = 0.3`, or use `solid = \"shell\"` for the surface itself"),
                );
                None
            }
            _ => Some(0.0),
        };
        let amount = self.sizing_value(&path(key), key, value, from);
        if !ok {
            return Some(None);
        }
        let (level, amount) = (level?, amount?);
        let uniform = match &amount {
            Amount::Uniform(v) => *v,
            Amount::Graded(_) => 0.0,
        };
        let graded = match amount {
            Amount::Uniform(_) => None,
            Amount::Graded(g) => Some(g),
        };
        let solid = match (kind, key) {
            (_, "volume_fraction") => match kind {
                "inside" => Solid::Inside { offset: 0.0 },
                "outside" => Solid::Outside { offset: 0.0 },
                _ => Solid::Shell { thickness: 0.0 },
            },
            ("outside", _) => Solid::Outside { offset: -uniform },
            ("inside", _) => Solid::Inside { offset: uniform },
            _ => Solid::Shell { thickness: uniform },
        };
        let sizing = match key {
            "volume_fraction" => Sizing::VolumeFraction {
                level,
                target: match graded {
                    None => Target::Uniform(uniform),
                    Some(g) => Target::Graded(g),
                },
            },
            _ => Sizing::Length { level, graded },
        };
        Some(Some((solid, sizing)))
    }

    /// A uniform number (checked against the key's range) or a graded string.
    fn sizing_value(
        &mut self,
        path: &str,
        key: &str,
        value: &Value<'_>,
        from: GradedFrom,
    ) -> Option<Amount> {
        if let DeValue::String(_) = value.get_ref() {
            return match from {
                GradedFrom::Scaffold { is_grid } => {
                    self.nodal(path, value, is_grid).map(Amount::Graded)
                }
                GradedFrom::Block => self.block_expression(path, value).map(Amount::Graded),
            };
        }
        let expected = "a number or an expression string";
        let n = match key {
            "wall" => self.positive_number(path, value, expected)?,
            _ => self.number(path, value, expected)?,
        };
        if key == "volume_fraction" && !(n > 0.0 && n < 1.0) {
            let shown = self.raw(value);
            self.error(
                value.span(),
                &format!("`{path}` cannot be reached"),
                &format!("found `{shown}`; the reachable range is 0 < volume_fraction < 1"),
                Some("give the solid's share of the volume, e.g. `volume_fraction = 0.2` for 20 %"),
            );
            return None;
        }
        Some(Amount::Uniform(n))
    }

    /// An expression in x, y, z for a plain output (node data needs a scaffold).
    fn block_expression(&mut self, key: &str, value: &Value<'_>) -> Option<NodalValue> {
        let text = self.string(key, value)?;
        if text.trim_start().starts_with("nodedata:") {
            self.error(
                value.span(),
                &format!("`{key}` reads node data, but the output has no scaffold"),
                "node data belongs to a scaffold's nodes",
                Some("write an expression in x, y, z instead, e.g. `\"0.3 + x / 100\"`"),
            );
            return None;
        }
        match expression::check_expression(text) {
            Ok(()) => Some(NodalValue::Expr(text.to_string())),
            Err(err) => {
                let sources = self.report.sources();
                let (span, diag) = expression::error_at(sources, key, &value.span(), text, err);
                self.report.at(&span, diag);
                None
            }
        }
    }
}

enum Amount {
    Uniform(f64),
    Graded(NodalValue),
}
