//! The `contour` stage: samples a cell's formula over an output's domain and contours the
//! solid into a checked, watertight mesh.
//!
//! Shells over a box are contoured as the band between their two levels of the field (see
//! `contour::contour_band`: a wall between two samples is kept), and the thinnest wall the
//! samples saw goes into the payload for the report's warning; so are shells over the cube
//! element. Shells confined to a part (`within`), clipped to the tetrahedron or drawn as
//! planar regions are still contoured from `|f − c| − w/2` (combined with the clip), which can
//! lose walls thinner than a sample spacing: the two-level contourer does not combine with a
//! third surface, and the planar contourer has no two-level variant.

use latticebuild_geom::contour::{
    BandMesh, contour, contour_band, steepest_at_level, steepest_at_level_within,
};
use latticebuild_geom::contour2d::{
    Element2, PlanarRegion, contour_planar, contour_planar_band, contour_planar_box,
    contour_planar_box_band,
};
use latticebuild_geom::element::{Element3, contour_clipped, contour_cube_band};
use latticebuild_geom::field::{Band, Grid, ScalarField, Solid, SolidField, SolidSampler};
use latticebuild_geom::mesh::Mesh;
use latticebuild_geom::mesh_io::Units;
use latticebuild_geom::symmetric::{Group, ReferenceElement};
use latticebuild_geom::within::WithinSampler;

use super::StageError;
use super::artifact::{MeshArtifact, MeshSummary, Planar, ShellSummary};
use super::mesh::part_sdf;
use super::sizing::{DensityStage, Over, cell_field, sized_field, table_of};
use super::symmetric::group_of;
use crate::cache::{KeyBuilder, Param};
use crate::manifest::{GroupSpec, Output, Sizing, Symmetric};
use crate::progress::StageProgress;

/// 3: shells contoured as bands of the field, with their wall in the payload. 4: sized
/// solids (`wall`, `grow`, `volume_fraction`) and their summary in the payload. 5: point
/// distances (tetrahedra, planar regions) projected onto the surface. 6: the tetrahedron and
/// triangle elements contoured on their symmetric subdivisions.
pub const VERSION: u32 = 6;

#[derive(Clone, Debug, PartialEq)]
pub struct ContourStage {
    /// `None`: the input is a formula; `Some`: a fitted cell of this group.
    pub fitted: Option<GroupSpec>,
    /// Clip to the cell's reference element instead of repeating it over a box.
    pub over_element: bool,
    /// The region of a 2D cell over the rectangle `domain` in the plane z = 0.
    pub planar_domain: bool,
    pub domain_min: [f64; 3],
    pub domain_max: [f64; 3],
    pub cell_size: [f64; 3],
    pub solid: Solid,
    pub sizing: Sizing,
    pub samples: [usize; 3],
    /// `within`: the part file's name (its bytes are the second input), and the skin.
    pub within: Option<String>,
    /// The model's unit, which a 3MF part is converted to (set by the graph; `mm` here).
    pub units: Units,
    pub skin: Option<f64>,
}

/// The sizing in a key: its kind, level and graded text (uniform values are the solid's).
pub fn sizing_param(sizing: &Sizing) -> Param {
    let graded = |g: &Option<crate::manifest::NodalValue>| match g {
        None => String::new(),
        Some(crate::manifest::NodalValue::Expr(t)) => format!("expr:{t}"),
        Some(crate::manifest::NodalValue::NodeData(v)) => format!("nodedata:{v}"),
    };
    Param::List(match sizing {
        Sizing::Field => vec![Param::Str("field".into())],
        Sizing::Length { level, graded: g } => vec![
            Param::Str("length".into()),
            Param::F64(*level),
            Param::Str(graded(g)),
        ],
        Sizing::VolumeFraction { level, target } => vec![
            Param::Str("volume_fraction".into()),
            Param::F64(*level),
            match target {
                crate::manifest::Target::Uniform(phi) => Param::F64(*phi),
                crate::manifest::Target::Graded(g) => Param::Str(graded(&Some(g.clone()))),
            },
        ],
    })
}

fn vec3(v: [f64; 3]) -> Param {
    Param::List(v.iter().map(|&x| Param::F64(x)).collect())
}

