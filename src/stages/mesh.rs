//! Triangle-mesh cells: the `cell` stage of a mesh cell, which reads, places and packs the
//! mesh (a `file` node's bytes, see [`super::file`]) for every stage that samples a cell.
//!
//! Invariants:
//! - This module never opens paths: the mesh arrives as the bytes of its `file` node.
//! - A mesh cell's payload is the placed soup, little-endian `f64` positions and `u32` indices
//!   behind a magic and the sampling mode: a pure function of the file's bytes and the cell's
//!   keys. Reading errors name the file and the line, byte offset or face of the problem.
//! - A mesh cell's field is its solid repeated with period 1 (the union of the copies, by the
//!   geometry crate's `PeriodicMeshSdf`): continuous across cell faces, where the nearest
//!   surface may be a neighbouring copy's and a strut's end caps meet the next cell's.

use latticebuild_geom::field::ScalarField;
use latticebuild_geom::mesh_io::Units;
use latticebuild_geom::mesh_read::{self, Format, TriangleSoup};
use latticebuild_geom::mesh_sdf::{MeshSdf, Mode, PeriodicMeshSdf, SdfOptions};

use super::StageError;
use crate::cache::KeyBuilder;
use crate::manifest::{MeshCell, MeshSampling};

pub const VERSION: u32 = 1;

const MESH_CELL_MAGIC: &[u8; 8] = b"LBMCEL01";

/// The reader format of a file name (validated by the manifest: one of the known extensions).
fn format_of(given: &str) -> Result<Format, StageError> {
    std::path::Path::new(given)
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Format::from_extension)
        .ok_or_else(|| StageError::NoMeshExtension {
            given: given.to_string(),
        })
}

/// Reads the soup of a mesh file's bytes, in the format its content shows (its extension
/// when the content does not tell); errors name the file. A 3MF's coordinates are taken as
/// written: a mesh cell is in cell units, whatever unit the package names.
pub fn read_soup(given: &str, bytes: &[u8]) -> Result<TriangleSoup, StageError> {
    let extension = format_of(given)?.extension();
    mesh_read::read_auto(bytes, Some(extension))
        .map_err(|e| StageError::geometry_of(format!("cannot read `{given}`"), e))
}

/// [`read_soup`] in the model's `units`: a 3MF package's coordinates are converted from its
/// unit (the other formats have none).
pub fn read_soup_in(given: &str, bytes: &[u8], units: Units) -> Result<TriangleSoup, StageError> {
    let extension = format_of(given)?.extension();
    mesh_read::read_auto_in(bytes, Some(extension), units)
        .map_err(|e| StageError::geometry_of(format!("cannot read `{given}`"), e))
}

/// `cell` of a mesh cell: the soup in the cell's reference frame, with its sampling mode.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshCellStage {
    pub cell: MeshCell,
}

impl MeshCellStage {
    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        // The file's content enters as the input hash; its extension picks the reader.
        let format = format_of(&self.cell.file.given)
            .map(|f| f.extension())
            .unwrap_or("");
        key.param("format", format)
            .param(
                "placement",
                if self.cell.fit_placement {
                    "fit"
                } else {
                    "reference"
                },
            )
            .param(
                "sample",
                match self.cell.sampling {
                    MeshSampling::SignedDistance => "sdf",
                    MeshSampling::Containment => "containment",
                },
            )
    }

    pub fn run(&self, file: &[u8]) -> Result<Vec<u8>, StageError> {
        let mut soup = read_soup(&self.cell.file.given, file)?;
        if self.cell.fit_placement {
            place_in_unit_cell(&mut soup);
        }
        Ok(encode(&soup, self.cell.sampling))
    }
}

/// Scales the soup uniformly and centres it so that its bounding box fits the reference cell
/// `[-½, ½]³` (the largest extent becomes 1), which also holds the tetrahedron's bounding box.
fn place_in_unit_cell(soup: &mut TriangleSoup) {
    let Some((lo, hi)) = soup.bounds() else {
        return;
    };
    let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    if extent <= 0.0 {
        return;
    }
    let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
    for p in &mut soup.positions {
        *p = std::array::from_fn(|a| (p[a] - centre[a]) / extent);
    }
}

