//! An output's resolved parameters: what the build used, in the manifest's own terms, for
//! the report's `resolved` and the written files' stamps (3MF metadata).
//!
//! Invariants:
//! - It starts from the output's table as read (after `--set`/`--unset`), and every key the
//!   parsed model decides is then written from the model, not from a second copy of the
//!   defaults: `solid`, its `offset`/`thickness` (or `wall`, `grow`, `volume_fraction`),
//!   `domain`, `cell_size`, `samples` (the counts, also when `voxel` gave them), `formats`,
//!   `ascii`, `path`, `keep`, and the SDF (its program in canonical text) and tiled outputs'
//!   own keys. A key the build did not
//!   use (no `bounds`, no `skin`) stays absent.
//! - `cell` (and a tiled output's `scaffold`) is the referenced table as read, with `name`
//!   added, and a symmetric cell's `fit` as the model resolved it; a transition's `cell` is
//!   `{ blend = [from, to], by }` with both cells so.
//! - [`flatten`] turns it into the stamp's `(name, value)` pairs: nested keys joined by `.`,
//!   a string as itself, anything else as compact JSON, so each value reads back as the
//!   report's.

use serde_json::{Map, Value, json};

use latticebuild_geom::field::Solid;
use latticebuild_geom::islands::IslandFilter;
use latticebuild_geom::mesh_io::{Encoding, Format};

use super::model::{
    FitResolution, Manifest, NodalValue, Output, ProgramOutput, ProgramResolution, Sizing, Target,
    TiledOutput,
};

impl Manifest {
    /// Output `name`'s resolved parameters (see the module docs); `None` for no such output.
    pub fn resolved(&self, name: &str) -> Option<Value> {
        let model = if let Some(o) = self.outputs.get(name) {
            self.box_output(o)
        } else if let Some(o) = self.program_outputs.get(name) {
            program_output(o)
        } else if let Some(o) = self.tiled_outputs.get(name) {
            self.tiled_output(o)
        } else {
            return None;
        };
        let mut table = match self.parameters.get(name) {
            Some(Value::Object(table)) => table.clone(),
            _ => Map::new(),
        };
        // Sizing keys other than the one used cannot be in a valid table, so the model's
        // keys replace the table's without leaving a contradiction behind.
        table.extend(model);
        Some(Value::Object(table))
    }

    fn box_output(&self, o: &Output) -> Map<String, Value> {
        // A planar domain's lengths are given, and shown, in x and y only.
        let axes = if o.planar_domain { 2 } else { 3 };
        let cut = |v: [f64; 3]| json!(v[..axes]);
        let mut m = Map::new();
        m.insert("cell".into(), self.cell(&o.cell));
        if o.over_element {
            m.insert("over".into(), json!("element"));
        }
        m.insert(
            "domain".into(),
            json!({ "min": cut(o.domain_min), "max": cut(o.domain_max) }),
        );
        m.insert("cell_size".into(), cut(o.cell_size));
        solid(&mut m, &o.solid, &o.sizing);
        m.insert("samples".into(), json!(o.samples[..axes]));
        if let Some(part) = &o.within {
            m.insert("within".into(), json!(part.given));
        }
        if let Some(skin) = o.skin {
            m.insert("skin".into(), json!(skin));
        }
        files(&mut m, &o.formats, o.encoding, &o.stem, &o.islands);
        m
    }

    fn tiled_output(&self, o: &TiledOutput) -> Map<String, Value> {
        let mut m = Map::new();
        let mut scaffold = self.table(&self.scaffold_tables, &o.scaffold);
        if let (Value::Object(table), Some(s)) = (&mut scaffold, self.scaffolds.get(&o.scaffold)) {
            table.insert("continuity".into(), json!(s.continuity.key()));
        }
        m.insert("scaffold".into(), scaffold);
        let cell = match &o.transition {
            None => self.cell(&o.cell),
            Some(t) => json!({
                "blend": [self.cell(&o.cell), self.cell(&t.to)],
                "by": nodal(&t.by),
            }),
        };
        m.insert("cell".into(), cell);
        solid(&mut m, &o.solid, &o.sizing);
        // Graded field values replace the solid's own, node by node.
        for (key, graded) in [("thickness", &o.thickness), ("offset", &o.offset)] {
            if let Some(g) = graded {
                m.insert(key.into(), nodal(g));
            }
        }
        m.insert("resolution".into(), json!(o.resolution));
        if let Some(skin) = o.skin {
            m.insert("skin".into(), json!(skin));
        }
        if let Some(t) = o.thicken {
            m.insert(t.key().into(), json!(t.length()));
        }
        files(&mut m, &o.formats, o.encoding, &o.stem, &o.islands);
        m
    }

