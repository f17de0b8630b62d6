//! `cargo xtask test`, the README's test command: installs what the tests need
//! (`.ci/interop-setup`), runs every test binary of the workspace whatever fails
//! (`cargo test --workspace --release --no-fail-fast`), runs every fuzz target briefly (a
//! smoke: a crash fails), lists at the end each test that skipped and why, and exits with
//! cargo's status. `cargo xtask fuzz` runs the fuzz targets for longer ([`fuzz`]).
//!
//! The tests skip through one rule (`tests/common/skip.rs`, included here): each skip is
//! appended to the skip log this command names in `NORD_TEST_SKIP_LOG`, and in strict mode
//! (`--strict`, `NORD_TEST_STRICT`, or a CI system's `CI`, `JENKINS_URL`, `GITLAB_CI`) a test
//! that would skip fails instead.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

#[path = "../../tests/common/skip.rs"]
mod skip;

mod fuzz;
/// The import graph of the crates' top-level modules, checked acyclic by its tests.
#[cfg(test)]
mod imports;

/// Seconds each fuzz target runs in `cargo xtask test`'s smoke.
const SMOKE_SECONDS: u32 = 2;

const USAGE: &str = "\
usage: cargo xtask test [--strict] [--no-setup] [--no-fuzz] [-- ARGS...]
       cargo xtask fuzz [--seconds N] [--merge] [--no-texts] [TARGET...]

test: installs what the tests need (.ci/interop-setup: tshark, chromium, xmllint, iproute2 and
the interop venv in the build folder; Debian packages need root or sudo), runs
`cargo test --workspace --release --no-fail-fast [ARGS...]` (which replays the fuzz corpus),
then every fuzz target of the codecs and devices for 2 s (built instrumented; the readers'
targets need the harness instrumented, too long for CI), and lists every skipped test and why.
Exits with cargo's status, or 1 if a fuzz target crashed.

  --strict    a test that would skip fails instead (NORD_TEST_STRICT=1); also on when CI,
              JENKINS_URL or GITLAB_CI is set
  --no-setup  do not run .ci/interop-setup
  --no-fuzz   do not run the fuzz smoke

fuzz: builds the fuzz targets (fuzz/) instrumented and runs each (or each TARGET) for N
seconds (default 60) on its corpus (fuzz/corpus/TARGET), printing exec/s, executions,
coverage (cov, ft) and crashes; exits 1 if one crashed (its input is kept under
<target>/fuzz/artifacts/TARGET/). docs/fuzzing.md has the figures and how to run a campaign.

  --seconds N  seconds each target runs
  --merge      then minimise each corpus with what the run found (-merge=1) and write it back
  --no-texts   leave out the targets of the suite and description readers (the CI smoke)";

/// What the command line asks for.
#[derive(Debug, PartialEq, Eq)]
struct Options {
    /// `--strict`.
    strict: bool,
    /// Not `--no-setup`.
    setup: bool,
    /// Not `--no-fuzz`.
    fuzz: bool,
    /// After `--`: passed on to `cargo test`.
    cargo_args: Vec<String>,
}

/// The command line after `cargo xtask`; `Err` with what is wrong.
fn parse(args: &[String]) -> Result<Options, String> {
    let Some((command, rest)) = args.split_first() else {
        return Err("no command".into());
    };
    if command != "test" {
        return Err(format!("unknown command `{command}`"));
    }
    let mut options = Options {
        strict: false,
        setup: true,
        fuzz: true,
        cargo_args: Vec::new(),
    };
    for (i, arg) in rest.iter().enumerate() {
        match arg.as_str() {
            "--strict" => options.strict = true,
            "--no-setup" => options.setup = false,
            "--no-fuzz" => options.fuzz = false,
            "--" => {
                options.cargo_args = rest[i + 1..].to_vec();
                break;
            }
            other => return Err(format!("unknown option `{other}`")),
        }
    }
    Ok(options)
}

/// The target directory this command was built into (`<target>/debug/xtask`): the build
/// folder where the tests look for the interop venv.
fn target_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the path of this program");
    exe.ancestors()
        .nth(2)
        .expect("xtask runs from <target>/<profile>/")
        .to_path_buf()
}

/// The skip log's lines as the list printed at the end of the run, sorted by test.
fn skip_list(log: &str) -> Vec<String> {
    let mut lines: Vec<String> = log
        .lines()
        .filter_map(skip::parse_log_line)
        .map(|(kind, test, reason)| match kind {
            "skip" => format!("skipped: {test} — {reason}"),
            _ => format!("failed, not skipped (strict mode): {test} — {reason}"),
        })
        .collect();
    lines.sort();
    lines.dedup();
    lines
}

