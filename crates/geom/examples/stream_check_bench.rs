//! `StreamCheck` against `check`: time and (with `/usr/bin/time -v`) peak memory.
//!
//! - `torus-whole N M`: a closed N×M-quad torus (2NM triangles) made whole, then `check`.
//! - `torus-stream N M ROWS`: the same torus produced lazily, ROWS quad rows (2·ROWS·M
//!   triangles) a chunk, each chunk checked and dropped before the next is made; the whole
//!   mesh never exists, so the process's peak is the streaming part's.
//! - `torus-both N M ROWS`: both on one mesh, results compared field by field.
//! - `tile ELEMENTS RESOLUTION TRIANGLES`: Schwarz P tiled into a grid of about ELEMENTS
//!   tetrahedra; `check` of the mesh, then `StreamCheck` over `MeshChunk::split` chunks, then
//!   the binary STL writer into a sink.
//!
//! `cargo run --release -p latticebuild-geom --example stream_check_bench -- torus-stream 4096 4096 512`

use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::mesh::{Mesh, MeshChunk};
use latticebuild_geom::mesh_io::{Encoding, Format, write_mesh};
use latticebuild_geom::scaffold::{ElementKind, grid};
use latticebuild_geom::tile::{TiledSolid, tile_scaffold};
use latticebuild_geom::validate::{MeshCheck, StreamCheck, check};
use rayon::prelude::*;
use std::f64::consts::TAU;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize, default: usize| {
        args.get(i)
            .and_then(|a| a.parse::<usize>().ok())
            .unwrap_or(default)
    };
    println!("{} rayon threads", rayon::current_num_threads());
    match args.first().map(String::as_str) {
        Some("torus-whole") => {
            let torus = Torus::new(number(1, 4096), number(2, 4096), 1);
            let mesh = torus.whole();
            time_check(&mesh);
        }
        Some("torus-stream") => {
            let torus = Torus::new(number(1, 4096), number(2, 4096), number(3, 512));
            time_stream(torus.chunks(), torus.triangles());
        }
        Some("torus-both") => {
            let torus = Torus::new(number(1, 4096), number(2, 4096), number(3, 512));
            let whole = time_check(&torus.whole());
            let streamed = time_stream(torus.chunks(), torus.triangles());
            compare(&whole, &streamed);
        }
        Some("tile") => tile(number(1, 100_000), number(2, 12), number(3, 4_000_000)),
        _ => eprintln!(
            "usage: stream_check_bench torus-whole N M | torus-stream N M ROWS | torus-both N M ROWS | tile ELEMENTS RESOLUTION TRIANGLES"
        ),
    }
}

fn time_check(mesh: &Mesh) -> MeshCheck {
    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..3 {
        let start = Instant::now();
        let c = check(mesh);
        best = best.min(start.elapsed().as_secs_f64());
        result = Some(c);
    }
    let Some(result) = result else {
        unreachable!("three runs")
    };
    println!(
        "check: {} triangles, {} vertices: best of 3 {best:.3} s = {:.1} M triangles/s; watertight {}, manifold {}, χ {}",
        mesh.triangles.len(),
        mesh.vertices.len(),
        mesh.triangles.len() as f64 / best / 1e6,
        result.watertight,
        result.manifold,
        result.euler_characteristic
    );
    result
}

/// Streams the chunks as they come; only the checker's time is counted.
fn time_stream(chunks: impl Iterator<Item = MeshChunk>, triangles: usize) -> MeshCheck {
    let mut checker = StreamCheck::new();
    let mut checking = 0.0;
    let mut making = Instant::now();
    let mut producing = 0.0;
    let (mut count, mut held) = (0, 0);
    for chunk in chunks {
        producing += making.elapsed().as_secs_f64();
        let start = Instant::now();
        checker.push(&chunk);
        checking += start.elapsed().as_secs_f64();
        count += 1;
        held = held.max(checker.held_corners());
        drop(chunk);
        making = Instant::now();
    }
    let start = Instant::now();
    let result = checker.finish();
    checking += start.elapsed().as_secs_f64();
    println!(
        "StreamCheck: {triangles} triangles in {count} chunks: {checking:.3} s = {:.1} M triangles/s (producing the chunks: {producing:.3} s); at most {held} corners held between chunks; watertight {}, manifold {}, χ {}",
        triangles as f64 / checking / 1e6,
        result.watertight,
        result.manifold,
        result.euler_characteristic
    );
    result
}

fn compare(whole: &MeshCheck, streamed: &MeshCheck) {
    if whole == streamed
        && whole.volume.to_bits() == streamed.volume.to_bits()
        && whole.area.to_bits() == streamed.area.to_bits()
    {
        println!("results identical (volume and area bit for bit)");
    } else {
        println!("RESULTS DIFFER:\n  check  {whole:?}\n  stream {streamed:?}");
    }
}

/// A closed torus of `n × m` quads, vertex `(i, j)` numbered `i·m + j`, made a band of `rows`
/// quad rows at a time.
struct Torus {
    n: usize,
    m: usize,
    rows: usize,
}

impl Torus {
    fn new(n: usize, m: usize, rows: usize) -> Torus {
        Torus {
            n: n.max(3),
            m: m.max(3),
            rows: rows.max(1),
        }
    }

