//! Times contouring of the benchmark gyroid with a hand-written separable sampler, so the
//! contourer's own cost can be seen apart from field evaluation: `cargo run --release
//! -p latticebuild-geom --example contour_speed -- 800`.
use std::f64::consts::TAU;
use std::time::Instant;

use latticebuild_geom::contour::contour;
use latticebuild_geom::field::{Grid, PlaneSampler};

struct Gyroid {
    grid: Grid,
    cos: [Vec<f64>; 3],
    sin: [Vec<f64>; 3],
}

impl PlaneSampler for Gyroid {
    fn grid(&self) -> &Grid {
        &self.grid
    }
    fn sample_rows(&self, k: usize, rows: std::ops::Range<usize>, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        let (cz, sz) = (self.cos[2][k], self.sin[2][k]);
        for (j, row) in rows.zip(out.chunks_mut(nx)) {
            let (cy, sy) = (self.cos[1][j], self.sin[1][j]);
            for ((v, &cx), &sx) in row.iter_mut().zip(&self.cos[0]).zip(&self.sin[0]) {
                *v = cx * sy + cy * sz + cz * sx;
            }
        }
    }
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(200);
    let grid = Grid::spanning([-1.0; 3], [1.0; 3], [n; 3]);
    let table = |f: fn(f64) -> f64| {
        std::array::from_fn(|a| grid.axis(a).iter().map(|&x| f(TAU * x)).collect())
    };
    let sampler = Gyroid {
        grid,
        cos: table(f64::cos),
        sin: table(f64::sin),
    };
    let t = Instant::now();
    let mut plane = vec![0.0; n * n];
    for k in 0..n {
        sampler.sample_plane(k, &mut plane);
    }
    let sample_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mesh = contour(&sampler, &grid, &|_| {}).expect("contour");
    println!(
        "n={n} sampling-only={sample_s:.3}s contour={:.3}s triangles={} vertices={}",
        t.elapsed().as_secs_f64(),
        mesh.triangles.len(),
        mesh.vertices.len()
    );
}
