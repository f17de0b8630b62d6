//! The one rule for end-to-end tests that need something a developer's machine may lack —
//! root (network namespaces, raw sockets, capturing on `lo`), `ip`, tshark, the interop venv
//! with its third-party peers: without it a test says what is missing and why it skips; when
//! `CI` is set (any non-empty value) it fails with the same words instead, so a CI run can
//! never pass by skipping. `.ci/run` installs every peer before the tests run.

#![allow(dead_code)] // each test binary uses a part

use std::path::PathBuf;
use std::process::{Command, Stdio};

/// What a test does about something it needs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Decision {
    /// It is there: run.
    Run,
    /// Missing on a developer's machine: skip, saying this.
    Skip(String),
    /// Missing under CI: fail, saying this.
    Fail(String),
}

/// The rule itself: `missing` names what is not there (`None`: all is), `why` what the test
/// would have checked.
pub(crate) fn decide(ci: bool, missing: Option<&str>, why: &str) -> Decision {
    match missing {
        None => Decision::Run,
        Some(what) if ci => Decision::Fail(format!("{why}: needs {what}, and CI must not skip it")),
        Some(what) => Decision::Skip(format!("skipped: {why}: needs {what}")),
    }
}

/// Whether this run is CI's (the `CI` environment variable set and not empty).
pub(crate) fn in_ci() -> bool {
    std::env::var_os("CI").is_some_and(|v| !v.is_empty())
}

/// `true` when `have` holds; else skips (`false`, after printing why) or, under CI, fails.
pub(crate) fn require_or_skip(have: bool, what: &str, why: &str) -> bool {
    match decide(in_ci(), (!have).then_some(what), why) {
        Decision::Run => true,
        Decision::Skip(message) => {
            eprintln!("{message}");
            false
        }
        Decision::Fail(message) => panic!("{message}"),
    }
}

/// Whether this process runs as root (effective user id 0, from `/proc/self/status`).
pub(crate) fn is_root() -> bool {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let euid = status
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))
        .and_then(|ids| ids.split_whitespace().nth(1).map(str::to_string));
    euid.as_deref() == Some("0")
}

/// Whether `program ARG` runs and succeeds (a tool on the `PATH`).
pub(crate) fn runs(program: &str, arg: &str) -> bool {
    Command::new(program)
        .arg(arg)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// tshark, or the test skips (fails under CI).
pub(crate) fn require_tshark(why: &str) -> bool {
    require_or_skip(
        runs("tshark", "--version"),
        "tshark (bash .ci/interop-setup installs it)",
        why,
    )
}

/// The interop venv's python (`.ci/interop-setup`, `$INTEROP_VENV`) able to import every one
/// of `modules`, or the test skips (fails under CI).
pub(crate) fn interop_python(modules: &[&str], why: &str) -> Option<PathBuf> {
    let venv = std::env::var("INTEROP_VENV").unwrap_or_else(|_| "/tmp/nord-interop-venv".into());
    let python = PathBuf::from(venv).join("bin/python");
    let imports = modules
        .iter()
        .map(|m| format!("import {m}"))
        .collect::<Vec<_>>()
        .join("; ");
    let have = python.exists()
        && Command::new(&python)
            .args(["-c", &imports])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
    let what = format!(
        "the interop venv with {} (bash .ci/interop-setup)",
        modules.join(", ")
    );
    require_or_skip(have, &what, why).then_some(python)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_peer_skips_on_a_developer_machine_and_fails_under_ci() {
        assert_eq!(decide(false, None, "w"), Decision::Run);
        assert_eq!(decide(true, None, "w"), Decision::Run);
        assert_eq!(
            decide(false, Some("tshark"), "the capture"),
            Decision::Skip("skipped: the capture: needs tshark".into())
        );
        assert_eq!(
            decide(true, Some("tshark"), "the capture"),
            Decision::Fail("the capture: needs tshark, and CI must not skip it".into())
        );
    }
}
