//! Facets of a scaffold (faces in 3D, edges in 2D), matched by their sorted corner nodes.
//!
//! Invariants: every element facet appears in exactly one [`Facet`]; `interior` facets have
//! two sides, `boundary` facets one, and facets used by three or more elements (a non-manifold
//! mesh) are listed in `overused` with all their sides. Facets are ordered by their sorted
//! corners, so the order depends only on the mesh.

use super::Scaffold;

/// One element's view of a facet: the element and its local face index (into `kind.faces()`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FacetSide {
    pub element: u32,
    pub face: u8,
}

/// A facet: its corner nodes, sorted, and the elements on its sides.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Facet {
    corners: [u32; 4],
    corner_count: u8,
    pub sides: Vec<FacetSide>,
}

impl Facet {
    /// Corner node indices, ascending (the canonical order of the facet's frame).
    pub fn corners(&self) -> &[u32] {
        &self.corners[..self.corner_count as usize]
    }
}

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Facets {
    pub interior: Vec<Facet>,
    pub boundary: Vec<Facet>,
    pub overused: Vec<Facet>,
}

impl Scaffold {
    /// All facets, interior (two elements) and boundary (one).
    pub fn facets(&self) -> Facets {
        let faces = self.kind.faces();
        let mut keys: Vec<([u32; 4], u8, FacetSide)> =
            Vec::with_capacity(self.element_count() * faces.len());
        for e in 0..self.element_count() {
            let nodes = self.element(e);
            for (f, face) in faces.iter().enumerate() {
                let mut key = [u32::MAX; 4];
                for (k, &c) in face.iter().enumerate() {
                    key[k] = nodes[c];
                }
                key[..face.len()].sort_unstable();
                keys.push((
                    key,
                    face.len() as u8,
                    FacetSide {
                        element: e as u32,
                        face: f as u8,
                    },
                ));
            }
        }
        keys.sort_unstable_by_key(|&(key, _, side)| (key, side.element, side.face));
        let mut facets = Facets::default();
        let mut i = 0;
        while i < keys.len() {
            let mut j = i + 1;
            while j < keys.len() && keys[j].0 == keys[i].0 {
                j += 1;
            }
            let facet = Facet {
                corners: keys[i].0,
                corner_count: keys[i].1,
                sides: keys[i..j].iter().map(|k| k.2).collect(),
            };
            match j - i {
                1 => facets.boundary.push(facet),
                2 => facets.interior.push(facet),
                _ => facets.overused.push(facet),
            }
            i = j;
        }
        facets
    }
}
