//! Comparing runs: two transcripts line by line ([`compare_transcripts`], which `harness diff`
//! and the snapshots both use), and two whole runs case by case ([`compare_runs`]) — how one
//! firmware release is compared with the previous one.
//!
//! A transcript difference is a list of hunks: the changed lines, paired old against new, with
//! [`CONTEXT`] unchanged lines either side, each hunk named by the step it falls in. A run
//! difference lists every case (profile and id) whose verdict or transcript changed, the cases
//! only the new run has and those it lost.
//!
//! A **regression** is a case that passed in the old run and, in the new one, still runs and
//! fails, errs or is inconclusive. A **new failure** is a fail or an error of the new run that
//! the old run did not have: a case only the new run has that fails or errs, or one whose
//! verdict became fail or error from anything else (not applicable → fail included). A passing
//! case that became not applicable or vanished is listed as coverage lost but is neither: that
//! comes from a changed selection, suite or profile, not from the device answering differently.
//!
//! [`Gate`] says which of them make `harness diff` exit 1: both by default (a release gate that
//! a new case failing on the new firmware must stop), regressions only on request.

use std::collections::BTreeMap;

use super::redact::redact;
use super::transcript;
use crate::bus::Bus;
use crate::outcome::{CaseResult, RunMeta, RunResult, Verdict};

/// Unchanged lines shown either side of a change.
pub(crate) const CONTEXT: usize = 2;

/// Larger middles (after the common head and tail) are shown as one replaced block instead of
/// being aligned line by line, which costs their product in memory.
const ALIGN_LIMIT: usize = 4_000_000;

/// One line of a transcript, with its 1-based number.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Numbered {
    /// Line number in its transcript.
    pub(crate) at: usize,
    /// The line.
    pub(crate) text: String,
}

/// One row of a side-by-side difference.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Row {
    /// A line both sides have, shown for context, with its number on each side.
    Same {
        /// The line in the old transcript.
        old: Numbered,
        /// The same line in the new one.
        new: Numbered,
    },
    /// A line only one side has, or a line changed: old and new, each absent when that side has
    /// fewer lines in this block.
    Changed {
        /// The old line.
        old: Option<Numbered>,
        /// The new line.
        new: Option<Numbered>,
    },
}

/// A run of changed lines with their context.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Hunk {
    /// Where it is: the step line it falls in (`step 1: read P102`), or `header`.
    pub(crate) place: String,
    /// The rows, in order.
    pub(crate) rows: Vec<Row>,
}

/// How two transcripts differ: at least one hunk.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TranscriptDiff {
    /// The hunks, in order.
    pub(crate) hunks: Vec<Hunk>,
}

impl TranscriptDiff {
    /// The first changed row: where it is, its line number and both lines (`(none)` for a
    /// missing one).
    pub(crate) fn first(&self) -> (String, usize, String, String) {
        for h in &self.hunks {
            for r in &h.rows {
                if let Row::Changed { old, new } = r {
                    let at = old.as_ref().or(new.as_ref()).map_or(0, |l| l.at);
                    let show = |l: &Option<Numbered>| {
                        l.as_ref().map_or("(none)".to_string(), |l| l.text.clone())
                    };
                    return (h.place.clone(), at, show(old), show(new));
                }
            }
        }
        (String::new(), 0, String::new(), String::new())
    }
}

/// One step of an alignment: a line both have, or one only the old or the new has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    Same(usize, usize),
    Old(usize),
    New(usize),
}

