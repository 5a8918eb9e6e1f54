//! Tiling throughput: Schwarz P tiled at a given resolution into a scaffold file, or into a
//! structured grid split into about N tetrahedra; prints triangles per second.
//!
//! `cargo run --release -p latticebuild-geom --example tile_bench -- 100000 12`
//! `cargo run --release -p latticebuild-geom --example tile_bench -- bracket.msh 12`
//!
//! With `stream` as a third argument the mesh is streamed in chunks of about 4M triangles
//! (`tile::stream_scaffold`) and dropped chunk by chunk: peak memory is then what tiling holds,
//! not the mesh.

use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::mesh::SpareArrays;
use latticebuild_geom::scaffold::{ElementKind, Scaffold, grid, read_scaffold};
use latticebuild_geom::tile::{TiledSolid, chunk_elements_for, stream_scaffold, tile_scaffold};
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

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(path) = args.get(1).filter(|a| a.parse::<usize>().is_err()) {
        let resolution: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(12);
        return tile_file(path, resolution);
    }
    let elements: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(100_000);
    let resolution: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(12);
    let d = ((elements as f64 / 6.0).cbrt().round() as usize).max(1);
    let scaffold = match grid([0.0; 3], [d as f64; 3], [d; 3], ElementKind::Tet4) {
        Ok(s) => s,
        Err(e) => return eprintln!("{e}"),
    };
    report(&format!("grid {d}³ × 6"), &scaffold, resolution, 0.0);
}

fn tile_file(path: &str, resolution: usize) {
    let read = Instant::now();
    let scaffold = match std::fs::read(path)
        .map_err(|e| e.to_string())
        .and_then(|bytes| read_scaffold(&bytes, path, None).map_err(|e| e.to_string()))
    {
        Ok(s) => s,
        Err(e) => return eprintln!("{e}"),
    };
    report(path, &scaffold, resolution, read.elapsed().as_secs_f64());
}

fn report(what: &str, scaffold: &Scaffold, resolution: usize, read: f64) {
    let solid = TiledSolid::of(&SchwarzP, Solid::Inside { offset: 0.0 });
    let start = Instant::now();
    if std::env::args().nth(3).as_deref() == Some("stream") {
        let per_chunk = chunk_elements_for(
            resolution,
            std::env::var("CHUNK_TRIANGLES")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(4_000_000),
        );
        let (mut triangles, mut vertices, mut chunks, mut open) = (0usize, 0usize, 0usize, 0usize);
        let spare = SpareArrays::default();
        let result = stream_scaffold(
            scaffold,
            &solid,
            None,
            resolution,
            per_chunk,
            &spare,
            &mut |c| {
                triangles += c.triangles.len();
                vertices += c.vertices.len();
                chunks += 1;
                open = open.max(c.open.len());
                Ok(())
            },
        );
        let seconds = start.elapsed().as_secs_f64();
        match result {
            Ok(stats) => println!(
                "{what}: {} {} elements (read in {read:.2} s), resolution {resolution}, streamed in {chunks} chunks of {per_chunk} elements (at most {open} vertices open): {triangles} triangles, {vertices} vertices in {seconds:.3} s = {:.2} M triangles/s",
                stats.elements,
                scaffold.kind.name(),
                triangles as f64 / seconds / 1e6
            ),
            Err(e) => eprintln!("tiling failed: {e}"),
        }
        return;
    }
    match tile_scaffold(scaffold, &solid, resolution) {
        Ok((mesh, stats)) => {
            let seconds = start.elapsed().as_secs_f64();
            println!(
                "{what}: {} {} elements (read in {read:.2} s), resolution {resolution}: {} triangles, {} vertices in {seconds:.3} s = {:.2} M triangles/s",
                stats.elements,
                scaffold.kind.name(),
                mesh.triangles.len(),
                mesh.vertices.len(),
                mesh.triangles.len() as f64 / seconds / 1e6
            );
        }
        Err(e) => eprintln!("tiling failed: {e}"),
    }
}
