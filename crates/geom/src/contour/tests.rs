//! Contouring tests: closedness and orientation on random fields (which exercise every case,
//! chunk seam and cap), and volumes against analytic values.

use std::collections::HashMap;

use super::*;
use crate::field::{Band, Grid, PlaneSampler};

/// Samples a precomputed array, or a closure of the model position.
pub(super) struct FnSampler<F: Fn([f64; 3]) -> f64 + Sync> {
    pub(super) grid: Grid,
    pub(super) f: F,
}

impl<F: Fn([f64; 3]) -> f64 + Sync> PlaneSampler for FnSampler<F> {
    fn grid(&self) -> &Grid {
        &self.grid
    }
    fn sample_rows(&self, k: usize, rows: std::ops::Range<usize>, out: &mut [f64]) {
        let nx = self.grid.counts[0];
        for (j, row) in rows.zip(out.chunks_mut(nx)) {
            for (i, v) in row.iter_mut().enumerate() {
                *v = (self.f)([
                    self.grid.coord(0, i),
                    self.grid.coord(1, j),
                    self.grid.coord(2, k),
                ]);
            }
        }
    }
}

pub(super) fn run(grid: Grid, f: impl Fn([f64; 3]) -> f64 + Sync) -> Mesh {
    contour(&FnSampler { grid, f }, &grid, &|_| {}).expect("contour")
}

/// Independent closedness check: every directed edge appears once and its reverse once, and
/// the triangles around every vertex form one cycle. Returns the Euler characteristic.
pub(super) fn assert_closed_manifold(mesh: &Mesh) -> i64 {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "degenerate {t:?}"
        );
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "edge {a}->{b} used {n} times");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge {a}->{b} is on the boundary"
        );
    }
    // Vertex links: the edges opposite each vertex must chain into a single cycle.
    let mut link: HashMap<u32, HashMap<u32, u32>> = HashMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            link.entry(t[k])
                .or_default()
                .insert(t[(k + 1) % 3], t[(k + 2) % 3]);
        }
    }
    for (v, next) in &link {
        let start = *next.keys().next().expect("vertex with a fan");
        let (mut at, mut steps) = (start, 0);
        loop {
            at = next[&at];
            steps += 1;
            if at == start {
                break;
            }
        }
        assert_eq!(steps, next.len(), "vertex {v} has a pinched fan");
    }
    let mut positions: Vec<[u32; 3]> = mesh.vertices.iter().map(|p| p.map(f32::to_bits)).collect();
    positions.sort_unstable();
    positions.dedup();
    assert_eq!(
        positions.len(),
        mesh.vertices.len(),
        "two vertices share a position"
    );
    assert_eq!(link.len(), mesh.vertices.len(), "unreferenced vertices");
    let edges = directed.len() as i64 / 2;
    mesh.vertices.len() as i64 - edges + mesh.triangles.len() as i64
}

