//! Planar contouring in the 2D reference elements: exact element areas, closed and oriented
//! boundary loops that are exactly the mesh's boundary edges, and the SVG drawing.

use latticebuild_geom::contour2d::{
    Element2, PlanarError, PlanarRegion, contour_planar, contour_planar_band, contour_planar_box,
    contour_planar_box_band,
};
use latticebuild_geom::field::Band;
use latticebuild_geom::mesh_io::write_svg;
use latticebuild_geom::validate::check;
use std::collections::{HashMap, HashSet};
use std::f64::consts::PI;

fn region(f: impl Fn([f64; 2]) -> f64 + Sync, element: Element2, samples: usize) -> PlanarRegion {
    contour_planar(&f, element, samples).expect("contour")
}

fn disc(r: f64) -> impl Fn([f64; 2]) -> f64 + Sync {
    move |p| p[0].hypot(p[1]) - r
}

fn signed_area(lp: &[[f64; 2]]) -> f64 {
    (0..lp.len())
        .map(|k| {
            let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
            0.5 * (a[0] * b[1] - b[0] * a[1])
        })
        .sum()
}

/// Checks the structural invariants and returns the loops' signed areas.
fn assert_consistent(r: &PlanarRegion, what: &str) -> Vec<f64> {
    let mesh = &r.mesh;
    // Planar, counter-clockwise from +z, no degenerate or duplicate vertices, no pinches.
    assert!(mesh.vertices.iter().all(|v| v[2] == 0.0), "{what}: z != 0");
    let c = check(mesh);
    assert!(c.manifold, "{what}: not manifold: {c:?}");
    let p = |i: u32| mesh.vertices[i as usize].map(f64::from);
    for t in &mesh.triangles {
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(
            cross > 0.0,
            "{what}: triangle {t:?} is not counter-clockwise"
        );
    }
    // Edge uses: every undirected edge once (boundary) or twice in opposite directions.
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    let mut mesh_boundary = HashSet::new();
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "{what}: directed edge {a}->{b} used {n} times");
        if !directed.contains_key(&(b, a)) {
            mesh_boundary.insert((a, b));
        }
    }
    assert_eq!(c.boundary_edges, mesh_boundary.len(), "{what}");
    // The loops' edges, mapped back to vertex ids by position, are exactly those edges.
    assert_eq!(r.positions.len(), mesh.vertices.len(), "{what}");
    // The f32 rounding, or (a crossing kept inside its edge far from the origin) the next
    // f32 value beside it.
    for (p, v) in r.positions.iter().zip(&mesh.vertices) {
        for a in 0..2 {
            let rounded = p[a] as f32;
            assert!(
                [rounded, rounded.next_up(), rounded.next_down()].contains(&v[a]),
                "{what}: {v:?} is not {p:?} in f32"
            );
        }
    }
    let id: HashMap<[u64; 2], u32> = r
        .positions
        .iter()
        .enumerate()
        .map(|(i, q)| ([q[0].to_bits(), q[1].to_bits()], i as u32))
        .collect();
    let key = |q: [f64; 2]| id[&[q[0].to_bits(), q[1].to_bits()]];
    let mut loop_edges = HashSet::new();
    for lp in &r.boundary {
        assert!(lp.len() >= 3, "{what}: loop of {} points", lp.len());
        for k in 0..lp.len() {
            let e = (key(lp[k]), key(lp[(k + 1) % lp.len()]));
            assert!(loop_edges.insert(e), "{what}: edge {e:?} in two loops");
        }
    }
    assert_eq!(
        loop_edges, mesh_boundary,
        "{what}: loops and mesh boundary differ"
    );
    r.boundary.iter().map(|lp| signed_area(lp)).collect()
}

#[test]
fn contour2d_constant_inside_field_covers_the_element_exactly() {
    for element in [Element2::Square, Element2::Triangle] {
        for samples in [2, 3, 10, 57] {
            let what = format!("{element:?} at {samples}");
            let r = region(|_| -1.0, element, samples);
            let area = r.area();
            assert!((area - element.area()).abs() < 1e-9, "{what}: area {area}");
            let loops = assert_consistent(&r, &what);
            assert_eq!(loops.len(), 1, "{what}");
            assert!(
                (loops[0] - element.area()).abs() < 1e-12,
                "{what}: {loops:?}"
            );
            // The loop passes through every corner of the element.
            for corner in element.outline() {
                let near = r.boundary[0]
                    .iter()
                    .any(|q| (q[0] - corner[0]).hypot(q[1] - corner[1]) < 1e-6);
                assert!(near, "{what}: corner {corner:?} missing");
            }
        }
    }
    // A shallow constant too: the triangle's sides are its subdivision's.
    let r = region(|_| -1e-3, Element2::Triangle, 30);
    assert!((r.area() - Element2::Triangle.area()).abs() < 1e-9);
}

