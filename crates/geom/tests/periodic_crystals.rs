//! Periodic surfaces from crystals: the statements of issue 7 as tests.
//!
//! - PS transforms equal evaluation at inverse-transformed points (Lemmas 2–4), to 1e-12.
//! - The CIF files of `tests/data/crystals` expand to the atom counts of its README table.
//! - The reconstructed Faujasite (Si) and NaCl surfaces pass through every atom to 1e-9
//!   relative to max |ψ| over the cell, with porosity in (0, 1]; both checked against
//!   direct evaluation, independently of the reconstruction's own grid.
//! - Malformed CIF files give errors at their line and column.

use latticebuild_geom::periodic::reconstruct::{ReconstructOptions, reconstruct};
use latticebuild_geom::periodic::{
    Crystal, ExpandOptions, PsModel, PsTerm, cif, positions_of, read_crystal,
};

fn data(name: &str) -> Vec<u8> {
    let path = format!("{}/tests/data/crystals/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn crystal(name: &str) -> Crystal {
    read_crystal(name, &data(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// A small deterministic generator (xorshift), uniform in [lo, hi).
struct Random(u64);

impl Random {
    fn next(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn random_model(rng: &mut Random) -> PsModel {
    let mut terms = vec![PsTerm {
        moment: rng.next(-1.0, 1.0),
        scale: 1.0,
        vector: [0.0; 4],
    }];
    for scale in [1.0, 2.0, 4.0] {
        for _ in 0..4 {
            terms.push(PsTerm {
                moment: rng.next(-1.0, 1.0),
                scale,
                vector: [
                    rng.next(-2.0, 2.0).round(),
                    rng.next(-2.0, 2.0).round(),
                    rng.next(-2.0, 2.0).round(),
                    rng.next(-0.5, 0.5),
                ],
            });
        }
    }
    PsModel::new(terms)
}

fn apply(linear: [[f64; 3]; 3], t: [f64; 3], p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|j| linear[i][j] * p[j]).sum::<f64>() + t[i])
}

/// `x` solving `linear x + t = p`, by Gaussian elimination with partial pivoting: an
/// inverse computed independently of the model's own.
fn apply_inverse(linear: [[f64; 3]; 3], t: [f64; 3], p: [f64; 3]) -> [f64; 3] {
    let mut m = [[0.0; 4]; 3];
    for i in 0..3 {
        m[i][..3].copy_from_slice(&linear[i]);
        m[i][3] = p[i] - t[i];
    }
    for c in 0..3 {
        let pivot = (c..3)
            .max_by(|&a, &b| m[a][c].abs().total_cmp(&m[b][c].abs()))
            .expect("a column has a largest entry");
        m.swap(c, pivot);
        for r in 0..3 {
            if r != c {
                let f = m[r][c] / m[c][c];
                let pivot_row = m[c];
                for (v, p) in m[r].iter_mut().zip(pivot_row) {
                    *v -= f * p;
                }
            }
        }
    }
    std::array::from_fn(|i| m[i][3] / m[i][i])
}

fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let len = axis.iter().map(|v| v * v).sum::<f64>().sqrt();
    let [x, y, z] = axis.map(|v| v / len);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// A transform's name, the transformed model, and the point map `x ↦ L x + t`.
type Case = (&'static str, PsModel, [[f64; 3]; 3], [f64; 3]);

#[test]
fn transforms_equal_evaluation_at_inverse_transformed_points() {
    let mut rng = Random(0x9e3779b97f4a7c15);
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..20 {
        let model = random_model(&mut rng);
        let axis = [
            rng.next(-1.0, 1.0),
            rng.next(-1.0, 1.0),
            rng.next(-1.0, 1.0),
        ];
        let r = rotation(axis, rng.next(-3.0, 3.0));
        let t = [
            rng.next(-2.0, 2.0),
            rng.next(-2.0, 2.0),
            rng.next(-2.0, 2.0),
        ];
        let s = [rng.next(0.3, 3.0), -rng.next(0.3, 3.0), rng.next(0.3, 3.0)];
        let n = [
            rng.next(-1.0, 1.0),
            rng.next(-1.0, 1.0),
            rng.next(-1.0, 1.0),
        ];
        let len2: f64 = n.iter().map(|v| v * v).sum();
        let householder: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| identity[i][j] - 2.0 * n[i] * n[j] / len2)
        });
        let scaling = [[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]];
        // Rotation, anisotropic scaling and another rotation: a shear with condition ≤ 10.
        let r2 = rotation([axis[1], axis[2], axis[0]], rng.next(-3.0, 3.0));
        let general: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| r2[i][k] * s[k] * r[k][j]).sum())
        });
        let cases: Vec<Case> = vec![
            ("rotation", model.rotated(r).unwrap(), r, [0.0; 3]),
            ("translation", model.translated(t), identity, t),
            ("scaling", model.scaled(s).unwrap(), scaling, [0.0; 3]),
            (
                "reflection",
                model.reflected(n).unwrap(),
                householder,
                [0.0; 3],
            ),
            ("affine", model.transformed(general, t).unwrap(), general, t),
        ];
        for (name, moved, linear, shift) in cases {
            for _ in 0..20 {
                let p = [
                    rng.next(-2.0, 2.0),
                    rng.next(-2.0, 2.0),
                    rng.next(-2.0, 2.0),
                ];
                let expected = model.value(apply_inverse(linear, shift, p));
                let got = moved.value(p);
                assert!(
                    (got - expected).abs() <= 1e-12,
                    "{name}: {got} vs {expected}"
                );
                // And the forward direction: the moved model at T x is the model at x.
                let back = moved.value(apply(linear, shift, p));
                assert!((back - model.value(p)).abs() <= 1e-12, "{name} forward");
            }
        }
    }
}

