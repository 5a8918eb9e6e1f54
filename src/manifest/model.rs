//! The validated manifest. Every reference is resolved, every default filled in, every value
//! in range: code downstream of [`crate::manifest`] never re-checks user input.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::PathBuf;

use latticebuild_geom::contour::Contouring;
use latticebuild_geom::field::Solid;
use latticebuild_geom::islands::IslandFilter;
use latticebuild_geom::mesh_io::{Encoding, Format};
use latticebuild_geom::scaffold::ElementKind;
use latticebuild_geom::stack_lang::Program;

/// A validated manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// The manifest file, as given on the command line.
    pub path: PathBuf,
    /// The directory holding the manifest; relative paths in it resolve against this.
    pub root: PathBuf,
    /// Where outputs are written (`[build] out_dir`, default `out/` next to the manifest).
    pub out_dir: PathBuf,
    /// What the model's lengths are in (`[build] units`, default `"mm"`), echoed in reports.
    pub units: String,
    /// How much each report measures (`[build] report`, default `"full"`).
    pub report: crate::stages::measure::ReportLevel,
    /// Whether each output gets a PNG preview (`[build] previews`, default true;
    /// `--no-previews` turns them off).
    pub previews: bool,
    /// The previews' width and height in pixels (`[build] preview_size`).
    pub preview_size: [u32; 2],
    pub cells: BTreeMap<String, Cell>,
    pub outputs: BTreeMap<String, Output>,
    /// Outputs whose solid is an SDF program (`sdf = "…"`); their names differ from those of
    /// `outputs` (one `[outputs]` table holds both).
    pub program_outputs: BTreeMap<String, ProgramOutput>,
    /// `[scaffolds.NAME]`: meshes (or generated grids) that cells are tiled into.
    pub scaffolds: BTreeMap<String, Scaffold>,
    /// Outputs tiling a cell into a scaffold (`scaffold = "…"`); their names differ from those
    /// of `outputs` and `program_outputs`.
    pub tiled_outputs: BTreeMap<String, TiledOutput>,
    /// Every external file the manifest references (not the manifest itself), for `watch`.
    pub inputs: Vec<PathBuf>,
    /// Each output's table as read after `--set`/`--unset`, as JSON (a report's `parameters`).
    pub parameters: BTreeMap<String, serde_json::Value>,
    /// Each `[cells.NAME]` and `[scaffolds.NAME]` table as read, the same way (for an
    /// output's resolved parameters, `Manifest::resolved`).
    pub cell_tables: BTreeMap<String, serde_json::Value>,
    pub scaffold_tables: BTreeMap<String, serde_json::Value>,
    /// How many bytes of entries the stage cache may keep (`[cache] max_size`).
    pub cache_max_size: u64,
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
    /// Present when the cell is fitted onto a symmetric Fourier basis (`symmetry = …`), and
    /// always for blends and Minkowski combinations (which take their members' group).
    pub symmetric: Option<Symmetric>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum CellSource {
    /// A surface of the TPMS library, by its canonical name (see `latticebuild_geom::tpms`).
    Tpms(String),
    /// A free-form expression in the cell coordinates x, y, z (period 1 is up to the user).
    Expr(String),
    /// Weighted average of the coefficients of symmetric cells of one group (names of cells;
    /// weights as given here, divided by their sum when blended).
    Blend {
        cells: Vec<String>,
        weights: Vec<f64>,
    },
    /// Minkowski sum or difference of two symmetric cells of one group.
    Minkowski { op: MinkowskiOp, cells: [String; 2] },
    /// The solid of a triangle mesh file, in the cell's reference frame.
    Mesh(MeshCell),
    /// A voxel image of occupancy or signed distance spanning the cell (`voxels = "part.npy"`).
    Voxels(VoxelCell),
    /// Points with outward normals on the cell's surface (`points = "scan.ply"`).
    Points(InputFile),
    /// A loci surface reconstructed from a crystal structure (`crystal = "file.cif"`).
    Crystal(CrystalCell),
    /// A periodic-surface model given term by term (`ps = { terms = [...] }`), moved by
    /// `transform` when given.
    Ps {
        terms: Vec<latticebuild_geom::periodic::PsTerm>,
        transform: Option<PsTransform>,
    },
}

