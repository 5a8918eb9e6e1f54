//! Generated scaffolds: a box divided into hex8, tet4, quad4 or tri3 elements.
//!
//! Invariants:
//! - Nodes form a regular lattice (x fastest, then y, then z), the box corners exactly at `min`
//!   and `max`; node and element tags run from 1.
//! - Every element is positively oriented (det J > 0 in 3D, counter-clockwise seen from +z in
//!   2D), and the mesh is conforming: each hex is split into 6 tets along its main diagonal
//!   (Kuhn/Freudenthal, the same split in every cube, so shared faces have the same diagonal);
//!   each square into 2 triangles along the diagonal from its (min, min) corner.
//! - 2D kinds ignore z (`min[2]`, `max[2]`, `divisions[2]`): their nodes lie in z = 0.

use super::{ElementKind, HEX_CORNERS, Location, Scaffold, ScaffoldError};

/// The 6 axis orders of the Kuhn split, with their permutation sign.
const KUHN: [([usize; 3], bool); 6] = [
    ([0, 1, 2], true),
    ([1, 2, 0], true),
    ([2, 0, 1], true),
    ([0, 2, 1], false),
    ([2, 1, 0], false),
    ([1, 0, 2], false),
];

/// At most this many elements (about 1 GB of connectivity for hexes).
const MAX_ELEMENTS: usize = 30_000_000;

pub fn grid(
    min: [f64; 3],
    max: [f64; 3],
    divisions: [usize; 3],
    kind: ElementKind,
) -> Result<Scaffold, ScaffoldError> {
    let fail = |m: String| ScaffoldError::new("grid", Location::File, m);
    let dims = kind.dimension();
    if !matches!(
        kind,
        ElementKind::Hex8 | ElementKind::Tet4 | ElementKind::Quad4 | ElementKind::Tri3
    ) {
        return Err(fail(format!(
            "a grid of {kind} elements cannot be generated: expected hex8, tet4, quad4 or tri3"
        )));
    }
    for a in 0..dims {
        if !(min[a].is_finite() && max[a].is_finite() && min[a] < max[a]) {
            return Err(fail(format!(
                "grid axis {}: expected finite min < max, found {} and {}",
                ["x", "y", "z"][a],
                min[a],
                max[a]
            )));
        }
        for (end, v) in [("min", min[a]), ("max", max[a])] {
            let mut p = [0.0; 3];
            p[a] = v;
            if let Some(problem) = super::assemble::coordinate_problem(p) {
                return Err(fail(format!("grid {end}: {problem}")));
            }
        }
        if divisions[a] == 0 {
            return Err(fail(format!(
                "grid axis {}: expected at least 1 division, found 0",
                ["x", "y", "z"][a]
            )));
        }
    }
    let d = if dims == 3 {
        divisions
    } else {
        [divisions[0], divisions[1], 1]
    };
    let per_cell = match kind {
        ElementKind::Tet4 => 6,
        ElementKind::Tri3 => 2,
        _ => 1,
    };
    let cells = d[0]
        .checked_mul(d[1])
        .and_then(|c| c.checked_mul(d[2]))
        .and_then(|c| c.checked_mul(per_cell))
        .filter(|&c| c <= MAX_ELEMENTS)
        .ok_or_else(|| {
            fail(format!(
                "a grid of {} x {} x {} is too large: at most {MAX_ELEMENTS} elements",
                d[0], d[1], d[2]
            ))
        })?;
    let layers = if dims == 3 { d[2] + 1 } else { 1 };
    let coordinate = |a: usize, i: usize| {
        if i == d[a] {
            max[a]
        } else {
            min[a] + (max[a] - min[a]) * (i as f64 / d[a] as f64)
        }
    };
    let mut nodes = Vec::with_capacity((d[0] + 1) * (d[1] + 1) * layers);
    for k in 0..layers {
        for j in 0..=d[1] {
            for i in 0..=d[0] {
                let z = if dims == 3 { coordinate(2, k) } else { 0.0 };
                nodes.push([coordinate(0, i), coordinate(1, j), z]);
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| (i + (d[0] + 1) * (j + (d[1] + 1) * k)) as u32;
    let mut connectivity = Vec::with_capacity(cells * kind.node_count());
    for k in 0..d[2] {
        for j in 0..d[1] {
            for i in 0..d[0] {
                let at = |o: [usize; 3]| id(i + o[0], j + o[1], k + o[2]);
                match kind {
                    ElementKind::Hex8 => {
                        for o in HEX_CORNERS {
                            connectivity.push(at(o.map(|c| c as usize)));
                        }
                    }
                    ElementKind::Tet4 => {
                        for (axes, even) in KUHN {
                            let mut o = [0usize; 3];
                            let mut tet = [at(o); 4];
                            for (step, &a) in axes.iter().enumerate() {
                                o[a] = 1;
                                tet[step + 1] = at(o);
                            }
                            if !even {
                                tet.swap(2, 3);
                            }
                            connectivity.extend_from_slice(&tet);
                        }
                    }
                    ElementKind::Quad4 => {
                        for o in [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]] {
                            connectivity.push(at(o));
                        }
                    }
                    _ => {
                        for o in [
                            [0, 0, 0],
                            [1, 0, 0],
                            [1, 1, 0],
                            [0, 0, 0],
                            [1, 1, 0],
                            [0, 1, 0],
                        ] {
                            connectivity.push(at(o));
                        }
                    }
                }
            }
        }
    }
    let elements = connectivity.len() / kind.node_count();
    Ok(Scaffold {
        kind,
        node_tags: (1..=nodes.len() as u64).collect(),
        nodes,
        connectivity,
        element_tags: (1..=elements as u64).collect(),
        physical: vec![0; elements],
        physical_names: Vec::new(),
        node_data: Vec::new(),
        source: "grid".to_string(),
        smooth: None,
    })
}
