//! `cargo xtask fuzz`: builds the libFuzzer targets of `fuzz/` instrumented, runs each for a
//! fixed time on its corpus and prints per target the executions per second, the executions,
//! the coverage (libFuzzer's `cov:` edges and `ft:` features) and the crashes.
//!
//! The build passes rustc what `cargo fuzz build --sanitizer none --debug-assertions` passes
//! (cargo-fuzz's `src/project.rs`: sancov-module with 8-bit counters, the PC table and
//! compare tracing, stack depth on Linux, `--cfg fuzzing`, debug assertions, so overflow
//! panics), with `--target` so that build scripts and proc macros are built as in the normal
//! release build and shared with it (the targets land in `<target>/x86_64-unknown-linux-gnu/`,
//! the normal build's files stay untouched). No `cargo install cargo-fuzz`, no nightly: stable rustc
//! takes these flags.
//!
//! A crash is what libFuzzer stops on: a panic, an input slower than `-timeout`, a process
//! past `-rss_limit_mb` or a single allocation past `-malloc_limit_mb`. Its input is kept
//! under `<target>/fuzz/artifacts/<target>/`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The flags of the instrumented build.
pub(crate) const RUSTFLAGS: &str = "-Cpasses=sancov-module \
     -Cllvm-args=-sanitizer-coverage-level=4 \
     -Cllvm-args=-sanitizer-coverage-inline-8bit-counters \
     -Cllvm-args=-sanitizer-coverage-pc-table \
     -Cllvm-args=-sanitizer-coverage-trace-compares \
     --cfg fuzzing -Cllvm-args=-sanitizer-coverage-stack-depth -Cdebug-assertions";

/// The host's target triple (the instrumented build names it so that RUSTFLAGS skip the
/// build scripts).
const HOST: &str = "x86_64-unknown-linux-gnu";

/// A single input running longer than this is a crash (a hang): the slowest corpus input
/// takes well under a tenth of it, also on a loaded CI host.
const TIMEOUT_SECS: u32 = 10;
/// A process past this resident size is a crash.
const RSS_LIMIT_MB: u32 = 2048;
/// A single allocation past this is a crash.
const MALLOC_LIMIT_MB: u32 = 512;

/// The targets of the harness's readers, built only with the `fuzz` crate's feature `texts`
/// (their `required-features` in `fuzz/Cargo.toml`): the harness is most of the
/// instrumented build, which the smoke leaves out (`--no-texts`).
const TEXT_TARGETS: [&str; 2] = ["description", "suite"];

/// The longest input of a target (`-max_len`; libFuzzer's default, the longest corpus input,
/// for the others): a device session or a suite or description text past this adds little
/// coverage and makes the corpus kept in the repository big and every execution slow.
fn max_len(target: &str) -> Option<usize> {
    if TEXT_TARGETS.contains(&target) {
        Some(4 * 1024)
    } else if target.starts_with("device_") {
        Some(2 * 1024)
    } else {
        None
    }
}

/// What `cargo xtask fuzz` is asked.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct FuzzOptions {
    /// Seconds each target runs.
    pub(crate) seconds: u32,
    /// Minimise each target's corpus after its run (`-merge=1`) and write it back.
    pub(crate) merge: bool,
    /// Build and run the targets of the harness's readers too (not `--no-texts`).
    pub(crate) texts: bool,
    /// The targets; empty: all.
    pub(crate) targets: Vec<String>,
}

/// Parses the arguments after `fuzz`.
pub(crate) fn parse(args: &[String]) -> Result<FuzzOptions, String> {
    let mut options = FuzzOptions {
        seconds: 60,
        merge: false,
        texts: true,
        targets: Vec::new(),
    };
    let mut args = args.iter();
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--seconds" => {
                let n = args.next().ok_or("--seconds needs a number")?;
                options.seconds = n
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or(format!("--seconds {n}: a whole number of seconds above 0"))?;
            }
            "--merge" => options.merge = true,
            "--no-texts" => options.texts = false,
            other if other.starts_with('-') => return Err(format!("unknown option `{other}`")),
            target => options.targets.push(target.to_string()),
        }
    }
    Ok(options)
}

/// The figures of one target's run.
#[derive(Debug, Default, PartialEq, Eq)]
pub(crate) struct Figures {
    pub(crate) execs: u64,
    pub(crate) execs_per_sec: u64,
    pub(crate) cov: u64,
    pub(crate) ft: u64,
    /// Whether libFuzzer stopped on a crash.
    pub(crate) crashed: bool,
}

