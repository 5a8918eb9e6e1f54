//! Signed distance, winding number and containment of triangle meshes, robust to the defects
//! of real files: holes, duplicated, flipped and sliver triangles, soups.
//!
//! ```text
//!   soup ──prepare──▶ triangles ──bvh──▶ nodes + leaf-ordered triangles ──▶ moments
//!        weld, drop repeats,                     │                            │
//!        orient (optional)               nearest triangle          hierarchical winding
//!                                                └──── signed distance ───────┘
//! ```
//!
//! Conventions (those of the crate): the field is negative inside; distances are in the mesh's
//! own units; a point is inside when its generalized winding number `w` exceeds ½.
//!
//! What "inside" means for imperfect meshes, decided here (module docs of `prepare.rs` and
//! `winding.rs` give the mechanics):
//! - Closed, consistently oriented: `w` is 1 inside and 0 outside, exactly the solid.
//! - Holes: `w` is smooth across the hole, so points away from it are classified as for the
//!   closed mesh, and the ½ level set spans the hole like a soap film.
//! - Repeated triangles (same corners, same order) are dropped, since each copy would add its
//!   solid angle again (just outside a doubled face `w` would reach −½ instead of 0).
//! - Flipped triangles are turned back to agree with their edge neighbours; an edge-connected
//!   component keeps the orientation of the larger part of its area, and a surface enclosing
//!   negative volume is turned inside out. So a closed mesh with some faces flipped, or all of
//!   them, is the solid it bounds, while an inner shell facing inward stays a cavity. We chose
//!   repair over classifying by `|w|`: `|w| > ½` fixes only the all-flipped case, and a face
//!   flipped in a closed mesh leaves `w ≈ 0` just inside it, which no threshold recovers.
//!   With [`SdfOptions::repair`] off, triangles are used exactly as given.
//! - Slivers: the distance needs no division by area (see `nearest.rs`), and the solid angle
//!   formula is exact for any shape.
//!
//! The signed distance is `±` the distance to the nearest triangle, the sign from `w`. With a
//! [`SdfOptions::band`] `h`, its magnitude is clamped to `h` (the sign stays exact everywhere),
//! which lets the nearest-triangle search stop at `h`: callers that only need distances near
//! the surface (a skin of thickness `t ≤ h`, intersecting a lattice with a part) pay much less
//! far from it. [`Mode::Containment`] samples −1 inside and +1 outside, skipping the distance.
//!
//! Grid sampling exploits coherence along rows, exactly: when the surface is closed (every
//! edge traversed equally often both ways, see [`SurfaceReport::closed`]), `w` is constant
//! wherever the surface is not crossed, so the previous sample's side carries over when the
//! step to it is shorter than the distance to the surface (or, for containment, when no
//! triangle's box meets the step). On open surfaces every sample evaluates `w`.
//!
//! [`PeriodicMeshSdf`] (`periodic.rs`) is the solid repeated with period 1, as a mesh cell
//! tiles space: the signed distance to the union of the copies, continuous across cell faces.
//!
//! Invariant: every value is the same bits for any rayon thread count; parallel sums (the
//! orientation's volume, the exact winding number) add fixed blocks in order.
//!
//! Limit: at most 2²⁹ triangles ([`MeshSdfError::TooLarge`]), so that a BVH node's links fit
//! one word beside its oriented box (`bvh.rs`).
//!
//! Invariant: `MeshSdf` owns everything it needs (no borrow of the soup), is `Send + Sync`, and
//! every value is a pure function of the soup, the options and the query point (or, for
//! samplers, the grid row): never of thread count or evaluation order.

mod bvh;
mod lanes;
mod nearest;
mod periodic;
mod prepare;
mod sampler;

mod winding;

use crate::field::{Grid, PlaneSampler, ScalarField};
use crate::mesh_read::TriangleSoup;
use rayon::prelude::*;
use std::time::{Duration, Instant};
use thiserror::Error;

pub use periodic::{GLUE_TOLERANCE, MAX_PERIODS, PeriodicMeshSdf};
pub use prepare::SurfaceReport;
pub use sampler::MeshSampler;

