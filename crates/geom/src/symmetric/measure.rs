//! Sharp measures of a cell's solid `{Φ ≤ 0}` in its reference element, on the domain grid
//! (docs/method.md §Surface area): the volume fraction (weighted share of samples with
//! `Φ ≤ 0`) and the surface-area density (area of the level set inside the element divided
//! by the element's volume; perimeter per area in 2D), what `optimize` reports and
//! `latticebuild cell` prints.
//!
//! The area is that of the piecewise-linear zero set of marching tetrahedra (six per grid
//! cube, along the main diagonal) or marching triangles (two per grid square) on the periodic
//! grid, each piece clipped to the element's half-spaces. Only the level set's own surface
//! counts, never the element's faces: a solid touching a face adds nothing there.
//!
//! Invariant: the same bits for any thread count (planes summed in parallel into their own
//! slots, then added in order).

use rayon::prelude::*;

use super::fit::{FitError, FittedCell};
use super::group::{Domain, ReferenceElement};

/// What [`measure`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellMeasures {
    /// Share of the reference element where `Φ ≤ 0`.
    pub volume_fraction: f64,
    /// Area of `{Φ = 0}` inside the element per element volume (cell units: 1/cell size);
    /// for 2D groups, perimeter per area.
    pub surface_area: f64,
}

/// Grid samples per axis of [`measure`]: twice the optimisation grid.
pub fn measure_grid(cell: &FittedCell) -> usize {
    2 * super::optimize::optimization_grid(cell)
}

/// Both measures on the grid of [`measure_grid`].
pub fn measure(cell: &FittedCell) -> Result<CellMeasures, FitError> {
    let grid = measure_grid(cell);
    Ok(CellMeasures {
        volume_fraction: sharp_fraction(cell, grid)?,
        surface_area: sharp_area(cell, grid)?,
    })
}

/// The weighted share of the domain grid's samples with `Φ ≤ 0`.
pub(super) fn sharp_fraction(cell: &FittedCell, grid: usize) -> Result<f64, FitError> {
    let weights = super::objective::element_weights(cell, grid);
    let phi = cell.grid(grid)?;
    let inside: f64 = phi
        .iter()
        .zip(&weights)
        .filter(|(v, _)| **v <= 0.0)
        .map(|(_, w)| w)
        .sum();
    Ok(inside / weights.iter().sum::<f64>())
}

/// Half-spaces `n·x ≤ o` (Cartesian) whose intersection is the reference element, or none
/// when the element is the whole domain.
fn half_spaces(cell: &FittedCell) -> Vec<([f64; 3], f64)> {
    match cell.group.reference_element() {
        Some(ReferenceElement::Tetrahedron) => super::group::TETRAHEDRON_FACE_NORMALS
            .iter()
            .map(|n| (*n, 0.5))
            .collect(),
        Some(ReferenceElement::Triangle) => {
            let h = 3f64.sqrt() / 6.0;
            let q = [[-0.5, -h], [0.5, -h], [0.0, 2.0 * h]];
            (0..3)
                .map(|i| {
                    let (a, b) = (q[i], q[(i + 1) % 3]);
                    // Outward normal of a counter-clockwise edge: the edge turned clockwise.
                    let n = [b[1] - a[1], a[0] - b[0], 0.0];
                    (n, n[0] * a[0] + n[1] * a[1])
                })
                .collect()
        }
        _ => Vec::new(),
    }
}

/// The element's volume (area in 2D) in Cartesian cell units.
fn element_measure(cell: &FittedCell) -> f64 {
    match cell.group.reference_element() {
        Some(ReferenceElement::Tetrahedron) => 1.0 / 3.0,
        Some(ReferenceElement::Triangle) => 3f64.sqrt() / 4.0,
        Some(ReferenceElement::Cube | ReferenceElement::Square) => 1.0,
        None => match cell.group.domain() {
            Domain::Square | Domain::Cube => 1.0,
            Domain::Rhombus | Domain::RhombicPrism => 3f64.sqrt() / 2.0,
        },
    }
}