/// Runs `.ci/interop-setup`; whether it installed everything.
fn setup(root: &Path, venv: &Path) -> bool {
    eprintln!("xtask: installing what the tests need (.ci/interop-setup; --no-setup skips this)");
    Command::new("bash")
        .arg(root.join(".ci/interop-setup"))
        .env("INTEROP_VENV", venv)
        .status()
        .is_ok_and(|s| s.success())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--help" || a == "-h") {
        println!("{USAGE}");
        return ExitCode::SUCCESS;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask/ is in the workspace");
    if let Some(("fuzz", rest)) = args.split_first().map(|(c, r)| (c.as_str(), r)) {
        let options = match fuzz::parse(rest) {
            Ok(options) => options,
            Err(e) => {
                eprintln!("xtask: {e}\n\n{USAGE}");
                return ExitCode::from(2);
            }
        };
        return match fuzz::run(root, &target_dir(), &options) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::FAILURE,
            Err(e) => {
                eprintln!("xtask: {e}");
                ExitCode::FAILURE
            }
        };
    }
    let options = match parse(&args) {
        Ok(options) => options,
        Err(e) => {
            eprintln!("xtask: {e}\n\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let target = target_dir();
    let venv = std::env::var_os("INTEROP_VENV")
        .filter(|v| !v.is_empty())
        .map_or_else(|| target.join("interop-venv"), PathBuf::from);
    let strict = if options.strict {
        Some("--strict")
    } else {
        skip::strict()
    };
    if let Some(by) = strict {
        eprintln!("xtask: strict mode ({by}): a test that cannot run here fails");
    }

    if options.setup && !setup(root, &venv) {
        if strict.is_some() {
            eprintln!(
                "xtask: the setup did not install everything (above); strict mode stops here"
            );
            return ExitCode::FAILURE;
        }
        eprintln!(
            "xtask: the setup did not install everything (above): the tests that need it skip"
        );
    }

    let log = target.join("nord-test-skips.log");
    match std::fs::remove_file(&log) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            eprintln!("xtask: cannot clear the skip log {}: {e}", log.display());
            return ExitCode::FAILURE;
        }
        _ => {}
    }
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut test = Command::new(cargo);
    test.current_dir(root)
        .args(["test", "--workspace", "--release", "--no-fail-fast"])
        .args(&options.cargo_args)
        .env("INTEROP_VENV", &venv)
        .env("NORD_TEST_SKIP_LOG", &log);
    if options.strict {
        test.env("NORD_TEST_STRICT", "1");
    }
    let status = match test.status() {
        Ok(status) => status,
        Err(e) => {
            eprintln!("xtask: cargo test did not start: {e}");
            return ExitCode::FAILURE;
        }
    };

    let fuzzed = !options.fuzz || smoke(root, &target);

    let list = skip_list(&std::fs::read_to_string(&log).unwrap_or_default());
    println!();
    for line in &list {
        println!("{line}");
    }
    match list.len() {
        0 => println!("xtask: no test skipped"),
        1 => println!("xtask: 1 test could not run here (above)"),
        n => println!("xtask: {n} tests could not run here (above)"),
    }
    match status.code() {
        Some(0) if !fuzzed => ExitCode::FAILURE,
        Some(0) => ExitCode::SUCCESS,
        Some(code) => ExitCode::from(u8::try_from(code).unwrap_or(1)),
        None => {
            println!("xtask: cargo test ended by a signal");
            ExitCode::FAILURE
        }
    }
}

/// Runs every fuzz target for [`SMOKE_SECONDS`]; whether none crashed.
fn smoke(root: &Path, target: &Path) -> bool {
    eprintln!(
        "xtask: fuzz smoke: the codec and device targets for {SMOKE_SECONDS} s each (--no-fuzz \
         skips this)"
    );
    let options = fuzz::FuzzOptions {
        seconds: SMOKE_SECONDS,
        merge: false,
        texts: false,
        targets: Vec::new(),
    };
    match fuzz::run(root, target, &options) {
        Ok(true) => true,
        Ok(false) => {
            println!("xtask: a fuzz target crashed (above)");
            false
        }
        Err(e) => {
            println!("xtask: the fuzz smoke did not run: {e}");
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(line: &str) -> Vec<String> {
        line.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn the_command_line_is_test_its_switches_and_cargo_s_arguments() {
        assert_eq!(
            parse(&args("test")),
            Ok(Options {
                strict: false,
                setup: true,
                fuzz: true,
                cargo_args: vec![]
            })
        );
        assert_eq!(
            parse(&args(
                "test --no-setup --no-fuzz --strict -- --test network_dut --strict"
            )),
            Ok(Options {
                strict: true,
                setup: false,
                fuzz: false,
                cargo_args: args("--test network_dut --strict")
            })
        );
        assert_eq!(parse(&args("")), Err("no command".into()));
        assert_eq!(parse(&args("build")), Err("unknown command `build`".into()));
        assert_eq!(
            parse(&args("test --release")),
            Err("unknown option `--release`".into())
        );
    }

    #[test]
    fn the_skip_list_names_each_test_and_why_once() {
        let log = [
            skip::log_line("skip", "network_epl::every_suite", "needs root"),
            skip::log_line("fail", "report_html::chromium", "needs chromium"),
            skip::log_line("skip", "network_epl::every_suite", "needs root"),
            "not a line of the log\n".into(),
        ]
        .concat();
        assert_eq!(
            skip_list(&log),
            [
                "failed, not skipped (strict mode): report_html::chromium — needs chromium",
                "skipped: network_epl::every_suite — needs root",
            ]
        );
    }
}
