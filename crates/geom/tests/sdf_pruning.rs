//! Skipping tiles by interval bounds is invisible in the output: meshes with and without it
//! are identical, and samples are pure functions of their grid indices.

use crate::common;

use common::sdf_sphere::SphereFile;

use latticebuild_geom::field::{Grid, ScalarField};
use latticebuild_geom::stack_lang::{self, Program, ProgramField};

/// A sphere of radius 1.5 standing in for every mesh, a true distance.
const FILES: SphereFile = SphereFile {
    name: None,
    radius: 1.5,
};

fn field(program: &str, pruning: bool) -> ProgramField {
    let mut f = Program::parse_str(program)
        .expect("the program parses")
        .field(&FILES)
        .expect("its files resolve");
    f.set_pruning(pruning);
    f
}

const PROGRAMS: [(&str, Option<&str>); 6] = [
    (
        "ball scale 5 tpms.p scale 4 tpms.d scale 3.75 tpms.gyroid scale 1.25 intersection \
         intersection intersection",
        Some("-4,-4,-4,4,4,4"),
    ),
    (
        "cylinder move 0,-2,0 cylinder move 0,2,0 union scale 1/2 orient 1,0,0 complement box \
         intersection tpms.gyroid offset 1/4 complement scale 1.3 intersection",
        None,
    ),
    (
        "tpms.gyroid rotate 1,1,0 0.3 scale 0.4 expression \"x*x + y*y/2 + z*z - 1\" \
         intersection ball scale 0.3 move 0.5,0,0 difference",
        None,
    ),
    ("tpms.neovius scale 0.3 file part.stl intersection", None),
    (
        "tpms.gyroid offset 0.3 tpms.p scale 0.5 sigmoid-blend 0,0,1 0 0.2 ball scale 1.5 \
         intersection",
        None,
    ),
    (
        "ball scale 0.1 move 2,0,0 box scale 0.2 move -2,1,0 union",
        Some("-3,-3,-3,3,3,3"),
    ),
];

#[test]
fn pruning_never_changes_the_mesh() {
    for (program, domain) in PROGRAMS {
        let exact = field(program, false);
        let pruned = field(program, true);
        let domain = domain.map_or_else(|| exact.domain(), |b| stack_lang::parse_box(b).unwrap());
        for counts in [[61, 61, 61], [70, 45, 53]] {
            let a = stack_lang::mesh(&exact, &domain, counts).unwrap();
            let b = stack_lang::mesh(&pruned, &domain, counts).unwrap();
            assert!(!a.triangles.is_empty(), "{program}: empty");
            assert!(a == b, "{program} at {counts:?}: meshes differ");
        }
    }
}

#[test]
fn pruning_replaces_values_far_from_the_surface_only() {
    // Two tiny solids in a big box: most tiles are provably outside.
    let (program, domain) = PROGRAMS[5];
    let domain = stack_lang::parse_box(domain.unwrap()).unwrap();
    let grid = Grid::spanning(domain.min, domain.max, [90, 90, 90]);
    let (exact, pruned) = (field(program, false), field(program, true));
    let (exact, pruned) = (exact.sampler(&grid), pruned.sampler(&grid));
    let mut a = vec![0.0; 90 * 90];
    let mut b = vec![0.0; 90 * 90];
    let mut replaced = 0;
    for k in 0..90 {
        exact.sample_plane(k, &mut a);
        pruned.sample_plane(k, &mut b);
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(*x < 0.0, *y < 0.0);
            replaced += usize::from(x != y);
        }
    }
    assert!(
        replaced > 90 * 90 * 45,
        "only {replaced} samples were skipped"
    );
}

#[test]
fn samples_do_not_depend_on_the_rows_asked_for() {
    for (program, _) in PROGRAMS {
        let f = field(program, true);
        let d = f.domain();
        let grid = Grid::spanning(d.min, d.max, [53, 47, 9]);
        let sampler = f.sampler(&grid);
        let nx = 53;
        for k in 0..9 {
            let mut whole = vec![0.0; nx * 47];
            sampler.sample_plane(k, &mut whole);
            // Rows in uneven pieces that cut across the tiles.
            let mut start = 0;
            for len in [1, 5, 11, 3, 17, 10] {
                let rows = start..(start + len).min(47);
                let mut part = vec![0.0; nx * rows.len()];
                sampler.sample_rows(k, rows.clone(), &mut part);
                let want = &whole[rows.start * nx..rows.end * nx];
                assert!(
                    part.iter()
                        .zip(want)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{program}: plane {k}, rows {rows:?}"
                );
                start = rows.end;
            }
            assert_eq!(start, 47);
        }
    }
}