/// Clips a convex polygon to `n·x ≤ o` (Sutherland–Hodgman).
fn clip(polygon: Vec<[f64; 3]>, n: [f64; 3], o: f64) -> Vec<[f64; 3]> {
    let side = |p: &[f64; 3]| n[0] * p[0] + n[1] * p[1] + n[2] * p[2] - o;
    let mut out = Vec::with_capacity(polygon.len() + 1);
    for i in 0..polygon.len() {
        let (a, b) = (polygon[i], polygon[(i + 1) % polygon.len()]);
        let (sa, sb) = (side(&a), side(&b));
        if sa <= 0.0 {
            out.push(a);
        }
        if (sa < 0.0 && sb > 0.0) || (sa > 0.0 && sb < 0.0) {
            let t = sa / (sa - sb);
            out.push(std::array::from_fn(|k| a[k] + t * (b[k] - a[k])));
        }
    }
    out
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn length(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The measure of a piece (triangle in 3D, segment in 2D) after clipping: area of a planar
/// polygon, or length of a segment.
fn clipped_measure(piece: Vec<[f64; 3]>, planes: &[([f64; 3], f64)]) -> f64 {
    let segment = piece.len() == 2;
    let mut poly = piece;
    for &(n, o) in planes {
        if poly.is_empty() {
            return 0.0;
        }
        poly = if segment {
            clip_segment(&poly, n, o)
        } else {
            clip(poly, n, o)
        };
    }
    match poly.len() {
        0 | 1 => 0.0,
        2 => length(sub(poly[1], poly[0])),
        _ => {
            let mut s = [0.0; 3];
            for i in 1..poly.len() - 1 {
                let c = cross(sub(poly[i], poly[0]), sub(poly[i + 1], poly[0]));
                s = [s[0] + c[0], s[1] + c[1], s[2] + c[2]];
            }
            0.5 * length(s)
        }
    }
}

fn clip_segment(seg: &[[f64; 3]], n: [f64; 3], o: f64) -> Vec<[f64; 3]> {
    let side = |p: &[f64; 3]| n[0] * p[0] + n[1] * p[1] + n[2] * p[2] - o;
    let (a, b) = (seg[0], seg[1]);
    let (sa, sb) = (side(&a), side(&b));
    let cut = |t: f64| std::array::from_fn(|k| a[k] + t * (b[k] - a[k]));
    match (sa <= 0.0, sb <= 0.0) {
        (true, true) => vec![a, b],
        (false, false) => Vec::new(),
        (true, false) => vec![a, cut(sa / (sa - sb))],
        (false, true) => vec![cut(sa / (sa - sb)), b],
    }
}

/// The zero set's pieces in one simplex (`Φ ≤ 0` inside): crossings on the edges between an
/// inside and an outside vertex. A tetrahedron gives a triangle or a quadrilateral (as two
/// triangles), a triangle one segment.
fn simplex_pieces(p: &[[f64; 3]], v: &[f64], out: &mut Vec<Vec<[f64; 3]>>) {
    let crossing = |i: usize, j: usize| -> [f64; 3] {
        let t = v[i] / (v[i] - v[j]);
        std::array::from_fn(|k| p[i][k] + t * (p[j][k] - p[i][k]))
    };
    let inside: Vec<usize> = (0..v.len()).filter(|&i| v[i] <= 0.0).collect();
    let outside: Vec<usize> = (0..v.len()).filter(|&i| v[i] > 0.0).collect();
    if inside.is_empty() || outside.is_empty() {
        return;
    }
    if v.len() == 3 {
        let (lone, pair) = if inside.len() == 1 {
            (inside[0], outside)
        } else {
            (outside[0], inside)
        };
        out.push(vec![crossing(lone, pair[0]), crossing(lone, pair[1])]);
        return;
    }
    match (inside.len(), outside.len()) {
        (1, 3) | (3, 1) => {
            let (lone, rest) = if inside.len() == 1 {
                (inside[0], outside)
            } else {
                (outside[0], inside)
            };
            out.push(rest.iter().map(|&r| crossing(lone, r)).collect());
        }
        _ => {
            let (i, j, k, l) = (inside[0], inside[1], outside[0], outside[1]);
            let quad = [
                crossing(i, k),
                crossing(i, l),
                crossing(j, l),
                crossing(j, k),
            ];
            out.push(vec![quad[0], quad[1], quad[2]]);
            out.push(vec![quad[0], quad[2], quad[3]]);
        }
    }
}

/// The surface-area density of the zero set on the periodic domain grid (module docs).
pub(super) fn sharp_area(cell: &FittedCell, grid: usize) -> Result<f64, FitError> {
    let phi = cell.grid(grid)?;
    let d = cell.group.dimension();
    let domain = cell.group.domain();
    let (origin, frame) = (domain.origin(), domain.frame());
    let planes = half_spaces(cell);
    let layers = if d == 3 { grid } else { 1 };
    let point = |i: [usize; 3]| -> ([f64; 3], f64) {
        let s: [f64; 3] = std::array::from_fn(|a| {
            if a < d {
                origin[a] + i[a] as f64 / grid as f64
            } else {
                0.0
            }
        });
        let w = [
            i[0] % grid,
            i[1] % grid,
            if d == 3 { i[2] % grid } else { 0 },
        ];
        (
            frame.to_cartesian(s),
            phi[w[0] + grid * (w[1] + grid * w[2])],
        )
    };
    let per_layer: Vec<f64> = (0..layers)
        .into_par_iter()
        .map(|z| {
            let mut total = 0.0;
            let mut pieces = Vec::new();
            for y in 0..grid {
                for x in 0..grid {
                    pieces.clear();
                    if d == 3 {
                        let corner: Vec<([f64; 3], f64)> = (0..8)
                            .map(|c| point([x + (c & 1), y + (c >> 1 & 1), z + (c >> 2 & 1)]))
                            .collect();
                        // Six tetrahedra 0 → 7 along the axis orders (Kuhn).
                        for order in [
                            [0, 1, 2],
                            [0, 2, 1],
                            [1, 0, 2],
                            [1, 2, 0],
                            [2, 0, 1],
                            [2, 1, 0],
                        ] {
                            let mut c = 0;
                            let mut ids = vec![0];
                            for a in order {
                                c |= 1 << a;
                                ids.push(c);
                            }
                            let p: Vec<[f64; 3]> = ids.iter().map(|&i| corner[i].0).collect();
                            let v: Vec<f64> = ids.iter().map(|&i| corner[i].1).collect();
                            simplex_pieces(&p, &v, &mut pieces);
                        }
                    } else {
                        let corner: Vec<([f64; 3], f64)> = (0..4)
                            .map(|c| point([x + (c & 1), y + (c >> 1), 0]))
                            .collect();
                        for ids in [[0, 1, 3], [0, 3, 2]] {
                            let p: Vec<[f64; 3]> = ids.iter().map(|&i| corner[i].0).collect();
                            let v: Vec<f64> = ids.iter().map(|&i| corner[i].1).collect();
                            simplex_pieces(&p, &v, &mut pieces);
                        }
                    }
                    for piece in pieces.drain(..) {
                        total += clipped_measure(piece, &planes);
                    }
                }
            }
            total
        })
        .collect();
    Ok(per_layer.iter().sum::<f64>() / element_measure(cell))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symmetric::{FitOptions, Group, fit, from_fn};
    use std::f64::consts::TAU;

    /// Balls and discs about the centroid against `4πr²` and `2πr` over the element's
    /// volume; for Td and D3 inside the element, so no face clips them.
    #[test]
    fn balls_have_the_area_of_spheres() {
        let r = 0.3;
        let ball = fit(
            &Group::oh(),
            32,
            &from_fn(move |x| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - r),
            &FitOptions::default(),
        )
        .unwrap();
        let m = measure(&ball).unwrap();
        let area = 4.0 * std::f64::consts::PI * r * r;
        let volume = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!(
            (m.surface_area - area).abs() < 0.02 * area,
            "{m:?} vs {area}"
        );
        assert!(
            (m.volume_fraction - volume).abs() < 0.01,
            "{m:?} vs {volume}"
        );

        let disc = fit(
            &Group::d4(),
            64,
            &from_fn(move |x| (x[0] * x[0] + x[1] * x[1]).sqrt() - r),
            &FitOptions::default(),
        )
        .unwrap();
        let m = measure(&disc).unwrap();
        let perimeter = TAU * r;
        assert!(
            (m.surface_area - perimeter).abs() < 0.01 * perimeter,
            "{m:?}"
        );

        let r = 0.2;
        let ball = fit(
            &Group::td(),
            32,
            &from_fn(move |x| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - r),
            &FitOptions::default(),
        )
        .unwrap();
        let m = measure(&ball).unwrap();
        let area = 4.0 * std::f64::consts::PI * r * r * 3.0;
        assert!(
            (m.surface_area - area).abs() < 0.02 * area,
            "{m:?} vs {area}"
        );

        let r = 0.15;
        let disc = fit(
            &Group::d3(),
            64,
            &from_fn(move |x| (x[0] * x[0] + x[1] * x[1]).sqrt() - r),
            &FitOptions::default(),
        )
        .unwrap();
        let m = measure(&disc).unwrap();
        let perimeter = TAU * r / (3f64.sqrt() / 4.0);
        assert!(
            (m.surface_area - perimeter).abs() < 0.01 * perimeter,
            "{m:?}"
        );
    }
}
