//! The schema of symmetric Fourier cells (docs/method.md §Symmetry groups to §Blends and
//! Minkowski combinations): `symmetry`, `fit` and the other
//! keys of a fitted cell, blends and Minkowski combinations, and outputs `over = "element"`.
//!
//! A child of `schema.rs` (it extends its `Checker`), in a file of its own because cells are
//! checked in two passes here:
//! 1. each cell's table on its own ([`Draft`]): types, ranges, names, and references to cells
//!    that are not defined at all or to the cell itself;
//! 2. the references between cells ([`Checker::resolve`]): every cell a blend or Minkowski
//!    combination uses must be symmetric, all of one group (which the combination takes), and
//!    the references must not form a cycle. Only then are the fit defaults known, since they
//!    depend on the group's dimension.
//!
//! Invariants:
//! - A reference to a cell that is defined but invalid is not reported again: the cell's own
//!   error is the one to fix. A cycle is reported once, at its first reference in the walk.
//! - References are followed with an explicit stack, so a long chain of blends cannot overflow
//!   the call stack.

use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;

use latticebuild_geom::expr::{ParseError, Var};
use latticebuild_geom::spelling;
use latticebuild_geom::symmetric::group::{Group, GroupError, Matrix, ReferenceElement};
use toml::de::{DeTable, DeValue};

use super::super::expression;
use super::super::model::{
    Cell, CellSource, FitResolution, GroupSpec, MinkowskiOp, Name, Optimize, Symmetric,
};
use super::keys::{
    BLEND_KEYS, CELL_KEYS, FIT_KEYS, GENERATOR_KEYS, MINKOWSKI_KEYS, SAMPLING_KEYS, SOURCE_KEYS,
    SYMMETRIC_KEYS,
};
use super::{Checker, Fields, Key, Value, list};

/// The named groups, in their canonical spelling.
pub(super) const GROUP_NAMES: [&str; 4] = ["D3", "D4", "Td", "Oh"];
const EXTENDS: [&str; 2] = ["mirror", "none"];
const MINKOWSKI_OPS: [&str; 2] = ["sum", "difference"];

/// The smallest fit resolution, and the largest per dimension of the group (the FFT grid has
/// N² or N³ points).
const MIN_FIT_N: i64 = 4;
const MAX_FIT_N_2D: usize = 8192;
const MAX_FIT_N_3D: usize = 512;
/// Default fit resolutions per dimension of the group.
const DEFAULT_FIT_N_2D: usize = 256;
const DEFAULT_FIT_N_3D: usize = 128;
const DEFAULT_TOLERANCE: f64 = 1e-3;
/// `n = "auto"` stops doubling here unless `max_n` says otherwise.
const DEFAULT_MAX_N_2D: usize = 4096;
const DEFAULT_MAX_N_3D: usize = 256;
/// The smallest `max_n`: automatic N starts at 32 and needs two sizes to compare.
const MIN_MAX_N: i64 = 64;

/// A valid group with the way it was written.
#[derive(Clone)]
pub(super) struct GroupDef {
    spec: GroupSpec,
    group: Group,
}

impl GroupDef {
    /// The group as shown in messages: `Oh`, or `a group of order 8 given by generators`.
    fn describe(&self) -> String {
        match &self.spec {
            GroupSpec::Named(name) => format!("`{name}`"),
            GroupSpec::Generators { .. } => {
                format!(
                    "a group of order {} given by generators",
                    self.group.order()
                )
            }
        }
    }
}

/// A cell named by a blend or Minkowski combination, where it was named.
struct Reference {
    name: String,
    span: Range<usize>,
}

/// `fit.n` (and `fit.max_n`) as written, kept until the group (and so the largest allowed
/// N) is known.
struct FitDraft {
    resolution: FitResolution,
    n_span: Range<usize>,
    n_raw: String,
    /// `max_n` when given: its value, span and text.
    max_n: Option<(usize, Range<usize>, String)>,
}

/// A cell whose table is valid on its own; its references are not resolved yet.
pub(super) struct Draft {
    name: Name,
    source: CellSource,
    /// The cells a combination uses, in order; empty for `tpms` and `expr` cells.
    references: Vec<Reference>,
    /// The span of a combination's `cells` value, and what to call it in messages.
    combination: Option<(Range<usize>, &'static str)>,
    /// The group of a `tpms` or `expr` cell with `symmetry`.
    group: Option<GroupDef>,
    fit: Option<FitDraft>,
    mirror: bool,
    symmetrize: bool,
    normal_to_faces: bool,
    offset: f64,
    invert: bool,
    optimize: Option<Optimize>,
}

/// Where a cell stands in the walk over references.
#[derive(Clone)]
enum Visit {
    New,
    OnStack,
    /// The cell's group, or `None` when it has none or its references failed.
    Done(Option<GroupDef>),
}

/// One combination being resolved in the walk over references.
struct Frame {
    cell: usize,
    /// The next of its references to look at.
    next: usize,
    /// The span of the reference that led here (none for a root of the walk).
    via: Option<Range<usize>>,
    /// The members' groups so far, with their names.
    members: Vec<(String, GroupDef)>,
    failed: bool,
}

impl Checker<'_, '_, '_> {
    // ---- pass 1: one cell table ----------------------------------------------------------

