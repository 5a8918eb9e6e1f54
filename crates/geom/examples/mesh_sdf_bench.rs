//! Mesh SDF benchmark: a finely tessellated torus (1,000,000 triangles by default), the time to
//! prepare it and build the hierarchy, then a 128³ grid of signed distances, of containment
//! and of band-limited distances, the contoured zero set, the winding-number error against
//! the exact sum, and the binary STL reader on the same mesh.
//!
//! `cargo run --release -p latticebuild-geom --example mesh_sdf_bench -- [triangles] [n]`, or
//! `cargo xtask bench-mesh`. Targets (issue 4, 2 cores): build ≤ 1 s, 128³ distances ≤ 3 s.

use latticebuild_geom::contour::contour;
use latticebuild_geom::field::{Grid, PlaneSampler, ScalarField};
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::{Encoding, Format, write_mesh};
use latticebuild_geom::mesh_read::{self, TriangleSoup};
use latticebuild_geom::mesh_sdf::{MeshSdf, Mode, SdfOptions};
use latticebuild_geom::synthetic::{Rng, torus, torus_sd};
use latticebuild_geom::validate;
use rayon::prelude::*;
use std::time::Instant;

const BIG_R: f64 = 1.0;
const SMALL_R: f64 = 0.4;

/// Best wall time of `runs` runs of `f`, and its last result.
fn best_of<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..runs {
        let start = Instant::now();
        let value = f();
        best = best.min(start.elapsed().as_secs_f64());
        last = Some(value);
    }
    (best, last.expect("at least one run"))
}

/// CPU seconds used by this process so far (user + system), from `/proc/self/stat`; 0 where
/// that is not available. Less disturbed than wall time when other jobs share the machine.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are the 12th and 13th.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let ticks: f64 = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse::<f64>().ok())
        .sum();
    ticks / 100.0
}

/// Samples every plane of `grid` in parallel; returns the values.
fn sample_all(sampler: &dyn PlaneSampler, grid: &Grid) -> Vec<f64> {
    let mut values = vec![0.0; grid.plane_len() * grid.counts[2]];
    values
        .par_chunks_mut(grid.plane_len())
        .enumerate()
        .for_each(|(k, plane)| sampler.sample_plane(k, plane));
    values
}

