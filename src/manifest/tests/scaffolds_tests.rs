//! Tests of tiling in manifests: `[scaffolds.NAME]` (`mesh`, `grid`) and outputs with a
//! `scaffold` — what valid tables produce, and where and what each error says.

use super::*;

const CELLS: &str = "\
[cells.p]
tpms = \"p\"
symmetry = \"Oh\"

[cells.w]
expr = \"cos(tau*x) + cos(tau*y) + cos(tau*z)\"
symmetry = \"Oh\"

[cells.t]
tpms = \"p\"
symmetry = \"Td\"

[cells.plain]
tpms = \"gyroid\"
";

fn with_cells(rest: &str) -> String {
    format!("{CELLS}\n{rest}")
}

/// The rendered errors, each fragment required in order of appearance.
fn assert_errors(text: &str, fragments: &[&str]) {
    let rendered = render_errors(text, &[]);
    let mut at = 0;
    for fragment in fragments {
        match rendered[at..].find(fragment) {
            Some(i) => at += i + fragment.len(),
            None => panic!("`{fragment}` not found (in order) in:\n{rendered}"),
        }
    }
}

#[test]
fn a_grid_and_a_mesh_scaffold_with_every_tiling_key() {
    let manifest = parse_ok(
        &with_cells(
            "[scaffolds.g]\ngrid = { min = [0, 0, 0], max = [3, 2, 1], divisions = [3, 2, 1], element = \"hex\" }\n\n\
             [scaffolds.m]\nmesh = \"meshes/part.MSH\"\n\n\
             [outputs.a]\nscaffold = \"g\"\ncell = { blend = [\"p\", \"w\"], by = \"x / 3\" }\n\
             solid = \"eccentric_shell\"\nthickness = \"0.1 + 0.1 * z\"\noffset = 0.2\nskin = 0.05\nresolution = 16\n\n\
             [outputs.b]\nscaffold = \"m\"\ncell = \"t\"\nsolid = \"shell\"\nthickness = \"nodedata:thick\"\nformats = [\"ply\"]\n",
        ),
        &[],
    );
    let ScaffoldSource::Grid(grid) = &manifest.scaffolds["g"].source else {
        panic!("not a grid");
    };
    assert_eq!(grid.divisions, [3, 2, 1]);
    assert_eq!(grid.max, [3.0, 2.0, 1.0]);
    assert_eq!(grid.element, latticebuild_geom::scaffold::ElementKind::Hex8);
    let ScaffoldSource::Mesh(file) = &manifest.scaffolds["m"].source else {
        panic!("not a mesh");
    };
    assert_eq!(file.path, Path::new("./meshes/part.MSH"));
    let a = &manifest.tiled_outputs["a"];
    assert_eq!(a.cell, "p");
    let transition = a.transition.as_ref().expect("transition");
    assert_eq!(transition.to, "w");
    assert_eq!(transition.by, NodalValue::Expr("x / 3".into()));
    assert_eq!(
        a.solid,
        Solid::EccentricShell {
            offset: 0.2,
            thickness: 0.0
        }
    );
    assert_eq!(a.thickness, Some(NodalValue::Expr("0.1 + 0.1 * z".into())));
    assert_eq!(
        (a.offset.clone(), a.skin, a.resolution),
        (None, Some(0.05), 16)
    );
    let b = &manifest.tiled_outputs["b"];
    assert_eq!(b.thickness, Some(NodalValue::NodeData("thick".into())));
    assert_eq!(b.resolution, 12, "the default resolution");
    assert_eq!(b.formats, vec![Format::Ply]);
    assert!(manifest.outputs.is_empty());
    // The scaffold file is watched (and checked on load).
    assert_eq!(manifest.inputs, vec![PathBuf::from("./meshes/part.MSH")]);
}

#[test]
fn a_cell_of_the_wrong_group_for_a_grid_says_which_is_needed() {
    assert_errors(
        &with_cells(
            "[scaffolds.g]\ngrid = { min = [0, 0, 0], max = [1, 1, 1], divisions = 2, element = \"tet\" }\n\n\
             [outputs.o]\nscaffold = \"g\"\ncell = \"p\"\n",
        ),
        &[
            "error: `outputs.o.cell` does not fit the scaffold's elements",
            "--> lattice.toml:21:8",
            "cell `p` has group `Oh`, but tet4 elements need `Td`",
        ],
    );
}

