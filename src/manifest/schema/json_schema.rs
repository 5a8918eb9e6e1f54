//! `docs/manifest.schema.json`, the manifest's JSON Schema (for editors' TOML language
//! servers, which read a manifest as JSON), generated here from the key lists of `keys.rs`.
//!
//! Invariants (tested below):
//! - The committed file is exactly what [`manifest_schema`] generates (`cargo xtask golden
//!   --bless` rewrites it), so the schema lists exactly the keys the validator accepts, table
//!   by table, with `additionalProperties: false`.
//! - Every key has a type here ([`key_type`]): a new key in `keys.rs` without one fails the
//!   test. Types are as loose as the validator's forms (a number or an expression string,
//!   an integer or an array): the schema must accept every valid manifest (the examples are
//!   checked against it) and catch misspelt keys and wrong kinds of value; ranges and
//!   references are left to the validator, whose errors point at the line.

use serde_json::{Map, Value, json};

use super::keys::*;

fn string() -> Value {
    json!({ "type": "string" })
}
fn number() -> Value {
    json!({ "type": "number" })
}
fn integer() -> Value {
    json!({ "type": "integer" })
}
fn boolean() -> Value {
    json!({ "type": "boolean" })
}
fn numbers() -> Value {
    json!({ "type": "array", "items": { "type": "number" } })
}
fn strings() -> Value {
    json!({ "type": "array", "items": { "type": "string" } })
}
fn one_of(names: &[&str]) -> Value {
    json!({ "enum": names })
}
/// A number, or an expression string graded over the part.
fn number_or_expression() -> Value {
    json!({ "type": ["number", "string"] })
}
fn number_or_numbers() -> Value {
    json!({ "anyOf": [number(), numbers()] })
}

/// A table of `keys`, each typed by [`key_type`] within `table` (a dotted path, `*` for a
/// name), no other key allowed.
fn table(path: &str, keys: &[&str]) -> Value {
    let mut properties = Map::new();
    for key in keys {
        let typed = key_type(path, key)
            .unwrap_or_else(|| panic!("`{key}` of `[{path}]` has no type in json_schema.rs"));
        properties.insert(key.to_string(), typed);
    }
    json!({ "type": "object", "properties": properties, "additionalProperties": false })
}

/// Tables of one kind by name (`[cells.NAME]`).
fn named(path: &str, keys: &[&str]) -> Value {
    json!({
        "type": "object",
        "additionalProperties": table(&format!("{path}.*"), keys),
    })
}