/// What the field of a [`MeshSdf`] samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// The signed distance to the surface, negative inside.
    #[default]
    SignedDistance,
    /// −1 inside, +1 outside; no distance search.
    Containment,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SdfOptions {
    pub mode: Mode,
    /// Clamp distances to `±band` (positive). `None`: exact distances everywhere.
    pub band: Option<f64>,
    /// Far-field threshold of the winding number: a BVH node is approximated when the query is
    /// farther than `beta` times its radius. At least 1. With 2, errors against the exact sum
    /// are about 5e-4 on average and below 5e-3 at worst (`tests/mesh_sdf_winding.rs`); 4 gives
    /// about 2e-4 at worst. Sign decisions on closed surfaces need far less (see `sampler.rs`).
    pub beta: f64,
    /// Weld, drop repeated and degenerate triangles and make orientations consistent (module
    /// docs). Off: the triangles are used exactly as given.
    pub repair: bool,
}

impl Default for SdfOptions {
    fn default() -> SdfOptions {
        SdfOptions {
            mode: Mode::SignedDistance,
            band: None,
            beta: 2.0,
            repair: true,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Error)]
pub enum MeshSdfError {
    #[error("the mesh has no triangles")]
    Empty,
    #[error("every triangle of the mesh is degenerate (two corners at one position)")]
    Degenerate,
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {count} vertices")]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        count: usize,
    },
    #[error("the mesh has {triangles} triangles, more than the {max} supported")]
    TooLarge { triangles: usize, max: usize },
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite { vertex: usize },
    #[error(
        "the mesh spans {extent} periods along {axis}, more than the {max} a periodic cell \
         takes (a cell's mesh is given in the cell's frame, the cube [-1/2, 1/2]^3)"
    )]
    TooManyPeriods {
        axis: &'static str,
        extent: f64,
        max: f64,
    },
    #[error(
        "every face of the mesh is glued to a face of a neighbouring copy: repeated, the solid \
         fills space and has no surface"
    )]
    FillsSpace,
    #[error("{what} must be {expected}, got {value}")]
    BadOption {
        what: &'static str,
        expected: &'static str,
        value: f64,
    },
}

/// A triangle mesh prepared for distance, winding-number and containment queries.
pub struct MeshSdf {
    bvh: bvh::Bvh,
    moments: Vec<winding::Moments>,
    options: SdfOptions,
    report: SurfaceReport,
    bounds: ([f64; 3], [f64; 3]),
    /// Lengths below this are rounding noise at the mesh's scale.
    tolerance: f64,
    timings: BuildTimings,
}

/// Wall time of the construction phases of a [`MeshSdf`], for benchmarks. Not part of any
/// result.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildTimings {
    /// Welding, clean-up, orientation and closedness (`prepare.rs`).
    pub prepare: Duration,
    /// The hierarchy with its aligned and oriented boxes.
    pub bvh: Duration,
    /// The winding-number moments.
    pub moments: Duration,
}

impl MeshSdf {
    /// Prepares `soup` (module docs) and builds the hierarchy.
    pub fn new(soup: &TriangleSoup, options: SdfOptions) -> Result<MeshSdf, MeshSdfError> {
        check_options(&options)?;
        check_soup(soup)?;
        let start = Instant::now();
        let surface = prepare::prepare(soup, options.repair);
        if surface.triangles.is_empty() {
            return Err(MeshSdfError::Degenerate);
        }
        let prepared = Instant::now();
        let bvh = bvh::build(surface.triangles);
        let built = Instant::now();
        let moments = winding::moments(&bvh);
        let timings = BuildTimings {
            prepare: prepared - start,
            bvh: built - prepared,
            moments: built.elapsed(),
        };
        let (lo, hi) = bvh.bounds;
        let scale = (0..3)
            .map(|a| lo[a].abs().max(hi[a].abs()).max(hi[a] - lo[a]))
            .fold(0.0, f64::max);
        Ok(MeshSdf {
            bounds: (lo, hi),
            tolerance: 1e-12 * scale,
            bvh,
            moments,
            options,
            report: surface.report,
            timings,
        })
    }