/// Aligns `a` with `b` by longest common subsequence, after taking off the common head and
/// tail (transcripts of two firmware releases differ in a few places).
fn align(a: &[&str], b: &[&str]) -> Vec<Op> {
    let head = a.iter().zip(b).take_while(|(x, y)| x == y).count();
    let tail = a[head..]
        .iter()
        .rev()
        .zip(b[head..].iter().rev())
        .take_while(|(x, y)| x == y)
        .count();
    let (ma, mb) = (&a[head..a.len() - tail], &b[head..b.len() - tail]);
    let mut ops: Vec<Op> = (0..head).map(|i| Op::Same(i, i)).collect();
    if ma.len().saturating_mul(mb.len()) > ALIGN_LIMIT {
        ops.extend((0..ma.len()).map(|i| Op::Old(head + i)));
        ops.extend((0..mb.len()).map(|j| Op::New(head + j)));
    } else {
        // lcs[i][j]: longest common subsequence of ma[i..] and mb[j..].
        let w = mb.len() + 1;
        let mut lcs = vec![0u32; (ma.len() + 1) * w];
        for i in (0..ma.len()).rev() {
            for j in (0..mb.len()).rev() {
                lcs[i * w + j] = if ma[i] == mb[j] {
                    lcs[(i + 1) * w + j + 1] + 1
                } else {
                    lcs[(i + 1) * w + j].max(lcs[i * w + j + 1])
                };
            }
        }
        let (mut i, mut j) = (0, 0);
        while i < ma.len() || j < mb.len() {
            if i < ma.len() && j < mb.len() && ma[i] == mb[j] {
                ops.push(Op::Same(head + i, head + j));
                (i, j) = (i + 1, j + 1);
            } else if j == mb.len() || (i < ma.len() && lcs[(i + 1) * w + j] >= lcs[i * w + j + 1])
            {
                ops.push(Op::Old(head + i));
                i += 1;
            } else {
                ops.push(Op::New(head + j));
                j += 1;
            }
        }
    }
    let (sa, sb) = (a.len() - tail, b.len() - tail);
    ops.extend((0..tail).map(|k| Op::Same(sa + k, sb + k)));
    ops
}

/// The step line a transcript line falls in: the last `step N: …` line up to `at`, else
/// `header`.
fn place(lines: &[&str], at: usize) -> String {
    lines[..at.min(lines.len())]
        .iter()
        .rev()
        .find(|l| l.starts_with("step "))
        .map_or("header".to_string(), |l| l.to_string())
}

/// Compares two transcripts (each after [`redact`]); `None` when they are equal.
pub(crate) fn compare_transcripts(buses: &[&Bus], old: &str, new: &str) -> Option<TranscriptDiff> {
    let (old, new) = (redact(buses, old), redact(buses, new));
    if old == new {
        return None;
    }
    let (a, b): (Vec<&str>, Vec<&str>) = (old.lines().collect(), new.lines().collect());
    let ops = align(&a, &b);
    let line = |lines: &[&str], i: usize| Numbered {
        at: i + 1,
        text: lines[i].to_string(),
    };
    let changed: Vec<usize> = (0..ops.len())
        .filter(|&k| !matches!(ops[k], Op::Same(..)))
        .collect();
    let mut hunks = Vec::new();
    let mut k = 0;
    while k < changed.len() {
        // A hunk: changes whose contexts touch or overlap, from CONTEXT before the first to
        // CONTEXT after the last.
        let start = k;
        while k + 1 < changed.len() && changed[k + 1] - changed[k] <= 2 * CONTEXT + 1 {
            k += 1;
        }
        let (first, last) = (changed[start], changed[k]);
        let (from, to) = (
            first.saturating_sub(CONTEXT),
            (last + CONTEXT).min(ops.len() - 1),
        );
        // Old lines up to the first change, itself included when it is an old line.
        let upto = ops[..=first]
            .iter()
            .filter(|o| !matches!(o, Op::New(_)))
            .count();
        let mut rows: Vec<Row> = Vec::new();
        let (mut olds, mut news) = (Vec::new(), Vec::new());
        let flush = |rows: &mut Vec<Row>, olds: &mut Vec<Numbered>, news: &mut Vec<Numbered>| {
            let n = olds.len().max(news.len());
            let (mut o, mut w) = (olds.drain(..), news.drain(..));
            for _ in 0..n {
                rows.push(Row::Changed {
                    old: o.next(),
                    new: w.next(),
                });
            }
        };
        for op in &ops[from..=to] {
            match *op {
                Op::Same(i, j) => {
                    flush(&mut rows, &mut olds, &mut news);
                    rows.push(Row::Same {
                        old: line(&a, i),
                        new: line(&b, j),
                    });
                }
                Op::Old(i) => olds.push(line(&a, i)),
                Op::New(j) => news.push(line(&b, j)),
            }
        }
        flush(&mut rows, &mut olds, &mut news);
        hunks.push(Hunk {
            place: place(&a, upto),
            rows,
        });
        k += 1;
    }
    Some(TranscriptDiff { hunks })
}

/// Fail or error: what gates a release.
fn failing(v: Verdict) -> bool {
    matches!(v, Verdict::Fail | Verdict::Error)
}

/// Which differences make a comparison fail (`harness diff` exit 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Gate {
    /// Regressions and new failures (the module documentation says what each is).
    NewFailures,
    /// Regressions only (`--regressions-only`): passed → fail, error or inconclusive.
    RegressionsOnly,
}