#[test]
fn crystal_files_expand_to_the_readme_atom_counts() {
    let count = |c: &Crystal, species: &str, images: bool| {
        let atoms = c.atoms(&ExpandOptions {
            include_images: images,
            ..ExpandOptions::default()
        });
        positions_of(&atoms, Some(species)).len()
    };
    let fau = crystal("FAU.cif");
    assert_eq!(fau.lengths, [24.345; 3]);
    assert_eq!(fau.operations.len(), 192);
    assert_eq!(fau.species(), ["Si", "O"]);
    assert_eq!(
        (count(&fau, "Si", false), count(&fau, "O", false)),
        (192, 384)
    );
    assert_eq!(
        (count(&fau, "Si", true), count(&fau, "O", true)),
        (192, 408)
    );
    let nacl = crystal("NaCl.cif");
    assert_eq!(
        (count(&nacl, "Na", false), count(&nacl, "Cl", false)),
        (4, 4)
    );
    assert_eq!(
        (count(&nacl, "Na", true), count(&nacl, "Cl", true)),
        (14, 13)
    );
    // Images lie in [0, 1]³, and every atom is an image of a cell atom under an integer shift.
    let atoms = nacl.atoms(&ExpandOptions {
        include_images: true,
        ..ExpandOptions::default()
    });
    assert!(
        atoms
            .iter()
            .all(|a| a.fract.iter().all(|c| (0.0..=1.0).contains(c)))
    );
    let fau_atoms = fau.atoms(&ExpandOptions::default());
    assert!(
        fau_atoms
            .iter()
            .all(|a| a.fract.iter().all(|c| (0.0..1.0).contains(c)))
    );
    // The first Si is the site itself.
    assert_eq!(fau_atoms[0].fract, [0.9469, 0.1251, 0.0364]);
}

/// Max |ψ| by direct evaluation on a 72³ grid (not the reconstruction's grid or sampler).
fn direct_max(model: &PsModel) -> f64 {
    let n = 72;
    let mut max: f64 = 0.0;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = [i, j, k].map(|c| c as f64 / n as f64);
                max = max.max(model.value(p).abs());
            }
        }
    }
    max
}

