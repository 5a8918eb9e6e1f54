//! The schema of tiling: `[scaffolds.NAME]` (`mesh = "file"` or `grid = { … }`) and outputs
//! that tile a symmetric cell into a scaffold (`scaffold`, `cell` or `cell = { blend, by }`,
//! graded `thickness`/`offset`, `resolution`, `skin`, and for 2D scaffolds `extrude` or
//! `thickness_normal`).
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariants:
//! - No IO and no geometry: a scaffold file's name is resolved and its extension checked
//!   (through the shared `Checker::input_file`); whether it exists is checked on load, and its
//!   element kind, node data and element quality only when the `tile` stage reads it.
//! - The group check happens as early as the facts allow: a cell without a named group, or a
//!   transition between two groups, is an error here; so is a group that does not match a
//!   grid's element (a mesh file's element is checked by the stage, naming the file).
//! - `extrude`/`thickness_normal` are positive and exclusive; on a grid they need 2D elements
//!   and `skin` needs 3D ones (a mesh file's dimension is checked by the stage).
//! - Expressions (`by`, `thickness`, `offset`) are parsed here, their errors shown inside the
//!   string; `"nodedata:NAME"` on a generated grid is an error (grids have no node data).
//! - Keys of box outputs (`domain`, `samples`, `within`, …) beside `scaffold` are errors
//!   naming what to write instead.

use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
use std::path::PathBuf;

use latticebuild_geom::field::Solid;
use latticebuild_geom::scaffold::ElementKind;
use latticebuild_geom::spelling;
use toml::de::DeValue;

use super::super::expression;
use super::super::model::{
    Cell, Continuity, GroupSpec, MAX_GRID_ELEMENTS, NodalValue, Scaffold, ScaffoldGrid,
    ScaffoldSource, Sizing, Thicken, TiledOutput, TiledTransition, tiling_group,
};
use super::keys::{ALL_KEYS, GRID_KEYS, SCAFFOLD_KEYS, THICKEN_KEYS, TILED_KEYS, TRANSITION_KEYS};
use super::meshes::FileKind;
use super::{Checker, Fields, Key, Value};

const GRID_ELEMENTS: [&str; 4] = ["hex", "tet", "quad", "tri"];
const CONTINUITIES: [&str; 2] = ["c0", "c1"];
pub(crate) const DEFAULT_RESOLUTION: usize = 12;
const MAX_RESOLUTION: i64 = 256;
const NODE_DATA_PREFIX: &str = "nodedata:";

pub(super) const SCAFFOLD_FILES: FileKind = FileKind {
    extensions: &["msh", "vtk", "vtu", "inp", "obj", "off"],
    noun: "scaffold mesh",
    help: "export the scaffold from the mesher as Gmsh `.msh`, VTK `.vtk`/`.vtu`, Abaqus \
           `.inp`, or (surfaces) OBJ/OFF",
};

/// Whether an output table tiles a scaffold (and is checked by [`Checker::tiled_output`]).
pub(super) fn is_tiled_output(value: &Value<'_>) -> bool {
    matches!(value.get_ref(), DeValue::Table(t) if t.keys().any(|k| k.get_ref() == "scaffold"))
}

/// The scaffold files, for `watch` and the load-time existence check.
pub(super) fn scaffold_files(scaffolds: &BTreeMap<String, Scaffold>) -> Vec<PathBuf> {
    scaffolds
        .values()
        .filter_map(|s| match &s.source {
            ScaffoldSource::Mesh(file) => Some(file.path.clone()),
            ScaffoldSource::Grid(_) => None,
        })
        .collect()
}

/// What the tiled output's checks need to know about the manifest's other tables.
pub(super) struct TilingContext<'c> {
    /// Every scaffold name defined (valid or not), for reference checks.
    pub scaffold_names: &'c BTreeSet<&'c str>,
    pub scaffolds: &'c BTreeMap<String, Scaffold>,
    pub cell_names: &'c BTreeSet<&'c str>,
    pub cells: &'c BTreeMap<String, Cell>,
}