impl ContourStage {
    pub fn new(output: &Output, fitted: Option<&Symmetric>) -> ContourStage {
        ContourStage {
            fitted: fitted.map(|s| s.group.clone()),
            over_element: output.over_element,
            planar_domain: output.planar_domain,
            domain_min: output.domain_min,
            domain_max: output.domain_max,
            cell_size: output.cell_size,
            solid: output.solid,
            sizing: output.sizing.clone(),
            samples: output.samples,
            within: output.within.as_ref().map(|f| f.given.clone()),
            units: Units::Millimeter,
            skin: output.skin,
        }
    }

    pub fn key_params(&self, key: KeyBuilder) -> KeyBuilder {
        let (solid, offset, thickness) = match self.solid {
            Solid::Inside { offset } => ("inside", offset, 0.0),
            Solid::Outside { offset } => ("outside", offset, 0.0),
            Solid::Shell { thickness } => ("shell", 0.0, thickness),
            Solid::EccentricShell { offset, thickness } => ("eccentric_shell", offset, thickness),
        };
        let key = key
            .param("fitted", self.fitted.is_some())
            .param("over_element", self.over_element)
            .param("planar_domain", self.planar_domain)
            .param("domain.min", vec3(self.domain_min))
            .param("domain.max", vec3(self.domain_max))
            .param("cell_size", vec3(self.cell_size))
            .param("solid", solid)
            .param("offset", offset)
            .param("thickness", thickness)
            .param(
                "samples",
                Param::List(self.samples.iter().map(|&n| Param::U64(n as u64)).collect()),
            )
            // The part's content enters as the second input's hash; its extension picks the
            // reader.
            .param(
                "within",
                self.within
                    .as_deref()
                    .and_then(|w| std::path::Path::new(w).extension())
                    .map_or(String::new(), |e| e.to_string_lossy().to_lowercase()),
            )
            .param("skin", self.skin.unwrap_or(0.0))
            .param("sizing", sizing_param(&self.sizing));
        // Only a 3MF part has a unit to convert (other keys stay as they were).
        let three_mf = self.within.as_deref().is_some_and(|w| {
            std::path::Path::new(w)
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("3mf"))
        });
        match three_mf {
            true => key.param("within_units", self.units.name()),
            false => key,
        }
    }

    /// Whether the stage reads a density table (its last input): to solve a volume fraction.
    pub fn reads_table(&self) -> bool {
        matches!(self.sizing, Sizing::VolumeFraction { .. })
    }

    /// The density stage whose table it reads.
    pub fn density(&self) -> Option<DensityStage> {
        self.reads_table().then(|| DensityStage {
            fitted: self.fitted.clone(),
            projected: false,
            over: if self.over_element {
                Over::Element
            } else {
                Over::Period {
                    dimension: if self.planar_domain { 2 } else { 3 },
                }
            },
            distance: self.sizing.distance_level(&self.solid).map(|level| {
                (
                    level,
                    if self.over_element {
                        [1.0; 3]
                    } else {
                        self.cell_size
                    },
                )
            }),
        })
    }

    /// Model points where a graded volume fraction must lie in (0, 1): a 9-point lattice
    /// per axis over the domain, corners included.
    fn probes(&self) -> Vec<[f64; 3]> {
        const N: usize = 9;
        let at = |a: usize, i: usize| {
            self.domain_min[a]
                + (self.domain_max[a] - self.domain_min[a]) * i as f64 / (N - 1) as f64
        };
        let mut points = Vec::with_capacity(N * N * N);
        for k in 0..N {
            for j in 0..N {
                for i in 0..N {
                    points.push([at(0, i), at(1, j), at(2, k)]);
                }
            }
        }
        points
    }

    /// Number of progress steps [`ContourStage::run`] reports.
    pub fn steps(&self) -> u64 {
        self.samples[2] as u64 - 1
    }

    /// Contours the cell whose formula is `cell_payload`, then checks the mesh.
    /// Contours the cell whose payload is `cell_payload` (a formula, a mesh cell or a fitted
    /// cell), confined to the part whose file bytes are `part` when the output has `within`.
    pub fn run(
        &self,
        cell_payload: &[u8],
        part: Option<&[u8]>,
        table: Option<&[u8]>,
        progress: &dyn StageProgress,
    ) -> Result<MeshArtifact, StageError> {
        let field = cell_field(cell_payload, self.fitted.as_ref())?;
        let table = table.map(table_of).transpose()?;
        let scale = if self.over_element {
            [1.0; 3]
        } else {
            self.cell_size
        };
        let sized = sized_field(
            field,
            self.solid,
            &self.sizing,
            scale,
            table.as_ref(),
            &self.probes(),
        )?;
        // The contourers see the sized field and solid as if they had been given.
        let stage = ContourStage {
            solid: sized.solid,
            ..self.clone()
        };
        let artifact = stage.contour_field(&*sized.field, part, progress)?;
        let sized_shell = sized.summary.is_some();
        Ok(MeshArtifact {
            sizing: sized.summary,
            shell: artifact.shell.map(|shell| ShellSummary {
                sized: sized_shell,
                ..shell
            }),
            ..artifact
        })
    }

    /// Contours `field` as `self.solid` (see [`ContourStage::run`]).
    fn contour_field(
        &self,
        field: &dyn ScalarField,
        part: Option<&[u8]>,
        progress: &dyn StageProgress,
    ) -> Result<MeshArtifact, StageError> {
        progress.phase("contouring");
        let mut shell = None;
        let (mesh, planar) = if self.over_element {
            let group = match &self.fitted {
                Some(spec) => group_of(spec)?,
                None => {
                    return Err(StageError::Internal(
                        "`over = \"element\"` needs a cell with a symmetry".into(),
                    ));
                }
            };
            self.contour_element(field, &group, progress, &mut shell)?
        } else if self.planar_domain {
            self.contour_planar_domain(field, &mut shell)?
        } else {
            let model = Grid::spanning(self.domain_min, self.domain_max, self.samples);
            let cell_grid = model.scaled_down(self.cell_size);
            let lattice = SolidSampler {
                inner: field.sampler(&cell_grid),
                solid: self.solid,
            };
            let advance = |n: usize| progress.advance(n);
            let mesh = match (&self.within, part, self.solid.band()) {
                (Some(given), Some(bytes), _) => {
                    progress.phase("preparing the part");
                    let band = WithinSampler::band_for(&model, self.skin);
                    let sdf = part_sdf(given, bytes, band, self.units)?;
                    if let Some(band) = self.solid.band() {
                        // Contoured from |f − c| − w/2 below: its wall is measured on f apart.
                        progress.phase("measuring the shell's wall");
                        let f = field.sampler(&cell_grid);
                        let middle = band.lo + 0.5 * (band.hi - band.lo);
                        let steepest = steepest_at_level(f.as_ref(), middle);
                        shell = Some(self.shell_summary(band, steepest, self.samples, true));
                    }
                    progress.phase("contouring");
                    let sampler = WithinSampler {
                        lattice: Box::new(lattice),
                        part: sdf.sampler(&model),
                        band,
                        skin: self.skin,
                    };
                    contour(&sampler, &model, &advance)
                }
                (_, _, Some(band)) => {
                    let contoured = contour_band(lattice.inner.as_ref(), band, &model, &advance)?;
                    shell = Some(self.shell_summary(band, contoured.steepest, self.samples, false));
                    Ok(contoured.mesh)
                }
                _ => contour(&lattice, &model, &advance),
            }?;
            (mesh, None)
        };
        if mesh.is_empty() {
            return Err(StageError::EmptySolid(
                self.why_empty(field, part.is_some()),
            ));
        }
        progress.phase("checking the mesh");
        let summary = MeshSummary::of_mesh(&mesh, planar.is_some());
        Ok(MeshArtifact {
            mesh,
            summary,
            planar,
            domain: None,
            tiling: None,
            shell,
            sizing: None,
        })
    }

    /// What the report says of a shell's wall: `steepest` is the largest `|∇f|` per sample
    /// step where the band's middle level crosses the grid (`BandMesh::steepest`); `sampled`
    /// when the shell was contoured from `|f − c| − w/2`.
    fn shell_summary(
        &self,
        band: Band,
        steepest: f64,
        samples: [usize; 3],
        sampled: bool,
    ) -> ShellSummary {
        let thickness = match self.solid {
            Solid::Shell { thickness } | Solid::EccentricShell { thickness, .. } => thickness,
            Solid::Inside { .. } | Solid::Outside { .. } => band.hi - band.lo,
        };
        ShellSummary {
            thickness,
            thinnest_wall: BandMesh::wall(band, steepest),
            samples,
            sampled,
            tiled: false,
            sized: false,
        }
    }

    /// What the report says of a shell whose contourer did not measure it: its wall measured
    /// on `f` over `grid` (cell coordinates), in the cubes whose centre `within` takes, marked
    /// `sampled` (contoured from `|f − c| − w/2`, as over the tetrahedron; callers that
    /// contour the band say otherwise); `None` for other solids.
    fn measured_shell(
        &self,
        field: &dyn ScalarField,
        grid: Grid,
        within: &(dyn Fn([f64; 3]) -> bool + Sync),
    ) -> Option<ShellSummary> {
        let band = self.solid.band()?;
        let middle = band.lo + 0.5 * (band.hi - band.lo);
        let steepest = steepest_at_level_within(field.sampler(&grid).as_ref(), middle, within);
        let [nx, ny, nz] = grid.counts;
        let samples = if nz == 2 { [nx, ny, 1] } else { [nx, ny, nz] };
        Some(self.shell_summary(band, steepest, samples, true))
    }

    /// Why the solid came out empty, with the cell's field range over the output's samples,
    /// so the user sees how far the offset or thickness is from giving a surface. Sampling
    /// again costs one more pass, but only on this failure path.
    fn why_empty(&self, field: &dyn ScalarField, within: bool) -> String {
        let [nx, ny, nz] = self.samples;
        let (min, max, counts) = if self.planar_domain {
            (self.domain_min, self.domain_max, [nx, ny, 1])
        } else {
            (self.domain_min, self.domain_max, [nx, ny, nz])
        };
        let size = if self.over_element {
            [1.0; 3]
        } else {
            self.cell_size
        };
        let grid = Grid {
            origin: std::array::from_fn(|a| min[a] / size[a]),
            spacing: std::array::from_fn(|a| match counts[a] {
                1 => 0.0,
                n => (max[a] - min[a]) / size[a] / (n - 1) as f64,
            }),
            counts,
        };
        let (low, high) = field_range(field, &grid);
        let holds = match self.solid {
            Solid::Inside { offset } => format!("f ≤ {offset}"),
            Solid::Outside { offset } => format!("f ≥ {offset}"),
            Solid::Shell { thickness } => format!("|f| ≤ {}", thickness / 2.0),
            Solid::EccentricShell { offset, thickness } => {
                format!("|f − {offset}| ≤ {}", thickness / 2.0)
            }
        };
        let part = if within {
            " (before it is confined to the `within` part; if the field does cross, the \
             lattice and the part do not overlap)"
        } else {
            ""
        };
        if low.is_nan() {
            return "the output is empty: the cell's field is not a number at any sample".into();
        }
        format!(
            "the output is empty: the solid {holds} holds at no sample of the domain; the \
             cell's field ranges over [{low:.6}, {high:.6}] there{part}"
        )
    }

    /// The region `Φ ≤ 0` of a 2D cell repeated over the rectangle of the domain (model units;
    /// `cell_size` model units per period).
    fn contour_planar_domain(
        &self,
        field: &dyn ScalarField,
        shell: &mut Option<ShellSummary>,
    ) -> Result<(Mesh, Option<Planar>), StageError> {
        let size = self.cell_size;
        // A shell is the band of the field itself; other solids their implicit function.
        let band = self.solid.band();
        let solid = SolidField {
            inner: field,
            solid: if band.is_some() {
                Solid::Inside { offset: 0.0 }
            } else {
                self.solid
            },
        };
        let value = |p: [f64; 2]| {
            let mut out = [0.0];
            solid.eval_points(&[p[0] / size[0]], &[p[1] / size[1]], &[0.0], &mut out);
            out[0]
        };
        let (min, max) = (
            [self.domain_min[0], self.domain_min[1]],
            [self.domain_max[0], self.domain_max[1]],
        );
        let counts = [self.samples[0], self.samples[1]];
        let region = match band {
            Some(band) => contour_planar_box_band(&value, band, min, max, counts),
            None => contour_planar_box(&value, min, max, counts),
        }?;
        let cell_min = [min[0] / size[0], min[1] / size[1]];
        let cell_max = [max[0] / size[0], max[1] / size[1]];
        *shell = self
            .measured_shell(field, planar_grid(cell_min, cell_max, counts), &|_| true)
            .map(|summary| ShellSummary {
                sampled: false,
                ..summary
            });
        let outline = vec![min, [max[0], min[1]], max, [min[0], max[1]]];
        let area = (max[0] - min[0]) * (max[1] - min[1]);
        Ok(planar_output(region, outline, area))
    }

    /// The cell clipped to its reference element: a closed mesh for the cube and the
    /// tetrahedron, a planar region (and its outline, for the SVG) for the square and triangle.
    fn contour_element(
        &self,
        field: &dyn ScalarField,
        group: &Group,
        progress: &dyn StageProgress,
        shell: &mut Option<ShellSummary>,
    ) -> Result<(Mesh, Option<Planar>), StageError> {
        let samples = self.samples[0].max(self.samples[1]);
        let solid = SolidField {
            inner: field,
            solid: self.solid,
        };
        let mut planar = |element: Element2| -> Result<(Mesh, Option<Planar>), StageError> {
            let (lo, hi) = element.bbox();
            let measured = self.measured_shell(field, planar_grid(lo, hi, [samples; 2]), &|_| true);
            // The square's sides are the grid's: a shell is its band. The triangle's third
            // side is a clip, combined with one sampled function.
            let band = self.solid.band().filter(|_| element == Element2::Square);
            *shell = measured.map(|summary| ShellSummary {
                sampled: band.is_none(),
                ..summary
            });
            let raw = |p: [f64; 2]| {
                let mut out = [0.0];
                field.eval_points(&[p[0]], &[p[1]], &[0.0], &mut out);
                out[0]
            };
            let value = |p: [f64; 2]| {
                let mut out = [0.0];
                solid.eval_points(&[p[0]], &[p[1]], &[0.0], &mut out);
                out[0]
            };
            let region = match band {
                Some(band) => contour_planar_band(&raw, band, samples),
                None => contour_planar(&value, element, samples),
            }?;
            Ok(planar_output(region, element.outline(), element.area()))
        };
        let advance = |n: usize| progress.advance(n);
        match group.reference_element() {
            // A shell over the cube: the band of the field, clipped by the box alone.
            Some(ReferenceElement::Cube) => match self.solid.band() {
                Some(band) => {
                    let contoured = contour_cube_band(field, band, samples, &advance)?;
                    *shell =
                        Some(self.shell_summary(band, contoured.steepest, [samples; 3], false));
                    Ok((contoured.mesh, None))
                }
                None => Ok((
                    contour_clipped(&solid, Element3::Cube, samples, &advance)?,
                    None,
                )),
            },
            Some(ReferenceElement::Tetrahedron) => {
                let grid = Grid::spanning([-0.5; 3], [0.5; 3], [samples; 3]);
                let tet = |p: [f64; 3]| Element3::Tetrahedron.signed_distance(p) < 0.0;
                *shell = self.measured_shell(field, grid, &tet);
                Ok((
                    contour_clipped(&solid, Element3::Tetrahedron, samples, &advance)?,
                    None,
                ))
            }
            Some(ReferenceElement::Square) => planar(Element2::Square),
            Some(ReferenceElement::Triangle) => planar(Element2::Triangle),
            None => Err(StageError::DoesNotFit(format!(
                "group {} has no reference element to contour over",
                group.name()
            ))),
        }
    }
}

