//! The run's record: which harness and which suites ran, when, and how they were called
//! ([`RunMeta`]), so that a report says what was tested without anyone's memory of the run.

use std::path::Path;
use std::process::Command;

use crate::outcome::RunMeta;

/// The harness's git revision, recorded when it was built (see `build.rs`).
pub(crate) const HARNESS_REVISION: &str = env!("HARNESS_GIT_REVISION");

/// The record of a run starting now, of the suites in `dir` whose content hashes to `digest`;
/// what the run finds (the DUT's identities, the limits it kept) the runner adds.
pub(crate) fn start(dir: &Path, digest: &str) -> RunMeta {
    RunMeta {
        harness_version: env!("CARGO_PKG_VERSION").into(),
        harness_revision: HARNESS_REVISION.into(),
        suites_revision: suites_revision(dir, digest),
        started: humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string(),
        host: std::fs::read_to_string("/proc/sys/kernel/hostname")
            .map(|h| h.trim().to_string())
            .unwrap_or_default(),
        command_line: std::env::args().collect(),
        ..RunMeta::default()
    }
}

/// `git <commit>[-dirty], sha256:<digest>`: the suites' commit where they are in a git
/// checkout (`-dirty` when a suite file differs from it), and always their content digest,
/// which names them exactly even outside git or with changes.
fn suites_revision(dir: &Path, digest: &str) -> String {
    let git = |args: &[&str]| -> Option<String> {
        let out = Command::new("git")
            .arg("-C")
            .arg(dir)
            .args(args)
            .output()
            .ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    let content = format!("sha256:{digest}");
    match git(&["log", "-1", "--format=%H", "--", "."]).filter(|c| !c.is_empty()) {
        Some(commit) => {
            let dirty = git(&["status", "--porcelain", "--", "."]).is_some_and(|s| !s.is_empty());
            format!(
                "git {commit}{}, {content}",
                if dirty { "-dirty" } else { "" }
            )
        }
        None => content,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outside_git_the_suites_are_named_by_their_content() {
        let dir = std::env::temp_dir().join(format!("record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(suites_revision(&dir, "ab12"), "sha256:ab12");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_checked_in_suites_carry_their_commit_and_digest() {
        let suites = Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites");
        let r = suites_revision(&suites, "ab12");
        // A clone without git (a source tarball) has the digest alone.
        if Command::new("git")
            .arg("-C")
            .arg(&suites)
            .arg("rev-parse")
            .output()
            .is_ok_and(|o| o.status.success())
        {
            assert!(r.starts_with("git "), "{r}");
            let commit = r.split(' ').nth(1).unwrap_or_default();
            assert_eq!(
                commit
                    .trim_end_matches(',')
                    .trim_end_matches("-dirty")
                    .len(),
                40,
                "{r}"
            );
        }
        assert!(r.ends_with(", sha256:ab12") || r == "sha256:ab12", "{r}");
    }
}