    /// Checks a cell's table on its own. `None` when anything was reported.
    pub(super) fn cell(
        &mut self,
        key: &Key<'_>,
        value: &Value<'_>,
        cells: &BTreeSet<&str>,
    ) -> Option<Draft> {
        let before = self.report.len();
        let name = key.get_ref().as_ref();
        self.check_name("cell", key);
        let help = format!("define it as a `[cells.{name}]` table");
        let table = self.table(&format!("cells.{name}"), value, &help)?;
        let within = format!("in cell `{name}`");
        let fields = self.fields(table, &CELL_KEYS, &within);
        let header = value.span();
        let path = |k: &str| format!("cells.{name}.{k}");

        let (given, source) = self.cell_source(name, &header, &fields, cells);
        let combination = match given.as_slice() {
            ["blend"] => Some("a blend"),
            ["minkowski"] => Some("a Minkowski combination"),
            _ => None,
        };

        let group = match (fields.get("symmetry"), combination) {
            (Some((k, _)), Some(kind)) => {
                self.error(
                    k.span(),
                    &format!("`{}` does not apply to {kind}", path("symmetry")),
                    "it takes the group of the cells it combines",
                    Some("remove `symmetry`"),
                );
                None
            }
            (Some((_, v)), None) => self.symmetry(name, v),
            (None, _) => None,
        };
        // Without `symmetry` (and not misspelled), the keys of a fitted cell do not apply.
        let symmetric = fields.contains_key("symmetry") || fields.misspelled("symmetry");
        let unfitted = !symmetric && source.is_some();
        self.misplaced_fit_keys(name, &fields, combination, unfitted);
        if let (Some(group), Some((_, sym)), Some((source, source_value))) =
            (&group, fields.get("symmetry"), &source)
        {
            self.check_planar(name, group, sym, source, source_value);
        }

        // Values of keys reported above as not applying are not checked as well.
        let applies = |k: &str| {
            let sampling = SAMPLING_KEYS.contains(&k);
            if combination.is_some() {
                !sampling
            } else {
                symmetric
            }
        };
        let value_of = |k: &str| fields.get(k).filter(|_| applies(k)).map(|(_, v)| *v);
        let fit = value_of("fit").and_then(|v| self.fit(name, v));
        let mirror = match value_of("extend") {
            None => Some(true),
            Some(v) => self.extend(&path("extend"), v),
        };
        let mut flag = |k: &str| match value_of(k) {
            None => Some(false),
            Some(v) => self.boolean(&path(k), v),
        };
        let (symmetrize, normal_to_faces, invert) =
            (flag("symmetrize"), flag("normal_to_faces"), flag("invert"));
        let offset = match value_of("offset") {
            None => Some(0.0),
            Some(v) => self.finite_number(&path("offset"), v),
        };
        let optimize = match value_of("optimize") {
            None => Some(None),
            Some(v) => self.optimize(name, v).map(Some),
        };
        let is_mesh = matches!(source, Some((CellSource::Mesh(_), _))) || given.contains(&"mesh");
        let mesh_options = self.mesh_options(name, &fields, is_mesh);
        let is_crystal =
            matches!(source, Some((CellSource::Crystal(_), _))) || given.contains(&"crystal");
        let crystal_options = self.crystal_options(name, &fields, is_crystal);
        let voxels = match &source {
            Some((CellSource::Voxels(v), value)) => {
                Some((*value, v.file.given.to_ascii_lowercase().ends_with(".raw")))
            }
            _ => None,
        };
        // The options of an invalid or conflicting `voxels` are not checked as well.
        let voxel_options = if given.contains(&"voxels") && voxels.is_none() {
            None
        } else {
            self.voxel_options(name, &fields, voxels)
        };
        let is_ps = matches!(source, Some((CellSource::Ps { .. }, _))) || given.contains(&"ps");
        let transform = self.ps_transform(name, &fields, is_crystal || is_ps);

        if self.report.len() > before {
            return None;
        }
        let (mut source, _) = source?;
        if let (CellSource::Mesh(mesh), Some((fit_placement, sampling))) =
            (&mut source, mesh_options)
        {
            mesh.fit_placement = fit_placement;
            mesh.sampling = sampling;
        }
        if let (CellSource::Voxels(cell), Some((raw, values))) = (&mut source, voxel_options) {
            cell.raw = raw;
            cell.values = values;
        }
        if let (CellSource::Crystal(crystal), Some(options)) = (&mut source, crystal_options) {
            options.apply(crystal);
        }
        match (&mut source, transform.flatten()) {
            (CellSource::Crystal(crystal), Some(t)) => crystal.transform = Some(t),
            (CellSource::Ps { transform, .. }, Some(t)) => *transform = Some(t),
            _ => {}
        }
        let (references, combination) = match &source {
            CellSource::Blend { .. } | CellSource::Minkowski { .. } => {
                let (refs, span) = references_of(&fields);
                (refs, Some((span, combination.unwrap_or("a blend"))))
            }
            _ => (Vec::new(), None),
        };
        Some(Draft {
            name: self.name(key),
            source,
            references,
            combination,
            group,
            fit,
            mirror: mirror?,
            symmetrize: symmetrize?,
            normal_to_faces: normal_to_faces?,
            offset: offset?,
            invert: invert?,
            optimize: optimize?,
        })
    }

    /// The cell's one source key, checked. Every source given is checked, so that its errors
    /// show even when there are several; the kinds given come back in file order.
    fn cell_source<'t, 'i>(
        &mut self,
        name: &str,
        header: &Range<usize>,
        fields: &Fields<'t, 'i>,
        cells: &BTreeSet<&str>,
    ) -> (Vec<&'static str>, Option<(CellSource, &'t Value<'i>)>) {
        let mut given: Vec<(&'static str, &Key<'_>, &'t Value<'i>)> = SOURCE_KEYS
            .iter()
            .filter_map(|k| fields.get(k).map(|(key, v)| (*k, *key, *v)))
            .collect();
        given.sort_by_key(|(_, key, _)| key.span().start);
        let checked: Vec<Option<CellSource>> = given
            .iter()
            .map(|(kind, _, v)| self.source(name, kind, v, cells))
            .collect();
        let source = match given.as_slice() {
            [] => {
                if !SOURCE_KEYS.iter().any(|k| fields.misspelled(k)) {
                    self.error(
                        header.clone(),
                        &format!("cell `{name}` has no source"),
                        "expected `tpms`, `expr`, `mesh`, `voxels`, `points`, `crystal`, `ps`, \
                         `blend` or `minkowski`",
                        Some(
                            "add `tpms = \"gyroid\"` for a library surface or \
                             `expr = \"...\"` for a formula in x, y, z",
                        ),
                    );
                }
                None
            }
            [(_, _, value)] => checked.into_iter().next().flatten().map(|s| (s, *value)),
            [(a, ..), (b, ..)] => {
                self.error(
                    header.clone(),
                    &format!("cell `{name}` has both `{a}` and `{b}`"),
                    "expected exactly one of them",
                    Some(&format!("remove `{a}` or `{b}`")),
                );
                None
            }
            several => {
                let names: Vec<&str> = several.iter().map(|(k, ..)| *k).collect();
                self.error(
                    header.clone(),
                    &format!("cell `{name}` has {} sources", names.len()),
                    "expected exactly one of them",
                    Some(&format!("keep one of {}", list(&names))),
                );
                None
            }
        };
        (given.iter().map(|(k, ..)| *k).collect(), source)
    }

