//! What a build will cost, estimated from the manifest before any stage runs, and the check
//! that refuses a build the machine cannot hold: `samples = 100000` would ask for an 80 GB
//! plane of samples, a 10-million-element grid at resolution 12 for a terabyte of STL.
//!
//! The estimates are upper-end guesses from sizes alone (samples, cell size, elements ×
//! resolution), not measurements: a contoured surface is taken as dense as a TPMS at the
//! output's cell size (about 3.5 / cell size of area per unit volume, twice that for a sheet,
//! plus the whole box's faces), marching cubes as about 3 triangles per h² of surface, a tiled
//! element as at most 16 res² triangles (4 res² for a triangle or tetrahedron). Calibrated on
//! the shipped examples, where they come out 1 to 5 times the real figure.
//!
//! Invariants: no geometry runs and no file is written here (a mesh scaffold is read to count
//! its elements); a refusal names the output's key that drives the estimate, the estimate and
//! what the machine has.

use std::path::Path;

use serde::Serialize;

use crate::manifest::{
    FitResolution, Manifest, Output, ProgramResolution, ScaffoldSource, TiledOutput,
};
use latticebuild_geom::field::Solid;
use latticebuild_geom::mesh_io::{Encoding, Format};
use latticebuild_geom::scaffold::ElementKind;

/// One output's estimated peak memory and bytes written (its files and its cache entry).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    pub memory_bytes: u64,
    pub disk_bytes: u64,
    pub triangles: u64,
    /// The manifest key that drives the estimate, as `outputs.NAME.samples`.
    #[serde(skip)]
    pub key: String,
}

/// Bytes per triangle of each format (a closed mesh has about half as many vertices as
/// triangles), measured on the writers' output.
fn bytes_per_triangle(format: Format, encoding: Encoding) -> f64 {
    let ascii = encoding == Encoding::Ascii;
    match format {
        Format::Stl if ascii => 270.0,
        Format::Stl => 50.0,
        Format::Ply if ascii => 40.0,
        Format::Ply => 19.0,
        Format::Obj | Format::Off => 45.0,
        Format::Vtk if ascii => 45.0,
        Format::Vtk => 22.0,
        // Points (12 bytes a vertex), three Int64 indices, an offset and a type.
        Format::Vtu => 39.0,
        // The deflated XML, about a quarter of its 60 bytes a triangle.
        Format::ThreeMf => 20.0,
    }
}

/// A mesh held in memory and checked: positions, indices and the check's edge tables.
const MEMORY_PER_TRIANGLE: f64 = 64.0;
/// The cache entry of a mesh (f32 positions, u32 indices).
const CACHE_PER_TRIANGLE: f64 = 18.0;
/// A tiling streams its chunks: a bounded working set whatever the scaffold's size.
const TILING_WORKING_SET: f64 = 512.0 * 1024.0 * 1024.0;

fn files_bytes(triangles: f64, formats: &[Format], encoding: Encoding) -> f64 {
    let files: f64 = formats
        .iter()
        .map(|&f| bytes_per_triangle(f, encoding))
        .sum();
    triangles * (files + CACHE_PER_TRIANGLE)
}

/// Triangles of a contoured box `min..max` at `samples`, for a surface with about `density`
/// area per unit volume.
fn box_triangles(min: [f64; 3], max: [f64; 3], samples: [usize; 3], density: f64) -> f64 {
    let extent: [f64; 3] = std::array::from_fn(|a| (max[a] - min[a]).abs());
    if extent.contains(&0.0) {
        // A planar region (z = 0): filled with about two triangles per sample square.
        let flat = (0..3).filter(|&a| extent[a] > 0.0);
        return 2.0 * flat.map(|a| samples[a] as f64).product::<f64>();
    }
    let volume: f64 = extent.iter().product();
    let faces = 2.0 * (extent[0] * extent[1] + extent[1] * extent[2] + extent[0] * extent[2]);
    let h2: f64 = (0..3)
        .map(|a| (extent[a] / (samples[a].max(2) - 1) as f64).powi(2))
        .fold(f64::INFINITY, f64::min)
        .max(f64::MIN_POSITIVE);
    3.0 * (density * volume + faces) / h2
}

/// Memory of the contourer's planes: two planes of samples and vertex ids per chunk, one
/// chunk per core. Cores, not `-j`: reports are the same bytes for any thread count.
fn plane_bytes(samples: [usize; 3]) -> f64 {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    threads * samples[0] as f64 * samples[1] as f64 * 40.0
}

fn sheet_factor(solid: &Solid) -> f64 {
    match solid {
        Solid::Shell { .. } | Solid::EccentricShell { .. } => 2.0,
        _ => 1.0,
    }
}

