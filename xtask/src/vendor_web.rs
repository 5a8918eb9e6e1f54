//! `cargo xtask vendor-web`: refreshes `web/vendor/` from the npm registry at the versions
//! `web/package-lock.json` pins (`npm ci`), so a plain `cargo build` needs no npm.
//!
//! Copied: three.js's `build/three.module.min.js` and the `build/three.core.min.js` it imports,
//! the `OrbitControls` addon with its bare `'three'` import pointed at the served
//! `./three.module.js` (the page then needs no import map, which a strict
//! Content-Security-Policy would refuse as an inline script), and three.js's `LICENSE` (MIT).

use std::path::Path;
use std::process::Command;

pub fn run() -> Result<(), String> {
    let web = super::root().join("web");
    let status = Command::new("npm")
        .args(["ci", "--no-audit", "--no-fund"])
        .current_dir(&web)
        .status()
        .map_err(|e| format!("cannot run npm: {e}"))?;
    if !status.success() {
        return Err(format!("`npm ci` in {} failed: {status}", web.display()));
    }
    let three = web.join("node_modules/three");
    let vendor = web.join("vendor");
    std::fs::create_dir_all(&vendor).map_err(|e| format!("{}: {e}", vendor.display()))?;
    let read = |p: &Path| std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()));
    let write = |name: &str, text: &str| {
        let p = vendor.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
    };
    write(
        "three.module.min.js",
        &read(&three.join("build/three.module.min.js"))?,
    )?;
    write(
        "three.core.min.js",
        &read(&three.join("build/three.core.min.js"))?,
    )?;
    let controls = read(&three.join("examples/jsm/controls/OrbitControls.js"))?;
    let pointed = controls.replace("from 'three';", "from './three.module.js';");
    if pointed == controls {
        return Err("OrbitControls.js no longer imports from 'three': update vendor_web.rs".into());
    }
    write("OrbitControls.js", &pointed)?;
    write("LICENSE", &read(&three.join("LICENSE"))?)?;
    let version = read(&three.join("package.json"))?;
    let version = version
        .lines()
        .find(|l| l.trim_start().starts_with("\"version\""))
        .unwrap_or("")
        .trim();
    println!("vendored three.js {version} into {}", vendor.display());
    Ok(())
}