/// `transform = { scale, rotate, translate }` of a `ps` or `crystal` cell: the point map
/// `r ↦ t + R·S·r` in cell coordinates (scale first, then rotate, then translate). The
/// transformed model's value at `r` is the original's at the inverse image of `r`.
/// Validation guarantees finite numbers, non-zero scale factors and a non-zero axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PsTransform {
    /// Per-axis factors `S` (1 when not given).
    pub scale: [f64; 3],
    /// The rotation axis (not necessarily of unit length) and angle in degrees,
    /// counter-clockwise about the axis (right-hand rule); angle 0 when not given.
    pub axis: [f64; 3],
    pub angle_degrees: f64,
    /// `t` (0 when not given).
    pub translate: [f64; 3],
}

impl PsTransform {
    /// The identity's parts, for filling in what is not given.
    pub const IDENTITY: PsTransform = PsTransform {
        scale: [1.0; 3],
        axis: [0.0, 0.0, 1.0],
        angle_degrees: 0.0,
        translate: [0.0; 3],
    };

    /// The rotation `R` (Rodrigues' formula about the unit axis).
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let norm = self.axis.iter().map(|v| v * v).sum::<f64>().sqrt();
        let k = self.axis.map(|v| v / norm);
        // Quarter turns exactly, so they keep integer term vectors integer.
        let quarter = self.angle_degrees / 90.0;
        let (sin, cos) = if quarter == quarter.round() && quarter.abs() < 1e15 {
            match quarter.rem_euclid(4.0) as u8 {
                0 => (0.0, 1.0),
                1 => (1.0, 0.0),
                2 => (0.0, -1.0),
                _ => (-1.0, 0.0),
            }
        } else {
            self.angle_degrees.to_radians().sin_cos()
        };
        let cross = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let identity = if i == j { 1.0 } else { 0.0 };
                cos * identity + sin * cross[i][j] + (1.0 - cos) * k[i] * k[j]
            })
        })
    }

    /// The linear part `R·S`.
    pub fn linear(&self) -> [[f64; 3]; 3] {
        let r = self.rotation();
        std::array::from_fn(|i| std::array::from_fn(|j| r[i][j] * self.scale[j]))
    }

    /// The model moved by this map: exact on the terms (Wang's lemmas). `None` only for a
    /// singular linear part, which validation excludes.
    pub fn apply(
        &self,
        model: &latticebuild_geom::periodic::PsModel,
    ) -> Option<latticebuild_geom::periodic::PsModel> {
        model.transformed(self.linear(), self.translate)
    }

    /// The numbers, in a fixed order, for cache keys: scale, axis, angle, translate.
    pub fn numbers(&self) -> [f64; 10] {
        let [s, a, t] = [self.scale, self.axis, self.translate];
        [
            s[0],
            s[1],
            s[2],
            a[0],
            a[1],
            a[2],
            self.angle_degrees,
            t[0],
            t[1],
            t[2],
        ]
    }
}

/// A cell whose surface passes through the atoms of a crystal file (fractional coordinates:
/// the conventional cell is the period-1 cell). Validation guarantees `tolerance > 0` and
/// `1 ≤ max_scale ≤ 64`.
#[derive(Clone, Debug, PartialEq)]
pub struct CrystalCell {
    /// The CIF or extended XYZ file.
    pub file: InputFile,
    /// Only the atoms of this element (case-insensitive); all atoms when `None`.
    pub species: Option<String>,
    pub tolerance: f64,
    pub max_scale: u32,
    /// Also pass through the periodic images of atoms on the cell's faces.
    pub include_images: bool,
    /// Drop terms greedily to raise the porosity (Wang §5.3).
    pub optimize: bool,
    /// Applied to the reconstructed model's terms.
    pub transform: Option<PsTransform>,
}

/// A file the manifest names as an input: a triangle mesh (`mesh = …`, `within = …`), a
/// crystal (CIF, extended XYZ), a scaffold mesh, or a `file` mesh of an SDF program.
#[derive(Clone, Debug, PartialEq)]
pub struct InputFile {
    /// As written in the manifest (shown in messages).
    pub given: String,
    /// Resolved against the manifest's directory.
    pub path: PathBuf,
    /// Byte span of the value (in the manifest text, or past it in a `--set` argument).
    pub span: Range<usize>,
}

/// A cell whose solid is a triangle mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshCell {
    pub file: InputFile,
    /// `fit`: scale and centre the mesh's bounding box into the reference cell; otherwise the
    /// mesh is already in the reference frame (centre at the origin, size 1).
    pub fit_placement: bool,
    /// What is sampled: signed distances, or only inside (−1) / outside (+1).
    pub sampling: MeshSampling,
}