    fn triangles(&self) -> usize {
        2 * self.n * self.m
    }

    fn position(&self, id: usize) -> [f32; 3] {
        let (i, j) = (id / self.m, id % self.m);
        let theta = TAU * i as f64 / self.n as f64;
        let phi = TAU * j as f64 / self.m as f64;
        let rho = 30.0 + 10.0 * phi.cos();
        [rho * theta.cos(), rho * theta.sin(), 10.0 * phi.sin()].map(|x| x as f32)
    }

    fn id(&self, i: usize, j: usize) -> u32 {
        ((i % self.n) * self.m + j % self.m) as u32
    }

    /// The triangles of quad rows `rows`, in order.
    fn quads(&self, rows: std::ops::Range<usize>) -> Vec<[u32; 3]> {
        rows.into_par_iter()
            .flat_map_iter(|i| {
                (0..self.m).flat_map(move |j| {
                    let (a, b) = (self.id(i, j), self.id(i + 1, j));
                    let (c, d) = (self.id(i + 1, j + 1), self.id(i, j + 1));
                    [[a, b, c], [a, c, d]]
                })
            })
            .collect()
    }

    fn positions(&self, ids: std::ops::Range<usize>) -> Vec<[f32; 3]> {
        ids.into_par_iter().map(|id| self.position(id)).collect()
    }

    fn whole(&self) -> Mesh {
        Mesh {
            vertices: self.positions(0..self.n * self.m),
            triangles: self.quads(0..self.n),
        }
    }

    /// Chunk `k` has quad rows `k·rows ..` and owns the vertex rows its quads reach first:
    /// rows `0..=rows` for the first, then `(k·rows, (k + 1)·rows]`. Row 0 stays open to the
    /// last chunk, whose last quad row closes the torus onto it.
    fn chunks(&self) -> impl Iterator<Item = MeshChunk> + '_ {
        let (n, m, b) = (self.n, self.m, self.rows);
        let count = n.div_ceil(b);
        (0..count).map(move |k| {
            let last = k + 1 == count;
            let first_row = if k == 0 { 0 } else { k * b + 1 };
            let end_row = if last { n } else { ((k + 1) * b + 1).min(n) };
            let row_ids = |row: usize| row * m..(row + 1) * m;
            let mut borrowed = Vec::new();
            if k > 0 && last {
                borrowed.extend(row_ids(0));
            }
            if k > 0 {
                borrowed.extend(row_ids(k * b));
            }
            let mut open = Vec::new();
            if !last {
                open.extend(row_ids(0));
                open.extend(row_ids((k + 1) * b));
            }
            MeshChunk {
                first_vertex: (first_row * m) as u32,
                vertices: self.positions(first_row * m..end_row * m),
                triangles: self.quads(k * b..((k + 1) * b).min(n)),
                borrowed: borrowed
                    .into_iter()
                    .map(|id| (id as u32, self.position(id)))
                    .collect(),
                open: open.into_iter().map(|id| id as u32).collect(),
            }
        })
    }
}

struct SchwarzP;

impl ScalarField for SchwarzP {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = (TAU * xs[i]).cos() + (TAU * ys[i]).cos() + (TAU * zs[i]).cos() - 0.3;
        }
    }
}

fn tile(elements: usize, resolution: usize, per_chunk: usize) {
    let d = ((elements as f64 / 6.0).cbrt().round() as usize).max(1);
    let scaffold = match grid([0.0; 3], [d as f64; 3], [d; 3], ElementKind::Tet4) {
        Ok(s) => s,
        Err(e) => return eprintln!("{e}"),
    };
    let solid = TiledSolid::of(&SchwarzP, Solid::Inside { offset: 0.0 });
    let start = Instant::now();
    let mesh = match tile_scaffold(&scaffold, &solid, resolution) {
        Ok((mesh, _)) => mesh,
        Err(e) => return eprintln!("tiling failed: {e}"),
    };
    println!(
        "tiled {d}³ × 6 tetrahedra at resolution {resolution} in {:.2} s",
        start.elapsed().as_secs_f64()
    );
    let whole = time_check(&mesh);
    let start = Instant::now();
    let chunks = MeshChunk::split(&mesh, per_chunk);
    println!(
        "split into {} chunks in {:.2} s",
        chunks.len(),
        start.elapsed().as_secs_f64()
    );
    let triangles = mesh.triangles.len();
    let streamed = time_stream(chunks.into_iter(), triangles);
    compare(&whole, &streamed);
    time_stl(&mesh);
}

/// The binary STL writer on the same mesh, into a sink: what the output side of a tiled
/// build costs per triangle besides the check.
fn time_stl(mesh: &Mesh) {
    let mut best = f64::INFINITY;
    for _ in 0..15 {
        let start = Instant::now();
        if let Err(e) = write_mesh(mesh, Format::Stl, Encoding::Binary, &mut std::io::sink()) {
            return eprintln!("writing STL failed: {e}");
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    println!(
        "binary STL: best of 15 {best:.3} s = {:.1} M triangles/s",
        mesh.triangles.len() as f64 / best / 1e6
    );
}
