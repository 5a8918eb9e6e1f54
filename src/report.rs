//! Per-output reports: `out/NAME.report.json`, the `--report` JSON array, and the one-line
//! summary on stderr. Every number comes from our validator run on the mesh that was written
//! (with `formats = []`, the mesh that would have been: the same artifact, measured the same
//! way), except a shell's thinnest wall, which the contourer measured on its samples. Warnings
//! (`warnings` in the JSON) are also printed on stderr, one `warning:` line each.
//!
//! The JSON is a contract with programs (`docs/report.schema.json`, against which the tests
//! validate every example's reports): each report says [`SCHEMA_VERSION`], the tool's version,
//! its units, the output's parameters as given and as resolved, and `--report` lists a [`FailedOutput`] for each
//! output that did not build. A field that changes meaning or goes raises the version.

use serde::Serialize;

use crate::build::OutputResult;
use crate::manifest::Manifest;
use crate::stages::measure::Spread;
use crate::stages::warnings::{self, percent};
use crate::stages::{Removed, TilingSummary};

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bbox {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageReport {
    pub stage: String,
    pub cached: bool,
    pub seconds: f64,
}

/// The version of the report's JSON layout ([`Report::schema_version`]): raised when a field
/// changes meaning or goes, not when one is added (`docs/report.schema.json` describes it).
pub const SCHEMA_VERSION: u32 = 1;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// [`SCHEMA_VERSION`]: what a program reading the report may rely on.
    pub schema_version: u32,
    /// The version of latticebuild that built the output.
    pub tool_version: String,
    /// `"built"` (a failed output's entry in `--report` says `"failed"`: [`FailedOutput`]).
    pub status: &'static str,
    pub name: String,
    pub triangles: u64,
    pub vertices: u64,
    pub watertight: bool,
    pub manifold: bool,
    pub euler_characteristic: i64,
    pub volume: f64,
    pub area: f64,
    /// Area over volume, per unit of [`Report::units`] (`null` for a planar region or a mesh
    /// of no volume).
    pub specific_surface: Option<f64>,
    /// What lengths are in (`[build] units`).
    pub units: String,
    /// Volume over the domain's volume; for a planar region (2D cell), area over the element's.
    pub volume_fraction: f64,
    /// Solid pieces of the mesh (connected surfaces of positive volume, so a cavity inside a
    /// piece is not one; for a planar region, connected parts); more than one is warned
    /// about: a lattice that falls apart into loose pieces is rarely what was meant.
    pub components: u64,
    /// The largest piece's share of the volume (of the area, for a planar region), each
    /// piece measured within its outer surface.
    pub largest_component_fraction: f64,
    /// What `keep`/`min_island_volume` removed (the other numbers describe what was kept).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub removed: Option<Removed>,
    /// A planar region of a 2D cell (open by nature: `watertight` is false).
    pub planar: bool,
    /// For an SDF output, the box it was contoured over (its bounds, when not given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sdf_box: Option<Bbox>,
    /// For a tiled output: the scaffold's element kind, counts and volume (the volume
    /// fraction is over the scaffold's volume).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tiling: Option<TilingSummary>,
    /// For a shell: its thinnest wall in sample spacings, or lattice spacings when tiled (see
    /// [`crate::stages::ShellSummary::thinnest_wall`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thinnest_wall: Option<f64>,
    /// For a solid sized by `wall`, `grow` or `volume_fraction`: what was asked and, for a
    /// volume fraction, the level or wall solved and the bisection steps it took.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sizing: Option<crate::stages::artifact::SizingSummary>,
    /// Local thickness of the solid (the diameter of the largest ball inside the solid that
    /// holds the point) over its volume, `{min, p05, median, max}` in model units, with the
    /// voxel it was measured on; absent with `[build] report = "basic"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_thickness: Option<Spread>,
    /// Local thickness of the void within the output's box (blocks of a cell only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pore_size: Option<Spread>,
    /// The genus (handles) of each solid piece, largest piece first (at most
    /// [`crate::stages::measure::GENUS_LISTED`]); `null` for a surface that is not closed.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub genus: Vec<Option<i64>>,
    /// Closed voids sealed inside the solid.
    pub cavities: u64,
    /// What the build found worth saying about this output: more than one piece, a wall
    /// thinner than [`crate::stages::ShellSummary::THIN_WALL`] sample spacings, an automatic N that stopped
    /// at `max_n` short of its tolerance.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    pub bbox: Bbox,
    pub files: Vec<String>,
    pub stages: Vec<StageReport>,
    /// What is wrong with the mesh (not closed, not manifold); empty for a good one. A build
    /// with a defective output fails unless the user allowed defects.
    pub defects: Vec<String>,
    /// The estimate made before the build (peak memory, bytes written, triangles), against
    /// which it was allowed to run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimate: Option<crate::budget::Estimate>,
    /// The output's `[outputs.NAME]` table as the build read it, after `--set` and `--unset`
    /// (defaults not filled in).
    pub parameters: serde_json::Value,
    /// What the build used ([`Manifest::resolved`]): the output's keys with every default
    /// filled in from the parsed manifest, and the referenced cell's (and scaffold's) table
    /// with its `name`. The written files' stamps (3MF metadata) carry the same values.
    pub resolved: serde_json::Value,
}

