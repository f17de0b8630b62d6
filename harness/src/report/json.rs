//! `run.json`: the run for scripts. The run's record (`meta`: harness and suites revisions,
//! start, command line, DUT identity per profile, motion allowed), every case's id, profile,
//! kind, verdict, manual reference and message, counts per verdict (overall and per profile;
//! `counts*` for device cases, `counts_model*` for reference-model cases, which never touch the
//! DUT), the manuals' errata and the load errors. Transcripts stay out (they are files of their
//! own; each case names its file).

use serde::Serialize;
use std::collections::BTreeMap;

use super::summary::Counts;
use super::write::transcript_file;
use crate::outcome::{
    CaseKind, CaseResult, Erratum, ManualRef, MutationScore, Refusal, RunMeta, RunResult,
    SectionCount, StatementCoverage, Verdict,
};

/// One case in `run.json`.
#[derive(Debug, Serialize)]
struct Case<'a> {
    id: &'a str,
    title: &'a str,
    profile: &'a str,
    kind: CaseKind,
    verdict: Verdict,
    manual: &'a ManualRef,
    message: &'a str,
    /// Seconds.
    duration: f64,
    /// The transcript, relative to the output folder (none for a case that did not apply).
    transcript: Option<String>,
    /// Position in the unsharded run's order (`harness merge` restores it).
    seq: usize,
    /// The step that decided the verdict, without its exchanges (the transcript has them).
    #[serde(skip_serializing_if = "Option::is_none")]
    step: Option<Step<'a>>,
    /// Why each attempt that did not count was discarded (the host was late).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    discarded: Vec<&'a str>,
}

/// A case's deciding step in `run.json`.
#[derive(Debug, Serialize)]
struct Step<'a> {
    step: &'a str,
    verdict: Verdict,
    observed: &'a serde_json::Value,
    #[serde(skip_serializing_if = "Option::is_none")]
    refusal: Option<&'a Refusal>,
    message: &'a str,
}

impl<'a> From<&'a CaseResult> for Case<'a> {
    fn from(c: &'a CaseResult) -> Self {
        Case {
            id: &c.id,
            title: &c.title,
            profile: &c.profile,
            kind: c.kind,
            verdict: c.verdict,
            manual: &c.manual,
            message: &c.message,
            duration: c.duration.as_secs_f64(),
            transcript: transcript_file(c),
            seq: c.seq,
            step: c.deciding_step().map(|st| Step {
                step: &st.step,
                verdict: st.verdict,
                observed: &st.observed,
                refusal: st.refusal.as_ref(),
                message: &st.message,
            }),
            discarded: c.discarded.iter().map(|d| d.why.as_str()).collect(),
        }
    }
}

/// The whole document.
#[derive(Debug, Serialize)]
struct Doc<'a> {
    dut: &'a str,
    meta: &'a RunMeta,
    profiles: &'a [String],
    /// Seconds.
    duration: f64,
    /// Device cases.
    counts: Counts,
    /// Reference-model cases.
    counts_model: Counts,
    counts_by_profile: BTreeMap<&'a str, Counts>,
    counts_model_by_profile: BTreeMap<&'a str, Counts>,
    load_errors: &'a [String],
    errata: &'a [Erratum],
    /// The manuals' statements per section, as the inventories count them.
    statements: &'a [StatementCoverage],
    /// The mutation score `harness mutants` left in the report folder, if it ran there.
    #[serde(skip_serializing_if = "Option::is_none")]
    mutation: Option<&'a MutationScore>,
    /// The manuals' tables of contents: sections, with statements, with nothing testable.
    sections: &'a [SectionCount],
    cases: Vec<Case<'a>>,
}

