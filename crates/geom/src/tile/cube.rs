//! The cube's lattice: `n³` points `ξ = −½ + (i, j, k)/(n − 1)`, contoured by the streaming
//! contourer's marching-cubes tables (the same face rule, so two elements sharing a face draw
//! the same segments on it, and the caps use the same rule).
//!
//! Corners are numbered in Gmsh's hex order (0 (−,−,−), 1 (+,−,−), 2 (+,+,−), 3 (−,+,−), then
//! the same at z = +½); faces in the tables' cap order `2·axis + side`.

use super::lattice::{Lattice, Weights, grid_representative};
use super::local::{LocalBuilder, LocalMesh, Samples, inside};
use crate::contour::table::{HI_SLOT, tables};
pub use crate::scaffold::HEX_CORNERS;

pub struct CubeLattice {
    /// Points per edge.
    n: u32,
    face_masks: [u8; 6],
}

impl CubeLattice {
    /// `n ≥ 2` points per edge.
    pub fn new(n: usize) -> CubeLattice {
        let face_masks = std::array::from_fn(|f| {
            let (axis, side) = (f / 2, (f % 2) as u32);
            (0..8).fold(0u8, |m, c| {
                if HEX_CORNERS[c][axis] == side {
                    m | 1 << c
                } else {
                    m
                }
            })
        });
        CubeLattice {
            n: n as u32,
            face_masks,
        }
    }

    #[inline]
    fn index(&self, [i, j, k]: [u32; 3]) -> u32 {
        i + self.n * (j + self.n * k)
    }

    #[inline]
    fn coords(&self, p: u32) -> [u32; 3] {
        [p % self.n, (p / self.n) % self.n, p / (self.n * self.n)]
    }
}

impl Lattice for CubeLattice {
    fn index_len(&self) -> usize {
        (self.n as usize).pow(3)
    }

    fn is_point(&self, p: u32) -> bool {
        (p as usize) < self.index_len()
    }

    fn xi(&self, p: u32) -> [f64; 3] {
        let m = f64::from(self.n - 1);
        self.coords(p).map(|c| f64::from(c) / m - 0.5)
    }

    fn representative(&self, p: u32) -> u32 {
        self.index(grid_representative(self.coords(p), self.n - 1))
    }

    fn weights(&self, p: u32) -> Weights {
        Weights::grid(self.coords(p), self.n - 1, &HEX_CORNERS)
    }

    fn face_masks(&self) -> &[u8] {
        &self.face_masks
    }

    fn takes_bands(&self) -> bool {
        true
    }

    fn contour(&self, samples: Samples) -> LocalMesh {
        let tables = tables();
        let last = self.n - 2;
        let lower = samples.lower;
        let mut builder = LocalBuilder::new(samples, 6);
        for k in 0..=last {
            for j in 0..=last {
                for i in 0..=last {
                    let corner = |c: u8| {
                        let c = u32::from(c);
                        self.index([i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)])
                    };
                    let config_of = |bit: &dyn Fn(usize) -> bool| {
                        (0..8u8).fold(0u8, |bits, c| bits | u8::from(bit(corner(c) as usize)) << c)
                    };
                    let on_face = [i == 0, i == last, j == 0, j == last, k == 0, k == last];
                    let vertex = |builder: &mut LocalBuilder, slot: u8| builder.slot(slot, corner);
                    let Some(upper) = samples.upper else {
                        let config = config_of(&|p| inside(lower[p]));
                        for tri in tables.triangles(config) {
                            let t = tri.map(|s| vertex(&mut builder, s));
                            builder.mesh.triangles.push(t);
                        }
                        for face in (0..6).filter(|&f| on_face[f]) {
                            for tri in tables.cap(config, face) {
                                let t = tri.map(|s| vertex(&mut builder, s));
                                builder.mesh.caps[face].push(t);
                            }
                        }
                        continue;
                    };
                    // A band, as the box contourer takes it (`contour::table`): `p` the corners
                    // above the lower level, `q ⊆ p` those at or above the upper one; `p`'s
                    // surface on the lower crossings, `q`'s reversed on the upper ones.
                    let p = config_of(&|p| inside(lower[p]));
                    let q = config_of(&|p| upper[p] >= 0.0);
                    for tri in tables.triangles(p) {
                        let t = tri.map(|s| vertex(&mut builder, s));
                        builder.mesh.triangles.push(t);
                    }
                    for tri in tables.triangles(q) {
                        let t = [tri[0], tri[2], tri[1]].map(|s| vertex(&mut builder, HI_SLOT + s));
                        builder.mesh.triangles.push(t);
                    }
                    for face in (0..6).filter(|&f| on_face[f]) {
                        for tri in tables.band_cap(p, q, face) {
                            let t = tri.map(|s| vertex(&mut builder, s));
                            builder.mesh.caps[face].push(t);
                        }
                    }
                }
            }
        }
        builder.finish()
    }
}
