//! The schema of periodic-surface cells: `crystal = "file.cif"` with `species` and
//! `reconstruct = { tolerance, max_scale, include_images, optimize }`, and explicit models
//! `ps = { terms = [{ moment, scale, vector = [a, b, c, θ] }, …] }`.
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariants:
//! - No IO: the crystal file's name is resolved against the manifest's directory and its
//!   extension checked; whether it exists is checked when a manifest is loaded from disk.
//! - `species` and `reconstruct` are errors on a cell without `crystal`, naming what is
//!   missing; every term of `ps` is checked, and each error points at the term's value.
//! - `transform` is an error on a cell that is neither `ps` nor `crystal`; a given transform
//!   has finite numbers, non-zero scale factors and a non-zero rotation axis.

use latticebuild_geom::periodic::PsTerm;
use toml::de::DeValue;

use super::super::model::{CellSource, CrystalCell, PsTransform};
use super::keys::{PS_KEYS, RECONSTRUCT_KEYS, ROTATE_KEYS, TERM_KEYS, TRANSFORM_KEYS};
use super::meshes::FileKind;
use super::{Checker, Fields, Value};

/// File extensions of the crystal readers, lower case.
const CRYSTAL_FILES: FileKind = FileKind {
    extensions: &["cif", "xyz", "extxyz"],
    noun: "crystal",
    help: "give a CIF file, or extended XYZ with a `Lattice=\"…\"`",
};
/// The largest `max_scale` (scales 1, 2, …, 64: seven steps of the search).
const MAX_SCALE: i64 = 64;

/// `species` and `reconstruct` of a crystal cell.
pub(super) struct CrystalOptions {
    species: Option<String>,
    tolerance: f64,
    max_scale: u32,
    include_images: bool,
    optimize: bool,
}

impl CrystalOptions {
    pub(super) fn apply(self, cell: &mut CrystalCell) {
        cell.species = self.species;
        cell.tolerance = self.tolerance;
        cell.max_scale = self.max_scale;
        cell.include_images = self.include_images;
        cell.optimize = self.optimize;
    }
}