/// The figures in libFuzzer's output: the last status line's `cov:` and `ft:`, the final
/// statistics (`-print_final_stats=1`), and whether it reported a crash.
pub(crate) fn figures(log: &str) -> Figures {
    let field = |line: &str, key: &str| -> Option<u64> {
        let rest = &line[line.find(key)? + key.len()..];
        rest.split_whitespace().next()?.parse().ok()
    };
    let mut f = Figures::default();
    for line in log.lines() {
        if let (Some(cov), Some(ft)) = (field(line, "cov: "), field(line, "ft: ")) {
            (f.cov, f.ft) = (cov, ft);
        }
        if let Some(n) = field(line, "stat::number_of_executed_units: ") {
            f.execs = n;
        }
        if let Some(n) = field(line, "stat::average_exec_per_sec: ") {
            f.execs_per_sec = n;
        }
        let crash = [
            "==ERROR: libFuzzer",
            "ERROR: libFuzzer",
            "deadly signal",
            "panicked at",
        ];
        if crash.iter().any(|c| line.contains(c)) {
            f.crashed = true;
        }
    }
    f
}

/// The targets: `fuzz/fuzz_targets/*.rs`, sorted.
fn all_targets(root: &Path) -> Result<Vec<String>, String> {
    let dir = root.join("fuzz/fuzz_targets");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "rs").then(|| p.file_stem()?.to_str().map(str::to_string))?
        })
        .collect();
    names.sort();
    Ok(names)
}

/// Builds the instrumented `targets` into `target`; whether they built.
fn build(root: &Path, target: &Path, targets: &[String], texts: bool) -> bool {
    eprintln!("xtask: building the instrumented fuzz targets ({HOST}, {target:?})");
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    Command::new(cargo)
        .current_dir(root)
        .args([
            "build",
            "--release",
            "--package",
            "fuzz",
            "--features",
            "libfuzzer",
        ])
        .args(if texts {
            None
        } else {
            Some("--no-default-features")
        })
        .args(targets.iter().flat_map(|t| ["--bin", t]))
        .args(["--target", HOST])
        .env("CARGO_TARGET_DIR", target)
        .env("RUSTFLAGS", RUSTFLAGS)
        .status()
        .is_ok_and(|s| s.success())
}

/// Runs libFuzzer `bin` with `args`; its output (stderr and stdout).
fn libfuzzer(bin: &Path, args: &[String]) -> Result<(bool, String), String> {
    let out = Command::new(bin)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("{}: {e}", bin.display()))?;
    let log =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    Ok((out.status.success(), log))
}

