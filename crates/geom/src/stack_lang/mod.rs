//! The Cesogen stack language for signed distance functions (Patience, Audet & Blais 2025,
//! §2 and §4.2–4.3): parse a program, find its bounds, and evaluate or sample its field.
//!
//! ```text
//! words ──include::expand──▶ words ──parse──▶ Tree ──ProgramField::new──▶ ProgramField: ScalarField
//!  (@file)                  (positions kept)   │ canonical()   (files resolved, bounds,
//!                                              ▼               compiled plan, tile sampler)
//!                                         cache keys
//! ```
//!
//! Semantics, as the paper's equations 2–11 (the field is negative inside):
//!
//! | word | field |
//! |---|---|
//! | `ball`, `cylinder`, `box` | `\|x\| − 1`; `√(x²+y²) − 1` (infinite along z); exact distance to `[-1,1]³` |
//! | `tpms.NAME`, `expression F` | the library formula (period 1, `crate::tpms`); the formula F in x, y, z |
//! | `file PATH` | the caller's field for PATH ([`ExternalSolids`]) |
//! | `complement`, `offset ξ`, `shell Ξ` | `−f`; `f − ξ`; `\|f\| − Ξ/2` |
//! | `move δ`, `scale κ₀` | `f(x − δ)`; `\|κ₀\| f(x/κ₀)` |
//! | `scale κx,κy,κz` | `min_i \|κ_i\| f(x/κ)` (eq. 4 as written: the smallest factor where `f ≥ 0`, the largest where `f < 0`) |
//! | `rotate v θ` | `f(R x)`, R the Rodrigues matrix of v̂ and θ (eq. 5 as written, so the solid turns by −θ about v) |
//! | `orient v` | the solid turned about `e3 × v` by `arccos(v3/\|v\|)` so that its z axis points along v: `f(Rᵀ x)` with `R e3 = v̂` |
//! | `union`, `intersection`, `difference` | `min(f, g)`; `max(f, g)`; `max(f, −g)` |
//! | `sigmoid-blend d x0 width` | `f + w·(g − f)`, `w = 1/(1 + exp(−(d̂·x − x0)/width))` (`blend.rs`) |
//!
//! Numeric arguments are expressions without coordinates (`1/2`, `pi/4`, `2^-3`), vectors are
//! comma-separated in one word (`0,-2,0`).
//!
//! Evaluation: the tree is compiled once (`compile.rs`) into leaves in world coordinates, each
//! an expression of `crate::expr` with the point transformations substituted (so scaled and
//! moved TPMS keep their separable per-axis tables), and a post-order list of value operations
//! run by a stack machine over blocks of points (`machine.rs`). Grids are sampled in tiles
//! (`sampler.rs`): a tile whose samples provably share one sign is filled without evaluation,
//! and operands of min/max that cannot win in a tile are skipped, both decided by interval
//! arithmetic on the samples themselves, so the contoured mesh is the same as without it.
//!
//! Why not `fidget` (a crate for exactly this: tapes, interval pruning, a JIT): its current
//! release needs Rust 1.95 (the workspace promises 1.89), is MPL-2.0 where the project is
//! MIT/Apache, evaluates in `f32` where the contourer and the TPMS tables work in `f64`, and
//! brings a JIT and, by default, GPU and GUI crates to a 2-core build. The TPMS fast path it
//! would replace is the separable table sampler we already have, which no per-point
//! evaluator, JIT or not, matches.
//!
//! Invariants of the module:
//! - No paths, no IO: `@file` includes go through an [`IncludeResolver`] and `file` words
//!   through [`ExternalSolids`], both supplied by the caller.
//! - Errors are [`ProgramError`]s naming the word at fault by position and text; nothing here
//!   panics on any program.
//! - The TPMS and expression leaves are never assumed to be distances: bounds treat them as
//!   unbounded, and tiles are skipped only when interval arithmetic proves the sign of the
//!   samples themselves.

mod affine;
mod args;
mod blend;
mod bounds;
mod compile;
mod error;
mod external;
mod field;
mod include;
mod interval;
mod machine;
mod options;
mod parse;
mod sampler;
mod tree;
mod words;

pub use affine::Affine;
pub use args::{constant, constants, split_components, vector3};
pub use bounds::Aabb;
pub use error::ProgramError;
pub use external::{ExternalField, ExternalSolids, NoExternalSolids};
pub use field::ProgramField;
pub use include::{IncludeResolver, Included, MAX_DEPTH, MAX_WORDS, expand};
pub use options::{MAX_SAMPLES_PER_AXIS, OptionError, parse_box, parse_samples, spread_samples};
pub use parse::{BINARY_WORDS, SOLID_WORDS, UNARY_WORDS};
pub use sampler::{TILE_X, TILE_Y};
pub use tree::{Node, Op, Tree};
pub use words::{At, Origin, Word, quote, split_words, split_words_spanned};