fn plain(manifest: &Manifest, name: &str, o: &Output) -> Estimate {
    let period = o.cell_size.iter().copied().fold(f64::INFINITY, f64::min);
    let density = 3.5 / period.max(f64::MIN_POSITIVE) * sheet_factor(&o.solid);
    let triangles = box_triangles(o.domain_min, o.domain_max, o.samples, density);
    // A fitted cell's FFT grid: three complex N³ arrays.
    let fit = manifest
        .cells
        .get(&o.cell)
        .and_then(|c| c.symmetric.as_ref())
        .map_or(0.0, |s| match s.n {
            FitResolution::Fixed(n) => 48.0 * (n as f64).powi(3),
            FitResolution::Auto { .. } => 0.0,
        });
    let memory = (plane_bytes(o.samples) + triangles * MEMORY_PER_TRIANGLE).max(fit);
    Estimate {
        memory_bytes: saturate(memory),
        disk_bytes: saturate(files_bytes(triangles, &o.formats, o.encoding)),
        triangles: saturate(triangles),
        key: format!("outputs.{name}.samples"),
    }
}

fn sdf(name: &str, o: &crate::manifest::ProgramOutput) -> Option<Estimate> {
    // Without `bounds`, a voxel size gives counts only once the program's box is known.
    let (min, max, samples) = match (o.resolution, o.bounds) {
        (ProgramResolution::Counts(samples), Some([min, max])) => (min, max, samples),
        (ProgramResolution::Counts(samples), None) => ([0.0; 3], [1.0; 3], samples),
        (ProgramResolution::Voxel(voxel), Some([min, max])) => {
            let samples = crate::manifest::voxel_samples(min, max, voxel).ok()?;
            (min, max, samples)
        }
        (ProgramResolution::Voxel(_), None) => return None,
    };
    Some(box_estimate(
        &format!("outputs.{name}.samples"),
        [min, max],
        samples,
        &o.formats,
        o.encoding,
    ))
}

/// An SDF program contoured over `bounds` at `samples` (the `sdf` outputs and command). A
/// program's lattice scale is not known here: the surface is taken as a sheet with four
/// periods across the box's smallest side.
pub fn box_estimate(
    key: &str,
    [min, max]: [[f64; 3]; 2],
    samples: [usize; 3],
    formats: &[Format],
    encoding: Encoding,
) -> Estimate {
    let extent = (0..3)
        .map(|a| (max[a] - min[a]).abs())
        .fold(f64::INFINITY, f64::min);
    let density = 3.5 * 2.0 / (extent / 4.0).max(f64::MIN_POSITIVE);
    let triangles = box_triangles(min, max, samples, density);
    Estimate {
        memory_bytes: saturate(plane_bytes(samples) + triangles * MEMORY_PER_TRIANGLE),
        disk_bytes: saturate(files_bytes(triangles, formats, encoding)),
        triangles: saturate(triangles),
        key: key.to_string(),
    }
}

/// Elements of a scaffold: a grid's by its divisions, a file's by reading it (`None` when it
/// cannot be read: the tile stage then reports why).
fn scaffold_elements(source: &ScaffoldSource) -> Option<(ElementKind, u64)> {
    match source {
        ScaffoldSource::Grid(g) => {
            let dims = g.element.dimension();
            let per_box = match g.element {
                ElementKind::Tet4 => 6,
                ElementKind::Tri3 => 2,
                _ => 1,
            };
            let boxes: u64 = g.divisions[..dims].iter().map(|&d| d as u64).product();
            Some((g.element, boxes * per_box))
        }
        ScaffoldSource::Mesh(file) => {
            let bytes = std::fs::read(&file.path).ok()?;
            let extension = Path::new(&file.given)
                .extension()
                .map(|e| e.to_string_lossy().to_lowercase());
            let scaffold = latticebuild_geom::scaffold::read_scaffold(
                &bytes,
                &file.given,
                extension.as_deref(),
            )
            .ok()?;
            Some((scaffold.kind, scaffold.element_count() as u64))
        }
    }
}

fn tiled(manifest: &Manifest, name: &str, o: &TiledOutput) -> Option<Estimate> {
    let (kind, elements) = scaffold_elements(&manifest.scaffolds.get(&o.scaffold)?.source)?;
    let per_element = match kind {
        ElementKind::Tet4 | ElementKind::Tet10 | ElementKind::Tri3 | ElementKind::Tri6 => 4.0,
        _ => 16.0,
    } * (o.resolution as f64).powi(2)
        * sheet_factor(&o.solid);
    let triangles = elements as f64 * per_element;
    // A 2D region is made whole in memory; a 3D tiling streams.
    let memory = if kind.dimension() == 2 {
        triangles * MEMORY_PER_TRIANGLE
    } else {
        TILING_WORKING_SET + elements as f64 * 256.0
    };
    Some(Estimate {
        memory_bytes: saturate(memory),
        disk_bytes: saturate(files_bytes(triangles, &o.formats, o.encoding)),
        triangles: saturate(triangles),
        key: format!("outputs.{name}.resolution"),
    })
}

fn saturate(x: f64) -> u64 {
    if x.is_finite() {
        x.min(u64::MAX as f64) as u64
    } else {
        u64::MAX
    }
}

