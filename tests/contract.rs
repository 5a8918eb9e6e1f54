//! The automation contract (docs/manifest.md, "What the report measures"; README, "Driving
//! latticebuild from a program"): reports that say their schema, tool version, units and
//! parameters and validate against `docs/report.schema.json`; a manifest schema that accepts
//! the examples and rejects misspelt keys; `formats = []`; failed outputs in `--report`;
//! `--unset`; a cache that keeps revisited values; `graph --json` and `--dot`.

use crate::common;

use std::path::Path;
use std::process::Command;

use common::{Project, by_name, ran};

fn schema(file: &str) -> jsonschema::Validator {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs")
        .join(file);
    let text = std::fs::read_to_string(&path).expect("schema file");
    let schema: serde_json::Value = serde_json::from_str(&text).expect("schema JSON");
    jsonschema::validator_for(&schema).expect("a valid JSON Schema")
}

/// Panics with every violation when `value` does not validate against `docs/FILE`.
pub fn assert_valid(file: &str, value: &serde_json::Value, what: &str) {
    let validator = schema(file);
    let errors: Vec<String> = validator
        .iter_errors(value)
        .map(|e| e.to_string())
        .collect();
    assert!(
        errors.is_empty(),
        "{what} violates {file}:\n{}",
        errors.join("\n")
    );
}

/// A manifest's TOML text as the JSON an editor's language server validates.
pub fn manifest_json(text: &str) -> serde_json::Value {
    toml::from_str(text).expect("TOML")
}

const BLOCK: &str = r#"
[cells.g]
tpms = "gyroid"

[outputs.g]
cell = "g"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
solid = "inside"
offset = 0.1
samples = 17
"#;

