//! What a build says about an output besides its numbers: the warnings of its mesh (loose
//! pieces, thin walls, a missed volume fraction, sealed cavities, measures not taken) and of
//! the cells it was made from (read from their stages' payloads). The report lists them and
//! the preview draws them, from this one place, so the two always agree.

use super::Stage;
use super::artifact::{ShellSummary, SizingSummary, WrittenOutput};
use super::measure::Measures;
use super::symmetric::FittedPayload;

/// How far a built volume fraction may be from the one asked before the report says so.
pub const FRACTION_TOLERANCE: f64 = 0.01;

/// The output's volume fraction: volume over the scaffold's volume (tiled), or over the box
/// it was made in (`domain`: an SDF output's found box, else the manifest's for a cell);
/// for a planar region, its area over the element's.
pub fn volume_fraction(written: &WrittenOutput, domain: Option<[[f64; 3]; 2]>) -> f64 {
    let s = &written.summary;
    if let Some(element_area) = written.planar_element_area {
        return s.area / element_area;
    }
    let domain_volume = match &written.tiling {
        Some(tiling) => tiling.scaffold_volume,
        None => written.domain.or(domain).map_or(f64::NAN, |[min, max]| {
            (0..3).map(|a| max[a] - min[a]).product()
        }),
    };
    s.volume / domain_volume
}

/// The warnings of the mesh written: more than one piece, a thin shell wall, a volume
/// fraction missed, sealed cavities, measures not taken. `within`: the solid fills a part,
/// so its fraction (over the box) is not compared with the one asked.
pub fn mesh_warnings(written: &WrittenOutput, volume_fraction: f64, within: bool) -> Vec<String> {
    let s = &written.summary;
    let planar = written.planar_element_area.is_some();
    pieces_warning(s.components, s.largest_component_fraction, planar)
        .into_iter()
        .chain(written.shell.as_ref().and_then(ShellSummary::warning))
        .chain(
            written
                .sizing
                .as_ref()
                .and_then(|s| fraction_warning(s, volume_fraction, within)),
        )
        .chain(written.measures.iter().flat_map(measure_warnings))
        .collect()
}

/// Whether node payloads of this stage may carry a warning ([`node_warning`]).
pub fn carries_warning(stage: &Stage) -> bool {
    match stage {
        Stage::Fit(fit) => !fit.reads_samples(),
        Stage::Constrain(_) | Stage::Crystal(_) => true,
        _ => false,
    }
}

/// The warning node `node`'s payload carries: an automatic-N fit that stopped short of its
/// tolerance, an `optimize` that did not reach its target, or a crystal cell through whose
/// atoms several surfaces fit; `None` for every other node.
pub fn node_warning(stage: &Stage, node: &str, payload: &[u8]) -> Option<String> {
    if !carries_warning(stage) {
        return None;
    }
    let cell = node.split_once(':').map_or(node, |(_, cell)| cell);
    let fitted = || FittedPayload::from_bytes(payload).ok();
    let warning = match stage {
        Stage::Crystal(_) => return super::crystal::multiplicity_warning(cell, payload),
        Stage::Fit(_) => fitted().and_then(|p| p.auto).and_then(|a| a.warning()),
        _ => fitted()
            .and_then(|p| p.optimization)
            .and_then(|o| o.warning()),
    };
    warning.map(|w| format!("cell `{cell}`: {w}"))
}

/// A volume fraction asked for and missed by more than [`FRACTION_TOLERANCE`]: the table is
/// of one period (or element), so a domain that cuts periods or a skin moves it. Within a
/// part the report's fraction is over the box, not the part: not compared.
fn fraction_warning(sizing: &SizingSummary, achieved: f64, within: bool) -> Option<String> {
    let asked = sizing
        .target
        .filter(|_| sizing.by == "volume_fraction" && !within)?;
    ((achieved - asked).abs() > FRACTION_TOLERANCE).then(|| {
        format!(
            "the volume fraction is {achieved:.4}, not the {asked} asked: it was solved over one \
             period of the cell (or its reference element), which a domain that cuts periods, a \
             skin, or elements that are not affine images of the reference element change"
        )
    })
}

/// Sealed cavities, and local thickness that was asked for and not measured. (No warning is
/// drawn from the thickness figures themselves: their low percentiles hold the voxels at the
/// part's cut edges, where local thickness goes to zero by definition.)
fn measure_warnings(m: &Measures) -> impl Iterator<Item = String> + '_ {
    let cavities = (m.cavities > 0).then(|| {
        format!(
            "{} sealed {} inside the solid: powder or resin stays trapped there (a skin or \
             a cap closes the lattice off; open it with a drain hole, or leave the skin out)",
            m.cavities,
            if m.cavities == 1 {
                "cavity"
            } else {
                "cavities"
            }
        )
    });
    let missing = m
        .not_measured
        .as_ref()
        .map(|why| format!("wall thickness and pore size not measured: {why}"));
    cavities.into_iter().chain(missing)
}

/// The warning for a mesh of more than one piece, with the largest piece's share.
pub fn pieces_warning(components: u64, largest: f64, planar: bool) -> Option<String> {
    (components > 1).then(|| {
        // A planar region cannot drop pieces (their drawing would keep them).
        let remedy = if planar {
            "check the sizing or the cell's fit"
        } else {
            "check the sizing or the cell's fit, or drop them with `keep = \"largest\"` or \
             `min_island_volume`"
        };
        format!(
            "the mesh is {components} separate pieces; the largest holds {} of the {}: loose \
             pieces fall out of a print ({remedy})",
            percent(largest),
            if planar { "area" } else { "volume" }
        )
    })
}

/// A fraction as a percentage with two significant decimals where small (`0.3 %`, `97 %`).
pub fn percent(fraction: f64) -> String {
    let p = 100.0 * fraction;
    if p >= 10.0 {
        format!("{p:.0} %")
    } else if p >= 1.0 {
        format!("{p:.1} %")
    } else {
        format!("{p:.2} %")
    }
}

#[cfg(test)]
mod tests {
    use super::{percent, pieces_warning};

    #[test]
    fn more_than_one_piece_is_a_warning_with_the_largest_share() {
        assert_eq!(pieces_warning(1, 1.0, false), None);
        let warning = pieces_warning(5166, 0.003, false).expect("warned");
        assert!(
            warning.starts_with(
                "the mesh is 5166 separate pieces; the largest holds 0.30 % of the volume"
            ),
            "{warning}"
        );
        assert!(pieces_warning(2, 0.6, true).is_some_and(|w| w.contains("60 % of the area")));
        assert_eq!(percent(0.5), "50 %");
        assert_eq!(percent(0.0123), "1.2 %");
    }
}