#[test]
fn contour2d_disc_has_the_disc_area_and_one_ccw_loop() {
    for (element, radius) in [(Element2::Square, 0.3), (Element2::Triangle, 0.2)] {
        for (samples, tolerance) in [(41, 4e-3), (101, 8e-4)] {
            let what = format!("{element:?} disc at {samples}");
            let r = region(disc(radius), element, samples);
            let exact = PI * radius * radius;
            let error = (r.area() - exact) / exact;
            assert!(error.abs() < tolerance, "{what}: relative error {error:e}");
            let loops = assert_consistent(&r, &what);
            assert_eq!(loops.len(), 1, "{what}");
            assert!(loops[0] > 0.0, "{what}: loop is clockwise");
            assert!((loops[0] - r.area()).abs() < 1e-6, "{what}");
        }
    }
    assert!((PI * 0.09 - region(disc(0.3), Element2::Square, 201).area()).abs() < 2e-4);
}

#[test]
fn contour2d_annulus_has_an_outer_ccw_and_an_inner_cw_loop() {
    let annulus = |p: [f64; 2]| {
        let r = p[0].hypot(p[1]);
        (r - 0.35).max(0.15 - r)
    };
    for element in [Element2::Square, Element2::Triangle] {
        // The triangle's inradius is √3/6 ≈ 0.289 < 0.35: its annulus is cut by the sides,
        // still one outer loop around one hole.
        let r = region(annulus, element, 81);
        let what = format!("{element:?} annulus");
        let loops = assert_consistent(&r, &what);
        assert_eq!(loops.len(), 2, "{what}: {loops:?}");
        assert_eq!(loops.iter().filter(|&&a| a > 0.0).count(), 1, "{what}");
        assert_eq!(loops.iter().filter(|&&a| a < 0.0).count(), 1, "{what}");
        let total: f64 = loops.iter().sum();
        assert!(
            (total - r.area()).abs() < 1e-6,
            "{what}: {total} vs {}",
            r.area()
        );
        if element == Element2::Square {
            let exact = PI * (0.35f64.powi(2) - 0.15f64.powi(2));
            assert!(((r.area() - exact) / exact).abs() < 3e-3, "{}", r.area());
        }
    }
}

#[test]
fn contour2d_saddles_follow_the_face_rule() {
    // A checkerboard of discs puts ambiguous cells everywhere; with the face rule the inside
    // corners are separated, so the region stays an edge- and vertex-manifold set of loops.
    let checker = |p: [f64; 2]| -(6.0 * PI * p[0]).cos() * (6.0 * PI * p[1]).cos();
    for element in [Element2::Square, Element2::Triangle] {
        for samples in [7, 13, 40] {
            let what = format!("{element:?} checker at {samples}");
            let r = region(checker, element, samples);
            let loops = assert_consistent(&r, &what);
            let total: f64 = loops.iter().sum();
            assert!((total - r.area()).abs() < 1e-6, "{what}");
        }
    }
    // Exactly ambiguous square: inside at two diagonal corners only gives two corner triangles.
    let r = region(
        |p| if p[0] * p[1] > 0.0 { -1.0 } else { 1.0 },
        Element2::Square,
        2,
    );
    assert_eq!(r.mesh.triangles.len(), 2);
    assert_eq!(r.boundary.len(), 2);
}

#[test]
fn contour2d_bad_input_is_an_error() {
    for element in [Element2::Square, Element2::Triangle] {
        for samples in [0, 1] {
            assert_eq!(
                contour_planar(&|_| -1.0, element, samples),
                Err(PlanarError::TooFewSamples(samples))
            );
        }
        assert!(matches!(
            contour_planar(&|_| -1.0, element, usize::MAX),
            Err(PlanarError::TooManySamples(_))
        ));
        let empty = region(|_| f64::NAN, element, 9);
        assert!(empty.mesh.is_empty() && empty.boundary.is_empty());
    }
}

