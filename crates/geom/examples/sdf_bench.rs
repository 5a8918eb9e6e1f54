//! Release benchmark of SDF programs: `cargo run --release -p latticebuild-geom --example
//! sdf_bench [-- CASE N]`.
//!
//! Without arguments, runs every case in its own process (so each peak RSS is its own) and
//! prints a table: the Figure 6 command of the Cesogen paper at 130³, 260³ and 520³, with and
//! without tile pruning, and `tpms.gyroid` at 800³ through the SDF path and through the
//! foundation's dense path (the compiled expression's separable sampler straight into the
//! contourer, as `latticebuild build` does). Times are wall clock for compiling the program,
//! sampling and contouring (no file writing); "sample" is sampling every plane alone.

use std::time::Instant;

use latticebuild_geom::contour::contour;
use latticebuild_geom::expr::compile;
use latticebuild_geom::field::{Grid, PlaneSampler, ScalarField};
use latticebuild_geom::stack_lang::{self, Aabb, NoExternalSolids, Program};
use latticebuild_geom::tpms;
use rayon::prelude::*;

const FIGURE_6: &str = "ball scale 5 tpms.p scale 4 tpms.d scale 3.75 tpms.gyroid scale 1.25 \
                        intersection intersection intersection";

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [case, n] = args.as_slice() {
        let n: usize = n.parse().expect("N");
        run_case(case, n);
        return;
    }
    let cases: &[(&str, usize)] = &[
        ("figure6", 130),
        ("figure6-dense", 130),
        ("figure6", 260),
        ("figure6-dense", 260),
        ("figure6", 520),
        ("figure6-dense", 520),
        ("gyroid-sdf", 800),
        ("gyroid-dense", 800),
    ];
    println!(
        "{:<15} {:>5} {:>9} {:>9} {:>10} {:>11}",
        "case", "N", "total s", "sample s", "peak MiB", "triangles"
    );
    let exe = std::env::current_exe().expect("own path");
    for &(case, n) in cases {
        let out = std::process::Command::new(&exe)
            .args([case, &n.to_string()])
            .output()
            .expect("run case");
        print!("{}", String::from_utf8_lossy(&out.stdout));
        if !out.status.success() {
            println!(
                "{case} {n}: failed: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
}

fn run_case(case: &str, n: usize) {
    let started = Instant::now();
    let counts = [n; 3];
    let (triangles, sample_seconds) = match case {
        "figure6" | "figure6-dense" => {
            let mut field = Program::parse_str(FIGURE_6)
                .expect("parses")
                .field(&NoExternalSolids)
                .expect("compiles");
            field.set_pruning(case == "figure6");
            let domain = Aabb::cube(4.0);
            let mesh = stack_lang::mesh(&field, &domain, counts).expect("contour");
            let t = mesh.triangles.len();
            drop(mesh);
            (
                t,
                sample_all(&field, &Grid::spanning(domain.min, domain.max, counts)),
            )
        }
        "gyroid-sdf" => {
            let field = Program::parse_str("tpms.gyroid")
                .expect("parses")
                .field(&NoExternalSolids)
                .expect("compiles");
            let domain = field.domain();
            let mesh = stack_lang::mesh(&field, &domain, counts).expect("contour");
            let t = mesh.triangles.len();
            drop(mesh);
            (
                t,
                sample_all(&field, &Grid::spanning(domain.min, domain.max, counts)),
            )
        }
        "gyroid-dense" => {
            let surface = tpms::lookup("gyroid").expect("library");
            let field = compile(surface.formula).expect("parses");
            let grid = Grid::spanning([-1.0; 3], [1.0; 3], counts);
            let sampler = field.sampler(&grid);
            let mesh = contour(sampler.as_ref(), &grid, &|_| {}).expect("contour");
            let t = mesh.triangles.len();
            drop(mesh);
            (t, sample_all(&field, &grid))
        }
        _ => panic!("unknown case {case}"),
    };
    // The sampling-only pass ran after the contour; report the contour's own time.
    let total = started.elapsed().as_secs_f64() - sample_seconds;
    println!(
        "{case:<15} {n:>5} {total:>9.3} {sample_seconds:>9.3} {:>10.0} {triangles:>11}",
        peak_mib()
    );
}

/// Seconds to sample every plane (in parallel, as the contourer does), values discarded.
fn sample_all(field: &dyn ScalarField, grid: &Grid) -> f64 {
    let t = Instant::now();
    let sampler: Box<dyn PlaneSampler + '_> = field.sampler(grid);
    let len = grid.plane_len();
    let checksum: f64 = (0..grid.counts[2])
        .into_par_iter()
        .map_init(
            || vec![0.0; len],
            |plane, k| {
                sampler.sample_plane(k, plane);
                plane[len / 2]
            },
        )
        .sum();
    std::hint::black_box(checksum);
    t.elapsed().as_secs_f64()
}

/// Peak resident set size of this process, from /proc (Linux).
fn peak_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}
