//! The schema of loose-piece removal, the same on every kind of output (cell, SDF, tiled):
//! `keep = "largest"` (or `"all"`, the default) and `min_island_volume = V`.
//!
//! A child of `schema.rs` (it extends its `Checker`). Invariants:
//! - `keep` is one of [`KEEP`], an error at the value otherwise (with the closest spelling);
//!   `min_island_volume` is a finite number greater than 0.
//! - Both together are allowed and both apply: the largest piece is kept, and only if its
//!   volume reaches `V` (otherwise the build fails rather than write an empty mesh).
//! - Where the output is known here to be a planar region (a 2D domain, a 2D grid without
//!   `extrude`/`thickness_normal`), either key (but `keep = "all"`) is an error at its key: a region's pieces have
//!   no volume, and its drawing is made with it. A scaffold file's dimension is known only when
//!   it is read: the `islands` stage refuses a region then.

use latticebuild_geom::islands::IslandFilter;
use latticebuild_geom::spelling;

use super::{Checker, Fields};

/// What `keep` accepts.
const KEEP: [&str; 2] = ["all", "largest"];

impl Checker<'_, '_, '_> {
    /// `keep` and `min_island_volume` of output `output`; `None` when anything was reported.
    pub(super) fn islands(
        &mut self,
        output: &str,
        fields: &Fields<'_, '_>,
        region: bool,
    ) -> Option<IslandFilter> {
        let before = self.report.len();
        let path = |k: &str| format!("outputs.{output}.{k}");
        let mut filter = IslandFilter::default();
        if let Some((_, value)) = fields.get("keep") {
            let key = path("keep");
            match self.string(&key, value) {
                Some("all") | None => {}
                Some("largest") => filter.largest = true,
                Some(text) => {
                    let help = match spelling::closest(text, KEEP) {
                        Some(close) => format!("did you mean `\"{close}\"`?"),
                        None => "`\"largest\"` keeps the largest piece only; `\"all\"` (the \
                                 default) keeps every piece"
                            .to_string(),
                    };
                    self.error(
                        value.span(),
                        &format!("unknown value `{text}` for `{key}`"),
                        "expected \"largest\" or \"all\"",
                        Some(&help),
                    );
                }
            }
        }
        if let Some((_, value)) = fields.get("min_island_volume") {
            filter.min_volume = self.positive_number(&path("min_island_volume"), value, "a number");
        }
        if region {
            let asked = [
                ("keep", filter.largest),
                (
                    "min_island_volume",
                    fields.contains_key("min_island_volume"),
                ),
            ];
            for (k, _) in asked.into_iter().filter(|&(_, asked)| asked) {
                if let Some((key, _)) = fields.get(k) {
                    self.error(
                        key.span(),
                        &format!("`{}` does not apply to a planar region", path(k)),
                        "a region's pieces have an area, not a volume",
                        Some(
                            "remove it, or make the region a solid: `[x, y, z]` domain \
                             corners fill a box with the 2D cell as a prism; `extrude = h` or \
                             `thickness_normal = h` thicken a 2D scaffold's region",
                        ),
                    );
                }
            }
        }
        (self.report.len() == before).then_some(filter)
    }
}