    /// A fitted cell's keys where they do not apply: sampling keys on a combination (nothing
    /// is sampled), any of them on a cell without `symmetry` (`unfitted`).
    fn misplaced_fit_keys(
        &mut self,
        name: &str,
        fields: &Fields<'_, '_>,
        combination: Option<&str>,
        unfitted: bool,
    ) {
        let path = |k: &str| format!("cells.{name}.{k}");
        for k in SYMMETRIC_KEYS {
            let Some((key, _)) = fields.get(k) else {
                continue;
            };
            if let Some(kind) = combination {
                if SAMPLING_KEYS.contains(&k) {
                    self.error(
                        key.span(),
                        &format!("`{}` does not apply to {kind}", path(k)),
                        "it combines fitted cells: nothing is sampled",
                        Some(&format!("set `{k}` on the cells it combines")),
                    );
                }
            } else if unfitted {
                self.error(
                    key.span(),
                    &format!("`{}` applies only to cells with a `symmetry`", path(k)),
                    &format!("cell `{name}` has no `symmetry`"),
                    Some(&format!(
                        "add `symmetry = \"Oh\"` (or `\"D3\"`, `\"D4\"`, `\"Td\"`), or remove `{k}`"
                    )),
                );
            }
        }
    }

    /// One source key's value.
    fn source(
        &mut self,
        cell: &str,
        kind: &str,
        value: &Value<'_>,
        cells: &BTreeSet<&str>,
    ) -> Option<CellSource> {
        match kind {
            "tpms" => self.tpms_name(cell, value).map(CellSource::Tpms),
            "expr" => self.expression(cell, value).map(CellSource::Expr),
            "blend" => self.blend(cell, value, cells),
            "mesh" => self.mesh_source(cell, value),
            "voxels" => self.voxel_source(cell, value),
            "points" => self.points_source(cell, value),
            "crystal" => self.crystal_source(cell, value),
            "ps" => self.ps_source(cell, value),
            _ => self.minkowski(cell, value, cells),
        }
    }

    /// A 2D group needs a planar source: no TPMS surface, and no `z` in an expression.
    fn check_planar(
        &mut self,
        cell: &str,
        group: &GroupDef,
        symmetry: &Value<'_>,
        source: &CellSource,
        source_value: &Value<'_>,
    ) {
        if group.group.dimension() != 2 {
            return;
        }
        let shown = group.describe();
        match source {
            CellSource::Mesh(_) => self.error(
                symmetry.span(),
                &format!("2D group for a mesh cell in `cells.{cell}.symmetry`"),
                &format!("{shown} is a 2D group, but a triangle mesh bounds a 3D solid"),
                Some("use `symmetry = \"Oh\"` or `\"Td\"`"),
            ),
            CellSource::Voxels(_) | CellSource::Points(_) => self.error(
                symmetry.span(),
                &format!("2D group for a voxel or point cell in `cells.{cell}.symmetry`"),
                &format!("{shown} is a 2D group, but a voxel image or point cloud is 3D"),
                Some("use `symmetry = \"Oh\"` or `\"Td\"`"),
            ),
            CellSource::Tpms(_) => self.error(
                symmetry.span(),
                &format!("2D group for a TPMS cell in `cells.{cell}.symmetry`"),
                &format!("{shown} is a 2D group, but the TPMS library's surfaces are 3D"),
                Some("use `symmetry = \"Oh\"` or `\"Td\"`, or write the cell as an `expr` in x and y"),
            ),
            CellSource::Expr(text) => {
                let uses_z = latticebuild_geom::expr::parse(text)
                    .is_ok_and(|e| e.var_mask() & (1 << Var::Z.index()) != 0);
                if uses_z {
                    let span = first_identifier(text, "z").unwrap_or(0..text.len());
                    let err = ParseError {
                        span,
                        message: format!("`z` in a cell of the 2D group {shown}"),
                        help: Some("a 2D cell is a function of x and y only".into()),
                    };
                    let key = format!("cells.{cell}.expr");
                    let sources = self.report.sources();
                    let (at, diag) =
                        expression::error_at(sources, &key, &source_value.span(), text, err);
                    self.report.at(&at, diag);
                }
            }
            _ => {}
        }
    }

    // ---- symmetry ----------------------------------------------------------------------------

    fn symmetry(&mut self, cell: &str, value: &Value<'_>) -> Option<GroupDef> {
        let key = format!("cells.{cell}.symmetry");
        match value.get_ref() {
            DeValue::String(text) => {
                let text: &str = text.as_ref();
                if let Some(name) = GROUP_NAMES.iter().find(|g| g.eq_ignore_ascii_case(text)) {
                    let group = Group::by_name(name).ok()?;
                    return Some(GroupDef {
                        spec: GroupSpec::Named(name.to_string()),
                        group,
                    });
                }
                let help = match spelling::closest(text, GROUP_NAMES) {
                    Some(close) => format!("did you mean `{close}`?"),
                    None => format!(
                        "expected one of {}, or `{{ generators = [...] }}`",
                        list(&GROUP_NAMES)
                    ),
                };
                self.error(
                    value.span(),
                    &format!("unknown symmetry group `{text}` in `{key}`"),
                    "not a known group",
                    Some(&help),
                );
                None
            }
            DeValue::Table(table) => self.generators(&key, value, table),
            _ => {
                let help = "write `symmetry = \"Oh\"` (or `\"D3\"`, `\"D4\"`, `\"Td\"`), or \
                            `symmetry = { generators = [...], dimension = 3 }`";
                self.wrong_type(&key, value, "a group name or a table", Some(help));
                None
            }
        }
    }

