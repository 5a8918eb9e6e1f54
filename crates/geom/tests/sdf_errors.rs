//! Every kind of bad program gives an error naming the word at fault, with the exact text a
//! user reads; and the canonical form reads back to itself.

use crate::common;

use common::sdf_sphere::SphereFile;
use std::collections::HashMap;

use latticebuild_geom::stack_lang::{
    IncludeResolver, Included, NoExternalSolids, Program, ProgramError, expand,
};

fn error(program: &str) -> String {
    match Program::parse_str(program) {
        Ok(p) => panic!("`{program}` parsed as `{}`", p.canonical()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn stack_errors() {
    assert_eq!(
        error("ball intersection"),
        "word 2 `intersection`: intersection needs two solids, found one"
    );
    assert_eq!(
        error("union"),
        "word 1 `union`: union needs two solids, found none"
    );
    assert_eq!(
        error("scale 2"),
        "word 1 `scale`: scale needs a solid, found none"
    );
    assert_eq!(
        error("ball cylinder box union"),
        "word 1 `ball`: the solid made here is never used: the program ends with 2 solids on \
         the stack; join them with `union`, `intersection` or `difference`"
    );
    assert_eq!(
        error("  "),
        "the program is empty: start it with a solid such as `ball`, `tpms.gyroid` or \
         `expression \"…\"`"
    );
}

#[test]
fn unknown_words_suggest_the_closest() {
    assert_eq!(
        error("bal"),
        "word 1 `bal`: unknown word; did you mean `ball`?"
    );
    assert_eq!(
        error("ball cylinder unoin"),
        "word 3 `unoin`: unknown word; did you mean `union`?"
    );
    assert_eq!(
        error("ball translate 1,0,0"),
        "word 2 `translate`: unknown word; the word for this is `move`"
    );
    assert_eq!(
        error("tpms.gyroyd"),
        "word 1 `tpms.gyroyd`: no TPMS named `gyroyd` in the library; did you mean \
         `tpms.gyroid`?"
    );
    assert_eq!(
        error("ball scale 2 3"),
        "word 4 `3`: unknown word; a number here is not the argument of any word (a word \
         takes a fixed number of arguments: `scale 2` or `scale 1,2,3`, `rotate 0,0,1 pi/2`)"
    );
    assert!(error("ball zzzzzzzz").starts_with(
        "word 2 `zzzzzzzz`: unknown word; expected a solid (`ball`, `cylinder`, `box`, \
         `tpms.NAME`, `expression`, `file`) or an operation"
    ));
}

#[test]
fn missing_and_malformed_arguments() {
    assert_eq!(
        error("ball scale"),
        "word 2 `scale`: `scale` needs a factor k or kx,ky,kz, none of them 0, found the end \
         of the program"
    );
    assert_eq!(
        error("ball rotate 1,0,0"),
        "word 2 `rotate`: `rotate` needs an angle in radians after its axis, found the end of \
         the program"
    );
    assert_eq!(
        error("ball scale 0"),
        "word 3 `0`: `scale` needs a factor k or kx,ky,kz, none of them 0: `0` has a factor of 0"
    );
    assert_eq!(
        error("ball scale 1,2"),
        "word 3 `1,2`: `scale` needs a factor k or kx,ky,kz, none of them 0: `1,2` has 2 \
         components, not one or three"
    );
    assert_eq!(
        error("ball move 1,x,2"),
        "word 3 `1,x,2`: `move` needs a distance dx,dy,dz: `x` uses a coordinate; arguments \
         are numbers or expressions without x, y, z"
    );
    assert_eq!(
        error("ball shell -1"),
        "word 3 `-1`: `shell` needs a thickness of at least 0: `-1` is -1, less than 0"
    );
    assert_eq!(
        error("ball offset 1/0"),
        "word 3 `1/0`: `offset` needs a radius: `1/0` is inf, not a finite number"
    );
    assert_eq!(
        error("ball rotate 0,0,0 1"),
        "word 3 `0,0,0`: `rotate` needs an axis ax,ay,az (not 0,0,0): `0,0,0` is the zero \
         vector, which has no direction"
    );
    assert_eq!(
        error("ball orient 0,0,-1"),
        "word 3 `0,0,-1`: `orient` needs an axis ax,ay,az off the negative z half-axis: \
         `0,0,-1` lies on the negative z half-axis (x = y = 0, z ≤ 0), where the turn from z \
         is not defined"
    );
    assert_eq!(
        error("expression \"x +\""),
        "word 2 `x +`: bad expression at byte 3: unexpected end of input; expected a number, \
         a variable, a function call or `(`"
    );
    assert_eq!(
        error("file"),
        "word 1 `file`: `file` needs the path of a mesh, found the end of the program"
    );
    assert_eq!(
        error("ball \"oops"),
        "the program has an unclosed quote at byte 5"
    );
    assert_eq!(
        error("@shapes.txt"),
        "word 1 `@shapes.txt`: `@file` includes must be expanded before the program is parsed"
    );
}

/// Files in memory for includes.
struct Files(HashMap<&'static str, &'static str>);

impl IncludeResolver for Files {
    fn read(&self, name: &str, _from: Option<&str>) -> Result<Included, String> {
        let text = self.0.get(name).ok_or("no such file")?;
        Ok(Included {
            id: name.to_string(),
            text: text.to_string(),
        })
    }
}

#[test]
fn errors_in_included_files_name_the_file() {
    let files = Files(HashMap::from([
        ("pair.txt", "cylinder move 0,-2,0 cylinder move 0,2,0 union"),
        ("bad.txt", "scale 2"),
    ]));
    let words = expand(&["@pair.txt", "scale", "1/2"], &files).unwrap();
    let program = Program::parse(&words).unwrap();
    assert_eq!(
        program.canonical(),
        "cylinder move 0.0,-2.0,0.0 cylinder move 0.0,2.0,0.0 union scale 0.5"
    );
    let words = expand(&["@bad.txt"], &files).unwrap();
    assert_eq!(
        Program::parse(&words).unwrap_err().to_string(),
        "word 1 of `bad.txt` `scale`: scale needs a solid, found none"
    );
}

#[test]
fn canonical_text_reads_back_and_ignores_spelling() {
    let a = Program::parse_str("Ball Scale 1/2 TPMS.G intersection").unwrap();
    let b = Program::parse_str("ball  scale 0.5\ttpms.gyroid   intersection").unwrap();
    assert_eq!(a.canonical(), "ball scale 0.5 tpms.gyroid intersection");
    assert_eq!(a.canonical(), b.canonical());
    let text = "expression 'sin(x) * cos(y)' offset 2^-3 scale 0.5,1,2 rotate 1,0,0 pi/3 \
                orient 0,1,1 move 1,2,3 file 'my part.stl' union shell 1e-7 complement \
                box difference";
    let p = Program::parse_str(text).unwrap();
    let again = Program::parse_str(&p.canonical()).unwrap();
    assert_eq!(again.canonical(), p.canonical());
    assert_eq!(p.files(), ["my part.stl"]);
    assert!(
        p.canonical()
            .starts_with("expression sin(x)*cos(y) offset 0.125 ")
    );
    assert_eq!(
        p.canonical_with(&|path| format!("blake3:{}", path.len())),
        p.canonical().replace("\"my part.stl\"", "blake3:11")
    );
}

/// A unit sphere for `sphere.stl`; other files cannot be read.
const ONLY_SPHERE: SphereFile = SphereFile {
    name: Some("sphere.stl"),
    radius: 1.0,
};

#[test]
fn file_words_are_resolved_by_the_caller() {
    let p = Program::parse_str("tpms.p file sphere.stl intersection file other.stl union").unwrap();
    let err = p.field(&ONLY_SPHERE).err().expect("other.stl is unknown");
    assert_eq!(
        err.to_string(),
        "word 5 `file`: `file` cannot be used: cannot read `other.stl`"
    );
    assert!(matches!(err, ProgramError::File { .. }));
    let err = Program::parse_str("file x.stl")
        .unwrap()
        .field(&NoExternalSolids)
        .err()
        .expect("no meshes");
    assert_eq!(
        err.to_string(),
        "word 1 `file`: `file` cannot be used: meshes are not available here"
    );
    let f = Program::parse_str("file sphere.stl scale 2 move 1,0,0")
        .unwrap()
        .field(&ONLY_SPHERE)
        .unwrap();
    assert!((f.eval([3.0, 0.0, 0.0])).abs() < 1e-12);
    assert!((f.eval([1.0, 0.0, 0.0]) + 2.0).abs() < 1e-12);
}
