//! The validated manifest. Every reference is resolved, every default filled in, every value
//! in range: code downstream of [`crate::manifest`] never re-checks user input.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::PathBuf;

use latticebuild_geom::field::Solid;
use latticebuild_geom::mesh_io::{Encoding, Format};

/// A validated manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// The manifest file, as given on the command line.
    pub path: PathBuf,
    /// The directory holding the manifest; relative paths in it resolve against this.
    pub root: PathBuf,
    /// Where outputs are written (`[build] out_dir`, default `out/` next to the manifest).
    pub out_dir: PathBuf,
    pub cells: BTreeMap<String, Cell>,
    pub outputs: BTreeMap<String, Output>,
    /// Every external file the manifest references (not the manifest itself), for `watch`.
    pub inputs: Vec<PathBuf>,
}

/// Where a name was written, so errors found late (in the graph) can still point at it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Name {
    pub text: String,
    /// Byte span in the manifest text; `None` for names that came from `--set`.
    pub span: Option<Range<usize>>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    pub name: Name,
    pub source: CellSource,
}

#[derive(Clone, Debug, PartialEq)]
pub enum CellSource {
    /// A surface of the TPMS library, by its canonical name (see `latticebuild_geom::tpms`).
    Tpms(String),
    /// A free-form expression in the cell coordinates x, y, z (period 1 is up to the user).
    Expr(String),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    pub name: Name,
    /// The name of the cell it contours (a key of [`Manifest::cells`]).
    pub cell: String,
    pub domain_min: [f64; 3],
    pub domain_max: [f64; 3],
    /// Model units per period of the cell, per axis.
    pub cell_size: [f64; 3],
    pub solid: Solid,
    /// Sample points per axis over the domain, at least 2 (resolved from `samples` or `voxel`).
    pub samples: [usize; 3],
    /// Formats to write, sorted and without duplicates.
    pub formats: Vec<Format>,
    pub encoding: Encoding,
    /// Output path stem relative to `out_dir` (default: the output's name).
    pub stem: String,
}
