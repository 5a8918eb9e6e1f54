//! The 2D continuity statement on the shared Gmsh meshes, with graded and transition fields:
//! every lattice point on an edge shared by two elements has bitwise the same sample from
//! both; and the lattices' orbit representatives are invariant under the element's group.

use super::super::lattice::Lattice;
use super::super::square::SquareLattice;
use super::super::triangle::TriangleLattice;
use super::super::{ElementSamples, Nodes, TiledSolid, Transition, symmetric_samples};
use crate::field::{ScalarField, Solid};
use crate::scaffold::read_scaffold;
use std::collections::HashMap;

/// `cos 2πx + cos 2πy − offset` (D4, and the triangle's lattice does not care: samples are
/// taken at orbit representatives whatever the field).
struct Waves(f64);

impl ScalarField for Waves {
    fn eval_points(&self, xs: &[f64], ys: &[f64], _: &[f64], out: &mut [f64]) {
        let tau = std::f64::consts::TAU;
        for i in 0..out.len() {
            out[i] = (tau * xs[i]).cos() + (tau * ys[i]).cos() - self.0;
        }
    }
}

/// A disc of radius `r` about the centre.
struct Disc(f64);

impl ScalarField for Disc {
    fn eval_points(&self, xs: &[f64], ys: &[f64], _: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = xs[i].hypot(ys[i]) - self.0;
        }
    }
}

/// `x + 2y`: no symmetry at all.
struct Tilted;

impl ScalarField for Tilted {
    fn eval_points(&self, xs: &[f64], ys: &[f64], _: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = xs[i] + 2.0 * ys[i];
        }
    }
}

#[test]
fn shared_edge_samples_are_bitwise_equal_from_both_sides() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/scaffolds");
    let (waves, disc) = (Waves(0.3), Disc(0.3));
    for (file, resolution) in [
        ("plate_hole_tri3.msh", 9),
        ("plate_hole_tri6.msh", 8),
        ("plate_hole_quad4.msh", 9),
        ("plate_hole_quad8.msh", 7),
        ("plate_hole_quad9.msh", 8),
        ("sphere_surface_tri6.msh", 7),
        ("cylinder_side_quad9.msh", 6),
    ] {
        let bytes = std::fs::read(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        let scaffold = read_scaffold(&bytes, file, None).unwrap_or_else(|e| panic!("{e}"));
        let weight: Vec<f64> = scaffold
            .nodes
            .iter()
            .map(|x| (0.13 * x[0]).sin().abs())
            .collect();
        let thickness: Vec<f64> = scaffold.nodes.iter().map(|x| 0.4 + 0.01 * x[1]).collect();
        let solid = TiledSolid {
            transition: Some(Transition {
                to: &disc,
                weight: &weight,
            }),
            thickness: Some(&thickness),
            ..TiledSolid::of(
                &waves,
                Solid::EccentricShell {
                    offset: 0.1,
                    thickness: 0.0,
                },
            )
        };
        let lattice: Box<dyn Lattice> = if scaffold.kind.is_simplex() {
            Box::new(TriangleLattice::new(resolution))
        } else {
            Box::new(SquareLattice::new(resolution))
        };
        let lattice = lattice.as_ref();
        let nodes = Nodes {
            kind: scaffold.kind,
            ids: &scaffold.connectivity,
        };
        let samples =
            ElementSamples::new(lattice, &solid, symmetric_samples(lattice, &waves), nodes)
                .unwrap_or_else(|e| panic!("{file}: {e}"));
        let (per, corners) = (scaffold.kind.node_count(), scaffold.kind.corner_count());
        let mut seen: HashMap<Vec<(u32, u32)>, (u64, usize)> = HashMap::new();
        let mut values = vec![f64::NAN; lattice.index_len()];
        let (mut compared, mut points) = (0usize, 0usize);
        for (e, element) in scaffold.connectivity.chunks_exact(per).enumerate() {
            let corner_nodes = &element[..corners];
            samples.fill(e, &mut values, false);
            for q in (0..lattice.index_len() as u32).filter(|&q| lattice.is_point(q)) {
                let w = lattice.weights(q);
                if !lattice.face_masks().iter().any(|&f| w.mask() & !f == 0) {
                    continue;
                }
                let mut name: Vec<(u32, u32)> = w
                    .as_slice()
                    .iter()
                    .map(|&(c, k)| (corner_nodes[c as usize], k))
                    .collect();
                name.sort_unstable();
                let bits = values[q as usize].to_bits();
                match seen.get(&name) {
                    Some(&(other, from)) if from != e => {
                        compared += 1;
                        assert_eq!(bits, other, "{file}: elements {from} and {e} at {name:?}");
                    }
                    Some(_) => {}
                    None => {
                        points += 1;
                        seen.insert(name, (bits, e));
                    }
                }
            }
        }
        assert!(
            compared > points / 2,
            "{file}: only {compared} comparisons of {points}"
        );
    }
}

/// The point `(i, j)` of the square's lattice under the 8 elements of D4, and the point with
/// barycentric `a` of the triangle's under the 6 permutations of S3 (= D3): all have one
/// representative, and the sample of an asymmetric field is the same across each orbit.
#[test]
fn representatives_are_constant_on_orbits() {
    let n = 7u32;
    let square = SquareLattice::new(n as usize);
    let m = n - 1;
    let index = |i: u32, j: u32| i + n * j;
    for j in 0..n {
        for i in 0..n {
            let rep = square.representative(index(i, j));
            for (a, b) in [(i, j), (j, i)] {
                for (x, y) in [(a, b), (m - a, b), (a, m - b), (m - a, m - b)] {
                    assert_eq!(square.representative(index(x, y)), rep, "({i}, {j})");
                }
            }
        }
    }
    let triangle = TriangleLattice::new(n as usize);
    let tri_index = |a: [u32; 3]| a[1] + n * a[2];
    for u in 0..=m {
        for v in 0..=m - u {
            let a = [m - u - v, u, v];
            let rep = triangle.representative(tri_index(a));
            for p in [
                [0, 1, 2],
                [1, 2, 0],
                [2, 0, 1],
                [0, 2, 1],
                [2, 1, 0],
                [1, 0, 2],
            ] {
                let b = p.map(|k| a[k]);
                assert_eq!(triangle.representative(tri_index(b)), rep, "{a:?}");
            }
        }
    }
    // An asymmetric field takes its representative's value across the orbit.
    let samples = symmetric_samples(&square, &Tilted);
    assert_eq!(
        samples[index(2, 1) as usize],
        1.0 / m as f64 - 0.5 + 2.0 * (2.0 / m as f64 - 0.5)
    );
    assert_eq!(
        samples[index(1, 2) as usize].to_bits(),
        samples[index(m - 2, 1) as usize].to_bits()
    );
}