    pub fn options(&self) -> &SdfOptions {
        &self.options
    }

    pub fn timings(&self) -> BuildTimings {
        self.timings
    }

    /// What preparation found and changed.
    pub fn report(&self) -> &SurfaceReport {
        &self.report
    }

    /// The bounding box of the triangles used.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.bounds
    }

    /// The generalized winding number at `p`, hierarchically (accuracy set by `beta`).
    pub fn winding_number(&self, p: [f64; 3]) -> f64 {
        winding::fast(&self.bvh, &self.moments, p, self.options.beta.powi(2))
    }

    /// The winding number at `p` summed exactly over every triangle: O(n), for checks.
    pub fn winding_number_exact(&self, p: [f64; 3]) -> f64 {
        winding::exact(&self.bvh.triangles, p)
    }

    /// Whether `p` is inside: winding number above ½.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        self.winding_number(p) > 0.5
    }

    /// Distance from `p` to the nearest triangle, clamped to the band if there is one.
    pub fn unsigned_distance(&self, p: [f64; 3]) -> f64 {
        let band = self.options.band.unwrap_or(f64::INFINITY);
        let (d2, tri) = nearest::nearest(
            &self.bvh,
            p,
            None,
            band * band,
            &mut nearest::Search::default(),
        );
        if tri.is_some() { d2.sqrt() } else { band }
    }

    /// Signed distance (negative inside), clamped to the band if there is one.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        let d = self.unsigned_distance(p);
        if self.contains(p) { -d } else { d }
    }

    /// The field's value at `p`: the signed distance, or ±1 for [`Mode::Containment`].
    pub fn value(&self, p: [f64; 3]) -> f64 {
        sampler::Walker::new(self).value(p)
    }
}

fn check_options(options: &SdfOptions) -> Result<(), MeshSdfError> {
    if !(options.beta >= 1.0 && options.beta.is_finite()) {
        return Err(MeshSdfError::BadOption {
            what: "beta",
            expected: "finite and at least 1",
            value: options.beta,
        });
    }
    if let Some(band) = options.band
        && !(band > 0.0 && band.is_finite())
    {
        return Err(MeshSdfError::BadOption {
            what: "band",
            expected: "finite and positive",
            value: band,
        });
    }
    Ok(())
}

fn check_soup(soup: &TriangleSoup) -> Result<(), MeshSdfError> {
    if soup.triangles.is_empty() {
        return Err(MeshSdfError::Empty);
    }
    if soup.triangles.len() > bvh::MAX_TRIANGLES {
        return Err(MeshSdfError::TooLarge {
            triangles: soup.triangles.len(),
            max: bvh::MAX_TRIANGLES,
        });
    }
    let count = soup.positions.len();
    if let Some((triangle, &index)) = soup
        .triangles
        .par_iter()
        .enumerate()
        .find_first(|(_, t)| t.iter().any(|&i| i as usize >= count))
        .and_then(|(t, tri)| tri.iter().find(|&&i| i as usize >= count).map(|i| (t, i)))
    {
        return Err(MeshSdfError::IndexOutOfRange {
            triangle,
            index,
            count,
        });
    }
    if let Some(vertex) = soup
        .positions
        .par_iter()
        .position_first(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(MeshSdfError::NonFinite { vertex });
    }
    Ok(())
}

impl ScalarField for MeshSdf {
    /// Chunks of points are evaluated in parallel, each walking its points in order so that
    /// neighbours share work (module docs); chunking depends only on the number of points.
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        const CHUNK: usize = 256;
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let mut walker = sampler::Walker::new(self);
                for (k, v) in chunk.iter_mut().enumerate() {
                    let i = c * CHUNK + k;
                    *v = walker.value([xs[i], ys[i], zs[i]]);
                }
            });
    }

    fn sampler<'a>(&'a self, grid: &Grid) -> Box<dyn PlaneSampler + 'a> {
        Box::new(MeshSampler::new(self, grid))
    }
}
