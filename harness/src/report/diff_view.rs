//! A [`RunDiff`] for people: plain text for the terminal, `diff.md` and a self-contained
//! `diff.html`. All three show the same things in the same order: both runs' identities, the
//! headline, the verdict changes (regressions marked), every changed transcript's hunks side by
//! side (old line against new line), the new and the vanished cases.

use std::fmt::Write;
use std::path::{Path, PathBuf};

use super::diff::{CaseChange, Hunk, LoneCase, Numbered, Row, RunDiff, RunSide};
use super::markup::text as esc;
use super::write::{write_file, ReportError};
use crate::outcome::Verdict;

/// Writes `diff.md` and `diff.html` into `out`; returns their paths.
pub(crate) fn write_diff(d: &RunDiff, out: &Path) -> Result<[PathBuf; 2], ReportError> {
    let files = [out.join("diff.md"), out.join("diff.html")];
    write_file(&files[0], markdown(d).as_bytes())?;
    write_file(&files[1], html(d).as_bytes())?;
    Ok(files)
}

/// The rows of the header table: label, old value, new value.
fn header_rows(d: &RunDiff) -> Vec<(String, String, String)> {
    let both =
        |label: &str, f: &dyn Fn(&RunSide) -> String| (label.to_string(), f(&d.old), f(&d.new));
    let mut rows = vec![
        both("report", &|s| s.source.clone()),
        both("DUT", &|s| s.dut.clone()),
        both("harness", &|s| {
            let m = &s.meta;
            if m.harness_version.is_empty() {
                String::new()
            } else {
                format!("{} ({})", m.harness_version, m.harness_revision)
            }
        }),
        both("suites", &|s| s.meta.suites_revision.clone()),
        both("started", &|s| s.meta.started.clone()),
        both("host", &|s| s.meta.host.clone()),
        both("command line", &|s| s.meta.command_line.join(" ")),
    ];
    let mut profiles: Vec<&String> = d
        .old
        .meta
        .identities
        .keys()
        .chain(d.new.meta.identities.keys())
        .collect();
    profiles.sort();
    profiles.dedup();
    for p in profiles {
        let id = |s: &RunSide| {
            s.meta
                .identities
                .get(p)
                .map(|i| i.line())
                .unwrap_or_default()
        };
        rows.push((format!("identity {p}"), id(&d.old), id(&d.new)));
    }
    rows.push(both("verdicts", &|s| {
        Verdict::ALL
            .iter()
            .zip(s.counts)
            .map(|(v, n)| format!("{} {n}", v.name()))
            .collect::<Vec<_>>()
            .join(", ")
    }));
    // A report from a harness that did not record a field leaves it out.
    rows.retain(|(_, old, new)| !(old.is_empty() && new.is_empty()));
    rows
}

fn verdict_change(c: &CaseChange) -> String {
    let mut s = format!("{} → {}", c.old.verdict.name(), c.new.verdict.name());
    if c.regressed() {
        s.push_str(" (regression)");
    } else if c.new_failure() {
        s.push_str(" (new failure)");
    } else if c.lost_coverage() {
        s.push_str(" (coverage lost)");
    }
    s
}

/// A change that gates under the default rule: a regression or a new failure.
fn gates(c: &CaseChange) -> bool {
    c.regressed() || c.new_failure()
}

/// A lone case's verdict, marked when it is a new failure (a new case that fails or errs).
fn lone_verdict(c: &LoneCase, added: bool) -> String {
    let v = c.side.verdict.name();
    if added && matches!(c.side.verdict, Verdict::Fail | Verdict::Error) {
        format!("{v} (new failure)")
    } else {
        v.to_string()
    }
}

fn verdicts_changed(d: &RunDiff) -> impl Iterator<Item = &CaseChange> {
    d.changed.iter().filter(|c| c.old.verdict != c.new.verdict)
}

