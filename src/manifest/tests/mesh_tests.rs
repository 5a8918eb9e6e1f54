//! Tests of mesh inputs in manifests: `mesh`, `placement`, `sample` on cells and `within`,
//! `skin` on outputs — invalid manifests with their exact diagnostics, then valid ones.

use super::*;

pub(super) const MESH_ERR_CASES: &[ErrCase] = &[ErrCase {
    name: "mesh keys without a mesh, unknown extension and sampling, 2D group, skin and within",
    manifest: "[cells.a]\ntpms = \"p\"\nplacement = \"fit\"\n\n[cells.m]\nmesh = \"part.step\"\nsample = \"sdff\"\n\n[cells.n]\nmesh = \"x.stl\"\nsymmetry = \"D4\"\n\n[outputs.o]\ncell = \"a\"\nskin = 1\ndomain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\n\n[outputs.q]\ncell = \"a\"\nover = \"element\"\nwithin = \"part.stl\"\nsamples = 8\n",
    sets: &[],
}];

#[test]
fn invalid_mesh_manifests_render_exactly() {
    check_err_cases(MESH_ERR_CASES);
}

#[test]
fn mesh_files_resolve_against_the_manifest_directory() {
    let manifest = parse_ok(
        "[cells.m]\nmesh = \"meshes/cell.STL\"\nplacement = \"fit\"\nsample = \"containment\"\n\n\
         [outputs.o]\ncell = \"m\"\nwithin = \"part.obj\"\nskin = 0.5\n\
         domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\n",
        &[],
    );
    let CellSource::Mesh(mesh) = &manifest.cells["m"].source else {
        panic!("not a mesh cell");
    };
    assert_eq!(mesh.file.given, "meshes/cell.STL");
    assert_eq!(mesh.file.path, std::path::Path::new("./meshes/cell.STL"));
    assert!(mesh.fit_placement);
    assert_eq!(mesh.sampling, MeshSampling::Containment);
    let out = &manifest.outputs["o"];
    assert_eq!(
        out.within.as_ref().map(|f| f.given.as_str()),
        Some("part.obj")
    );
    assert_eq!(out.skin, Some(0.5));
    // Both files are watched.
    assert_eq!(manifest.inputs.len(), 2);
}
