//! `cargo xtask fuzz`: a mutation fuzzer for the readers, on stable Rust.
//!
//! ```text
//! cargo xtask fuzz [--minutes M] [--seed N] [--cpu-ms MS] [--memory-mib MIB] [TARGET…]
//! cargo xtask fuzz --list
//! cargo xtask fuzz --replay [TARGET…]     (what tests/fuzz_corpus.rs runs)
//! cargo xtask fuzz --check TARGET FILE…   (one verdict per file)
//! ```
//!
//! Each target (`targets.rs`) starts from its seeds (`seeds.rs`), mutates them (`mutate.rs`)
//! and runs every input in a child process (`runner.rs`) under a CPU budget (1 s) and a heap
//! bound (512 MiB). Without coverage instrumentation (no nightly toolchain), the feedback is
//! the outcome: an input whose outcome — the error message with numbers and quoted text
//! blanked, or a summary of what was read — has not been seen joins the corpus, so the
//! mutations reach past the first check that refuses them. A panic, a hang, an allocation past
//! the bound or a crash is confirmed in a fresh child with backtraces, shrunk (chunks removed
//! while the failure stays the same) and saved as `tests/fuzz_corpus/<target>/<hash>`, which
//! `--replay` runs again; one input is kept per distinct failure (panic location, or kind and
//! first workspace frame).
//!
//! Invariants: a run is a function of `--seed` and the corpus files (the machine's load only
//! changes how many inputs fit in the time); saved inputs are named by the first 16 hex
//! digits of their blake3, which `--replay` checks.

mod bound;
mod mutate;
mod runner;
mod seeds;
mod targets;

pub use bound::Bounded;
pub use runner::serve;

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use mutate::Rng;
use runner::{Limits, Runner, Verdict};
use targets::{TARGETS, Target};

/// Inputs kept for mutation per target, seeds included.
const MAX_CORPUS: usize = 4096;

struct Options {
    minutes: f64,
    seed: u64,
    limits: Limits,
    targets: Vec<&'static Target>,
}

pub fn run(args: &[String]) -> Result<(), String> {
    let mut minutes = 1.0;
    let mut seed = None;
    let mut cpu_ms = 1000u64;
    let mut memory_mib = 512usize;
    let mut names = Vec::new();
    let mut mode = "fuzz";
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |what: &str| {
            it.next()
                .cloned()
                .ok_or_else(|| format!("{a} needs {what}"))
        };
        match a.as_str() {
            "--minutes" => {
                minutes = value("a number")?
                    .parse()
                    .map_err(|_| "--minutes needs a number".to_string())?
            }
            "--seed" => {
                seed = Some(
                    value("a number")?
                        .parse()
                        .map_err(|_| "--seed needs a number".to_string())?,
                )
            }
            "--cpu-ms" => {
                cpu_ms = value("milliseconds")?
                    .parse()
                    .map_err(|_| "--cpu-ms needs a number".to_string())?
            }
            "--memory-mib" => {
                memory_mib = value("MiB")?
                    .parse()
                    .map_err(|_| "--memory-mib needs a number".to_string())?
            }
            "--list" => mode = "list",
            "--replay" => mode = "replay",
            "--check" => mode = "check",
            other if other.starts_with('-') => {
                return Err(format!("unknown fuzz argument `{other}`"));
            }
            other => names.push(other.to_string()),
        }
    }
    let limits = Limits {
        cpu: Duration::from_millis(cpu_ms),
        memory: memory_mib << 20,
    };
    match mode {
        "list" => {
            for t in TARGETS.iter().filter(|t| !t.hidden) {
                println!("{:<17} {}", t.name, t.about);
            }
            Ok(())
        }
        "replay" => replay(&names, &limits),
        "check" => {
            let (target, files) = names
                .split_first()
                .ok_or("--check needs a target and files")?;
            check(target, files, &limits)
        }
        _ => {
            let targets = if names.is_empty() {
                TARGETS.iter().filter(|t| !t.hidden).collect()
            } else {
                names
                    .iter()
                    .map(|n| {
                        targets::find(n).ok_or_else(|| {
                            format!("no fuzz target `{n}` (`cargo xtask fuzz --list` lists them)")
                        })
                    })
                    .collect::<Result<_, _>>()?
            };
            let seed = seed.unwrap_or_else(|| {
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(1, |d| d.as_nanos() as u64)
            });
            fuzz(&Options {
                minutes,
                seed,
                limits,
                targets,
            })
        }
    }
}