/// A case as one side of a comparison has it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CaseSide {
    /// Verdict.
    pub(crate) verdict: Verdict,
    /// Why (empty on pass).
    pub(crate) message: String,
}

/// A case both runs have, whose verdict or transcript changed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CaseChange {
    /// Profile.
    pub(crate) profile: String,
    /// Case id.
    pub(crate) id: String,
    /// Title (the new run's).
    pub(crate) title: String,
    /// In the old run.
    pub(crate) old: CaseSide,
    /// In the new run.
    pub(crate) new: CaseSide,
    /// How the transcript changed, when it did.
    pub(crate) transcript: Option<TranscriptDiff>,
}

impl CaseChange {
    /// Passed before, runs and does not pass now.
    pub(crate) fn regressed(&self) -> bool {
        self.old.verdict == Verdict::Pass
            && matches!(
                self.new.verdict,
                Verdict::Fail | Verdict::Error | Verdict::Inconclusive
            )
    }

    /// Fails or errs now and did not end so before.
    pub(crate) fn new_failure(&self) -> bool {
        failing(self.new.verdict) && self.old.verdict != self.new.verdict
    }

    /// Passed before and does not apply now.
    pub(crate) fn lost_coverage(&self) -> bool {
        self.old.verdict == Verdict::Pass && self.new.verdict == Verdict::NotApplicable
    }
}

/// A case only one run has.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LoneCase {
    /// Profile.
    pub(crate) profile: String,
    /// Case id.
    pub(crate) id: String,
    /// Title.
    pub(crate) title: String,
    /// Its verdict and message in the run that has it.
    pub(crate) side: CaseSide,
}

/// One of the two runs: where it was read from and what it says about itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct RunSide {
    /// The folder or file as given.
    pub(crate) source: String,
    /// What was tested.
    pub(crate) dut: String,
    /// Harness, suites, start, command line, device identities.
    pub(crate) meta: RunMeta,
    /// Cases per verdict, in [`Verdict::ALL`] order.
    pub(crate) counts: [usize; 5],
}

impl RunSide {
    fn of(source: &str, run: &RunResult) -> Self {
        RunSide {
            source: source.to_string(),
            dut: run.dut.clone(),
            meta: run.meta.clone(),
            counts: Verdict::ALL.map(|v| run.count(v)),
        }
    }
}

/// How two runs differ.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct RunDiff {
    /// The old run.
    pub(crate) old: RunSide,
    /// The new run.
    pub(crate) new: RunSide,
    /// Cases whose verdict or transcript changed, in the new run's order.
    pub(crate) changed: Vec<CaseChange>,
    /// Cases only the new run has.
    pub(crate) added: Vec<LoneCase>,
    /// Cases only the old run has.
    pub(crate) vanished: Vec<LoneCase>,
    /// Cases equal in both.
    pub(crate) unchanged: usize,
}

impl RunDiff {
    /// The regressions (see the module documentation).
    pub(crate) fn regressions(&self) -> impl Iterator<Item = &CaseChange> {
        self.changed.iter().filter(|c| c.regressed())
    }

    /// The new failures (see the module documentation): `profile id: old → new`, `new` for a
    /// case only the new run has, in the new run's order of changes, then of new cases.
    pub(crate) fn new_failures(&self) -> Vec<String> {
        let changed = self
            .changed
            .iter()
            .filter(|c| c.new_failure())
            .map(|c| (c, c.old.verdict.name()));
        let added = self
            .added
            .iter()
            .filter(|c| failing(c.side.verdict))
            .map(|c| (&c.profile, &c.id, "new", c.side.verdict));
        changed
            .map(|(c, old)| (&c.profile, &c.id, old, c.new.verdict))
            .chain(added)
            .map(|(profile, id, old, new)| format!("{profile} {id}: {old} → {}", new.name()))
            .collect()
    }

    /// The cases that make the comparison fail under `gate`, one line each, regressions first.
    pub(crate) fn gated(&self, gate: Gate) -> Vec<String> {
        let mut out: Vec<String> = self
            .regressions()
            .map(|c| {
                format!(
                    "{} {}: {} → {}",
                    c.profile,
                    c.id,
                    c.old.verdict.name(),
                    c.new.verdict.name()
                )
            })
            .collect();
        if gate == Gate::NewFailures {
            // pass → fail is both: listed once.
            let seen: std::collections::BTreeSet<String> = out.iter().cloned().collect();
            out.extend(
                self.new_failures()
                    .into_iter()
                    .filter(|f| !seen.contains(f)),
            );
        }
        out
    }

