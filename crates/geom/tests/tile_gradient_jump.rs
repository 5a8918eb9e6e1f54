//! The gradient jump of a tiled field across scaffold faces, with the isoparametric (C⁰) maps
//! and with the C¹ maps of `Scaffold::make_c1` (docs/method.md §Smooth element maps).
//!
//! The tiled field in element `e` is `F = Φ(ξ_e(x))`, whose gradient is `J_e⁻ᵀ ∇Φ(ξ)`. At points
//! on every interior face it is evaluated from both elements, independently (each element's
//! own Jacobian, `Φ`'s gradient written out by hand), and the largest difference is reported
//! over the largest gradient seen. `Φ` is an Oh (D4 in 2D) cosine series: its faces are mirror
//! planes, so it meets them at right angles, as the C¹ maps need.

use std::path::PathBuf;

use latticebuild_geom::scaffold::{ElementKind, FacetSide, Scaffold, grid, read_scaffold};

const TAU: f64 = std::f64::consts::TAU;

/// ∇Φ for `Φ = Σ cos τξ_a − 0.4 Π cos τξ_a` over the element's dimensions.
fn cell_gradient(xi: [f64; 3], dim: usize) -> [f64; 3] {
    let c: [f64; 3] = std::array::from_fn(|a| if a < dim { (TAU * xi[a]).cos() } else { 1.0 });
    std::array::from_fn(|a| {
        if a >= dim {
            return 0.0;
        }
        let others: f64 = (0..dim).filter(|&b| b != a).map(|b| c[b]).product();
        -TAU * (TAU * xi[a]).sin() * (1.0 - 0.4 * others)
    })
}

/// `J⁻ᵀ g` on the element's own axes (`dim` of them; a 2D scaffold lies in a plane z = c).
fn physical_gradient(j: [[f64; 3]; 3], g: [f64; 3], dim: usize) -> [f64; 3] {
    let mut m = j;
    if dim == 2 {
        m[2] = [0.0, 0.0, 1.0];
    }
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    // J⁻ᵀ g: solve Jᵀ y = g by Cramer's rule, column by column of Jᵀ.
    let jt: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| m[c][r]));
    std::array::from_fn(|k| {
        let mut mk = jt;
        for r in 0..3 {
            mk[r][k] = g[r];
        }
        let d = mk[0][0] * (mk[1][1] * mk[2][2] - mk[1][2] * mk[2][1])
            - mk[0][1] * (mk[1][0] * mk[2][2] - mk[1][2] * mk[2][0])
            + mk[0][2] * (mk[1][0] * mk[2][1] - mk[1][1] * mk[2][0]);
        d / det
    })
}

/// The reference point of a side's face at weights `w` on the face's corners, the corners
/// named by global node (in `global`'s order), so that both sides give the same point.
fn face_point(s: &Scaffold, e: usize, global: &[u32], w: &[f64]) -> [f64; 3] {
    let nodes = s.element(e);
    let mut xi = [0.0; 3];
    for (k, &g) in global.iter().enumerate() {
        let local = nodes.iter().position(|&n| n == g).expect("a shared corner");
        let r = s.kind.reference_node(local);
        for a in 0..3 {
            xi[a] += w[k] * r[a];
        }
    }
    xi
}

/// The largest gradient jump over the largest gradient, on all interior faces and on the
/// faces `smooth_face` accepts (its side elements and global corners).
struct Jump {
    all: f64,
    selected: f64,
    faces: usize,
    selected_faces: usize,
}

fn gradient_jump(s: &Scaffold, select: &dyn Fn(&[u32]) -> bool) -> Jump {
    let dim = s.kind.dimension();
    let facets = s.facets();
    let mut largest: f64 = 0.0;
    let mut jumps = Vec::new();
    for facet in &facets.interior {
        let sides: [FacetSide; 2] = [facet.sides[0], facet.sides[1]];
        let face = s.kind.faces()[sides[0].face as usize];
        let corners = 2 * (dim - 1);
        let global: Vec<u32> = face[..corners]
            .iter()
            .map(|&l| s.element(sides[0].element as usize)[l])
            .collect();
        let mut worst: f64 = 0.0;
        for i in 0..5 {
            for k in 0..if dim == 3 { 5 } else { 1 } {
                let (p, q) = ((i as f64 + 0.5) / 5.0, (k as f64 + 0.5) / 5.0);
                let w: Vec<f64> = if dim == 3 {
                    vec![(1.0 - p) * (1.0 - q), p * (1.0 - q), p * q, (1.0 - p) * q]
                } else {
                    vec![1.0 - p, p]
                };
                let [ga, gb] = sides.map(|side| {
                    let e = side.element as usize;
                    let xi = face_point(s, e, &global, &w);
                    physical_gradient(s.jacobian(e, xi), cell_gradient(xi, dim), dim)
                });
                let d = (0..3).map(|a| (ga[a] - gb[a]).powi(2)).sum::<f64>().sqrt();
                worst = worst.max(d);
                for g in [ga, gb] {
                    largest = largest.max(g.iter().map(|v| v * v).sum::<f64>().sqrt());
                }
            }
        }
        jumps.push((worst, select(&global)));
    }
    let max_of = |only: bool| {
        jumps
            .iter()
            .filter(|j| !only || j.1)
            .fold(0.0f64, |m, j| m.max(j.0))
            / largest
    };
    Jump {
        all: max_of(false),
        selected: max_of(true),
        faces: jumps.len(),
        selected_faces: jumps.iter().filter(|j| j.1).count(),
    }
}