    /// Cell `name`'s table with its name, and a symmetric cell's resolved `fit`.
    fn cell(&self, name: &str) -> Value {
        let mut cell = self.table(&self.cell_tables, name);
        let fit = self
            .cells
            .get(name)
            .and_then(|c| c.symmetric.as_ref())
            .map(|s| match s.n {
                FitResolution::Fixed(n) => json!({ "n": n }),
                FitResolution::Auto { tolerance, max_n } => {
                    json!({ "n": "auto", "tolerance": tolerance, "max_n": max_n })
                }
            });
        if let (Value::Object(table), Some(fit)) = (&mut cell, fit) {
            table.insert("fit".into(), fit);
        }
        cell
    }

    /// A table as read, `name` first.
    fn table(&self, tables: &std::collections::BTreeMap<String, Value>, name: &str) -> Value {
        let mut table = Map::new();
        table.insert("name".into(), json!(name));
        if let Some(Value::Object(read)) = tables.get(name) {
            table.extend(read.iter().map(|(k, v)| (k.clone(), v.clone())));
        }
        Value::Object(table)
    }
}

fn program_output(o: &ProgramOutput) -> Map<String, Value> {
    let mut m = Map::new();
    // Canonical, as the stage's key has it: another spelling of the same program (`BALL`,
    // `4/2`) builds, and stamps, the same file.
    m.insert("sdf".into(), json!(o.program.canonical()));
    // Without `bounds`, the box is the program's own, found when it is contoured (the
    // report's `sdf_box`).
    if let Some([min, max]) = o.bounds {
        m.insert("bounds".into(), json!({ "min": min, "max": max }));
    }
    match o.resolution {
        ProgramResolution::Counts(counts) => m.insert("samples".into(), json!(counts)),
        ProgramResolution::Voxel(voxel) => m.insert("voxel".into(), json!(voxel)),
    };
    m.insert("contour".into(), json!(o.contouring.name()));
    files(&mut m, &o.formats, o.encoding, &o.stem, &o.islands);
    m
}

/// `solid` and the keys sizing it, as the model holds them (docs/manifest.md, "Solids" and
/// "Sizes in model units").
fn solid(m: &mut Map<String, Value>, solid: &Solid, sizing: &Sizing) {
    let (kind, offset, thickness) = match *solid {
        Solid::Inside { offset } => ("inside", Some(offset), None),
        Solid::Outside { offset } => ("outside", Some(offset), None),
        Solid::Shell { thickness } => ("shell", None, Some(thickness)),
        Solid::EccentricShell { offset, thickness } => {
            ("eccentric_shell", Some(offset), Some(thickness))
        }
    };
    match sizing {
        Sizing::Field => {
            m.insert("solid".into(), json!(kind));
            for (key, value) in [("offset", offset), ("thickness", thickness)] {
                if let Some(v) = value {
                    m.insert(key.into(), json!(v));
                }
            }
        }
        Sizing::Length { level, graded } => {
            // The model's solid is in model units here: a shell's thickness is the wall, an
            // inside solid's offset the growth, an outside one's minus it.
            let (key, amount) = match *solid {
                Solid::Inside { offset } => ("grow", offset),
                Solid::Outside { offset } => ("grow", -offset),
                Solid::Shell { thickness } | Solid::EccentricShell { thickness, .. } => {
                    ("wall", thickness)
                }
            };
            let amount = graded.as_ref().map_or(json!(amount), nodal);
            m.insert(key.into(), amount);
            shell_level(m, kind, *level);
        }
        Sizing::VolumeFraction { level, target } => {
            let target = match target {
                Target::Uniform(v) => json!(v),
                Target::Graded(g) => nodal(g),
            };
            m.insert("volume_fraction".into(), target);
            shell_level(m, kind, *level);
        }
    }
}

/// The solid kind of a solid sized in model units or by fraction: the model keeps an
/// eccentric shell's level in its sizing, so a shell about a level other than 0 is one.
fn shell_level(m: &mut Map<String, Value>, kind: &str, level: f64) {
    if kind == "shell" && level != 0.0 {
        m.insert("solid".into(), json!("eccentric_shell"));
        m.insert("offset".into(), json!(level));
    } else {
        m.insert("solid".into(), json!(kind));
    }
}

/// `formats`, `ascii`, `path`, `keep` and `min_island_volume`, shared by every output.
fn files(
    m: &mut Map<String, Value>,
    formats: &[Format],
    encoding: Encoding,
    stem: &str,
    islands: &IslandFilter,
) {
    let names: Vec<&str> = formats.iter().map(|f| f.name()).collect();
    m.insert("formats".into(), json!(names));
    m.insert("ascii".into(), json!(encoding == Encoding::Ascii));
    m.insert("path".into(), json!(stem));
    let keep = if islands.largest { "largest" } else { "all" };
    m.insert("keep".into(), json!(keep));
    if let Some(v) = islands.min_volume {
        m.insert("min_island_volume".into(), json!(v));
    }
}

