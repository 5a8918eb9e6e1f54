//! The mesh of one element in reference coordinates, before it is welded to its neighbours.
//!
//! Invariants: every vertex lies on one lattice edge `(a, b)` (`a < b`, lattice point indices)
//! strictly between its ends — for a band (a shell, [`Samples::upper`]) one vertex per level
//! that crosses the edge, the two at least [`EDGE_MARGIN`] of the edge apart —, or — for cap corners, and inside corners of a 2D region — on one
//! lattice point `a` (`b == POINT`); triangles are counter-clockwise seen from outside the
//! solid in reference coordinates (2D: filled region triangles, counter-clockwise in ξ); `caps[f]` closes the solid on the element's face `f` and is used only where
//! that face is on the scaffold's boundary.

use std::collections::HashMap;

/// `LocalVertex::b` of a vertex that sits on a lattice point (a cap corner).
pub const POINT: u32 = u32::MAX;

/// Fraction of an edge kept between a crossing and the edge's ends, as in the contourer: no
/// two vertices share a position even where the field is exactly zero at a sample.
const EDGE_MARGIN: f64 = 1.0 / 256.0;

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

/// Where along the lattice edge `a → b` (0 at `a`) a level crosses it. Alone on its edge, the
/// level's linear crossing kept [`EDGE_MARGIN`] from the ends. An edge of a band from below it
/// (`lower ≥ 0`, or NaN) to above it (`upper ≥ 0`) holds both levels' crossings: measured
/// from the end below, the lower one is kept in `[m, 1 − 2m]` and the upper one in
/// `[lower + m, 1 − m]` (`m` the margin), so the two never meet however thin the band is —
/// and both are computed from the same four samples whichever element computes them.
fn edge_fraction(samples: Samples, a: usize, b: usize, upper: bool) -> f64 {
    let lower = samples.lower;
    let level = |values: &[f64]| crossing(values[a], values[b]);
    let Some(high) = samples.upper else {
        return level(lower);
    };
    let below = |p: usize| lower[p].partial_cmp(&0.0) != Some(std::cmp::Ordering::Less);
    let above = |p: usize| high[p] >= 0.0;
    let from_a = below(a) && above(b);
    if !(from_a || (below(b) && above(a))) {
        return level(if upper { high } else { lower });
    }
    let (from, to) = if from_a { (a, b) } else { (b, a) };
    let raw = |values: &[f64]| values[from] / (values[from] - values[to]);
    let m = EDGE_MARGIN;
    let t_lo = raw(lower);
    let t_lo = if t_lo.is_finite() {
        t_lo.clamp(m, 1.0 - 2.0 * m)
    } else {
        1.0 / 3.0
    };
    let t = if upper {
        let t_hi = raw(high);
        if t_hi.is_finite() {
            t_hi.clamp(t_lo + m, 1.0 - m)
        } else {
            (2.0f64 / 3.0).max(t_lo + m)
        }
    } else {
        t_lo
    };
    if from_a { t } else { 1.0 - t }
}

/// The linear zero crossing between samples `va` and `vb`, as a fraction from `va`, kept
/// [`EDGE_MARGIN`] from the ends (the middle when the samples do not place it).
fn crossing(va: f64, vb: f64) -> f64 {
    let t = va / (va - vb);
    if t.is_finite() {
        t.clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN)
    } else {
        0.5
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
