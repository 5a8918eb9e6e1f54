use super::*;
use crate::scaffold::grid;

/// A grid's nodes moved by `f`.
fn moved(mut scaffold: Scaffold, f: impl Fn([f64; 3]) -> [f64; 3]) -> Scaffold {
    for p in &mut scaffold.nodes {
        *p = f(*p);
    }
    scaffold
}

/// A small deterministic pseudo-random number in [-1, 1] from a node position.
fn jitter(p: [f64; 3], salt: f64) -> f64 {
    let s = (p[0] * 12.9898 + p[1] * 78.233 + p[2] * 37.719 + salt).sin() * 43758.5453;
    2.0 * (s - s.floor()) - 1.0
}

fn distorted_hex() -> Scaffold {
    let s = grid([0.0; 3], [4.0, 3.0, 3.0], [4, 3, 3], ElementKind::Hex8).unwrap();
    moved(s, |p| {
        let interior = (0..3).all(|a| p[a] > 0.0 && p[a] < [4.0, 3.0, 3.0][a]);
        if !interior {
            return p;
        }
        std::array::from_fn(|a| p[a] + 0.25 * jitter(p, a as f64))
    })
}

#[test]
fn an_affine_grid_keeps_its_affine_map() {
    // Every corner derivative is the edge vector, so the Hermite patch is the affine map.
    for kind in [ElementKind::Hex8, ElementKind::Quad4] {
        let s = grid([0.0; 3], [3.0, 2.0, 2.0], [3, 2, 2], kind).unwrap();
        let s = moved(s, |p| {
            [
                p[0] + 0.3 * p[1] - 0.2 * p[2],
                1.5 * p[1] + 0.1 * p[0],
                0.7 * p[2] + 0.2 * p[1],
            ]
        });
        let mut c1 = s.clone();
        c1.make_c1().unwrap();
        for e in 0..s.element_count() {
            for xi in [[0.1, -0.3, 0.4], [0.5, 0.5, -0.5], [-0.2, 0.0, 0.1]] {
                let xi = if kind == ElementKind::Quad4 {
                    [xi[0], xi[1], 0.0]
                } else {
                    xi
                };
                let (a, b) = (s.map(e, xi), c1.map(e, xi));
                let (ja, jb) = (s.jacobian(e, xi), c1.jacobian(e, xi));
                for i in 0..3 {
                    assert!(
                        (a[i] - b[i]).abs() < 1e-12,
                        "{kind:?} {e} {xi:?}: {a:?} {b:?}"
                    );
                    for k in 0..3 {
                        assert!((ja[i][k] - jb[i][k]).abs() < 1e-12, "{ja:?} {jb:?}");
                    }
                }
            }
        }
    }
}

#[test]
fn the_jacobian_is_the_derivative_of_the_map() {
    let mut s = distorted_hex();
    s.make_c1().unwrap();
    let h = 1e-6;
    for e in [0, 7, 20] {
        let xi = [0.13, -0.37, 0.29];
        let j = s.jacobian(e, xi);
        for a in 0..3 {
            let (mut p, mut m) = (xi, xi);
            p[a] += h;
            m[a] -= h;
            let (xp, xm) = (s.map(e, p), s.map(e, m));
            for i in 0..3 {
                let fd = (xp[i] - xm[i]) / (2.0 * h);
                assert!((fd - j[i][a]).abs() < 1e-7, "{e} {a} {i}: {fd} {}", j[i][a]);
            }
        }
    }
}

/// The reference point of face `face` of `kind` at bilinear face coordinates `(s, t)`, with
/// the face's corners given by global node: `(s, t)` are weights on the face's corners in the
/// order of `global` (any element sharing the face gives the same physical point).
fn face_point(s: &Scaffold, e: usize, global: &[u32], st: [f64; 2]) -> [f64; 3] {
    let w = [
        (1.0 - st[0]) * (1.0 - st[1]),
        st[0] * (1.0 - st[1]),
        st[0] * st[1],
        (1.0 - st[0]) * st[1],
    ];
    let nodes = s.element(e);
    let mut xi = [0.0; 3];
    for (k, &g) in global.iter().enumerate() {
        let local = nodes.iter().position(|&n| n == g).unwrap();
        let r = s.kind.reference_node(local);
        for a in 0..3 {
            xi[a] += w[k] * r[a];
        }
    }
    xi
}

/// The reference axis normal to a side's face.
fn across(s: &Scaffold, side: crate::scaffold::FacetSide) -> usize {
    let face = s.kind.faces()[side.face as usize];
    let corner = |k: usize| s.kind.reference_node(face[k]);
    (0..3)
        .find(|&a| (1..4).all(|k| corner(k)[a] == corner(0)[a]))
        .unwrap()
}

#[test]
fn faces_match_and_their_cross_derivatives_are_opposite() {
    let mut s = distorted_hex();
    s.make_c1().unwrap();
    let smooth = s.smooth.clone().unwrap();
    let facets = s.facets();
    assert!(!facets.interior.is_empty());
    let mut worst_gap: f64 = 0.0;
    let mut worst_cross: f64 = 0.0;
    for facet in &facets.interior {
        let [a, b] = [facet.sides[0], facet.sides[1]].map(|x| x.element as usize);
        // The face's corners in cyclic order, as element a lists them.
        let face = s.kind.faces()[facet.sides[0].face as usize];
        let cyclic: Vec<u32> = face[..4].iter().map(|&l| s.element(a)[l]).collect();
        for st in [[0.2, 0.3], [0.5, 0.5], [0.9, 0.1], [0.0, 0.6]] {
            let (xa, xb) = (
                face_point(&s, a, &cyclic, st),
                face_point(&s, b, &cyclic, st),
            );
            let (pa, pb) = (s.map(a, xa), s.map(b, xb));
            worst_gap = worst_gap.max(length(sub(pa, pb)));
            // The derivative across the face: along the axis its corners all share.
            let (ka, kb) = (across(&s, facet.sides[0]), across(&s, facet.sides[1]));
            let (ja, jb) = (s.jacobian(a, xa), s.jacobian(b, xb));
            // Outward from each element: the sign of its face coordinate.
            let da: [f64; 3] = std::array::from_fn(|i| ja[i][ka] * xa[ka].signum());
            let db: [f64; 3] = std::array::from_fn(|i| jb[i][kb] * xb[kb].signum());
            worst_cross = worst_cross.max(length([da[0] + db[0], da[1] + db[1], da[2] + db[2]]));
        }
    }
    assert!(worst_gap < 1e-12, "faces apart by {worst_gap}");
    assert!(
        worst_cross < 1e-12,
        "cross derivatives differ by {worst_cross}"
    );
    // Every node of a jittered grid is regular: every interior corner edge is paired.
    let unpaired = (0..s.element_count())
        .flat_map(|e| (0..8).flat_map(move |c| (0..3).map(move |a| (e, c, a))))
        .filter(|&(e, c, a)| !smooth.paired(e, c, a))
        .count();
    // Only edges leaving the boundary (from a boundary node inward) stay unpaired.
    assert!(unpaired > 0 && unpaired < 8 * 3 * s.element_count() / 2);
}

#[test]
fn only_linear_quadrilaterals_and_hexahedra_are_made_c1() {
    let mut tets = grid([0.0; 3], [1.0; 3], [1, 1, 1], ElementKind::Tet4).unwrap();
    let error = tets.make_c1().unwrap_err();
    assert!(error.message.contains("tet4"), "{error}");
    assert!(tets.smooth.is_none());
}