/// A cell whose solid is a voxel image spanning the cell `[-½, ½]³` (see
/// `latticebuild_geom::voxels` for the conventions).
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelCell {
    /// A `.npy` file, or a `.raw` one read with `raw`.
    pub file: InputFile,
    /// The layout of a raw file (validation guarantees it is given exactly for `.raw`).
    pub raw: Option<RawLayout>,
    pub values: latticebuild_geom::voxels::VoxelValues,
}

/// How a raw voxel file is laid out: x fastest, then y, then z. Validation guarantees every
/// axis is at least 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawLayout {
    pub shape: [u64; 3],
    pub dtype: latticebuild_geom::voxels::VoxelType,
    pub big_endian: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshSampling {
    SignedDistance,
    Containment,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MinkowskiOp {
    Sum,
    Difference,
}

/// How a cell is fitted, constrained and adjusted (docs/method.md §Overview; the sample → fit →
/// constrain
/// stages). Validation guarantees the group is known (or its generators close to a finite
/// group of at most 1000 elements) and `n` is even and at least 4.
#[derive(Clone, Debug, PartialEq)]
pub struct Symmetric {
    pub group: GroupSpec,
    pub n: FitResolution,
    /// For D3 and Td: fill the extended domain by mirroring (default) or sample it as is.
    pub mirror: bool,
    /// Replace the source by the union of its group images before fitting.
    pub symmetrize: bool,
    /// Constrain the cell to meet its element's faces at right angles
    /// (docs/method.md §Face-normal condition).
    pub normal_to_faces: bool,
    /// Dilation (positive grows the solid) in cell units: Φ − offset.
    pub offset: f64,
    /// Swap solid and void: −Φ.
    pub invert: bool,
    /// The least change of the coefficients reaching a volume fraction and/or surface area
    /// (after the other keys).
    pub optimize: Option<Optimize>,
}

/// `optimize = { ... }` of a symmetric cell (docs/method.md §Coefficient optimisation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Optimize {
    /// Target share of the reference element that is solid, in (0, 1).
    pub volume_fraction: Option<f64>,
    /// Target surface-area density: area of the level set inside the reference element per
    /// element volume (perimeter per area in 2D), positive. At least one target is given.
    pub surface_area: Option<f64>,
    pub max_iterations: usize,
    /// Allowed error of the volume fraction.
    pub tolerance: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub enum GroupSpec {
    /// `"D3"`, `"D4"`, `"Td"` or `"Oh"`, canonical spelling.
    Named(String),
    /// Integer generator matrices (rows; 2×2 given as the upper-left block for dimension 2).
    Generators {
        dimension: usize,
        generators: Vec<[[i32; 3]; 3]>,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FitResolution {
    /// Samples per axis of the sampling domain (even, ≥ 4).
    Fixed(usize),
    /// Double N from 32 until the fitted zero set moves less than `tolerance` (cell units),
    /// at most up to `max_n` (a power of two, at least 64, within the group's limit).
    Auto { tolerance: f64, max_n: usize },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    pub name: Name,
    /// The name of the cell it contours (a key of [`Manifest::cells`]).
    pub cell: String,
    /// `over = "element"`: contour the cell clipped to its reference element (square, cube,
    /// triangle or tetrahedron; cell size 1, centroid at the origin) instead of a periodic box.
    /// The domain is then the element's bounding box and `cell_size` is 1.
    pub over_element: bool,
    /// The domain was given as `[x, y]` corners: the region `Φ ≤ 0` of a 2D cell over a
    /// rectangle in the plane z = 0 (a planar mesh and an SVG), not a box.
    pub planar_domain: bool,
    pub domain_min: [f64; 3],
    pub domain_max: [f64; 3],
    /// Model units per period of the cell, per axis.
    pub cell_size: [f64; 3],
    pub solid: Solid,
    /// What the solid's numbers are: field values, model units, or a volume fraction to solve.
    pub sizing: Sizing,
    /// Sample points per axis over the domain, at least 2 (resolved from `samples` or `voxel`).
    pub samples: [usize; 3],
    /// Formats to write, sorted and without duplicates.
    pub formats: Vec<Format>,
    pub encoding: Encoding,
    /// Output path stem relative to `out_dir` (default: the output's name).
    pub stem: String,
    /// `within = "part.stl"`: the lattice is intersected with the solid of this mesh (model
    /// units).
    pub within: Option<InputFile>,
    /// `skin = t`: a closed skin of thickness `t` (model units) along the part's surface;
    /// only with `within`.
    pub skin: Option<f64>,
    /// `keep = "largest"`, `min_island_volume = V`: the pieces to remove (inactive: none).
    pub islands: IslandFilter,
}

/// An output whose solid is an SDF program in the Cesogen stack language (`sdf = "…"`).
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramOutput {
    pub name: Name,
    /// The program, parsed and checked (`latticebuild_geom::stack_lang`).
    pub program: Program,
    /// The mesh files its `file` words name, once each in order of first use; each span is
    /// the path's word in the program string.
    pub files: Vec<InputFile>,
    /// `bounds = { min, max }`; `None`: the program's own bounds, found when it is contoured.
    pub bounds: Option<[[f64; 3]; 2]>,
    pub resolution: ProgramResolution,
    /// `contour = "cubes"` (the default) or `"tetrahedra"`.
    pub contouring: Contouring,
    /// Formats to write, sorted and without duplicates.
    pub formats: Vec<Format>,
    pub encoding: Encoding,
    /// Output path stem relative to `out_dir` (default: the output's name).
    pub stem: String,
    /// The pieces to remove, as for [`Output::islands`].
    pub islands: IslandFilter,
}

/// How finely an SDF output is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProgramResolution {
    /// Samples per axis, each at least 2.
    Counts([usize; 3]),
    /// Grid spacing in model units; the counts follow from the box ([`voxel_samples`]), which
    /// without `bounds` is known only when the program is contoured.
    Voxel(f64),
}

/// Most samples along one axis (a guard against typos such as `voxel = 1e-9`).
pub const MAX_SAMPLES_PER_AXIS: usize = 100_000;

/// Voxel ratios this close (relatively) to a whole number count as that number, so that
/// `1.1 / 0.1 = 11.000000000000002` gives 11 intervals, not 12.
const VOXEL_ROUNDING: f64 = 1e-9;

/// Samples per axis for grid spacing `voxel` over the box: `ceil(extent / voxel) + 1` (at
/// least 2), or the first axis that would need more than [`MAX_SAMPLES_PER_AXIS`].
pub fn voxel_samples(min: [f64; 3], max: [f64; 3], voxel: f64) -> Result<[usize; 3], usize> {
    let mut counts = [0; 3];
    for axis in 0..3 {
        let ratio = (max[axis] - min[axis]) / voxel;
        let intervals = if (ratio - ratio.round()).abs() <= VOXEL_ROUNDING * ratio {
            ratio.round()
        } else {
            ratio.ceil()
        };
        // Compared as floats first: a tiny voxel can give a ratio beyond `usize`.
        if intervals + 1.0 > MAX_SAMPLES_PER_AXIS as f64 {
            return Err(axis);
        }
        // An axis without extent (z of a 2D element) still gets 2 samples.
        counts[axis] = (intervals as usize).max(1) + 1;
    }
    Ok(counts)
}

/// A scaffold: the mesh whose elements a cell is tiled into.
#[derive(Clone, Debug, PartialEq)]
pub struct Scaffold {
    pub name: Name,
    pub source: ScaffoldSource,
    pub continuity: Continuity,
}

/// `continuity`: how smoothly the tiled field joins across element faces. Validation
/// guarantees `C1` only on a grid of quad or hex elements (a mesh file's kind is checked by the
/// stage).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Continuity {
    /// The isoparametric maps: the field is continuous, its gradient jumps across faces.
    #[default]
    C0,
    /// Cubic Hermite maps through shared corner derivatives (`geom::scaffold::SmoothMap`).
    C1,
}

impl Continuity {
    pub fn key(self) -> &'static str {
        match self {
            Continuity::C0 => "c0",
            Continuity::C1 => "c1",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum ScaffoldSource {
    /// A mesh file (`mesh = "…"`: Gmsh, VTK, Abaqus, OBJ/OFF); its element kind is known only
    /// once it is read.
    Mesh(InputFile),
    /// A generated box (`grid = { … }`).
    Grid(ScaffoldGrid),
}

/// `grid = { min, max, divisions, element }`. Validation guarantees `min < max` and at least
/// one division on every axis the element uses (z is ignored by quad and tri grids), and at
/// most [`MAX_GRID_ELEMENTS`] elements.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaffoldGrid {
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub divisions: [usize; 3],
    /// `Hex8`, `Tet4`, `Quad4` or `Tri3`.
    pub element: ElementKind,
}

/// The group a cell tiled into elements of `kind` must have: Oh for hexahedra, Td for
/// tetrahedra, D4 for quadrilaterals, D3 for triangles (their reference elements' groups).
pub fn tiling_group(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Hex8 | ElementKind::Hex20 | ElementKind::Hex27 => "Oh",
        ElementKind::Tet4 | ElementKind::Tet10 => "Td",
        ElementKind::Quad4 | ElementKind::Quad8 | ElementKind::Quad9 => "D4",
        ElementKind::Tri3 | ElementKind::Tri6 => "D3",
    }
}

/// Most elements of a generated grid.
pub const MAX_GRID_ELEMENTS: usize = 10_000_000;

/// An output tiling a symmetric cell (or a transition between two) into every element of a
/// scaffold. Validation guarantees the scaffold and cells exist, the cells have named groups
/// (one group, for a transition), the group matches a grid's element, `2 ≤ resolution ≤ 256`
/// and `skin > 0`; `thicken` is positive and, on a grid, only on a 2D one (with no `skin`).
#[derive(Clone, Debug, PartialEq)]
pub struct TiledOutput {
    pub name: Name,
    /// A key of [`Manifest::scaffolds`].
    pub scaffold: String,
    /// The cell (a key of [`Manifest::cells`]); with a transition, the cell at weight 0.
    pub cell: String,
    pub transition: Option<TiledTransition>,
    /// The solid; a graded `thickness` or `offset` replaces its own value node by node.
    pub solid: Solid,
    /// What the solid's numbers are (a graded `wall`, `grow` or `volume_fraction` is here).
    pub sizing: Sizing,
    pub thickness: Option<NodalValue>,
    pub offset: Option<NodalValue>,
    /// Samples per element edge.
    pub resolution: usize,
    /// A closed skin of this thickness (model units) along the scaffold's boundary.
    pub skin: Option<f64>,
    /// For a 2D scaffold, how its tiled region becomes a solid (`None`: the region itself).
    pub thicken: Option<Thicken>,
    pub formats: Vec<Format>,
    pub encoding: Encoding,
    pub stem: String,
    /// The pieces to remove, as for [`Output::islands`].
    pub islands: IslandFilter,
}

/// How the region tiled into a 2D scaffold is made a closed solid (lengths in model units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Thicken {
    /// `extrude = h`: a planar region swept by `h` along +z.
    Extrude(f64),
    /// `thickness_normal = h`: `±h/2` along the surface's normals.
    ThicknessNormal(f64),
}

