//! `harness merge`: the report folders of a run's shards (`--shard K/N`) joined into the run
//! the unsharded command would have made, which [`super::write_all`] then writes like any run.
//!
//! The shards must be one run cut in N: the same harness, suites, DUT, profiles and selection,
//! every shard 1..N once, and every case-run position (`seq`) exactly once. The merged run takes
//! the cases in `seq` order; its start is the earliest shard's, its duration the longest
//! shard's (the shards run side by side), its command line the first shard's without `--shard`.

use std::collections::BTreeSet;

use crate::outcome::RunResult;
use crate::shard::Shard;

/// Shards that are not one run cut in pieces.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum MergeError {
    /// Nothing to merge.
    #[error("no report folders to merge")]
    Empty,
    /// Two shards disagree about what was run.
    #[error("{what} differs between {first} and {other}: `{a}` vs `{b}`")]
    Mismatch {
        /// What differs (`DUT`, `suites revision`, …).
        what: &'static str,
        /// The first shard's source.
        first: String,
        /// The disagreeing shard's source.
        other: String,
        /// The first shard's value.
        a: String,
        /// The other's.
        b: String,
    },
    /// A case-run position shows up twice.
    #[error("case-run {seq} ({case}) is in {first} and in {other}")]
    Twice {
        /// The position.
        seq: usize,
        /// `<profile> <id>`.
        case: String,
        /// Where it was first seen.
        first: String,
        /// Where it showed up again.
        other: String,
    },
    /// Shards or case-runs are missing.
    #[error("incomplete: {0}")]
    Missing(String),
}

/// Removes `--shard K/N` (or `--shard=K/N`) from a command line.
fn unsharded(command_line: &[String]) -> Vec<String> {
    let mut out = Vec::with_capacity(command_line.len());
    let mut args = command_line.iter();
    while let Some(a) = args.next() {
        if a == "--shard" {
            args.next();
        } else if !a.starts_with("--shard=") {
            out.push(a.clone());
        }
    }
    out
}

/// Joins shards (each with the folder it was read from, for errors) into one run.
pub(crate) fn merge(shards: Vec<(String, RunResult)>) -> Result<RunResult, MergeError> {
    let mut shards = shards.into_iter();
    let (first_src, mut merged) = shards.next().ok_or(MergeError::Empty)?;
    let mut seen: Vec<(usize, String)> = merged
        .cases
        .iter()
        .map(|c| (c.seq, first_src.clone()))
        .collect();
    let mut parts: Vec<Option<Shard>> = vec![merged.meta.shard];
    for (src, run) in shards {
        let mismatch = |what, a: String, b: String| MergeError::Mismatch {
            what,
            first: first_src.clone(),
            other: src.clone(),
            a,
            b,
        };
        let (m, r) = (&merged.meta, &run.meta);
        for (what, a, b) in [
            ("DUT", &merged.dut, &run.dut),
            ("harness version", &m.harness_version, &r.harness_version),
            ("harness revision", &m.harness_revision, &r.harness_revision),
            ("suites revision", &m.suites_revision, &r.suites_revision),
        ] {
            if a != b {
                return Err(mismatch(what, a.clone(), b.clone()));
            }
        }
        let shown = |v: &dyn std::fmt::Debug| format!("{v:?}");
        if merged.profiles != run.profiles {
            return Err(mismatch(
                "profiles",
                merged.profiles.join(","),
                run.profiles.join(","),
            ));
        }
        if m.identities != r.identities {
            return Err(mismatch(
                "DUT identity",
                shown(&m.identities),
                shown(&r.identities),
            ));
        }
        if m.motion_allowed != r.motion_allowed {
            return Err(mismatch(
                "--allow-motion",
                m.motion_allowed.to_string(),
                r.motion_allowed.to_string(),
            ));
        }
        if merged.errata != run.errata || merged.load_errors != run.load_errors {
            return Err(mismatch(
                "suites loaded (errata or load errors)",
                format!("{} errata", merged.errata.len()),
                format!("{} errata", run.errata.len()),
            ));
        }
        parts.push(r.shard);
        seen.extend(run.cases.iter().map(|c| (c.seq, src.clone())));
        if r.started < merged.meta.started {
            merged.meta.started.clone_from(&r.started);
        }
        merged.duration = merged.duration.max(run.duration);
        merged.cases.extend(run.cases);
    }
    check_parts(&parts)?;
    let total = parts.iter().flatten().map(|s| s.of).next();
    check_seqs(&merged, &mut seen, total)?;
    merged.cases.sort_by_key(|c| c.seq);
    merged.meta.shard = None;
    merged.meta.command_line = unsharded(&merged.meta.command_line);
    Ok(merged)
}