/// The estimate of every output named in `targets` (all when empty), by name.
pub fn estimate(manifest: &Manifest, targets: &[String]) -> Vec<(String, Estimate)> {
    let wanted = |name: &str| targets.is_empty() || targets.iter().any(|t| t == name);
    let mut all = Vec::new();
    for (name, o) in manifest.outputs.iter().filter(|(n, _)| wanted(n)) {
        all.push((name.clone(), plain(manifest, name, o)));
    }
    for (name, o) in manifest.program_outputs.iter().filter(|(n, _)| wanted(n)) {
        all.extend(sdf(name, o).map(|e| (name.clone(), e)));
    }
    for (name, o) in manifest.tiled_outputs.iter().filter(|(n, _)| wanted(n)) {
        all.extend(tiled(manifest, name, o).map(|e| (name.clone(), e)));
    }
    all
}

/// What the machine has: memory the kernel says is available, and free disk where the
/// outputs go.
#[derive(Clone, Copy, Debug)]
pub struct Machine {
    pub memory_bytes: Option<u64>,
    pub disk_bytes: Option<u64>,
}

impl Machine {
    pub fn probe(out_dir: &Path) -> Machine {
        Machine {
            memory_bytes: available_memory(),
            disk_bytes: free_disk(out_dir),
        }
    }
}

/// `MemAvailable` from /proc/meminfo (Linux); `None` elsewhere.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Free bytes (for unprivileged users) on the file system that holds `dir`, or its nearest
/// existing ancestor.
#[cfg(unix)]
pub fn free_disk(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let absolute = std::path::absolute(dir).ok()?;
    let existing = absolute.ancestors().find(|p| p.exists())?;
    let c_path = std::ffi::CString::new(existing.as_os_str().as_bytes()).ok()?;
    // SAFETY: `statvfs` fills the zeroed struct for a NUL-terminated path we own.
    unsafe {
        let mut stat: libc::statvfs = std::mem::zeroed();
        if libc::statvfs(c_path.as_ptr(), &mut stat) != 0 {
            return None;
        }
        Some((stat.f_bavail as u64).saturating_mul(stat.f_frsize as u64))
    }
}

#[cfg(not(unix))]
pub fn free_disk(_dir: &Path) -> Option<u64> {
    None
}

/// `1.2 GB`, `80 GB`, `350 MB`.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e12 {
        format!("{:.1} TB", b / 1e12)
    } else if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else {
        format!("{:.0} MB", (b / 1e6).max(1.0))
    }
}

/// The refusals: every output whose estimate exceeds the machine's memory, and the outputs'
/// bytes together against the free disk. Empty when the build fits.
pub fn refusals(estimates: &[(String, Estimate)], machine: Machine) -> Vec<String> {
    let mut found = Vec::new();
    if let Some(memory) = machine.memory_bytes {
        for (name, e) in estimates.iter().filter(|(_, e)| e.memory_bytes > memory) {
            found.push(format!(
                "output `{name}` would need about {} of memory (`{}`: about {} triangles), \
                 but {} is available",
                human(e.memory_bytes),
                e.key,
                e.triangles,
                human(memory)
            ));
        }
    }
    if let Some(disk) = machine.disk_bytes {
        let total: u64 = estimates
            .iter()
            .map(|(_, e)| e.disk_bytes)
            .fold(0, u64::saturating_add);
        if total > disk {
            let mut biggest: Vec<&(String, Estimate)> = estimates.iter().collect();
            biggest.sort_by_key(|(_, e)| std::cmp::Reverse(e.disk_bytes));
            let named: Vec<String> = biggest
                .iter()
                .take(3)
                .map(|(n, e)| format!("`{n}` {} (`{}`)", human(e.disk_bytes), e.key))
                .collect();
            found.push(format!(
                "the outputs would write about {} (files and cache; {}), but the disk has {} \
                 free",
                human(total),
                named.join(", "),
                human(disk)
            ));
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate_of(triangles: u64, memory: u64, disk: u64) -> (String, Estimate) {
        (
            "o".into(),
            Estimate {
                memory_bytes: memory,
                disk_bytes: disk,
                triangles,
                key: "outputs.o.samples".into(),
            },
        )
    }

    #[test]
    fn a_box_estimate_is_within_a_few_times_a_real_gyroid() {
        // A gyroid over 2 periods at 200 samples contours to 1,012,412 triangles.
        let t = box_triangles([0.0; 3], [2.0; 3], [200; 3], 3.5);
        assert!((1.0e6..5.0e6).contains(&t), "{t}");
    }

    #[test]
    fn refusals_name_the_key_and_both_sizes() {
        let machine = Machine {
            memory_bytes: Some(8_000_000_000),
            disk_bytes: Some(10_000_000_000),
        };
        assert!(refusals(&[estimate_of(1, 1_000_000, 1_000_000)], machine).is_empty());
        let found = refusals(&[estimate_of(5, 80_000_000_000, 1)], machine);
        assert_eq!(found.len(), 1);
        assert!(found[0].contains("80.0 GB") && found[0].contains("8.0 GB"));
        assert!(found[0].contains("outputs.o.samples"));
        let found = refusals(&[estimate_of(5, 1, 20_000_000_000)], machine);
        assert!(found[0].contains("20.0 GB") && found[0].contains("10.0 GB free"));
    }
}
