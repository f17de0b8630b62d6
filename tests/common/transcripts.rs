//! A case's transcript from a report folder: the section `=== <profile>/<case id>` of its
//! `transcripts.txt`, as `harness run` writes it.

#![allow(dead_code)] // each test binary uses a part

use std::path::Path;

/// The transcript of `case` under `profile` in the report folder `out`.
pub(crate) fn transcript(out: &Path, profile: &str, case: &str) -> String {
    let file = out.join("transcripts.txt");
    let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    section(&text, profile, case)
        .unwrap_or_else(|| panic!("{}: no transcript of {profile} {case}", file.display()))
}

/// The section of `profile`'s `case` in a `transcripts.txt` text, if there is one.
pub(crate) fn section(text: &str, profile: &str, case: &str) -> Option<String> {
    let header = format!("=== {profile}/{case}\n");
    let start = if text.starts_with(&header) {
        header.len()
    } else {
        text.find(&format!("\n{header}"))? + 1 + header.len()
    };
    let body = &text[start..];
    let end = body.find("\n=== ").map_or(body.len(), |i| i + 1);
    Some(body[..end].to_string())
}
