//! `latticebuild sdf WORDS… [-s SAMPLES] [-b x0,y0,z0,x1,y1,z1] [-o out.ply] [--contour
//! tetrahedra]`: a Cesogen command line (paper §4.2) with the program name replaced.
//!
//! The arguments are read as Cesogen reads them: every `@FILE` is replaced by the
//! whitespace-separated words of FILE (recursively, names relative to the including file),
//! then the options are taken out wherever they stand and the remaining words are the
//! program. `-s` is one total number of samples (spread evenly over the axes: `130^3`) or
//! three counts; `-b` the box, six numbers; `-o` the output file, `out.ply` by default, its
//! format chosen by its extension. Without `-b` the box is the solid's bounds, with the paper's
//! box rule where it is unbounded; without `-s`, 60³ samples. `--contour tetrahedra` contours
//! by marching tetrahedra instead of marching cubes. The file is stamped as a build's
//! outputs are (tool version, `--units`, default `mm`; in 3MF metadata the program, box,
//! samples and contouring), and a contouring past half a second shows a bar on a terminal.
//!
//! Exit codes as for `build`: 0 written, 2 bad arguments or program, 1 nothing could be
//! written. One summary line on stderr, like the build's.
//!
//! Invariant: this command touches files itself: included files and
//! `file` meshes are read here (a relative name is relative to the include file naming it;
//! only regular files are read, so a FIFO or a device is an error, not a wait), and the mesh
//! is written to a temporary file renamed into place, in a directory that must exist.
//! Contouring is the `sdf` stage's (`stages/sdf.rs`), so a program gives the same mesh here
//! and in a manifest.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use latticebuild_geom::contour::Contouring;
use latticebuild_geom::mesh_io::{self, Encoding, Format, Stamp, Units};
use latticebuild_geom::stack_lang::{
    self, Aabb, ExternalField, ExternalSolids, IncludeResolver, Included, Program, Word,
};

use clap::Args;

use super::Failure;
use crate::budget;
use crate::files::{output_problem, read_input, read_input_text, write_user_file};
use crate::progress;
use crate::stages::program::{box_text, contour_field, mesh_field};

#[derive(Args, Debug, Clone)]
pub struct SdfArgs {
    /// The program's words, with -s, -b, -o and @FILE anywhere among them
    #[arg(
        value_name = "WORDS",
        required = true,
        trailing_var_arg = true,
        allow_hyphen_values = true
    )]
    pub words: Vec<String>,
}

/// `file` words' meshes from the filesystem: a path is relative to the include file holding
/// the word (to the working directory for words on the command line), like `@` names.
struct MeshFiles;

impl ExternalSolids for MeshFiles {
    fn resolve(&self, path: &str, from: Option<&str>) -> Result<Arc<dyn ExternalField>, String> {
        let full = relative_to(path, from);
        let shown = full.display().to_string();
        let bytes = read_input(&full).map_err(|e| format!("cannot read `{shown}`: {e}"))?;
        mesh_field(&shown, &bytes).map_err(|e| e.to_string())
    }
}

/// `name` relative to the directory of the file `from` (as is when `from` is `None`).
fn relative_to(name: &str, from: Option<&str>) -> PathBuf {
    match from.and_then(|f| Path::new(f).parent()) {
        Some(dir) => dir.join(name),
        None => PathBuf::from(name),
    }
}

/// `@FILE` includes from the filesystem: names relative to the including file's directory
/// (to the working directory on the command line); identified by canonical path, so a file
/// reached by two names is still recognised when it includes itself.
struct FileIncludes;

impl IncludeResolver for FileIncludes {
    fn read(&self, name: &str, from: Option<&str>) -> Result<Included, String> {
        let path = relative_to(name, from);
        let canonical = path
            .canonicalize()
            .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
        let text = read_input_text(&canonical)
            .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
        Ok(Included {
            id: canonical.display().to_string(),
            text,
        })
    }
}