#[test]
fn reports_say_their_schema_tool_units_and_parameters() {
    let p = Project::new(BLOCK);
    let reports = p.build(&[
        "--set",
        "outputs.g.offset=0.25",
        "--set",
        "build.units=\"cm\"",
    ]);
    assert_valid("report.schema.json", &reports, "the --report array");
    let r = by_name(&reports, "g");
    assert_eq!(r["schema_version"], 1);
    assert_eq!(r["tool_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(r["status"], "built");
    assert_eq!(r["units"], "cm");
    let expected = serde_json::json!({
        "cell": "g", "domain": { "min": [0, 0, 0], "max": [1, 1, 1] },
        "solid": "inside", "offset": 0.25, "samples": 17
    });
    assert_eq!(r["parameters"], expected);
    // The file beside the mesh is the same report, and validates alone.
    let file: serde_json::Value =
        serde_json::from_slice(&std::fs::read(p.out("g.report.json")).expect("report file"))
            .expect("JSON");
    assert_valid("report.schema.json", &file, "g.report.json");
    assert_eq!(file["parameters"], expected);
}

/// `(dotted name, value)` of every leaf of `value`'s nested objects.
fn leaves(prefix: &str, value: &serde_json::Value, out: &mut Vec<(String, serde_json::Value)>) {
    match value {
        serde_json::Value::Object(table) => {
            for (key, v) in table {
                let name = if prefix.is_empty() {
                    key.clone()
                } else {
                    format!("{prefix}.{key}")
                };
                leaves(&name, v, out);
            }
        }
        leaf => out.push((prefix.to_string(), leaf.clone())),
    }
}

#[test]
fn resolved_parameters_fill_in_defaults_and_the_3mf_metadata_says_the_same() {
    let p = Project::new(BLOCK);
    let reports = p.build(&[
        "--set",
        "outputs.g.offset=0.25",
        "--set",
        "outputs.g.formats=[\"3mf\"]",
    ]);
    assert_valid("report.schema.json", &reports, "the --report array");
    let r = &by_name(&reports, "g")["resolved"];
    // The value set, the defaults of docs/manifest.md, the cell's table.
    assert_eq!(r["offset"], 0.25);
    assert_eq!(r["solid"], "inside");
    assert_eq!(r["cell_size"], serde_json::json!([1.0, 1.0, 1.0]));
    assert_eq!(r["samples"], serde_json::json!([17, 17, 17]));
    assert_eq!(r["domain"]["max"], serde_json::json!([1.0, 1.0, 1.0]));
    assert_eq!(r["formats"], serde_json::json!(["3mf"]));
    assert_eq!(r["ascii"], false);
    assert_eq!(r["path"], "g");
    assert_eq!(r["keep"], "all");
    assert_eq!(
        r["cell"],
        serde_json::json!({ "name": "g", "tpms": "gyroid" })
    );
    // Every leaf is a `latticebuild:` metadata entry of the 3MF reading back as the same
    // value (a string as itself, anything else as JSON), and there is no other.
    let bytes = std::fs::read(p.out("g.3mf")).expect("g.3mf");
    let model = latticebuild_geom::mesh_read::read_3mf(&bytes).expect("a 3MF");
    let stamped: std::collections::BTreeMap<&str, &str> = model
        .metadata
        .iter()
        .filter_map(|(n, v)| Some((n.strip_prefix("latticebuild:")?, v.as_str())))
        .collect();
    let mut expected = Vec::new();
    leaves("", r, &mut expected);
    assert_eq!(stamped.len(), expected.len(), "{stamped:?}");
    for (name, leaf) in expected {
        let text = stamped
            .get(name.as_str())
            .unwrap_or_else(|| panic!("no {name}"));
        let back = match leaf {
            serde_json::Value::String(_) => serde_json::Value::String(text.to_string()),
            _ => serde_json::from_str(text).unwrap_or_else(|e| panic!("{name}: {text}: {e}")),
        };
        assert_eq!(back, leaf, "{name}");
    }
    let application = model.metadata.iter().find(|(n, _)| n == "Application");
    assert_eq!(
        application.map(|(_, v)| v.as_str()),
        Some(concat!("latticebuild ", env!("CARGO_PKG_VERSION")))
    );
}

#[test]
fn no_formats_writes_nothing_and_reports_the_same_numbers() {
    let p = Project::new(BLOCK);
    let none = p.build(&["--set", "outputs.g.formats=[]"]);
    assert!(!p.out("g.stl").exists(), "no mesh file with `formats = []`");
    let stl = p.build(&["--set", "outputs.g.formats=[\"stl\"]"]);
    assert!(p.out("g.stl").is_file());
    // The contour stage is shared (cached); only the write ran again.
    assert_eq!(ran(&stl), ["write:g"]);
    let strip = |r: &serde_json::Value| {
        let mut r = r.clone();
        let map = r.as_object_mut().expect("object");
        for volatile in ["files", "stages", "parameters", "resolved", "estimate"] {
            map.remove(volatile);
        }
        r
    };
    let (none, stl) = (by_name(&none, "g"), by_name(&stl, "g"));
    assert_eq!(none["files"], serde_json::json!([]));
    // The mesh and its preview.
    assert_eq!(stl["files"].as_array().map(Vec::len), Some(2));
    assert_eq!(strip(none), strip(stl));
    assert!(none["triangles"].as_u64().expect("count") > 100);
    assert_eq!(none["watertight"], true);
}

const ONE_FAILS: &str = r#"
[cells.g]
tpms = "gyroid"

[cells.one]
expr = "1 + 0.5 * cos(tau * x)"

[outputs.blank]
cell = "one"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 9

[outputs.g]
cell = "g"
domain = { min = [0, 0, 0], max = [1, 1, 1] }
samples = 13
"#;

#[test]
fn a_failed_build_still_reports_what_built_and_why_the_rest_failed() {
    let p = Project::new(ONE_FAILS);
    let out = p.run(&["build", "lattice.toml", "--report", "-", "-q"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let reports: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    assert_valid("report.schema.json", &reports, "a failed build's --report");
    let entries = reports.as_array().expect("array");
    assert_eq!(entries.len(), 2, "{reports:#}");
    let blank = &entries[0];
    assert_eq!(blank["status"], "failed");
    assert_eq!(blank["output"], "blank");
    let error = blank["error"].as_str().expect("error text");
    assert!(error.contains("the output is empty"), "{error}");
    assert!(stderr.contains(error), "stderr says the same: {stderr}");
    let g = &entries[1];
    assert_eq!(
        (g["status"].as_str(), g["name"].as_str()),
        (Some("built"), Some("g"))
    );
    assert_eq!(g["watertight"], true);
    assert!(p.out("g.stl").is_file(), "the output that built is written");
    assert!(!p.out("blank.stl").exists());
}

#[test]
fn unset_switches_a_grid_from_voxel_to_samples() {
    let p = Project::new(&BLOCK.replace("samples = 17", "voxel = 0.05"));
    let by_voxel = p.build(&[]);
    assert_eq!(by_name(&by_voxel, "g")["parameters"]["voxel"], 0.05);
    let switched = p.build(&[
        "--unset",
        "outputs.g.voxel",
        "--set",
        "outputs.g.samples=17",
    ]);
    let r = by_name(&switched, "g");
    assert_eq!(r["parameters"].get("voxel"), None);
    assert_eq!(r["parameters"]["samples"], 17);
    // The same mesh as a manifest that says `samples = 17`.
    let written = Project::new(BLOCK).build(&[]);
    assert_eq!(r["triangles"], by_name(&written, "g")["triangles"]);
    assert_ne!(r["triangles"], by_name(&by_voxel, "g")["triangles"]);
    // A key that is not there is an error naming the argument.
    let out = p.run(&["build", "lattice.toml", "--unset", "outputs.g.samples"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("cannot unset `outputs.g.samples`"),
        "{stderr}"
    );
    assert!(stderr.contains("--> --unset:1:11"), "{stderr}");
}

#[test]
fn a_value_revisited_is_found_in_the_cache() {
    let p = Project::new(&BLOCK.replace("samples = 17", "samples = 17\nformats = []"));
    let at = |offset: &str| {
        let reports = p.build(&["--set", &format!("outputs.g.offset={offset}")]);
        ran(&reports)
    };
    assert_eq!(at("0.1"), ["cell:g", "contour:g", "write:g"]);
    assert_eq!(at("0.2"), ["contour:g", "write:g"]);
    assert!(
        at("0.1").is_empty(),
        "every stage of a value built before is cached"
    );
    // With files, the write puts them back (the files on disk are the last value's).
    let with_files = |offset: &str| {
        let set = format!("outputs.g.offset={offset}");
        ran(&p.build(&["--set", &set, "--set", "outputs.g.formats=[\"stl\"]"]))
    };
    assert_eq!(with_files("0.1"), ["write:g"]);
    assert_eq!(with_files("0.2"), ["write:g"]);
}

#[test]
fn a_tiny_cache_limit_keeps_only_what_the_last_build_used() {
    let p = Project::new(&BLOCK.replace("samples = 17", "samples = 17\nformats = []"));
    let at = |offset: &str, limit: &str| {
        let reports = p.build(&[
            "--set",
            &format!("outputs.g.offset={offset}"),
            "--set",
            &format!("cache.max_size={limit}"),
        ]);
        ran(&reports)
    };
    at("0.1", "\"4GB\"");
    at("0.2", "\"4GB\"");
    // Within the limit both stay; at 0 bytes the other value's entries go.
    assert!(at("0.1", "\"4GB\"").is_empty());
    assert!(at("0.2", "0").is_empty(), "what a build uses stays");
    assert_eq!(at("0.2", "0"), Vec::<String>::new());
    assert_eq!(at("0.1", "0"), ["contour:g", "write:g"], "0.1 was evicted");
    let objects = p.path().join(".latticebuild/lattice.toml/objects");
    let entries = std::fs::read_dir(&objects)
        .expect("objects")
        .flat_map(|shard| std::fs::read_dir(shard.expect("shard").path()).expect("shard dir"))
        .count();
    assert_eq!(entries, 3, "cell, contour and write of the last build");
}

#[test]
fn graph_prints_json_and_dot() {
    let p = Project::new(
        ONE_FAILS
            .replace("[outputs.blank]", "[outputs.blank]\nformats = [\"ply\"]")
            .as_str(),
    );
    p.run(&["build", "lattice.toml", "-q", "g"]);
    let out = p.run(&["graph", "lattice.toml", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let nodes: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let nodes = nodes.as_array().expect("array");
    let find = |id: &str| {
        nodes
            .iter()
            .find(|n| n["id"] == id)
            .unwrap_or_else(|| panic!("no node {id}"))
    };
    let contour = find("contour:g");
    assert_eq!(contour["kind"], "contour");
    assert_eq!(contour["status"], "cached");
    assert_eq!(contour["why"], serde_json::Value::Null);
    assert_eq!(contour["inputs"], serde_json::json!(["cell:g"]));
    let blank = find("write:blank");
    assert_eq!(blank["status"], "stale");
    assert!(blank["why"].as_str().is_some_and(|w| !w.is_empty()));
    // Build order: every node after its inputs.
    for (i, node) in nodes.iter().enumerate() {
        for input in node["inputs"].as_array().expect("inputs") {
            let at = nodes
                .iter()
                .position(|n| n["id"] == *input)
                .expect("input node");
            assert!(at < i, "{input} after {}", node["id"]);
        }
    }
    let out = p.run(&["graph", "lattice.toml", "--dot"]);
    let dot = String::from_utf8(out.stdout).expect("UTF-8");
    assert!(dot.starts_with("digraph latticebuild {"), "{dot}");
    let edges: usize = nodes
        .iter()
        .map(|n| n["inputs"].as_array().map_or(0, Vec::len))
        .sum();
    assert_eq!(dot.matches(" -> ").count(), edges);
    for node in nodes {
        for input in node["inputs"].as_array().expect("inputs") {
            let line = format!("  {input} -> {};", node["id"]);
            assert!(dot.contains(&line), "no `{line}` in\n{dot}");
        }
    }
}

#[test]
fn the_manifest_schema_accepts_the_examples_and_rejects_mistakes() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut checked = 0;
    for entry in std::fs::read_dir(&examples).expect("examples") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).expect("manifest");
            assert_valid(
                "manifest.schema.json",
                &manifest_json(&text),
                &path.display().to_string(),
            );
            checked += 1;
        }
    }
    assert!(checked >= 10, "{checked} examples");
    let validator = schema("manifest.schema.json");
    for (why, bad) in [
        ("a misspelt key", BLOCK.replace("samples", "sample")),
        (
            "an unknown table",
            format!("{BLOCK}\n[bulid]\nunits = \"mm\"\n"),
        ),
        (
            "a number as a string",
            BLOCK.replace("offset = 0.1", "offset = true"),
        ),
        (
            "an unknown solid",
            BLOCK.replace("\"inside\"", "\"insides\""),
        ),
        ("an unknown format", format!("{BLOCK}formats = [\"stp\"]\n")),
        ("a bad unit", format!("[build]\nunits = \"mile\"\n{BLOCK}")),
        (
            "a cache size without a unit",
            format!("[cache]\nmax_size = \"4\"\n{BLOCK}"),
        ),
    ] {
        assert!(
            !validator.is_valid(&manifest_json(&bad)),
            "{why} passes:\n{bad}"
        );
    }
    let fine = format!("[cache]\nmax_size = \"1.5 GiB\"\n{BLOCK}formats = []\n");
    assert!(validator.is_valid(&manifest_json(&fine)));
}

/// README's optimizer loop, `examples/optimizer_loop.py`, runs against this build and finds
/// its offset, and its last line is a build served from the cache.
#[test]
fn the_readme_optimizer_loop_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README");
    let script = std::fs::read_to_string(root.join("examples/optimizer_loop.py")).expect("script");
    let shown = readme
        .split("```python\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("a python block in README.md");
    assert!(
        script.contains(shown.trim()),
        "README's loop is not examples/optimizer_loop.py's"
    );
    let scratch = tempfile::tempdir().expect("tempdir");
    let manifest = scratch.path().join("optimizer_loop.toml");
    std::fs::copy(root.join("examples/optimizer_loop.toml"), &manifest).expect("copy");
    let out = Command::new("python3")
        .arg(root.join("examples/optimizer_loop.py"))
        .arg(common::BIN)
        .arg(&manifest)
        .output()
        .expect("python3");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fraction: f64 = stdout
        .lines()
        .rev()
        .nth(1)
        .and_then(|l| l.split("volume fraction ").nth(1))
        .and_then(|t| t.split(',').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!((fraction - 0.30).abs() < 0.01, "{fraction}\n{stdout}");
    let last = stdout.lines().last().unwrap_or_default();
    assert!(last.ends_with("3 of 3 stages cached"), "{stdout}");
    assert!(
        !scratch.path().join("out/block.stl").exists(),
        "formats = [] writes no mesh"
    );
}
