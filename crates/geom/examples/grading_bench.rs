//! Graded tiling throughput: Schwarz P blending into a ball, as a shell of graded thickness,
//! tiled into a structured grid of about N elements of one kind (quadratic kinds get straight
//! mid-edge, face and centre nodes), against the uniform solid on the same scaffold; prints
//! the best of `runs` timings of each.
//!
//! `cargo run --release -p latticebuild-geom --example grading_bench -- hex27 20000 10 3`

use latticebuild_geom::field::{ScalarField, Solid};
use latticebuild_geom::scaffold::{ElementKind, Scaffold, grid};
use latticebuild_geom::tile::{TiledSolid, Transition, tile_scaffold};
use std::collections::HashMap;
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

struct Ball;

impl ScalarField for Ball {
    fn eval_points(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            out[i] = xs[i] * xs[i] + ys[i] * ys[i] + zs[i] * zs[i] - 0.09;
        }
    }
}

/// Corners each node of `kind` is the midpoint of (as in `scaffold::element`'s order).
fn support(kind: ElementKind, i: usize) -> Vec<usize> {
    let corners = kind.corner_count();
    if i < corners {
        return vec![i];
    }
    if kind.is_simplex() {
        return kind.edges()[i - corners].to_vec();
    }
    let s = |j: usize| kind.reference_node(j).map(|x| (2.0 * x).round() as i8);
    (0..corners)
        .filter(|&c| (0..3).all(|a| s(i)[a] == 0 || s(c)[a] == s(i)[a]))
        .collect()
}

/// The linear grid made `kind`, with straight sides.
fn promote(linear: Scaffold, kind: ElementKind) -> Scaffold {
    if kind == linear.kind {
        return linear;
    }
    let mut nodes = linear.nodes.clone();
    let mut ids: HashMap<Vec<u32>, u32> = HashMap::new();
    let mut connectivity = Vec::with_capacity(linear.element_count() * kind.node_count());
    for e in 0..linear.element_count() {
        let corners = linear.element(e);
        for i in 0..kind.node_count() {
            let mut key: Vec<u32> = support(kind, i).iter().map(|&c| corners[c]).collect();
            key.sort_unstable();
            if key.len() == 1 {
                connectivity.push(key[0]);
                continue;
            }
            let id = *ids.entry(key.clone()).or_insert_with(|| {
                let mut p = [0.0; 3];
                for &c in &key {
                    for a in 0..3 {
                        p[a] += nodes[c as usize][a] / key.len() as f64;
                    }
                }
                nodes.push(p);
                nodes.len() as u32 - 1
            });
            connectivity.push(id);
        }
    }
    Scaffold {
        kind,
        node_tags: (1..=nodes.len() as u64).collect(),
        nodes,
        connectivity,
        ..linear
    }
}

/// User + system CPU seconds of this process (all threads), from /proc (0 elsewhere): wall
/// time is unreliable on a loaded machine.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name (which may hold spaces): utime and stime are 14 and 15.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = args
        .get(1)
        .and_then(|k| ElementKind::from_name(k))
        .unwrap_or(ElementKind::Hex27);
    let elements: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(20_000);
    let resolution: usize = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(10);
    let runs: usize = args.get(4).and_then(|a| a.parse().ok()).unwrap_or(3);
    let per_cell = if kind.is_simplex() { 6.0 } else { 1.0 };
    let d = ((elements as f64 / per_cell).cbrt().round() as usize).max(1);
    let linear = match grid([0.0; 3], [d as f64; 3], [d; 3], kind.linear()) {
        Ok(s) => s,
        Err(e) => return eprintln!("{e}"),
    };
    let scaffold = promote(linear, kind);
    let size = d as f64;
    let field = |p: &[f64; 3]| {
        let [x, y, z] = p.map(|c| c / size);
        x * x + y * z
    };
    // In [0, 1] at the nodes (x² + yz ∈ [0, 2]).
    let weight: Vec<f64> = scaffold.nodes.iter().map(|p| 0.5 * field(p)).collect();
    let thickness: Vec<f64> = scaffold
        .nodes
        .iter()
        .map(|p| 0.2 + 0.3 * field(p))
        .collect();
    let uniform = TiledSolid::of(&SchwarzP, Solid::Inside { offset: 0.0 });
    let graded = TiledSolid {
        transition: Some(Transition {
            to: &Ball,
            weight: &weight,
        }),
        thickness: Some(&thickness),
        ..TiledSolid::of(
            &SchwarzP,
            Solid::EccentricShell {
                offset: 0.1,
                thickness: 0.0,
            },
        )
    };
    for (what, solid) in [("uniform", &uniform), ("graded", &graded)] {
        let (mut best, mut best_cpu) = (f64::INFINITY, f64::INFINITY);
        let mut triangles = 0;
        for _ in 0..runs {
            let (start, cpu) = (Instant::now(), cpu_seconds());
            match tile_scaffold(&scaffold, solid, resolution) {
                Ok((mesh, _)) => triangles = mesh.triangles.len(),
                Err(e) => return eprintln!("tiling failed: {e}"),
            }
            best = best.min(start.elapsed().as_secs_f64());
            best_cpu = best_cpu.min(cpu_seconds() - cpu);
        }
        println!(
            "{} {} elements ({d}³ cells), resolution {resolution}, {what}: {triangles} triangles in {best:.3} s = {:.2} M triangles/s; CPU {best_cpu:.2} s = {:.1} µs/element",
            scaffold.element_count(),
            kind.name(),
            triangles as f64 / best / 1e6,
            best_cpu / scaffold.element_count() as f64 * 1e6
        );
    }
}