    /// One line: `verdict changes: 2 (regressions: 1), new fails or errors: 1, transcript
    /// changes: 3, new: 1, vanished: 1, unchanged: 40`, and the coverage lost when there is
    /// some.
    pub(crate) fn headline(&self) -> String {
        let verdicts = self
            .changed
            .iter()
            .filter(|c| c.old.verdict != c.new.verdict)
            .count();
        let transcripts = self
            .changed
            .iter()
            .filter(|c| c.transcript.is_some())
            .count();
        let regressions = self.regressions().count();
        let failures = self.new_failures().len();
        let lost = self.changed.iter().filter(|c| c.lost_coverage()).count()
            + self
                .vanished
                .iter()
                .filter(|c| c.side.verdict == Verdict::Pass)
                .count();
        let mut s = format!(
            "verdict changes: {verdicts} (regressions: {regressions}), new fails or errors: {failures}, transcript changes: {transcripts}, new: {}, vanished: {}, unchanged: {}",
            self.added.len(),
            self.vanished.len(),
            self.unchanged
        );
        if lost > 0 {
            s.push_str(&format!(
                ", coverage lost: {lost} (passing cases that no longer run)"
            ));
        }
        s
    }
}

fn side(c: &CaseResult) -> CaseSide {
    CaseSide {
        verdict: c.verdict,
        message: c.message.clone(),
    }
}

fn lone(c: &CaseResult) -> LoneCase {
    LoneCase {
        profile: c.profile.clone(),
        id: c.id.clone(),
        title: c.title.clone(),
        side: side(c),
    }
}