/// Every shard recorded (reports from before sharding record none), of one N and one total,
/// 1..=N each once.
fn check_parts(parts: &[Option<Shard>]) -> Result<(), MergeError> {
    let known: Vec<Shard> = parts.iter().flatten().copied().collect();
    if known.is_empty() {
        return Ok(());
    }
    if known.len() != parts.len() {
        return Err(MergeError::Missing(
            "some folders are shards (--shard) and some are not".into(),
        ));
    }
    let n = known[0].count;
    if let Some(s) = known.iter().find(|s| s.count != n || s.of != known[0].of) {
        return Err(MergeError::Missing(format!(
            "shard {s} of {} case-runs does not belong with shard {} of {}",
            s.of, known[0], known[0].of
        )));
    }
    let have: BTreeSet<usize> = known.iter().map(|s| s.index).collect();
    if have.len() != known.len() {
        return Err(MergeError::Missing(format!(
            "a shard is given twice ({})",
            known
                .iter()
                .map(Shard::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let absent: Vec<String> = (1..=n)
        .filter(|k| !have.contains(k))
        .map(|k| format!("{k}/{n}"))
        .collect();
    if !absent.is_empty() {
        return Err(MergeError::Missing(format!(
            "shard {} not given",
            absent.join(", ")
        )));
    }
    Ok(())
}

/// Every case-run position 0..total exactly once (total: as the shards recorded it, else one
/// past the highest position).
fn check_seqs(
    merged: &RunResult,
    seen: &mut [(usize, String)],
    total: Option<usize>,
) -> Result<(), MergeError> {
    let mut order: Vec<usize> = (0..seen.len()).collect();
    order.sort_by_key(|&i| seen[i].0);
    for w in order.windows(2) {
        let (a, b) = (&seen[w[0]], &seen[w[1]]);
        if a.0 == b.0 {
            let c = merged
                .cases
                .iter()
                .find(|c| c.seq == a.0)
                .map(|c| format!("{} {}", c.profile, c.id))
                .unwrap_or_default();
            return Err(MergeError::Twice {
                seq: a.0,
                case: c,
                first: a.1.clone(),
                other: b.1.clone(),
            });
        }
    }
    let total = total.unwrap_or_else(|| seen.iter().map(|s| s.0 + 1).max().unwrap_or(0));
    let present: BTreeSet<usize> = seen.iter().map(|s| s.0).collect();
    let absent: Vec<usize> = (0..total).filter(|i| !present.contains(i)).collect();
    if !absent.is_empty() || present.len() != total {
        let mut shown: Vec<String> = absent.iter().take(5).map(usize::to_string).collect();
        if absent.len() > 5 {
            shown.push("…".into());
        }
        return Err(MergeError::Missing(format!(
            "{} of {total} case-runs present (missing positions: {})",
            present.len(),
            shown.join(", ")
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outcome::RunMeta;
    use crate::report::fixtures::sample_run;
    use std::time::Duration;

    /// The sample run cut into `n` shards as `--shard k/n` would.
    fn shards(n: usize) -> Vec<(String, RunResult)> {
        let whole = sample_run();
        (1..=n)
            .map(|k| {
                let shard = Shard {
                    index: k,
                    count: n,
                    of: whole.cases.len(),
                };
                let mut run = whole.clone();
                run.cases.retain(|c| shard.selects(c.seq));
                run.meta.shard = Some(shard);
                run.meta.command_line = vec![
                    "harness".into(),
                    "run".into(),
                    "--shard".into(),
                    shard.to_string(),
                ];
                run.meta.started = format!("2026-11-27T06:00:0{k}Z");
                run.duration = Duration::from_millis(10 * k as u64);
                (format!("shard{k}"), run)
            })
            .collect()
    }

    #[test]
    fn shards_merge_into_the_unsharded_run() {
        let mut parts = shards(3);
        parts.reverse();
        let merged = merge(parts).unwrap();
        let whole = sample_run();
        assert_eq!(merged.cases, whole.cases, "cases in unsharded order");
        assert_eq!(merged.meta.command_line, ["harness", "run"]);
        assert_eq!(merged.meta.started, "2026-11-27T06:00:01Z", "earliest");
        assert_eq!(merged.meta.shard, None);
        assert_eq!(merged.duration, Duration::from_millis(30), "longest shard");
        assert_eq!(
            merged,
            RunResult {
                duration: merged.duration,
                meta: RunMeta {
                    started: merged.meta.started.clone(),
                    ..whole.meta.clone()
                },
                ..whole
            }
        );
    }

    #[test]
    fn a_missing_or_doubled_shard_is_refused() {
        let mut parts = shards(3);
        parts.remove(1);
        assert_eq!(
            merge(parts).unwrap_err(),
            MergeError::Missing("shard 2/3 not given".into())
        );
        let mut parts = shards(3);
        parts.push(parts[0].clone());
        let err = merge(parts).unwrap_err();
        assert!(err.to_string().contains("a shard is given twice"), "{err}");
    }

    #[test]
    fn a_doubled_or_missing_case_run_is_refused_without_shard_records() {
        let mut parts = shards(2);
        for (_, r) in &mut parts {
            r.meta.shard = None;
        }
        let mut doubled = parts.clone();
        let extra = doubled[0].1.cases[0].clone();
        doubled[1].1.cases.push(extra);
        assert_eq!(
            merge(doubled).unwrap_err().to_string(),
            "case-run 0 (sk550p bu0620/pkw-telegrams/p102-write) is in shard1 and in shard2"
        );
        parts[1].1.cases.remove(0);
        let err = merge(parts).unwrap_err();
        assert_eq!(
            err.to_string(),
            "incomplete: 4 of 5 case-runs present (missing positions: 1)"
        );
    }

    #[test]
    fn shards_of_different_runs_are_refused() {
        for (what, change) in [
            (
                "DUT",
                &(|r: &mut RunResult| r.dut = "enip://10.0.0.2".into()) as &dyn Fn(&mut RunResult),
            ),
            ("suites revision", &|r: &mut RunResult| {
                r.meta.suites_revision = "feed".into()
            }),
            ("harness revision", &|r: &mut RunResult| {
                r.meta.harness_revision = "beef".into()
            }),
            ("profiles", &|r: &mut RunResult| {
                r.profiles.pop().map(drop).unwrap_or(())
            }),
        ] {
            let mut parts = shards(2);
            change(&mut parts[1].1);
            let err = merge(parts).unwrap_err();
            assert!(
                matches!(&err, MergeError::Mismatch { what: w, .. } if *w == what),
                "{what}: {err}"
            );
            assert!(
                err.to_string().contains("between shard1 and shard2"),
                "{err}"
            );
        }
        assert_eq!(merge(Vec::new()).unwrap_err(), MergeError::Empty);
    }
}
