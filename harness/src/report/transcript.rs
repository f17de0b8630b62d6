//! A case's transcript: header (id, title, manual reference, verdict), then every step with its
//! verdict, observation, message and link exchanges in hex and decoded.
//!
//! Deterministic: no timestamps and no durations, so transcripts can be stored as snapshots and
//! diffed across firmware releases (see `snapshot.rs`). Layout:
//!
//! ```text
//! case: <id>
//! title: <title>
//! manual: <doc> (<edition>) §<section> p. <page>
//! profile: <profile>
//! verdict: <verdict>
//! message: <message>            (only when not empty)
//!
//! step <n>: <step line>
//!   verdict: <verdict>
//!   observed: <compact JSON>    (only when not null)
//!   message: <message>          (only when not empty)
//!   -> <sent hex>
//!      <sent decoded>
//!   <- <received hex>           (`(nothing received)` when the DUT stayed silent)
//!      <received decoded>
//! ```
//!
//! An attempt that did not count (the host was late while a step waited on the device, see
//! `crate::timing`) comes first, as `attempt <k> discarded: <why>` and its steps as
//! `attempt <k>, step <n>: …`; then `attempt <k> (counted):` and the steps above.

use std::fmt::Write;

#[cfg(test)]
use crate::outcome::Verdict;
use crate::outcome::{CaseResult, Exchange, StepResult};

fn exchange(s: &mut String, x: &Exchange) {
    let _ = writeln!(s, "  -> {}\n     {}", x.sent_hex, x.sent);
    if x.received_hex.is_empty() && x.received.is_empty() {
        let _ = writeln!(s, "  <- (nothing received)");
    } else if x.received_hex.is_empty() {
        // What the harness made of the silence (POWERLINK: a PRes missing).
        let _ = writeln!(s, "  <- (nothing received: {})", x.received);
    } else {
        let _ = writeln!(s, "  <- {}\n     {}", x.received_hex, x.received);
    }
}

/// The transcript text of one case: its header, then its steps as rendered from them, or as
/// kept (a case that ran has them sealed, see [`seal`]; a case read back from a report folder,
/// where `run.json` holds its deciding step at most, has the text its transcript file held).
pub(crate) fn render(c: &CaseResult) -> String {
    let mut s = header(c);
    match &c.transcript {
        Some(body) => s.push_str(body),
        None => body(&mut s, c),
    }
    s
}

/// The lines before the steps: id, title, manual reference, profile, verdict, message.
fn header(c: &CaseResult) -> String {
    let mut s = String::new();
    let m = &c.manual;
    let _ = writeln!(s, "case: {}\ntitle: {}", c.id, c.title);
    let _ = writeln!(s, "manual: {} ({}) {}", m.doc, m.edition, m.place());
    let _ = writeln!(s, "profile: {}\nverdict: {}", c.profile, c.verdict.name());
    if !c.message.is_empty() {
        let _ = writeln!(s, "message: {}", c.message);
    }
    s
}

/// The attempts that did not count and the steps, with their exchanges.
fn body(s: &mut String, c: &CaseResult) {
    for (n, d) in (1..).zip(&c.discarded) {
        let _ = writeln!(s, "\nattempt {n} discarded: {}", d.why);
        steps(s, &format!("attempt {n}, step"), &d.steps);
    }
    if !c.discarded.is_empty() {
        let _ = writeln!(s, "\nattempt {} (counted):", c.discarded.len() + 1);
    }
    steps(s, "step", &c.steps);
}

/// Renders the steps of a case that ran into its transcript text and drops their exchanges:
/// kept as strings, the exchanges were most of a run's memory (a default run's 33,000
/// case-runs held 65 MB of them), and every report reads the text alone. The runner seals
/// each case as it ends, on the thread that ran it.
pub(crate) fn seal(c: &mut CaseResult) {
    if c.transcript.is_some() || (c.steps.is_empty() && c.discarded.is_empty()) {
        return;
    }
    let mut text = String::new();
    body(&mut text, c);
    text.shrink_to_fit();
    c.transcript = Some(text);
    let discarded = c.discarded.iter_mut().flat_map(|d| d.steps.iter_mut());
    for st in c.steps.iter_mut().chain(discarded) {
        st.exchanges = Vec::new();
    }
}

