//! Periodic-surface cells: the `crystal` stage, which reads a crystal file's bytes (the
//! `file:` node) and reconstructs the loci surface through its atoms, and the payload of a
//! PS model, shared with explicit `ps = { terms = … }` cells.
//!
//! Invariants:
//! - The crystal file enters by content hash (its `file:` node), so renaming or touching it
//!   rebuilds nothing; every reconstruction option is in the key.
//! - A PS payload is the model's terms, little-endian `f64`s behind a magic: a pure function
//!   of the file's bytes and the options (or of the manifest's terms), reloaded bit for bit.
//! - A reconstruction that does not reach its tolerance by `max_scale` is an error naming the
//!   file and the error reached, never a surface that misses the atoms.

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::periodic::reconstruct::{ReconstructOptions, Reconstruction, reconstruct};
use latticebuild_geom::periodic::{ExpandOptions, PsModel, PsTerm, positions_of, read_crystal};

use super::StageError;
use crate::cache::KeyBuilder;
use crate::manifest::{CrystalCell, PsTransform};

pub const VERSION: u32 = 4;

const PS_MAGIC: &[u8; 8] = b"LBPSCEL1";

/// `crystal`: the reconstructed PS model of a crystal cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CrystalStage {
    pub cell: CrystalCell,
}

impl CrystalStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // The file's content enters as the input hash; its extension picks the reader.
        let extension = std::path::Path::new(&self.cell.file.given)
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let key = key
            .param("format", extension)
            .param("species", self.cell.species.clone().unwrap_or_default())
            .param("tolerance", self.cell.tolerance)
            .param("max_scale", self.cell.max_scale)
            .param("include_images", self.cell.include_images)
            .param("optimize", self.cell.optimize);
        // Only when given, so a cell without transform keeps its key.
        match &self.cell.transform {
            Some(t) => key.param("transform", t.numbers()),
            None => key,
        }
    }

    pub fn run(&self, file: &[u8]) -> Result<Vec<u8>, StageError> {
        let options = ReconstructOptions {
            tolerance: self.cell.tolerance,
            max_scale: self.cell.max_scale,
            optimize: self.cell.optimize,
            ..ReconstructOptions::default()
        };
        let found = reconstruct_crystal(
            &self.cell.file.given,
            file,
            self.cell.species.as_deref(),
            self.cell.include_images,
            &options,
        )?;
        let r = &found.reconstruction;
        if !r.converged {
            return Err(StageError::NotConverged(format!(
                "the surface through `{}` reaches a relative error of {:.3e} at scale {}, \
                 above the tolerance {:e}: raise `reconstruct.max_scale` or `tolerance`",
                self.cell.file.given, r.metrics.max_error, self.cell.max_scale, options.tolerance
            )));
        }
        let model = match &self.cell.transform {
            Some(t) => transform(&r.model, t)?,
            None => r.model.clone(),
        };
        let mut payload = encode(&model);
        // Several surfaces fit: the count rides after the terms so the build report can say so
        // on every build, cached or not (`multiplicity` reads it; unique payloads keep their
        // bytes).
        if r.metrics.multiplicity > 1 {
            payload.extend_from_slice(&(r.metrics.multiplicity as u64).to_le_bytes());
        }
        Ok(payload)
    }
}

/// How many independent surfaces pass through the atoms equally well (1 for a unique
/// reconstruction and for `ps` cells), as the crystal stage recorded it.
pub fn multiplicity(payload: &[u8]) -> usize {
    let Some(rest) = payload.strip_prefix(PS_MAGIC) else {
        return 1;
    };
    let Some(count) = rest.get(..8).and_then(|b| b.try_into().ok()) else {
        return 1;
    };
    let trailer = u64::from_le_bytes(count)
        .checked_mul(48)
        .and_then(|n| usize::try_from(n).ok())
        .and_then(|n| rest.get(8 + n..))
        .and_then(|t| <[u8; 8]>::try_from(t).ok());
    trailer.map_or(1, |b| (u64::from_le_bytes(b) as usize).max(1))
}