/// `run.json`, pretty-printed, streamed into `out` (a default run's is tens of megabytes).
pub(super) fn write(run: &RunResult, out: &mut dyn std::io::Write) -> std::io::Result<()> {
    let by_profile = |kind| Counts::per_profile(run, kind).into_iter().collect();
    let doc = Doc {
        dut: &run.dut,
        meta: &run.meta,
        profiles: &run.profiles,
        duration: run.duration.as_secs_f64(),
        counts: Counts::of_kind(run, CaseKind::Device, None),
        counts_model: Counts::of_kind(run, CaseKind::Model, None),
        counts_by_profile: by_profile(CaseKind::Device),
        counts_model_by_profile: by_profile(CaseKind::Model),
        load_errors: &run.load_errors,
        errata: &run.errata,
        statements: &run.statements,
        mutation: run.mutation.as_ref(),
        sections: &run.sections,
        cases: run.cases.iter().map(Case::from).collect(),
    };
    serde_json::to_writer_pretty(out, &doc).map_err(std::io::Error::from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;
    use serde_json::{json, Value};

    fn doc() -> Value {
        let mut out = Vec::new();
        write(&sample_run(), &mut out).unwrap();
        serde_json::from_slice(&out).unwrap()
    }

    #[test]
    fn cases_carry_verdict_manual_reference_and_message() {
        let v = doc();
        assert_eq!(
            v["cases"][1],
            json!({
                "id": "bu0620/addressing/coe-p102",
                "title": "title of bu0620/addressing/coe-p102",
                "profile": "sk550p",
                "kind": "device",
                "verdict": "fail",
                "manual": {"doc": "BU 0620", "edition": "2020-03 en", "section": "2.2.7", "page": 20},
                "message": "status: expected 2865 (0B31h), got 2871 (0B37h)",
                "duration": 0.003,
                "transcript": "transcripts.txt#sk550p/bu0620/addressing/coe-p102",
                "seq": 1,
                "step": {
                    "step": "read P102 set 3 FI 5",
                    "verdict": "fail",
                    "observed": {"ak": 1, "pwe": 250},
                    "message": "status: expected 2865 (0B31h), got 2871 (0B37h)",
                },
            })
        );
        assert_eq!(v["cases"][2]["verdict"], "not_applicable");
        assert!(
            v["cases"][0].get("steps").is_none(),
            "no transcripts in run.json"
        );
    }

    #[test]
    fn counts_errata_and_run_fields() {
        let v = doc();
        assert_eq!(
            v["counts"],
            json!({"pass": 1, "fail": 1, "inconclusive": 1, "error": 1, "not_applicable": 1})
        );
        assert_eq!(
            v["counts_model"],
            json!({"pass": 1, "fail": 0, "inconclusive": 0, "error": 0, "not_applicable": 0})
        );
        assert_eq!(v["counts_by_profile"]["sk550p"]["pass"], 1);
        assert_eq!(v["counts_model_by_profile"]["sk550p"]["pass"], 1);
        assert_eq!(v["counts_model_by_profile"]["tu3-eip"]["pass"], 0);
        assert_eq!(v["cases"][5]["kind"], "model");
        assert_eq!(
            v["meta"]["suites_revision"],
            "0123456789abcdef0123456789abcdef01234567"
        );
        assert_eq!(v["meta"]["started"], "2026-11-27T06:00:00Z");
        assert_eq!(
            v["meta"]["command_line"],
            json!(["harness", "run", "--filter", "a b"])
        );
        assert_eq!(v["meta"]["identities"]["sk550p"]["serial"], "123456");
        assert_eq!(v["meta"]["motion_allowed"], false);
        assert_eq!(v["counts_by_profile"]["tu3-eip"]["error"], 1);
        assert_eq!(v["errata"][0]["printed"], "class 103");
        assert_eq!(v["errata"][0]["correct"], "class 102");
        assert_eq!(v["errata"][0]["why"], "FI 2 is class 102");
        assert_eq!(v["errata"][0]["section"], "2.3.5");
        assert_eq!(v["dut"], "embedded simulator");
        assert_eq!(
            v["mutation"],
            json!({"mutants": 1000, "killed": 962, "measured": "2026-11-27T05:00:00Z", "sample": false})
        );
        assert_eq!(v["profiles"], json!(["sk550p", "tu3-eip"]));
        assert_eq!(v["load_errors"], json!([]));
        assert_eq!(
            v["sections"],
            json!([{"doc": "BU 0620", "edition": "2020-03 en", "contents": 5, "with_statements": 3, "nothing": 2}])
        );
        assert_eq!(v["duration"], 0.015);
    }
}
