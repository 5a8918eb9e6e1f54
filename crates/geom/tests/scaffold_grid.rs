//! Generated grids: counts, measure = box volume, conforming facets (every interior facet shared
//! by exactly two elements, boundary facets only on the box), positive Jacobians; and `check`
//! catching an element turned inside out.

use latticebuild_geom::scaffold::{ElementKind, Scaffold, check, grid};

const MIN: [f64; 3] = [-1.0, 0.5, 2.0];
const MAX: [f64; 3] = [3.0, 2.0, 2.75];
const DIV: [usize; 3] = [4, 3, 2];

fn on_box_surface(p: [f64; 3], dims: usize) -> bool {
    (0..dims).any(|a| p[a] == MIN[a] || p[a] == MAX[a])
}

fn facet_counts(kind: ElementKind) -> (usize, usize, usize) {
    let [nx, ny, nz] = DIV;
    match kind {
        ElementKind::Hex8 => {
            let cells = nx * ny * nz;
            let boundary = 2 * (nx * ny + ny * nz + nx * nz);
            (cells, (6 * cells - boundary) / 2, boundary)
        }
        ElementKind::Tet4 => {
            let cells = 6 * nx * ny * nz;
            let boundary = 4 * (nx * ny + ny * nz + nx * nz);
            (cells, (4 * cells - boundary) / 2, boundary)
        }
        ElementKind::Quad4 => {
            let cells = nx * ny;
            let boundary = 2 * (nx + ny);
            (cells, (4 * cells - boundary) / 2, boundary)
        }
        _ => {
            let cells = 2 * nx * ny;
            let boundary = 2 * (nx + ny);
            (cells, (3 * cells - boundary) / 2, boundary)
        }
    }
}

fn assert_grid(s: &Scaffold) {
    let kind = s.kind;
    let dims = kind.dimension();
    let (elements, interior, boundary) = facet_counts(kind);
    let layers = if dims == 3 { DIV[2] + 1 } else { 1 };
    assert_eq!(s.element_count(), elements, "{kind}");
    assert_eq!(
        s.nodes.len(),
        (DIV[0] + 1) * (DIV[1] + 1) * layers,
        "{kind}"
    );
    let volume: f64 = (0..dims).map(|a| MAX[a] - MIN[a]).product();
    assert!(
        (s.measure() - volume).abs() < 1e-12 * volume,
        "{kind}: {}",
        s.measure()
    );
    let facets = s.facets();
    assert!(facets.overused.is_empty(), "{kind}");
    assert_eq!(facets.interior.len(), interior, "{kind}: interior facets");
    assert_eq!(facets.boundary.len(), boundary, "{kind}: boundary facets");
    for f in &facets.interior {
        assert_eq!(f.sides.len(), 2);
        assert_ne!(f.sides[0].element, f.sides[1].element);
    }
    // A non-conforming split would leave unmatched facets inside the box.
    for f in &facets.boundary {
        let centre: Vec<f64> = (0..3)
            .map(|a| {
                f.corners()
                    .iter()
                    .map(|&n| s.nodes[n as usize][a])
                    .sum::<f64>()
                    / f.corners().len() as f64
            })
            .collect();
        let all_on_one_side = (0..dims).any(|a| {
            f.corners()
                .iter()
                .all(|&n| s.nodes[n as usize][a] == MIN[a])
                || f.corners()
                    .iter()
                    .all(|&n| s.nodes[n as usize][a] == MAX[a])
        });
        assert!(
            all_on_one_side,
            "{kind}: boundary facet at {centre:?} inside the box"
        );
        assert!(
            f.corners()
                .iter()
                .all(|&n| on_box_surface(s.nodes[n as usize], dims))
        );
    }
    // Positive orientation everywhere.
    for e in 0..s.element_count() {
        let j = s.jacobian(e, [0.0; 3]);
        let d = if dims == 3 {
            j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
                - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
                + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
        } else {
            j[0][0] * j[1][1] - j[1][0] * j[0][1]
        };
        assert!(d > 0.0, "{kind}: element {e} has det J {d}");
    }
    check(s).unwrap_or_else(|e| panic!("{e}"));
    // Each interior facet's two sides list the same corners in opposite winding (outward
    // normals oppose), the property the tiler's welding relies on.
    for f in &facets.interior {
        let normal = |side: latticebuild_geom::scaffold::FacetSide| {
            let nodes = s.element(side.element as usize);
            let face = kind.faces()[side.face as usize];
            let p: Vec<[f64; 3]> = face.iter().map(|&c| s.nodes[nodes[c] as usize]).collect();
            if dims == 3 {
                let u = [0, 1, 2].map(|a| p[1][a] - p[0][a]);
                let v = [0, 1, 2].map(|a| p[2][a] - p[0][a]);
                [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ]
            } else {
                [p[1][1] - p[0][1], p[0][0] - p[1][0], 0.0]
            }
        };
        let (a, b) = (normal(f.sides[0]), normal(f.sides[1]));
        let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
        assert!(
            dot < 0.0,
            "{kind}: outward normals of a shared facet oppose"
        );
    }
}