fn main() {
    let mut args = std::env::args().skip(1);
    let triangles: u32 = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(128);
    // n·m·2 triangles with segments about square: m ≈ n·r/R.
    let around = ((f64::from(triangles) / 2.0 * BIG_R / SMALL_R).sqrt()).round() as u32;
    let tube = (f64::from(triangles) / 2.0 / f64::from(around)).round() as u32;
    let soup = torus(around, tube, BIG_R, SMALL_R);
    println!(
        "torus R={BIG_R} r={SMALL_R}: {} triangles, {} vertices; {} rayon threads",
        soup.triangles.len(),
        soup.positions.len(),
        rayon::current_num_threads()
    );

    let (t_build, sdf) = best_of(3, || {
        MeshSdf::new(&soup, SdfOptions::default()).expect("mesh")
    });
    let t = sdf.timings();
    println!(
        "build: {t_build:.3} s = prepare (weld, dedup, orient, closedness) {:.3} s + BVH {:.3} s \
         + moments {:.3} s; closed={} flipped={}",
        t.prepare.as_secs_f64(),
        t.bvh.as_secs_f64(),
        t.moments.as_secs_f64(),
        sdf.report().closed,
        sdf.report().flipped
    );
    let (t_plain, _) = best_of(3, || {
        MeshSdf::new(
            &soup,
            SdfOptions {
                repair: false,
                ..SdfOptions::default()
            },
        )
        .expect("mesh")
    });
    println!("build without repair (weld for closedness, BVH, moments): {t_plain:.3} s");

    let pad = 0.1;
    let (lo, hi) = sdf.bounds();
    let grid = Grid::spanning(lo.map(|c| c - pad), hi.map(|c| c + pad), [n, n, n]);
    let cpu = cpu_seconds();
    let (t_sdf, values) = best_of(2, || sample_all(sdf.sampler(&grid).as_ref(), &grid));
    let cpu_sdf = (cpu_seconds() - cpu) / 2.0;
    // Spot-check against the analytic torus: the mesh is within its chord error of it.
    let worst = values
        .iter()
        .enumerate()
        .step_by(997)
        .map(|(i, &v)| {
            let p = [
                grid.coord(0, i % n),
                grid.coord(1, (i / n) % n),
                grid.coord(2, i / (n * n)),
            ];
            (v - torus_sd(p, BIG_R, SMALL_R)).abs()
        })
        .fold(0.0, f64::max);
    println!(
        "{n}^3 signed distances: {t_sdf:.3} s wall, {cpu_sdf:.3} s CPU ({:.0} ns CPU per \
         sample), max |mesh − analytic| on a subset {worst:.1e}",
        cpu_sdf * 1e9 / values.len() as f64
    );

    let containment = MeshSdf::new(
        &soup,
        SdfOptions {
            mode: Mode::Containment,
            ..SdfOptions::default()
        },
    )
    .expect("mesh");
    let cpu = cpu_seconds();
    let (t_in, inside) = best_of(2, || sample_all(containment.sampler(&grid).as_ref(), &grid));
    let cpu_in = (cpu_seconds() - cpu) / 2.0;
    let disagree = inside
        .iter()
        .zip(&values)
        .filter(|(c, d)| **d != 0.0 && (**c < 0.0) != (**d < 0.0))
        .count();
    println!(
        "{n}^3 containment: {t_in:.3} s wall, {cpu_in:.3} s CPU, {disagree} samples disagree \
         with the distance sign"
    );

    let band = 2.0 * grid.spacing[0];
    let banded = MeshSdf::new(
        &soup,
        SdfOptions {
            band: Some(band),
            ..SdfOptions::default()
        },
    )
    .expect("mesh");
    let cpu = cpu_seconds();
    let (t_band, _) = best_of(2, || sample_all(banded.sampler(&grid).as_ref(), &grid));
    let cpu_band = (cpu_seconds() - cpu) / 2.0;
    println!(
        "{n}^3 signed distances clamped to ±{band:.4} (two cells): {t_band:.3} s wall, \
         {cpu_band:.3} s CPU"
    );

    let sampler = sdf.sampler(&grid);
    let (t_contour, mesh) = best_of(1, || {
        contour(sampler.as_ref(), &grid, &|_| {}).expect("contour")
    });
    let check = validate::check(&mesh);
    println!(
        "contour of the {n}^3 distances: {t_contour:.3} s, {} triangles, watertight={} \
         manifold={}, volume {:.5} (torus 2π²Rr² = {:.5})",
        mesh.triangles.len(),
        check.watertight,
        check.manifold,
        check.volume,
        2.0 * std::f64::consts::PI.powi(2) * BIG_R * SMALL_R * SMALL_R
    );

    let mut rng = Rng::new(7);
    let mut far = (0.0f64, 0.0f64);
    let mut near = (0.0f64, 0.0f64);
    let count = 40;
    for k in 0..2 * count {
        let p = if k < count {
            rng.point(-1.5, 1.5)
        } else {
            // Within 1e-3 of the surface.
            let t = soup.triangles[rng.below(soup.triangles.len())];
            let c = t.map(|i| soup.positions[i as usize]);
            std::array::from_fn(|a| (c[0][a] + c[1][a] + c[2][a]) / 3.0 + rng.range(-1e-3, 1e-3))
        };
        let e = (sdf.winding_number(p) - sdf.winding_number_exact(p)).abs();
        let slot = if k < count { &mut far } else { &mut near };
        slot.0 = slot.0.max(e);
        slot.1 += e / count as f64;
    }
    let start = Instant::now();
    let mut rng = Rng::new(8);
    let queries = 100_000;
    let w_sum: f64 = (0..queries)
        .map(|_| rng.point(-1.5, 1.5))
        .collect::<Vec<_>>()
        .par_iter()
        .map(|&p| sdf.winding_number(p))
        .sum();
    let t_w = start.elapsed().as_secs_f64();
    println!(
        "winding number, fast (β=2) vs exact: random points max {:.1e} mean {:.1e}; within \
         1e-3 of the surface max {:.1e} mean {:.1e}; {:.2} µs per point query ({w_sum:.0})",
        far.0,
        far.1,
        near.0,
        near.1,
        t_w * 1e6 * rayon::current_num_threads() as f64 / queries as f64
    );

    let mesh32 = Mesh {
        vertices: soup.positions.iter().map(|p| p.map(|c| c as f32)).collect(),
        triangles: soup.triangles.clone(),
    };
    let mut stl = Vec::new();
    write_mesh(&mesh32, Format::Stl, Encoding::Binary, &mut stl).expect("in memory");
    let (t_read, read) = best_of(3, || {
        mesh_read::read(&stl, mesh_read::Format::Stl).expect("own STL")
    });
    let (t_soup, from_stl) = best_of(1, || {
        MeshSdf::new(&read, SdfOptions::default()).expect("mesh")
    });
    let _: &TriangleSoup = &read;
    println!(
        "binary STL ({:.0} MB): read {t_read:.3} s; build from the unwelded soup ({} positions) \
         {t_soup:.3} s, welded to {} vertices, closed={}",
        stl.len() as f64 / 1e6,
        read.positions.len(),
        from_stl.report().vertices,
        from_stl.report().closed
    );
}