/// The report's warning for a crystal cell through whose atoms several surfaces fit.
pub fn multiplicity_warning(cell: &str, payload: &[u8]) -> Option<String> {
    let m = multiplicity(payload);
    (m > 1).then(|| {
        format!(
            "cell `{cell}`: not unique: {m} independent surfaces of the basis pass through the \
             atoms equally well (the smallest singular value repeats {m} times); the canonical \
             one is built, the same however the file lists the atoms \
             (`latticebuild crystal FILE` shows it)"
        )
    })
}

/// A PS model moved by a cell's `transform`, exactly on its terms (Wang's lemmas).
pub fn transform(model: &PsModel, t: &PsTransform) -> Result<PsModel, StageError> {
    t.apply(model).ok_or_else(|| {
        StageError::Internal("a singular `transform` (manifest validation missed it)".into())
    })
}

/// A crystal file's atoms and the surface through them.
pub struct FoundSurface {
    pub name: String,
    /// The species of the structure, in order of first appearance.
    pub species: Vec<String>,
    pub reconstruction: Reconstruction,
}

/// Reads a crystal file's bytes, expands its sites and reconstructs the surface through the
/// atoms of `species` (all atoms with `None`). Errors name the file.
pub fn reconstruct_crystal(
    given: &str,
    bytes: &[u8],
    species: Option<&str>,
    include_images: bool,
    options: &ReconstructOptions,
) -> Result<FoundSurface, StageError> {
    let crystal = read_crystal(given, bytes)?;
    let atoms = crystal.atoms(&ExpandOptions {
        include_images,
        ..ExpandOptions::default()
    });
    let points = positions_of(&atoms, species);
    let present = crystal.species();
    if points.is_empty() {
        let what = species.map_or("atoms".to_string(), |s| format!("`{s}` atoms"));
        return Err(StageError::DoesNotFit(format!(
            "`{given}` has no {what}; its species are {}",
            present.join(", ")
        )));
    }
    let reconstruction = reconstruct(&points, options)
        .map_err(|e| StageError::geometry_of(format!("the surface through `{given}`"), e))?;
    Ok(FoundSurface {
        name: crystal.name,
        species: present,
        reconstruction,
    })
}

