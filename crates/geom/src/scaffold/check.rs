//! Element quality: inverted and degenerate elements, by element tag.
//!
//! Invariants:
//! - The Jacobian is evaluated at every local node and at 2 Gauss points per direction (once
//!   for tet4 and tri3, where it is constant).
//!   3D elements: det J ≤ 0 is inverted, and |det J| ≤ 1e-10 h³ (h the longest distance between
//!   two corners) is degenerate. 2D elements lying in a plane z = const: the signed area
//!   (J_1 × J_2)·z against the mesh's majority orientation, so a clockwise element among
//!   counter-clockwise ones is inverted; 2D surfaces in 3D are only checked for zero area
//!   (|J_1 × J_2| ≤ 1e-10 h²), since their orientation is relative.
//! - The error lists up to 10 elements with what was found, and how many there are in all.

use super::map::{Quadrature, cross2, det3, norm};
use super::{ElementKind, Location, Scaffold, ScaffoldError};

/// A value relative to h^d, the value itself, and the point (index) where it was found.
type Extreme = (f64, f64, usize);

const RELATIVE_TOLERANCE: f64 = 1e-10;
const LISTED: usize = 10;

/// Where in the element a value was found.
fn point_name(index: usize, nodes: usize) -> String {
    if index < nodes {
        format!("local node {index}")
    } else {
        format!("quadrature point {}", index - nodes)
    }
}

pub fn check(scaffold: &Scaffold) -> Result<(), ScaffoldError> {
    let kind = scaffold.kind;
    let n = kind.node_count();
    // tet4 and tri3 have one constant Jacobian: one point says everything.
    let points: Vec<[f64; 3]> = if matches!(kind, ElementKind::Tet4 | ElementKind::Tri3) {
        vec![kind.reference_node(0)]
    } else {
        let mut p: Vec<[f64; 3]> = (0..n).map(|i| kind.reference_node(i)).collect();
        p.extend(Quadrature::new(kind, 2).points);
        p
    };
    let three_d = kind.dimension() == 3;
    let planar = !three_d && {
        let z0 = scaffold.nodes.first().map_or(0.0, |p| p[2]);
        let extent = scaffold
            .nodes
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        scaffold
            .nodes
            .iter()
            .all(|p| (p[2] - z0).abs() <= 1e-12 * extent.max(1.0))
    };
    // Per element: the smallest and largest value relative to h^d, where they were found.
    let mut extremes: Vec<(Extreme, Extreme)> = Vec::with_capacity(scaffold.element_count());
    let mut orientation = 0i64;
    for e in 0..scaffold.element_count() {
        let nodes = scaffold.element(e);
        let mut h = 0.0f64;
        for a in 0..kind.corner_count() {
            for b in 0..a {
                let p = scaffold.nodes[nodes[a] as usize];
                let q = scaffold.nodes[nodes[b] as usize];
                h = h.max(norm([p[0] - q[0], p[1] - q[1], p[2] - q[2]]));
            }
        }
        let scale = if three_d { h * h * h } else { h * h };
        let mut low = (f64::INFINITY, 0.0, 0usize);
        let mut high = (f64::NEG_INFINITY, 0.0, 0usize);
        for (k, &xi) in points.iter().enumerate() {
            let j = scaffold.jacobian(e, xi);
            let v = if three_d {
                det3(&j)
            } else if planar {
                cross2(&j)[2]
            } else {
                norm(cross2(&j))
            };
            let relative = if scale > 0.0 { v / scale } else { 0.0 };
            if relative < low.0 {
                low = (relative, v, k);
            }
            if relative > high.0 {
                high = (relative, v, k);
            }
        }
        if planar {
            orientation += if cross2(&scaffold.jacobian(e, [0.0; 3]))[2] >= 0.0 {
                1
            } else {
                -1
            };
        }
        extremes.push((low, high));
    }
    let positive = orientation >= 0;
    let mut bad = Vec::new();
    for (e, &(low, high)) in extremes.iter().enumerate() {
        // The value that must stay clearly positive, signed so that the expected side is > 0.
        let (relative, v, k) = if planar && !positive {
            (-high.0, high.1, high.2)
        } else {
            low
        };
        if relative > RELATIVE_TOLERANCE {
            continue;
        }
        let tag = scaffold.element_tags[e];
        let at = point_name(k, n);
        bad.push(if three_d && relative < -RELATIVE_TOLERANCE {
            format!("element {tag} is inverted (det J = {v:.3e} at {at})")
        } else if three_d {
            format!("element {tag} is degenerate (det J = {v:.3e} at {at})")
        } else if planar && relative < -RELATIVE_TOLERANCE {
            let side = if positive { "clockwise" } else { "counter-clockwise" };
            format!(
                "element {tag} is inverted ({side} seen from +z, unlike most elements: signed area Jacobian {v:.3e} at {at})"
            )
        } else {
            format!("element {tag} is degenerate (zero area: |J1 x J2| = {:.3e} at {at})", v.abs())
        });
    }
    if bad.is_empty() {
        return Ok(());
    }
    let count = bad.len();
    let mut message = if count == 1 {
        bad.remove(0)
    } else {
        format!(
            "{count} inverted or degenerate elements: {}",
            bad[..count.min(LISTED)].join("; ")
        )
    };
    if count > LISTED {
        message.push_str(&format!("; and {} more", count - LISTED));
    }
    Err(ScaffoldError::new(
        &scaffold.source,
        Location::File,
        message,
    ))
}
