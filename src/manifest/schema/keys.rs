//! Every key the manifest accepts, table by table: the one list that unknown-key detection,
//! spelling suggestions and `--set` typing ([`expects_string`]) read.
//!
//! Invariants (checked by the tests below):
//! - Each table's keys are listed here and nowhere else in the schema; a checker reads the
//!   list of the table it walks.
//! - Every key listed is documented in `docs/manifest.md`, and every key [`expects_string`]
//!   names is listed in its table.

// `[build]` and the top level.

pub(super) const TOP_KEYS: [&str; 5] = ["build", "cache", "cells", "scaffolds", "outputs"];

pub(super) const BUILD_KEYS: [&str; 5] = ["out_dir", "units", "report", "previews", "preview_size"];

pub(super) const CACHE_KEYS: [&str; 1] = ["max_size"];

// `[cells.NAME]`.

pub(super) const CELL_KEYS: [&str; 27] = [
    "tpms",
    "expr",
    "blend",
    "minkowski",
    "mesh",
    "placement",
    "sample",
    "voxels",
    "shape",
    "dtype",
    "byte_order",
    "values",
    "threshold",
    "points",
    "crystal",
    "species",
    "reconstruct",
    "ps",
    "transform",
    "symmetry",
    "fit",
    "extend",
    "symmetrize",
    "normal_to_faces",
    "offset",
    "invert",
    "optimize",
];

/// The keys that give a cell its shape; a cell has exactly one.
pub(super) const SOURCE_KEYS: [&str; 9] = [
    "tpms",
    "expr",
    "blend",
    "minkowski",
    "mesh",
    "voxels",
    "points",
    "crystal",
    "ps",
];

/// The keys of a fitted cell other than `symmetry`, in the order they are documented.
pub(super) const SYMMETRIC_KEYS: [&str; 7] = [
    "fit",
    "extend",
    "symmetrize",
    "normal_to_faces",
    "offset",
    "invert",
    "optimize",
];

/// The keys of [`SYMMETRIC_KEYS`] that concern sampling a source, so not a combination.
pub(super) const SAMPLING_KEYS: [&str; 2] = ["extend", "symmetrize"];

pub(super) const FIT_KEYS: [&str; 3] = ["n", "tolerance", "max_n"];

pub(super) const OPTIMIZE_KEYS: [&str; 4] = [
    "volume_fraction",
    "surface_area",
    "max_iterations",
    "tolerance",
];

pub(super) const GENERATOR_KEYS: [&str; 2] = ["generators", "dimension"];

pub(super) const BLEND_KEYS: [&str; 2] = ["cells", "weights"];

pub(super) const MINKOWSKI_KEYS: [&str; 2] = ["op", "cells"];

pub(super) const RECONSTRUCT_KEYS: [&str; 4] =
    ["tolerance", "max_scale", "include_images", "optimize"];

pub(super) const PS_KEYS: [&str; 1] = ["terms"];

pub(super) const TERM_KEYS: [&str; 3] = ["moment", "scale", "vector"];

/// The parts of a `ps` or `crystal` cell's `transform`, in the order they apply.
pub(super) const TRANSFORM_KEYS: [&str; 3] = ["scale", "rotate", "translate"];

pub(super) const ROTATE_KEYS: [&str; 2] = ["axis", "angle"];

// `[outputs.NAME]` over a box or a mesh, and their sizing.

pub(super) const OUTPUT_KEYS: [&str; 22] = [
    "cell",
    "sdf",
    "bounds",
    "contour",
    "over",
    "domain",
    "cell_size",
    "solid",
    "wall",
    "grow",
    "volume_fraction",
    "offset",
    "thickness",
    "samples",
    "voxel",
    "formats",
    "ascii",
    "path",
    "within",
    "skin",
    "keep",
    "min_island_volume",
];

pub(super) const DOMAIN_KEYS: [&str; 2] = ["min", "max"];

/// The keys that size a solid in the user's terms.
pub(super) const SIZING_KEYS: [&str; 3] = ["wall", "grow", "volume_fraction"];

// `[scaffolds.NAME]` and the outputs tiled over them.

pub(super) const SCAFFOLD_KEYS: [&str; 3] = ["mesh", "grid", "continuity"];

pub(super) const GRID_KEYS: [&str; 4] = ["min", "max", "divisions", "element"];

/// The keys a tiled output reads; the other output keys are errors beside `scaffold`.
pub(super) const TILED_KEYS: [&str; 17] = [
    "scaffold",
    "cell",
    "solid",
    "wall",
    "grow",
    "volume_fraction",
    "offset",
    "thickness",
    "resolution",
    "skin",
    "extrude",
    "thickness_normal",
    "formats",
    "ascii",
    "path",
    "keep",
    "min_island_volume",
];

/// The keys that make a 2D scaffold's region a solid (at most one).
pub(super) const THICKEN_KEYS: [&str; 2] = ["extrude", "thickness_normal"];