/// A case read back from a report folder: `text`, its transcript as the file held it, kept
/// past the header (which the case's own fields give, as judged now). A header that does not
/// match the case's fields ends where the first step or attempt begins.
pub(crate) fn read_back(c: &mut CaseResult, text: &str) {
    let body = text.strip_prefix(&header(c)).unwrap_or_else(|| {
        ["\n\nstep ", "\n\nattempt "]
            .iter()
            .filter_map(|m| text.find(m))
            .min()
            .map_or("", |at| &text[at + 1..])
    });
    c.transcript = Some(body.to_string());
}

/// Steps, each under `label` and its number.
fn steps(s: &mut String, label: &str, steps: &[StepResult]) {
    for (i, st) in steps.iter().enumerate() {
        let _ = writeln!(
            s,
            "\n{label} {}: {}\n  verdict: {}",
            i + 1,
            st.step,
            st.verdict.name()
        );
        if !st.observed.is_null() {
            let _ = writeln!(s, "  observed: {}", st.observed);
        }
        if !st.message.is_empty() {
            let _ = writeln!(s, "  message: {}", st.message);
        }
        for x in &st.exchanges {
            exchange(s, x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;

    #[test]
    fn failing_case_shows_header_step_and_exchange() {
        let run = sample_run();
        insta::assert_snapshot!(render(&run.cases[1]), @r#"
        case: bu0620/addressing/coe-p102
        title: title of bu0620/addressing/coe-p102
        manual: BU 0620 (2020-03 en) §2.2.7 p. 20
        profile: sk550p
        verdict: fail
        message: status: expected 2865 (0B31h), got 2871 (0B37h)

        step 1: read P102 set 3 FI 5
          verdict: fail
          observed: {"ak":1,"pwe":250}
          message: status: expected 2865 (0B31h), got 2871 (0B37h)
          -> 65 02 24 4E 01 00 00 00 00 FA
             AK 2, PNU 1102 = P102, IND 0100h, PWE 250
          <- 65 02 14 4E 01 00 00 00 00 FA
             AK 1, PNU 1102 = P102, IND 0100h, PWE 250
        "#);
    }

    #[test]
    fn silence_and_passing_steps_are_explicit() {
        let run = sample_run();
        let silent = render(&run.cases[3]);
        assert!(
            silent.ends_with("  -> 65 02 24 4E 01 00 00 00 00 FA\n     AK 2, PNU 1102 = P102, IND 0100h, PWE 250\n  <- (nothing received)\n"),
            "{silent}"
        );
        let pass = render(&run.cases[0]);
        assert!(!pass.contains("message:"), "{pass}");
        let na = render(&run.cases[2]);
        assert!(!na.contains("step 1"), "{na}");
        assert!(
            na.contains("verdict: not_applicable\nmessage: the statement is about sk550p"),
            "{na}"
        );
    }

    #[test]
    fn a_case_read_back_renders_its_stored_text() {
        let mut c = sample_run().cases.remove(1);
        let stored = format!("{}\nstep 1: as the file held it\n", header(&c));
        read_back(&mut c, &stored);
        assert_eq!(render(&c), stored, "whatever steps it kept");
        c.verdict = Verdict::Pass;
        c.message.clear();
        let now = "case: bu0620/addressing/coe-p102\ntitle: title of bu0620/addressing/coe-p102\nmanual: BU 0620 (2020-03 en) §2.2.7 p. 20\nprofile: sk550p\nverdict: pass\n\nstep 1: as the file held it\n";
        assert_eq!(render(&c), now, "the header as judged now");
        read_back(&mut c, &stored);
        assert_eq!(render(&c), now, "a header that differs is replaced");
    }

    #[test]
    fn a_sealed_case_renders_as_before_without_its_exchanges() {
        for mut c in sample_run().cases {
            let before = render(&c);
            seal(&mut c);
            assert_eq!(render(&c), before, "{}", c.id);
            assert!(c.steps.iter().all(|st| st.exchanges.is_empty()), "{}", c.id);
        }
    }

    #[test]
    fn deterministic_without_times() {
        let run = sample_run();
        let mut slower = run.cases[1].clone();
        slower.duration *= 1000;
        assert_eq!(render(&run.cases[1]), render(&slower));
    }
}
