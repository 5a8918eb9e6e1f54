//! What an engineer checks of a lattice, measured from its final mesh: wall thickness and
//! pore size as local thickness, genus per solid piece, specific surface.
//!
//! Invariants:
//! - Everything is measured from the closed, outward mesh alone (any output: box, tiled,
//!   SDF), sampled onto a grid of cubic voxels of the caller's spacing ([`voxel`]).
//! - Wall thickness and pore size are local thickness (Hildebrand and Rüegsegger 1997, as
//!   in BoneJ) of the solid and of the void, in model units, with ridges refined between
//!   voxels from the mesh's tangent planes ([`thickness`]).
//! - The void is the measuring box minus the solid. The box's faces are not walls: distances
//!   are to the solid only, so a pore that the box cuts is measured by the balls that fit
//!   between the solid walls (centred inside the grid), as if the void went on. The grid
//!   holds one voxel of margin round the box; the margin's voxels can centre balls but are
//!   not counted.
//! - Accuracy (tests, voxel side Δ): slabs of width 2Δ to 8.5Δ, axis-aligned with the
//!   mid-plane between samples or oblique, measure a median wall within 0.01 % of `W`; a
//!   spherical shell of wall 2.6Δ (radius 12Δ) and a spherical cavity of diameter 13.2Δ
//!   within 0.5 % (tangent planes cut a little into the phase a curved wall bounds). Voxels near edges and corners (a slab's rim) read less
//!   than a true maximal ball would give them (their own ball), so `min` and `p05` are
//!   conservative there.
//! - A phase whose largest inscribed ball spans more than [`DEEPEST`] voxels in radius is
//!   measured on its own coarser grid (the spacing that brings that ball to `DEEPEST`
//!   voxels): painting costs each ball's volume in voxels, and a pore is often ten walls
//!   wide. [`Thickness::spacing`] says what each phase was measured with.
//! - Cost: a voxelisation and one feature transform per phase (linear), one search of eight
//!   bins per boundary voxel for its tangent plane, then the ridge chords (linear) and ball
//!   painting (each ball's volume in voxels, at most `(2·DEEPEST)³`). A gyroid sheet of 2³
//!   cells at 200³ samples (1.6 M triangles, walls of 6.5 voxels) measures in about 3.5 s
//!   in release on 2 cores, against 0.15 s to contour it.
//! - Nothing panics on degenerate input (empty mesh, NaN positions, bad indices, zero or NaN
//!   spacing): the figures are `None` instead.

pub mod edt;
pub mod genus;
pub mod surface;
pub mod thickness;
pub mod voxel;

use crate::mesh::Mesh;
use crate::vec3::{cross, norm, sub};
pub use genus::{Topology, solid_genera};
pub use voxel::Grid;

/// Order statistics of local thickness over a phase's voxels, in model units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    pub min: f64,
    pub p05: f64,
    pub median: f64,
    pub max: f64,
}

/// Wall thickness (solid) and pore size (void) of a mesh; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thickness {
    pub wall: Option<Stats>,
    pub pore: Option<Stats>,
    /// The voxel side each phase was measured with (solid, void): the spacing asked, or a
    /// coarser one for a phase whose balls would span more than [`DEEPEST`] voxels.
    pub spacing: [f64; 2],
    /// The voxels per axis of the asked spacing's grid (margin included).
    pub samples: [usize; 3],
}

/// The most voxels a phase's largest inscribed ball may span in radius before that phase is
/// measured on a coarser grid. Painting costs each ball's volume in voxels, so a pore forty
/// voxels across would cost a thousand times a wall's; at eight voxels of radius the
/// sub-voxel ridges keep a ball's diameter within a fraction of a percent.
pub const DEEPEST: f64 = 8.0;

/// The spacing that puts `samples` voxels along the longest side of `[min, max]`.
pub fn spacing_for(min: [f64; 3], max: [f64; 3], samples: usize) -> f64 {
    let longest = (0..3).map(|a| max[a] - min[a]).fold(0.0, f64::max);
    longest / samples.max(1) as f64
}