/// A directory for the runners: the manifest target writes its input here, next to links to
/// the examples' input directories. Removed when dropped.
struct ScratchDir(PathBuf);

impl ScratchDir {
    fn new() -> Result<ScratchDir, String> {
        let dir = std::env::temp_dir().join(format!("latticebuild-fuzz-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let examples = super::root().join("examples");
        for (link, to) in [
            ("meshes", "meshes"),
            ("scaffolds", "scaffolds"),
            ("crystals", "crystals"),
            ("FAU.cif", "crystals/FAU.cif"),
        ] {
            std::os::unix::fs::symlink(examples.join(to), dir.join(link))
                .map_err(|e| format!("{}: {e}", dir.join(link).display()))?;
        }
        Ok(ScratchDir(dir))
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn content_name(bytes: &[u8]) -> String {
    blake3::hash(bytes).to_hex()[..16].to_string()
}

/// The outcome with what varies between inputs of one code path left out: it keeps the
/// short words made of letters only (and their punctuation), outside backticks and quotes,
/// which are the fixed words of a message; numbers and quoted input are what the input varied.
/// A summary of what was read (`ok …`, sizes already grouped) is kept up to ` | `. Messages
/// joined by `; ` count as a set, each by its first words (where messages differ; later
/// words tend to repeat the input).
fn normalize(outcome: &str) -> String {
    if outcome.starts_with("ok ") {
        let (summary, rest) = outcome.split_once(" | ").unwrap_or((outcome, ""));
        let summary: String = summary.chars().take(200).collect();
        return format!("{summary} | {}", normalize(rest));
    }
    let mut parts: Vec<String> = outcome.split("; ").map(normalize_message).collect();
    parts.sort();
    parts.dedup();
    parts.join("; ")
}

fn normalize_message(outcome: &str) -> String {
    let mut words = Vec::new();
    // The quote character of the quoted input being skipped, if any.
    let mut quoted: Option<char> = None;
    for word in outcome.split_whitespace() {
        let bare = word.trim_end_matches([',', ':', ';', '.', ')']);
        if let Some(q) = quoted {
            if bare.ends_with(q) {
                quoted = None;
            }
            continue;
        }
        if let Some(q) = bare.chars().next().filter(|c| matches!(c, '`' | '"')) {
            words.push("`…`");
            if !(bare.len() > 1 && bare.ends_with(q)) {
                quoted = Some(q);
            }
            continue;
        }
        // Long words are input that a message repeats without quotes (a PLY element name).
        if !bare.is_empty()
            && bare.len() <= 16
            && bare
                .chars()
                .all(|c| c.is_ascii_alphabetic() || "-'(/_$".contains(c))
        {
            words.push(bare);
        }
        if words.len() == 12 {
            break;
        }
    }
    words.join(" ")
}

/// What identifies a failure: the panic's place, or the kind and the first frame of this
/// workspace in the backtrace (or the first line of what the child printed).
fn signature(v: &Verdict) -> String {
    match v {
        Verdict::Fine(_) => "fine".into(),
        Verdict::Panic(text) => {
            let first = text.lines().next().unwrap_or("");
            let place = first
                .strip_prefix("panicked at ")
                .and_then(|rest| rest.split(": ").next())
                .unwrap_or(first);
            format!("panic at {place}")
        }
        Verdict::Hang(_) => "hang".into(),
        Verdict::Memory(text) | Verdict::Crash(text) => {
            let frame = text.lines().map(str::trim).find(|l| {
                l.starts_with("at ")
                    && (l.contains("crates/geom/src") || l.contains("/src/"))
                    && !l.contains("xtask/src")
                    && !l.contains("/rustc/")
                    && !l.contains(".cargo/registry")
            });
            match frame {
                Some(f) => format!("{} {f}", v.kind()),
                None => format!(
                    "{} {}",
                    v.kind(),
                    normalize(text.lines().find(|l| !l.trim().is_empty()).unwrap_or(""))
                ),
            }
        }
    }
}

/// The failure as seen in a batch (no backtrace): the key for shrinking.
fn quick_signature(v: &Verdict) -> String {
    match v {
        Verdict::Panic(_) => signature(v),
        other => other.kind().to_string(),
    }
}

fn single(target: &str, scratch: &Path, limits: &Limits, input: &[u8], trace: bool) -> Verdict {
    match Runner::spawn(target, scratch, limits, trace) {
        Ok(mut r) => r.run(input),
        Err(e) => Verdict::Crash(e),
    }
}

struct Finding {
    kind: &'static str,
    count: u64,
    path: PathBuf,
    bytes: usize,
}

struct Campaign<'a> {
    target: &'static Target,
    scratch: &'a Path,
    limits: &'a Limits,
    rng: Rng,
    runner: Option<Runner>,
    corpus: Vec<Vec<u8>>,
    seeds: usize,
    seen: HashSet<String>,
    dictionary: Vec<Vec<u8>>,
    max_len: usize,
    execs: u64,
    findings: BTreeMap<String, Finding>,
    /// Confirmations spent per batch signature; after a few, more of the same are counted
    /// without one (a hang costs a whole CPU budget to confirm).
    confirmed: HashMap<String, u32>,
    /// Failures past those confirmation budgets, by batch signature.
    more: BTreeMap<String, u64>,
    unconfirmed: u64,
}

impl Campaign<'_> {
    fn exec(&mut self, input: &[u8]) -> Result<Verdict, String> {
        if self.runner.is_none() {
            self.runner = Some(Runner::spawn(
                self.target.name,
                self.scratch,
                self.limits,
                false,
            )?);
        }
        let runner = self.runner.as_mut().expect("spawned above");
        let verdict = runner.run(input);
        if runner.dead {
            self.runner = None;
        }
        self.execs += 1;
        Ok(verdict)
    }

    /// Runs an input; keeps it if its outcome is new, reports it if it fails.
    fn try_input(&mut self, input: Vec<u8>) -> Result<(), String> {
        match self.exec(&input)? {
            Verdict::Fine(outcome) => {
                if self.seen.insert(normalize(&outcome)) {
                    if self.corpus.len() < MAX_CORPUS {
                        self.corpus.push(input);
                    } else {
                        // Full: replace a random non-seed entry.
                        let i = self.seeds + self.rng.below(self.corpus.len() - self.seeds);
                        self.corpus[i] = input;
                    }
                }
                Ok(())
            }
            failure => self.failure(input, failure),
        }
    }

    fn failure(&mut self, input: Vec<u8>, verdict: Verdict) -> Result<(), String> {
        let quick = quick_signature(&verdict);
        // A panic's place is known from the batch; other kinds need a traced run for their
        // frame, and after a few of a kind (a hang costs a whole CPU budget) more are counted.
        if let Some(f) = self.findings.get_mut(&quick) {
            f.count += 1;
            return Ok(());
        }
        let spent = self.confirmed.entry(quick.clone()).or_insert(0);
        if *spent >= if quick == "hang" { 3 } else { 50 } {
            *self.more.entry(quick).or_insert(0) += 1;
            return Ok(());
        }
        *spent += 1;
        let confirmed = single(self.target.name, self.scratch, self.limits, &input, true);
        if confirmed.is_fine() {
            self.unconfirmed += 1;
            println!(
                "  {} in a batch, but not alone ({} bytes): not saved\n    {}",
                verdict.kind(),
                input.len(),
                first_lines(verdict.text(), 3)
            );
            return Ok(());
        }
        let sig = signature(&confirmed);
        if let Some(f) = self.findings.get_mut(&sig) {
            f.count += 1;
            return Ok(());
        }
        let dir = seeds::corpus_dir(&super::root(), self.target.name);
        let saved = dir.join(content_name(&input));
        if saved.exists() {
            // A saved input (run as a seed) that still fails: known, not saved again.
            println!("  {} still fails: {sig}", saved.display());
            self.findings.insert(
                sig,
                Finding {
                    kind: confirmed.kind(),
                    count: 1,
                    path: saved,
                    bytes: input.len(),
                },
            );
            return Ok(());
        }
        let small = self.shrink(input.clone(), &quick);
        let (bytes, report) = if small.len() < input.len() {
            let again = single(self.target.name, self.scratch, self.limits, &small, true);
            if signature(&again) == sig {
                (small, again)
            } else {
                (input, confirmed)
            }
        } else {
            (input, confirmed)
        };
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = dir.join(content_name(&bytes));
        std::fs::write(&path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        println!(
            "  NEW {} ({} bytes) saved as {}\n    {sig}\n{}",
            report.kind(),
            bytes.len(),
            path.strip_prefix(super::root()).unwrap_or(&path).display(),
            indent(&first_lines(report.text(), 40), "    | ")
        );
        self.findings.insert(
            sig,
            Finding {
                kind: report.kind(),
                count: 1,
                path,
                bytes: bytes.len(),
            },
        );
        Ok(())
    }

    /// Removes chunks (halves, quarters, … single bytes) while the batch signature stays.
    fn shrink(&mut self, mut input: Vec<u8>, quick: &str) -> Vec<u8> {
        let budget = if quick == "hang" { 8 } else { 400 };
        let started = Instant::now();
        let mut tries = 0;
        let mut chunk = input.len() / 2;
        while chunk > 0 && tries < budget && started.elapsed() < Duration::from_secs(60) {
            let mut at = 0;
            while at < input.len() && tries < budget {
                let end = (at + chunk).min(input.len());
                let mut candidate = input[..at].to_vec();
                candidate.extend_from_slice(&input[end..]);
                tries += 1;
                let Ok(v) = self.exec(&candidate) else {
                    return input;
                };
                if !v.is_fine() && quick_signature(&v) == quick {
                    input = candidate;
                } else {
                    at = end;
                }
            }
            chunk /= 2;
        }
        input
    }

    /// A parent for the next mutation: usually the smaller of two picks, so that big seeds,
    /// slow to run, are mutated less often.
    fn pick(&mut self) -> usize {
        let a = self.rng.below(self.corpus.len());
        if self.rng.chance(1, 4) {
            return a;
        }
        let b = self.rng.below(self.corpus.len());
        if self.corpus[b].len() < self.corpus[a].len() {
            b
        } else {
            a
        }
    }
}

fn first_lines(text: &str, n: usize) -> String {
    text.lines().take(n).collect::<Vec<_>>().join("\n")
}

fn indent(text: &str, prefix: &str) -> String {
    text.lines()
        .map(|l| format!("{prefix}{l}"))
        .collect::<Vec<_>>()
        .join("\n")
}

fn fuzz(options: &Options) -> Result<(), String> {
    let scratch = ScratchDir::new()?;
    let root = super::root();
    println!(
        "fuzzing {} target(s), {} min each, seed {}, {:.1} s CPU and {} MiB per input",
        options.targets.len(),
        options.minutes,
        options.seed,
        options.limits.cpu.as_secs_f64(),
        options.limits.memory >> 20
    );
    let mut summary = Vec::new();
    for (index, target) in options.targets.iter().enumerate() {
        let seeds = seeds::seeds(&root, target);
        if seeds.is_empty() {
            return Err(format!("fuzz target `{}` has no seeds", target.name));
        }
        let largest = seeds.iter().map(|s| s.bytes.len()).max().unwrap_or(0);
        let mut campaign = Campaign {
            target,
            scratch: &scratch.0,
            limits: &options.limits,
            rng: Rng::new(options.seed ^ (index as u64).wrapping_mul(0x9e37_79b9)),
            runner: None,
            corpus: Vec::new(),
            seeds: 0,
            seen: HashSet::new(),
            dictionary: mutate::vocabulary(seeds.iter().map(|s| s.bytes.as_slice()), 2000),
            max_len: (2 * largest).clamp(64 << 10, 4 << 20),
            execs: 0,
            findings: BTreeMap::new(),
            confirmed: HashMap::new(),
            more: BTreeMap::new(),
            unconfirmed: 0,
        };
        println!(
            "{}: {} seeds (largest {} bytes), {} words",
            target.name,
            seeds.len(),
            largest,
            campaign.dictionary.len()
        );
        let started = Instant::now();
        let deadline = started + Duration::from_secs_f64(options.minutes * 60.0);
        for seed in &seeds {
            campaign.try_input(seed.bytes.clone())?;
            // Seeds stay whatever their outcome: each is a different starting point.
            if campaign.corpus.last() != Some(&seed.bytes) {
                campaign.corpus.push(seed.bytes.clone());
            }
        }
        campaign.seeds = campaign.corpus.len();
        let mut next_status = started + Duration::from_secs(60);
        while Instant::now() < deadline {
            let parent = campaign.pick();
            let other = campaign.rng.below(campaign.corpus.len());
            let input = mutate::mutate(
                &mut campaign.rng,
                &campaign.corpus[parent],
                &campaign.corpus[other],
                &campaign.dictionary,
                campaign.max_len,
            );
            campaign.try_input(input)?;
            if Instant::now() >= next_status {
                next_status += Duration::from_secs(60);
                println!(
                    "  {:>4.0} s: {} inputs, corpus {}, findings {}",
                    started.elapsed().as_secs_f64(),
                    campaign.execs,
                    campaign.corpus.len(),
                    campaign.findings.len()
                );
            }
        }
        let seconds = started.elapsed().as_secs_f64();
        let found: u64 = campaign.findings.values().map(|f| f.count).sum::<u64>()
            + campaign.more.values().sum::<u64>();
        let line = format!(
            "{:<17} {:>9} inputs in {:>6.1} s ({:>6.0}/s), corpus {:>4} ({} seeds), outcomes {:>5}, \
             failures {} ({} distinct, {} unconfirmed)",
            target.name,
            campaign.execs,
            seconds,
            campaign.execs as f64 / seconds,
            campaign.corpus.len(),
            campaign.seeds,
            campaign.seen.len(),
            found,
            campaign.findings.len(),
            campaign.unconfirmed
        );
        println!("{line}");
        for (sig, f) in &campaign.findings {
            println!(
                "    {} x{} ({} bytes) {}: {sig}",
                f.kind,
                f.count,
                f.bytes,
                f.path.display()
            );
        }
        for (kind, n) in &campaign.more {
            println!("    {kind} x{n} more, not confirmed (budget spent)");
        }
        summary.push(line);
    }
    println!("\nsummary (seed {}):", options.seed);
    for line in summary {
        println!("{line}");
    }
    Ok(())
}

/// Runs `inputs` through `target` in one child (a new one after each death) and returns the
/// verdicts in order.
fn verdicts(
    target: &str,
    scratch: &Path,
    limits: &Limits,
    inputs: &[Vec<u8>],
) -> Result<Vec<Verdict>, String> {
    let mut runner: Option<Runner> = None;
    let mut out = Vec::with_capacity(inputs.len());
    for input in inputs {
        let r = match runner.as_mut() {
            Some(r) => r,
            None => runner.insert(Runner::spawn(target, scratch, limits, false)?),
        };
        let v = r.run(input);
        if r.dead {
            runner = None;
        }
        out.push(v);
    }
    Ok(out)
}

fn check(target: &str, files: &[String], limits: &Limits) -> Result<(), String> {
    targets::find(target).ok_or_else(|| format!("no fuzz target `{target}`"))?;
    let scratch = ScratchDir::new()?;
    let inputs = files
        .iter()
        .map(|f| std::fs::read(f).map_err(|e| format!("{f}: {e}")))
        .collect::<Result<Vec<_>, _>>()?;
    for (file, v) in files
        .iter()
        .zip(verdicts(target, &scratch.0, limits, &inputs)?)
    {
        println!(
            "{file}\t{}\t{}",
            v.kind(),
            v.text().lines().next().unwrap_or("")
        );
    }
    Ok(())
}

/// Runs every saved input of `tests/fuzz_corpus` (or of the named targets) and fails unless
/// each returns within the limits and its file name is its hash.
fn replay(names: &[String], limits: &Limits) -> Result<(), String> {
    let root = super::root();
    let scratch = ScratchDir::new()?;
    let mut failures = Vec::new();
    let mut total = 0;
    for target in TARGETS.iter().filter(|t| !t.hidden) {
        if !names.is_empty() && !names.iter().any(|n| n == target.name) {
            continue;
        }
        let dir = seeds::corpus_dir(&root, target.name);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        files.sort();
        let inputs = files
            .iter()
            .map(|f| std::fs::read(f).map_err(|e| format!("{}: {e}", f.display())))
            .collect::<Result<Vec<_>, _>>()?;
        let results = verdicts(target.name, &scratch.0, limits, &inputs)?;
        for ((file, bytes), v) in files.iter().zip(&inputs).zip(results) {
            total += 1;
            let shown = file
                .strip_prefix(&root)
                .unwrap_or(file)
                .display()
                .to_string();
            let name = file.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if name != content_name(bytes) {
                failures.push(format!(
                    "{shown}: the name is not the blake3 of the content ({})",
                    content_name(bytes)
                ));
            } else if v.is_fine() {
                println!("{shown}: fine: {}", v.text().lines().next().unwrap_or(""));
            } else {
                failures.push(format!(
                    "{shown}: {}: {}",
                    v.kind(),
                    first_lines(v.text(), 20)
                ));
            }
        }
    }
    for target in names {
        if targets::find(target).is_none_or(|t| t.hidden) {
            return Err(format!("no fuzz target `{target}`"));
        }
    }
    println!("{total} saved inputs replayed, {} failed", failures.len());
    if failures.is_empty() {
        Ok(())
    } else {
        Err(failures.join("\n"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outcomes_group_by_code_path_not_by_value() {
        assert_eq!(
            normalize("fuzz.msh:12: expected 4 nodes, found `abc` in \"x y\""),
            normalize("fuzz.msh:7: expected 10 nodes, found `q``x` in \"\"")
        );
        assert_eq!(
            normalize("fuzz.msh:12: expected `$Nodes`, found `a b` at line 3"),
            "expected `…` found `…` at line"
        );
        assert_ne!(
            normalize("fuzz.msh:12: expected 4 nodes"),
            normalize("fuzz.msh:12: expected 4 elements")
        );
    }

    #[test]
    fn failures_are_told_apart_by_place() {
        let a = Verdict::Panic("panicked at crates/geom/src/a.rs:1:2: index out of bounds".into());
        let b = Verdict::Panic("panicked at crates/geom/src/a.rs:9:2: index out of bounds".into());
        assert_eq!(signature(&a), "panic at crates/geom/src/a.rs:1:2");
        assert_ne!(signature(&a), signature(&b));
        let m = Verdict::Memory(
            "fuzz-runner: an allocation of 8 bytes\n   0: std::backtrace\n             at /rustc/x/library/std/src/backtrace.rs:1:1\n   5: latticebuild_geom::scaffold::msh::read\n             at ./crates/geom/src/scaffold/msh.rs:40:9".into(),
        );
        assert_eq!(
            signature(&m),
            "memory at ./crates/geom/src/scaffold/msh.rs:40:9"
        );
    }
}