#[test]
fn contour2d_element_geometry() {
    let tri = Element2::Triangle;
    let outline = tri.outline();
    assert!((signed_area(&outline) - 3f64.sqrt() / 4.0).abs() < 1e-15);
    let centroid = outline
        .iter()
        .fold([0.0; 2], |c, p| [c[0] + p[0] / 3.0, c[1] + p[1] / 3.0]);
    assert!(centroid[0].abs() < 1e-15 && centroid[1].abs() < 1e-15);
    for k in 0..3 {
        let (a, b) = (outline[k], outline[(k + 1) % 3]);
        assert!(((a[0] - b[0]).hypot(a[1] - b[1]) - 1.0).abs() < 1e-15);
        assert!(tri.signed_distance(a).abs() < 1e-15);
    }
    assert!(outline[2][0] == 0.0 && outline[2][1] > 0.0, "points to +y");
    assert!((tri.signed_distance([0.0, 0.0]) + 3f64.sqrt() / 6.0).abs() < 1e-15);
    let sq = Element2::Square;
    assert!((sq.signed_distance([0.8, 0.9]) - 0.5).abs() < 1e-15);
    assert!((sq.signed_distance([0.0, 0.1]) + 0.4).abs() < 1e-15);
    assert_eq!(sq.bbox(), ([-0.5; 2], [0.5; 2]));
}

/// Checks that tags are balanced: a tiny tag-stack parser, enough for what we write.
fn assert_balanced_xml(s: &str) {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = s;
    while let Some(open) = rest.find('<') {
        let close = rest[open..].find('>').expect("unclosed tag") + open;
        let tag = &rest[open + 1..close];
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.trim()),
                "mismatched </{name}>"
            );
        } else if !tag.ends_with('/') {
            let name = tag.split_whitespace().next().expect("tag name");
            stack.push(name.to_string());
        }
        rest = &rest[close + 1..];
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
}

#[test]
fn contour2d_svg_draws_every_loop_in_one_evenodd_path() {
    let annulus = |p: [f64; 2]| {
        let r = p[0].hypot(p[1]);
        (r - 0.35).max(0.15 - r)
    };
    for element in [Element2::Square, Element2::Triangle] {
        let r = region(annulus, element, 33);
        let mut out = Vec::new();
        write_svg(&r, &element.outline(), &mut out).expect("svg");
        let svg = String::from_utf8(out.clone()).expect("utf8");
        assert!(svg.starts_with("<svg"), "{svg}");
        assert_balanced_xml(&svg);
        assert_eq!(svg.matches("<path").count(), 1);
        assert!(svg.contains("fill-rule=\"evenodd\""));
        let d_start = svg.find(" d=\"").expect("d") + 4;
        let d = &svg[d_start..d_start + svg[d_start..].find('"').expect("end of d")];
        assert_eq!(d.matches('M').count(), r.boundary.len());
        assert_eq!(d.matches('Z').count(), r.boundary.len());
        assert!(
            !d.contains("NaN") && !d.contains("e-"),
            "plain decimals: {d}"
        );
        // y is flipped: the triangle's apex (+y) is at the top, i.e. the most negative y.
        if element == Element2::Triangle {
            let apex = "0,-0.57735".to_string();
            assert!(svg.contains(&apex), "apex {apex} not in {svg}");
        }
        // Deterministic.
        let mut again = Vec::new();
        write_svg(&r, &element.outline(), &mut again).expect("svg");
        assert_eq!(out, again);
    }
    // Empty region and non-finite input.
    let mut out = Vec::new();
    write_svg(&PlanarRegion::default(), &[], &mut out).expect("empty svg");
    assert_balanced_xml(std::str::from_utf8(&out).expect("utf8"));
    let bad = [[0.0, f64::NAN]];
    let mut none = Vec::new();
    assert!(write_svg(&PlanarRegion::default(), &bad, &mut none).is_err());
    assert!(none.is_empty(), "nothing written on bad input");
}

