//! What a run produces: verdicts, per-case results with transcripts, errata. The runner fills
//! these; the reports (JUnit, `run.json`, transcripts, summary) only read them.

use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::time::Duration;

/// Id of the case that stands for a failed connection check in the reports.
pub(crate) const CONNECTION_CHECK: &str = "harness/connection-check";

/// The verdict of one case (or one step).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ManualRef {
    /// Manual, e.g. `BU 0620`.
    pub doc: String,
    /// Edition, e.g. `2020-03 en`.
    pub edition: String,
    /// Section, e.g. `2.2.7`.
    pub section: String,
    /// Page as printed; a specification cited by section and table alone has none.
    pub page: Option<u32>,
    /// The requirement in the manual's own words, where the suite quotes it (`ref.quote`);
    /// reports fall back to the case title, the requirement as the suite states it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quote: Option<String>,
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
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
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
    /// Ambiguous rather than wrong: the case accepts every reading the text allows.
    #[serde(default)]
    pub ambiguous: bool,
    /// Which check of the errata pass found it.
    pub check: ErratumCheck,
    /// The clause of the standard the correct value comes from (`CiA 301 4.2.0 §7.2.4.3.17`);
    /// always there for [`ErratumCheck::Standard`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub standard: Option<String>,
}

impl Erratum {
    /// `why`, marked when the manual is ambiguous rather than wrong.
    pub fn reason(&self) -> String {
        if self.ambiguous {
            format!("ambiguous: {}", self.why)
        } else {
            self.why.clone()
        }
    }

    /// How it was found, with the standard's clause where there is one: `standard: CiA 301
    /// 4.2.0 §7.2.4.3.17`.
    pub fn found_by(&self) -> String {
        let check = self.check.label();
        match &self.standard {
            Some(clause) => format!("{check}: {clause}"),
            None => check.to_string(),
        }
    }
}

/// The four checks of the errata pass: each table and example is held against the manual's
/// own text, the standard it implements, the other manuals, and its own default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ErratumCheck {
    /// An example or value against the manual's own formula, table or rule.
    OwnText,
    /// A value against the standard the manual implements (CiA 301, ETG.1000, EPSG DS 301,
    /// CIP, PROFINET, IEEE); the erratum names the clause.
    Standard,
    /// One manual or edition against another that describes the same thing.
    OtherManual,
    /// A range against the default it should contain.
    RangeDefault,
}

impl ErratumCheck {
    /// The word the suites use for it.
    pub fn label(self) -> &'static str {
        match self {
            ErratumCheck::OwnText => "own-text",
            ErratumCheck::Standard => "standard",
            ErratumCheck::OtherManual => "other-manual",
            ErratumCheck::RangeDefault => "range-default",
        }
    }
}

/// A device's refusal of a request, in its bus's own terms: a parameter-channel error number
/// (response label 7), a CIP general status, an SDO abort code, an AL status code. It is data
/// about the device — the request reached it and it said no — kept apart from a broken link or
/// a broken protocol.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Refusal {
    /// The kind of code, as the bus names it (`SDO abort code`).
    pub kind: Cow<'static, str>,
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
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
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
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
    /// Link exchanges of this step (empty for `compute`, and once the case's transcript is
    /// rendered: see [`CaseResult::transcript`]).
    pub exchanges: Vec<Exchange>,
}

/// What a case checks: the device, or only the harness's reference model of the manuals.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum CaseKind {
    /// At least one step reaches the DUT: a verdict about the device.
    #[default]
    Device,
    /// Every step is a reference-model check of the manuals' formulas and tables (`compute`):
    /// it never touches the DUT, so its pass is no pass of the device; reports count it apart.
    Model,
}

impl CaseKind {
    /// Name as written in reports.
    pub fn name(self) -> &'static str {
        match self {
            CaseKind::Device => "device",
            CaseKind::Model => "model",
        }
    }
}

/// The outcome of one case under one profile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// Full id: `bu0620/<file>/<case>`.
    pub id: String,
    /// One-line title.
    pub title: String,
    /// Profile it ran under (`sk550p`, …).
    pub profile: String,
    /// Where the manual says it.
    pub manual: ManualRef,
    /// Whether the case checks the device or only the reference model.
    #[serde(default)]
    pub kind: CaseKind,
    /// Case verdict (the worst step verdict; not applicable without steps run).
    pub verdict: Verdict,
    /// Why, for anything but pass (the failing step's message, or the not-applicable reason).
    pub message: String,
    /// Step outcomes, in order.
    pub steps: Vec<StepResult>,
    /// Wall time spent.
    #[serde(serialize_with = "ser_secs", deserialize_with = "de_secs")]
    pub duration: Duration,
    /// Position of this case-run in the unsharded run's order (profile-major, cases as
    /// loaded), so `harness merge` can restore that order from shards.
    #[serde(default)]
    pub seq: usize,
    /// Attempts that did not count: the host was late while a step waited on the device
    /// (`crate::timing`), and the case ran again. Shown in the transcript before the steps of
    /// the attempt that counted.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub discarded: Vec<Discarded>,
    /// The transcript text past its header (the steps and their exchanges), once rendered:
    /// the runner renders it as the case ends and drops the exchanges, and a case read back
    /// from a report folder has it from its transcript file (`run.json` keeps the deciding
    /// step at most). The reports render it in place of the steps (see `report::transcript`).
    #[serde(skip)]
    pub transcript: Option<String>,
}