/// Compares two runs case by case (profile and id); `old_source`/`new_source` name them, and
/// `buses` know what in their transcripts varies.
pub(crate) fn compare_runs(
    buses: &[&Bus],
    old_source: &str,
    old: &RunResult,
    new_source: &str,
    new: &RunResult,
) -> RunDiff {
    let key = |c: &CaseResult| (c.profile.clone(), c.id.clone());
    let olds: BTreeMap<_, &CaseResult> = old.cases.iter().map(|c| (key(c), c)).collect();
    let news: BTreeMap<_, &CaseResult> = new.cases.iter().map(|c| (key(c), c)).collect();
    let mut diff = RunDiff {
        old: RunSide::of(old_source, old),
        new: RunSide::of(new_source, new),
        changed: Vec::new(),
        added: Vec::new(),
        vanished: Vec::new(),
        unchanged: 0,
    };
    for n in &new.cases {
        let Some(o) = olds.get(&key(n)) else {
            diff.added.push(lone(n));
            continue;
        };
        let transcript = compare_transcripts(buses, &transcript::render(o), &transcript::render(n));
        if o.verdict == n.verdict && transcript.is_none() {
            diff.unchanged += 1;
            continue;
        }
        diff.changed.push(CaseChange {
            profile: n.profile.clone(),
            id: n.id.clone(),
            title: n.title.clone(),
            old: side(o),
            new: side(n),
            transcript,
        });
    }
    diff.vanished = old
        .cases
        .iter()
        .filter(|o| !news.contains_key(&key(o)))
        .map(lone)
        .collect();
    diff
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;

    fn same(old: usize, new: usize, text: &str) -> Row {
        let n = |at| Numbered {
            at,
            text: text.into(),
        };
        Row::Same {
            old: n(old),
            new: n(new),
        }
    }

    fn changed(old: Option<(usize, &str)>, new: Option<(usize, &str)>) -> Row {
        let n = |l: Option<(usize, &str)>| l.map(|(at, t)| Numbered { at, text: t.into() });
        Row::Changed {
            old: n(old),
            new: n(new),
        }
    }

    #[test]
    fn equal_transcripts_have_no_difference() {
        assert_eq!(
            compare_transcripts(crate::buses::BUSES, "a\nb\n", "a\nb\n"),
            None
        );
        assert_eq!(compare_transcripts(crate::buses::BUSES, "", ""), None);
    }

    #[test]
    fn a_changed_line_is_paired_with_two_lines_of_context_and_named_by_its_step() {
        let old = "case: x\n\nstep 1: read P102\n  verdict: pass\n  -> 01\n     AK 1\n  <- 02\n     PWE 250\n\nstep 2: y\n";
        let new = old
            .replace("PWE 250", "PWE 251")
            .replace("  <- 02", "  <- 03");
        let d = compare_transcripts(crate::buses::BUSES, old, &new).unwrap();
        assert_eq!(
            d.hunks,
            vec![Hunk {
                place: "step 1: read P102".into(),
                rows: vec![
                    same(5, 5, "  -> 01"),
                    same(6, 6, "     AK 1"),
                    changed(Some((7, "  <- 02")), Some((7, "  <- 03"))),
                    changed(Some((8, "     PWE 250")), Some((8, "     PWE 251"))),
                    same(9, 9, ""),
                    same(10, 10, "step 2: y"),
                ],
            }]
        );
        assert_eq!(
            d.first(),
            (
                "step 1: read P102".into(),
                7,
                "  <- 02".into(),
                "  <- 03".into()
            )
        );
    }

    #[test]
    fn far_apart_changes_are_separate_hunks_and_unequal_blocks_pair_with_none() {
        let old: String = (1..=20).map(|i| format!("l{i}\n")).collect();
        let new = old
            .replace("l2\n", "l2\nextra\n")
            .replace("l15\n", "L15\n")
            .replace("l20\n", "");
        let d = compare_transcripts(crate::buses::BUSES, &old, &new).unwrap();
        assert_eq!(d.hunks.len(), 2, "{d:#?}");
        assert_eq!(d.hunks[0].place, "header");
        assert_eq!(
            d.hunks[0].rows,
            vec![
                same(1, 1, "l1"),
                same(2, 2, "l2"),
                changed(None, Some((3, "extra"))),
                same(3, 4, "l3"),
                same(4, 5, "l4"),
            ]
        );
        // l15 changed and l20 gone, four unchanged lines apart: one hunk, from l13 to the end.
        let rows = &d.hunks[1].rows;
        assert_eq!(rows[2], changed(Some((15, "l15")), Some((16, "L15"))));
        assert_eq!(rows.last(), Some(&changed(Some((20, "l20")), None)));
        assert_eq!(
            d.first().1,
            3,
            "a pure insertion is numbered by its new line"
        );
        assert_eq!(d.first().2, "(none)");
    }

    #[test]
    fn a_huge_middle_is_one_replaced_block() {
        let old: String = (0..3000).map(|i| format!("a{i}\n")).collect();
        let new: String = (0..3000).map(|i| format!("b{i}\n")).collect();
        let d = compare_transcripts(crate::buses::BUSES, &old, &new).unwrap();
        assert_eq!(d.hunks.len(), 1);
        assert_eq!(d.hunks[0].rows.len(), 3000);
        assert_eq!(
            d.hunks[0].rows[0],
            changed(Some((1, "a0")), Some((1, "b0")))
        );
    }

    #[test]
    fn runs_compare_by_profile_and_id() {
        let old = sample_run();
        let mut new = sample_run();
        // Firmware change: the passing P102 write is answered with PWE 251 and fails.
        let c = &mut new.cases[0];
        c.steps[0].exchanges[0].received_hex = "65 02 14 4E 01 00 00 00 00 FB".into();
        c.verdict = Verdict::Fail;
        c.message = "pwe: expected 250, got 251".into();
        // The error case passes now; the inconclusive one is gone; a case is new.
        new.cases[3].verdict = Verdict::Pass;
        new.cases.remove(4);
        let mut added = sample_run().cases.remove(0);
        added.id = "bu0620/new/case".into();
        new.cases.push(added);

        let d = compare_runs(crate::buses::BUSES, "old", &old, "new", &new);
        let names: Vec<(&str, Verdict, Verdict, bool)> = d
            .changed
            .iter()
            .map(|c| (c.id.as_str(), c.old.verdict, c.new.verdict, c.regressed()))
            .collect();
        assert_eq!(
            names,
            vec![
                (
                    "bu0620/pkw-telegrams/p102-write",
                    Verdict::Pass,
                    Verdict::Fail,
                    true
                ),
                (
                    "bu0620/pkw-telegrams/silent",
                    Verdict::Error,
                    Verdict::Pass,
                    false
                ),
            ]
        );
        let t = d.changed[0].transcript.as_ref().unwrap();
        assert_eq!(t.hunks[0].place, "header", "the verdict line changed");
        assert!(t.hunks.iter().any(|h| h.rows.contains(&changed(
            Some((12, "  <- 65 02 14 4E 01 00 00 00 00 FA")),
            Some((13, "  <- 65 02 14 4E 01 00 00 00 00 FB"))
        ))));
        assert_eq!(d.changed[0].new.message, "pwe: expected 250, got 251");
        assert_eq!(d.added.len(), 1);
        assert_eq!(d.added[0].id, "bu0620/new/case");
        assert_eq!(d.vanished.len(), 1);
        assert_eq!(d.vanished[0].side.verdict, Verdict::Inconclusive);
        assert_eq!(d.unchanged, old.cases.len() - 3);
        assert_eq!(d.regressions().count(), 1);
        assert_eq!(d.old.counts, Verdict::ALL.map(|v| old.count(v)));
        assert_eq!(d.new.counts, Verdict::ALL.map(|v| new.count(v)));
        assert_eq!(
            d.headline(),
            format!(
                "verdict changes: 2 (regressions: 1), new fails or errors: 1, transcript changes: 2, new: 1, vanished: 1, unchanged: {}",
                old.cases.len() - 3
            )
        );
        let gated = ["sk550p bu0620/pkw-telegrams/p102-write: pass → fail"];
        assert_eq!(d.gated(Gate::NewFailures), gated);
        assert_eq!(d.gated(Gate::RegressionsOnly), gated);
    }

    #[test]
    fn a_new_fail_or_error_gates_by_default_and_only_a_regression_gates_the_narrow_rule() {
        let old = sample_run();
        let verdicts: Vec<(&str, &str, Verdict)> = old
            .cases
            .iter()
            .map(|c| (c.profile.as_str(), c.id.as_str(), c.verdict))
            .collect();
        // The fixture: sk550p pass, fail, model pass; tu3-eip not applicable, error,
        // inconclusive.
        assert_eq!(
            verdicts.iter().map(|v| v.2).collect::<Vec<_>>(),
            [
                Verdict::Pass,
                Verdict::Fail,
                Verdict::NotApplicable,
                Verdict::Error,
                Verdict::Inconclusive,
                Verdict::Pass
            ],
            "{verdicts:?}"
        );
        let mut new = sample_run();
        // Not applicable → fail, inconclusive → error, the fail stays a fail, and a case
        // only the new run has errs.
        new.cases[2].verdict = Verdict::Fail;
        new.cases[4].verdict = Verdict::Error;
        let mut added = sample_run().cases.remove(3);
        added.id = "bu0620/new/case".into();
        new.cases.push(added);
        let d = compare_runs(crate::buses::BUSES, "old", &old, "new", &new);
        assert_eq!(d.regressions().count(), 0);
        let want = [
            "tu3-eip bu0620/addressing/coe-p102: not_applicable → fail",
            "tu3-eip bu2100/cip/identity: inconclusive → error",
            "tu3-eip bu0620/new/case: new → error",
        ];
        assert_eq!(d.new_failures(), want);
        assert_eq!(d.gated(Gate::NewFailures), want);
        assert!(d.gated(Gate::RegressionsOnly).is_empty());
        assert!(
            d.headline()
                .contains("(regressions: 0), new fails or errors: 3,"),
            "{}",
            d.headline()
        );
        // A pass → inconclusive is a regression under both rules, and no new fail.
        let mut new = sample_run();
        new.cases[0].verdict = Verdict::Inconclusive;
        let d = compare_runs(crate::buses::BUSES, "old", &old, "new", &new);
        assert!(d.new_failures().is_empty());
        let regression = ["sk550p bu0620/pkw-telegrams/p102-write: pass → inconclusive"];
        assert_eq!(d.gated(Gate::NewFailures), regression);
        assert_eq!(d.gated(Gate::RegressionsOnly), regression);
        // The same run twice gates nothing.
        assert!(compare_runs(crate::buses::BUSES, "old", &old, "new", &old)
            .gated(Gate::NewFailures)
            .is_empty());
    }

    #[test]
    fn pass_to_not_applicable_and_a_vanished_pass_are_lost_coverage_not_regressions() {
        let old = sample_run();
        let mut new = sample_run();
        new.cases[0].verdict = Verdict::NotApplicable;
        new.cases[0].steps.clear();
        let d = compare_runs(crate::buses::BUSES, "old", &old, "new", &new);
        assert_eq!(d.regressions().count(), 0);
        assert!(d.changed[0].lost_coverage());
        assert!(d
            .headline()
            .ends_with(", coverage lost: 1 (passing cases that no longer run)"));
        new.cases.remove(0);
        let d = compare_runs(crate::buses::BUSES, "old", &old, "new", &new);
        assert_eq!((d.regressions().count(), d.vanished.len()), (0, 1));
        assert!(
            d.headline().contains("coverage lost: 1"),
            "{}",
            d.headline()
        );
    }
}