    fn generators(
        &mut self,
        key: &str,
        value: &Value<'_>,
        table: &DeTable<'_>,
    ) -> Option<GroupDef> {
        let within = format!("in `{key}`");
        let fields = self.fields(table, &GENERATOR_KEYS, &within);
        let dimension = match fields.get("dimension") {
            None => Some(None),
            Some((_, v)) => {
                let dkey = format!("{key}.dimension");
                match self.integer(&dkey, v, "an integer")? {
                    d @ (2 | 3) => Some(Some(d as usize)),
                    _ => {
                        let shown = self.raw(v);
                        self.error(
                            v.span(),
                            &format!("`{dkey}` must be 2 or 3"),
                            &format!("found `{shown}`"),
                            None,
                        );
                        None
                    }
                }
            }
        };
        let Some((_, list_value)) = fields.get("generators") else {
            let help = "add `generators = [[[0, -1, 0], [1, 0, 0], [0, 0, 1]], ...]` \
                        (integer matrices, rows first)";
            self.missing(
                &fields,
                &value.span(),
                "generators",
                &within,
                "missing `generators`",
                help,
            );
            return None;
        };
        let gkey = format!("{key}.generators");
        let DeValue::Array(items) = list_value.get_ref() else {
            self.wrong_type(&gkey, list_value, "an array of integer matrices", None);
            return None;
        };
        let matrices: Vec<Option<(usize, Matrix)>> =
            items.iter().map(|item| self.matrix(&gkey, item)).collect();
        let dimension = dimension?;
        let matrices: Vec<(usize, Matrix)> = matrices.into_iter().collect::<Option<_>>()?;
        let dimension = dimension
            .or_else(|| matrices.first().map(|(size, _)| *size))
            .unwrap_or(3);
        let mut ok = true;
        for ((size, _), item) in matrices.iter().zip(items.iter()) {
            if *size == 2 && dimension == 3 {
                ok = false;
                self.error(
                    item.span(),
                    &format!("a 2×2 matrix in the 3D group of `{key}`"),
                    "expected a 3×3 matrix",
                    Some("give 3×3 matrices, or set `dimension = 2`"),
                );
            }
        }
        if !ok {
            return None;
        }
        let generators: Vec<Matrix> = matrices.into_iter().map(|(_, m)| m).collect();
        match Group::from_generators(dimension, &generators) {
            Ok(group) => Some(GroupDef {
                spec: GroupSpec::Generators {
                    dimension,
                    generators,
                },
                group,
            }),
            Err(err) => {
                let at = |index: usize| items.get(index).map_or(list_value.span(), |v| v.span());
                let finite = format!("the generators in `{gkey}` do not form a finite group");
                let orthogonal = "each generator must be a rotation or reflection: a signed \
                                  permutation matrix (an integer matrix M with Mᵀ·M = I)";
                let (span, message, label, help) = match err {
                    GroupError::NotEmbedded { index, .. } => (
                        at(index),
                        format!("a 3D matrix in the 2D group of `{key}`"),
                        "outside the upper-left 2×2 block it must equal the identity".to_string(),
                        Some("write 2×2 matrices for `dimension = 2`".to_string()),
                    ),
                    GroupError::NotInvertible { index, det } => (
                        at(index),
                        finite,
                        format!("determinant {det}: not invertible over the integers"),
                        Some(orthogonal.to_string()),
                    ),
                    GroupError::NotOrthogonal { index, .. } => (
                        at(index),
                        finite,
                        "not orthogonal, so its powers never repeat".to_string(),
                        Some(orthogonal.to_string()),
                    ),
                    GroupError::TooLarge { bound } => (
                        list_value.span(),
                        finite,
                        format!("more than {bound} elements"),
                        None,
                    ),
                    other => (list_value.span(), finite, other.to_string(), None),
                };
                self.error(span, &message, &label, help.as_deref());
                None
            }
        }
    }

    /// A 2×2 or 3×3 integer matrix, rows first, embedded in a 3×3 one; with its size.
    fn matrix(&mut self, key: &str, value: &Value<'_>) -> Option<(usize, Matrix)> {
        let expected = "a matrix (an array of rows of integers)";
        let DeValue::Array(rows) = value.get_ref() else {
            self.wrong_type(key, value, expected, None);
            return None;
        };
        let size = rows.len();
        if size != 2 && size != 3 {
            self.error(
                value.span(),
                &format!("`{key}` must hold 2×2 or 3×3 matrices"),
                &format!("found {size} rows"),
                None,
            );
            return None;
        }
        let mut matrix = latticebuild_geom::symmetric::group::IDENTITY;
        let mut ok = true;
        for (r, row) in rows.iter().enumerate() {
            let DeValue::Array(entries) = row.get_ref() else {
                self.wrong_type(key, row, "a row (an array of integers)", None);
                ok = false;
                continue;
            };
            if entries.len() != size {
                self.error(
                    row.span(),
                    &format!("a matrix in `{key}` must be square"),
                    &format!("expected {size} entries, found {}", entries.len()),
                    None,
                );
                ok = false;
                continue;
            }
            for (c, entry) in entries.iter().enumerate() {
                match self.integer(key, entry, "an integer") {
                    Some(v) => match i32::try_from(v) {
                        Ok(v) => matrix[r][c] = v,
                        Err(_) => {
                            let shown = self.raw(entry);
                            self.error(
                                entry.span(),
                                &format!("`{key}` entry is out of range"),
                                &format!("found `{shown}`"),
                                None,
                            );
                            ok = false;
                        }
                    },
                    None => ok = false,
                }
            }
        }
        ok.then_some((size, matrix))
    }

    // ---- fitting options -----------------------------------------------------------------