/// Runs `cargo xtask fuzz`; whether no target crashed.
pub(crate) fn run(root: &Path, target: &Path, options: &FuzzOptions) -> Result<bool, String> {
    let mut targets = if options.targets.is_empty() {
        all_targets(root)?
    } else {
        options.targets.clone()
    };
    if !options.texts {
        targets.retain(|t| !TEXT_TARGETS.contains(&t.as_str()));
    }
    if !build(root, target, &targets, options.texts) {
        return Err("the instrumented build failed (above)".into());
    }
    let bins = target.join(HOST).join("release");
    let inst = target.join("fuzz");
    let work = inst.join("work");
    let mut crashed = Vec::new();
    println!(
        "{:<14} {:>7} {:>9} {:>12} {:>7} {:>8} {:>7}",
        "target", "seconds", "exec/s", "execs", "cov", "ft", "crashes"
    );
    for name in &targets {
        let corpus = root.join("fuzz/corpus").join(name);
        let scratch = work.join(name);
        let artifacts = inst.join("artifacts").join(name);
        // Each run starts from the repository's corpus alone.
        let _ = std::fs::remove_dir_all(&scratch);
        for dir in [&corpus, &scratch, &artifacts] {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        let path = |p: &PathBuf| p.display().to_string();
        let mut args = vec![
            format!("-max_total_time={}", options.seconds),
            format!("-timeout={TIMEOUT_SECS}"),
            format!("-rss_limit_mb={RSS_LIMIT_MB}"),
            format!("-malloc_limit_mb={MALLOC_LIMIT_MB}"),
            "-print_final_stats=1".into(),
            format!("-artifact_prefix={}/", path(&artifacts)),
        ];
        args.extend(max_len(name).map(|n| format!("-max_len={n}")));
        // New inputs go to the scratch folder; the repository's corpus is only read.
        args.extend([path(&scratch), path(&corpus)]);
        let (ok, log) = libfuzzer(&bins.join(name), &args)?;
        let f = figures(&log);
        let crash = !ok || f.crashed;
        println!(
            "{name:<14} {:>7} {:>9} {:>12} {:>7} {:>8} {:>7}",
            options.seconds,
            f.execs_per_sec,
            f.execs,
            f.cov,
            f.ft,
            u8::from(crash)
        );
        if crash {
            let tail: Vec<&str> = log.lines().rev().take(40).collect();
            eprintln!(
                "xtask: {name} crashed; the input is in {}:",
                artifacts.display()
            );
            for line in tail.iter().rev() {
                eprintln!("  {line}");
            }
            crashed.push(name.clone());
            continue;
        }
        if options.merge {
            merge(&bins.join(name), name, &corpus, &scratch)?;
        }
    }
    if !crashed.is_empty() {
        eprintln!("xtask: crashed: {}", crashed.join(", "));
    }
    Ok(crashed.is_empty())
}

/// Replaces `corpus` by the smallest set of its and `scratch`'s inputs with the same
/// coverage (`-merge=1`).
fn merge(bin: &Path, name: &str, corpus: &Path, scratch: &Path) -> Result<(), String> {
    let merged = corpus.with_extension("merged");
    let _ = std::fs::remove_dir_all(&merged);
    std::fs::create_dir_all(&merged).map_err(|e| format!("{}: {e}", merged.display()))?;
    let mut args = vec!["-merge=1".to_string(), format!("-timeout={TIMEOUT_SECS}")];
    args.extend(max_len(name).map(|n| format!("-max_len={n}")));
    args.extend([&merged, corpus, scratch].map(|p| p.display().to_string()));
    let (ok, log) = libfuzzer(bin, &args)?;
    if !ok {
        return Err(format!("merging into {} failed:\n{log}", merged.display()));
    }
    std::fs::remove_dir_all(corpus).map_err(|e| format!("{}: {e}", corpus.display()))?;
    std::fs::rename(&merged, corpus).map_err(|e| format!("{}: {e}", corpus.display()))?;
    let _ = std::fs::remove_dir_all(scratch);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(line: &str) -> Vec<String> {
        line.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn the_command_line_is_seconds_merge_and_targets() {
        assert_eq!(
            parse(&args("--seconds 5 --merge ecat suite")),
            Ok(FuzzOptions {
                seconds: 5,
                merge: true,
                texts: true,
                targets: args("ecat suite")
            })
        );
        assert_eq!(
            parse(&args("--no-texts")).map(|o| (o.texts, o.targets)),
            Ok((false, vec![]))
        );
        assert_eq!(parse(&[]).map(|o| o.seconds), Ok(60));
        assert!(parse(&args("--seconds 0")).is_err());
        assert!(parse(&args("--seconds")).is_err());
        assert_eq!(
            parse(&args("--jobs 2")),
            Err("unknown option `--jobs`".into())
        );
    }

    #[test]
    fn the_figures_are_the_last_status_and_the_final_stats() {
        // libFuzzer's output of a run of 2 s (shortened).
        let log = "\
INFO: Seed: 1234
#2\tINITED cov: 811 ft: 1201 corp: 40/2Kb exec/s: 0 rss: 40Mb
#4096\tpulse  cov: 820 ft: 1300 corp: 45/3Kb lim: 100 exec/s: 2048 rss: 41Mb
#9000\tDONE   cov: 825 ft: 1333 corp: 47/3Kb lim: 120 exec/s: 4500 rss: 42Mb
Done 9000 runs in 2 second(s)
stat::number_of_executed_units: 9000
stat::average_exec_per_sec:     4500
stat::new_units_added:          7
";
        assert_eq!(
            figures(log),
            Figures {
                execs: 9000,
                execs_per_sec: 4500,
                cov: 825,
                ft: 1333,
                crashed: false
            }
        );
        let crash = "thread '<unnamed>' panicked at proto/src/x.rs:1:1:\n==12== ERROR: libFuzzer: deadly signal";
        assert!(figures(crash).crashed);
    }
}
