//! Tiling throughput: Schwarz P tiled at a given resolution into a scaffold file, or into a
//! structured grid split into about N tetrahedra; prints triangles per second.
//!
//! `cargo run --release -p latticebuild-geom --example tile_bench -- 100000 12`
//! `cargo run --release -p latticebuild-geom --example tile_bench -- bracket.msh 12`

use latticebuild_geom::element::Element3;
use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::scaffold::read_scaffold;
use latticebuild_geom::tile::{ElementMap, Elements, TiledSolid, tile, tile_scaffold};
use std::time::Instant;

struct SchwarzP;

impl ScalarField for SchwarzP {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let tau = std::f64::consts::TAU;
        for i in 0..out.len() {
            out[i] = (tau * xs[i]).cos() + (tau * ys[i]).cos() + (tau * zs[i]).cos() - 0.3;
        }
    }
}

struct Affine<'a> {
    nodes: &'a [[f64; 3]],
    corners: &'a [u32],
}

impl ElementMap for Affine<'_> {
    fn map(&self, e: usize, xi: [f64; 3]) -> [f64; 3] {
        let c = &self.corners[4 * e..4 * e + 4];
        let q = [xi[0] + 0.5, xi[1] + 0.5, xi[2] + 0.5];
        let (u, v, w) = (
            (q[0] + q[1] - q[2]) / 2.0,
            (-q[0] + q[1] + q[2]) / 2.0,
            (q[0] - q[1] + q[2]) / 2.0,
        );
        let x: [[f64; 3]; 4] = std::array::from_fn(|k| self.nodes[c[k] as usize]);
        std::array::from_fn(|a| {
            x[0][a] + u * (x[1][a] - x[0][a]) + v * (x[2][a] - x[0][a]) + w * (x[3][a] - x[0][a])
        })
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(path) = args.get(1).filter(|a| a.parse::<usize>().is_err()) {
        let resolution: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(12);
        return tile_file(path, resolution);
    }
    let elements: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(100_000);
    let resolution: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(12);
    let d = ((elements as f64 / 6.0).cbrt().round() as usize).max(1);
    let node = |i: usize, j: usize, k: usize| (i + (d + 1) * (j + (d + 1) * k)) as u32;
    let mut nodes = Vec::new();
    for k in 0..=d {
        for j in 0..=d {
            for i in 0..=d {
                nodes.push([i as f64, j as f64, k as f64]);
            }
        }
    }
    let paths = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut corners = Vec::new();
    for k in 0..d {
        for j in 0..d {
            for i in 0..d {
                for path in paths {
                    let mut at = [i, j, k];
                    let mut tet = vec![node(i, j, k)];
                    for axis in path {
                        at[axis] += 1;
                        tet.push(node(at[0], at[1], at[2]));
                    }
                    // Odd paths are left-handed: swap two corners to keep orientation.
                    if left_handed(&tet.iter().map(|&n| nodes[n as usize]).collect::<Vec<_>>()) {
                        tet.swap(2, 3);
                    }
                    corners.extend(tet);
                }
            }
        }
    }
    let maps = Affine {
        nodes: &nodes,
        corners: &corners,
    };
    let scaffold = Elements {
        shape: Element3::Tetrahedron,
        corners: &corners,
        map: &maps,
    };
    let start = Instant::now();
    let solid = TiledSolid::of(&SchwarzP, Solid::Inside { offset: 0.0 });
    match tile(&scaffold, &solid, resolution) {
        Ok((mesh, stats)) => {
            let seconds = start.elapsed().as_secs_f64();
            println!(
                "{} tets, resolution {resolution}: {} triangles, {} vertices in {seconds:.3} s = {:.2} M triangles/s",
                stats.elements,
                mesh.triangles.len(),
                mesh.vertices.len(),
                mesh.triangles.len() as f64 / seconds / 1e6
            );
        }
        Err(e) => eprintln!("tiling failed: {e}"),
    }
}

fn left_handed(x: &[[f64; 3]]) -> bool {
    let d = |i: usize| [x[i][0] - x[0][0], x[i][1] - x[0][1], x[i][2] - x[0][2]];
    let (a, b, c) = (d(1), d(2), d(3));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
        < 0.0
}

fn tile_file(path: &str, resolution: usize) {
    let read = Instant::now();
    let scaffold = match std::fs::read(path).map_err(|e| e.to_string()).and_then(|bytes| {
        read_scaffold(&bytes, path, None).map_err(|e| e.to_string())
    }) {
        Ok(s) => s,
        Err(e) => return eprintln!("{e}"),
    };
    let read = read.elapsed().as_secs_f64();
    let solid = TiledSolid::of(&SchwarzP, Solid::Inside { offset: 0.0 });
    let start = Instant::now();
    match tile_scaffold(&scaffold, &solid, resolution) {
        Ok((mesh, stats)) => {
            let seconds = start.elapsed().as_secs_f64();
            println!(
                "{path}: {} {} elements (read in {read:.2} s), resolution {resolution}: {} triangles in {seconds:.3} s = {:.2} M triangles/s",
                stats.elements,
                scaffold.kind.name(),
                mesh.triangles.len(),
                mesh.triangles.len() as f64 / seconds / 1e6
            );
        }
        Err(e) => eprintln!("tiling failed: {e}"),
    }
}
