//! Tiling a [`Scaffold`] read from a file or generated: its corners name vertices across
//! elements, its isoparametric maps (linear or quadratic) place them.
//!
//! Invariant: only volume scaffolds (tet4/tet10, hex8/hex20/hex27) are tiled here; the first
//! `corner_count` nodes of every kind are its corners in the reference element's order.

use super::{ElementMap, Elements, Nodes, TileError, TileStats, TiledSolid, tile};
use crate::element::Element3;
use crate::mesh::Mesh;
use crate::scaffold::{ElementKind, Scaffold};

impl ElementMap for Scaffold {
    fn map(&self, element: usize, xi: [f64; 3]) -> [f64; 3] {
        Scaffold::map(self, element, xi)
    }
}

/// The reference element of a volume element kind.
pub fn reference_element(kind: ElementKind) -> Option<Element3> {
    match kind {
        ElementKind::Tet4 | ElementKind::Tet10 => Some(Element3::Tetrahedron),
        ElementKind::Hex8 | ElementKind::Hex20 | ElementKind::Hex27 => Some(Element3::Cube),
        _ => None,
    }
}

/// Tiles `solid` into every element of `scaffold` (nodal arrays indexed like its nodes).
pub fn tile_scaffold(
    scaffold: &Scaffold,
    solid: &TiledSolid,
    resolution: usize,
) -> Result<(Mesh, TileStats), TileError> {
    let (shape, corners) = corners(scaffold)?;
    let elements = Elements {
        shape,
        corners: &corners,
        nodes: nodes(scaffold),
        map: scaffold,
    };
    tile(&elements, solid, resolution).map_err(|e| e.tagged(&scaffold.element_tags))
}

/// Every node of every element of `scaffold`, which interpolate its nodal values.
pub(super) fn nodes(scaffold: &Scaffold) -> Nodes<'_> {
    Nodes {
        kind: scaffold.kind,
        ids: &scaffold.connectivity,
    }
}

/// The reference shape of a volume scaffold and its elements' corner nodes, element by element.
pub(super) fn corners(scaffold: &Scaffold) -> Result<(Element3, Vec<u32>), TileError> {
    let shape =
        reference_element(scaffold.kind).ok_or(TileError::NotVolume(scaffold.kind.name()))?;
    let (per, corners_per) = (scaffold.kind.node_count(), scaffold.kind.corner_count());
    let corners: Vec<u32> = scaffold
        .connectivity
        .chunks_exact(per)
        .flat_map(|element| element[..corners_per].iter().copied())
        .collect();
    Ok((shape, corners))
}