use crate::contour::{ContourError, Contouring, contour_with};
use crate::field::{Grid, ScalarField};
use crate::mesh::Mesh;

/// Samples Cesogen takes when none are given: 60³ (the paper's default for its figures).
pub const DEFAULT_SAMPLES: [usize; 3] = [60, 60, 60];

/// A parsed program.
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    tree: Tree,
}

impl Program {
    /// Parses words that carry their origins (from [`expand`], or [`Word::args`]).
    pub fn parse(words: &[Word]) -> Result<Program, ProgramError> {
        Ok(Program {
            tree: parse::parse(words)?,
        })
    }

    /// Parses a list of words, e.g. command-line arguments (without `@file` includes).
    pub fn parse_args<S: AsRef<str>>(args: &[S]) -> Result<Program, ProgramError> {
        Program::parse(&Word::args(args))
    }

    /// Parses program text: words separated by whitespace, quotes grouping words
    /// (`expression "x + y"`), as in a manifest's `sdf = "…"`.
    pub fn parse_str(text: &str) -> Result<Program, ProgramError> {
        let words =
            split_words(text).map_err(|byte| ProgramError::UnclosedQuote { file: None, byte })?;
        Program::parse_args(&words)
    }

    pub fn tree(&self) -> &Tree {
        &self.tree
    }

    /// The canonical text of the program (see [`Tree::canonical`]): equal for programs that
    /// differ only in spelling (`1/2` and `0.5`, `tpms.G` and `tpms.gyroid`, case, spacing).
    pub fn canonical(&self) -> String {
        self.tree.canonical()
    }

    /// The canonical text with `file` paths replaced by `file_key(path)`.
    pub fn canonical_with(&self, file_key: &dyn Fn(&str) -> String) -> String {
        self.tree.canonical_with(file_key)
    }

    /// Paths of the `file` words, in order.
    pub fn files(&self) -> Vec<&str> {
        self.tree.files()
    }

    /// The compiled field, with `file` words resolved by `externals`.
    pub fn field(&self, externals: &dyn ExternalSolids) -> Result<ProgramField, ProgramError> {
        ProgramField::new(&self.tree, externals)
    }
}

/// Contours `field` on the grid of `counts` samples spanning `domain`, with the solid capped
/// on the domain's faces.
pub fn mesh(field: &ProgramField, domain: &Aabb, counts: [usize; 3]) -> Result<Mesh, ContourError> {
    mesh_with_progress(field, domain, counts, &|_| {})
}

/// [`mesh`], calling `progress(n)` as each `n` more layers of cubes (of `counts[2] − 1`) are
/// done.
pub fn mesh_with_progress(
    field: &ProgramField,
    domain: &Aabb,
    counts: [usize; 3],
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Mesh, ContourError> {
    mesh_by(Contouring::Cubes, field, domain, counts, progress)
}

/// [`mesh_with_progress`] by the contouring `method`.
pub fn mesh_by(
    method: Contouring,
    field: &ProgramField,
    domain: &Aabb,
    counts: [usize; 3],
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Mesh, ContourError> {
    if counts.iter().any(|&n| n < 2) {
        return Err(ContourError::TooFewSamples(counts));
    }
    // A side that overflows (bounds near ±1e308, from `offset 1e308`) leaves no spacing: the
    // samples would stand at inf and NaN and the mesh be noise.
    let spacing_ok = |a: usize| {
        let side = domain.max[a] - domain.min[a];
        side.is_finite() && side > 0.0 && side / (counts[a] - 1) as f64 > 0.0
    };
    if !(0..3).all(spacing_ok) {
        let sides: Vec<String> = (0..3)
            .map(|a| format!("[{},{}]", short(domain.min[a]), short(domain.max[a])))
            .collect();
        return Err(ContourError::BadBox(sides.join("×")));
    }
    let grid = Grid::spanning(domain.min, domain.max, counts);
    let sampler = field.sampler(&grid);
    contour_with(method, sampler.as_ref(), &grid, progress)
}

/// A coordinate as a reader wants it in a message: `1e308`, not 309 digits.
fn short(x: f64) -> String {
    if x != 0.0 && !(1e-4..1e9).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}