/// The JSON Schema of a key of `table` (a dotted path), `None` for a key it does not know.
fn key_type(table_path: &str, key: &str) -> Option<Value> {
    let formats: Vec<&str> = latticebuild_geom::mesh_io::Format::ALL
        .iter()
        .map(|f| f.name())
        .collect();
    Some(match (table_path, key) {
        ("", "build") => table("build", &BUILD_KEYS),
        ("", "cache") => table("cache", &CACHE_KEYS),
        ("", "cells") => named("cells", &CELL_KEYS),
        ("", "scaffolds") => named("scaffolds", &SCAFFOLD_KEYS),
        ("", "outputs") => named("outputs", &ALL_KEYS),
        ("build", "out_dir") => string(),
        ("build", "units") => one_of(&super::UNITS),
        ("build", "report") => one_of(&["full", "basic"]),
        ("build", "previews") => boolean(),
        ("build", "preview_size") => numbers(),
        ("cache", "max_size") => json!({
            "anyOf": [
                { "type": "integer", "minimum": 0 },
                { "type": "string", "pattern": "^\\s*[0-9.]+\\s*([kKmMgGtT][iI]?)?[bB]\\s*$" }
            ]
        }),
        ("cells.*", "tpms" | "expr" | "mesh" | "voxels" | "points" | "crystal" | "extend") => {
            string()
        }
        ("cells.*", "species") => json!({ "anyOf": [string(), strings()] }),
        ("cells.*", "placement") => one_of(&["reference", "fit"]),
        ("cells.*", "sample") => one_of(&["sdf", "containment"]),
        ("cells.*", "shape") => json!({ "type": "array", "items": integer() }),
        ("cells.*", "dtype") => one_of(&["uint8", "uint16", "int16", "float32", "float64"]),
        ("cells.*", "byte_order") => one_of(&["little", "big"]),
        ("cells.*", "values") => one_of(&["occupancy", "distance"]),
        ("cells.*", "threshold" | "offset") => number(),
        ("cells.*", "symmetrize" | "normal_to_faces" | "invert") => boolean(),
        ("cells.*", "blend") => table("cells.*.blend", &BLEND_KEYS),
        ("cells.*", "minkowski") => table("cells.*.minkowski", &MINKOWSKI_KEYS),
        ("cells.*", "reconstruct") => table("cells.*.reconstruct", &RECONSTRUCT_KEYS),
        ("cells.*", "ps") => table("cells.*.ps", &PS_KEYS),
        ("cells.*", "transform") => table("cells.*.transform", &TRANSFORM_KEYS),
        ("cells.*", "symmetry") => json!({
            "anyOf": [string(), table("cells.*.symmetry", &GENERATOR_KEYS)]
        }),
        ("cells.*", "fit") => table("cells.*.fit", &FIT_KEYS),
        ("cells.*", "optimize") => table("cells.*.optimize", &OPTIMIZE_KEYS),
        ("cells.*.fit", "n") => json!({ "anyOf": [integer(), { "const": "auto" }] }),
        ("cells.*.fit", "max_n") => integer(),
        ("cells.*.fit" | "cells.*.optimize" | "cells.*.reconstruct", "tolerance") => number(),
        ("cells.*.optimize", "volume_fraction" | "surface_area") => number(),
        ("cells.*.optimize", "max_iterations") => integer(),
        ("cells.*.symmetry", "generators") => json!({ "type": "array" }),
        ("cells.*.symmetry", "dimension") => integer(),
        ("cells.*.blend", "cells") => strings(),
        ("cells.*.blend", "weights") => numbers(),
        ("cells.*.minkowski", "op") => string(),
        ("cells.*.minkowski", "cells") => strings(),
        ("cells.*.reconstruct", "max_scale") => integer(),
        ("cells.*.reconstruct", "include_images" | "optimize") => boolean(),
        ("cells.*.ps", "terms") => json!({
            "type": "array",
            "items": table("cells.*.ps.terms", &TERM_KEYS),
        }),
        ("cells.*.ps.terms", "moment" | "scale" | "vector") => json!({}),
        ("cells.*.transform", "scale") => number_or_numbers(),
        ("cells.*.transform", "rotate") => table("cells.*.transform.rotate", &ROTATE_KEYS),
        ("cells.*.transform", "translate") => numbers(),
        ("cells.*.transform.rotate", "axis") => numbers(),
        ("cells.*.transform.rotate", "angle") => number(),
        ("outputs.*", "cell") => json!({
            "anyOf": [string(), table("outputs.*.cell", &TRANSITION_KEYS)]
        }),
        ("outputs.*.cell", "blend") => json!({}),
        ("outputs.*.cell", "by") => string(),
        ("outputs.*", "sdf" | "over" | "path" | "within" | "scaffold" | "contour") => string(),
        ("outputs.*", "domain" | "bounds") => table("outputs.*.domain", &DOMAIN_KEYS),
        ("outputs.*.domain", "min" | "max") => numbers(),
        ("outputs.*", "cell_size") => number_or_numbers(),
        ("outputs.*", "solid") => one_of(&super::SOLIDS),
        ("outputs.*", "wall" | "grow" | "volume_fraction" | "offset" | "thickness") => {
            number_or_expression()
        }
        ("outputs.*", "samples") => json!({
            "anyOf": [integer(), string(), { "type": "array", "items": integer() }]
        }),
        ("outputs.*", "resolution") => {
            json!({ "anyOf": [integer(), { "type": "array", "items": integer() }] })
        }
        ("outputs.*", "voxel" | "skin" | "min_island_volume" | "extrude" | "thickness_normal") => {
            number()
        }
        ("outputs.*", "formats") => json!({ "type": "array", "items": one_of(&formats) }),
        ("outputs.*", "ascii") => boolean(),
        ("outputs.*", "keep") => one_of(&["all", "largest"]),
        ("scaffolds.*", "mesh") => string(),
        ("scaffolds.*", "grid") => table("scaffolds.*.grid", &GRID_KEYS),
        ("scaffolds.*", "continuity") => one_of(&["c0", "c1"]),
        ("scaffolds.*.grid", "min" | "max") => numbers(),
        ("scaffolds.*.grid", "divisions") => {
            json!({ "anyOf": [integer(), { "type": "array", "items": integer() }] })
        }
        ("scaffolds.*.grid", "element") => string(),
        _ => return None,
    })
}