/// The options of a command line and the words of its program.
struct Options {
    samples: [usize; 3],
    /// `--contour cubes|tetrahedra`
    contouring: Contouring,
    domain: Option<Aabb>,
    output: PathBuf,
    /// `--units mm`: what the program's lengths are in, for the file's header.
    units: Units,
    quiet: bool,
    /// `--allow-large`: contour even what seems too big for the machine.
    allow_large: bool,
    words: Vec<Word>,
}

fn usage(text: impl std::fmt::Display) -> Failure {
    Failure::Usage(format!("error: {text}\n"))
}

impl Options {
    fn extract(words: Vec<Word>) -> Result<Options, Failure> {
        let mut options = Options {
            samples: stack_lang::DEFAULT_SAMPLES,
            contouring: Contouring::Cubes,
            domain: None,
            output: PathBuf::from("out.ply"),
            units: Units::Millimeter,
            quiet: false,
            allow_large: false,
            words: Vec::new(),
        };
        let mut it = words.into_iter();
        while let Some(word) = it.next() {
            let (flag, inline) = match word.text.split_once('=') {
                Some((f, v)) if f.starts_with("--") => (f.to_string(), Some(v.to_string())),
                _ => (word.text.clone(), None),
            };
            let name = match flag.as_str() {
                "-s" | "--samples" => "-s",
                "-b" | "--bounds" => "-b",
                "-o" | "--output" => "-o",
                "--contour" => "--contour",
                "--units" => "--units",
                "-q" | "--quiet" => {
                    options.quiet = true;
                    continue;
                }
                "--allow-large" => {
                    options.allow_large = true;
                    continue;
                }
                _ => {
                    options.words.push(word);
                    continue;
                }
            };
            let value = match inline.or_else(|| it.next().map(|w| w.text)) {
                Some(v) => v,
                None => {
                    return Err(usage(format_args!(
                        "{} `{flag}` needs a value after it ({})",
                        word.origin,
                        example(name)
                    )));
                }
            };
            let bad =
                |e: stack_lang::OptionError| usage(format_args!("{} `{flag}`: {e}", word.origin));
            match name {
                "-s" => options.samples = stack_lang::parse_samples(&value).map_err(bad)?,
                "-b" => options.domain = Some(stack_lang::parse_box(&value).map_err(bad)?),
                "--contour" => {
                    options.contouring = Contouring::from_name(&value).ok_or_else(|| {
                        usage(format_args!(
                            "{} `--contour {value}`: expected `cubes` (marching cubes, the \
                             default) or `tetrahedra` (marching tetrahedra)",
                            word.origin
                        ))
                    })?;
                }
                "--units" => {
                    options.units = Units::from_name(&value).ok_or_else(|| {
                        usage(format_args!(
                            "{} `--units {value}`: expected `mm` (the default), `cm`, `m`, \
                             `um` or `in`",
                            word.origin
                        ))
                    })?;
                }
                _ => options.output = PathBuf::from(value),
            }
        }
        Ok(options)
    }
}

fn example(flag: &str) -> &'static str {
    match flag {
        "-s" => "a total like `100^3` or three counts like `100,50,50`",
        "-b" => "six numbers `x0,y0,z0,x1,y1,z1`",
        "--contour" => "`cubes` or `tetrahedra`",
        "--units" => "`mm`, `cm`, `m`, `um` or `in`",
        _ => "a file name like `out.stl`",
    }
}

impl SdfArgs {
    /// `-h` or `--help` anywhere among the words: clap sees it only in first place, since the
    /// words may start with a hyphen.
    pub fn asks_for_help(&self) -> bool {
        self.words.iter().any(|a| a == "-h" || a == "--help")
    }
}

/// Runs `latticebuild sdf` with its raw arguments.
pub fn run(args: &SdfArgs) -> ExitCode {
    match command(&args.words) {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => f.exit(),
    }
}