/// A small deterministic pseudo-random number in [-1, 1] from a position.
fn jitter(p: [f64; 3], salt: f64) -> f64 {
    let s = (p[0] * 12.9898 + p[1] * 78.233 + p[2] * 37.719 + salt).sin() * 43758.5453;
    2.0 * (s - s.floor()) - 1.0
}

/// A grid of unit elements with every interior node moved up to `amount` along each axis.
fn distorted(kind: ElementKind, d: [usize; 3], amount: f64) -> Scaffold {
    let max = d.map(|n| n as f64);
    let mut s = grid([0.0; 3], max, d, kind).expect("a grid");
    let dim = kind.dimension();
    for p in &mut s.nodes {
        if (0..dim).all(|a| p[a] > 0.0 && p[a] < max[a]) {
            let q = *p;
            for (a, c) in p.iter_mut().enumerate().take(dim) {
                *c += amount * jitter(q, a as f64);
            }
        }
    }
    s
}

fn c1(s: &Scaffold) -> Scaffold {
    let mut c1 = s.clone();
    c1.make_c1().expect("a quad4 or hex8 scaffold");
    c1
}

#[test]
fn c1_maps_remove_the_gradient_jump_on_a_distorted_grid() {
    for (kind, d) in [
        (ElementKind::Hex8, [4, 4, 3]),
        (ElementKind::Quad4, [6, 5, 1]),
    ] {
        let s = distorted(kind, d, 0.25);
        let every = |_: &[u32]| true;
        let c0 = gradient_jump(&s, &every);
        let smooth = gradient_jump(&c1(&s), &every);
        eprintln!(
            "{kind:?} {d:?}: {} faces, jump/|∇F| C⁰ {:.3e}, C¹ {:.3e}",
            c0.faces, c0.all, smooth.all
        );
        assert!(c0.all > 0.05, "the C⁰ tiling should jump: {}", c0.all);
        assert!(smooth.all < 1e-12, "the C¹ tiling jumps by {}", smooth.all);
    }
}

/// Nodes whose every edge has an opposite edge through them, in the sense of the C¹ maps:
/// counted independently here, from the node's valence (4 in a planar quad mesh away from the
/// boundary, 6 in a hex mesh).
fn regular_interior_nodes(s: &Scaffold) -> Vec<bool> {
    let dim = s.kind.dimension();
    let mut neighbours = vec![Vec::new(); s.nodes.len()];
    for e in 0..s.element_count() {
        for &[a, b] in s.kind.edges() {
            let (v, w) = (s.element(e)[a], s.element(e)[b]);
            neighbours[v as usize].push(w);
            neighbours[w as usize].push(v);
        }
    }
    let mut boundary = vec![false; s.nodes.len()];
    for facet in &s.facets().boundary {
        for &n in facet.corners() {
            boundary[n as usize] = true;
        }
    }
    neighbours
        .iter_mut()
        .zip(&boundary)
        .map(|(list, &on_boundary)| {
            list.sort_unstable();
            list.dedup();
            !on_boundary && list.len() == 2 * dim
        })
        .collect()
}