/// An attempt at a case that did not count, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Discarded {
    /// Why it did not count: how late the host was, in which step, against which limit.
    pub why: String,
    /// Its steps, as they ran.
    pub steps: Vec<StepResult>,
}

impl CaseResult {
    /// The step that decided the verdict: the first with the case's verdict (the first step of
    /// a pass; none without steps). The reports show it as what was observed; `run.json` keeps
    /// it, so that a run read back from its reports shows the same.
    pub fn deciding_step(&self) -> Option<&StepResult> {
        self.steps.iter().find(|st| st.verdict == self.verdict)
    }
}

/// A device's identity as the device itself reports it over its bus (EtherNet/IP
/// ListIdentity, EtherCAT SII and object 1018h, POWERLINK IdentResponse, PROFINET DCP and I&M0,
/// the NORD information parameters over the parameter channel). Fields the bus does not give
/// stay empty.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Identity {
    /// Where the fields come from, e.g. `ListIdentity`.
    pub source: String,
    /// The vendor, by id and name where the bus gives both (`0x0001E6 NORD`).
    pub vendor: Option<String>,
    /// The product code or device id.
    pub product_code: Option<String>,
    /// The product name.
    pub product_name: Option<String>,
    /// The firmware (software) revision.
    pub revision: Option<String>,
    /// The serial number.
    pub serial: Option<String>,
}

impl Identity {
    /// One line: `NORD SK TU3-PNT, code 0x0003, firmware 1.2, serial 1234 (from I&M0)`; the
    /// source alone when the DUT gave no field (`none: …`).
    pub fn line(&self) -> String {
        let mut parts: Vec<String> = Vec::new();
        let name: Vec<&str> = [&self.vendor, &self.product_name]
            .into_iter()
            .flatten()
            .map(String::as_str)
            .collect();
        if !name.is_empty() {
            parts.push(name.join(" "));
        }
        for (label, v) in [
            ("code", &self.product_code),
            ("firmware", &self.revision),
            ("serial", &self.serial),
        ] {
            if let Some(v) = v {
                parts.push(format!("{label} {v}"));
            }
        }
        if parts.is_empty() {
            return self.source.clone();
        }
        format!("{} (from {})", parts.join(", "), self.source)
    }
}

/// What a run's reports must say about the run itself, so that a report is a record of what
/// was tested: by which harness and suites, when, how it was called.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunMeta {
    /// The harness's version (Cargo package version).
    pub harness_version: String,
    /// The git revision the harness was built from (`-dirty` when the tree had changes).
    pub harness_revision: String,
    /// The suites' revision: their git commit (`-dirty` when changed), else a content digest.
    pub suites_revision: String,
    /// Start time, RFC 3339 UTC.
    pub started: String,
    /// The machine the harness ran on (its host name).
    #[serde(default)]
    pub host: String,
    /// The command line, as given.
    pub command_line: Vec<String>,
    /// The DUT's identity per profile, as the device reported it (none for a profile whose
    /// identity could not be read; the run's connection check says why).
    pub identities: BTreeMap<String, Identity>,
    /// Whether steps that can make a motor turn were allowed (`--allow-motion`).
    pub motion_allowed: bool,
    /// The share of the case-runs this run made (`--shard K/N`); none for a whole run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<crate::shard::Shard>,
    /// The seed of the shuffled case order (`--shuffle SEED`); none for the suites' order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shuffle: Option<u64>,
    /// The attempts discarded because the host was late (see `crate::timing`), over all cases.
    #[serde(default)]
    pub discarded_attempts: usize,
    /// The EEPROM writes the run's cases made on a DUT on the network, each counted with the
    /// cleanup's restore of it (`--max-eeprom-writes` caps them).
    #[serde(default)]
    pub eeprom_writes: u32,
    /// Their cap (`--max-eeprom-writes`) on a DUT on the network; none for the embedded
    /// simulator, which has no motor to turn and no EEPROM to wear (no limit applies).
    #[serde(default)]
    pub eeprom_cap: Option<u32>,
    /// Set when a signal (Ctrl-C, SIGTERM) stopped the run before its end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interrupted: Option<Interrupted>,
}