    fn fit(&mut self, cell: &str, value: &Value<'_>) -> Option<FitDraft> {
        let key = format!("cells.{cell}.fit");
        let help =
            "write `fit = { n = 64 }` or `fit = { n = \"auto\", tolerance = 1e-3, max_n = 256 }`";
        let table = self.table(&key, value, help)?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &FIT_KEYS, &within);
        let nkey = format!("{key}.n");
        let Some((_, n)) = fields.get("n") else {
            self.missing(&fields, &value.span(), "n", &within, "missing `n`", help);
            return None;
        };
        let n_raw = self.raw(n);
        let auto = match n.get_ref() {
            DeValue::String(text) => {
                let text: &str = text.as_ref();
                if !text.eq_ignore_ascii_case("auto") {
                    let help = match spelling::closest(text, ["auto"]) {
                        Some(close) => format!("did you mean `{close}`?"),
                        None => "give an even number of samples per axis, like `n = 64`, or \
                                 `n = \"auto\"`"
                            .to_string(),
                    };
                    self.error(
                        n.span(),
                        &format!("unknown value `{text}` in `{nkey}`"),
                        "expected an even integer or `\"auto\"`",
                        Some(&help),
                    );
                    return None;
                }
                true
            }
            DeValue::Integer(_) => false,
            _ => {
                self.wrong_type(&nkey, n, "an even integer or `\"auto\"`", None);
                return None;
            }
        };
        let tolerance = fields.get("tolerance").map(|(k, v)| (*k, *v));
        let max_n_field = fields.get("max_n").map(|(k, v)| (*k, *v));
        let mut max_n = None;
        let resolution = if auto {
            let tolerance = match tolerance {
                None => DEFAULT_TOLERANCE,
                Some((_, v)) => self.positive_number(&format!("{key}.tolerance"), v, "a number")?,
            };
            if let Some((_, v)) = max_n_field {
                max_n = Some(self.max_n(&format!("{key}.max_n"), v)?);
            }
            // The group's default bound is set once the group is known (`finish`).
            FitResolution::Auto {
                tolerance,
                max_n: max_n.as_ref().map_or(0, |m| m.0),
            }
        } else {
            for (name, field) in [("tolerance", tolerance), ("max_n", max_n_field)] {
                if let Some((k, _)) = field {
                    self.error(
                        k.span(),
                        &format!("`{key}.{name}` applies only to `n = \"auto\"`"),
                        &format!("`n` is fixed at `{n_raw}`"),
                        Some(&format!("remove `{name}`, or set `n = \"auto\"`")),
                    );
                }
            }
            let value = self.integer(&nkey, n, "an even integer or `\"auto\"`")?;
            if value < MIN_FIT_N || value % 2 != 0 {
                self.error(
                    n.span(),
                    &format!("`{nkey}` must be even and at least {MIN_FIT_N}"),
                    &format!("found `{n_raw}`"),
                    Some("N is the number of samples per axis of the fit, like `n = 64`"),
                );
                return None;
            }
            // Beyond any group's limit; the limit of this cell's group is checked later.
            FitResolution::Fixed(usize::try_from(value).unwrap_or(usize::MAX))
        };
        (auto || tolerance.is_none() && max_n_field.is_none()).then_some(FitDraft {
            resolution,
            n_span: n.span(),
            n_raw,
            max_n,
        })
    }

    /// `fit.max_n`: a power of two, at least [`MIN_MAX_N`] (the group's upper limit is
    /// checked in `finish`).
    fn max_n(&mut self, key: &str, value: &Value<'_>) -> Option<(usize, Range<usize>, String)> {
        let raw = self.raw(value);
        let v = self.integer(key, value, "a power of two, like `max_n = 256`")?;
        let v = usize::try_from(v).ok().filter(|&v| v >= MIN_MAX_N as usize);
        match v {
            Some(v) if v.is_power_of_two() => Some((v, value.span(), raw)),
            _ => {
                self.error(
                    value.span(),
                    &format!("`{key}` must be a power of two, at least {MIN_MAX_N}"),
                    &format!("found `{raw}`"),
                    Some(
                        "automatic N doubles from 32, so it can stop at 64, 128, 256, 512 (and \
                         up to 8192 for a 2D group)",
                    ),
                );
                None
            }
        }
    }

    /// `extend`: whether the extended domain is filled by mirroring.
    fn extend(&mut self, key: &str, value: &Value<'_>) -> Option<bool> {
        let text = self.string(key, value)?;
        match text {
            "mirror" => return Some(true),
            "none" => return Some(false),
            _ => {}
        }
        let help = match spelling::closest(text, EXTENDS) {
            Some(close) => format!("did you mean `{close}`?"),
            None => format!("expected one of {}", list(&EXTENDS)),
        };
        self.error(
            value.span(),
            &format!("unknown extension `{text}` in `{key}`"),
            "not a way to extend the domain",
            Some(&help),
        );
        None
    }

    /// An integer, reported when it is not one or beyond `i64`.
    fn integer(&mut self, key: &str, value: &Value<'_>, expected: &str) -> Option<i64> {
        let DeValue::Integer(int) = value.get_ref() else {
            self.wrong_type(key, value, expected, None);
            return None;
        };
        let parsed = i64::from_str_radix(int.as_str(), int.radix()).ok();
        if parsed.is_none() {
            let shown = self.raw(value);
            self.error(
                value.span(),
                &format!("`{key}` is out of range"),
                &format!("found `{shown}`"),
                None,
            );
        }
        parsed
    }

    // ---- combinations --------------------------------------------------------------------

    fn blend(
        &mut self,
        cell: &str,
        value: &Value<'_>,
        cells: &BTreeSet<&str>,
    ) -> Option<CellSource> {
        let key = format!("cells.{cell}.blend");
        let example = "{ cells = [\"a\", \"b\"], weights = [0.5, 0.5] }";
        let table = self.table(&key, value, &format!("write it as `blend = {example}`"))?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &BLEND_KEYS, &within);
        let names = self.member_list(cell, &key, value, &fields, cells);
        let weights = match fields.get("weights") {
            None => {
                let help = "add `weights = [0.5, 0.5]`, one per cell";
                self.missing(
                    &fields,
                    &value.span(),
                    "weights",
                    &within,
                    "missing `weights`",
                    help,
                );
                None
            }
            Some((_, v)) => {
                let wkey = format!("{key}.weights");
                match v.get_ref() {
                    DeValue::Array(items) => {
                        let weights: Vec<Option<f64>> =
                            items.iter().map(|w| self.finite_number(&wkey, w)).collect();
                        let weights: Option<Vec<f64>> = weights.into_iter().collect();
                        if let (Some(w), Some((_, cells_len))) = (&weights, &names)
                            && w.len() != *cells_len
                        {
                            self.error(
                                v.span(),
                                &format!("`{wkey}` must have one weight per cell"),
                                &format!("found {} weights for {cells_len} cells", w.len()),
                                None,
                            );
                            None
                        } else {
                            weights
                        }
                    }
                    _ => {
                        self.wrong_type(&wkey, v, "an array of numbers", None);
                        None
                    }
                }
            }
        };
        let (names, _) = names?;
        Some(CellSource::Blend {
            cells: names?,
            weights: weights?,
        })
    }

    fn minkowski(
        &mut self,
        cell: &str,
        value: &Value<'_>,
        cells: &BTreeSet<&str>,
    ) -> Option<CellSource> {
        let key = format!("cells.{cell}.minkowski");
        let example = "{ op = \"sum\", cells = [\"a\", \"b\"] }";
        let table = self.table(&key, value, &format!("write it as `minkowski = {example}`"))?;
        let within = format!("in `{key}`");
        let fields = self.fields(table, &MINKOWSKI_KEYS, &within);
        let op = match fields.get("op") {
            None => {
                let help = "add `op = \"sum\"` or `op = \"difference\"`";
                self.missing(&fields, &value.span(), "op", &within, "missing `op`", help);
                None
            }
            Some((_, v)) => {
                let okey = format!("{key}.op");
                self.string(&okey, v).and_then(|text| match text {
                    "sum" => Some(MinkowskiOp::Sum),
                    "difference" => Some(MinkowskiOp::Difference),
                    _ => {
                        let help = match spelling::closest(text, MINKOWSKI_OPS) {
                            Some(close) => format!("did you mean `{close}`?"),
                            None => format!("expected one of {}", list(&MINKOWSKI_OPS)),
                        };
                        self.error(
                            v.span(),
                            &format!("unknown operation `{text}` in `{okey}`"),
                            "not a Minkowski operation",
                            Some(&help),
                        );
                        None
                    }
                })
            }
        };
        let names = self.member_list(cell, &key, value, &fields, cells);
        if let (Some((_, count)), Some((_, v))) = (&names, fields.get("cells"))
            && *count != 2
        {
            self.error(
                v.span(),
                &format!("`{key}.cells` must name exactly 2 cells"),
                &format!("found {count}"),
                Some("a Minkowski sum or difference combines two cells"),
            );
            return None;
        }
        let names = names?.0?;
        let [a, b]: [String; 2] = names.try_into().ok()?;
        Some(CellSource::Minkowski {
            op: op?,
            cells: [a, b],
        })
    }

    /// A combination's `cells`: with their count when the value is an array (the names only
    /// when every one is valid).
    fn member_list(
        &mut self,
        cell: &str,
        key: &str,
        value: &Value<'_>,
        fields: &Fields<'_, '_>,
        cells: &BTreeSet<&str>,
    ) -> Option<(Option<Vec<String>>, usize)> {
        let within = format!("in `{key}`");
        let Some((_, list_value)) = fields.get("cells") else {
            let help =
                "add `cells = [\"a\", \"b\"]`, naming `[cells.NAME]` tables with a `symmetry`";
            self.missing(
                fields,
                &value.span(),
                "cells",
                &within,
                "missing `cells`",
                help,
            );
            return None;
        };
        let ckey = format!("{key}.cells");
        let DeValue::Array(items) = list_value.get_ref() else {
            self.wrong_type(&ckey, list_value, "an array of cell names", None);
            return None;
        };
        if items.is_empty() {
            self.error(
                list_value.span(),
                &format!("`{ckey}` is empty"),
                "expected at least one cell",
                None,
            );
            return None;
        }
        let mut names = Some(Vec::new());
        for item in items.iter() {
            let name = self.cell_reference(&ckey, item, cells);
            let name = name.filter(|name| {
                if name != cell {
                    return true;
                }
                self.error(
                    item.span(),
                    &format!("cell `{cell}` refers to itself in `{ckey}`"),
                    "a cell cannot use itself",
                    Some("name other cells"),
                );
                false
            });
            names = names.zip(name).map(|(mut all, n)| {
                all.push(n);
                all
            });
        }
        Some((names, items.len()))
    }

    // ---- pass 2: references between cells -----------------------------------------------

    /// Resolves the references between the drafts (in source order) and builds the cells.
    pub(super) fn resolve(&mut self, drafts: Vec<Draft>) -> BTreeMap<String, Cell> {
        let index: BTreeMap<&str, usize> = drafts
            .iter()
            .enumerate()
            .map(|(i, d)| (d.name.text.as_str(), i))
            .collect();
        let mut visits = vec![Visit::New; drafts.len()];
        // The first reference of each cycle reported, so that a cycle entered twice (a cell
        // naming the same member twice) is reported once.
        let mut cycles = BTreeSet::new();
        for root in 0..drafts.len() {
            if !matches!(visits[root], Visit::New) {
                continue;
            }
            if drafts[root].combination.is_none() {
                visits[root] = Visit::Done(drafts[root].group.clone());
                continue;
            }
            visits[root] = Visit::OnStack;
            let mut stack = vec![Frame {
                cell: root,
                next: 0,
                via: None,
                members: Vec::new(),
                failed: false,
            }];
            while let Some(top) = stack.last_mut() {
                let draft = &drafts[top.cell];
                if let Some(reference) = draft.references.get(top.next) {
                    top.next += 1;
                    // A cell that is defined but invalid has its own error already.
                    let Some(&target) = index.get(reference.name.as_str()) else {
                        top.failed = true;
                        continue;
                    };
                    match visits[target].clone() {
                        Visit::Done(group) => {
                            let member = self.member(&drafts, draft, target, reference, group);
                            let top = stack.last_mut().expect("the frame being walked");
                            match member {
                                Some(member) => top.members.push(member),
                                None => top.failed = true,
                            }
                        }
                        Visit::OnStack => {
                            self.cycle(&drafts, &stack, target, reference, &mut cycles);
                            if let Some(top) = stack.last_mut() {
                                top.failed = true;
                            }
                        }
                        Visit::New if drafts[target].combination.is_none() => {
                            let group = drafts[target].group.clone();
                            visits[target] = Visit::Done(group.clone());
                            let member = self.member(&drafts, draft, target, reference, group);
                            let top = stack.last_mut().expect("the frame being walked");
                            match member {
                                Some(member) => top.members.push(member),
                                None => top.failed = true,
                            }
                        }
                        Visit::New => {
                            visits[target] = Visit::OnStack;
                            stack.push(Frame {
                                cell: target,
                                next: 0,
                                via: Some(reference.span.clone()),
                                members: Vec::new(),
                                failed: false,
                            });
                        }
                    }
                    continue;
                }
                let Some(frame) = stack.pop() else {
                    break;
                };
                let group = self.common_group(&drafts[frame.cell], &frame);
                visits[frame.cell] = Visit::Done(group.clone());
                if let Some(parent) = stack.last_mut() {
                    // A combination that failed has reported why (or its member has).
                    match group {
                        Some(group) => parent
                            .members
                            .push((drafts[frame.cell].name.text.clone(), group)),
                        None => parent.failed = true,
                    }
                }
            }
        }
        let mut cells = BTreeMap::new();
        for (draft, visit) in drafts.into_iter().zip(visits) {
            let group = match visit {
                Visit::Done(group) => group,
                _ => None,
            };
            if let Some(cell) = self.finish(draft, group) {
                cells.insert(cell.name.text.clone(), cell);
            }
        }
        cells
    }

    /// A member of a combination, or `None` (reported when it is a cell without a group).
    fn member(
        &mut self,
        drafts: &[Draft],
        combination: &Draft,
        target: usize,
        reference: &Reference,
        group: Option<GroupDef>,
    ) -> Option<(String, GroupDef)> {
        let member = &drafts[target];
        if let Some(group) = group {
            return Some((member.name.text.clone(), group));
        }
        if member.combination.is_none() {
            let kind = combination.combination.as_ref().map_or("a blend", |c| c.1);
            let name = &member.name.text;
            self.error(
                reference.span.clone(),
                &format!(
                    "cell `{name}` in `cells.{}.cells` has no `symmetry`",
                    combination_key(combination)
                ),
                &format!("{kind} combines symmetric cells"),
                Some(&format!(
                    "add `symmetry = \"Oh\"` (or its group) to `[cells.{name}]`"
                )),
            );
        }
        None
    }

    /// Reports the cycle closed by `reference` (from the top frame to `target`, on the stack).
    fn cycle(
        &mut self,
        drafts: &[Draft],
        stack: &[Frame],
        target: usize,
        reference: &Reference,
        reported: &mut BTreeSet<(usize, usize)>,
    ) {
        let Some(start) = stack.iter().position(|f| f.cell == target) else {
            return;
        };
        let mut names: Vec<&str> = stack[start..]
            .iter()
            .map(|f| drafts[f.cell].name.text.as_str())
            .collect();
        names.push(drafts[target].name.text.as_str());
        let path = names
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(" → ");
        // Shown at the cycle's first reference: from the cell where the walk entered it.
        let span = stack
            .get(start + 1)
            .and_then(|f| f.via.clone())
            .unwrap_or_else(|| reference.span.clone());
        if !reported.insert((span.start, span.end)) {
            return;
        }
        let (from, to) = (names[0], names[1]);
        self.error(
            span,
            &format!("reference cycle between cells: {path}"),
            &format!("`{from}` uses `{to}` here"),
            Some("a blend or Minkowski combination cannot use itself, directly or through other cells"),
        );
    }

    /// The group all members of a combination share, or `None` (reported when they differ).
    fn common_group(&mut self, draft: &Draft, frame: &Frame) -> Option<GroupDef> {
        if frame.failed {
            return None;
        }
        let ((first_name, first), rest) = frame.members.split_first()?;
        let other = rest.iter().find(|(_, g)| g.group != first.group);
        if let Some((name, group)) = other {
            let (span, kind) = draft.combination.clone()?;
            let what = if kind == "a blend" {
                "blend"
            } else {
                "Minkowski combination"
            };
            self.error(
                span,
                &format!(
                    "{what} of cells with different groups in `cells.{}.cells`",
                    combination_key(draft)
                ),
                &format!(
                    "`{first_name}` has group {}, `{name}` has group {}",
                    first.describe(),
                    group.describe()
                ),
                Some("combine cells of one group: different groups have different bases"),
            );
            return None;
        }
        Some(first.clone())
    }

    /// Builds a cell from its draft and its group (`None`: not symmetric, or failed).
    fn finish(&mut self, draft: Draft, group: Option<GroupDef>) -> Option<Cell> {
        let symmetric = match group {
            Some(group) => {
                let dimension = group.group.dimension();
                let (default, max) = if dimension == 2 {
                    (DEFAULT_FIT_N_2D, MAX_FIT_N_2D)
                } else {
                    (DEFAULT_FIT_N_3D, MAX_FIT_N_3D)
                };
                let default_max_n = if dimension == 2 {
                    DEFAULT_MAX_N_2D
                } else {
                    DEFAULT_MAX_N_3D
                };
                let n = match &draft.fit {
                    None => FitResolution::Fixed(default),
                    Some(FitDraft {
                        resolution: FitResolution::Auto { tolerance, .. },
                        max_n,
                        ..
                    }) => {
                        if let Some((value, span, raw)) = max_n
                            && *value > max
                        {
                            let key = format!("cells.{}.fit.max_n", draft.name.text);
                            self.error(
                                span.clone(),
                                &format!("`{key}` must be at most {max} for a {dimension}D group"),
                                &format!("found `{raw}`"),
                                Some(&format!(
                                    "the fit samples N^{dimension} points; {max} is the largest grid"
                                )),
                            );
                            return None;
                        }
                        FitResolution::Auto {
                            tolerance: *tolerance,
                            max_n: max_n.as_ref().map_or(default_max_n, |m| m.0),
                        }
                    }
                    Some(fit) => {
                        if let FitResolution::Fixed(n) = fit.resolution
                            && n > max
                        {
                            let key = format!("cells.{}.fit.n", draft.name.text);
                            self.error(
                                fit.n_span.clone(),
                                &format!("`{key}` must be at most {max} for a {dimension}D group"),
                                &format!("found `{}`", fit.n_raw),
                                Some(&format!(
                                    "the fit samples N^{dimension} points; use `n = \"auto\"` \
                                     to choose N by a tolerance"
                                )),
                            );
                            return None;
                        }
                        fit.resolution
                    }
                };
                Some(Symmetric {
                    group: group.spec,
                    n,
                    mirror: draft.mirror,
                    symmetrize: draft.symmetrize,
                    normal_to_faces: draft.normal_to_faces,
                    offset: draft.offset,
                    invert: draft.invert,
                    optimize: draft.optimize,
                })
            }
            // A combination always has a group; without one it failed (and was reported).
            None if draft.combination.is_some() => return None,
            None => None,
        };
        Some(Cell {
            name: draft.name,
            source: draft.source,
            symmetric,
        })
    }

    // ---- outputs over the reference element ----------------------------------------------

    /// `over`: whether the output covers the cell's reference element (`None`: invalid).
    pub(super) fn over(&mut self, key: &str, value: &Value<'_>) -> Option<bool> {
        let text = self.string(key, value)?;
        if text == "element" {
            return Some(true);
        }
        let help = match spelling::closest(text, ["element"]) {
            Some(close) => format!("did you mean `{close}`?"),
            None => "omit `over` to fill `domain` with repeated cells".to_string(),
        };
        self.error(
            value.span(),
            &format!("unknown value `{text}` in `{key}`"),
            "expected `\"element\"`",
            Some(&help),
        );
        None
    }

    /// A planar domain (`[x, y]` corners) is the plane of a 2D cell: reports any other cell.
    pub(super) fn check_planar_cell(
        &mut self,
        output: &str,
        domain: &Value<'_>,
        cell: &str,
        cells: &BTreeMap<String, Cell>,
    ) {
        let Some(found) = cells.get(cell) else {
            return;
        };
        let dimension = match found.symmetric.as_ref().map(|s| &s.group) {
            Some(GroupSpec::Named(name)) => Group::by_name(name).ok().map(|g| g.dimension()),
            Some(GroupSpec::Generators { dimension, .. }) => Some(*dimension),
            None => None,
        };
        if dimension == Some(2) {
            return;
        }
        let why = match dimension {
            None => format!("cell `{cell}` has no `symmetry`, so it is a 3D field"),
            Some(_) => format!("cell `{cell}` has a 3D group"),
        };
        self.error(
            domain.span(),
            &format!("the planar `outputs.{output}.domain` needs a 2D cell"),
            &why,
            Some(
                "give the corners as [x, y, z] to fill a box, or use a cell with a 2D \
                 `symmetry` (`\"D3\"`, `\"D4\"` or generators with `dimension = 2`)",
            ),
        );
    }

    /// The bounding box of the reference element of `cell` (`None` when `cell` is invalid, or
    /// reported when it has no reference element).
    pub(super) fn element_box(
        &mut self,
        output: &str,
        over: &Value<'_>,
        cell: &str,
        cells: &BTreeMap<String, Cell>,
    ) -> Option<([f64; 3], [f64; 3])> {
        let symmetric = cells.get(cell)?.symmetric.as_ref();
        let element = match symmetric.map(|s| &s.group) {
            Some(GroupSpec::Named(name)) => Group::by_name(name)
                .ok()
                .and_then(|g| g.reference_element()),
            _ => None,
        };
        let Some(element) = element else {
            let why = match symmetric {
                None => format!("cell `{cell}` has no `symmetry`"),
                Some(_) => format!("the group of cell `{cell}` is given by generators"),
            };
            self.error(
                over.span(),
                &format!("`outputs.{output}.over = \"element\"` needs a reference element"),
                &format!("{why}, so it has no reference element"),
                Some(&format!(
                    "give `[cells.{cell}]` a `symmetry` of `\"D3\"`, `\"D4\"`, `\"Td\"` or \
                     `\"Oh\"`, or remove `over`"
                )),
            );
            return None;
        };
        Some(bounding_box(element))
    }
}