#[test]
fn contour2d_box_of_discs_caps_on_the_rectangle() {
    // Discs of radius 0.3 on the unit lattice, over [0.2, 3.2] × [0, 2] (cut through discs
    // on every side): the area is that of the lattice pattern restricted to the rectangle,
    // computed here by fine midpoint quadrature.
    let field = |p: [f64; 2]| {
        let (dx, dy) = (p[0] - p[0].round(), p[1] - p[1].round());
        dx.hypot(dy) - 0.3
    };
    let (min, max) = ([0.2, 0.0], [3.2, 2.0]);
    let r = contour_planar_box(&field, min, max, [241, 161]).unwrap();
    let m = 3000;
    let mut inside = 0usize;
    for i in 0..m {
        for j in 0..m {
            let x = min[0] + (max[0] - min[0]) * (i as f64 + 0.5) / m as f64;
            let y = min[1] + (max[1] - min[1]) * (j as f64 + 0.5) / m as f64;
            inside += usize::from(field([x, y]) <= 0.0);
        }
    }
    let exact = 6.0 * inside as f64 / (m * m) as f64;
    assert!(
        (r.area() - exact).abs() / exact < 2e-3,
        "{} vs {exact}",
        r.area()
    );
    let loops = assert_consistent(&r, "box of discs");
    // Every region loop is counter-clockwise (no holes) and stays in the rectangle.
    assert!(loops.iter().all(|&a| a > 0.0), "{loops:?}");
    for p in r.boundary.iter().flatten() {
        assert!(p[0] >= min[0] - 1e-12 && p[0] <= max[0] + 1e-12, "{p:?}");
        assert!(p[1] >= min[1] - 1e-12 && p[1] <= max[1] + 1e-12, "{p:?}");
    }
    // One loop per disc meeting the rectangle: centres x ∈ {0, 1, 2, 3} × y ∈ {0, 1, 2}.
    assert_eq!(loops.len(), 12);
    assert!(matches!(
        contour_planar_box(&field, min, max, [1, 5]),
        Err(PlanarError::TooFewSamples(1))
    ));
}