/// An output that did not build, as `--report` lists it beside the reports of those that did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FailedOutput {
    pub schema_version: u32,
    pub tool_version: String,
    /// Always `"failed"`.
    pub status: &'static str,
    pub output: String,
    /// Why, as the error line on stderr says it.
    pub error: String,
}

impl FailedOutput {
    pub fn new(output: &str, error: String) -> FailedOutput {
        FailedOutput {
            schema_version: SCHEMA_VERSION,
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            status: "failed",
            output: output.to_string(),
            error,
        }
    }
}

impl Report {
    pub fn new(manifest: &Manifest, result: &OutputResult) -> Report {
        let s = &result.written.summary;
        let domain = manifest
            .outputs
            .get(&result.name)
            .map(|o| [o.domain_min, o.domain_max]);
        let planar = result.written.planar_element_area.is_some();
        let volume_fraction = warnings::volume_fraction(&result.written, domain);
        let sizing = result.written.sizing.clone();
        let measures = result.written.measures.as_ref();
        let within = manifest
            .outputs
            .get(&result.name)
            .is_some_and(|o| o.within.is_some());
        Report {
            schema_version: SCHEMA_VERSION,
            tool_version: env!("CARGO_PKG_VERSION").to_string(),
            status: "built",
            parameters: manifest
                .parameters
                .get(&result.name)
                .cloned()
                .unwrap_or_else(|| serde_json::Value::Object(Default::default())),
            resolved: manifest
                .resolved(&result.name)
                .unwrap_or_else(|| serde_json::Value::Object(Default::default())),
            defects: defects(s.watertight, s.manifold, planar),
            estimate: None,
            name: result.name.clone(),
            triangles: s.triangles,
            vertices: s.vertices,
            watertight: s.watertight,
            manifold: s.manifold,
            euler_characteristic: s.euler_characteristic,
            volume: s.volume,
            area: s.area,
            specific_surface: specific_surface(s.area, s.volume, planar),
            units: manifest.units.clone(),
            // A planar region reports its share of the element's area.
            volume_fraction,
            planar,
            sdf_box: result.written.domain.map(|[min, max]| Bbox { min, max }),
            tiling: result.written.tiling.clone(),
            thinnest_wall: result.written.shell.as_ref().and_then(|s| s.thinnest_wall),
            components: s.components,
            largest_component_fraction: s.largest_component_fraction,
            removed: s.removed.clone(),
            warnings: warnings::mesh_warnings(&result.written, volume_fraction, within)
                .into_iter()
                .chain(result.warnings.iter().cloned())
                .collect(),
            wall_thickness: measures.and_then(|m| m.wall_thickness),
            pore_size: measures.and_then(|m| m.pore_size),
            genus: measures.map(|m| m.genus.clone()).unwrap_or_default(),
            cavities: measures.map_or(0, |m| m.cavities),
            sizing,
            bbox: Bbox {
                min: s.bbox_min,
                max: s.bbox_max,
            },
            files: result
                .written
                .files
                .iter()
                .chain(&result.preview)
                .map(|f| manifest.out_dir.join(&f.path).display().to_string())
                .collect(),
            stages: result
                .stages
                .iter()
                .map(|r| StageReport {
                    stage: r.node.clone(),
                    cached: r.cached,
                    seconds: r.seconds,
                })
                .collect(),
        }
    }

    /// The warning lines for stderr, `warning: NAME: …` each.
    pub fn warning_lines(&self) -> Vec<String> {
        self.warnings
            .iter()
            .map(|w| format!("warning: {}: {w}", self.name))
            .collect()
    }