/// The bounding box of a reference element, in reference coordinates (z is 0 for 2D elements).
fn bounding_box(element: ReferenceElement) -> ([f64; 3], [f64; 3]) {
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for vertex in element.vertices() {
        for axis in 0..3 {
            min[axis] = min[axis].min(vertex[axis]);
            max[axis] = max[axis].max(vertex[axis]);
        }
    }
    (min, max)
}

/// The references of a valid combination, with the span of its `cells` value.
fn references_of(fields: &Fields<'_, '_>) -> (Vec<Reference>, Range<usize>) {
    let table = ["blend", "minkowski"]
        .iter()
        .find_map(|k| fields.get(k))
        .and_then(|(_, v)| match v.get_ref() {
            DeValue::Table(t) => Some(t),
            _ => None,
        });
    let cells = table.and_then(|t| {
        t.iter()
            .find(|(k, _)| k.get_ref().as_ref() == "cells")
            .map(|(_, v)| v)
    });
    let Some(cells) = cells else {
        return (Vec::new(), 0..0);
    };
    let refs = match cells.get_ref() {
        DeValue::Array(items) => items
            .iter()
            .filter_map(|item| match item.get_ref() {
                DeValue::String(s) => Some(Reference {
                    name: s.to_string(),
                    span: item.span(),
                }),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    };
    (refs, cells.span())
}

/// `NAME.blend` or `NAME.minkowski`, for naming a combination's keys.
fn combination_key(draft: &Draft) -> String {
    let table = match draft.source {
        CellSource::Minkowski { .. } => "minkowski",
        _ => "blend",
    };
    format!("{}.{table}", draft.name.text)
}

/// The span of the first identifier `name` in an expression (identifiers as the expression
/// lexer reads them: a letter or `_`, then letters, digits and `_`; numbers are skipped whole).
fn first_identifier(text: &str, name: &str) -> Option<Range<usize>> {
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        if b.is_ascii_digit() || b == b'.' {
            i += 1;
            while i < bytes.len() {
                let after_exponent = matches!(bytes[i - 1], b'e' | b'E');
                let c = bytes[i];
                let word = c.is_ascii_alphanumeric() || c == b'_' || c == b'.';
                if word || (after_exponent && matches!(c, b'+' | b'-')) {
                    i += 1;
                } else {
                    break;
                }
            }
        } else if b.is_ascii_alphabetic() || b == b'_' {
            let start = i;
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                i += 1;
            }
            if &text[start..i] == name {
                return Some(start..i);
            }
        } else {
            i += 1;
        }
    }
    None
}