/// The payload of a PS model.
pub fn encode(model: &PsModel) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + model.terms.len() * 48);
    out.extend_from_slice(PS_MAGIC);
    out.extend_from_slice(&(model.terms.len() as u64).to_le_bytes());
    for t in &model.terms {
        for v in [t.moment, t.scale]
            .into_iter()
            .chain(t.vector.iter().copied())
        {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Whether a cell payload is a PS model's.
pub fn is_ps_cell(payload: &[u8]) -> bool {
    payload.starts_with(PS_MAGIC)
}

pub fn decode(payload: &[u8]) -> Result<PsModel, StageError> {
    let bad = || StageError::malformed("periodic-surface cell");
    let rest = payload.strip_prefix(PS_MAGIC).ok_or_else(bad)?;
    let count = rest
        .get(..8)
        .and_then(|b| b.try_into().ok())
        .map(u64::from_le_bytes)
        .ok_or_else(bad)?;
    let body = &rest[8..];
    let terms_len = count.saturating_mul(48);
    // An 8-byte multiplicity may follow the terms (see `CrystalStage::run`).
    if body.len() as u64 != terms_len && body.len() as u64 != terms_len.saturating_add(8) {
        return Err(bad());
    }
    let body = &body[..terms_len as usize];
    let value = |c: &[u8]| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
    let terms = body
        .chunks_exact(48)
        .map(|c| {
            let v: Vec<f64> = c.chunks_exact(8).map(value).collect();
            PsTerm {
                moment: v[0],
                scale: v[1],
                vector: [v[2], v[3], v[4], v[5]],
            }
        })
        .collect();
    Ok(PsModel::new(terms))
}

/// The field of a PS payload (cell coordinates, period 1 for integer basis vectors).
pub fn ps_cell_field(payload: &[u8]) -> Result<Box<dyn ScalarField>, StageError> {
    Ok(Box::new(decode(payload)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_repeated_singular_value_rides_after_the_terms() {
        let model = PsModel::new(vec![PsTerm {
            moment: 0.5,
            scale: 1.0,
            vector: [1.0, 0.0, 0.0, 0.25],
        }]);
        let plain = encode(&model);
        assert_eq!(multiplicity(&plain), 1);
        assert_eq!(multiplicity_warning("c", &plain), None);
        let mut tagged = plain.clone();
        tagged.extend_from_slice(&6u64.to_le_bytes());
        assert_eq!(multiplicity(&tagged), 6);
        assert_eq!(decode(&tagged).expect("decodes"), model);
        let warning = multiplicity_warning("c", &tagged).expect("warns");
        assert!(warning.starts_with("cell `c`: not unique: 6 "), "{warning}");
        // Anything else after the terms is not a payload.
        tagged.push(0);
        assert!(decode(&tagged).is_err());
        assert_eq!(multiplicity(&tagged), 1);
    }

    #[test]
    fn payload_reloads_bit_for_bit() {
        let model = PsModel::new(vec![
            PsTerm {
                moment: 0.1 + 0.2,
                scale: 4.0,
                vector: [1.0, -1.0, 0.0, 1.0 / 3.0],
            },
            PsTerm {
                moment: -1e-300,
                scale: 1.0,
                vector: [0.0; 4],
            },
        ]);
        let bytes = encode(&model);
        assert!(is_ps_cell(&bytes));
        assert_eq!(decode(&bytes).unwrap(), model);
        assert!(decode(&bytes[..bytes.len() - 1]).is_err());
    }

    /// The cell of a manifest's `[cells.c]`.
    fn cell_of(text: &str) -> crate::manifest::Cell {
        let manifest = crate::manifest::parse(text, std::path::Path::new("lattice.toml"), &[])
            .unwrap_or_else(|e| panic!("valid manifest: {}", crate::diagnostics::render(&e)));
        manifest.cells["c"].clone()
    }

    /// Σ μ cos(2π κ (a x + b y + c z + θ)), written out here.
    fn psi(terms: &[[f64; 6]], p: [f64; 3]) -> f64 {
        terms
            .iter()
            .map(|[mu, kappa, a, b, c, theta]| {
                mu * (std::f64::consts::TAU * kappa * (a * p[0] + b * p[1] + c * p[2] + theta))
                    .cos()
            })
            .sum()
    }

    /// A `ps` cell with `transform` gives, through the manifest and the cell stage, a model
    /// whose value at r is the untransformed one's at T⁻¹ r = S⁻¹ Rᵀ (r − t), with R built
    /// here from a quaternion.
    #[test]
    fn a_transformed_ps_cell_is_the_model_at_the_inverse_point() {
        let terms = [
            [1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            [0.5, 2.0, 0.0, 1.0, -1.0, 0.25],
            [-0.75, 1.0, 1.0, 1.0, 1.0, 0.1],
        ];
        let text = "[cells.c]\nps = { terms = [\
            { moment = 1.0, scale = 1, vector = [1, 0, 0, 0] }, \
            { moment = 0.5, scale = 2, vector = [0, 1, -1, 0.25] }, \
            { moment = -0.75, scale = 1, vector = [1, 1, 1, 0.1] }] }\n\
            transform = { scale = [2, 0.5, -1.5], rotate = { axis = [1, 2, 2], angle = 30 }, \
            translate = [0.3, -0.2, 0.7] }\n";
        let cell = cell_of(text);
        let payload = crate::stages::cell::CellStage::new(&cell)
            .run()
            .expect("cell stage");
        let model = decode(&payload).expect("a PS payload");

        // R from the unit quaternion (cos θ/2, sin θ/2 · k), k = (1, 2, 2)/3.
        let half = 30f64.to_radians() / 2.0;
        let (w, x, y, z) = (
            half.cos(),
            half.sin() / 3.0,
            2.0 * half.sin() / 3.0,
            2.0 * half.sin() / 3.0,
        );
        let r = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - z * w),
                2.0 * (x * z + y * w),
            ],
            [
                2.0 * (x * y + z * w),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - x * w),
            ],
            [
                2.0 * (x * z - y * w),
                2.0 * (y * z + x * w),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        let (s, t) = ([2.0, 0.5, -1.5], [0.3, -0.2, 0.7]);
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        for _ in 0..300 {
            let p = [next(), next(), next()];
            let d = [p[0] - t[0], p[1] - t[1], p[2] - t[2]];
            let inverse: [f64; 3] =
                std::array::from_fn(|j| (0..3).map(|i| r[i][j] * d[i]).sum::<f64>() / s[j]);
            let (got, want) = (model.value(p), psi(&terms, inverse));
            assert!((got - want).abs() <= 1e-12, "at {p:?}: {got} vs {want}");
        }
        // Without the transform, the payload and the key are the untransformed model's.
        let plain = cell_of(&text[..text.find("transform").expect("transform")]);
        let plain_payload = crate::stages::cell::CellStage::new(&plain)
            .run()
            .expect("cell stage");
        let untransformed = decode(&plain_payload).expect("a PS payload");
        for p in [[0.1, 0.2, 0.3], [-1.0, 0.5, 2.0]] {
            assert!((untransformed.value(p) - psi(&terms, p)).abs() <= 1e-12);
        }
    }

    /// A crystal cell translated by t: the same vectors, each phase θ − (a, b, c)·t.
    #[test]
    fn a_translated_crystal_cell_shifts_only_the_phases() {
        let nacl = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/crates/geom/tests/data/crystals/NaCl.cif"
        );
        let bytes = std::fs::read(nacl).expect("NaCl.cif");
        let base = "[cells.c]\ncrystal = \"NaCl.cif\"\nspecies = \"Na\"\n";
        let run = |text: &str| {
            let crate::manifest::CellSource::Crystal(cell) = cell_of(text).source else {
                panic!("not a crystal cell");
            };
            let stage = CrystalStage { cell };
            let model = decode(&stage.run(&bytes).expect("crystal stage")).expect("payload");
            (stage, model)
        };
        let (plain_stage, plain) = run(base);
        let moved_text = format!("{base}transform = {{ translate = [0.5, 0, 0] }}\n");
        let (moved_stage, moved) = run(&moved_text);
        assert!(!plain.terms.is_empty());
        assert_eq!(plain.terms.len(), moved.terms.len());
        for (p, m) in plain.terms.iter().zip(&moved.terms) {
            assert_eq!((p.moment, p.scale), (m.moment, m.scale));
            assert_eq!(p.vector[..3], m.vector[..3]);
            let expected = p.vector[3] - p.vector[0] * 0.5;
            assert!(
                (m.vector[3] - expected).abs() <= 1e-15,
                "{:?} → {:?}",
                p.vector,
                m.vector
            );
        }
        // The translation is in the key; the cell without it keeps the key of a cell as before.
        let key = |s: &CrystalStage| {
            s.key_params(crate::cache::KeyBuilder::new("crystal", VERSION))
                .build()
                .expect("a key")
                .0
        };
        assert_ne!(key(&plain_stage), key(&moved_stage));
        let before = crate::cache::KeyBuilder::new("crystal", VERSION)
            .param("format", "cif")
            .param("species", "Na")
            .param("tolerance", 1e-9)
            .param("max_scale", 8u32)
            .param("include_images", false)
            .param("optimize", false)
            .build()
            .expect("a key")
            .0;
        assert_eq!(key(&plain_stage), before);
        let mut other = moved_stage.clone();
        other.cell.transform = Some(crate::manifest::PsTransform {
            translate: [0.25, 0.0, 0.0],
            ..crate::manifest::PsTransform::IDENTITY
        });
        assert_ne!(key(&other), key(&moved_stage));
    }
}