/// Every output key plus the tiled output's own, for unknown-key suggestions.
pub(super) const ALL_KEYS: [&str; OUTPUT_KEYS.len() + 4] = {
    let mut all = [""; OUTPUT_KEYS.len() + 4];
    let mut i = 0;
    while i < OUTPUT_KEYS.len() {
        all[i] = OUTPUT_KEYS[i];
        i += 1;
    }
    all[i] = "scaffold";
    all[i + 1] = "resolution";
    all[i + 2] = THICKEN_KEYS[0];
    all[i + 3] = THICKEN_KEYS[1];
    all
};

pub(super) const TRANSITION_KEYS: [&str; 2] = ["blend", "by"];

// Values.

/// The keys whose values are strings, by the path of their table (`*` stands for a name).
const STRING_KEYS: [(&[&str], &[&str]); 6] = [
    (&["build"], &["out_dir", "units", "report"]),
    (
        &["cells", "*"],
        &[
            "tpms",
            "expr",
            "extend",
            "mesh",
            "placement",
            "sample",
            "crystal",
            "species",
        ],
    ),
    (
        &["outputs", "*"],
        &[
            "cell", "sdf", "over", "solid", "path", "within", "scaffold", "keep", "contour",
        ],
    ),
    (&["outputs", "*", "cell"], &["by"]),
    (&["scaffolds", "*"], &["mesh"]),
    (&["scaffolds", "*", "grid"], &["element"]),
];

/// Whether the schema expects a string at this dotted path (for typing `--set` values).
pub(crate) fn expects_string(path: &[&str]) -> bool {
    let Some((key, table)) = path.split_last() else {
        return false;
    };
    STRING_KEYS.iter().any(|(pattern, keys)| {
        pattern.len() == table.len()
            && pattern.iter().zip(table).all(|(p, t)| *p == "*" || p == t)
            && keys.contains(key)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every table's list, with the dotted path of the table it belongs to.
    const TABLES: &[(&str, &[&str])] = &[
        ("", &TOP_KEYS),
        ("build", &BUILD_KEYS),
        ("cache", &CACHE_KEYS),
        ("cells.*", &CELL_KEYS),
        ("cells.*", &SOURCE_KEYS),
        ("cells.*", &SYMMETRIC_KEYS),
        ("cells.*", &SAMPLING_KEYS),
        ("cells.*.fit", &FIT_KEYS),
        ("cells.*.symmetry", &GENERATOR_KEYS),
        ("cells.*.blend", &BLEND_KEYS),
        ("cells.*.minkowski", &MINKOWSKI_KEYS),
        ("cells.*.reconstruct", &RECONSTRUCT_KEYS),
        ("cells.*.ps", &PS_KEYS),
        ("cells.*.ps.terms", &TERM_KEYS),
        ("cells.*.transform", &TRANSFORM_KEYS),
        ("cells.*.transform.rotate", &ROTATE_KEYS),
        ("outputs.*", &OUTPUT_KEYS),
        ("outputs.*.domain", &DOMAIN_KEYS),
        ("outputs.*", &SIZING_KEYS),
        ("scaffolds.*", &SCAFFOLD_KEYS),
        ("scaffolds.*.grid", &GRID_KEYS),
        ("outputs.*", &TILED_KEYS),
        ("outputs.*", &THICKEN_KEYS),
        ("outputs.*", &ALL_KEYS),
        ("outputs.*.cell", &TRANSITION_KEYS),
    ];

    #[test]
    fn every_key_is_documented() {
        let doc = include_str!("../../../docs/manifest.md");
        for (table, keys) in TABLES {
            for key in *keys {
                let written = [
                    format!("`{key}"),
                    format!("{key} ="),
                    format!(".{key}"),
                    format!("[{key}"),
                ];
                assert!(
                    written.iter().any(|w| doc.contains(w.as_str())),
                    "`{key}` of `[{table}]` is not in docs/manifest.md"
                );
            }
        }
    }

    /// The sub-lists name keys of the table they refine.
    #[test]
    fn sub_lists_are_part_of_their_table() {
        let parts: [(&[&str], &[&str]); 6] = [
            (&SOURCE_KEYS, &CELL_KEYS),
            (&SYMMETRIC_KEYS, &CELL_KEYS),
            (&SAMPLING_KEYS, &SYMMETRIC_KEYS),
            (&SIZING_KEYS, &OUTPUT_KEYS),
            (&THICKEN_KEYS, &TILED_KEYS),
            (&TILED_KEYS, &ALL_KEYS),
        ];
        for (part, whole) in parts {
            for key in part {
                assert!(whole.contains(key), "`{key}` is missing from {whole:?}");
            }
        }
    }

    #[test]
    fn string_keys_are_keys_of_their_table() {
        for (pattern, keys) in STRING_KEYS {
            let table = pattern.join(".");
            let listed: Vec<&str> = TABLES
                .iter()
                .filter(|(t, _)| *t == table)
                .flat_map(|(_, keys)| keys.iter().copied())
                .collect();
            for key in keys {
                assert!(
                    listed.contains(key),
                    "`{key}` of `[{table}]` is not a listed key"
                );
            }
        }
        assert!(expects_string(&["outputs", "lattice", "cell", "by"]));
        assert!(!expects_string(&["outputs", "lattice", "wall"]));
        assert!(!expects_string(&[]));
    }
}
