//! Command-line conventions: completion scripts for every shell, and `--color` with the
//! `NO_COLOR` / `CLICOLOR_FORCE` conventions. (The man page is tested in `xtask`.)

use std::process::{Command, Output};

use crate::common::{BIN, Project};

fn run(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(BIN);
    cmd.args(args)
        .env_remove("NO_COLOR")
        .env_remove("CLICOLOR_FORCE")
        .env_remove("CLICOLOR");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run latticebuild")
}

/// The subcommands `latticebuild --help` lists (its `Commands:` section), so a command added
/// later is checked too.
fn subcommands() -> Vec<String> {
    let help = String::from_utf8(run(&["--help"], &[]).stdout).expect("utf-8 help");
    let names: Vec<String> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|name| name != "help")
        .collect();
    for expected in ["build", "watch", "graph", "clean", "cell", "sdf", "crystal"] {
        assert!(
            names.iter().any(|n| n == expected),
            "{expected} in {names:?}"
        );
    }
    names
}

fn completions(shell: &str) -> String {
    let out = run(&["completions", shell], &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 script")
}

#[test]
fn completion_scripts_name_every_subcommand_and_bash_accepts_its_own() {
    let commands = subcommands();
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let script = completions(shell);
        for name in &commands {
            assert!(script.contains(name.as_str()), "{shell}: no `{name}`");
        }
        for flag in ["color", "jobs", "set", "report", "allow-large"] {
            // Fish names a long flag `-l color`, the others `--color`.
            let named = match shell {
                "fish" => format!("-l {flag}"),
                _ => format!("--{flag}"),
            };
            assert!(script.contains(&named), "{shell}: no `{named}`");
        }
    }
    let bad = run(&["completions", "tcsh"], &[]);
    assert_eq!(bad.status.code(), Some(2));

    // Bash parses the script, and completing `latticebuild bu` and `latticebuild build --co`
    // offers `build` and `--color` (skipped where there is no bash).
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("latticebuild.bash");
    std::fs::write(&file, completions("bash")).expect("write script");
    let Ok(check) = Command::new("bash").arg("-n").arg(&file).output() else {
        return;
    };
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let complete = |words: &str| {
        let probe = format!(
            "source '{}'; COMP_WORDS=({words}); COMP_CWORD=$((${{#COMP_WORDS[@]}}-1)); \
             COMP_LINE='{words}'; COMP_POINT=${{#COMP_LINE}}; \
             _latticebuild latticebuild \"${{COMP_WORDS[-1]}}\" \"${{COMP_WORDS[-2]}}\"; \
             printf '%s\\n' \"${{COMPREPLY[@]}}\"",
            file.display()
        );
        let out = Command::new("bash")
            .arg("-c")
            .arg(probe)
            .output()
            .expect("bash");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let offered = complete("latticebuild bu");
    assert!(offered.lines().any(|l| l == "build"), "{offered:?}");
    let offered = complete("latticebuild build --co");
    assert!(offered.lines().any(|l| l == "--color"), "{offered:?}");
}

const BAD: &str = "[outputs.g]\nsampels = 3\n";

#[test]
fn diagnostics_are_coloured_when_asked_and_plain_otherwise() {
    let project = Project::new(BAD);
    let manifest = project.path().join("lattice.toml");
    let manifest = manifest.to_str().expect("utf-8 path");
    let stderr = |args: &[&str], env: &[(&str, &str)]| {
        let mut all = vec!["build", manifest];
        all.extend_from_slice(args);
        let out = run(&all, env);
        assert_eq!(out.status.code(), Some(2));
        String::from_utf8(out.stderr).expect("utf-8 stderr")
    };
    let plain = stderr(&[], &[]);
    assert!(plain.starts_with("error: "), "{plain}");
    assert!(!plain.contains('\x1b'), "{plain:?}");
    assert_eq!(
        stderr(&["--color", "never"], &[("CLICOLOR_FORCE", "1")]),
        plain
    );
    assert_eq!(stderr(&["--color", "auto"], &[]), plain);
    assert_eq!(
        stderr(&[], &[("CLICOLOR_FORCE", "1"), ("NO_COLOR", "1")]),
        plain
    );

    // rustc's colours: `error` bold bright red, the message bold, the gutter bold blue.
    let coloured = stderr(&["--color", "always"], &[("NO_COLOR", "1")]);
    assert!(
        coloured.starts_with("\x1b[1;91merror\x1b[0m\x1b[1m: "),
        "{coloured:?}"
    );
    assert!(coloured.contains("\x1b[1;94m-->\x1b[0m "), "{coloured:?}");
    assert!(
        coloured.contains("\x1b[1;94m2 |\x1b[0m sampels = 3"),
        "{coloured:?}"
    );
    assert!(
        coloured.contains("\x1b[1;91m^^^^^^^ unknown key\x1b[0m"),
        "{coloured:?}"
    );
    assert!(
        coloured.contains("\x1b[1;94m=\x1b[0m \x1b[1mhelp\x1b[0m: "),
        "{coloured:?}"
    );
    // `--color` is global (after the manifest too), and CLICOLOR_FORCE colours a pipe.
    assert_eq!(stderr(&[], &[("CLICOLOR_FORCE", "1")]), coloured);
    // Colour only: without its escape sequences, the text is the plain one.
    let mut stripped = String::new();
    for (i, part) in coloured.split('\x1b').enumerate() {
        match i {
            0 => stripped.push_str(part),
            _ => stripped.push_str(&part[part.find('m').expect("SGR") + 1..]),
        }
    }
    assert_eq!(stripped, plain);
}
