//! `run.json`: the run for scripts. Every case's id, profile, verdict, manual reference and
//! message, counts per verdict (overall and per profile), the manuals' errata and the load
//! errors. Transcripts stay out (they are files of their own; each case names its file).

use serde::Serialize;
use std::collections::BTreeMap;

use super::summary::{profiles, Counts};
use super::write::transcript_file;
use crate::outcome::{CaseResult, Erratum, ManualRef, RunResult, Verdict};

/// One case in `run.json`.
#[derive(Debug, Serialize)]
struct Case<'a> {
    id: &'a str,
    title: &'a str,
    profile: &'a str,
    verdict: Verdict,
    manual: &'a ManualRef,
    message: &'a str,
    /// Seconds.
    duration: f64,
    /// The transcript, relative to the output folder (none for a case that did not apply).
    transcript: Option<String>,
}

impl<'a> From<&'a CaseResult> for Case<'a> {
    fn from(c: &'a CaseResult) -> Self {
        Case {
            id: &c.id,
            title: &c.title,
            profile: &c.profile,
            verdict: c.verdict,
            manual: &c.manual,
            message: &c.message,
            duration: c.duration.as_secs_f64(),
            transcript: transcript_file(c).map(|f| f.to_string_lossy().replace('\\', "/")),
        }
    }
}

/// The whole document.
#[derive(Debug, Serialize)]
struct Doc<'a> {
    dut: &'a str,
    profiles: &'a [String],
    /// Seconds.
    duration: f64,
    counts: Counts,
    counts_by_profile: BTreeMap<&'a str, Counts>,
    load_errors: &'a [String],
    errata: &'a [Erratum],
    cases: Vec<Case<'a>>,
}

/// `run.json`, pretty-printed.
pub(super) fn render(run: &RunResult) -> Result<String, serde_json::Error> {
    let doc = Doc {
        dut: &run.dut,
        profiles: &run.profiles,
        duration: run.duration.as_secs_f64(),
        counts: Counts::of(&run.cases),
        counts_by_profile: profiles(run)
            .into_iter()
            .map(|p| (p, Counts::of(run.cases.iter().filter(|c| c.profile == p))))
            .collect(),
        load_errors: &run.load_errors,
        errata: &run.errata,
        cases: run.cases.iter().map(Case::from).collect(),
    };
    serde_json::to_string_pretty(&doc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;
    use serde_json::{json, Value};

    fn doc() -> Value {
        serde_json::from_str(&render(&sample_run()).unwrap()).unwrap()
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
                "verdict": "fail",
                "manual": {"doc": "BU 0620", "edition": "2020-03 en", "section": "2.2.7", "page": 20},
                "message": "status: expected 2865 (0B31h), got 2871 (0B37h)",
                "duration": 0.003,
                "transcript": "transcripts/sk550p/bu0620__addressing__coe-p102.txt",
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
        assert_eq!(v["counts_by_profile"]["sk550p"]["pass"], 1);
        assert_eq!(v["counts_by_profile"]["tu3-eip"]["error"], 1);
        assert_eq!(v["errata"][0]["printed"], "class 103");
        assert_eq!(v["errata"][0]["correct"], "class 102");
        assert_eq!(v["errata"][0]["why"], "FI 2 is class 102");
        assert_eq!(v["errata"][0]["section"], "2.3.5");
        assert_eq!(v["dut"], "embedded simulator");
        assert_eq!(v["profiles"], json!(["sk550p", "tu3-eip"]));
        assert_eq!(v["load_errors"], json!([]));
        assert_eq!(v["duration"], 0.015);
    }
}