fn command(args: &[String]) -> Result<(), Failure> {
    let started = Instant::now();
    let words = stack_lang::expand(args, &FileIncludes).map_err(usage)?;
    let options = Options::extract(words)?;
    let format = output_format(&options.output)?;
    // Checked before contouring, which may take minutes: the directory is not created.
    if let Some(problem) = output_problem(&options.output) {
        return Err(usage(format_args!(
            "cannot write `{}`: {problem}",
            options.output.display()
        )));
    }
    let program = Program::parse(&options.words).map_err(usage)?;
    let field = program.field(&MeshFiles).map_err(usage)?;
    let shown = options.output.display();
    let domain = options.domain.unwrap_or_else(|| field.domain());
    if !options.allow_large {
        let estimate = budget::box_estimate(
            "-s",
            [domain.min, domain.max],
            options.samples,
            &[format],
            Encoding::Binary,
        );
        let machine = budget::Machine::probe(options.output.parent().unwrap_or(Path::new(".")));
        let refused = budget::refusals(&[(shown.to_string(), estimate)], machine);
        if !refused.is_empty() {
            return Err(usage(format_args!(
                "{}\n  = help: fewer samples with `-s`, or `--allow-large` to contour anyway",
                refused.join("\nerror: ")
            )));
        }
    }
    let samples = |_: &Aabb| Ok(options.samples);
    let bars = progress::on_stderr(options.quiet);
    let stage = bars.start("sdf", options.samples[2] as u64 - 1);
    let contoured = contour_field(
        &field,
        options.contouring,
        Some(domain),
        &samples,
        stage.as_ref(),
    )
    .map_err(|e| Failure::Build(format!("{e}: `{shown}` was not written")))?;
    let (mesh, check, domain) = (&contoured.mesh, &contoured.check, &contoured.domain);
    stage.phase("writing");
    let stamp = stamp(&options, &program, domain);
    write_user_file(&options.output, &mut |w| {
        mesh_io::write_mesh_stamped(mesh, format, Encoding::Binary, &stamp, w)
    })
    .map_err(|e| Failure::Build(format!("cannot write `{shown}`: {e}")))?;
    drop(stage);
    drop(bars);
    if !options.quiet {
        let validity = match (check.watertight, check.manifold) {
            (true, true) => "watertight, manifold".to_string(),
            (w, m) => format!(
                "{}, {}",
                if w { "watertight" } else { "NOT watertight" },
                if m { "manifold" } else { "NOT manifold" }
            ),
        };
        let [nx, ny, nz] = options.samples;
        eprintln!(
            "{shown}: {} triangles, {} vertices, {validity}, volume {:.6}, volume fraction {:.4} \
             of {} at {nx}×{ny}×{nz} samples ({:.2} s)",
            check.triangles,
            check.vertices,
            check.volume,
            check.volume / domain.volume(),
            box_text(domain),
            started.elapsed().as_secs_f64()
        );
    }
    if !(check.watertight && check.manifold) {
        return Err(Failure::Build(format!(
            "`{shown}` is not a closed manifold mesh; this is a bug, please report the command"
        )));
    }
    Ok(())
}

/// What the written file says about itself, as a build's output does: the tool and its
/// version, `--units`, the file's stem as title, and the parameters in the names of an SDF
/// output's resolved ones (`sdf` in canonical text, `bounds`, `samples`, `contour`).
fn stamp(options: &Options, program: &Program, domain: &Aabb) -> Stamp {
    let json = |v: &[f64; 3]| serde_json::json!(v).to_string();
    let parameters = [
        ("sdf", program.canonical()),
        ("bounds.min", json(&domain.min)),
        ("bounds.max", json(&domain.max)),
        ("samples", serde_json::json!(options.samples).to_string()),
        ("contour", options.contouring.name().to_string()),
    ];
    Stamp {
        generator: format!("latticebuild {}", env!("CARGO_PKG_VERSION")),
        units: Some(options.units),
        title: options
            .output
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        parameters: parameters
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
    }
}

fn output_format(path: &Path) -> Result<Format, Failure> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    Format::from_name(&ext).ok_or_else(|| {
        usage(format_args!(
            "cannot tell the mesh format of `{}` from its extension; use .stl, .ply, .obj, \
             .off, .vtk, .vtu or .3mf",
            path.display()
        ))
    })
}