#[test]
fn generated_grids_are_conforming_positive_and_fill_the_box() {
    for kind in [
        ElementKind::Hex8,
        ElementKind::Tet4,
        ElementKind::Quad4,
        ElementKind::Tri3,
    ] {
        let s = grid(MIN, MAX, DIV, kind).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.kind, kind);
        assert!(s.nodes.iter().all(|p| kind.dimension() == 3 || p[2] == 0.0));
        assert_grid(&s);
    }
}

#[test]
fn grids_reject_bad_boxes_and_kinds() {
    let e = grid([0.0; 3], [1.0, 0.0, 1.0], [1; 3], ElementKind::Hex8).expect_err("flat box");
    assert_eq!(
        e.to_string(),
        "grid: grid axis y: expected finite min < max, found 0 and 0"
    );
    let e = grid([0.0; 3], [1.0; 3], [1, 0, 1], ElementKind::Tet4).expect_err("no divisions");
    assert_eq!(
        e.to_string(),
        "grid: grid axis y: expected at least 1 division, found 0"
    );
    let e = grid([0.0; 3], [1.0; 3], [1; 3], ElementKind::Hex27).expect_err("kind");
    assert_eq!(
        e.to_string(),
        "grid: a grid of hex27 elements cannot be generated: expected hex8, tet4, quad4 or tri3"
    );
    let e = grid([0.0; 3], [1.0, 1e39, 1.0], [1; 3], ElementKind::Hex8).expect_err("huge");
    assert_eq!(
        e.to_string(),
        "grid: grid max: coordinate y = 1e39 is beyond ±3.4028235e38, the largest a mesh \
         vertex (single precision) holds"
    );
    // 2D grids ignore z entirely.
    let s = grid(
        [0.0, 0.0, 5.0],
        [1.0, 1.0, 5.0],
        [2, 2, 0],
        ElementKind::Quad4,
    )
    .expect("2D");
    assert!((s.measure() - 1.0).abs() < 1e-13);
}

#[test]
fn check_names_an_element_turned_inside_out() {
    // Unit cubes, so J = ±I exactly and the message is exact.
    let mut s = grid([0.0; 3], [2.0; 3], [2, 2, 2], ElementKind::Hex8).expect("grid");
    let e = 2; // element tag 3
    let n = 8;
    let (bottom, top) = s.connectivity[e * n..(e + 1) * n].split_at_mut(4);
    bottom.swap_with_slice(top);
    assert_eq!(
        check(&s).expect_err("inverted").to_string(),
        "grid: element 3 is inverted (det J = -1.000e0 at local node 0)"
    );
    let mut t = grid([0.0; 3], [1.0; 3], [1, 1, 1], ElementKind::Tet4).expect("grid");
    for e in [1, 4] {
        t.connectivity.swap(4 * e, 4 * e + 1);
    }
    let m = check(&t).expect_err("two inverted").to_string();
    assert!(
        m.starts_with("grid: 2 inverted or degenerate elements: element 2 is inverted"),
        "{m}"
    );
    assert!(m.contains("; element 5 is inverted"), "{m}");
}