    /// The one-line human summary.
    pub fn summary_line(&self) -> String {
        let seconds: f64 = self.stages.iter().map(|s| s.seconds).sum();
        let cached = self.stages.iter().filter(|s| s.cached).count();
        let validity = match (self.watertight, self.manifold) {
            _ if self.planar => format!(
                "planar region, {}, area fraction {:.4}",
                if self.manifold {
                    "manifold"
                } else {
                    "NOT manifold"
                },
                self.volume_fraction
            ),
            (true, true) => "watertight, manifold".to_string(),
            (w, m) => format!(
                "{}, {}",
                if w { "watertight" } else { "NOT watertight" },
                if m { "manifold" } else { "NOT manifold" }
            ),
        };
        let tiled = match &self.tiling {
            Some(t) => format!(" in {} {} elements", t.elements, t.element),
            None => String::new(),
        };
        let validity = if self.components > 1 {
            format!(
                "{validity}, {} pieces (the largest {})",
                self.components,
                percent(self.largest_component_fraction)
            )
        } else {
            validity
        };
        let validity = match &self.removed {
            Some(r) => format!("{validity}, {}", removed_text(r)),
            None => validity,
        };
        let measured: String = [("wall", self.wall_thickness), ("pore", self.pore_size)]
            .iter()
            .filter_map(|(what, spread)| {
                spread.map(|s| format!(", {what} {:.3} {}", s.median, self.units))
            })
            .collect();
        format!(
            "{}: {} triangles, {} vertices{tiled}, {validity}, volume fraction {:.4}{measured} -> {} ({:.2} s, {cached} of {} stages cached)",
            self.name,
            self.triangles,
            self.vertices,
            self.volume_fraction,
            self.files.join(", "),
            seconds,
            self.stages.len()
        )
    }
}

/// Area over volume for a solid of positive, finite volume.
fn specific_surface(area: f64, volume: f64, planar: bool) -> Option<f64> {
    (!planar && volume > 0.0 && volume.is_finite() && area.is_finite()).then(|| area / volume)
}

/// What the summary line says `keep`/`min_island_volume` removed.
fn removed_text(r: &Removed) -> String {
    match r.pieces {
        0 => "no loose pieces removed".into(),
        1 => format!("1 loose piece removed (volume {:.4e})", r.volume),
        n => format!("{n} loose pieces removed (volume {:.4e})", r.volume),
    }
}

/// The defects a mesh's check found: a solid must be closed and manifold, a planar region
/// (open by nature) manifold.
fn defects(watertight: bool, manifold: bool, planar: bool) -> Vec<String> {
    let mut found = Vec::new();
    if !watertight && !planar {
        found.push("the mesh is not watertight: some edges are used by one triangle only".into());
    }
    if !manifold {
        found.push(
            "the mesh is not manifold: some edges are used by more than two triangles, or \
             some vertices join separate fans"
                .into(),
        );
    }
    found
}

#[cfg(test)]
mod tests {
    use super::{defects, specific_surface};

    #[test]
    fn specific_surface_is_area_over_volume_of_a_solid() {
        // A unit cube: 6 / 1; a sphere of radius 2: 3 / r.
        assert_eq!(specific_surface(6.0, 1.0, false), Some(6.0));
        let r: f64 = 2.0;
        let pi = std::f64::consts::PI;
        let s = specific_surface(4.0 * pi * r * r, 4.0 / 3.0 * pi * r.powi(3), false);
        assert!(s.is_some_and(|s| (s - 1.5).abs() < 1e-12), "{s:?}");
        assert_eq!(specific_surface(1.0, 0.0, false), None);
        assert_eq!(
            specific_surface(1.0, 1.0, true),
            None,
            "a planar region has no volume"
        );
        assert_eq!(specific_surface(f64::NAN, 1.0, false), None);
    }

    #[test]
    fn a_solid_must_be_closed_and_manifold_a_planar_region_manifold() {
        assert!(defects(true, true, false).is_empty());
        assert!(defects(false, true, true).is_empty(), "regions are open");
        assert_eq!(defects(false, true, false).len(), 1);
        assert_eq!(defects(true, false, false).len(), 1);
        assert_eq!(defects(false, false, false).len(), 2);
        assert!(defects(false, false, true)[0].contains("not manifold"));
    }
}
