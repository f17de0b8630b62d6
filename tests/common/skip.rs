//! The one rule for a test that needs something a machine may lack (root, `ip`, tshark,
//! chromium, xmllint, the interop venv): without it the test skips, saying what is missing and
//! why, and records the skip; in strict mode it fails with the same words instead, so a run can
//! never pass by skipping.
//!
//! Strict mode is on when `NORD_TEST_STRICT` is set (`cargo xtask test --strict`, `.ci/run`),
//! or any of the CI systems' variables `CI`, `JENKINS_URL`, `GITLAB_CI`: set to anything but
//! empty, `0` or `false`.
//!
//! Every skip, and every failure strict mode made of one, is appended as a line
//! `skip|fail TAB <test binary>::<test> TAB <reason>` to the file `NORD_TEST_SKIP_LOG` names,
//! when it is set: `cargo xtask test` sets it and lists those lines at the end of the run.
//!
//! Standard library only: the harness's own unit tests include this file too
//! (`harness/src/net/veth.rs`).

#![allow(dead_code)] // each test binary uses a part

use std::io::Write;

/// The variables that turn strict mode on: the switch itself, then the CI systems' own.
pub(crate) const STRICT_VARS: [&str; 4] = ["NORD_TEST_STRICT", "CI", "JENKINS_URL", "GITLAB_CI"];

/// What a test does about something it needs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Decision {
    /// It is there: run.
    Run,
    /// Missing, not strict: skip, saying this.
    Skip(String),
    /// Missing in strict mode: fail, saying this.
    Fail(String),
}

/// The rule itself: `strict` names the variable that made the run strict (`None`: not strict),
/// `missing` what is not there (`None`: all is), `why` what the test would have checked.
pub(crate) fn decide(strict: Option<&str>, missing: Option<&str>, why: &str) -> Decision {
    match (missing, strict) {
        (None, _) => Decision::Run,
        (Some(what), Some(var)) => Decision::Fail(format!(
            "{why}: needs {what}, and strict mode ({var} is set) must not skip it"
        )),
        (Some(what), None) => Decision::Skip(format!("{why}: needs {what}")),
    }
}

/// The first of [`STRICT_VARS`] that `var` says is set (not empty, `0` or `false`).
pub(crate) fn strict_by(var: impl Fn(&str) -> Option<String>) -> Option<&'static str> {
    STRICT_VARS
        .into_iter()
        .find(|name| var(name).is_some_and(|v| !matches!(v.trim(), "" | "0" | "false")))
}

/// The variable that makes this run strict, if any.
pub(crate) fn strict() -> Option<&'static str> {
    strict_by(|name| std::env::var(name).ok())
}

/// The running test as `<test binary>::<test>`: libtest names each test's thread after it.
fn test_name() -> String {
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("(unnamed thread)");
    format!("{}::{test}", env!("CARGO_CRATE_NAME"))
}

/// One line of the skip log: `kind TAB test TAB reason`, tabs and line breaks in the reason
/// made spaces.
pub(crate) fn log_line(kind: &str, test: &str, reason: &str) -> String {
    let reason = reason.replace(['\t', '\n', '\r'], " ");
    format!("{kind}\t{test}\t{reason}\n")
}

/// A line of the skip log as its kind, test and reason (`None`: not such a line).
pub(crate) fn parse_log_line(line: &str) -> Option<(&str, &str, &str)> {
    let mut fields = line.trim_end_matches(['\n', '\r']).splitn(3, '\t');
    Some((fields.next()?, fields.next()?, fields.next()?))
}

/// Appends `kind`'s line for the running test to the skip log, when there is one. A log that
/// cannot be written fails the test: the list at the end of the run would lie.
fn record(kind: &str, reason: &str) {
    let Some(path) = std::env::var_os("NORD_TEST_SKIP_LOG").filter(|p| !p.is_empty()) else {
        return;
    };
    let line = log_line(kind, &test_name(), reason);
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| f.write_all(line.as_bytes()))
        .unwrap_or_else(|e| panic!("skip log {}: {e}", path.to_string_lossy()));
}

/// `true` when `have` holds; else skips (`false`, after printing and recording why) or, in
/// strict mode, fails. `what` names what is missing and how to get it, `why` what the test
/// checks.
pub(crate) fn require_or_skip(have: bool, what: &str, why: &str) -> bool {
    match decide(strict(), (!have).then_some(what), why) {
        Decision::Run => true,
        Decision::Skip(message) => {
            eprintln!("skipped: {message}");
            record("skip", &message);
            false
        }
        Decision::Fail(message) => {
            record("fail", &message);
            panic!("{message}")
        }
    }
}

/// The one skip strict mode lets pass: SocketCAN needs a kernel with AF_CAN and the `vcan`
/// module, which some machines lack (this project's CI among them); the README says so. `true`
/// when `have` holds; else prints and records the skip and returns `false`, strict or not.
#[allow(dead_code)] // only the SocketCAN test uses it
pub(crate) fn allowed_skip(have: bool, what: &str, why: &str) -> bool {
    if !have {
        let message = format!("{why}: needs {what} (the one skip allowed under CI)");
        eprintln!("skipped: {message}");
        record("skip", &message);
    }
    have
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_peer_skips_unless_strict_and_then_fails() {
        assert_eq!(decide(None, None, "w"), Decision::Run);
        assert_eq!(decide(Some("CI"), None, "w"), Decision::Run);
        assert_eq!(
            decide(None, Some("tshark"), "the capture"),
            Decision::Skip("the capture: needs tshark".into())
        );
        assert_eq!(
            decide(Some("JENKINS_URL"), Some("tshark"), "the capture"),
            Decision::Fail(
                "the capture: needs tshark, and strict mode (JENKINS_URL is set) must not skip it"
                    .into()
            )
        );
    }

    #[test]
    fn strict_mode_is_the_switch_or_any_ci_variable_set() {
        let with = |set: &'static [(&'static str, &'static str)]| {
            strict_by(move |name| {
                set.iter()
                    .find(|(n, _)| *n == name)
                    .map(|(_, v)| v.to_string())
            })
        };
        assert_eq!(with(&[]), None);
        assert_eq!(with(&[("CI", ""), ("GITLAB_CI", "0")]), None);
        assert_eq!(
            with(&[("NORD_TEST_STRICT", "false"), ("CI", "false")]),
            None
        );
        assert_eq!(with(&[("NORD_TEST_STRICT", "1")]), Some("NORD_TEST_STRICT"));
        assert_eq!(with(&[("CI", "true")]), Some("CI"));
        assert_eq!(
            with(&[("JENKINS_URL", "http://ci:8080/")]),
            Some("JENKINS_URL")
        );
        assert_eq!(with(&[("GITLAB_CI", "true")]), Some("GITLAB_CI"));
    }

    #[test]
    fn a_log_line_is_one_line_of_three_fields() {
        let line = log_line("skip", "network_epl::every_suite", "needs root\tfor\nnetns");
        assert_eq!(
            line,
            "skip\tnetwork_epl::every_suite\tneeds root for netns\n"
        );
        assert_eq!(
            parse_log_line(&line),
            Some(("skip", "network_epl::every_suite", "needs root for netns"))
        );
        assert_eq!(parse_log_line("skip\tno reason"), None);
        // libtest runs each test on a thread named after it.
        assert!(
            test_name().ends_with("::tests::a_log_line_is_one_line_of_three_fields"),
            "{}",
            test_name()
        );
    }
}
