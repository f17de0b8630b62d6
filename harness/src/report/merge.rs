//! `harness merge`: the report folders of a run's shards (`--shard K/N`) joined into the run
//! the unsharded command would have made, which [`super::write_all`] then writes like any run.
//!
//! The shards must be one run cut in N: the same harness, suites, DUT, profiles and selection,
//! every shard 1..N once, and every case-run position (`seq`) exactly once. The merged run takes
//! the cases in `seq` order; its start is the earliest shard's, its duration the longest
//! shard's (the shards run side by side), its command line the first shard's without `--shard`,
//! its host the shards' hosts (one name when they ran on one machine), its EEPROM writes the
//! shards' sum. Each shard keeps `--max-eeprom-writes` on its own: against a device, N shards
//! may write up to N times the cap, and where the cap decided a case, the merge can differ from
//! an unsharded run.

use crate::outcome::CONNECTION_CHECK;
use crate::outcome::{CaseResult, RunResult};
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
    /// A shard or a case-run is given twice.
    #[error("given twice: {0}")]
    Twice(String),
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

/// The second run is a shard of the same run as the first: same DUT (and identity), harness,
/// suites, profiles and motion setting.
fn same_run(first: &str, a: &RunResult, other: &str, b: &RunResult) -> Result<(), MergeError> {
    let mismatch = |what, x: String, y: String| MergeError::Mismatch {
        what,
        first: first.to_string(),
        other: other.to_string(),
        a: x,
        b: y,
    };
    let (m, r) = (&a.meta, &b.meta);
    for (what, x, y) in [
        ("DUT", &a.dut, &b.dut),
        ("harness version", &m.harness_version, &r.harness_version),
        ("harness revision", &m.harness_revision, &r.harness_revision),
        ("suites revision", &m.suites_revision, &r.suites_revision),
    ] {
        if x != y {
            return Err(mismatch(what, x.clone(), y.clone()));
        }
    }
    if a.profiles != b.profiles {
        return Err(mismatch(
            "profiles",
            a.profiles.join(","),
            b.profiles.join(","),
        ));
    }
    if m.identities != r.identities {
        let show = |i: &std::collections::BTreeMap<String, crate::outcome::Identity>| {
            i.iter()
                .map(|(p, id)| format!("{p}: {}", id.line()))
                .collect::<Vec<_>>()
                .join("; ")
        };
        return Err(mismatch(
            "DUT identity",
            show(&m.identities),
            show(&r.identities),
        ));
    }
    if m.eeprom_cap != r.eeprom_cap {
        let show = |c: Option<u32>| c.map_or("none".to_string(), |c| c.to_string());
        return Err(mismatch(
            "--max-eeprom-writes",
            show(m.eeprom_cap),
            show(r.eeprom_cap),
        ));
    }
    if m.motion_allowed != r.motion_allowed {
        return Err(mismatch(
            "--allow-motion",
            m.motion_allowed.to_string(),
            r.motion_allowed.to_string(),
        ));
    }
    if a.errata != b.errata || a.load_errors != b.load_errors {
        return Err(mismatch(
            "suites loaded (errata, load errors)",
            format!(
                "{} errata, {} load errors",
                a.errata.len(),
                a.load_errors.len()
            ),
            format!(
                "{} errata, {} load errors",
                b.errata.len(),
                b.load_errors.len()
            ),
        ));
    }
    Ok(())
}