fn transcripts_changed(d: &RunDiff) -> impl Iterator<Item = (&CaseChange, &[Hunk])> {
    d.changed
        .iter()
        .filter_map(|c| c.transcript.as_ref().map(|t| (c, t.hunks.as_slice())))
}

/// The new and the vanished cases, each with its title and whether it is the new run's.
fn lone_sections(d: &RunDiff) -> [(&'static str, &[LoneCase], bool); 2] {
    [
        ("New cases (only in the new run)", &d.added, true),
        ("Vanished cases (only in the old run)", &d.vanished, false),
    ]
}

/// For the terminal.
pub(crate) fn text(d: &RunDiff) -> String {
    let mut s = String::new();
    for (label, old, new) in header_rows(d) {
        if old == new {
            let _ = writeln!(s, "{label}: {old}");
        } else {
            let _ = writeln!(s, "{label}: {old}  →  {new}");
        }
    }
    let _ = writeln!(s, "\n{}", d.headline());
    let mut changes = verdicts_changed(d).peekable();
    if changes.peek().is_some() {
        let _ = writeln!(s, "\nVerdict changes:");
    }
    for c in changes {
        let _ = writeln!(s, "  {} {}: {}", c.profile, c.id, verdict_change(c));
        let _ = writeln!(s, "    old: {}", or_dash(&c.old.message));
        let _ = writeln!(s, "    new: {}", or_dash(&c.new.message));
    }
    let mut transcripts = transcripts_changed(d).peekable();
    if transcripts.peek().is_some() {
        let _ = writeln!(s, "\nTranscript changes (- old, + new):");
    }
    for (c, hunks) in transcripts {
        let _ = writeln!(s, "  {} {}", c.profile, c.id);
        for h in hunks {
            let _ = writeln!(s, "    @ {}", h.place);
            for r in &h.rows {
                match r {
                    Row::Same { old: l, .. } => {
                        let _ = writeln!(s, "      {:>4} {}", l.at, l.text);
                    }
                    Row::Changed { old, new } => {
                        for (sign, l) in [('-', old), ('+', new)] {
                            if let Some(l) = l {
                                let _ = writeln!(s, "    {sign} {:>4} {}", l.at, l.text);
                            }
                        }
                    }
                }
            }
        }
    }
    for (title, cases, added) in lone_sections(d) {
        if !cases.is_empty() {
            let _ = writeln!(s, "\n{title}:");
        }
        for c in cases {
            let _ = writeln!(
                s,
                "  {} {}: {}{}",
                c.profile,
                c.id,
                lone_verdict(c, added),
                if c.side.message.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", c.side.message)
                }
            );
        }
    }
    s
}

fn or_dash(s: &str) -> &str {
    if s.is_empty() {
        "—"
    } else {
        s
    }
}

/// A Markdown table cell: `|` escaped, line breaks as spaces.
fn md(s: &str) -> String {
    s.replace('\\', "\\\\")
        .replace('|', "\\|")
        .replace(['\n', '\r'], " ")
}

/// A transcript line in a Markdown cell: as code, so its leading spaces and hex keep their
/// shape; empty stays empty.
fn md_code(l: Option<&Numbered>) -> (String, String) {
    match l {
        None => (String::new(), String::new()),
        Some(l) if l.text.trim().is_empty() => (l.at.to_string(), String::new()),
        Some(l) => {
            let fence = if l.text.contains('`') { "``" } else { "`" };
            (l.at.to_string(), format!("{fence} {} {fence}", md(&l.text)))
        }
    }
}