/// The grid of a planar region's samples from `min` to `max` (cell coordinates), with one
/// sample step in z from the plane (where a 2D cell's gradient is measured).
fn planar_grid(min: [f64; 2], max: [f64; 2], counts: [usize; 2]) -> Grid {
    let step = (max[0] - min[0]) / (counts[0].max(2) - 1) as f64;
    Grid::spanning(
        [min[0], min[1], 0.0],
        [max[0], max[1], step],
        [counts[0], counts[1], 2],
    )
}

/// A planar region's mesh, and its outline inside `frame` (the element or the domain) for the
/// SVG and the report.
fn planar_output(region: PlanarRegion, frame: Vec<[f64; 2]>, area: f64) -> (Mesh, Option<Planar>) {
    let planar = Planar {
        boundary: region.boundary,
        element: frame,
        element_area: area,
        svg: None,
    };
    (region.mesh, Some(planar))
}

/// The smallest and largest value of `field` on `grid` (NaN samples ignored; both NaN when
/// every sample is). The planes are reduced in order, so the result does not depend on the
/// thread count (min and max are exact anyway).
fn field_range(field: &dyn ScalarField, grid: &Grid) -> (f64, f64) {
    use rayon::prelude::*;
    let sampler = field.sampler(grid);
    let ranges: Vec<(f64, f64)> = (0..grid.counts[2])
        .into_par_iter()
        .map(|k| {
            let mut plane = vec![0.0; grid.plane_len()];
            sampler.sample_plane(k, &mut plane);
            plane
                .iter()
                .fold((f64::NAN, f64::NAN), |(lo, hi), &v| (lo.min(v), hi.max(v)))
        })
        .collect();
    ranges
        .into_iter()
        .fold((f64::NAN, f64::NAN), |(lo, hi), (l, h)| {
            (lo.min(l), hi.max(h))
        })
}
