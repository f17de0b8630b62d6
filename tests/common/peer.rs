//! What end-to-end tests need that a developer's machine may lack — root (network namespaces,
//! raw sockets, capturing on `lo`), `ip`, tshark, the interop venv with its third-party peers —
//! and how to find it; whether a test without it skips or fails is [`skip`]'s one rule.
//! `cargo xtask test` installs every peer (`.ci/interop-setup`) before the tests run.

#![allow(dead_code)] // each test binary uses a part

use std::path::PathBuf;
use std::process::{Command, Stdio};

#[path = "skip.rs"]
mod skip;
#[allow(unused_imports)] // allowed_skip: only the SocketCAN test takes the one allowed skip
pub(crate) use skip::{allowed_skip, require_or_skip};

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

/// tshark, or the test skips (fails in strict mode).
pub(crate) fn require_tshark(why: &str) -> bool {
    require_or_skip(
        runs("tshark", "--version"),
        "tshark (`cargo xtask test` installs it: .ci/interop-setup)",
        why,
    )
}

/// The interop venv: `$INTEROP_VENV` when set, else `interop-venv` in the build folder (the
/// target directory), where `.ci/interop-setup` makes it. Never a shared place such as `/tmp`,
/// where another process's venv would be taken for this checkout's.
pub(crate) fn interop_venv() -> PathBuf {
    match std::env::var_os("INTEROP_VENV").filter(|v| !v.is_empty()) {
        Some(venv) => PathBuf::from(venv),
        // Cargo's scratch folder for integration tests is `<target dir>/tmp`.
        None => PathBuf::from(env!("CARGO_TARGET_TMPDIR")).with_file_name("interop-venv"),
    }
}

/// The interop venv's python ([`interop_venv`]) able to import every one of `modules`, or the
/// test skips (fails in strict mode).
pub(crate) fn interop_python(modules: &[&str], why: &str) -> Option<PathBuf> {
    let venv = interop_venv();
    let python = venv.join("bin/python");
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
        "the interop venv {} with {} (`cargo xtask test` makes it: .ci/interop-setup)",
        venv.display(),
        modules.join(", ")
    );
    require_or_skip(have, &what, why).then_some(python)
}