/// A graded value as the manifest writes it.
fn nodal(value: &NodalValue) -> Value {
    match value {
        NodalValue::Expr(text) => json!(text),
        NodalValue::NodeData(name) => json!(format!("nodedata:{name}")),
    }
}

/// `value`'s leaves as `(dotted name, text)` pairs, in key order: a string as itself, any
/// other leaf (numbers, booleans, arrays) as compact JSON.
pub fn flatten(value: &Value) -> Vec<(String, String)> {
    fn walk(prefix: &str, value: &Value, out: &mut Vec<(String, String)>) {
        match value {
            Value::Object(table) => {
                for (key, v) in table {
                    let name = match prefix {
                        "" => key.clone(),
                        _ => format!("{prefix}.{key}"),
                    };
                    walk(&name, v, out);
                }
            }
            Value::String(text) => out.push((prefix.to_string(), text.clone())),
            other => out.push((prefix.to_string(), other.to_string())),
        }
    }
    let mut out = Vec::new();
    walk("", value, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::flatten;
    use crate::manifest::parse_edited;
    use std::path::Path;

    const TEXT: &str = r#"
[cells.g]
tpms = "gyroid"

[cells.s]
tpms = "p"
symmetry = "Oh"

[outputs.plain]
cell = "g"
domain = { min = [0, 0, 0], max = [2, 2, 2] }
voxel = 0.5

[outputs.walled]
cell = "s"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
wall = 0.1
samples = 8
formats = ["3mf", "stl"]
"#;

    fn resolved(sets: &[&str]) -> crate::manifest::Manifest {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        parse_edited(TEXT, Path::new("lattice.toml"), &sets, &[])
            .unwrap_or_else(|d| panic!("{}", crate::diagnostics::render(&d)))
    }

    #[test]
    fn defaults_come_from_the_model_and_the_cell_table_is_included() {
        let m = resolved(&["outputs.plain.cell_size=2"]);
        let plain = m.resolved("plain").expect("an output");
        // As set; defaults of the manifest reference; the voxel's counts, 2 / 0.5 + 1.
        assert_eq!(plain["cell_size"], serde_json::json!([2.0, 2.0, 2.0]));
        assert_eq!(plain["solid"], "inside");
        assert_eq!(plain["offset"], 0.0);
        assert_eq!(plain["formats"], serde_json::json!(["stl"]));
        assert_eq!(plain["ascii"], false);
        assert_eq!(plain["path"], "plain");
        assert_eq!(plain["keep"], "all");
        assert_eq!(plain["voxel"], 0.5);
        assert_eq!(plain["samples"], serde_json::json!([5, 5, 5]));
        assert_eq!(
            plain["cell"],
            serde_json::json!({ "name": "g", "tpms": "gyroid" })
        );
        assert!(plain.get("within").is_none() && plain.get("bounds").is_none());

        let walled = m.resolved("walled").expect("an output");
        // `wall` without `solid` is a shell; the Oh cell's fit is N = 128 by default.
        assert_eq!(walled["solid"], "shell");
        assert_eq!(walled["wall"], 0.1);
        assert!(walled.get("thickness").is_none(), "wall replaces thickness");
        assert_eq!(walled["cell"]["fit"], serde_json::json!({ "n": 128 }));
        assert_eq!(walled["cell"]["symmetry"], "Oh");
        assert_eq!(walled["formats"], serde_json::json!(["stl", "3mf"]));
        assert!(m.resolved("nothing").is_none());
    }

    #[test]
    fn flattened_names_join_keys_and_values_read_back_as_json() {
        let m = resolved(&[]);
        let plain = m.resolved("plain").expect("an output");
        let pairs = flatten(&plain);
        let get = |name: &str| {
            pairs
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, v)| v.as_str())
        };
        assert_eq!(get("cell.name"), Some("g"));
        assert_eq!(get("domain.max"), Some("[2.0,2.0,2.0]"));
        assert_eq!(get("ascii"), Some("false"));
        assert_eq!(get("cell"), None, "tables are walked, not written whole");
        for (name, text) in &pairs {
            let pointer = format!("/{}", name.replace('.', "/"));
            let leaf = &plain.pointer(&pointer).expect("a leaf of the object");
            let back = match leaf {
                serde_json::Value::String(_) => serde_json::Value::String(text.clone()),
                _ => serde_json::from_str(text).expect("JSON"),
            };
            assert_eq!(&back, *leaf, "{name}");
        }
    }
}