/// How an interrupted run ended: the case cut short (its step under way finished, its cleanup
/// ran) and the case-runs that never started.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Interrupted {
    /// The case-runs stopped between two steps (`<profile> <id>`), their verdict inconclusive.
    pub cut: Vec<String>,
    /// The case-runs that never started (`<profile> <id>`), in the planned order.
    pub not_run: Vec<String>,
}

/// The statements of one manual section in the inventories (`suites/inventory/`), counted:
/// how much of what the manual says the suites assert.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StatementCoverage {
    /// Manual.
    pub doc: String,
    /// Edition.
    pub edition: String,
    /// Section.
    pub section: String,
    /// Statements listed.
    pub statements: usize,
    /// Asserted on the device: a device case (one that reaches the DUT) checks it.
    pub asserted: usize,
    /// Asserted by reference-model cases only (`compute` steps, which never reach the DUT).
    #[serde(default)]
    pub model_only: usize,
    /// Waiting for a bus binding.
    pub pending: usize,
    /// Not testable here.
    pub untestable: usize,
}

impl StatementCoverage {
    /// Testable statements (neither pending nor untestable) no case asserts yet.
    pub fn open(&self) -> usize {
        self.statements
            .saturating_sub(self.asserted + self.model_only + self.pending + self.untestable)
    }

    /// Testable statements: asserted on the device, by the model only, or open.
    pub fn testable(&self) -> usize {
        self.asserted + self.model_only + self.open()
    }

    /// Asserted on the device of the testable ones, in per cent; none when none is testable.
    pub fn device_percent(&self) -> Option<f64> {
        self.share(self.asserted)
    }

    /// Asserted by any case (on the device or by the model) of the testable ones, in per
    /// cent; none when none is testable.
    pub fn percent(&self) -> Option<f64> {
        self.share(self.asserted + self.model_only)
    }

    fn share(&self, n: usize) -> Option<f64> {
        match self.testable() {
            0 => None,
            t => Some(100.0 * n as f64 / t as f64),
        }
    }

    /// Adds another section's counts (a manual's total).
    pub fn add(&mut self, other: &StatementCoverage) {
        self.statements += other.statements;
        self.asserted += other.asserted;
        self.model_only += other.model_only;
        self.pending += other.pending;
        self.untestable += other.untestable;
    }
}

/// One manual's table of contents as its inventory lists it: how many sections, how many hold
/// statements, how many state nothing testable (each with the reason in the inventory).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SectionCount {
    /// Manual.
    pub doc: String,
    /// Edition.
    pub edition: String,
    /// Sections in the table of contents.
    pub contents: usize,
    /// Sections with at least one statement in them or below them.
    pub with_statements: usize,
    /// Sections with nothing testable (`nothing:`).
    pub nothing: usize,
}

/// A whole run: every case under every profile it ran with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// What was tested: `embedded simulator`, or the DUT's address.
    pub dut: String,
    /// Who ran what, when, with which harness and suites, against which device identity.
    #[serde(default)]
    pub meta: RunMeta,
    /// Profiles run, in order.
    pub profiles: Vec<String>,
    /// All case results.
    pub cases: Vec<CaseResult>,
    /// Every erratum the loaded suites record (once each, not per profile).
    pub errata: Vec<Erratum>,
    /// The manuals' statements per section as the inventories count them (none without
    /// inventories).
    #[serde(default)]
    pub statements: Vec<StatementCoverage>,
    /// The manuals' tables of contents as the inventories count them (none without
    /// inventories).
    #[serde(default)]
    pub sections: Vec<SectionCount>,
    /// Suite files that failed to load, with the error (file, line, what is wrong).
    pub load_errors: Vec<String>,
    /// The mutation score `harness mutants` last measured into the report folder, if any.
    #[serde(default)]
    pub mutation: Option<MutationScore>,
    /// Wall time of the run.
    #[serde(serialize_with = "ser_secs", deserialize_with = "de_secs")]
    pub duration: Duration,
}

/// How many of the manuals-as-code mutants the cases kill (`harness mutants`, its
/// `mutants.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MutationScore {
    /// Mutants run.
    pub mutants: usize,
    /// Mutants some case noticed.
    pub killed: usize,
    /// When they were run (RFC 3339).
    pub measured: String,
    /// Only some mutants ran (`--only`, `--every`).
    pub sample: bool,
}

impl MutationScore {
    /// Killed, in per cent of those run.
    pub fn percent(&self) -> f64 {
        match self.mutants {
            0 => 0.0,
            n => 100.0 * self.killed as f64 / n as f64,
        }
    }
}

impl std::fmt::Display for MutationScore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "mutation score: {} of {} mutants of the manuals as code killed ({:.1} %), measured {}{}",
            self.killed,
            self.mutants,
            self.percent(),
            self.measured,
            if self.sample { ", a sample" } else { "" }
        )
    }
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

fn de_secs<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Duration, D::Error> {
    let secs = f64::deserialize(d)?;
    Duration::try_from_secs_f64(secs).map_err(serde::de::Error::custom)
}
