//! Periodic surfaces from crystals (Wang, "Loci periodic surface reconstruction from
//! crystals"): the PS model ([`model`]), crystal structures read from CIF ([`cif`]) and
//! extended XYZ ([`xyz`]) files, and the loci-surface reconstruction of §5 ([`reconstruct`]).
//!
//! Invariants:
//! - Readers take bytes and a display name, never a path; every error names the file and the
//!   line and column of the problem ([`CrystalError`]), and nothing a file contains panics.
//! - A crystal's cell has a volume: every angle is strictly between 0° and 180° and together
//!   they span space ([`unit_volume_squared`] above [`FLAT_CELL`]); a file whose cell does
//!   not is an error at the cell's line.
//! - Atom positions are fractional coordinates of the conventional cell; the models built
//!   from them are in the same coordinates, so a model with integer basis vectors has period 1
//!   on every axis, like every other cell.

pub mod cif;
pub mod model;
pub mod nullspace;
pub mod optimize;
pub mod phase;
pub mod reconstruct;
pub mod xyz;

pub use model::{PsModel, PsTerm};

/// A crystal structure: the cell, the sites as given, and the symmetry operations.
#[derive(Clone, Debug, PartialEq)]
pub struct Crystal {
    /// The data block's name (`data_FAU` gives `FAU`), or the comment line of an XYZ file.
    pub name: String,
    /// `a, b, c` (Å) and `α, β, γ` (degrees).
    pub lengths: [f64; 3],
    pub angles: [f64; 3],
    pub sites: Vec<Site>,
    /// Symmetry operations on fractional coordinates (the identity among them).
    pub operations: Vec<SymOp>,
}

/// A site of the asymmetric unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Site {
    pub label: String,
    /// The element (`Si`, from `Si4+` or a label `Si1`).
    pub species: String,
    pub fract: [f64; 3],
}

/// `r ↦ W r + w` on fractional coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SymOp {
    pub rotation: [[f64; 3]; 3],
    pub translation: [f64; 3],
}

impl SymOp {
    pub const IDENTITY: SymOp = SymOp {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    pub fn apply(&self, r: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| {
            (0..3).map(|j| self.rotation[i][j] * r[j]).sum::<f64>() + self.translation[i]
        })
    }
}

/// An atom of the expanded structure.
#[derive(Clone, Debug, PartialEq)]
pub struct Atom {
    pub label: String,
    pub species: String,
    /// Fractional coordinates in `[0, 1)` (images: within `tolerance` outside it).
    pub fract: [f64; 3],
}

/// How sites become atoms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExpandOptions {
    /// Two positions closer than this modulo 1 (per fractional coordinate) are one atom, and
    /// a coordinate this close to 0 or 1 lies on a face of the cell.
    pub tolerance: f64,
    /// Also list the periodic images of atoms on faces, edges and corners inside `[0, 1]³`.
    pub include_images: bool,
}

impl Default for ExpandOptions {
    fn default() -> ExpandOptions {
        ExpandOptions {
            tolerance: 1e-3,
            include_images: false,
        }
    }
}

impl Crystal {
    /// Every site under every operation, reduced modulo 1, duplicates merged (the first
    /// occurrence is kept), in site order; then images on the cell's faces if asked.
    pub fn atoms(&self, options: &ExpandOptions) -> Vec<Atom> {
        let tol = options.tolerance;
        let mut atoms: Vec<Atom> = Vec::new();
        for site in &self.sites {
            let first = atoms.len();
            for op in &self.operations {
                let fract = op.apply(site.fract).map(|c| {
                    let w = c - c.floor();
                    if w >= 1.0 { 0.0 } else { w }
                });
                let duplicate = atoms[first..].iter().any(|a| {
                    (0..3).all(|i| {
                        let d = a.fract[i] - fract[i];
                        (d - d.round()).abs() < tol
                    })
                });
                if !duplicate {
                    atoms.push(Atom {
                        label: site.label.clone(),
                        species: site.species.clone(),
                        fract,
                    });
                }
            }
        }
        if !options.include_images {
            return atoms;
        }
        let mut with_images = Vec::with_capacity(atoms.len());
        for atom in atoms {
            // Each coordinate on a face has two places in [0, 1]: c and c ± 1.
            let choices: Vec<Vec<f64>> = atom
                .fract
                .iter()
                .map(|&c| {
                    if c < tol {
                        vec![c, c + 1.0]
                    } else if c > 1.0 - tol {
                        vec![c, c - 1.0]
                    } else {
                        vec![c]
                    }
                })
                .collect();
            for &x in &choices[0] {
                for &y in &choices[1] {
                    for &z in &choices[2] {
                        with_images.push(Atom {
                            fract: [x, y, z],
                            ..atom.clone()
                        });
                    }
                }
            }
        }
        with_images
    }

    /// The species present, in order of first appearance.
    pub fn species(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for s in &self.sites {
            if !out.contains(&s.species) {
                out.push(s.species.clone());
            }
        }
        out
    }
}

/// The positions of the atoms of one species (case-insensitive), or of all with `None`.
pub fn positions_of(atoms: &[Atom], species: Option<&str>) -> Vec<[f64; 3]> {
    atoms
        .iter()
        .filter(|a| species.is_none_or(|s| a.species.eq_ignore_ascii_case(s)))
        .map(|a| a.fract)
        .collect()
}

/// The squared volume of a cell with unit edges and angles `α, β, γ` (degrees):
/// `1 − cos²α − cos²β − cos²γ + 2 cosα cosβ cosγ`, the Gram determinant of its edge vectors.
/// Zero for a flat cell (the third edge in the plane of the other two), negative for angles
/// no three vectors can have (`α = β = 30°, γ = 90°`).
pub fn unit_volume_squared(angles: [f64; 3]) -> f64 {
    let [a, b, c] = angles.map(|d| d.to_radians().cos());
    1.0 - a * a - b * b - c * c + 2.0 * a * b * c
}

/// A cell whose [`unit_volume_squared`] is at most this is flat: its unit-edge volume is
/// below 10⁻⁶. Whole-degree angles round their cosines by about 10⁻¹⁶, so a truly flat cell
/// (60°, 60°, 120°) comes out within ~10⁻¹⁶ of 0, and every real crystal is above 10⁻².
pub const FLAT_CELL: f64 = 1e-12;

/// A problem in a crystal file, at a line and column (1-based; column 0 for a whole line).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{file}:{line}:{column}: {message}")]
pub struct CrystalError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// Reads a crystal file by its name's extension: `.cif`, or `.xyz` / `.extxyz`.
pub fn read_crystal(name: &str, bytes: &[u8]) -> Result<Crystal, CrystalError> {
    let extension = std::path::Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("xyz" | "extxyz") => xyz::read(name, bytes),
        Some("cif") => cif::read(name, bytes),
        _ => Err(CrystalError {
            file: name.to_string(),
            line: 0,
            column: 0,
            message: "not a crystal file the readers know (expected `.cif`, `.xyz` or `.extxyz`)"
                .to_string(),
        }),
    }
}