/// The manifest's JSON Schema (draft 7).
pub(crate) fn manifest_schema() -> Value {
    let mut schema = table("", &TOP_KEYS);
    if let Value::Object(map) = &mut schema {
        let head = [
            ("$schema", json!("http://json-schema.org/draft-07/schema#")),
            (
                "title",
                json!("latticebuild manifest (lattice.toml), version 1"),
            ),
            (
                "description",
                json!(
                    "The keys a latticebuild manifest accepts, table by table, with the kinds \
                     of their values (generated from src/manifest/schema/keys.rs; ranges and \
                     references are checked by `latticebuild build`). See docs/manifest.md."
                ),
            ),
        ];
        let mut ordered = Map::new();
        for (k, v) in head {
            ordered.insert(k.to_string(), v);
        }
        ordered.append(map);
        *map = ordered;
    }
    schema
}

#[cfg(test)]
mod tests {
    use super::manifest_schema;

    /// The committed schema is the generated one (`LATTICEBUILD_BLESS=1` rewrites it).
    #[test]
    fn manifest_json_schema_is_generated_from_the_key_lists() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/manifest.schema.json");
        let generated = serde_json::to_string_pretty(&manifest_schema()).unwrap() + "\n";
        if std::env::var_os("LATTICEBUILD_BLESS").is_some() {
            std::fs::write(&path, &generated).unwrap();
        }
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == generated,
            "docs/manifest.schema.json is stale: run `cargo xtask golden --bless`"
        );
    }

    /// Every table's keys, as the schema lists them, are exactly the keys `keys.rs` lists
    /// for it.
    #[test]
    fn the_schema_lists_exactly_the_keys_of_each_table() {
        use crate::manifest::schema::keys::*;
        let schema = manifest_schema();
        let keys_at = |pointer: &str| -> Vec<String> {
            let mut keys: Vec<String> = schema
                .pointer(pointer)
                .and_then(|v| v.as_object())
                .unwrap_or_else(|| panic!("no table at {pointer}"))
                .keys()
                .cloned()
                .collect();
            keys.sort();
            keys
        };
        let sorted = |list: &[&str]| -> Vec<String> {
            let mut keys: Vec<String> = list.iter().map(|s| s.to_string()).collect();
            keys.sort();
            keys
        };
        let cell = "/properties/cells/additionalProperties/properties";
        let output = "/properties/outputs/additionalProperties/properties";
        let scaffold = "/properties/scaffolds/additionalProperties/properties";
        let tables: [(String, &[&str]); 12] = [
            ("/properties".into(), &TOP_KEYS),
            ("/properties/build/properties".into(), &BUILD_KEYS),
            ("/properties/cache/properties".into(), &CACHE_KEYS),
            (cell.into(), &CELL_KEYS),
            (format!("{cell}/fit/properties"), &FIT_KEYS),
            (format!("{cell}/optimize/properties"), &OPTIMIZE_KEYS),
            (format!("{cell}/reconstruct/properties"), &RECONSTRUCT_KEYS),
            (format!("{cell}/transform/properties"), &TRANSFORM_KEYS),
            (output.into(), &ALL_KEYS),
            (format!("{output}/domain/properties"), &DOMAIN_KEYS),
            (scaffold.into(), &SCAFFOLD_KEYS),
            (format!("{scaffold}/grid/properties"), &GRID_KEYS),
        ];
        for (pointer, keys) in tables {
            assert_eq!(keys_at(&pointer), sorted(keys), "{pointer}");
        }
    }
}