pub(super) fn volume(mesh: &Mesh) -> f64 {
    let p = |i: u32| mesh.vertices[i as usize].map(f64::from);
    mesh.triangles
        .iter()
        .map(|t| {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            (a[0] * (b[1] * c[2] - b[2] * c[1])
                + a[1] * (b[2] * c[0] - b[0] * c[2])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// A cheap, reproducible hash of a lattice point to [-1, 1).
pub(super) fn noise(i: i64, j: i64, k: i64, seed: u64) -> f64 {
    let mut h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (k as u64).wrapping_mul(0x1656_67B1_9E37_79F9)
        ^ seed;
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    (h >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

#[test]
fn random_fields_give_closed_manifold_surfaces() {
    // Sizes chosen to cover several chunks, words of 64 columns and their edges.
    for (seed, counts) in [
        (1, [5, 4, 3]),
        (2, [9, 7, 40]),
        (3, [66, 5, 9]),
        (4, [2, 2, 2]),
        (5, [130, 3, 70]),
    ] {
        let grid = Grid::spanning([0.0; 3], [1.0, 2.0, 3.0], counts);
        let h = grid.spacing;
        let mesh = run(grid, |p| {
            let idx = |a: usize| (p[a] / h[a]).round() as i64;
            noise(idx(0), idx(1), idx(2), seed)
        });
        assert!(!mesh.is_empty());
        assert_closed_manifold(&mesh);
        assert!(
            volume(&mesh) > 0.0,
            "seed {seed}: outward orientation gives positive volume"
        );
    }
}

#[test]
fn exact_zeros_do_not_create_coincident_vertices() {
    // A field that is exactly zero on whole grid planes.
    let grid = Grid::spanning([-1.0; 3], [1.0; 3], [9, 9, 9]);
    let mesh = run(grid, |p| (p[0] * 4.0).round() * (p[1] * 4.0).round() - 0.0);
    assert_closed_manifold(&mesh);
}

#[test]
fn half_space_volume_is_exact() {
    // Linear fields are reproduced exactly by linear interpolation (the plane stays clear of
    // the samples, so the edge margin never moves a vertex): z < 0.312 − 0.01 x.
    let grid = Grid::spanning([0.0; 3], [1.0; 3], [11, 12, 41]);
    let mesh = run(grid, |p| p[2] - 0.312 + 0.01 * p[0]);
    assert_eq!(assert_closed_manifold(&mesh), 2);
    assert!(
        (volume(&mesh) - 0.307).abs() < 1e-6,
        "volume {}",
        volume(&mesh)
    );
}

#[test]
fn ball_inside_domain_has_sphere_volume_and_genus_zero() {
    let r = 0.7;
    let grid = Grid::spanning([-1.0; 3], [1.0; 3], [81, 81, 81]);
    let mesh = run(grid, |p| {
        (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - r
    });
    assert_eq!(assert_closed_manifold(&mesh), 2);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let h: f64 = 2.0 / 80.0;
    assert!((volume(&mesh) - exact).abs() < 0.5 * h * h * 4.0 * std::f64::consts::PI * r * r);
}

#[test]
fn ball_cut_by_the_box_is_capped() {
    // The ball of radius 0.8 about a corner of the unit box: one octant of it, closed by caps.
    let r = 0.8;
    let grid = Grid::spanning([0.0; 3], [1.0; 3], [61, 61, 61]);
    let mesh = run(grid, |p| {
        (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - r
    });
    assert_eq!(assert_closed_manifold(&mesh), 2);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r / 8.0;
    assert!(
        (volume(&mesh) - exact).abs() < 2e-3,
        "volume {} vs {exact}",
        volume(&mesh)
    );
}

#[test]
fn full_domain_is_the_box() {
    let grid = Grid::spanning([0.0; 3], [2.0, 3.0, 4.0], [5, 6, 7]);
    let mesh = run(grid, |_| -1.0);
    assert_eq!(assert_closed_manifold(&mesh), 2);
    assert!((volume(&mesh) - 24.0).abs() < 1e-5);
    assert!(run(grid, |_| 1.0).is_empty());
}

#[test]
fn one_and_many_threads_give_identical_meshes() {
    let grid = Grid::spanning([-1.0; 3], [1.0; 3], [40, 33, 90]);
    let f = |p: [f64; 3]| {
        use std::f64::consts::TAU;
        (TAU * p[0]).cos() * (TAU * p[1]).sin()
            + (TAU * p[1]).cos() * (TAU * p[2]).sin()
            + (TAU * p[2]).cos() * (TAU * p[0]).sin()
    };
    let single = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let many = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .expect("pool");
    let a = single.install(|| run(grid, f));
    let b = many.install(|| run(grid, f));
    assert_eq!(a, b);
    assert_closed_manifold(&a);
}

#[test]
fn rejects_degenerate_grids() {
    let grid = Grid {
        origin: [0.0; 3],
        spacing: [1.0; 3],
        counts: [1, 5, 5],
    };
    let err = contour(&FnSampler { grid, f: |_| 0.0 }, &grid, &|_| {}).unwrap_err();
    assert_eq!(err, ContourError::TooFewSamples([1, 5, 5]));
}

fn run_band(grid: Grid, band: Band, f: impl Fn([f64; 3]) -> f64 + Sync) -> BandMesh {
    contour_band(&FnSampler { grid, f }, band, &grid, &|_| {}).expect("contour")
}

/// A TPMS of the library over one period, sampled by its compiled expression.
pub(super) fn tpms(name: &str) -> crate::expr::CompiledExpr {
    crate::expr::compile(crate::tpms::lookup(name).expect("surface").formula).expect("formula")
}

fn unit_box(n: usize) -> Grid {
    Grid::spanning([0.0; 3], [1.0; 3], [n; 3])
}

#[test]
fn random_bands_give_closed_manifold_surfaces() {
    // Noise in [-1, 1): thick bands, and bands far thinner than a sample spacing, whose two
    // levels share many edges (and must not share positions).
    for (seed, counts, band) in [
        (1, [5, 4, 3], Band { lo: -0.3, hi: 0.3 }),
        (2, [9, 7, 40], Band { lo: -0.5, hi: 0.2 }),
        (
            3,
            [66, 5, 9],
            Band {
                lo: -1e-3,
                hi: 1e-3,
            },
        ),
        (4, [2, 2, 2], Band { lo: -0.2, hi: 0.9 }),
        (
            5,
            [130, 3, 70],
            Band {
                lo: 0.1,
                hi: 0.1 + 1e-9,
            },
        ),
        (
            6,
            [17, 65, 12],
            Band {
                lo: -0.05,
                hi: 0.05,
            },
        ),
    ] {
        let grid = Grid::spanning([0.0; 3], [1.0, 2.0, 3.0], counts);
        let h = grid.spacing;
        let out = run_band(grid, band, |p| {
            let idx = |a: usize| (p[a] / h[a]).round() as i64;
            noise(idx(0), idx(1), idx(2), seed)
        });
        assert!(!out.mesh.is_empty(), "seed {seed}");
        assert_closed_manifold(&out.mesh);
        assert!(volume(&out.mesh) > 0.0, "seed {seed}: outward orientation");
    }
}

#[test]
fn band_of_a_linear_field_is_an_exact_slab() {
    // 0.3 < z + 0.01 x < 0.3 + 0.004, a slab far thinner than the spacing (1/40 in z): the
    // sampled |f − c| − w/2 loses it entirely; the band reproduces it exactly.
    let grid = Grid::spanning([0.0; 3], [1.0; 3], [11, 12, 41]);
    let f = |p: [f64; 3]| p[2] + 0.01 * p[0];
    let band = Band { lo: 0.3, hi: 0.304 };
    let out = run_band(grid, band, f);
    assert_eq!(assert_closed_manifold(&out.mesh), 2);
    assert!(
        (volume(&out.mesh) - 0.004).abs() < 1e-6,
        "volume {}",
        volume(&out.mesh)
    );
    // |∇f| per sample step: (0.01 / 10, 0, 1 / 40).
    let steepest = (1e-6f64 + 1.0 / 1600.0).sqrt();
    assert!((out.steepest - steepest).abs() < 1e-12, "{}", out.steepest);
    assert!((out.thinnest_wall(band).expect("crossed") - 0.004 / steepest).abs() < 1e-9);
}

#[test]
fn empty_and_full_bands() {
    let grid = Grid::spanning([0.0; 3], [2.0, 3.0, 4.0], [5, 6, 7]);
    let full = run_band(grid, Band { lo: -1.0, hi: 1.0 }, |_| 0.0);
    assert_eq!(assert_closed_manifold(&full.mesh), 2);
    assert!((volume(&full.mesh) - 24.0).abs() < 1e-5);
    assert_eq!(full.steepest, 0.0);
    let band = Band { lo: -1.0, hi: 1.0 };
    assert!(run_band(grid, band, |_| 2.0).mesh.is_empty());
    assert!(run_band(grid, band, |_| -2.0).mesh.is_empty());
    assert!(run_band(grid, band, |_| f64::NAN).mesh.is_empty());
    assert!(
        run_band(grid, Band { lo: 1.0, hi: 1.0 }, |_| 1.0)
            .mesh
            .is_empty()
    );
}

/// The case: an IWP shell 0.2 thick over one period. The band's volume must be, at
/// every sample count, the difference of the two level sets' volumes contoured on the same
/// grid as ordinary solids (an independent path), and converge at second order to that
/// difference on a much finer grid. The sampled `|f| − w/2` kept 0.0007 of 0.0263 at 33
/// samples and was still 31 % low at 129.
#[test]
fn thin_iwp_shell_volume_converges_at_second_order() {
    use crate::field::{ScalarField, Solid, SolidSampler};
    let iwp = tpms("iwp");
    let band = Solid::Shell { thickness: 0.2 }.band().expect("a shell");
    let level_set = |n: usize, offset: f64| {
        let grid = unit_box(n);
        let sampler = SolidSampler {
            inner: iwp.sampler(&grid),
            solid: Solid::Inside { offset },
        };
        volume(&contour(&sampler, &grid, &|_| {}).expect("contour"))
    };
    let difference = |n: usize| level_set(n, band.hi) - level_set(n, band.lo);
    let reference = difference(385);
    let mut errors = Vec::new();
    for n in [33, 65, 129] {
        let grid = unit_box(n);
        let out = contour_band(iwp.sampler(&grid).as_ref(), band, &grid, &|_| {}).expect("band");
        assert_eq!(
            assert_closed_manifold(&out.mesh),
            -12,
            "n {n}: IWP's genus 7"
        );
        let v = volume(&out.mesh);
        let same_grid = difference(n);
        assert!(
            (v - same_grid).abs() < 1e-6 * same_grid,
            "n {n}: band {v} vs level sets {same_grid}"
        );
        errors.push((v - reference).abs());
    }
    assert!(errors[2] < 2e-3 * reference, "{errors:?} of {reference}");
    for k in 0..2 {
        let order = (errors[k] / errors[k + 1]).log2();
        assert!((1.7..2.5).contains(&order), "order {order}: {errors:?}");
    }
}

#[test]
fn bands_are_identical_for_one_and_many_threads() {
    let grid = Grid::spanning([-1.0; 3], [1.0; 3], [40, 33, 90]);
    let iwp = tpms("iwp");
    let band = Band { lo: 0.3, hi: 0.45 };
    let contour_in = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| {
                let sampler = crate::field::ScalarField::sampler(&iwp, &grid);
                contour_band(sampler.as_ref(), band, &grid, &|_| {}).expect("band")
            })
    };
    let (a, b) = (contour_in(1), contour_in(4));
    assert_eq!(a, b);
    assert_eq!(a.steepest.to_bits(), b.steepest.to_bits());
    assert_closed_manifold(&a.mesh);
}

#[test]
fn steepest_at_level_matches_the_band_contourers_estimate() {
    let grid = Grid::spanning([0.0; 3], [1.0, 1.2, 0.9], [37, 29, 71]);
    let iwp = tpms("iwp");
    let sampler = crate::field::ScalarField::sampler(&iwp, &grid);
    for band in [Band { lo: -0.1, hi: 0.1 }, Band { lo: 0.5, hi: 1.5 }] {
        let out = contour_band(sampler.as_ref(), band, &grid, &|_| {}).expect("band");
        let middle = band.lo + 0.5 * (band.hi - band.lo);
        let alone = steepest_at_level(sampler.as_ref(), middle);
        assert!(out.steepest > 0.0);
        assert_eq!(alone.to_bits(), out.steepest.to_bits(), "{band:?}");
    }
}

/// Far from the origin 1/256 of an edge can be less than an `f32` step (2⁻¹⁴ at 1000): a
/// crossing rounded onto its sample point met its neighbours there (the gyroid on
/// [1000, 1002]³ at 200 samples had 366 duplicate positions and 747 flat triangles). Every
/// placement here is closed and manifold with distinct `f32` positions — welded by position,
/// as an STL reader does, it is the same surface — and no flat triangle.
#[test]
fn far_from_the_origin_vertices_keep_distinct_f32_positions() {
    use std::f64::consts::TAU;
    let gyroid = |p: [f64; 3]| {
        (TAU * p[0]).sin() * (TAU * p[1]).cos()
            + (TAU * p[1]).sin() * (TAU * p[2]).cos()
            + (TAU * p[2]).sin() * (TAU * p[0]).cos()
    };
    for (min, max, samples) in [
        ([1000.0; 3], [1002.0; 3], 200),
        ([-1002.0, 1000.0, 0.0], [-1000.0, 1002.0, 2.0], 100),
        ([4000.0; 3], [4001.0; 3], 100),
        // About 4 f32 steps per edge: most crossings are moved to keep inside theirs.
        ([30000.0; 3], [30000.5; 3], 60),
    ] {
        let grid = Grid::spanning(min, max, [samples; 3]);
        let mesh = run(grid, gyroid);
        // Unique f32 positions, one cycle around every vertex.
        assert_closed_manifold(&mesh);
        let check = crate::validate::check(&mesh);
        assert_eq!(
            (check.degenerate_triangles, check.duplicate_positions),
            (0, 0),
            "{min:?}..{max:?}"
        );
        assert!(check.watertight && check.manifold, "{min:?}..{max:?}");
        // Welding by position changes nothing: the STL reader's view is the same surface.
        let mut ids = HashMap::new();
        let welded = Mesh {
            vertices: mesh.vertices.clone(),
            triangles: mesh
                .triangles
                .iter()
                .map(|t| {
                    t.map(|v| {
                        let key = mesh.vertices[v as usize].map(f32::to_bits);
                        *ids.entry(key).or_insert(v)
                    })
                })
                .collect(),
        };
        assert!(
            welded == mesh,
            "{min:?}..{max:?}: welding by position merged vertices"
        );
    }
}

/// Where no `f32` lies between two neighbouring samples no vertex fits between them: the
/// grid is refused, naming the axis and the samples.
#[test]
fn grids_finer_than_f32_at_their_place_are_refused() {
    // f32 steps are 1/16 near a million; the spacing is 0.01.
    let grid = Grid::spanning([0.0, 1.0e6, 0.0], [1.0, 1.0e6 + 0.1, 1.0], [5, 11, 5]);
    let err = contour(&FnSampler { grid, f: |_| -1.0 }, &grid, &|_| {}).unwrap_err();
    assert_eq!(
        err,
        ContourError::BeyondF32 {
            axis: 1,
            index: 0,
            needed: 1,
            at_bits: [1.0e6f64.to_bits(), grid.coord(1, 1).to_bits()],
        }
    );
    let message = err.to_string();
    assert!(
        message.contains("along y samples 0 and 1 lie at 1000000 and 1000000.01"),
        "{message}"
    );
}

/// A shell's two levels can cross one edge; far from the origin their crossings, 1/256 of an
/// edge apart, can round to one `f32`. Every placement keeps distinct positions, no flat
/// triangle, and is closed and manifold, for a thick and a very thin band.
#[test]
fn far_from_the_origin_band_crossings_keep_distinct_f32_positions() {
    use std::f64::consts::TAU;
    let gyroid = |p: [f64; 3]| {
        (TAU * p[0]).sin() * (TAU * p[1]).cos()
            + (TAU * p[1]).sin() * (TAU * p[2]).cos()
            + (TAU * p[2]).sin() * (TAU * p[0]).cos()
    };
    for (min, max, samples) in [
        ([1000.0; 3], [1002.0; 3], 120),
        ([4000.0; 3], [4001.0; 3], 60),
        // About 4 f32 steps per edge: both crossings of an edge often round together.
        ([30000.0; 3], [30000.5; 3], 60),
    ] {
        for band in [
            Band { lo: -0.4, hi: 0.4 },
            Band {
                lo: -1e-4,
                hi: 1e-4,
            },
        ] {
            let grid = Grid::spanning(min, max, [samples; 3]);
            let mesh = run_band(grid, band, gyroid).mesh;
            assert!(!mesh.is_empty());
            assert_closed_manifold(&mesh);
            let check = crate::validate::check(&mesh);
            assert_eq!(
                (check.degenerate_triangles, check.duplicate_positions),
                (0, 0),
                "{min:?}..{max:?} {band:?}"
            );
        }
    }
}

/// A shell needs two `f32` values inside each edge (one per level); a grid with only one is
/// refused for a band though a one-level contour accepts it.
#[test]
fn band_grids_need_two_f32_values_inside_each_edge() {
    // Near 2^20 = 1048576 f32 steps are 1/8: samples 0.25 apart have one f32 between them.
    let grid = Grid::spanning([0.0, 1048576.0, 0.0], [1.0, 1048577.0, 1.0], [5, 5, 5]);
    let f = |p: [f64; 3]| p[0] - 0.5;
    assert!(contour(&FnSampler { grid, f }, &grid, &|_| {}).is_ok());
    let band = Band { lo: -0.1, hi: 0.1 };
    let err = contour_band(&FnSampler { grid, f }, band, &grid, &|_| {}).unwrap_err();
    assert!(
        matches!(
            err,
            ContourError::BeyondF32 {
                axis: 1,
                needed: 2,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("fewer than two 32-bit values"),
        "{err}"
    );
}

#[test]
fn apart_in_f32_separates_merged_crossings_inside_their_edge() {
    use super::chunk::apart_in_f32;
    let (a, b) = (1.0f64, 1.0 + 4.0 * f64::from(f32::EPSILON));
    let mid = (1.0f32).next_up().next_up();
    // Increasing: the upper moves on; at the last inside value the lower moves back.
    assert_eq!(apart_in_f32(mid, mid, true, a, b), (mid, mid.next_up()));
    let last = (b as f32).next_down();
    assert_eq!(
        apart_in_f32(last, last, true, a, b),
        (last.next_down(), last)
    );
    // Decreasing: mirrored.
    assert_eq!(apart_in_f32(mid, mid, false, a, b), (mid, mid.next_down()));
    let first = (1.0f32).next_up();
    assert_eq!(
        apart_in_f32(first, first, false, a, b),
        (first.next_up(), first)
    );
    // Already apart: unchanged.
    assert_eq!(apart_in_f32(first, last, true, a, b), (first, last));
}
