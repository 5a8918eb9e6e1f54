//! The mesh of one element in reference coordinates, before it is welded to its neighbours.
//!
//! Invariants: every vertex lies on one lattice edge `(a, b)` (`a < b`, lattice point indices)
//! strictly between its ends — for a band (a shell, [`Samples::upper`]) one vertex per level
//! that crosses the edge, the two at least 1/256 of the edge apart —, or — for cap corners, and inside corners of a 2D region — on one
//! lattice point `a` (`b == POINT`); triangles are counter-clockwise seen from outside the
//! solid in reference coordinates (2D: filled region triangles, counter-clockwise in ξ); `caps[f]` closes the solid on the element's face `f` and is used only where
//! that face is on the scaffold's boundary.

use std::collections::HashMap;

use crate::contour::table::{CORNER_SLOT, EDGE_CORNERS, HI_SLOT};
use crate::contour::{band_fraction, crossing_fraction};

/// `LocalVertex::b` of a vertex that sits on a lattice point (a cap corner).
pub const POINT: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalVertex {
    pub a: u32,
    pub b: u32,
    /// Position along `a → b` (0 at `a`); 0 for a point vertex.
    pub t: f64,
    /// A band's upper level's crossing (false for the lower level's, one level's and points).
    pub upper: bool,
}

/// The lattice samples a lattice contours, one per point index. One level: `lower` is the
/// solid's implicit function (negative inside). A band (a shell): the solid is where both
/// `lower` and `upper` are negative, `lower = lo − f` and `upper = f − hi` for a cell value `f`
/// between levels `lo < hi` that may vary from point to point; so `upper ≥ 0` implies
/// `lower < 0` and the two levels' surfaces never meet. Contouring the two levels, rather than
/// the one function `|f − c| − w/2`, keeps a wall that passes between two samples (where that
/// function is positive at both).
#[derive(Clone, Copy)]
pub struct Samples<'v> {
    pub lower: &'v [f64],
    pub upper: Option<&'v [f64]>,
}

impl<'v> Samples<'v> {
    pub fn one(values: &'v [f64]) -> Samples<'v> {
        Samples {
            lower: values,
            upper: None,
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct LocalMesh {
    pub vertices: Vec<LocalVertex>,
    pub triangles: Vec<[u32; 3]>,
    pub caps: Vec<Vec<[u32; 3]>>,
}

/// Builds a [`LocalMesh`], giving each lattice edge (per level) or point one vertex.
pub struct LocalBuilder<'v> {
    samples: Samples<'v>,
    ids: HashMap<(u32, u32, bool), u32>,
    pub mesh: LocalMesh,
}

impl<'v> LocalBuilder<'v> {
    pub fn new(samples: Samples<'v>, faces: usize) -> Self {
        LocalBuilder {
            samples,
            ids: HashMap::new(),
            mesh: LocalMesh {
                caps: vec![Vec::new(); faces],
                ..LocalMesh::default()
            },
        }
    }

    /// The vertex where the surface crosses the lattice edge `p`–`q` (signs differ); for a
    /// band, the lower level's.
    pub fn crossing(&mut self, p: u32, q: u32) -> u32 {
        self.level_crossing(p, q, false)
    }

    /// The vertex where a level crosses the lattice edge `p`–`q`: the lower (or only) level's,
    /// or (`upper`) a band's upper level's.
    pub fn level_crossing(&mut self, p: u32, q: u32, upper: bool) -> u32 {
        let (a, b) = (p.min(q), p.max(q));
        let samples = self.samples;
        let mesh = &mut self.mesh;
        *self.ids.entry((a, b, upper)).or_insert_with(|| {
            let t = edge_fraction(samples, a as usize, b as usize, upper);
            mesh.vertices.push(LocalVertex { a, b, t, upper });
            (mesh.vertices.len() - 1) as u32
        })
    }

    /// The vertex of a contour table's slot (`crate::contour::table`) in a cell whose table
    /// corner `c` is lattice point `corner(c)`: an edge's crossing (its upper level's, for a
    /// band's `HI_SLOT` slots) or a corner.
    pub fn slot(&mut self, slot: u8, corner: impl Fn(u8) -> u32) -> u32 {
        if slot < CORNER_SLOT {
            let [a, b] = EDGE_CORNERS[slot as usize];
            self.crossing(corner(a), corner(b))
        } else if slot < HI_SLOT {
            self.point(corner(slot - CORNER_SLOT))
        } else {
            let [a, b] = EDGE_CORNERS[(slot - HI_SLOT) as usize];
            self.level_crossing(corner(a), corner(b), true)
        }
    }

    /// The vertex on lattice point `p` (an inside corner of a cap).
    pub fn point(&mut self, p: u32) -> u32 {
        let mesh = &mut self.mesh;
        *self.ids.entry((p, POINT, false)).or_insert_with(|| {
            mesh.vertices.push(LocalVertex {
                a: p,
                b: POINT,
                t: 0.0,
                upper: false,
            });
            (mesh.vertices.len() - 1) as u32
        })
    }

    /// The sample at lattice point `p` (of the lower level, for a band).
    #[inline]
    pub fn value(&self, p: u32) -> f64 {
        self.samples.lower[p as usize]
    }

    /// The samples being contoured.
    pub fn samples(&self) -> Samples<'v> {
        self.samples
    }

    pub fn finish(self) -> LocalMesh {
        self.mesh
    }
}

/// Inside means strictly negative; NaN is outside, as in the contourer.
#[inline]
pub fn inside(v: f64) -> bool {
    v < 0.0
}

/// Where along the lattice edge `a → b` (0 at `a`) a level crosses it: the box contourer's
/// rule ([`crate::contour::band_fraction`]), so a band's two crossings on one edge are
/// 1/256 apart and both computed from the same four samples whichever element
/// computes them.
fn edge_fraction(samples: Samples, a: usize, b: usize, upper: bool) -> f64 {
    let lower = samples.lower;
    match samples.upper {
        None => crossing_fraction(lower[a], lower[b]),
        Some(high) => band_fraction([lower[a], lower[b]], [high[a], high[b]], upper),
    }
}

/// A band sample's state: below the band (`lower ≥ 0`, or NaN: outside, as for one level),
/// between its levels (inside the solid), or at or above its upper level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BandState {
    Below,
    Between,
    Above,
}

/// The state of lattice point `p` in a band.
#[inline]
pub fn band_state(lower: &[f64], upper: &[f64], p: usize) -> BandState {
    if !inside(lower[p]) {
        BandState::Below
    } else if upper[p] >= 0.0 {
        BandState::Above
    } else {
        BandState::Between
    }
}

/// The part of a small triangle between a band's levels, as `visit` calls around its sides
/// `k → k + 1` (`state` its corners' states, counter-clockwise or not): `visit(k, None)` for
/// corner `k` when it is between, then `visit(k, Some(upper))` for each level side `k`
/// crosses, in the order met. All on the triangle's perimeter, in order: a convex polygon.
pub fn band_triangle_walk(state: [BandState; 3], mut visit: impl FnMut(usize, Option<bool>)) {
    for k in 0..3 {
        let (from, to) = (state[k], state[(k + 1) % 3]);
        if from == BandState::Between {
            visit(k, None);
        }
        let lower = (from == BandState::Below) != (to == BandState::Below);
        let upper = (from == BandState::Above) != (to == BandState::Above);
        let levels = if from == BandState::Above {
            [(upper, true), (lower, false)]
        } else {
            [(lower, false), (upper, true)]
        };
        for (crossed, level) in levels {
            if crossed {
                visit(k, Some(level));
            }
        }
    }
}