impl Checker<'_, '_, '_> {
    /// `continuity = "c0" | "c1"` (default `c0`); `c1` on a grid needs quad or hex elements.
    fn continuity(
        &mut self,
        name: &str,
        fields: &Fields<'_, '_>,
        source: Option<&ScaffoldSource>,
    ) -> Option<Continuity> {
        let Some((_, value)) = fields.get("continuity") else {
            return Some(Continuity::C0);
        };
        let key = format!("scaffolds.{name}.continuity");
        let continuity = match self.choice(&key, value, &CONTINUITIES, "continuity")? {
            "c1" => Continuity::C1,
            _ => Continuity::C0,
        };
        if let (Continuity::C1, Some(ScaffoldSource::Grid(grid))) = (continuity, source)
            && !matches!(grid.element, ElementKind::Hex8 | ElementKind::Quad4)
        {
            self.error(
                value.span(),
                &format!(
                    "`{key} = \"c1\"` needs quad or hex elements, but the grid has {} elements",
                    grid.element.name()
                ),
                "C¹ maps are made for quadrilaterals and hexahedra",
                Some("use `element = \"hex\"` (or `\"quad\"`), or leave `continuity` out"),
            );
            return None;
        }
        Some(continuity)
    }

    /// `[scaffolds.NAME]`: exactly one of `mesh` and `grid`.
    pub(super) fn scaffold(&mut self, key: &Key<'_>, value: &Value<'_>) -> Option<Scaffold> {
        let before = self.report.len();
        let name = key.get_ref().as_ref();
        self.check_name("scaffold", key);
        let help = format!("define it as a `[scaffolds.{name}]` table");
        let table = self.table(&format!("scaffolds.{name}"), value, &help)?;
        let within = format!("in scaffold `{name}`");
        let fields = self.fields(table, &SCAFFOLD_KEYS, &within);
        let source = match (fields.get("mesh"), fields.get("grid")) {
            (Some((_, mesh)), None) => {
                let key = format!("scaffolds.{name}.mesh");
                let given = self.string(&key, mesh)?;
                self.input_file(&format!("`{key}`"), given, mesh.span(), &SCAFFOLD_FILES)
                    .map(ScaffoldSource::Mesh)
            }
            (None, Some((_, grid))) => self.grid(name, grid).map(ScaffoldSource::Grid),
            (Some((_, mesh)), Some((_, grid))) => {
                let later = if grid.span().start > mesh.span().start {
                    grid
                } else {
                    mesh
                };
                self.error(
                    later.span(),
                    &format!("both `mesh` and `grid` given {within}"),
                    "a scaffold is a mesh file or a generated grid, not both",
                    Some("remove one of them"),
                );
                None
            }
            (None, None) => {
                let help = "add `mesh = \"scaffold.msh\"` (a Gmsh, VTK or Abaqus mesh) or \
                            `grid = { min = [0, 0, 0], max = [10, 10, 10], divisions = 5, \
                            element = \"hex\" }`";
                if !fields.misspelled("mesh") && !fields.misspelled("grid") {
                    self.error(
                        value.span(),
                        &format!("missing key `mesh` or `grid` {within}"),
                        "missing `mesh` or `grid`",
                        Some(help),
                    );
                }
                None
            }
        };
        let continuity = self.continuity(name, &fields, source.as_ref());
        if self.report.len() > before {
            return None;
        }
        Some(Scaffold {
            name: self.name(key),
            source: source?,
            continuity: continuity?,
        })
    }

    fn grid(&mut self, scaffold: &str, value: &Value<'_>) -> Option<ScaffoldGrid> {
        let key = format!("scaffolds.{scaffold}.grid");
        let example = "{ min = [0, 0, 0], max = [10, 10, 10], divisions = 5, element = \"hex\" }";
        let table = self.table(&key, value, &format!("write it as `grid = {example}`"))?;
        let fields = self.fields(table, &GRID_KEYS, &format!("in `{key}`"));
        let path = |k: &str| format!("{key}.{k}");
        let missing = |s: &mut Self, k: &str, help: &str| {
            let within = format!("in `{key}`");
            s.missing(
                &fields,
                &value.span(),
                k,
                &within,
                &format!("missing `{k}`"),
                help,
            );
        };
        let element = match fields.get("element") {
            None => {
                missing(
                    self,
                    "element",
                    "add `element = \"hex\"` (or \"tet\", \"quad\", \"tri\")",
                );
                None
            }
            Some((_, v)) => self.choice(&path("element"), v, &GRID_ELEMENTS, "grid element"),
        };
        let element = element.map(|e| match e {
            "hex" => ElementKind::Hex8,
            "tet" => ElementKind::Tet4,
            "quad" => ElementKind::Quad4,
            _ => ElementKind::Tri3,
        });
        let min = match fields.get("min") {
            None => {
                missing(self, "min", "add `min = [x, y, z]`");
                None
            }
            Some((_, v)) => self.point_numbers(&path("min"), v),
        };
        let max = match fields.get("max") {
            None => {
                missing(self, "max", "add `max = [x, y, z]`");
                None
            }
            Some((_, v)) => self.point_numbers(&path("max"), v),
        };
        let divisions = match fields.get("divisions") {
            None => {
                missing(self, "divisions", "add `divisions = 4` (or `[nx, ny, nz]`)");
                None
            }
            Some((_, v)) => self.divisions(&path("divisions"), v),
        };
        let (element, (min, min_values), (max, max_values)) = (element?, min?, max?);
        let (divisions, division_values) = divisions?;
        let axes = element.dimension();
        let mut ok = true;
        for (values, k) in [(&min_values, "min"), (&max_values, "max")] {
            if values.len() < axes {
                ok = false;
                self.error(
                    fields.get(k).map_or(value.span(), |(_, v)| v.span()),
                    &format!(
                        "`{}` needs {axes} values for a {} grid",
                        path(k),
                        element.name()
                    ),
                    &format!("found {}", values.len()),
                    Some("give the corner as [x, y, z]"),
                );
            }
        }
        if division_values.is_some_and(|n| n < axes) {
            ok = false;
            let span = fields
                .get("divisions")
                .map_or(value.span(), |(_, v)| v.span());
            self.error(
                span,
                &format!(
                    "`{}` needs {axes} values for a {} grid",
                    path("divisions"),
                    element.name()
                ),
                "too few divisions",
                Some("give one number for every axis, or a single number for all"),
            );
        }
        if !ok {
            return None;
        }
        for axis in 0..axes {
            if min[axis] >= max[axis] {
                let shown = self.raw(min_values[axis]);
                self.error(
                    max_values[axis].span(),
                    &format!("`{}` must be greater than `min` on every axis", path("max")),
                    &format!("not greater than min {} `{shown}`", ["x", "y", "z"][axis]),
                    None,
                );
                ok = false;
            }
        }
        let per_box = match element {
            ElementKind::Tet4 => 6,
            ElementKind::Tri3 => 2,
            _ => 1,
        };
        let elements = divisions[..axes]
            .iter()
            .try_fold(per_box, |n: usize, &d| n.checked_mul(d));
        if elements.is_none_or(|n| n > MAX_GRID_ELEMENTS) {
            let span = fields
                .get("divisions")
                .map_or(value.span(), |(_, v)| v.span());
            self.error(
                span,
                &format!("`{}` gives too many elements", path("divisions")),
                &format!("more than {MAX_GRID_ELEMENTS} {} elements", element.name()),
                Some("use fewer divisions (the lattice's own detail is `resolution`)"),
            );
            ok = false;
        }
        ok.then_some(ScaffoldGrid {
            min,
            max,
            divisions,
            element,
        })
    }

    /// A positive integer (every axis) or an array of 2 or 3; with the array's length.
    fn divisions(&mut self, key: &str, value: &Value<'_>) -> Option<([usize; 3], Option<usize>)> {
        let one = |s: &mut Self, v: &Value<'_>| -> Option<usize> {
            let DeValue::Integer(int) = v.get_ref() else {
                s.wrong_type(key, v, "a positive integer", None);
                return None;
            };
            match i64::from_str_radix(int.as_str(), int.radix()) {
                Ok(n) if n >= 1 => usize::try_from(n).ok(),
                _ => {
                    let shown = s.raw(v);
                    s.error(
                        v.span(),
                        &format!("`{key}` must be at least 1 on every axis"),
                        &format!("found `{shown}`"),
                        None,
                    );
                    None
                }
            }
        };
        match value.get_ref() {
            DeValue::Array(items) if items.len() == 2 || items.len() == 3 => {
                let counts: Vec<Option<usize>> = items.iter().map(|v| one(self, v)).collect();
                let mut out = [1; 3];
                for (slot, c) in out.iter_mut().zip(&counts) {
                    *slot = (*c)?;
                }
                Some((out, Some(items.len())))
            }
            DeValue::Array(items) => {
                self.error(
                    value.span(),
                    &format!("`{key}` must have 3 values (x, y, z), or 2 (x, y) in the plane"),
                    &format!("found {}", items.len()),
                    None,
                );
                None
            }
            _ => one(self, value).map(|n| ([n; 3], None)),
        }
    }

    /// An output with `scaffold = "…"`; `None` when anything was reported.
    pub(super) fn tiled_output(
        &mut self,
        key: &Key<'_>,
        value: &Value<'_>,
        context: &TilingContext<'_>,
    ) -> Option<TiledOutput> {
        let before = self.report.len();
        let name = key.get_ref().as_ref();
        self.check_name("output", key);
        let help = format!("define it as an `[outputs.{name}]` table");
        let table = self.table(&format!("outputs.{name}"), value, &help)?;
        let within = format!("in output `{name}`");
        let fields = self.fields(table, &ALL_KEYS, &within);
        let header = value.span();
        let path = |k: &str| format!("outputs.{name}.{k}");
        for k in ALL_KEYS.iter().filter(|k| !TILED_KEYS.contains(k)) {
            if let Some((key, _)) = fields.get(k) {
                let why = match *k {
                    "domain" | "over" | "cell_size" | "bounds" => {
                        "the scaffold's elements are the domain, one cell in each"
                    }
                    "samples" | "voxel" => "a tiled output is sampled per element",
                    _ => "a tiled output fills its scaffold",
                };
                let help = match *k {
                    "samples" | "voxel" => "write `resolution = 12` (samples per element edge)",
                    "within" => "the scaffold's boundary bounds the lattice already",
                    _ => "remove it",
                };
                self.error(
                    key.span(),
                    &format!(
                        "`{}` does not apply to an output with a `scaffold`",
                        path(k)
                    ),
                    why,
                    Some(help),
                );
            }
        }
        let scaffold = fields.get("scaffold").and_then(|(_, v)| {
            let key = path("scaffold");
            let text = self.string(&key, v)?;
            if context.scaffold_names.contains(text) {
                return Some((text.to_string(), v.span()));
            }
            let help = match spelling::closest(text, context.scaffold_names.iter().copied()) {
                Some(close) => format!("did you mean `{close}`?"),
                None => format!("define the scaffold in a `[scaffolds.{text}]` table"),
            };
            self.error(
                v.span(),
                &format!("unknown scaffold `{text}` in `{key}`"),
                "no scaffold with this name",
                Some(&help),
            );
            None
        });
        // The element of a generated grid is known now; a file's only once it is read.
        let scaffold_def = scaffold
            .as_ref()
            .and_then(|(s, _)| context.scaffolds.get(s));
        let grid_element = scaffold_def.and_then(|s| match &s.source {
            ScaffoldSource::Grid(g) => Some(g.element),
            ScaffoldSource::Mesh(_) => None,
        });
        let is_grid = grid_element.is_some();
        let cells = match fields.get("cell") {
            None => {
                let help = "add `cell = \"NAME\"` naming a symmetric cell, or \
                            `cell = { blend = [\"a\", \"b\"], by = \"x / 10\" }`";
                self.missing(&fields, &header, "cell", &within, "missing `cell`", help);
                None
            }
            Some((_, v)) => self.tiled_cells(name, v, context, is_grid),
        };
        if let (Some((cell, _, cell_span)), Some(element)) = (&cells, grid_element) {
            self.check_element_group(name, cell, cell_span, element, context.cells);
        }
        let from = super::sizing::GradedFrom::Scaffold { is_grid };
        let solid = match self.sized_solid(name, &fields, from) {
            Some(sized) => sized.map(|(solid, sizing)| (solid, sizing, None, None)),
            None => self
                .tiled_solid(name, &header, &within, &fields, is_grid)
                .map(|(solid, thickness, offset)| (solid, Sizing::Field, thickness, offset)),
        };
        let resolution = match fields.get("resolution") {
            None => Some(DEFAULT_RESOLUTION),
            Some((_, v)) => self.resolution(&path("resolution"), v),
        };
        let skin = match fields.get("skin") {
            None => Some(None),
            Some((_, v)) if grid_element.is_some_and(|e| e.dimension() == 2) => {
                self.error(
                    v.span(),
                    &format!("`{}` does not apply to a 2D scaffold", path("skin")),
                    "skins close the tiling of a 3D scaffold",
                    Some("remove it; `extrude = h` or `thickness_normal = h` makes a 2D region a solid"),
                );
                None
            }
            Some((_, v)) => self.positive_number(&path("skin"), v, "a number").map(Some),
        };
        let thicken = self.thicken(name, &fields, grid_element);
        let written = self.written_files(name, &fields);
        // A 2D grid's region stays a surface unless thickened: its pieces have no volume.
        let region = grid_element.is_some_and(|e| e.dimension() == 2)
            && !THICKEN_KEYS.iter().any(|k| fields.contains_key(k));
        let islands = self.islands(name, &fields, region);
        if self.report.len() > before {
            return None;
        }
        let (cell, transition, _) = cells?;
        let (solid, sizing, thickness, offset) = solid?;
        let written = written?;
        Some(TiledOutput {
            name: self.name(key),
            scaffold: scaffold?.0,
            cell,
            transition,
            solid,
            sizing,
            thickness,
            offset,
            resolution: resolution?,
            skin: skin?,
            thicken: thicken?,
            formats: written.formats,
            encoding: written.encoding,
            stem: written.stem,
            islands: islands?,
        })
    }

    /// `extrude = h` or `thickness_normal = h` (one at most, positive); on a grid, only when
    /// its elements are 2D (a mesh file's are checked by the stage).
    fn thicken(
        &mut self,
        output: &str,
        fields: &Fields<'_, '_>,
        grid_element: Option<ElementKind>,
    ) -> Option<Option<Thicken>> {
        let given: Vec<(&str, &Value<'_>)> = THICKEN_KEYS
            .iter()
            .filter_map(|&k| fields.get(k).map(|(_, v)| (k, *v)))
            .collect();
        let (key, value) = match given.as_slice() {
            [] => return Some(None),
            [one] => *one,
            [a, b, ..] => {
                let later = if b.1.span().start > a.1.span().start {
                    b
                } else {
                    a
                };
                self.error(
                    later.1.span(),
                    &format!("both `extrude` and `thickness_normal` given in output `{output}`"),
                    "a 2D region is extruded along z or thickened along its normals, not both",
                    Some("remove one of them"),
                );
                return None;
            }
        };
        let path = format!("outputs.{output}.{key}");
        if let Some(element) = grid_element.filter(|e| e.dimension() != 2) {
            self.error(
                value.span(),
                &format!("`{path}` applies only to 2D scaffolds"),
                &format!(
                    "the grid's elements are {}, which tile into a solid already",
                    element.name()
                ),
                Some("remove it, or use a grid of `element = \"quad\"` or `\"tri\"`"),
            );
            return None;
        }
        let h = self.positive_number(&path, value, "a length (model units)")?;
        Some(Some(match key {
            "extrude" => Thicken::Extrude(h),
            _ => Thicken::ThicknessNormal(h),
        }))
    }

    /// `cell = "a"` or `cell = { blend = ["a", "b"], by = "…" }`: the cell, the transition, and
    /// the span to cite for a group mismatch. Both cells need one named group.
    #[allow(clippy::type_complexity)]
    fn tiled_cells(
        &mut self,
        output: &str,
        value: &Value<'_>,
        context: &TilingContext<'_>,
        is_grid: bool,
    ) -> Option<(String, Option<TiledTransition>, Range<usize>)> {
        let key = format!("outputs.{output}.cell");
        if let DeValue::String(_) = value.get_ref() {
            let cell = self.cell_reference(&key, value, context.cell_names)?;
            self.named_group(&key, &value.span(), &cell, context.cells)?;
            return Some((cell, None, value.span()));
        }
        let example = "{ blend = [\"a\", \"b\"], by = \"z / 20\" }";
        let table = match value.get_ref() {
            DeValue::Table(t) => t,
            _ => {
                let help = format!("write `cell = \"NAME\"`, or `cell = {example}`");
                self.wrong_type(
                    &key,
                    value,
                    "a cell name or a transition table",
                    Some(&help),
                );
                return None;
            }
        };
        let fields = self.fields(table, &TRANSITION_KEYS, &format!("in `{key}`"));
        let within = format!("in `{key}`");
        let pair = match fields.get("blend") {
            None => {
                let help = "add `blend = [\"a\", \"b\"]` (the cells at weight 0 and 1)";
                self.missing(
                    &fields,
                    &value.span(),
                    "blend",
                    &within,
                    "missing `blend`",
                    help,
                );
                None
            }
            Some((_, v)) => self.blend_pair(&format!("{key}.blend"), v, context),
        };
        let by = match fields.get("by") {
            None => {
                let help = "add `by = \"z / 20\"` (the weight of the second cell, in x, y, z) \
                            or `by = \"nodedata:NAME\"`";
                self.missing(&fields, &value.span(), "by", &within, "missing `by`", help);
                None
            }
            Some((_, v)) => {
                let by_key = format!("{key}.by");
                match v.get_ref() {
                    DeValue::String(_) => self.nodal(&by_key, v, is_grid),
                    _ => {
                        let help = "write the weight as an expression, e.g. `by = \"x / 10\"`, \
                                    or `by = \"nodedata:NAME\"`";
                        self.wrong_type(&by_key, v, "a string", Some(help));
                        None
                    }
                }
            }
        };
        let ((a, b, span), by) = (pair?, by?);
        Some((a, Some(TiledTransition { to: b, by }), span))
    }

    /// The two cells of a transition, of one named group.
    fn blend_pair(
        &mut self,
        key: &str,
        value: &Value<'_>,
        context: &TilingContext<'_>,
    ) -> Option<(String, String, Range<usize>)> {
        let DeValue::Array(items) = value.get_ref() else {
            self.wrong_type(key, value, "an array of two cell names", None);
            return None;
        };
        if items.len() != 2 {
            self.error(
                value.span(),
                &format!("`{key}` must name two cells"),
                &format!("found {}", items.len()),
                Some("a transition goes from the first cell (weight 0) to the second (weight 1)"),
            );
            return None;
        }
        let mut member = |v: &Value<'_>| {
            let cell = self.cell_reference(key, v, context.cell_names)?;
            let group = self.named_group(key, &v.span(), &cell, context.cells)?;
            Some((cell, group))
        };
        let (a, b) = (member(&items[0]), member(&items[1]));
        let ((a, group_a), (b, group_b)) = (a?, b?);
        if group_a != group_b {
            self.error(
                items[1].span(),
                &format!("the cells of `{key}` have different groups"),
                &format!("`{a}` is `{group_a}`, `{b}` is `{group_b}`"),
                Some("a transition blends two cells of the element's group"),
            );
            return None;
        }
        Some((a, b, value.span()))
    }

    /// The named group of a symmetric cell; an error for any other cell. `None` without a
    /// report when the cell itself was invalid (reported with it).
    fn named_group(
        &mut self,
        key: &str,
        span: &Range<usize>,
        cell: &str,
        cells: &BTreeMap<String, Cell>,
    ) -> Option<String> {
        let found = cells.get(cell)?;
        let why = match found.symmetric.as_ref().map(|s| &s.group) {
            Some(GroupSpec::Named(name)) => return Some(name.clone()),
            Some(GroupSpec::Generators { .. }) => {
                format!("the group of cell `{cell}` is given by generators")
            }
            None => format!("cell `{cell}` has no `symmetry`"),
        };
        self.error(
            span.clone(),
            &format!("`{key}` needs a cell with the element's symmetry"),
            &why,
            Some(&format!(
                "give `[cells.{cell}]` `symmetry = \"Oh\"` (hex scaffolds), `\"Td\"` (tet), \
                 `\"D4\"` (quad) or `\"D3\"` (tri)"
            )),
        );
        None
    }

    /// A grid's element against the cell's group (Oh↔hex, Td↔tet, D4↔quad, D3↔tri).
    fn check_element_group(
        &mut self,
        output: &str,
        cell: &str,
        span: &Range<usize>,
        element: ElementKind,
        cells: &BTreeMap<String, Cell>,
    ) {
        let Some(Some(GroupSpec::Named(group))) = cells
            .get(cell)
            .map(|c| c.symmetric.as_ref().map(|s| &s.group))
        else {
            return;
        };
        let needed = tiling_group(element);
        if group != needed {
            self.error(
                span.clone(),
                &format!("`outputs.{output}.cell` does not fit the scaffold's elements"),
                &format!(
                    "cell `{cell}` has group `{group}`, but {} elements need `{needed}`",
                    element.name()
                ),
                Some(&format!(
                    "use a cell with `symmetry = \"{needed}\"`, or a scaffold of {} elements for \
                     `{group}`",
                    match group.as_str() {
                        "Oh" => "hex",
                        "Td" => "tet",
                        "D4" => "quad",
                        _ => "tri",
                    }
                )),
            );
        }
    }

    /// The solid of a tiled output, with a graded thickness or offset when given as a string.
    #[allow(clippy::type_complexity)]
    fn tiled_solid(
        &mut self,
        output: &str,
        header: &Range<usize>,
        within: &str,
        fields: &Fields<'_, '_>,
        is_grid: bool,
    ) -> Option<(Solid, Option<NodalValue>, Option<NodalValue>)> {
        let path = |k: &str| format!("outputs.{output}.{k}");
        let kind = match fields.get("solid") {
            None => Some("inside"),
            Some((_, v)) => self.solid_kind(&path("solid"), v),
        };
        let shell = matches!(kind, Some("shell" | "eccentric_shell"));
        let value_of = |s: &mut Self, k: &str, v: &Value<'_>, positive: bool| match v.get_ref() {
            DeValue::String(_) => s.nodal(&path(k), v, is_grid).map(|n| (0.0, Some(n))),
            _ if positive => s
                .positive_number(&path(k), v, "a number or an expression string")
                .map(|n| (n, None)),
            _ => s
                .number(&path(k), v, "a number or an expression string")
                .map(|n| (n, None)),
        };
        let thickness = match fields.get("thickness") {
            Some((_, v)) if kind.is_some() && !shell => {
                self.error(
                    v.span(),
                    &format!("`{}` applies only to shells", path("thickness")),
                    &format!("`solid` is `{}`", kind.unwrap_or("inside")),
                    Some("remove `thickness`, or set `solid = \"shell\"` or `\"eccentric_shell\"`"),
                );
                None
            }
            Some((_, v)) => value_of(self, "thickness", v, true),
            None if shell => {
                let label = format!("`solid = \"{}\"` needs a `thickness`", kind.unwrap_or(""));
                let help = "add `thickness = 0.2` (in field values), or an expression in x, y, z";
                self.missing(fields, header, "thickness", within, &label, help);
                None
            }
            None => Some((0.0, None)),
        };
        let offset = match fields.get("offset") {
            Some((_, v)) if kind == Some("shell") => {
                self.error(
                    v.span(),
                    &format!("`{}` does not apply to `solid = \"shell\"`", path("offset")),
                    "a shell is centred on the surface",
                    Some(
                        "use `solid = \"eccentric_shell\"` for a shell around an offset level set",
                    ),
                );
                None
            }
            Some((_, v)) => value_of(self, "offset", v, false),
            None => Some((0.0, None)),
        };
        let (kind, (thickness, graded_thickness), (offset, graded_offset)) =
            (kind?, thickness?, offset?);
        let solid = match kind {
            "inside" => Solid::Inside { offset },
            "outside" => Solid::Outside { offset },
            "shell" => Solid::Shell { thickness },
            _ => Solid::EccentricShell { offset, thickness },
        };
        Some((solid, graded_thickness, graded_offset))
    }

    /// A nodal value: `"nodedata:NAME"` (not on a grid) or an expression in x, y, z.
    pub(super) fn nodal(
        &mut self,
        key: &str,
        value: &Value<'_>,
        is_grid: bool,
    ) -> Option<NodalValue> {
        let text = self.string(key, value)?;
        if let Some(view) = text.strip_prefix(NODE_DATA_PREFIX) {
            let view = view.trim();
            if view.is_empty() {
                self.error(
                    value.span(),
                    &format!("`{key}` names no node data view"),
                    "expected `nodedata:NAME`",
                    Some("name one of the scaffold file's `$NodeData` views"),
                );
                return None;
            }
            if is_grid {
                self.error(
                    value.span(),
                    &format!("`{key}` reads node data, but the scaffold is a generated grid"),
                    "grids have no node data",
                    Some("write an expression in x, y, z instead, e.g. `\"x / 10\"`"),
                );
                return None;
            }
            return Some(NodalValue::NodeData(view.to_string()));
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

    fn resolution(&mut self, key: &str, value: &Value<'_>) -> Option<usize> {
        let DeValue::Integer(int) = value.get_ref() else {
            self.wrong_type(key, value, "an integer (samples per element edge)", None);
            return None;
        };
        match i64::from_str_radix(int.as_str(), int.radix()) {
            Ok(n) if (2..=MAX_RESOLUTION).contains(&n) => usize::try_from(n).ok(),
            _ => {
                let shown = self.raw(value);
                self.error(
                    value.span(),
                    &format!("`{key}` must be between 2 and {MAX_RESOLUTION}"),
                    &format!("found `{shown}`"),
                    Some("samples per element edge; 8 to 24 suits most cells"),
                );
                None
            }
        }
    }
}
