//! Tests of mesh inputs in manifests: `mesh`, `placement`, `sample` on cells and `within`,
//! `skin` on outputs — invalid manifests with their exact diagnostics, then valid ones.

use super::*;

const MESH_ERR_CASES: &[ErrCase] = &[ErrCase {
    name: "mesh keys without a mesh, unknown extension and sampling, 2D group, skin and within",
    manifest: "[cells.a]\ntpms = \"p\"\nplacement = \"fit\"\n\n[cells.m]\nmesh = \"part.step\"\nsample = \"sdff\"\n\n[cells.n]\nmesh = \"x.stl\"\nsymmetry = \"D4\"\n\n[outputs.o]\ncell = \"a\"\nskin = 1\ndomain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\n\n[outputs.q]\ncell = \"a\"\nover = \"element\"\nwithin = \"part.stl\"\nsamples = 8\n",
    sets: &[],
    expected: "\
error: `cells.a.placement` applies only to mesh cells
 --> lattice.toml:3:1
  |
3 | placement = \"fit\"
  | ^^^^^^^^^ cell `a` has no `mesh`
  |
  = help: remove `placement`, or give the cell a `mesh = \"part.stl\"`

error: `cells.m.mesh` is not a mesh file the readers know
 --> lattice.toml:6:8
  |
6 | mesh = \"part.step\"
  |        ^^^^^^^^^^^ `.step`; expected `stl`, `obj`, `ply`, `off`
  |
  = help: convert the mesh to STL, OBJ, PLY or OFF

error: unknown way of sampling `sdff` in `cells.m.sample`
 --> lattice.toml:7:10
  |
7 | sample = \"sdff\"
  |          ^^^^^^ expected one of `sdf`, `containment`
  |
  = help: did you mean `sdf`?

error: 2D group for a mesh cell in `cells.n.symmetry`
  --> lattice.toml:11:12
   |
11 | symmetry = \"D4\"
   |            ^^^^ `D4` is a 2D group, but a triangle mesh bounds a 3D solid
   |
   = help: use `symmetry = \"Oh\"` or `\"Td\"`

error: `outputs.o.skin` applies only with `within`
  --> lattice.toml:15:1
   |
15 | skin = 1
   | ^^^^ there is no part to put a skin on
   |
   = help: add `within = \"part.stl\"`, or remove `skin`

error: `outputs.q.within` does not apply here
  --> lattice.toml:22:1
   |
22 | within = \"part.stl\"
   | ^^^^^^ the output is one cell over its element (`over = \"element\"`)
   |
   = help: remove `over`, and give the `domain` to fill

error: could not load `lattice.toml` due to 6 previous errors
",
}];

#[test]
fn invalid_mesh_manifests_render_exactly() {
    for case in MESH_ERR_CASES {
        let actual = render_errors(case.manifest, case.sets);
        assert_eq!(actual, case.expected, "case `{}`", case.name);
    }
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
