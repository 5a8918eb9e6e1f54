//! `cargo xtask man [DIR]`: the man pages, generated from the command-line parser
//! (`latticebuild::cli::command`): `latticebuild.1` and one `latticebuild-COMMAND.1` per
//! subcommand, into DIR (default `target/man`).
//!
//! Generated, not committed: the parser is their only source, so a page is never stale, and
//! a flag added to `cli.rs` needs no second edit. Packagers run this at packaging time.

use std::path::PathBuf;

pub fn run(args: &[String]) -> Result<(), String> {
    let dir = match args.first() {
        Some(dir) => PathBuf::from(dir),
        None => target_dir().join("man"),
    };
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create `{}`: {e}", dir.display()))?;
    let pages = pages();
    for (name, roff) in &pages {
        let path = dir.join(name);
        // Written under a temporary name and renamed, so a page is whole or absent.
        let temporary = dir.join(format!(".{name}.tmp"));
        std::fs::write(&temporary, roff)
            .and_then(|()| std::fs::rename(&temporary, &path))
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    }
    eprintln!("wrote {} man pages to {}", pages.len(), dir.display());
    Ok(())
}

/// `$CARGO_TARGET_DIR`, else the workspace's `target/`.
fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| crate::root().join("target"), PathBuf::from)
}

/// Every page as (file name, roff text): the command's, then each visible subcommand's.
fn pages() -> Vec<(String, Vec<u8>)> {
    let mut cli = latticebuild::cli::command().disable_help_subcommand(true);
    // Building names the subcommands as their pages want them: title `latticebuild-build`,
    // synopsis `latticebuild build …`.
    cli.build();
    let mut pages = vec![render(clap_mangen::Man::new(cli.clone()))];
    for sub in cli.get_subcommands().filter(|s| !s.is_hide_set()) {
        pages.push(render(clap_mangen::Man::new(sub.clone())));
    }
    pages
}

fn render(man: clap_mangen::Man) -> (String, Vec<u8>) {
    let mut roff = Vec::new();
    man.render(&mut roff)
        .expect("rendering into memory cannot fail");
    (man.get_filename(), roff)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_main_page_has_the_sections_and_every_subcommand() {
        let pages = pages();
        let main = String::from_utf8(pages[0].1.clone()).unwrap();
        assert!(
            main.starts_with(".ie") || main.contains(".TH latticebuild 1"),
            "{main}"
        );
        for section in [".SH NAME", ".SH SYNOPSIS", ".SH OPTIONS", ".SH SUBCOMMANDS"] {
            assert!(main.contains(section), "no `{section}`:\n{main}");
        }
        assert!(main.contains("\\-\\-color"), "{main}");
        let cli = latticebuild::cli::command();
        let names: Vec<&str> = cli
            .get_subcommands()
            .filter(|s| !s.is_hide_set())
            .map(|s| s.get_name())
            .collect();
        for expected in [
            "build",
            "watch",
            "graph",
            "clean",
            "cell",
            "sdf",
            "crystal",
            "completions",
        ] {
            assert!(names.contains(&expected), "{names:?}");
        }
        for name in &names {
            // clap_mangen lists a subcommand as `latticebuild\-build(1)`.
            let listed = format!("latticebuild\\-{}(1)", name.replace('-', "\\-"));
            assert!(
                main.contains(&listed),
                "`{listed}` not in the main page:\n{main}"
            );
            let page = pages
                .iter()
                .find(|(file, _)| *file == format!("latticebuild-{name}.1"))
                .map(|(_, roff)| String::from_utf8_lossy(roff).into_owned())
                .unwrap_or_else(|| panic!("no page for `{name}`"));
            assert!(
                page.contains(".SH NAME") && page.contains(".SH SYNOPSIS"),
                "{page}"
            );
            let synopsis = format!("\\fBlatticebuild {name}\\fR");
            assert!(page.contains(&synopsis), "`{synopsis}` not in:\n{page}");
        }
        // `build`'s own options are on its page.
        let build = pages
            .iter()
            .find(|(f, _)| f == "latticebuild-build.1")
            .unwrap();
        let build = String::from_utf8_lossy(&build.1);
        assert!(
            build.contains("\\-\\-allow\\-large") && build.contains(".SH OPTIONS"),
            "{build}"
        );
    }
}