/// The local thickness of the solid of `mesh` and of the void of `box_` (the mesh's
/// bounding box when `None`) minus the solid, on voxels of side `spacing` (coarser for a
/// phase too deep for it: see [`DEEPEST`]).
pub fn thickness(mesh: &Mesh, box_: Option<[[f64; 3]; 2]>, spacing: f64) -> Thickness {
    let mut out = Thickness {
        wall: None,
        pore: None,
        spacing: [spacing; 2],
        samples: [0; 3],
    };
    let Some([min, max]) = box_.or_else(|| bounds(mesh)) else {
        return out;
    };
    let Some(grid) = Grid::covering(min, max, spacing, 1) else {
        return out;
    };
    out.samples = grid.dims;
    let fine = Voxels::new(mesh, grid);
    for phase in [true, false] {
        let feature = fine.features(phase);
        let deepest = feature
            .iter()
            .enumerate()
            .filter(|&(i, &f)| fine.inside[i] == phase && f != edt::NONE)
            .map(|(i, &f)| edt::distance2(grid.dims, i, f as usize))
            .fold(0.0, f64::max)
            .sqrt();
        let coarse = (deepest > DEEPEST)
            .then(|| Grid::covering(min, max, spacing * deepest / DEEPEST, 1))
            .flatten()
            .map(|grid| Voxels::new(mesh, grid));
        let (voxels, feature) = match &coarse {
            Some(coarse) => (coarse, coarse.features(phase)),
            None => (&fine, feature),
        };
        let values = thickness::local_thickness(
            &voxels.grid,
            &voxels.inside,
            phase,
            voxels.patches(),
            &feature,
        );
        drop(feature);
        let dims = voxels.grid.dims;
        let inside = &voxels.inside;
        let stats = if phase {
            thickness::stats(&values, |i| inside[i])
        } else {
            // The margin's voxels centre balls but are not counted: the void is the box's.
            let within = |i: usize| {
                let c = edt::coords(dims, i);
                (0..3).all(|a| c[a] >= 1 && c[a] + 1 < dims[a])
            };
            thickness::stats(&values, |i| !inside[i] && within(i))
        };
        let slot = usize::from(!phase);
        out.spacing[slot] = voxels.grid.spacing;
        if phase {
            out.wall = stats;
        } else {
            out.pore = stats;
        }
    }
    out
}

/// A mesh voxelised on a grid, with its boundary voxels' tangent planes once a phase needs
/// them (both phases share them).
struct Voxels<'a> {
    mesh: &'a Mesh,
    grid: Grid,
    inside: Vec<bool>,
    patches: std::sync::OnceLock<thickness::Patches>,
}

impl<'a> Voxels<'a> {
    fn new(mesh: &'a Mesh, grid: Grid) -> Voxels<'a> {
        Voxels {
            mesh,
            grid,
            inside: voxel::voxelise(mesh, &grid),
            patches: std::sync::OnceLock::new(),
        }
    }

    /// Every voxel's nearest voxel of the other phase than `phase`.
    fn features(&self, phase: bool) -> Vec<u32> {
        let seeds: Vec<bool> = self.inside.iter().map(|&s| s != phase).collect();
        edt::feature_transform(self.grid.dims, &seeds)
    }

    fn patches(&self) -> &thickness::Patches {
        self.patches.get_or_init(|| {
            let surface = surface::Surface::new(self.mesh, &self.grid);
            thickness::patches(&self.grid, &self.inside, &surface)
        })
    }
}

/// The bounding box of the finite vertices a triangle uses; `None` for none.
pub fn bounds(mesh: &Mesh) -> Option<[[f64; 3]; 2]> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in &mesh.triangles {
        for &v in t {
            let Some(p) = mesh.vertices.get(v as usize) else {
                continue;
            };
            if p.iter().all(|c| c.is_finite()) {
                for a in 0..3 {
                    lo[a] = lo[a].min(f64::from(p[a]));
                    hi[a] = hi[a].max(f64::from(p[a]));
                }
            }
        }
    }
    (lo[0] <= hi[0]).then_some([lo, hi])
}

/// The grid spacing a marching-cubes mesh was contoured at, from its mean triangle area: a
/// surface crossing a cube of side `h` is cut into about two triangles covering about `h²`
/// between them, so the mean triangle is about `h²/2`. NaN for a mesh of no valid triangle.
pub fn sample_spacing(mesh: &Mesh) -> f64 {
    let (area, counted) = mesh
        .triangles
        .iter()
        .filter_map(|t| voxel::triangle(mesh, t))
        .map(|[a, b, c]| 0.5 * norm(cross(sub(b, a), sub(c, a))))
        .filter(|area| area.is_finite())
        .fold((0.0, 0usize), |(sum, n), area| (sum + area, n + 1));
    (2.0 * area / counted as f64).sqrt()
}

#[cfg(test)]
mod tests;
