//! Tests of `transform` on `ps` and `crystal` cells: invalid manifests with their exact
//! rendered diagnostics, then a valid one with the transform it must give.

use super::*;

const PS: &str = "ps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }";

pub(super) const TRANSFORM_ERR_CASES: &[ErrCase] = &[
    ErrCase {
        name: "transform on a cell that is neither ps nor crystal",
        manifest: "[cells.a]\ntpms = \"p\"\ntransform = { translate = [0.5, 0, 0] }\n",
        sets: &[],
    },
    ErrCase {
        name: "transform that is not a table, and an empty transform",
        manifest: "[cells.a]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = [1, 0, 0]\n\n\
                   [cells.b]\ncrystal = \"FAU.cif\"\ntransform = {}\n",
        sets: &[],
    },
    ErrCase {
        name: "misspelled transform parts, with suggestions",
        manifest: "[cells.a]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\n\
                   transform = { translation = [1, 0, 0], rotate = { axis = [0, 0, 1], angel = 90 } }\n",
        sets: &[],
    },
    ErrCase {
        name: "zero and wrongly typed scale factors",
        manifest: "[cells.a]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = { scale = 0 }\n\n\
                   [cells.b]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = { scale = [1, 0.0, \"2\"] }\n\n\
                   [cells.c]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = { scale = [1, 2] }\n",
        sets: &[],
    },
    ErrCase {
        name: "a zero rotation axis, a missing angle and a rotate that is not a table",
        manifest: "[cells.a]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = { rotate = { axis = [0, 0, 0], angle = 90 } }\n\n\
                   [cells.b]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = { rotate = { axis = [0, 0, 1] } }\n\n\
                   [cells.c]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = { rotate = 90 }\n",
        sets: &[],
    },
    ErrCase {
        name: "non finite transform numbers and a translate of the wrong length",
        manifest: "[cells.a]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\n\
                   transform = { translate = [inf, 0, 0], scale = nan, rotate = { axis = [0, 0, 1], angle = -inf } }\n\n\
                   [cells.b]\nps = { terms = [{ moment = 1, vector = [1, 0, 0] }] }\ntransform = { translate = [1, 0] }\n",
        sets: &[],
    },
];

#[test]
fn invalid_transforms_render_exactly() {
    check_err_cases(TRANSFORM_ERR_CASES);
}

#[test]
fn transforms_validate_with_defaults_for_the_parts_not_given() {
    let text = format!(
        "[cells.p]\n{PS}\ntransform = {{ scale = 2, rotate = {{ axis = [0, 0, 3], angle = 90 }} }}\n\n\
         [cells.q]\n{PS}\ntransform = {{ translate = [0.5, 0, -1], scale = [1, -1, 0.5] }}\n\n\
         [cells.c]\ncrystal = \"FAU.cif\"\ntransform = {{ translate = [0.5, 0, 0] }}\n"
    );
    let manifest = parse_ok(&text, &[]);
    let transform_of = |name: &str| match &manifest.cells[name].source {
        CellSource::Ps { transform, .. } => *transform,
        CellSource::Crystal(c) => c.transform,
        other => panic!("not a ps or crystal cell: {other:?}"),
    };
    let p = transform_of("p").expect("a transform");
    assert_eq!(p.scale, [2.0; 3]);
    assert_eq!((p.axis, p.angle_degrees), ([0.0, 0.0, 3.0], 90.0));
    assert_eq!(p.translate, [0.0; 3]);
    // r ↦ t + R·S·r: (1, 0, 0) scaled to (2, 0, 0), then a quarter turn about z to (0, 2, 0).
    let l = p.linear();
    let image: Vec<f64> = (0..3).map(|i| l[i][0]).collect();
    assert_eq!(image, [0.0, 2.0, 0.0], "a quarter turn is exact");
    let q = transform_of("q").expect("a transform");
    assert_eq!((q.scale, q.translate), ([1.0, -1.0, 0.5], [0.5, 0.0, -1.0]));
    assert_eq!(q.angle_degrees, 0.0);
    let c = transform_of("c").expect("a transform");
    assert_eq!(
        c,
        PsTransform {
            translate: [0.5, 0.0, 0.0],
            ..PsTransform::IDENTITY
        }
    );
}
