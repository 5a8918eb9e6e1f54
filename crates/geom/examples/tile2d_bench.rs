//! 2D tiling throughput: a D4 cell tiled into a structured quad (or tri) grid of about N
//! elements at a given resolution; the region, its extrusion and its normal-offset shell.
//! Prints triangles per second for each.
//!
//! `cargo run --release -p latticebuild-geom --example tile2d_bench -- 100000 12 quad4`

use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::scaffold::{ElementKind, grid};
use latticebuild_geom::tile::{TiledSolid, extrude, thickness_normal, tile_surface_scaffold};
use std::time::Instant;

struct Waves;

impl ScalarField for Waves {
    fn eval_points(&self, xs: &[f64], ys: &[f64], _: &[f64], out: &mut [f64]) {
        let tau = std::f64::consts::TAU;
        for i in 0..out.len() {
            out[i] = (tau * xs[i]).cos() + (tau * ys[i]).cos() - 0.5;
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let elements: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(100_000);
    let resolution: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(12);
    let kind = args
        .get(3)
        .and_then(|k| ElementKind::from_name(k))
        .unwrap_or(ElementKind::Quad4);
    let per_square = if kind.is_simplex() { 2.0 } else { 1.0 };
    let d = ((elements as f64 / per_square).sqrt().round() as usize).max(1);
    let scaffold = match grid([0.0; 3], [d as f64, d as f64, 0.0], [d, d, 0], kind) {
        Ok(s) => s,
        Err(e) => return eprintln!("{e}"),
    };
    let solid = TiledSolid::of(&Waves, Solid::Inside { offset: 0.0 });
    let report = |what: &str, triangles: usize, seconds: f64| {
        println!(
            "{what}: {} {} elements, resolution {resolution}: {triangles} triangles in {seconds:.3} s = {:.2} M triangles/s",
            scaffold.element_count(),
            kind.name(),
            triangles as f64 / seconds / 1e6
        )
    };
    let start = Instant::now();
    let region = match tile_surface_scaffold(&scaffold, &solid, resolution) {
        Ok(r) => r,
        Err(e) => return eprintln!("tiling failed: {e}"),
    };
    report(
        "region",
        region.mesh.triangles.len(),
        start.elapsed().as_secs_f64(),
    );
    let start = Instant::now();
    match extrude(&region, 0.2) {
        Ok(mesh) => report(
            "extrude",
            mesh.triangles.len(),
            start.elapsed().as_secs_f64(),
        ),
        Err(e) => eprintln!("extrude failed: {e}"),
    }
    let start = Instant::now();
    match thickness_normal(&scaffold, &solid, resolution, 0.2) {
        Ok(shell) => report(
            "thickness_normal",
            shell.mesh.triangles.len(),
            start.elapsed().as_secs_f64(),
        ),
        Err(e) => eprintln!("thickness_normal failed: {e}"),
    }
}
