//! SVG drawing of a planar region inside its element's outline.
//!
//! Conventions: the viewBox is the outline's bounding box (the region's, when the outline is
//! empty) with a margin of 2% of its larger side. SVG's y axis points down, so every y is written
//! negated and the picture shows +y up. The region is ONE `<path>` holding every boundary loop
//! (`M … L … Z` per loop) with `fill-rule="evenodd"`, so holes stay empty whatever their
//! orientation; the outline is a thin unfilled `<polygon>` drawn on top.
//!
//! [`scaffold_svg`] draws a tiled planar region the same way, with the scaffold's element edges
//! as one faint unfilled `<path>` on top instead of an outline.
//!
//! [`with_physical_size`] gives a drawing its size on paper: `width` and `height` are the
//! viewBox's, in the model's unit (as a CSS length), so one model unit prints as one unit.
//!
//! Invariants: the output is a pure function of the input (numbers are printed with a fixed
//! number of decimals, trailing zeros trimmed and `-0` written `0`); nothing is written when a
//! coordinate is not finite, which fails with `InvalidInput`.

use super::stamp::Units;
use crate::contour2d::PlanarRegion;
use std::fmt::Write as _;
use std::io::{self, Write};

/// Decimals printed per coordinate: 1e-6 is far below anything visible at any sane size.
const DECIMALS: usize = 6;

/// Writes `region` and `element_outline` as a standalone SVG document to `out`.
pub fn write_svg(
    region: &PlanarRegion,
    element_outline: &[[f64; 2]],
    out: &mut dyn Write,
) -> io::Result<()> {
    let all_points = element_outline
        .iter()
        .chain(region.boundary.iter().flatten());
    check_finite(all_points)?;
    let framed: Vec<&[f64; 2]> = if element_outline.is_empty() {
        region.boundary.iter().flatten().collect()
    } else {
        element_outline.iter().collect()
    };
    let (mut svg, stroke) = header(&framed);
    region_path(&mut svg, &region.boundary);
    let points: Vec<String> = element_outline
        .iter()
        .map(|p| format!("{},{}", num(p[0]), num(-p[1])))
        .collect();
    let _ = writeln!(
        svg,
        "<polygon points=\"{}\" fill=\"none\" stroke=\"black\" stroke-width=\"{}\"/>",
        points.join(" "),
        num(stroke),
    );
    svg.push_str("</svg>\n");
    out.write_all(svg.as_bytes())?;
    out.flush()
}

/// A tiled planar region (its boundary `loops`, filled as in [`write_svg`]) over its
/// scaffold, whose element edges (`lines`, polylines) are drawn faintly on top, as one
/// `<path>`. The viewBox frames the lines (the loops when there are none).
pub fn scaffold_svg(loops: &[Vec<[f64; 2]>], lines: &[Vec<[f64; 2]>]) -> io::Result<String> {
    check_finite(loops.iter().chain(lines).flatten())?;
    let framed: Vec<&[f64; 2]> = if lines.is_empty() {
        loops.iter().flatten().collect()
    } else {
        lines.iter().flatten().collect()
    };
    let (mut svg, stroke) = header(&framed);
    region_path(&mut svg, loops);
    let mut d = String::new();
    for line in lines {
        for (k, p) in line.iter().enumerate() {
            if !d.is_empty() {
                d.push(' ');
            }
            d.push_str(if k == 0 { "M" } else { "L" });
            let _ = write!(d, "{},{}", num(p[0]), num(-p[1]));
        }
    }
    let _ = writeln!(
        svg,
        "<path d=\"{d}\" fill=\"none\" stroke=\"#808080\" stroke-opacity=\"0.5\" stroke-width=\"{}\"/>",
        num(0.3 * stroke),
    );
    svg.push_str("</svg>\n");
    Ok(svg)
}

/// `InvalidInput` naming the first point with a non-finite coordinate.
fn check_finite<'a>(mut points: impl Iterator<Item = &'a [f64; 2]>) -> io::Result<()> {
    match points.find(|p| !(p[0].is_finite() && p[1].is_finite())) {
        Some(p) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("point {p:?} has a non-finite coordinate"),
        )),
        None => Ok(()),
    }
}

/// The opening `<svg>` tag framing `framed` (see the module docs), and the outline's stroke
/// width.
fn header(framed: &[&[f64; 2]]) -> (String, f64) {
    let (min, max) = bounds(framed);
    let size = [max[0] - min[0], max[1] - min[1]];
    let margin = 0.02 * size[0].max(size[1]);
    let stroke = 0.005 * size[0].max(size[1]);
    let mut svg = String::new();
    // Writing to a String cannot fail, so the `fmt::Result`s here are ignored, not unwrapped.
    let _ = writeln!(
        svg,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{} {} {} {}\">",
        num(min[0] - margin),
        num(-max[1] - margin),
        num(size[0] + 2.0 * margin),
        num(size[1] + 2.0 * margin),
    );
    (svg, stroke)
}

