//! The square's lattice: `n²` points `ξ = −½ + (i, j)/(n − 1)` (z = 0), contoured by marching
//! squares with the face rule of the 3D tables (on a cell with two inside corners on a
//! diagonal, each inside corner is cut off on its own), so two elements sharing an edge draw
//! the same crossings on it and a 2D tiling is what a 3D one draws on a face.
//!
//! Corners are numbered in Gmsh's quad order (0 (−,−), 1 (+,−), 2 (+,+), 3 (−,+)); edges as the
//! quad's facets (01, 12, 23, 30). The symmetry group is D4: the orbit representative of
//! `(i, j)` folds each coordinate to `min(c, n − 1 − c)` and sorts the pair.
//!
//! A band (a shell: the part between two levels) is drawn cell by cell as the 3D contourer caps
//! a band on a cube face (`Tables::band_cap` on the face z = 0, turned to face +z), so it too
//! is what a 3D tiling draws on a face.
//!
//! Invariants: the local mesh is the filled region `{Φ < 0}` as triangles, counter-clockwise in
//! ξ (the lattice map `(i, j) ↦ ξ` is a positive scaling), with vertices on lattice edges
//! (crossings) or lattice points (inside corners); there are no caps (a region is closed by
//! its boundary loops, not by faces).

use super::lattice::{Lattice, Weights, grid_representative};
use super::local::{LocalBuilder, LocalMesh, Samples, inside};
use crate::contour::table::tables;

/// The quad's corners as 0/1 per axis, in Gmsh order.
const SQUARE_CORNERS: [[u32; 2]; 4] = [[0, 0], [1, 0], [1, 1], [0, 1]];

pub struct SquareLattice {
    /// Points per edge.
    n: u32,
}

impl SquareLattice {
    /// `n ≥ 2` points per edge.
    pub fn new(n: usize) -> SquareLattice {
        SquareLattice { n: n as u32 }
    }

    #[inline]
    fn index(&self, [i, j]: [u32; 2]) -> u32 {
        i + self.n * j
    }

    #[inline]
    fn coords(&self, p: u32) -> [u32; 2] {
        [p % self.n, p / self.n]
    }
}

/// A marching-squares polygon item: a cell corner or the crossing on the side from corner
/// `k` to corner `k + 1`.
#[derive(Clone, Copy)]
enum Item {
    Corner(usize),
    Side(usize),
}

impl Lattice for SquareLattice {
    fn index_len(&self) -> usize {
        (self.n as usize).pow(2)
    }

    fn is_point(&self, p: u32) -> bool {
        (p as usize) < self.index_len()
    }

    fn xi(&self, p: u32) -> [f64; 3] {
        let m = f64::from(self.n - 1);
        let [i, j] = self.coords(p).map(|c| f64::from(c) / m - 0.5);
        [i, j, 0.0]
    }

    fn representative(&self, p: u32) -> u32 {
        self.index(grid_representative(self.coords(p), self.n - 1))
    }

    fn weights(&self, p: u32) -> Weights {
        Weights::grid(self.coords(p), self.n - 1, &SQUARE_CORNERS)
    }

    fn face_masks(&self) -> &[u8] {
        &[0b0011, 0b0110, 0b1100, 0b1001]
    }

    fn takes_bands(&self) -> bool {
        true
    }

    fn contour(&self, samples: Samples) -> LocalMesh {
        if let Some(upper) = samples.upper {
            return self.contour_band(samples.lower, upper);
        }
        let values = samples.lower;
        let mut builder = LocalBuilder::new(samples, 0);
        let last = self.n - 2;
        let mut polygon: Vec<u32> = Vec::with_capacity(8);
        for j in 0..=last {
            for i in 0..=last {
                // Counter-clockwise; side k runs from corner k to corner k + 1.
                let corners =
                    [[i, j], [i + 1, j], [i + 1, j + 1], [i, j + 1]].map(|c| self.index(c));
                let ins = corners.map(|p| inside(values[p as usize]));
                if !ins.iter().any(|&b| b) {
                    continue;
                }
                let mut id = |item: Item| match item {
                    Item::Corner(k) => builder.point(corners[k]),
                    Item::Side(k) => builder.crossing(corners[k], corners[(k + 1) % 4]),
                };
                let crossings = (0..4).filter(|&k| ins[k] != ins[(k + 1) % 4]).count();
                if crossings == 4 {
                    // The face rule: each inside corner of an ambiguous cell on its own.
                    let mut cut = Vec::with_capacity(2);
                    for k in (0..4).filter(|&k| ins[k]) {
                        cut.push(
                            [Item::Corner(k), Item::Side(k), Item::Side((k + 3) % 4)].map(&mut id),
                        );
                    }
                    builder.mesh.triangles.extend(cut);
                    continue;
                }
                polygon.clear();
                for k in 0..4 {
                    if ins[k] {
                        polygon.push(id(Item::Corner(k)));
                    }
                    if ins[k] != ins[(k + 1) % 4] {
                        polygon.push(id(Item::Side(k)));
                    }
                }
                // One cut line leaves a convex inside part: a fan triangulates it.
                for k in 1..polygon.len() - 1 {
                    builder
                        .mesh
                        .triangles
                        .push([polygon[0], polygon[k], polygon[k + 1]]);
                }
            }
        }
        builder.finish()
    }
}

impl SquareLattice {
    /// The band where both `lower` and `upper` are negative ([`Samples`]), cell by cell: the
    /// cube tables' band cap on the face z = 0 (its corners 0–3 are the cell's, x fastest),
    /// reversed, since caps face outward (−z there) and regions face +z.
    fn contour_band(&self, lower: &[f64], upper: &[f64]) -> LocalMesh {
        /// The cube's face z = 0 in the tables' cap order (`2 · axis + side`).
        const FACE_Z0: usize = 4;
        let tables = tables();
        let mut builder = LocalBuilder::new(
            Samples {
                lower,
                upper: Some(upper),
            },
            0,
        );
        let last = self.n - 2;
        for j in 0..=last {
            for i in 0..=last {
                let corner = |c: u8| {
                    let c = u32::from(c);
                    self.index([i + (c & 1), j + ((c >> 1) & 1)])
                };
                let config_of = |bit: &dyn Fn(usize) -> bool| {
                    (0..4u8).fold(0u8, |bits, c| bits | u8::from(bit(corner(c) as usize)) << c)
                };
                let p = config_of(&|p| inside(lower[p]));
                let q = config_of(&|p| upper[p] >= 0.0);
                for tri in tables.band_cap(p, q, FACE_Z0) {
                    let t = [tri[0], tri[2], tri[1]].map(|slot| builder.slot(slot, corner));
                    builder.mesh.triangles.push(t);
                }
            }
        }
        builder.finish()
    }
}