fn check_reconstruction(file: &str, species: Option<&str>, images: bool) -> (usize, f64, f64) {
    let c = crystal(file);
    let atoms = c.atoms(&ExpandOptions {
        include_images: images,
        ..ExpandOptions::default()
    });
    let points = positions_of(&atoms, species);
    let r = reconstruct(&points, &ReconstructOptions::default()).expect("reconstruct");
    assert!(r.converged, "{file}: {:?}", r.steps);
    assert_eq!(r.atoms, points.len());
    assert!(
        r.metrics.max_error <= 1e-9,
        "{file}: {}",
        r.metrics.max_error
    );
    assert!(
        r.metrics.porosity > 0.0 && r.metrics.porosity <= 1.0,
        "{}",
        r.metrics.porosity
    );
    // Independent check: the normalised model's max over the cell is 1 (a coarser direct
    // grid can only find less), and it vanishes at every atom relative to that maximum.
    let max = direct_max(&r.model);
    assert!(max <= 1.0 + 1e-9 && max > 0.9, "{file}: direct max {max}");
    let worst = points
        .iter()
        .map(|&p| r.model.value(p).abs())
        .fold(0.0, f64::max);
    assert!(worst / max <= 1e-9, "{file}: {worst} / {max}");
    // The porosity is the mean square of ψ/ψ_M: compare with a direct 40³ mean.
    let n = 40;
    let mut sum = 0.0;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let v = r.model.value([i, j, k].map(|c| c as f64 / n as f64));
                sum += v * v;
            }
        }
    }
    let direct = sum / (n * n * n) as f64;
    assert!(
        (direct - r.metrics.porosity).abs() < 1e-9,
        "{direct} vs {}",
        r.metrics.porosity
    );
    (r.metrics.dimension, r.metrics.max_error, r.metrics.porosity)
}

#[test]
fn faujasite_surface_passes_through_every_silicon() {
    // Origin choice 2 puts the T sites on the zero set of a scale-1 model: the constant and
    // the four body diagonals with signs + − − − (the pattern of the paper's Table 1).
    let (dimension, error, porosity) = check_reconstruction("FAU.cif", Some("Si"), false);
    println!("FAU Si: dimension {dimension}, error {error:e}, porosity {porosity}");
    assert_eq!(dimension, 5);
    check_reconstruction("FAU.cif", Some("si"), true);
    // All 600 atoms (Si and O, with images) need scale 4.
    check_reconstruction("FAU.cif", None, true);
}

#[test]
fn rock_salt_surface_passes_through_every_ion() {
    check_reconstruction("NaCl.cif", None, false);
    check_reconstruction("NaCl.cif", None, true);
    check_reconstruction("NaCl.cif", Some("Cl"), true);
}

#[test]
fn too_few_scales_report_the_error_and_stop_unconverged() {
    // Faujasite's oxygens need scale 4; with scale 1 only, the search stops unconverged.
    let c = crystal("FAU.cif");
    let points = positions_of(&c.atoms(&ExpandOptions::default()), Some("O"));
    let options = ReconstructOptions {
        max_scale: 1,
        ..ReconstructOptions::default()
    };
    let r = reconstruct(&points, &options).unwrap();
    assert!(r.metrics.dimension <= 14);
    assert!(!r.converged);
    assert!(r.metrics.max_error > 1e-3, "{}", r.metrics.max_error);
    assert_eq!(r.steps.len(), 1);
}

/// At tolerance 0 the search cannot stop early: it goes through scales 1, 2 and 4 (the
/// property the Faujasite timing of `cargo xtask bench geom periodic` relies on).
#[test]
fn zero_tolerance_searches_every_scale_up_to_the_largest() {
    let c = crystal("FAU.cif");
    let points = positions_of(&c.atoms(&ExpandOptions::default()), Some("Si"));
    let options = ReconstructOptions {
        tolerance: 0.0,
        max_scale: 4,
        ..ReconstructOptions::default()
    };
    let r = reconstruct(&points, &options).unwrap();
    assert_eq!(r.steps.len(), 3);
}

