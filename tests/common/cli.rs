//! The `harness` binary run as a user runs it: from the repository's root, with a scratch folder
//! of the test's own for its reports.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `harness ARGS` from the repository's root, its output collected.
pub(crate) fn harness(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_harness"))
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .args(args)
        .output()
        .expect("the harness binary runs")
}

/// An empty folder under the temporary directory, named for the test binary, `tag` and this
/// process.
pub(crate) fn scratch(binary: &str, tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("harness-{binary}-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