#[test]
fn unknown_scaffolds_and_cells_without_symmetry_are_errors() {
    assert_errors(
        &with_cells(
            "[scaffolds.block]\ngrid = { min = [0, 0, 0], max = [1, 1, 1], divisions = 2, element = \"hex\" }\n\n\
             [outputs.o]\nscaffold = \"blok\"\ncell = \"plain\"\n\n\
             [outputs.q]\nscaffold = \"block\"\ncell = { blend = [\"p\", \"t\"], by = \"x\" }\n",
        ),
        &[
            "unknown scaffold `blok` in `outputs.o.scaffold`",
            "did you mean `block`?",
            "`outputs.o.cell` needs a cell with the element's symmetry",
            "cell `plain` has no `symmetry`",
            "the cells of `outputs.q.cell.blend` have different groups",
            "`p` is `Oh`, `t` is `Td`",
        ],
    );
}

#[test]
fn bad_grids_name_the_axis_and_the_value() {
    assert_errors(
        "[scaffolds.a]\ngrid = { min = [0, 0, 0], max = [1, 0, 1], divisions = [2, 0, 2], element = \"hexa\" }\n\n\
         [scaffolds.b]\nmesh = \"b.step\"\n\n\
         [scaffolds.c]\ngrid = { min = [0, 0, 0], max = [1, 1, 1], divisions = 100000, element = \"tet\" }\n\n\
         [scaffolds.d]\n",
        &[
            "`scaffolds.a.grid.divisions` must be at least 1 on every axis",
            "unknown grid element `hexa` in `scaffolds.a.grid.element`",
            "did you mean `hex`?",
            "`scaffolds.b.mesh` is not a scaffold mesh file the readers know",
            "`.step`; expected `msh`, `vtk`, `vtu`, `inp`, `obj`, `off`",
            "`scaffolds.c.grid.divisions` gives too many elements",
            "missing key `mesh` or `grid` in scaffold `d`",
        ],
    );
    assert_errors(
        "[scaffolds.a]\ngrid = { min = [0, 0, 0], max = [1, 0, 1], divisions = 2, element = \"hex\" }\n",
        &[
            "`scaffolds.a.grid.max` must be greater than `min` on every axis",
            "--> lattice.toml:2:37",
            "not greater than min y `0`",
        ],
    );
}

#[test]
fn tiled_outputs_check_their_own_keys() {
    assert_errors(
        &with_cells(
            "[scaffolds.g]\ngrid = { min = [0, 0, 0], max = [1, 1, 1], divisions = 2, element = \"hex\" }\n\n\
             [outputs.o]\nscaffold = \"g\"\ncell = { blend = [\"p\", \"w\"], by = \"x +* 2\" }\n\
             domain = { min = [0, 0, 0], max = [1, 1, 1] }\nsamples = 8\nresolution = 1\n\
             thickness = 0.2\noffset = \"nodedata:off\"\nskin = -1\n",
        ),
        &[
            "invalid expression in `outputs.o.cell.by`",
            "--> lattice.toml:21:39",
            "`outputs.o.domain` does not apply to an output with a `scaffold`",
            "`outputs.o.samples` does not apply to an output with a `scaffold`",
            "write `resolution = 12` (samples per element edge)",
            "`outputs.o.resolution` must be between 2 and 256",
            "`outputs.o.thickness` applies only to shells",
            "`outputs.o.offset` reads node data, but the scaffold is a generated grid",
            "`outputs.o.skin` must be greater than 0",
        ],
    );
}