/// Eq. 12 on Faujasite's Si: at scale 1 the exact fit is unique (five terms, nothing to drop),
/// one scale further the exact fits span six dimensions, and the best of them has a higher
/// porosity. Checked here against a direct mean of ψ² over a grid and the atoms' residuals.
#[test]
fn optimisation_raises_faujasite_porosity_keeping_every_atom_on_the_surface() {
    let c = crystal("FAU.cif");
    let points = positions_of(&c.atoms(&ExpandOptions::default()), Some("Si"));
    let options = ReconstructOptions {
        optimize: true,
        ..ReconstructOptions::default()
    };
    let r = reconstruct(&points, &options).unwrap();
    let o = r.optimization.clone().expect("optimised");
    println!("FAU optimisation: {o:?}");
    assert_eq!(o.before.dimension, 5);
    assert_eq!(o.before.multiplicity, 1);
    assert_eq!(o.scales, [1, 2]);
    assert_eq!(o.freedom, 6);
    assert_eq!(r.metrics, o.after);
    let max = direct_max(&r.model);
    let worst = points
        .iter()
        .map(|&p| r.model.value(p).abs())
        .fold(0.0, f64::max);
    assert!(worst / max <= 1e-9, "{worst} / {max}");
    // Porosity from a direct 40³ mean and the 72³ maximum: a grid maximum can only be lower
    // than the true one, so this is at least the true porosity, and close to it.
    let n = 40;
    let mut sum = 0.0;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let v = r.model.value([i, j, k].map(|c| c as f64 / n as f64));
                sum += v * v;
            }
        }
    }
    let direct = sum / (n * n * n) as f64 / (max * max);
    assert!(
        (direct - o.after.porosity).abs() < 0.01,
        "{direct} vs {o:?}"
    );
    assert!(o.after.porosity > o.before.porosity + 0.1, "{o:?}");
    // Without the option the surface is the five-term one.
    let plain = reconstruct(&points, &ReconstructOptions::default()).unwrap();
    assert_eq!(plain.metrics, o.before);
}

fn cif_error(text: &str) -> (usize, usize, String) {
    let e = cif::read("bad.cif", text.as_bytes()).expect_err("the CIF is refused");
    assert_eq!(e.file, "bad.cif");
    (e.line, e.column, e.message)
}

const HEADER: &str = "data_x\n_cell_length_a 4\n_cell_length_b 4\n_cell_length_c 4\n";

#[test]
fn malformed_cif_files_give_located_errors() {
    let sites = "loop_\n_atom_site_label\n_atom_site_fract_x\n_atom_site_fract_y\n\
                 _atom_site_fract_z\nNa1 0 0 0\n";
    // A symmetry operation that does not parse: the column of the bad character.
    let text =
        format!("{HEADER}loop_\n_symmetry_equivalent_pos_as_xyz\n'x,y,z'\n'-y+1/2,q,z'\n{sites}");
    let (line, column, message) = cif_error(&text);
    assert_eq!((line, column), (8, 9), "{message}");
    assert!(message.contains("-y+1/2,q,z"), "{message}");
    // A bad coordinate.
    let text = format!("{HEADER}{}", sites.replace("Na1 0 0 0", "Na1 0 0.5(2 abc"));
    let (line, column, message) = cif_error(&text);
    assert_eq!(line, 10, "{message}");
    assert!(
        column > 0 && message.contains("_atom_site_fract_y"),
        "{message}"
    );
    // A loop whose values do not fill its rows.
    let text = format!("{HEADER}{}", sites.replace("Na1 0 0 0", "Na1 0 0"));
    let (line, _, message) = cif_error(&text);
    assert_eq!(line, 5, "{message}");
    assert!(message.contains("4 tags has 3 values"), "{message}");
    // Unsupported constructs are reported, not skipped.
    let text = format!("{HEADER}_symmetry_space_group_name_H-M 'F m -3 m'\n{sites}");
    let (line, column, message) = cif_error(&text);
    assert_eq!((line, column), (5, 1), "{message}");
    assert!(message.contains("by name only"), "{message}");
    let text = format!("{HEADER}{sites}data_second\n");
    let (line, _, message) = cif_error(&text);
    assert_eq!(line, 11, "{message}");
    let cartesian = "loop_\n_atom_site_label\n_atom_site_Cartn_x\n_atom_site_Cartn_y\n\
                     _atom_site_Cartn_z\nNa1 0 0 0\n";
    let (line, _, message) = cif_error(&format!("{HEADER}{cartesian}"));
    assert_eq!(line, 7, "{message}");
    assert!(message.contains("Cartesian"), "{message}");
    let (line, column, message) = cif_error(&format!("{HEADER}_cell_angle_alpha 'ninety\n"));
    assert_eq!((line, column), (5, 19), "{message}");
    let (line, _, message) = cif_error("data_x\n_cell_length_a 4\n");
    assert_eq!(line, 1, "{message}");
    assert!(message.contains("_cell_length_b"), "{message}");
}