/// The region: one even-odd filled `<path>` with a `M … L … Z` run per loop.
fn region_path(svg: &mut String, loops: &[Vec<[f64; 2]>]) {
    let mut d = String::new();
    for lp in loops {
        for (k, p) in lp.iter().enumerate() {
            if !d.is_empty() {
                d.push(' ');
            }
            d.push_str(if k == 0 { "M" } else { "L" });
            let _ = write!(d, "{},{}", num(p[0]), num(-p[1]));
        }
        if !lp.is_empty() {
            d.push_str(" Z");
        }
    }
    let _ = writeln!(
        svg,
        "<path d=\"{d}\" fill=\"#4a7ab5\" fill-rule=\"evenodd\" stroke=\"none\"/>"
    );
}

/// `svg` (a drawing of this module) with `width` and `height` attributes on its `<svg>` tag:
/// its viewBox's size in `units`. Unchanged when it has them already or no viewBox.
pub fn with_physical_size(svg: &str, units: Units) -> String {
    let Some(tag_end) = svg.find('>') else {
        return svg.to_string();
    };
    let tag = &svg[..tag_end];
    if !tag.starts_with("<svg ") || tag.contains(" width=") {
        return svg.to_string();
    }
    let view_box = tag
        .split_once("viewBox=\"")
        .and_then(|(_, rest)| rest.split_once('"'))
        .map(|(numbers, _)| {
            numbers
                .split_ascii_whitespace()
                .map(str::parse::<f64>)
                .collect::<Result<Vec<f64>, _>>()
        });
    let Some(Ok(numbers)) = view_box else {
        return svg.to_string();
    };
    let [_, _, width, height] = numbers[..] else {
        return svg.to_string();
    };
    let length = |v: f64| {
        let (value, unit) = units.css_length(v);
        format!("{}{unit}", num(value))
    };
    format!(
        "<svg width=\"{}\" height=\"{}\"{}",
        length(width),
        length(height),
        &svg["<svg".len()..]
    )
}

/// Bounding box of `points`; the reference square `[-½, ½]²` when there are none, so an empty
/// drawing still has a valid viewBox.
fn bounds(points: &[&[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    if points.is_empty() {
        return ([-0.5; 2], [0.5; 2]);
    }
    let mut min = [f64::INFINITY; 2];
    let mut max = [f64::NEG_INFINITY; 2];
    for p in points {
        for a in 0..2 {
            min[a] = min[a].min(p[a]);
            max[a] = max[a].max(p[a]);
        }
    }
    // A degenerate (point or segment) outline would give a zero-size viewBox.
    for a in 0..2 {
        if max[a] - min[a] <= 0.0 {
            min[a] -= 0.5;
            max[a] += 0.5;
        }
    }
    (min, max)
}

/// A coordinate with [`DECIMALS`] decimals, trailing zeros trimmed, and no negative zero.
fn num(x: f64) -> String {
    let mut s = format!("{x:.DECIMALS$}");
    if s.contains('.') {
        let trimmed = s.trim_end_matches('0').trim_end_matches('.').len();
        s.truncate(trimmed);
    }
    if s == "-0" { "0".to_string() } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_deterministic() {
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(-0.0000001), "0");
        assert_eq!(num(2.0), "2");
        assert_eq!(num(-1.25), "-1.25");
        assert_eq!(num(1.0 / 3.0), "0.333333");
    }

    /// The physical size is the viewBox's in the model's unit, given once.
    #[test]
    fn physical_size_is_the_view_box_in_model_units() {
        let svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"-1 -2 30.5 20\">\n</svg>\n";
        let sized = with_physical_size(svg, Units::Millimeter);
        assert!(sized.starts_with("<svg width=\"30.5mm\" height=\"20mm\" xmlns="));
        assert!(sized.ends_with("viewBox=\"-1 -2 30.5 20\">\n</svg>\n"));
        assert_eq!(with_physical_size(&sized, Units::Inch), sized);
        let metres = with_physical_size(svg, Units::Meter);
        assert!(metres.starts_with("<svg width=\"3050cm\" height=\"2000cm\""));
        let microns = with_physical_size(svg, Units::Micron);
        assert!(microns.starts_with("<svg width=\"0.0305mm\" height=\"0.02mm\""));
    }
}
