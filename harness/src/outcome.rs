//! What a run produces: verdicts, per-case results with transcripts, errata. The runner fills
//! these; the reports (JUnit, `run.json`, transcripts, summary) only read them.

use serde::Serialize;
use std::time::Duration;

/// The verdict of one case (or one step).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The DUT did what the manual says.
    Pass,
    /// The DUT answered, and the answer contradicts the manual (or broke the protocol).
    Fail,
    /// The statement could not be judged: a setup step failed.
    Inconclusive,
    /// The link or the harness failed (timeout with no answer, a suite bug).
    Error,
    /// The case does not apply to this profile or DUT; the reason says why.
    NotApplicable,
}

impl Verdict {
    /// Every verdict, in report order.
    pub const ALL: [Verdict; 5] = [
        Verdict::Pass,
        Verdict::Fail,
        Verdict::Inconclusive,
        Verdict::Error,
        Verdict::NotApplicable,
    ];

    /// Name as written in reports (`pass`, `not_applicable`, …).
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::Inconclusive => "inconclusive",
            Verdict::Error => "error",
            Verdict::NotApplicable => "not_applicable",
        }
    }
}

/// Where a case's statement stands in the manuals.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ManualRef {
    /// Manual, e.g. `BU 0620`.
    pub doc: String,
    /// Edition, e.g. `2020-03 en`.
    pub edition: String,
    /// Section, e.g. `2.2.7`.
    pub section: String,
    /// Page as printed; a specification cited by section and table alone has none.
    pub page: Option<u32>,
}

impl ManualRef {
    /// `§2.2.7 p. 20`, or `§2-3.3` without a page.
    pub fn place(&self) -> String {
        match self.page {
            Some(p) => format!("§{} p. {p}", self.section),
            None => format!("§{}", self.section),
        }
    }
}

/// A wrong value a manual prints, recorded by a case.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Erratum {
    /// Manual.
    pub doc: String,
    /// Edition.
    pub edition: String,
    /// Section.
    pub section: String,
    /// Page.
    pub page: Option<u32>,
    /// Id of the case that records it.
    pub case: String,
    /// What the manual prints.
    pub printed: String,
    /// What the case tests instead.
    pub correct: String,
    /// Why.
    pub why: String,
}

/// A device's refusal of a request, in its bus's own terms: a parameter-channel error number
/// (response label 7), a CIP general status, an SDO abort code, an AL status code. It is data
/// about the device — the request reached it and it said no — kept apart from a broken link or
/// a broken protocol.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Refusal {
    /// The kind of code, as the bus names it (`SDO abort code`).
    pub kind: &'static str,
    /// The code.
    pub code: u32,
    /// The code as the manual or the standard names it.
    pub text: String,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.kind, self.text)
    }
}

/// One request/response pair on the link, for transcripts.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Exchange {
    /// Link frame sent, as hex bytes (`"01 01 70 66 …"`).
    pub sent_hex: String,
    /// The request decoded in the manuals' terms.
    pub sent: String,
    /// Link frame received, as hex bytes; empty when nothing came.
    pub received_hex: String,
    /// The response decoded in the manuals' terms.
    pub received: String,
}

/// The outcome of one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepResult {
    /// The step as written, one line (`read P102 set 3 FI 5`).
    pub step: String,
    /// Step verdict.
    pub verdict: Verdict,
    /// What was observed (the compute result or the decoded DUT answer), as JSON.
    pub observed: serde_json::Value,
    /// The device refused the step's request, in its bus's terms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refusal: Option<Refusal>,
    /// Why it failed or errored; empty on pass.
    pub message: String,
    /// Link exchanges of this step (empty for `compute`).
    pub exchanges: Vec<Exchange>,
}

/// The outcome of one case under one profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    /// Full id: `bu0620/<file>/<case>`.
    pub id: String,
    /// One-line title.
    pub title: String,
    /// Profile it ran under (`sk550p`, …).
    pub profile: String,
    /// Where the manual says it.
    pub manual: ManualRef,
    /// Case verdict (the worst step verdict; not applicable without steps run).
    pub verdict: Verdict,
    /// Why, for anything but pass (the failing step's message, or the not-applicable reason).
    pub message: String,
    /// Step outcomes, in order.
    pub steps: Vec<StepResult>,
    /// Wall time spent.
    #[serde(serialize_with = "ser_secs")]
    pub duration: Duration,
}

/// A whole run: every case under every profile it ran with.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunResult {
    /// What was tested: `embedded simulator`, or the DUT's address.
    pub dut: String,
    /// Profiles run, in order.
    pub profiles: Vec<String>,
    /// All case results.
    pub cases: Vec<CaseResult>,
    /// Every erratum the loaded suites record (once each, not per profile).
    pub errata: Vec<Erratum>,
    /// Suite files that failed to load, with the error (file, line, what is wrong).
    pub load_errors: Vec<String>,
    /// Wall time of the run.
    #[serde(serialize_with = "ser_secs")]
    pub duration: Duration,
}

impl RunResult {
    /// How many cases ended with `v`.
    pub fn count(&self, v: Verdict) -> usize {
        self.cases.iter().filter(|c| c.verdict == v).count()
    }
}

fn ser_secs<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(d.as_secs_f64())
}
