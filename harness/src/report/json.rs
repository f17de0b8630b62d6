//! `run.json`: the run for scripts — every case's id, profile, verdict and manual reference,
//! counts, errata and load errors (no transcripts: those are files of their own).

use serde_json::{json, Value};

use crate::outcome::{RunResult, Verdict};

/// The document.
pub(super) fn render(run: &RunResult) -> String {
    let cases: Vec<Value> = run
        .cases
        .iter()
        .map(|c| {
            json!({
                "id": c.id,
                "title": c.title,
                "profile": c.profile,
                "verdict": c.verdict,
                "manual": c.manual,
                "message": c.message,
            })
        })
        .collect();
    let counts: serde_json::Map<String, Value> = Verdict::ALL
        .iter()
        .map(|v| (v.name().to_string(), json!(run.count(*v))))
        .collect();
    let doc = json!({
        "dut": run.dut,
        "profiles": run.profiles,
        "duration": run.duration.as_secs_f64(),
        "counts": counts,
        "load_errors": run.load_errors,
        "errata": run.errata,
        "cases": cases,
    });
    serde_json::to_string_pretty(&doc).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_run;

    #[test]
    fn cases_counts_and_errata() {
        let v: Value = serde_json::from_str(&render(&sample_run())).unwrap();
        assert_eq!(v["cases"][0]["id"], "bu0620/addr/coe-p102");
        assert_eq!(v["cases"][0]["manual"]["section"], "2.2.7");
        assert_eq!(v["counts"]["fail"], 1);
        assert_eq!(v["errata"][0]["printed"], "class 103");
    }
}