fn encode(soup: &TriangleSoup, sampling: MeshSampling) -> Vec<u8> {
    let mut out =
        Vec::with_capacity(8 + 1 + 16 + soup.positions.len() * 24 + soup.triangles.len() * 12);
    out.extend_from_slice(MESH_CELL_MAGIC);
    out.push(match sampling {
        MeshSampling::SignedDistance => 0,
        MeshSampling::Containment => 1,
    });
    out.extend_from_slice(&(soup.positions.len() as u64).to_le_bytes());
    out.extend_from_slice(&(soup.triangles.len() as u64).to_le_bytes());
    for p in &soup.positions {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in &soup.triangles {
        for i in t {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// Whether a cell payload is a mesh cell's (the others are formula text).
pub fn is_mesh_cell(payload: &[u8]) -> bool {
    payload.starts_with(MESH_CELL_MAGIC)
}

fn decode(payload: &[u8]) -> Result<(TriangleSoup, MeshSampling), StageError> {
    let bad = || StageError::malformed("mesh cell");
    let rest = payload.strip_prefix(MESH_CELL_MAGIC).ok_or_else(bad)?;
    let (&mode, rest) = rest.split_first().ok_or_else(bad)?;
    let count = |b: &[u8]| -> Result<usize, StageError> {
        Ok(u64::from_le_bytes(b.try_into().map_err(|_| bad())?) as usize)
    };
    let (np, nt) = (
        count(rest.get(..8).ok_or_else(bad)?)?,
        count(rest.get(8..16).ok_or_else(bad)?)?,
    );
    let body = &rest[16..];
    if body.len() != np * 24 + nt * 12 {
        return Err(bad());
    }
    let (pos, tri) = body.split_at(np * 24);
    let f = |c: &[u8]| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]));
    let u = |c: &[u8]| u32::from_le_bytes(c.try_into().unwrap_or([0; 4]));
    let positions = pos
        .chunks_exact(24)
        .map(|c| [f(&c[..8]), f(&c[8..16]), f(&c[16..])])
        .collect();
    let triangles = tri
        .chunks_exact(12)
        .map(|c| [u(&c[..4]), u(&c[4..8]), u(&c[8..])])
        .collect();
    let sampling = match mode {
        0 => MeshSampling::SignedDistance,
        _ => MeshSampling::Containment,
    };
    Ok((
        TriangleSoup {
            positions,
            triangles,
        },
        sampling,
    ))
}

/// The field of a mesh cell's payload, repeated with period 1 (the cell is the unit cube
/// centred at the origin, like every cell): the signed distance to the union of the mesh's
/// periodic copies (or its containment), continuous across the cell's faces.
pub fn mesh_cell_field(payload: &[u8]) -> Result<Box<dyn ScalarField>, StageError> {
    let (soup, sampling) = decode(payload)?;
    let options = SdfOptions {
        mode: match sampling {
            MeshSampling::SignedDistance => Mode::SignedDistance,
            MeshSampling::Containment => Mode::Containment,
        },
        ..SdfOptions::default()
    };
    let sdf = PeriodicMeshSdf::new(&soup, options)
        .map_err(|e| StageError::geometry_of("the cell's mesh", e))?;
    Ok(Box::new(sdf))
}

/// The part of `within`: its signed distance in model units (`units`), exact within `band`
/// of the surface and clamped beyond (the sign stays exact everywhere).
pub fn part_sdf(given: &str, bytes: &[u8], band: f64, units: Units) -> Result<MeshSdf, StageError> {
    let soup = read_soup_in(given, bytes, units)?;
    let options = SdfOptions {
        band: Some(band),
        ..SdfOptions::default()
    };
    MeshSdf::new(&soup, options)
        .map_err(|e| StageError::geometry_of(format!("the part `{given}`"), e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use latticebuild_geom::expr;
    use latticebuild_geom::field::Grid;

    /// A UV sphere (every vertex on the sphere) as a soup, counter-clockwise from outside.
    fn sphere(centre: [f64; 3], radius: f64, rings: usize, segments: usize) -> TriangleSoup {
        let point = |i: usize, j: usize| -> [f64; 3] {
            let theta = std::f64::consts::PI * i as f64 / rings as f64;
            let phi = std::f64::consts::TAU * (j % segments) as f64 / segments as f64;
            let (s, c) = (theta.sin(), theta.cos());
            // Poles exact, so that the surface closes.
            let s = if i == 0 || i == rings { 0.0 } else { s };
            [
                centre[0] + radius * s * phi.cos(),
                centre[1] + radius * s * phi.sin(),
                centre[2] + radius * c,
            ]
        };
        let mut soup = TriangleSoup {
            positions: Vec::new(),
            triangles: Vec::new(),
        };
        for i in 0..rings {
            for j in 0..segments {
                let quad = [
                    point(i, j),
                    point(i + 1, j),
                    point(i + 1, j + 1),
                    point(i, j + 1),
                ];
                for [a, b, c] in [[0, 1, 2], [0, 2, 3]] {
                    let n = soup.positions.len() as u32;
                    soup.positions.extend([quad[a], quad[b], quad[c]]);
                    soup.triangles.push([n, n + 1, n + 2]);
                }
            }
        }
        soup
    }

    /// The field sampled plane by plane on `grid`, as the contour stage samples it.
    fn sample(field: &dyn ScalarField, grid: &Grid) -> Vec<f64> {
        let sampler = field.sampler(grid);
        let plane = grid.plane_len();
        let mut out = vec![0.0; plane * grid.counts[2]];
        for (k, chunk) in out.chunks_mut(plane).enumerate() {
            sampler.sample_plane(k, chunk);
        }
        out
    }

    const CENTRE: [f64; 3] = [0.27, 0.1, -0.06];
    const RADIUS: f64 = 0.3;

    /// An off-centre ball that crosses the cell's +x face, as a mesh cell and as the
    /// expression of its periodic copies' signed distance (the balls are disjoint, so the
    /// least of their distances is the union's, inside too), on a grid over the whole cell,
    /// both faces of every axis included. The facets lie inside the ball and outside the
    /// ball of their least distance to the centre, `r_in`, so the mesh's field lies between
    /// the two balls' fields: `0 ≤ mesh − expression ≤ r − r_in`.
    #[test]
    fn a_mesh_cell_is_its_solids_periodic_signed_distance_on_the_whole_cell() {
        let soup = sphere(CENTRE, RADIUS, 24, 48);
        let r_in = soup
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| soup.positions[i as usize]);
                let (u, v) = (
                    [0, 1, 2].map(|k| b[k] - a[k]),
                    [0, 1, 2].map(|k| c[k] - a[k]),
                );
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                if len == 0.0 {
                    return RADIUS; // a pole's sliver: no plane
                }
                (0..3).map(|k| (a[k] - CENTRE[k]) * n[k]).sum::<f64>().abs() / len
            })
            .fold(f64::INFINITY, f64::min);
        let sagitta = RADIUS - r_in;
        assert!(sagitta > 0.0 && sagitta < 3e-3, "{sagitta}");

        let mesh = mesh_cell_field(&encode(&soup, MeshSampling::SignedDistance)).expect("field");
        let mut copies = Vec::new();
        for i in -1..=1 {
            for j in -1..=1 {
                for k in -1..=1 {
                    let c = [
                        CENTRE[0] + i as f64,
                        CENTRE[1] + j as f64,
                        CENTRE[2] + k as f64,
                    ];
                    copies.push(format!(
                        "sqrt((x - {})^2 + (y - {})^2 + (z - {})^2)",
                        c[0], c[1], c[2]
                    ));
                }
            }
        }
        let text = format!("min({}) - {RADIUS}", copies.join(", "));
        let ball = expr::compile(&text).expect("expression");

        let grid = Grid::spanning([-0.5; 3], [0.5; 3], [25; 3]);
        let (got, want) = (sample(&*mesh, &grid), sample(&ball, &grid));
        let mut worst = 0.0f64;
        for (n, (g, w)) in got.iter().zip(&want).enumerate() {
            let d = g - w;
            assert!(
                (-1e-12..=sagitta + 1e-12).contains(&d),
                "sample {n}: mesh {g}, expression {w}"
            );
            worst = worst.max(d);
        }
        // The faceting shows: the bound is not loose by orders of magnitude.
        assert!(worst > 0.1 * sagitta, "{worst} vs {sagitta}");
    }

    /// The samples on a cell face equal those on the opposite face, on every axis: the field
    /// is continuous across the faces (an off-centre ball that crosses the +x face, and the
    /// example's struts, whose end caps lie on the faces).
    #[test]
    fn a_mesh_cells_field_is_the_same_on_opposite_faces() {
        let cross = read_soup(
            "cross.obj",
            include_bytes!("../../examples/meshes/cross.obj"),
        )
        .expect("cross");
        for soup in [sphere(CENTRE, RADIUS, 24, 48), cross] {
            let field =
                mesh_cell_field(&encode(&soup, MeshSampling::SignedDistance)).expect("field");
            let n = 33;
            let grid = Grid::spanning([-0.5; 3], [0.5; 3], [n; 3]);
            let values = sample(&*field, &grid);
            let at = |i: usize, j: usize, k: usize| values[(k * n + j) * n + i];
            for a in 0..n {
                for b in 0..n {
                    for (low, high) in [
                        (at(0, a, b), at(n - 1, a, b)),
                        (at(a, 0, b), at(a, n - 1, b)),
                        (at(a, b, 0), at(a, b, n - 1)),
                    ] {
                        assert!(
                            (low - high).abs() <= 1e-12,
                            "({a}, {b}): {low} on the low face, {high} on the high face"
                        );
                    }
                }
            }
        }
    }

    /// The struts cross the cell faces: at a face, inside a strut, the field is the depth in
    /// the strut (its half-width 0.12 on the axis), not zero at the end caps that meet there.
    #[test]
    fn a_strut_through_a_cell_face_is_solid_at_the_face() {
        let cross = read_soup(
            "cross.obj",
            include_bytes!("../../examples/meshes/cross.obj"),
        )
        .expect("cross");
        let field = mesh_cell_field(&encode(&cross, MeshSampling::SignedDistance)).expect("field");
        let points = [
            [-0.5, 0.0, 0.0],
            [0.5, 0.03, 0.0],
            [0.0, 0.5, -0.02],
            [0.01, 0.0, -0.5],
        ];
        let mut out = [0.0; 4];
        field.eval_points(
            &points.map(|p| p[0]),
            &points.map(|p| p[1]),
            &points.map(|p| p[2]),
            &mut out,
        );
        let expected = [-0.12, -0.09, -0.1, -0.11];
        for (got, want) in out.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{out:?} vs {expected:?}");
        }
    }

    /// `n = "auto"` on the shipped mesh cell, through the stages a build runs: the fit it
    /// returns is the fixed-N fit (`sample` then `fit`) at the N it chose, bit for bit, since
    /// its nested samples are those of sampling that size afresh. Oh converges (N = 32 at
    /// tolerance 0.1); Td (tetrahedron corners mirrored, evaluated point by point in both
    /// paths) stops at `max_n` = 64 under a tolerance it cannot meet.
    #[test]
    fn automatic_n_on_a_mesh_cell_is_the_fixed_n_fit_at_the_n_it_chose() {
        use super::super::symmetric::{FitStage, FittedPayload, SampleStage};
        use crate::manifest::{FitResolution, GroupSpec, Symmetric};

        let cross = read_soup(
            "cross.obj",
            include_bytes!("../../examples/meshes/cross.obj"),
        )
        .expect("cross");
        let cell = encode(&cross, MeshSampling::SignedDistance);
        for (group, tolerance, n_expected, converged) in
            [("Oh", 0.1, 32, true), ("Td", 1e-9, 64, false)]
        {
            let spec = |n| Symmetric {
                group: GroupSpec::Named(group.to_string()),
                n,
                mirror: true,
                symmetrize: false,
                normal_to_faces: false,
                offset: 0.0,
                invert: false,
                optimize: None,
            };
            let auto = FitStage {
                spec: spec(FitResolution::Auto {
                    tolerance,
                    max_n: 64,
                }),
            };
            let found =
                FittedPayload::from_bytes(&auto.run(&cell).expect("auto fit")).expect("payload");
            let summary = found.auto.clone().expect("auto summary");
            assert_eq!((summary.n, summary.converged), (n_expected, converged));
            let fixed_spec = spec(FitResolution::Fixed(n_expected));
            let samples = SampleStage {
                spec: fixed_spec.clone(),
                n: n_expected,
            }
            .run(&cell)
            .expect("samples");
            let fixed = FitStage { spec: fixed_spec }
                .run(&samples)
                .expect("fixed fit");
            let fixed = FittedPayload::from_bytes(&fixed).expect("payload");
            assert_eq!(found.n, fixed.n, "{group}");
            assert!(
                found.coefficients == fixed.coefficients,
                "{group}: the coefficients of automatic N differ from the fixed-N fit's"
            );
        }
    }
}