#[test]
fn extrude_and_thickness_normal_need_a_2d_grid_and_exclude_each_other() {
    let quad = "[cells.q]\nexpr = \"cos(tau*x) + cos(tau*y)\"\nsymmetry = \"D4\"\n\n\
                [scaffolds.plate]\ngrid = { min = [0, 0], max = [4, 2], divisions = [4, 2], element = \"quad\" }\n\n\
                [scaffolds.block]\ngrid = { min = [0, 0, 0], max = [1, 1, 1], divisions = 2, element = \"hex\" }\n\n";
    let ok = parse_ok(
        &format!(
            "{quad}[outputs.a]\nscaffold = \"plate\"\ncell = \"q\"\nextrude = 0.5\n\n\
         [outputs.b]\nscaffold = \"plate\"\ncell = \"q\"\nthickness_normal = 2\n"
        ),
        &[],
    );
    assert_eq!(ok.tiled_outputs["a"].thicken, Some(Thicken::Extrude(0.5)));
    assert_eq!(
        ok.tiled_outputs["b"].thicken,
        Some(Thicken::ThicknessNormal(2.0))
    );
    assert_errors(
        &format!(
            "{quad}[outputs.a]\nscaffold = \"plate\"\ncell = \"q\"\nextrude = 0.5\nthickness_normal = 1\n\n\
             [outputs.b]\nscaffold = \"block\"\ncell = \"q\"\nextrude = 1\n\n\
             [outputs.c]\nscaffold = \"plate\"\ncell = \"q\"\nskin = 0.1\nextrude = -1\n"
        ),
        &[
            "both `extrude` and `thickness_normal` given in output `a`",
            "--> lattice.toml:15:20",
            "`outputs.b.cell` does not fit the scaffold's elements",
            "`outputs.b.extrude` applies only to 2D scaffolds",
            "the grid's elements are hex8",
            "`outputs.c.skin` does not apply to a 2D scaffold",
            "`outputs.c.extrude` must be greater than 0",
        ],
    );
}

#[test]
fn two_dimensional_grids_need_d4_or_d3_cells() {
    assert_errors(
        "[cells.q]\nexpr = \"cos(tau*x) + cos(tau*y)\"\nsymmetry = \"D4\"\n\n\
         [cells.r]\nexpr = \"cos(2*tau*x) + cos(2*tau*y)\"\nsymmetry = \"D3\"\n\n\
         [scaffolds.quads]\ngrid = { min = [0, 0], max = [4, 2], divisions = 2, element = \"quad\" }\n\n\
         [scaffolds.tris]\ngrid = { min = [0, 0], max = [4, 2], divisions = 2, element = \"tri\" }\n\n\
         [outputs.a]\nscaffold = \"quads\"\ncell = \"r\"\n\n\
         [outputs.b]\nscaffold = \"tris\"\ncell = \"q\"\n",
        &[
            "`outputs.a.cell` does not fit the scaffold's elements",
            "cell `r` has group `D3`, but quad4 elements need `D4`",
            "`outputs.b.cell` does not fit the scaffold's elements",
            "cell `q` has group `D4`, but tri3 elements need `D3`",
        ],
    );
}

#[test]
fn continuity_is_c0_unless_c1_is_asked_and_c1_needs_quads_or_hexahedra() {
    let manifest = parse_ok(
        &with_cells(
            "[scaffolds.g]\ngrid = { min = [0, 0, 0], max = [3, 2, 1], divisions = 1, element = \"hex\" }\n\
             continuity = \"c1\"\n\n\
             [scaffolds.q]\ngrid = { min = [0, 0], max = [3, 2], divisions = 1, element = \"quad\" }\n\
             continuity = \"c0\"\n\n\
             [scaffolds.m]\nmesh = \"part.msh\"\n",
        ),
        &[],
    );
    let continuity = |name: &str| manifest.scaffolds[name].continuity;
    assert_eq!(continuity("g"), Continuity::C1);
    assert_eq!(continuity("q"), Continuity::C0);
    assert_eq!(continuity("m"), Continuity::C0, "the default");
    assert_errors(
        &with_cells(
            "[scaffolds.g]\ngrid = { min = [0, 0, 0], max = [1, 1, 1], divisions = 1, element = \"tri\" }\n\
             continuity = \"c1\"\n\n\
             [scaffolds.h]\nmesh = \"part.msh\"\ncontinuity = \"smooth\"\n",
        ),
        &[
            "`scaffolds.g.continuity = \"c1\"` needs quad or hex elements, but the grid has tri3",
            "--> lattice.toml:18:14",
            "unknown continuity `smooth` in `scaffolds.h.continuity`",
            "expected one of",
        ],
    );
}