impl Checker<'_, '_, '_> {
    /// `crystal = "file"`: a cell source; its options are filled in by
    /// [`Checker::crystal_options`].
    pub(super) fn crystal_source(&mut self, cell: &str, value: &Value<'_>) -> Option<CellSource> {
        let key = format!("cells.{cell}.crystal");
        let given = self.string(&key, value)?;
        let file = self.input_file(&format!("`{key}`"), given, value.span(), &CRYSTAL_FILES)?;
        Some(CellSource::Crystal(CrystalCell {
            file,
            species: None,
            tolerance: 1e-9,
            max_scale: 8,
            include_images: false,
            optimize: false,
            transform: None,
        }))
    }

    /// `species` and `reconstruct` of a cell: the options of a crystal cell, and an error for
    /// each of them given to another cell.
    pub(super) fn crystal_options(
        &mut self,
        cell: &str,
        fields: &Fields<'_, '_>,
        is_crystal: bool,
    ) -> Option<CrystalOptions> {
        let path = |k: &str| format!("cells.{cell}.{k}");
        if !is_crystal {
            for k in ["species", "reconstruct"] {
                if let Some((key, _)) = fields.get(k) {
                    self.error(
                        key.span(),
                        &format!("`{}` applies only to crystal cells", path(k)),
                        &format!("cell `{cell}` has no `crystal`"),
                        Some(&format!(
                            "remove `{k}`, or give the cell a `crystal = \"structure.cif\"`"
                        )),
                    );
                }
            }
            return None;
        }
        let species = match fields.get("species") {
            None => Some(None),
            Some((_, v)) => {
                let key = path("species");
                let text = self.string(&key, v);
                match text {
                    Some(t) if !t.is_empty() && t.chars().all(|c| c.is_ascii_alphabetic()) => {
                        Some(Some(t.to_string()))
                    }
                    Some(t) => {
                        self.error(
                            v.span(),
                            &format!("`{key}` must be an element symbol"),
                            &format!("found `{t}`"),
                            Some("write the element as in the file, like `species = \"Si\"`"),
                        );
                        None
                    }
                    None => None,
                }
            }
        };
        let mut options = CrystalOptions {
            species: None,
            tolerance: 1e-9,
            max_scale: 8,
            include_images: false,
            optimize: false,
        };
        let mut ok = true;
        if let Some((_, v)) = fields.get("reconstruct") {
            let key = path("reconstruct");
            let example = "{ tolerance = 1e-9, max_scale = 8 }";
            match self.table(&key, v, &format!("write it as `reconstruct = {example}`")) {
                None => ok = false,
                Some(table) => {
                    let within = format!("in `{key}`");
                    let inner = self.fields(table, &RECONSTRUCT_KEYS, &within);
                    let sub = |k: &str| format!("{key}.{k}");
                    if let Some((_, t)) = inner.get("tolerance") {
                        match self.positive_number(&sub("tolerance"), t, "a number") {
                            Some(t) => options.tolerance = t,
                            None => ok = false,
                        }
                    }
                    if let Some((_, m)) = inner.get("max_scale") {
                        match self.max_scale(&sub("max_scale"), m) {
                            Some(m) => options.max_scale = m,
                            None => ok = false,
                        }
                    }
                    for (k, slot) in [
                        ("include_images", &mut options.include_images),
                        ("optimize", &mut options.optimize),
                    ] {
                        if let Some((_, b)) = inner.get(k) {
                            match self.boolean(&sub(k), b) {
                                Some(b) => *slot = b,
                                None => ok = false,
                            }
                        }
                    }
                }
            }
        }
        options.species = species?;
        ok.then_some(options)
    }

    fn max_scale(&mut self, key: &str, value: &Value<'_>) -> Option<u32> {
        let DeValue::Integer(int) = value.get_ref() else {
            self.wrong_type(key, value, "an integer", None);
            return None;
        };
        let n = i64::from_str_radix(int.as_str(), int.radix()).ok();
        match n {
            Some(n) if (1..=MAX_SCALE).contains(&n) => u32::try_from(n).ok(),
            _ => {
                let shown = self.raw(value);
                self.error(
                    value.span(),
                    &format!("`{key}` must be between 1 and {MAX_SCALE}"),
                    &format!("found `{shown}`"),
                    Some("the search tries scales 1, 2, 4, … up to `max_scale`"),
                );
                None
            }
        }
    }

    /// `ps = { terms = [...] }`: every term checked.
    pub(super) fn ps_source(&mut self, cell: &str, value: &Value<'_>) -> Option<CellSource> {
        let key = format!("cells.{cell}.ps");
        let example = "{ terms = [{ moment = 1.0, scale = 1, vector = [1, 0, 0, 0] }] }";
        let table = self.table(&key, value, &format!("write it as `ps = {example}`"))?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &PS_KEYS, &within);
        let Some((_, terms)) = fields.get("terms") else {
            let help = format!("write it as `ps = {example}`");
            self.missing(
                &fields,
                &value.span(),
                "terms",
                &within,
                "missing `terms`",
                &help,
            );
            return None;
        };
        let tkey = format!("{key}.terms");
        let DeValue::Array(items) = terms.get_ref() else {
            self.wrong_type(&tkey, terms, "an array of term tables", None);
            return None;
        };
        if items.is_empty() {
            self.error(
                terms.span(),
                &format!("`{tkey}` is empty"),
                "expected at least one term",
                Some("add `{ moment = 1.0, scale = 1, vector = [1, 0, 0, 0] }`"),
            );
            return None;
        }
        let checked: Vec<Option<PsTerm>> = items
            .iter()
            .enumerate()
            .map(|(i, item)| self.ps_term(&format!("{tkey}[{i}]"), item))
            .collect();
        checked
            .into_iter()
            .collect::<Option<Vec<_>>>()
            .map(|terms| CellSource::Ps {
                terms,
                transform: None,
            })
    }

    fn ps_term(&mut self, key: &str, value: &Value<'_>) -> Option<PsTerm> {
        let example = "{ moment = 1.0, scale = 1, vector = [1, 0, 0, 0] }";
        let table = self.table(key, value, &format!("write each term as `{example}`"))?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &TERM_KEYS, &within);
        let moment = match fields.get("moment") {
            Some((_, v)) => self.finite_number(&format!("{key}.moment"), v),
            None => {
                let help = "add `moment = 1.0` (the term's coefficient)";
                self.missing(
                    &fields,
                    &value.span(),
                    "moment",
                    &within,
                    "missing `moment`",
                    help,
                );
                None
            }
        };
        let scale = match fields.get("scale") {
            Some((_, v)) => self.positive_number(&format!("{key}.scale"), v, "a number"),
            None => Some(1.0),
        };
        let vector = match fields.get("vector") {
            Some((_, v)) => self.ps_vector(&format!("{key}.vector"), v),
            None => {
                let help = "add `vector = [a, b, c, θ]` (the basis plane a x + b y + c z + θ)";
                self.missing(
                    &fields,
                    &value.span(),
                    "vector",
                    &within,
                    "missing `vector`",
                    help,
                );
                None
            }
        };
        Some(PsTerm {
            moment: moment?,
            scale: scale?,
            vector: vector?,
        })
    }

    /// `[a, b, c, θ]`, or `[a, b, c]` with θ = 0.
    fn ps_vector(&mut self, key: &str, value: &Value<'_>) -> Option<[f64; 4]> {
        let DeValue::Array(items) = value.get_ref() else {
            self.wrong_type(key, value, "an array of 4 numbers [a, b, c, θ]", None);
            return None;
        };
        if items.len() != 3 && items.len() != 4 {
            self.error(
                value.span(),
                &format!("`{key}` must have 4 values [a, b, c, θ] (or 3, with θ = 0)"),
                &format!("found {}", items.len()),
                None,
            );
            return None;
        }
        let mut vector = [0.0; 4];
        let mut ok = true;
        for (slot, item) in vector.iter_mut().zip(items.iter()) {
            match self.finite_number(key, item) {
                Some(v) => *slot = v,
                None => ok = false,
            }
        }
        ok.then_some(vector)
    }

    /// `transform = { scale, rotate, translate }` of a `ps` or `crystal` cell: `Some(None)`
    /// when absent, `None` after an error (also when given to another cell).
    pub(super) fn ps_transform(
        &mut self,
        cell: &str,
        fields: &Fields<'_, '_>,
        applies: bool,
    ) -> Option<Option<PsTransform>> {
        let key = format!("cells.{cell}.transform");
        let Some(&(k, value)) = fields.get("transform") else {
            return Some(None);
        };
        let example = "{ translate = [0.5, 0, 0], rotate = { axis = [0, 0, 1], angle = 45 } }";
        if !applies {
            self.error(
                k.span(),
                &format!("`{key}` applies only to `ps` and `crystal` cells"),
                &format!("cell `{cell}` has neither `ps` nor `crystal`"),
                Some("remove `transform`, or give the cell `ps = { terms = [...] }` or `crystal = \"structure.cif\"`"),
            );
            return None;
        }
        let table = self.table(&key, value, &format!("write it as `transform = {example}`"))?;
        let within = format!("in `{key}`");
        let inner = self.fields(table, &TRANSFORM_KEYS, &within);
        if table.is_empty() {
            self.error(
                value.span(),
                &format!("`{key}` is empty"),
                "expected at least one of `scale`, `rotate`, `translate`",
                Some(&format!(
                    "write it as `transform = {example}`, or remove it"
                )),
            );
            return None;
        }
        let sub = |k: &str| format!("{key}.{k}");
        let mut transform = PsTransform::IDENTITY;
        let mut ok = true;
        if let Some((_, v)) = inner.get("scale") {
            match self.scale_factors(&sub("scale"), v) {
                Some(s) => transform.scale = s,
                None => ok = false,
            }
        }
        if let Some((_, v)) = inner.get("rotate") {
            match self.rotation(&sub("rotate"), v) {
                Some((axis, angle)) => {
                    transform.axis = axis;
                    transform.angle_degrees = angle;
                }
                None => ok = false,
            }
        }
        if let Some((_, v)) = inner.get("translate") {
            let help = "write it as `translate = [0.5, 0, 0]` (cell coordinates, period 1)";
            match self.vec3(&sub("translate"), v, help) {
                Some(t) => transform.translate = t,
                None => ok = false,
            }
        }
        ok.then_some(Some(transform))
    }

    /// `rotate = { axis = [x, y, z], angle = DEG }`: the axis and the angle in degrees.
    fn rotation(&mut self, key: &str, value: &Value<'_>) -> Option<([f64; 3], f64)> {
        let example = "{ axis = [0, 0, 1], angle = 90 }";
        let table = self.table(key, value, &format!("write it as `rotate = {example}`"))?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &ROTATE_KEYS, &within);
        let mut parts = [None, None];
        for (slot, (k, help)) in parts.iter_mut().zip([
            ("axis", "add `axis = [0, 0, 1]` (the axis of the rotation)"),
            (
                "angle",
                "add `angle = 90` (degrees, counter-clockwise about the axis)",
            ),
        ]) {
            match fields.get(k) {
                Some((_, v)) => *slot = Some(v),
                None => {
                    let label = format!("missing `{k}`");
                    self.missing(&fields, &value.span(), k, &within, &label, help);
                }
            }
        }
        let [Some(axis), Some(angle)] = parts else {
            return None;
        };
        let axis_value = axis;
        let axis = self.vec3(
            &format!("{key}.axis"),
            axis_value,
            "write it as `axis = [0, 0, 1]`",
        );
        let angle = self.transform_number(
            &format!("{key}.angle"),
            angle,
            "a number",
            "give the angle in degrees, like `angle = 90`",
        );
        let axis = axis?;
        let length = axis.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(length.is_finite() && length > 0.0) {
            let shown = self.raw(axis_value);
            self.error(
                axis_value.span(),
                &format!("`{key}.axis` must not be zero"),
                &format!("found `{shown}`"),
                Some("give the direction to rotate about, like `axis = [0, 0, 1]`"),
            );
            return None;
        }
        Some((axis, angle?))
    }

    /// `scale = s` or `[sx, sy, sz]`: non-zero finite factors.
    fn scale_factors(&mut self, key: &str, value: &Value<'_>) -> Option<[f64; 3]> {
        let help = "give a non-zero factor, like `scale = 2` or `scale = [1, 1, 2]`";
        let factor = |this: &mut Self, v: &Value<'_>, expected: &str| {
            let n = this.transform_number(key, v, expected, help)?;
            if n == 0.0 {
                this.error(
                    v.span(),
                    &format!("`{key}` must not be zero"),
                    "a zero factor flattens the cell",
                    Some(help),
                );
                return None;
            }
            Some(n)
        };
        let DeValue::Array(items) = value.get_ref() else {
            return factor(self, value, "a number or an array of 3 numbers").map(|n| [n; 3]);
        };
        if items.len() != 3 {
            self.three_values(key, value, items.len(), help);
            return None;
        }
        let [x, y, z] = [&items[0], &items[1], &items[2]].map(|v| factor(self, v, "a number"));
        Some([x?, y?, z?])
    }

    /// An array of exactly 3 finite numbers.
    fn vec3(&mut self, key: &str, value: &Value<'_>, help: &str) -> Option<[f64; 3]> {
        let DeValue::Array(items) = value.get_ref() else {
            self.wrong_type(key, value, "an array of 3 numbers [x, y, z]", Some(help));
            return None;
        };
        if items.len() != 3 {
            self.three_values(key, value, items.len(), help);
            return None;
        }
        let [x, y, z] = [&items[0], &items[1], &items[2]]
            .map(|v| self.transform_number(key, v, "a number", help));
        Some([x?, y?, z?])
    }

    fn three_values(&mut self, key: &str, value: &Value<'_>, len: usize, help: &str) {
        self.error(
            value.span(),
            &format!("`{key}` must have 3 values (x, y, z)"),
            &format!("found {len}"),
            Some(help),
        );
    }

    /// A finite number of a transform; each error has `help`.
    fn transform_number(
        &mut self,
        key: &str,
        value: &Value<'_>,
        expected: &str,
        help: &str,
    ) -> Option<f64> {
        match value.get_ref() {
            DeValue::Integer(_) => {}
            DeValue::Float(float) => {
                if float.as_str().parse::<f64>().is_ok_and(|x| !x.is_finite()) {
                    let shown = self.raw(value);
                    self.error(
                        value.span(),
                        &format!("`{key}` must be a finite number"),
                        &format!("found `{shown}`"),
                        Some(help),
                    );
                    return None;
                }
            }
            _ => {
                self.wrong_type(key, value, expected, Some(help));
                return None;
            }
        }
        self.number(key, value, expected)
    }
}