/// Joins shards (each with the folder it was read from, for errors) into one run.
pub(crate) fn merge(shards: Vec<(String, RunResult)>) -> Result<RunResult, MergeError> {
    let mut shards = shards.into_iter();
    let (first, mut merged) = shards.next().ok_or(MergeError::Empty)?;
    let mut parts = vec![(first.clone(), merged.meta.shard)];
    let mut cases: Vec<(String, CaseResult)> = std::mem::take(&mut merged.cases)
        .into_iter()
        .map(|c| (first.clone(), c))
        .collect();
    for (src, run) in shards {
        same_run(&first, &merged, &src, &run)?;
        parts.push((src.clone(), run.meta.shard));
        if run.meta.started < merged.meta.started {
            merged.meta.started.clone_from(&run.meta.started);
        }
        merged.duration = merged.duration.max(run.duration);
        merged.meta.eeprom_writes += run.meta.eeprom_writes;
        merged.meta.discarded_attempts += run.meta.discarded_attempts;
        if !merged.meta.host.split(", ").any(|h| h == run.meta.host) {
            merged.meta.host = format!("{}, {}", merged.meta.host, run.meta.host);
        }
        cases.extend(run.cases.into_iter().map(|c| (src.clone(), c)));
    }
    check_parts(&parts)?;
    cases.sort_by_key(|(_, c)| c.seq);
    // A DUT that cannot be reached stops every shard at the same connection check, the one
    // case-run the whole run has.
    cases.dedup_by(|(_, later), (_, kept)| {
        later.id == CONNECTION_CHECK
            && (later.seq, &later.id, &later.profile, &later.message)
                == (kept.seq, &kept.id, &kept.profile, &kept.message)
    });
    let total = parts.iter().find_map(|(_, s)| s.map(|s| s.of));
    check_seqs(&cases, total)?;
    merged.cases = cases.into_iter().map(|(_, c)| c).collect();
    merged.meta.shard = None;
    merged.meta.command_line = unsharded(&merged.meta.command_line);
    Ok(merged)
}