/// `diff.md`.
pub(crate) fn markdown(d: &RunDiff) -> String {
    let mut s = String::from("# Run comparison\n\n| | old | new |\n|---|---|---|\n");
    for (label, old, new) in header_rows(d) {
        let _ = writeln!(s, "| {} | {} | {} |", md(&label), md(&old), md(&new));
    }
    let _ = writeln!(s, "\n**{}**", d.headline());
    let mut changes = verdicts_changed(d).peekable();
    if changes.peek().is_some() {
        s.push_str("\n## Verdict changes\n\n| profile | case | verdict | old message | new message |\n|---|---|---|---|---|\n");
    }
    for c in changes {
        let v = verdict_change(c);
        let v = if gates(c) { format!("**{v}**") } else { v };
        let _ = writeln!(
            s,
            "| {} | `{}` | {} | {} | {} |",
            md(&c.profile),
            md(&c.id),
            v,
            md(&c.old.message),
            md(&c.new.message)
        );
    }
    let mut transcripts = transcripts_changed(d).peekable();
    if transcripts.peek().is_some() {
        s.push_str("\n## Transcript changes\n");
    }
    for (c, hunks) in transcripts {
        let _ = writeln!(
            s,
            "\n### {} `{}` — {}\n",
            md(&c.profile),
            md(&c.id),
            md(&c.title)
        );
        for h in hunks {
            let _ = writeln!(
                s,
                "*{}*\n\n| line | old | line | new |\n|---:|---|---:|---|",
                md(&h.place)
            );
            for r in &h.rows {
                let (old, new) = match r {
                    Row::Same { old, new } => (Some(old), Some(new)),
                    Row::Changed { old, new } => (old.as_ref(), new.as_ref()),
                };
                let (mut o, mut n) = (md_code(old), md_code(new));
                if matches!(r, Row::Changed { .. }) {
                    for (_, t) in [&mut o, &mut n] {
                        if !t.is_empty() {
                            *t = format!("**{t}**");
                        }
                    }
                }
                let _ = writeln!(s, "| {} | {} | {} | {} |", o.0, o.1, n.0, n.1);
            }
            s.push('\n');
        }
    }
    for (title, cases, added) in lone_sections(d) {
        if cases.is_empty() {
            continue;
        }
        let _ = writeln!(
            s,
            "\n## {title}\n\n| profile | case | verdict | message |\n|---|---|---|---|"
        );
        for c in cases {
            let _ = writeln!(
                s,
                "| {} | `{}` | {} | {} |",
                md(&c.profile),
                md(&c.id),
                lone_verdict(c, added),
                md(&c.side.message)
            );
        }
    }
    s
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse;margin:.5em 0}\
td,th{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}\
td.code{font-family:monospace;white-space:pre}td.n{text-align:right;color:#888}\
tr.changed td.old{background:#fdd}tr.changed td.new{background:#dfd}.regression{color:#b00;font-weight:bold}";

/// `diff.html`: one file, no scripts, every text escaped.
pub(crate) fn html(d: &RunDiff) -> String {
    let mut s = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Run comparison</title><style>{STYLE}</style></head><body>\n<h1>Run comparison</h1>\n<table><tr><th></th><th>old</th><th>new</th></tr>\n"
    );
    for (label, old, new) in header_rows(d) {
        let _ = writeln!(
            s,
            "<tr><th>{}</th><td>{}</td><td>{}</td></tr>",
            esc(&label),
            esc(&old),
            esc(&new)
        );
    }
    let _ = writeln!(
        s,
        "</table>\n<p><strong>{}</strong></p>",
        esc(&d.headline())
    );
    let mut changes = verdicts_changed(d).peekable();
    if changes.peek().is_some() {
        s.push_str("<h2>Verdict changes</h2>\n<table><tr><th>profile</th><th>case</th><th>verdict</th><th>old message</th><th>new message</th></tr>\n");
        for c in changes {
            let class = if gates(c) {
                " class=\"regression\""
            } else {
                ""
            };
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td>{}</td><td{class}>{}</td><td>{}</td><td>{}</td></tr>",
                esc(&c.profile),
                esc(&c.id),
                esc(&verdict_change(c)),
                esc(&c.old.message),
                esc(&c.new.message)
            );
        }
        s.push_str("</table>\n");
    }
    let mut transcripts = transcripts_changed(d).peekable();
    if transcripts.peek().is_some() {
        s.push_str("<h2>Transcript changes</h2>\n");
    }
    for (c, hunks) in transcripts {
        let _ = writeln!(
            s,
            "<h3>{} {} — {}</h3>",
            esc(&c.profile),
            esc(&c.id),
            esc(&c.title)
        );
        for h in hunks {
            let _ = writeln!(
                s,
                "<p><em>{}</em></p>\n<table><tr><th>line</th><th>old</th><th>line</th><th>new</th></tr>",
                esc(&h.place)
            );
            for r in &h.rows {
                let (class, old, new) = match r {
                    Row::Same { old, new } => ("same", Some(old), Some(new)),
                    Row::Changed { old, new } => ("changed", old.as_ref(), new.as_ref()),
                };
                let cell = |l: Option<&Numbered>, side: &str| match l {
                    Some(l) => format!(
                        "<td class=\"n\">{}</td><td class=\"code {side}\">{}</td>",
                        l.at,
                        esc(&l.text)
                    ),
                    None => format!("<td class=\"n\"></td><td class=\"code {side}\"></td>"),
                };
                let _ = writeln!(
                    s,
                    "<tr class=\"{class}\">{}{}</tr>",
                    cell(old, "old"),
                    cell(new, "new")
                );
            }
            s.push_str("</table>\n");
        }
    }
    for (title, cases, added) in lone_sections(d) {
        if cases.is_empty() {
            continue;
        }
        let _ = writeln!(
            s,
            "<h2>{}</h2>\n<table><tr><th>profile</th><th>case</th><th>verdict</th><th>message</th></tr>",
            esc(title)
        );
        for c in cases {
            let v = lone_verdict(c, added);
            let class = if v.ends_with("(new failure)") {
                " class=\"regression\""
            } else {
                ""
            };
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td>{}</td><td{class}>{}</td><td>{}</td></tr>",
                esc(&c.profile),
                esc(&c.id),
                v,
                esc(&c.side.message)
            );
        }
        s.push_str("</table>\n");
    }
    s.push_str("</body></html>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::diff::compare_runs;
    use crate::report::fixtures::sample_run;

    /// The sample run against a "new firmware" that answers the P102 write with PWE 251 (the
    /// passing case fails) and titles one case with markup.
    fn diff() -> RunDiff {
        let old = sample_run();
        let mut new = sample_run();
        let c = &mut new.cases[0];
        c.steps[0].exchanges[0].received_hex = "65 02 14 4E 01 00 00 00 00 FB".into();
        c.verdict = Verdict::Fail;
        c.message = "pwe: expected 250, got <251> | \"x\"".into();
        c.title = "<script>alert(1)</script>".into();
        new.cases.remove(4);
        // Not applicable → fail: a new failure, no regression.
        new.cases[2].verdict = Verdict::Fail;
        new.cases[2].message = "now it applies and fails".into();
        // A case only the new run has, and it errs.
        let mut added = sample_run().cases.remove(3);
        added.id = "bu0620/new/errs".into();
        new.cases.push(added);
        compare_runs(crate::buses::BUSES, "old/", &old, "new/", &new)
    }

    #[test]
    fn new_failures_are_marked_in_all_three() {
        let d = diff();
        let t = text(&d);
        assert!(
            t.contains(
                "  tu3-eip bu0620/addressing/coe-p102: not_applicable → fail (new failure)\n"
            ),
            "{t}"
        );
        assert!(
            t.contains("New cases (only in the new run):\n  tu3-eip bu0620/new/errs: error (new failure) (no answer"),
            "{t}"
        );
        let m = markdown(&d);
        assert!(
            m.contains("| tu3-eip | `bu0620/addressing/coe-p102` | **not_applicable → fail (new failure)** |"),
            "{m}"
        );
        assert!(
            m.contains("| tu3-eip | `bu0620/new/errs` | error (new failure) |"),
            "{m}"
        );
        let h = html(&d);
        assert!(
            h.contains("<td class=\"regression\">not_applicable → fail (new failure)</td>"),
            "{h}"
        );
        assert!(
            h.contains("<td>bu0620/new/errs</td><td class=\"regression\">error (new failure)</td>"),
            "{h}"
        );
    }

    #[test]
    fn text_shows_the_flip_its_messages_and_the_changed_exchange() {
        let t = text(&diff());
        assert!(t.contains("report: old/  →  new/\n"), "{t}");
        assert!(
            t.contains("harness: 0.1.0 (0123456789abcdef0123456789abcdef01234567)\n"),
            "{t}"
        );
        assert!(
            t.contains("identity sk550p: NORD SK 550P, firmware V1.2 R0, serial 123456"),
            "{t}"
        );
        assert!(
            t.contains("  sk550p bu0620/pkw-telegrams/p102-write: pass → fail (regression)\n    old: —\n    new: pwe: expected 250, got <251> | \"x\"\n"),
            "{t}"
        );
        assert!(
            t.contains("    @ step 1: pkw FI 2: 24 4E 01 00 00 00 00 FA\n        10   -> 65 02 24 4E 01 00 00 00 00 FA\n        11      AK 2, PNU 1102 = P102, IND 0100h, PWE 250\n    -   12   <- 65 02 14 4E 01 00 00 00 00 FA\n    +   13   <- 65 02 14 4E 01 00 00 00 00 FB\n"),
            "{t}"
        );
        assert!(
            t.contains("Vanished cases (only in the old run):\n  tu3-eip bu2100/cip/identity: inconclusive (setup step 1 failed: no connection)\n"),
            "{t}"
        );
    }

    #[test]
    fn markdown_tables_escape_pipes_and_pair_lines_side_by_side() {
        let m = markdown(&diff());
        assert!(
            m.starts_with("# Run comparison\n\n| | old | new |\n"),
            "{m}"
        );
        assert!(
            m.contains("| sk550p | `bu0620/pkw-telegrams/p102-write` | **pass → fail (regression)** |  | pwe: expected 250, got <251> \\| \"x\" |\n"),
            "{m}"
        );
        assert!(
            m.contains("| 12 | **`   <- 65 02 14 4E 01 00 00 00 00 FA `** | 13 | **`   <- 65 02 14 4E 01 00 00 00 00 FB `** |\n"),
            "{m}"
        );
        assert!(m.contains("## Vanished cases (only in the old run)"), "{m}");
    }

    #[test]
    fn html_is_one_escaped_file_without_scripts() {
        let h = html(&diff());
        assert!(h.starts_with("<!DOCTYPE html>"), "{h}");
        assert!(!h.contains("<script"), "title escaped");
        assert!(h.contains("&lt;script&gt;alert(1)&lt;/script&gt;"), "{h}");
        assert!(h.contains("got &lt;251&gt; | &quot;x&quot;"), "{h}");
        assert!(
            h.contains("<td class=\"regression\">pass → fail (regression)</td>"),
            "{h}"
        );
        assert!(
            h.contains("<tr class=\"changed\"><td class=\"n\">12</td><td class=\"code old\">  &lt;- 65 02 14 4E 01 00 00 00 00 FA</td><td class=\"n\">13</td><td class=\"code new\">  &lt;- 65 02 14 4E 01 00 00 00 00 FB</td></tr>"),
            "{h}"
        );
        assert!(
            h.contains("<tr class=\"same\"><td class=\"n\">11</td><td class=\"code old\">     AK 2, PNU 1102 = P102, IND 0100h, PWE 250</td><td class=\"n\">12</td>"),
            "context lines carry each side's number (the new run has a message line more): {h}"
        );
        assert!(
            !h.contains("src=") && !h.contains("href="),
            "self-contained"
        );
    }
}