#[test]
fn c1_maps_on_a_shipped_scaffold() {
    let file = "plate_hole_quad4.msh";
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/scaffolds");
    let bytes = std::fs::read(path.join(file)).expect("the shipped scaffold");
    let s = read_scaffold(&bytes, file, Some("msh")).expect("it reads");
    let regular = regular_interior_nodes(&s);
    let all_regular = |corners: &[u32]| corners.iter().all(|&n| regular[n as usize]);
    let c0 = gradient_jump(&s, &all_regular);
    let smooth = gradient_jump(&c1(&s), &all_regular);
    eprintln!(
        "{file}: {} interior edges, {} between regular nodes; jump/|∇F| C⁰ {:.3e} ({:.3e} \
         there), C¹ {:.3e} ({:.3e} there)",
        c0.faces, c0.selected_faces, c0.all, c0.selected, smooth.all, smooth.selected
    );
    assert!(c0.selected_faces > c0.faces / 2);
    assert!(
        c0.selected > 0.05,
        "the C⁰ tiling should jump: {}",
        c0.selected
    );
    assert!(smooth.selected < 1e-12, "C¹ jumps by {}", smooth.selected);
    // Next to irregular nodes the jump is only reduced.
    assert!(smooth.all < c0.all, "{} against {}", smooth.all, c0.all);
}

/// The cell whose gradient the jump tests write out: `Φ` as a field, offset so that the
/// solid is one network through every face.
struct Wavy;

impl latticebuild_geom::field::ScalarField for Wavy {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (((o, &x), &y), &z) in out.iter_mut().zip(xs).zip(ys).zip(zs) {
            let c = [x, y, z].map(|v| (TAU * v).cos());
            *o = c[0] + c[1] + c[2] - 0.4 * c[0] * c[1] * c[2];
        }
    }
}

#[test]
fn a_c1_tiling_is_closed_and_one_piece() {
    use latticebuild_geom::field::Solid;
    use latticebuild_geom::tile::{TiledSolid, tile_scaffold};
    use latticebuild_geom::validate::{check, components};
    let s = c1(&distorted(ElementKind::Hex8, [4, 4, 3], 0.25));
    let solid = TiledSolid::of(&Wavy, Solid::Inside { offset: 0.0 });
    let (mesh, stats) = tile_scaffold(&s, &solid, 10).expect("it tiles");
    let c = check(&mesh);
    assert!(c.watertight && c.manifold, "{c:?}");
    assert_eq!(components(&mesh), 1);
    assert_eq!(stats.elements, 48);
    // The surface follows the C¹ maps: each element's vertices are where Φ(ξ) = 0 for ξ
    // found by Newton on that element's own map (checked on a few elements).
    let c0 = distorted(ElementKind::Hex8, [4, 4, 3], 0.25);
    let (mut on, mut moved): (f64, f64) = (0.0, 0.0);
    // Vertices of the caps on the box's faces are not on the zero set: skipped.
    let inside = |x: &[f64; 3]| (0..3).all(|a| x[a] > 1e-4 && x[a] < [4.0, 4.0, 3.0][a] - 1e-4);
    let points = mesh.vertices.iter().map(|v| v.map(f64::from));
    for x in points.filter(inside).step_by(97) {
        on = on.max(distance_to_surface(&s, x));
        moved = moved.max(distance_to_surface(&c0, x));
    }
    eprintln!("C¹ tiling's vertices: {on:.2e} from its field's zero set, {moved:.2e} from C⁰'s");
    // On its own zero set to the contouring's accuracy (elements of size 1 at resolution 10);
    // off the C⁰ tiling's by a visible fraction of an element.
    assert!(on < 5e-3, "{on}");
    assert!(moved > 5.0 * on, "{moved}");
}

/// How far `x` is from the zero set of the tiled field, to first order: |Φ(ξ)| / |∇F| in the
/// element containing `x` (Newton on its map), or 0 outside every element.
fn distance_to_surface(s: &Scaffold, x: [f64; 3]) -> f64 {
    let mut best = f64::INFINITY;
    for e in 0..s.element_count() {
        let mut xi = [0.0; 3];
        for _ in 0..20 {
            let p = s.map(e, xi);
            let j = s.jacobian(e, xi);
            let r = [x[0] - p[0], x[1] - p[1], x[2] - p[2]];
            // Solve J d = r (Cramer), via J⁻ᵀ's transpose: d = J⁻¹ r.
            let jt: [[f64; 3]; 3] = std::array::from_fn(|a| std::array::from_fn(|b| j[b][a]));
            let d = physical_gradient(jt, r, 3);
            for a in 0..3 {
                xi[a] += d[a];
            }
        }
        if xi.iter().all(|v| v.abs() <= 0.5 + 1e-9) {
            let c = xi.map(|v| (TAU * v).cos());
            let phi = c[0] + c[1] + c[2] - 0.4 * c[0] * c[1] * c[2];
            let g = physical_gradient(s.jacobian(e, xi), cell_gradient(xi, 3), 3);
            let norm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
            best = best.min(phi.abs() / norm.max(1e-9));
        }
    }
    if best.is_finite() { best } else { 0.0 }
}