impl Thicken {
    /// The manifest key.
    pub fn key(self) -> &'static str {
        match self {
            Thicken::Extrude(_) => "extrude",
            Thicken::ThicknessNormal(_) => "thickness_normal",
        }
    }

    pub fn length(self) -> f64 {
        match self {
            Thicken::Extrude(h) | Thicken::ThicknessNormal(h) => h,
        }
    }
}

/// `cell = { blend = [a, b], by = … }`: `Φ = (1 − w) Φ_a + w Φ_b`, with `w` clamped to [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct TiledTransition {
    /// The cell at weight 1.
    pub to: String,
    pub by: NodalValue,
}

/// What an output's solid is sized by (docs/manifest.md, "Sizes in model units").
///
/// With [`Sizing::Length`] the [`Solid`]'s numbers are model units on the distance field
/// `h = (f − level) / |∇f|`: `Shell { thickness }` is the wall, `Inside { offset }` the
/// growth `grow`, and `Outside { offset }` minus it (the solid `h ≥ −grow`). With
/// [`Sizing::VolumeFraction`] they are placeholders, replaced by what the build solves.
#[derive(Clone, Debug, PartialEq)]
pub enum Sizing {
    /// `offset` and `thickness`: values of the cell's field.
    Field,
    /// `wall` or `grow`, in model units; `graded` replaces the solid's value point by point
    /// (an expression in x, y, z, or node data on a scaffold).
    Length {
        level: f64,
        graded: Option<NodalValue>,
    },
    /// `volume_fraction`: the level (`inside`/`outside`, field values) or the wall (shells,
    /// model units about `level`) that gives this solid fraction, from the cell's table.
    VolumeFraction { level: f64, target: Target },
}

impl Sizing {
    /// The level of the field whose distance the solid is measured on, when it is.
    pub fn distance_level(&self, solid: &Solid) -> Option<f64> {
        match self {
            Sizing::Field => None,
            Sizing::Length { level, .. } => Some(*level),
            Sizing::VolumeFraction { level, .. } => solid.band().map(|_| *level),
        }
    }
}

/// A volume fraction, uniform or graded.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    Uniform(f64),
    Graded(NodalValue),
}

/// A value given at the scaffold's nodes (or, for an expression, anywhere in the model).
#[derive(Clone, Debug, PartialEq)]
pub enum NodalValue {
    /// An expression in the model coordinates x, y, z (checked by the expression parser).
    Expr(String),
    /// `"nodedata:NAME"`: a `$NodeData` view (VTK point data) of the scaffold file.
    NodeData(String),
}
