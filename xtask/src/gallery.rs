//! `cargo xtask gallery`: one small preview per example for the README, in `docs/gallery/`.
//!
//! Each `examples/*.toml` is built (release binary, in a scratch copy of `examples/`, so the
//! checkout gets no `out/` or cache) with small previews, and the preview of its first output
//! (by name, or the one [`CHOSEN`] names) is copied to `docs/gallery/EXAMPLE.png`. The images
//! are a pure function of the examples and the code, so rerunning changes no byte unless one
//! of those did. An example writing no files (`formats = []`) has no preview and is skipped.

use std::path::Path;
use std::process::Command;

/// The gallery's image size: small enough to commit (tens of KB), big enough to read.
const SIZE: &str = "[512, 384]";

/// Examples whose most telling output is not their first by name.
const CHOSEN: &[(&str, &str)] = &[];

pub fn run() -> Result<(), String> {
    let bin = super::release_binary()?;
    let root = super::root();
    let examples = root.join("examples");
    let scratch = std::env::temp_dir().join(format!("latticebuild-gallery-{}", std::process::id()));
    copy_dir(&examples, &scratch)?;
    let gallery = root.join("docs/gallery");
    std::fs::create_dir_all(&gallery).map_err(|e| e.to_string())?;
    let mut manifests: Vec<_> = std::fs::read_dir(&scratch)
        .map_err(|e| e.to_string())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    manifests.sort();
    for manifest in manifests {
        let stem = manifest
            .file_stem()
            .and_then(|s| s.to_str())
            .ok_or("an example's name is not UTF-8")?
            .to_string();
        let out = Command::new(&bin)
            .current_dir(&scratch)
            .arg("build")
            .arg(&manifest)
            .args(["-q", "--allow-defects", "--report", "-"])
            .args(["--set", &format!("build.preview_size={SIZE}")])
            .args(["--set", "build.report=\"basic\""])
            .output()
            .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
        if !out.status.success() {
            return Err(format!(
                "building {stem} failed:\n{}",
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        let reports: serde_json::Value =
            serde_json::from_slice(&out.stdout).map_err(|e| format!("{stem}: {e}"))?;
        let wanted = CHOSEN.iter().find(|(e, _)| *e == stem).map(|(_, o)| *o);
        let writes_files = reports
            .as_array()
            .into_iter()
            .flatten()
            .any(|r| r["files"].as_array().is_some_and(|f| !f.is_empty()));
        if !writes_files {
            // `formats = []` (an optimiser's loop reads the report alone): no preview, by design.
            println!("{stem}: writes no files, so no preview (skipped)");
            continue;
        }
        let png = reports
            .as_array()
            .into_iter()
            .flatten()
            .filter(|r| wanted.is_none_or(|w| r["name"] == w))
            .flat_map(|r| r["files"].as_array().cloned().unwrap_or_default())
            .filter_map(|f| f.as_str().map(str::to_string))
            .find(|f| f.ends_with(".png"))
            .ok_or(format!("{stem}: no preview"))?;
        let from = scratch.join(&png);
        let to = gallery.join(format!("{stem}.png"));
        std::fs::copy(&from, &to).map_err(|e| format!("{}: {e}", from.display()))?;
        let bytes = std::fs::metadata(&to).map_or(0, |m| m.len());
        println!("{} ({:.0} KB)", to.display(), bytes as f64 / 1024.0);
    }
    let _ = std::fs::remove_dir_all(&scratch);
    Ok(())
}

/// Copies `from` into `to`, leaving out build outputs and caches.
fn copy_dir(from: &Path, to: &Path) -> Result<(), String> {
    std::fs::create_dir_all(to).map_err(|e| e.to_string())?;
    for entry in std::fs::read_dir(from).map_err(|e| e.to_string())? {
        let entry = entry.map_err(|e| e.to_string())?;
        let name = entry.file_name();
        if name == "out" || name == ".latticebuild" {
            continue;
        }
        let path = entry.path();
        if path.is_dir() {
            copy_dir(&path, &to.join(&name))?;
        } else {
            std::fs::copy(&path, to.join(&name)).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}
