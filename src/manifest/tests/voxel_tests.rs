//! Tests of voxel cells in manifests: `voxels`, `shape`, `dtype`, `byte_order`, `values`,
//! `threshold` — invalid manifests with their exact diagnostics, then valid ones.

use super::*;
use latticebuild_geom::voxels::{VoxelType, VoxelValues};

const OUTPUT: &str =
    "\n[outputs.o]\ncell = \"a\"\ndomain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\n";

pub(super) const VOXEL_ERR_CASES: &[ErrCase] = &[
    ErrCase {
        name: "voxel keys without voxels, unknown voxel and point extensions and a 2D group",
        manifest: "[cells.a]\ntpms = \"p\"\nvalues = \"distance\"\nshape = [2, 2, 2]\n\n\
                   [cells.b]\nvoxels = \"scan.tif\"\n\n[cells.c]\nvoxels = \"scan.npy\"\n\
                   symmetry = \"D4\"\n\n[cells.d]\npoints = \"scan.pcd\"\n\n\
                   [cells.e]\npoints = \"scan.xyz\"\nthreshold = 3\n\n[outputs.o]\ncell = \"a\"\n\
                   domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\n",
        sets: &[],
    },
    ErrCase {
        name: "a raw file without its layout, and raw layout keys on a npy file",
        manifest: "[cells.a]\nvoxels = \"scan.raw\"\n\n[cells.b]\nvoxels = \"scan.npy\"\n\
                   dtype = \"uint8\"\nbyte_order = \"big\"\n\n[outputs.o]\ncell = \"a\"\n\
                   domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\n",
        sets: &[],
    },
    ErrCase {
        name: "bad raw shape, dtype, byte order, values and a threshold on distances",
        manifest: "[cells.a]\nvoxels = \"scan.raw\"\nshape = [64, 0, 2.5]\ndtype = \"uint32\"\n\
                   byte_order = \"bigg\"\n\n[cells.b]\nvoxels = \"scan.npy\"\nvalues = \"occupncy\"\n\n\
                   [cells.c]\nvoxels = \"scan.npy\"\nvalues = \"distance\"\nthreshold = 0.5\n\n\
                   [outputs.o]\ncell = \"a\"\ndomain = { min = [0, 0, 0], max = [1, 1, 1] }\n\
                   samples = 8\n",
        sets: &[],
    },
];

#[test]
fn invalid_voxel_manifests_render_exactly() {
    check_err_cases(VOXEL_ERR_CASES);
}

#[test]
fn voxel_cells_read_their_layout_and_values() {
    let manifest = parse_ok(
        &format!(
            "[cells.a]\nvoxels = \"ct/scan.RAW\"\nshape = [64, 32, 16]\ndtype = \"int16\"\n\
             byte_order = \"big\"\nthreshold = 1200\nsymmetry = \"Oh\"\n{OUTPUT}"
        ),
        &[],
    );
    let CellSource::Voxels(cell) = &manifest.cells["a"].source else {
        panic!("not a voxel cell");
    };
    assert_eq!(cell.file.path, std::path::Path::new("./ct/scan.RAW"));
    assert_eq!(
        cell.raw,
        Some(RawLayout {
            shape: [64, 32, 16],
            dtype: VoxelType::I16,
            big_endian: true
        })
    );
    assert_eq!(
        cell.values,
        VoxelValues::Occupancy {
            threshold: Some(1200.0)
        }
    );
    assert_eq!(manifest.inputs.len(), 1);

    let manifest = parse_ok(
        &format!("[cells.a]\nvoxels = \"d.npy\"\nvalues = \"distance\"\n{OUTPUT}"),
        &[],
    );
    let CellSource::Voxels(cell) = &manifest.cells["a"].source else {
        panic!("not a voxel cell");
    };
    assert_eq!((cell.raw, cell.values), (None, VoxelValues::Distance));

    let manifest = parse_ok(
        &format!("[cells.a]\npoints = \"scan/part.PLY\"\nsymmetry = \"Td\"\n{OUTPUT}"),
        &[],
    );
    let CellSource::Points(file) = &manifest.cells["a"].source else {
        panic!("not a point cell");
    };
    assert_eq!(file.path, std::path::Path::new("./scan/part.PLY"));
    assert_eq!(manifest.inputs.len(), 1);
}