/// Every shard recorded (reports from before sharding record none), of one N and one total,
/// 1..=N each once.
fn check_parts(parts: &[(String, Option<Shard>)]) -> Result<(), MergeError> {
    let known: Vec<(&String, Shard)> = parts
        .iter()
        .filter_map(|(src, s)| s.map(|s| (src, s)))
        .collect();
    let Some(&(first_src, first)) = known.first() else {
        return Ok(());
    };
    if known.len() != parts.len() {
        return Err(MergeError::Missing(
            "some folders are shards (--shard) and some are not".into(),
        ));
    }
    for &(src, s) in &known {
        if s.count != first.count || s.of != first.of {
            return Err(MergeError::Missing(format!(
                "{src} is shard {s} of {} case-runs, {first_src} shard {first} of {}: not one run",
                s.of, first.of
            )));
        }
    }
    for (n, &(src, s)) in known.iter().enumerate() {
        if let Some((other, _)) = known[..n].iter().find(|(_, t)| t.index == s.index) {
            return Err(MergeError::Twice(format!("shard {s}: {other} and {src}")));
        }
    }
    let absent: Vec<String> = (1..=first.count)
        .filter(|k| !known.iter().any(|(_, s)| s.index == *k))
        .map(|k| format!("{k}/{}", first.count))
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
/// past the highest position); `cases` sorted by position.
fn check_seqs(cases: &[(String, CaseResult)], total: Option<usize>) -> Result<(), MergeError> {
    for w in cases.windows(2) {
        let ((a_src, a), (b_src, b)) = (&w[0], &w[1]);
        if a.seq == b.seq {
            return Err(MergeError::Twice(format!(
                "case-run {} ({} {}): {a_src} and {b_src}",
                a.seq, a.profile, a.id
            )));
        }
    }
    let total = total.unwrap_or_else(|| cases.last().map_or(0, |(_, c)| c.seq + 1));
    let mut present = cases.iter().map(|(_, c)| c.seq).peekable();
    let mut absent = Vec::new();
    for i in 0..total {
        if present.next_if_eq(&i).is_none() {
            absent.push(i);
        }
    }
    if !absent.is_empty() || present.next().is_some() {
        let mut shown: Vec<String> = absent.iter().take(5).map(usize::to_string).collect();
        if absent.len() > 5 {
            shown.push("…".into());
        }
        return Err(MergeError::Missing(format!(
            "{} of {total} case-runs present (missing positions: {})",
            cases.len(),
            shown.join(", ")
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::outcome::{RunMeta, Verdict};
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
                run.meta
                    .command_line
                    .extend(["--shard".to_string(), shard.to_string()]);
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
        let merged = merge(parts.clone()).unwrap();
        parts[1].1.meta.host = "ci-2".into();
        assert_eq!(
            merge(parts).unwrap().meta.host,
            format!("{}, ci-2", sample_run().meta.host),
            "shards on several machines"
        );
        let whole = sample_run();
        assert_eq!(merged.cases, whole.cases, "cases in unsharded order");
        assert_eq!(
            merged.meta.command_line, whole.meta.command_line,
            "no --shard"
        );
        assert_eq!(merged.meta.started, "2026-11-27T06:00:01Z", "earliest");
        assert_eq!(merged.meta.shard, None);
        assert_eq!(merged.duration, Duration::from_millis(30), "longest shard");
        assert_eq!(
            merged.meta.eeprom_writes,
            3 * whole.meta.eeprom_writes,
            "each shard's writes"
        );
        assert_eq!(
            merged,
            RunResult {
                duration: merged.duration,
                meta: RunMeta {
                    started: merged.meta.started.clone(),
                    eeprom_writes: merged.meta.eeprom_writes,
                    ..whole.meta.clone()
                },
                ..whole
            }
        );
    }

    #[test]
    fn the_shard_option_leaves_the_command_line_in_either_spelling() {
        let line = |args: &[&str]| args.iter().map(|a| a.to_string()).collect::<Vec<_>>();
        assert_eq!(
            unsharded(&line(&["harness", "run", "--shard", "2/3", "-q"])),
            line(&["harness", "run", "-q"])
        );
        assert_eq!(
            unsharded(&line(&["harness", "--shard=1/2", "run"])),
            line(&["harness", "run"])
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
        assert_eq!(
            merge(parts).unwrap_err().to_string(),
            "given twice: shard 1/3: shard1 and shard1"
        );
        let mut parts = shards(3);
        parts[2].1.meta.shard = parts[2].1.meta.shard.map(|s| Shard { of: 99, ..s });
        let err = merge(parts).unwrap_err().to_string();
        assert!(err.contains("shard3 is shard 3/3 of 99 case-runs"), "{err}");
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
            "given twice: case-run 0 (sk550p bu0620/pkw-telegrams/p102-write): shard1 and shard2"
        );
        let n = sample_run().cases.len();
        parts[1].1.cases.remove(0);
        assert_eq!(
            merge(parts).unwrap_err().to_string(),
            format!(
                "incomplete: {} of {n} case-runs present (missing positions: 1)",
                n - 1
            )
        );
    }

    #[test]
    fn every_shard_stopped_at_the_connection_check_is_one_case_run() {
        let mut parts = shards(2);
        for (k, (_, r)) in parts.iter_mut().enumerate() {
            let mut check = sample_run().cases.remove(0);
            check.id = CONNECTION_CHECK.into();
            check.verdict = Verdict::Error;
            check.message = "no reply within 2 s; the run stopped before its cases".into();
            check.duration = Duration::from_millis(k as u64);
            r.cases = vec![check];
            r.meta.shard = r.meta.shard.map(|s| Shard { of: 1, ..s });
        }
        let merged = merge(parts).unwrap();
        assert_eq!(merged.cases.len(), 1);
        assert_eq!(merged.cases[0].id, CONNECTION_CHECK);
    }

    #[test]
    fn shards_of_different_runs_are_refused() {
        type Change = fn(&mut RunResult);
        let changes: [(&str, Change); 6] = [
            ("DUT", |r| r.dut = "enip://10.0.0.2".into()),
            ("suites revision", |r| {
                r.meta.suites_revision = "feed".into()
            }),
            ("harness revision", |r| {
                r.meta.harness_revision = "beef".into()
            }),
            ("profiles", |r| r.profiles.truncate(1)),
            ("DUT identity", |r| r.meta.identities.clear()),
            ("--max-eeprom-writes", |r| r.meta.eeprom_cap = Some(1)),
        ];
        for (what, change) in changes {
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
