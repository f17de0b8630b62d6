//! A case's transcript: steps, observations and every link exchange in hex and decoded.
//! Deterministic (no times), so transcripts can be stored as snapshots and diffed.

use std::fmt::Write;

use crate::outcome::CaseResult;

/// The transcript text.
pub(crate) fn render(c: &CaseResult) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "case: {}\ntitle: {}", c.id, c.title);
    let _ = writeln!(
        s,
        "manual: {} ({}) §{} p. {}",
        c.manual.doc, c.manual.edition, c.manual.section, c.manual.page
    );
    let _ = writeln!(s, "profile: {}\nverdict: {}", c.profile, c.verdict.name());
    if !c.message.is_empty() {
        let _ = writeln!(s, "message: {}", c.message);
    }
    for (i, st) in c.steps.iter().enumerate() {
        let _ = writeln!(
            s,
            "\nstep {}: {}\n  verdict: {}",
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
            let _ = writeln!(
                s,
                "  -> {}\n     {}\n  <- {}\n     {}",
                x.sent_hex, x.sent, x.received_hex, x.received
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_run;

    #[test]
    fn transcript_shows_exchanges_in_hex_and_decoded() {
        let run = sample_run();
        let t = render(&run.cases[1]);
        assert!(t.contains("-> 65 01 24 4E"), "{t}");
        assert!(t.contains("<- 65 01 14 4E"), "{t}");
        assert!(t.contains("verdict: fail"), "{t}");
        assert_eq!(t, render(&run.cases[1]), "deterministic");
    }
}