/// Over a rectangle far from the origin, where 1/256 of an edge is less than an `f32` step
/// (2⁻¹⁴ at 1000, the spacing here 0.005), crossings still keep their own `f32` positions:
/// manifold, no duplicate positions, no flat triangles. And a grid with no `f32` between
/// two neighbouring samples is refused.
#[test]
fn contour2d_box_far_from_the_origin_keeps_distinct_f32_positions() {
    let field = |p: [f64; 2]| {
        let (dx, dy) = (p[0] - p[0].round(), p[1] - p[1].round());
        // Circles of radius 0.3 about the integer points, and ones about the half points.
        dx.hypot(dy).min((dx.abs() - 0.5).hypot(dy.abs() - 0.5)) - 0.3
    };
    for (min, max) in [
        ([1000.0, 1000.0], [1002.0, 1001.0]),
        ([-1002.0, 2000.0], [-1000.0, 2001.0]),
    ] {
        let r = contour_planar_box(&field, min, max, [401, 201]).unwrap();
        assert_consistent(&r, "far rectangle");
        let c = check(&r.mesh);
        assert_eq!(
            (c.duplicate_positions, c.degenerate_triangles),
            (0, 0),
            "{min:?}"
        );
        assert!(c.manifold, "{min:?}: {c:?}");
        let distinct: HashSet<[u32; 3]> = r
            .mesh
            .vertices
            .iter()
            .map(|v| v.map(f32::to_bits))
            .collect();
        assert_eq!(distinct.len(), r.mesh.vertices.len(), "{min:?}");
    }
    // f32 steps are 1/16 near a million; the spacing is 0.01.
    let err = contour_planar_box(&field, [1.0e6, 0.0], [1.0e6 + 0.1, 1.0], [11, 5]).unwrap_err();
    assert!(
        matches!(
            err,
            PlanarError::BeyondF32 {
                axis: 0,
                index: 0,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("along x samples 0 and 1"), "{err}");
}

/// `cos 2πx + cos 2πy`: its zero set is steeper than 2π per unit everywhere but at saddles.
fn waves(p: [f64; 2]) -> f64 {
    (2.0 * PI * p[0]).cos() + (2.0 * PI * p[1]).cos()
}

/// Fraction of `[0, 2] × [0, 1]` where `lo < waves < hi`, by the midpoint rule.
fn band_fraction(band: Band) -> f64 {
    let n = 2000;
    let mut inside = 0usize;
    for j in 0..n {
        for i in 0..2 * n {
            let v = waves([(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64]);
            inside += usize::from(v > band.lo && v < band.hi);
        }
    }
    inside as f64 / (2 * n * n) as f64
}

/// A shell thinner than a sample spacing, contoured as the band between its levels, keeps
/// its area and converges; the region keeps every structural invariant. (Sampled as
/// `|f| − w/2` it vanished wherever the wall fell between two samples.)
#[test]
fn contour2d_thin_bands_keep_their_area() {
    let band = Band {
        lo: -0.15,
        hi: 0.15,
    };
    let expected = band_fraction(band);
    let errors: Vec<f64> = [9, 17, 65]
        .iter()
        .map(|&per_unit| {
            let counts = [2 * (per_unit - 1) + 1, per_unit];
            let r = contour_planar_box_band(&waves, band, [0.0; 2], [2.0, 1.0], counts).unwrap();
            let areas = assert_consistent(&r, &format!("band at {per_unit}"));
            (areas.iter().sum::<f64>() / 2.0 / expected - 1.0).abs()
        })
        .collect();
    assert!(errors[0] < 0.1, "relative errors {errors:?}");
    assert!(errors[2] < 0.01, "relative errors {errors:?}");
    // Over the square element: the band of the same field, within the element's square.
    let r = contour_planar_band(&|p: [f64; 2]| waves([p[0] + 0.5, p[1] + 0.5]), band, 65).unwrap();
    let area: f64 = assert_consistent(&r, "square band").iter().sum();
    assert!((area / expected - 1.0).abs() < 0.01, "{area} vs {expected}");
}

/// Far from the origin a band's two crossings on one edge can round to one `f32`: they are
/// kept apart, so the region has distinct positions and no flat triangle; a grid with room
/// for one `f32` between samples but not two is refused for a band.
#[test]
fn contour2d_far_bands_keep_distinct_f32_positions() {
    for band in [
        Band { lo: -0.4, hi: 0.4 },
        Band {
            lo: -1e-4,
            hi: 1e-4,
        },
    ] {
        let r = contour_planar_box_band(&waves, band, [30000.0; 2], [30000.5, 30000.25], [61, 31])
            .unwrap();
        let c = check(&r.mesh);
        assert!(c.manifold && c.triangles > 0, "{band:?}: {c:?}");
        assert_eq!(
            (c.duplicate_positions, c.degenerate_triangles),
            (0, 0),
            "{band:?}"
        );
    }
    // Near 2^20 f32 steps are 1/8: samples 0.25 apart have one f32 between them.
    let (min, max) = ([1048576.0, 0.0], [1048577.0, 1.0]);
    assert!(contour_planar_box(&waves, min, max, [5, 5]).is_ok());
    let band = Band { lo: -0.1, hi: 0.1 };
    let err = contour_planar_box_band(&waves, band, min, max, [5, 5]).unwrap_err();
    assert!(
        matches!(
            err,
            PlanarError::BeyondF32 {
                axis: 0,
                needed: 2,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn contour2d_square_keeps_the_square_s_symmetry() {
    // A D4-symmetric field (no sample zero to rounding): the region's full-precision vertices
    // map onto themselves under the 8 signed permutations of the plane.
    let t = 2.0 * PI;
    let f = move |p: [f64; 2]| {
        let (a, b) = ((t * p[0]).cos(), (t * p[1]).cos());
        a + b + 0.5 * a * b + 0.05
    };
    let r = region(f, Element2::Square, 33);
    let mut sorted = r.positions.clone();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]));
    for swap in [false, true] {
        for signs in 0..4 {
            let s = |a: usize| if (signs >> a) & 1 == 1 { -1.0 } else { 1.0 };
            for p in &r.positions {
                let q = if swap { [p[1], p[0]] } else { *p };
                let q = [s(0) * q[0], s(1) * q[1]];
                let from = sorted.partition_point(|v| v[0] < q[0] - 1e-9);
                let found = sorted[from..]
                    .iter()
                    .take_while(|v| v[0] <= q[0] + 1e-9)
                    .any(|v| (v[1] - q[1]).abs() < 1e-9);
                assert!(
                    found,
                    "image {q:?} of {p:?} (swap {swap}, signs {signs}) missing"
                );
            }
        }
    }
}
