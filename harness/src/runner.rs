//! The runner: every loaded case under every profile, step by step, into a [`RunResult`].
//!
//! Verdicts follow one rule set: a mismatch with the expectation is a failure (inconclusive in
//! a setup step); a malformed answer from the DUT is a failure; a silent DUT or a broken link
//! is an error; a suite bug (bad compute arguments) is an error; a case whose profile or
//! capabilities do not fit is not applicable, with the reason.

use serde_json::{json, Value};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crate::binding::{Binding, DutFactory, Observation, OpenError, StepError};
use crate::model::{Args, ComputeError, Ctx};
use std::cell::RefCell;
use std::collections::BTreeMap;

use crate::outcome::{
    CaseKind, CaseResult, Discarded, Identity, ManualRef, RunMeta, RunResult, StepResult, Verdict,
    CONNECTION_CHECK,
};
use crate::profile::{Capability, Profile};
use crate::progress::Progress;
use crate::safety::Guard;
use crate::shard::Shard;
use crate::suite::{Action, Case, Loaded, Step};

/// How to run.
pub(crate) struct RunOptions {
    /// Profiles to run every case under.
    pub(crate) profiles: Vec<Profile>,
    /// Only cases whose id contains this text.
    pub(crate) filter: Option<String>,
    /// Only the cases of these ids (`harness mutants` runs the cases that cite a datum).
    pub(crate) only: Option<std::collections::BTreeSet<String>>,
    /// Bus cycles a parameter order is repeated before the step times out.
    pub(crate) retries: u32,
    /// The run's capture (`--pcap`), if any: the runner labels its packets with the profile,
    /// case and step that produce them.
    pub(crate) tap: Option<crate::pcap::SharedTap>,
    /// Told of every case-run as it starts and ends (the progress bar).
    pub(crate) progress: RefCell<Box<dyn Progress>>,
    /// What a DUT on the network allows (`--allow-motion`, `--max-eeprom-writes`); `None`
    /// for the embedded simulator, which has no motor to turn and no EEPROM to wear.
    pub(crate) limits: Option<crate::safety::Limits>,
    /// Runs each profile's cases in an order shuffled from this seed (`--shuffle SEED`), to
    /// find cases whose verdict depends on what ran before them.
    pub(crate) shuffle: Option<u64>,
    /// Set to stop the run: the case under way ends after its step under way, and its cleanup
    /// runs; no case starts after it ([`crate::interrupt`]).
    pub(crate) stop: &'static AtomicBool,
}

/// A stop never asked for: the default [`RunOptions::stop`].
static NEVER: AtomicBool = AtomicBool::new(false);

impl RunOptions {
    /// Every case under `profiles`: no filter, 250 retries, no capture, no progress shown,
    /// no limits (the embedded simulator's run).
    pub(crate) fn new(profiles: Vec<Profile>) -> RunOptions {
        RunOptions {
            profiles,
            filter: None,
            only: None,
            retries: 250,
            tap: None,
            progress: RefCell::new(Box::new(crate::progress::Silent)),
            limits: None,
            shuffle: None,
            stop: &NEVER,
        }
    }

    /// Whether the run is to stop.
    fn stopping(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    /// Whether the DUT runs on the real clock (a device on the network): then a step that timed
    /// out while the host was late does not count (see [`crate::timing`]).
    fn real_time(&self) -> bool {
        self.limits.is_some()
    }
}

/// Attempts at a case whose deciding step timed out while the host was late, before its
/// verdict is inconclusive.
const ATTEMPTS: usize = 3;

/// What a profile's DUT offers, as its binding says: its description and capabilities. Learnt
/// at the connection check, so that a case needing what the DUT does not offer is not
/// applicable without opening it (a connection opened and closed for nothing, per case).
#[derive(Debug, Clone)]
struct Offer {
    describe: String,
    capabilities: Vec<Capability>,
}

impl Offer {
    fn of(dut: &dyn Binding) -> Offer {
        Offer {
            describe: dut.describe(),
            capabilities: dut.capabilities().to_vec(),
        }
    }
}

/// Runs the loaded suites: the connection check first (it reads the DUT's identity per
/// profile), then every selected case under every profile — or, when the DUT cannot be
/// reached, nothing more: one error says so instead of one per case.
pub(crate) fn run(loaded: &Loaded, opts: &RunOptions, factory: &mut dyn DutFactory) -> RunResult {
    run_shard(loaded, opts, None, factory)
}

/// Runs `shard`'s share of the case-runs (all of them without one), each numbered with its
/// position in the unsharded order (see [`crate::shard`]).
pub(crate) fn run_shard(
    loaded: &Loaded,
    opts: &RunOptions,
    shard: Option<Shard>,
    factory: &mut dyn DutFactory,
) -> RunResult {
    let start = Instant::now();
    let selected = |case: &&Case| {
        opts.filter.as_deref().is_none_or(|f| case.id.contains(f))
            && opts.only.as_ref().is_none_or(|ids| ids.contains(&case.id))
    };
    let mut meta = RunMeta::default();
    let mut cases = Vec::new();
    let seq;
    let mut guard = opts.limits.map(Guard::new);
    // Whether the last cleanup failed: the next case brings the drives back first.
    let mut unsettled = false;
    if opts.real_time() {
        crate::timing::start_watch();
    }
    let mut rng = opts.shuffle.map(fastrand::Rng::with_seed);
    let mut offers = BTreeMap::new();
    match connection_check(loaded, opts, factory, &selected, &mut offers) {
        Ok(identities) => {
            meta.identities = identities;
            let plan = plan(loaded, opts, shard, &selected, &mut rng);
            let total = plan.iter().map(Vec::len).sum();
            seq = opts.profiles.len() * loaded.cases.iter().filter(selected).count();
            let side_by_side = opts.limits.is_none() && opts.tap.is_none();
            match factory.fork().filter(|_| side_by_side) {
                Some(fork) => {
                    cases = run_side_by_side(&plan, opts, fork, &offers, total);
                }
                None => {
                    'profiles: for (profile, runs) in opts.profiles.iter().zip(&plan) {
                        for &(at, case) in runs {
                            if opts.stopping() {
                                break 'profiles;
                            }
                            crate::interrupt::doing(format!("{} {}", profile.name(), case.id));
                            opts.progress.borrow_mut().start(
                                profile.name(),
                                &case.id,
                                cases.len(),
                                total,
                            );
                            let r = CaseResult {
                                seq: at,
                                ..run_case(
                                    case,
                                    profile,
                                    opts,
                                    &mut guard,
                                    &mut unsettled,
                                    factory,
                                    offers.get(profile.name()),
                                )
                            };
                            opts.progress.borrow_mut().end(&r);
                            cases.push(r);
                        }
                    }
                }
            }
            opts.progress.borrow_mut().finish();
            if opts.stopping() {
                meta.interrupted = Some(interrupted(&plan, &opts.profiles, &cases));
            }
        }
        // Every shard stops at the check, with the one case-run the whole run has.
        Err(unreachable) => {
            cases.push(unreachable);
            seq = 1;
        }
    }
    let mut run = RunResult {
        dut: factory.describe(),
        meta: RunMeta {
            motion_allowed: guard.as_ref().is_none_or(Guard::motion_allowed),
            eeprom_writes: guard.as_ref().map_or(0, Guard::eeprom_writes),
            eeprom_cap: opts.limits.map(|l| l.max_eeprom_writes),
            ..meta
        },
        profiles: opts.profiles.iter().map(|p| p.name().to_string()).collect(),
        cases,
        errata: loaded.errata.clone(),
        statements: Vec::new(),
        mutation: None,
        sections: Vec::new(),
        load_errors: loaded.errors.iter().map(|e| e.to_string()).collect(),
        duration: start.elapsed(),
    };
    run.meta.shard = shard.map(|s| Shard { of: seq, ..s });
    run.meta.shuffle = opts.shuffle;
    run.meta.discarded_attempts = run.cases.iter().map(|c| c.discarded.len()).sum();
    run
}

/// Each profile's case-runs in the order they run, each with its position `seq` in the
/// unsharded order (profile by profile, cases as loaded): `shard`'s share, each profile's cases
/// shuffled first when asked. Planned before any runs, so the order is the same however many
/// threads then run it.
fn plan<'a>(
    loaded: &'a Loaded,
    opts: &RunOptions,
    shard: Option<Shard>,
    selected: &dyn Fn(&&Case) -> bool,
    rng: &mut Option<fastrand::Rng>,
) -> Vec<Vec<(usize, &'a Case)>> {
    let mut seq = 0;
    let mut plan = Vec::with_capacity(opts.profiles.len());
    for _ in &opts.profiles {
        let mut order: Vec<&Case> = loaded.cases.iter().filter(selected).collect();
        if let Some(rng) = rng.as_mut() {
            rng.shuffle(&mut order);
        }
        let mut runs = Vec::with_capacity(order.len());
        for case in order {
            if shard.is_none_or(|s| s.selects(seq)) {
                runs.push((seq, case));
            }
            seq += 1;
        }
        plan.push(runs);
    }
    plan
}

/// What a stop left: the cases cut short and the planned case-runs that never started.
fn interrupted(
    plan: &[Vec<(usize, &Case)>],
    profiles: &[Profile],
    cases: &[CaseResult],
) -> crate::outcome::Interrupted {
    let ran: std::collections::BTreeSet<usize> = cases.iter().map(|c| c.seq).collect();
    crate::outcome::Interrupted {
        cut: cases
            .iter()
            .filter(|c| c.message.starts_with(INTERRUPTED))
            .map(|c| format!("{} {}", c.profile, c.id))
            .collect(),
        not_run: profiles
            .iter()
            .zip(plan)
            .flat_map(|(p, runs)| runs.iter().map(move |(at, case)| (p, at, case)))
            .filter(|(_, at, _)| !ran.contains(at))
            .map(|(p, _, case)| format!("{} {}", p.name(), case.id))
            .collect(),
    }
}

/// How the message of a case stopped between two steps begins.
const INTERRUPTED: &str = "interrupted";

/// How often the runner's thread takes the reports of the threads running profiles.
const REPORT_BATCH: Duration = Duration::from_millis(5);

/// What a thread running profiles side by side tells the runner's thread, which shows the
/// progress and keeps the results.
enum Report {
    Start(usize, usize),
    End(usize, usize, Box<CaseResult>),
}

/// Runs the planned profiles on as many threads as the host has cores, each profile whole on
/// one thread with a DUT factory of its own (`fork`): the embedded simulator's profiles share
/// nothing. The results come back in the planned order, as one thread would give them.
fn run_side_by_side(
    plan: &[Vec<(usize, &Case)>],
    opts: &RunOptions,
    fork: Box<dyn DutFactory + Send>,
    offers: &BTreeMap<String, Offer>,
    total: usize,
) -> Vec<CaseResult> {
    let threads = std::thread::available_parallelism()
        .map_or(1, usize::from)
        .min(plan.len())
        .max(1);
    // Bus profiles first: they run the longest, and a long one started last ends the run late.
    let mut queue: Vec<usize> = (0..plan.len()).collect();
    queue.sort_by_key(|&p| opts.profiles[p].bus.is_none());
    let queue = std::sync::Mutex::new(queue.into_iter());
    let (filter, retries, stop) = (opts.filter.clone(), opts.retries, opts.stop);
    let profiles = &opts.profiles.clone();
    let mut ended = Vec::with_capacity(total);
    std::thread::scope(|s| {
        let (tx, rx) = std::sync::mpsc::channel();
        let mut forks = vec![fork];
        while forks.len() < threads {
            match forks[0].fork() {
                Some(f) => forks.push(f),
                None => break,
            }
        }
        for mut factory in forks {
            let (tx, queue, filter) = (tx.clone(), &queue, filter.clone());
            s.spawn(move || {
                // This thread's options: no progress of its own, no capture, no limits.
                let opts = RunOptions {
                    filter,
                    retries,
                    stop,
                    ..RunOptions::new(Vec::new())
                };
                let (mut guard, mut unsettled) = (None, false);
                loop {
                    let next = queue.lock().unwrap_or_else(|e| e.into_inner()).next();
                    let Some(p) = next else { break };
                    let profile = &profiles[p];
                    for (i, &(at, case)) in plan[p].iter().enumerate() {
                        if opts.stopping() {
                            break;
                        }
                        let _ = tx.send(Report::Start(p, i));
                        let r = run_case(
                            case,
                            profile,
                            &opts,
                            &mut guard,
                            &mut unsettled,
                            factory.as_mut(),
                            offers.get(profile.name()),
                        );
                        let _ = tx.send(Report::End(p, i, Box::new(CaseResult { seq: at, ..r })));
                    }
                }
            });
        }
        drop(tx);
        let mut done = 0;
        // Reports are taken in batches, a few milliseconds apart, rather than one by one:
        // a thread blocked on the channel is woken for every message, tens of thousands of
        // wake-ups a run that cost the workers a few per cent of their time (perf).
        loop {
            std::thread::sleep(REPORT_BATCH);
            let mut started = None;
            let mut open = true;
            loop {
                match rx.try_recv() {
                    Ok(Report::Start(p, i)) => started = Some((p, i)),
                    Ok(Report::End(p, i, r)) => {
                        opts.progress.borrow_mut().end(&r);
                        ended.push((p, i, r));
                        done += 1;
                    }
                    Err(std::sync::mpsc::TryRecvError::Empty) => break,
                    Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                        open = false;
                        break;
                    }
                }
            }
            // The latest case started is the one to show, and to name on an interruption.
            if let Some((p, i)) = started {
                let (profile, id) = (opts.profiles[p].name(), &plan[p][i].1.id);
                crate::interrupt::doing(format!("{profile} {id}"));
                opts.progress.borrow_mut().start(profile, id, done, total);
            }
            if !open {
                break;
            }
        }
    });
    // In the planned order: by profile, then case.
    ended.sort_unstable_by_key(|&(p, i, _)| (p, i));
    ended.into_iter().map(|(_, _, r)| *r).collect()
}

/// Opens the DUT once for every profile a selected case needs it under and reads its
/// identity. A DUT that cannot be reached or does not answer is the `Err`: one error result
/// naming the profile and the cause, after which the run stops; one that answers only past its
/// limits ([`OpenError::Late`]) is the same, a fail naming both times. Other failures (a profile the
/// DUT does not fit, an identity answer the harness cannot read) leave the identity out and
/// the cases say the rest.
fn connection_check(
    loaded: &Loaded,
    opts: &RunOptions,
    factory: &mut dyn DutFactory,
    selected: &dyn Fn(&&Case) -> bool,
    offers: &mut BTreeMap<String, Offer>,
) -> Result<BTreeMap<String, Identity>, CaseResult> {
    let start = Instant::now();
    let mut identities = BTreeMap::new();
    for profile in &opts.profiles {
        let needed = loaded
            .cases
            .iter()
            .filter(selected)
            .any(|c| needs_dut(c) && not_applicable(c, profile, None).is_none());
        if !needed {
            continue;
        }
        label(opts, || format!("{} connection check", profile.name()));
        let unreachable = |why: String, verdict: Verdict| CaseResult {
            id: CONNECTION_CHECK.into(),
            title: "the DUT can be reached and says who it is".into(),
            profile: profile.name().to_string(),
            manual: ManualRef {
                doc: "harness".into(),
                edition: env!("CARGO_PKG_VERSION").into(),
                section: "connection check".into(),
                page: None,
                quote: None,
            },
            kind: CaseKind::Device,
            verdict,
            message: format!("{why}; the run stopped before its cases"),
            steps: Vec::new(),
            duration: start.elapsed(),
            seq: 0,
            discarded: Vec::new(),
            transcript: None,
        };
        let mut dut = match factory.open(profile, opts.retries) {
            Ok(dut) => dut,
            Err(e @ (OpenError::Unreachable(_) | OpenError::Late(_))) => {
                return Err(unreachable(e.to_string(), e.verdict()))
            }
            Err(_) => continue,
        };
        offers.insert(profile.name().to_string(), Offer::of(dut.as_ref()));
        match crate::identity::identify(dut.as_mut(), profile) {
            Ok(id) => {
                identities.insert(profile.name().to_string(), id);
            }
            Err(
                e @ (StepError::Link(_)
                | StepError::Closed(_)
                | StepError::Silent { .. }
                | StepError::Late { .. }),
            ) => {
                return Err(unreachable(
                    format!("the DUT does not answer: {e}"),
                    Verdict::Error,
                ))
            }
            // An answer that breaks the protocol (a toggle bit not alternated, a size that
            // lies, bytes that do not parse) is the device's, whatever the cases would ask.
            Err(
                e @ (StepError::Protocol(_)
                | StepError::Malformed { .. }
                | StepError::Garbage(_)
                | StepError::Unanswered { .. }),
            ) => return Err(unreachable(format!("asked who it is: {e}"), Verdict::Error)),
            // Refused (an object a device need not have): no identity, and why.
            Err(e) => {
                identities.insert(
                    profile.name().to_string(),
                    Identity {
                        source: format!("none: {e}"),
                        ..Identity::default()
                    },
                );
            }
        }
        dut.take_exchanges();
        let _ = dut.finish();
        dut.take_exchanges();
    }
    Ok(identities)
}

fn result(
    case: &Case,
    profile: &Profile,
    verdict: Verdict,
    message: String,
    steps: Vec<StepResult>,
    start: Instant,
) -> CaseResult {
    CaseResult {
        id: case.id.clone(),
        title: case.title.clone(),
        profile: profile.name().to_string(),
        manual: case.manual.clone(),
        kind: if needs_dut(case) {
            CaseKind::Device
        } else {
            CaseKind::Model
        },
        verdict,
        message,
        steps,
        duration: start.elapsed(),
        seq: 0,
        discarded: Vec::new(),
        transcript: None,
    }
}

/// Why a case does not apply to a profile, if it does not, as far as is known before a DUT is
/// opened (`harness list --profile` shows the selection this gives).
pub(crate) fn not_applicable_before_opening(case: &Case, profile: &Profile) -> Option<String> {
    not_applicable(case, profile, None)
}

/// Why a case does not apply to a profile, if it does not.
fn not_applicable(case: &Case, profile: &Profile, dut: Option<&Offer>) -> Option<String> {
    if profile.product.is_none() {
        if let Some(s) = case
            .steps
            .iter()
            .find(|s| !matches!(s.action, Action::Bus(_)))
        {
            return Some(format!(
                "profile `{}` (any maker's device) runs its bus's own steps only; this case has `{}`",
                profile.name(),
                describe(&s.action)
            ));
        }
    }
    if let Some(products) = &case.products {
        if !profile.product.is_some_and(|p| products.contains(&p)) {
            let names: Vec<&str> = products.iter().map(|p| p.name()).collect();
            return Some(format!(
                "the statement is about {}, this run is {}",
                names.join(", "),
                profile.name()
            ));
        }
    }
    let needed = || {
        case.requires
            .iter()
            .copied()
            .chain(case.steps.iter().flat_map(|s| s.needs()))
    };
    // A bus's own steps need that bus: known from the profile, before any DUT is opened.
    for cap in needed() {
        if let Capability::Bus(bus) = cap {
            if profile.bus != Some(bus) {
                return Some(format!(
                    "needs `{cap}`, which profile `{}` does not run over",
                    profile.name()
                ));
            }
        }
    }
    let dut = dut?;
    for cap in needed() {
        if !dut.capabilities.contains(&cap) {
            return Some(format!(
                "needs `{cap}`, which {} does not offer",
                dut.describe
            ));
        }
    }
    None
}

fn needs_dut(case: &Case) -> bool {
    !case.requires.is_empty() || case.steps.iter().any(|s| !s.needs().is_empty())
}

fn run_case(
    case: &Case,
    profile: &Profile,
    opts: &RunOptions,
    guard: &mut Option<Guard>,
    unsettled: &mut bool,
    factory: &mut dyn DutFactory,
    offer: Option<&Offer>,
) -> CaseResult {
    let start = Instant::now();
    // What a device on the network allows is decided from the whole case before anything is
    // sent, opening included: no case half-runs.
    let refused = || guard.as_ref().and_then(|g| g.refuse(case));
    if let Some(why) = not_applicable(case, profile, offer).or_else(refused) {
        return result(
            case,
            profile,
            Verdict::NotApplicable,
            why,
            Vec::new(),
            start,
        );
    }
    let mut discarded = Vec::new();
    loop {
        let (mut r, excuse) = attempt(case, profile, opts, guard, unsettled, factory, start);
        match excuse {
            Some(why) if discarded.len() + 1 < ATTEMPTS => {
                discarded.push(Discarded {
                    why: format!("{why}; the case runs again"),
                    steps: r.steps,
                });
                continue;
            }
            Some(why) => {
                r.message = format!(
                    "{why}, in each of {ATTEMPTS} attempts: no attempt ran on time, nothing \
                     is known of the device (last attempt: {})",
                    r.message
                );
                r.verdict = Verdict::Inconclusive;
            }
            None => {}
        }
        r.discarded = discarded;
        r.duration = start.elapsed();
        crate::report::seal(&mut r);
        return r;
    }
}

/// One attempt at a case: the DUT opened, the steps, the cleanup. With the result comes why it
/// does not count, if it does not: its deciding step timed out while the host was late. When
/// the last cleanup failed (`unsettled`), the drives are brought back before the steps
/// ([`recover`]); a cleanup that fails leaves `unsettled` for the next case.
fn attempt(
    case: &Case,
    profile: &Profile,
    opts: &RunOptions,
    guard: &mut Option<Guard>,
    unsettled: &mut bool,
    factory: &mut dyn DutFactory,
    start: Instant,
) -> (CaseResult, Option<String>) {
    label(opts, || format!("{} {}: open", profile.name(), case.id));
    let mut channel = if needs_dut(case) {
        match factory.open(profile, opts.retries) {
            Ok(dut) => {
                if let Some(why) = not_applicable(case, profile, Some(&Offer::of(dut.as_ref()))) {
                    let r = result(
                        case,
                        profile,
                        Verdict::NotApplicable,
                        why,
                        Vec::new(),
                        start,
                    );
                    return (r, None);
                }
                Some(dut)
            }
            Err(e) => {
                return (
                    open_failed(case, profile, opts, &e, Vec::new(), start),
                    None,
                )
            }
        }
    } else {
        None
    };
    let recovery = match channel.as_mut() {
        Some(dut) if *unsettled => {
            let step = recover(dut.as_mut(), profile, opts);
            if step.verdict != Verdict::Pass {
                let message = step.message.clone();
                let r = result(case, profile, Verdict::Error, message, vec![step], start);
                return (r, None);
            }
            *unsettled = false;
            Some(step)
        }
        _ => None,
    };
    let reopen = channel.as_ref().is_some_and(|d| d.finish_closes());
    if let (Some(step), true) = (&recovery, reopen) {
        // The recovery's cleanup also closed what the opening set up (a bus's connection): the
        // case starts from an opening of its own.
        drop(channel.take());
        match factory.open(profile, opts.retries) {
            Ok(dut) => channel = Some(dut),
            Err(e) => {
                let r = open_failed(case, profile, opts, &e, vec![step.clone()], start);
                return (r, None);
            }
        }
    }
    let (mut r, excuse) = run_steps(case, profile, opts, &mut channel, start);
    if let Some(g) = guard.as_mut() {
        let taken: Vec<bool> = r.steps.iter().map(|s| s.refusal.is_none()).collect();
        g.ran(case, &taken);
    }
    if let Some(step) = recovery {
        r.steps.insert(0, step);
    }
    if let Some(dut) = channel.as_mut() {
        *unsettled = !finish(&mut r, dut.as_mut(), opts);
    }
    (r, excuse)
}

/// A case whose DUT did not open. The run's connection check reached this device: one that
/// cannot be reached now went away during the run (the case before it, which saw it go, has
/// the verdict), so this case is not judged.
fn open_failed(
    case: &Case,
    profile: &Profile,
    opts: &RunOptions,
    e: &OpenError,
    steps: Vec<StepResult>,
    start: Instant,
) -> CaseResult {
    let (verdict, message) = match e {
        OpenError::Unreachable(_) if opts.real_time() => (
            Verdict::Inconclusive,
            format!("not judged: the device stopped answering during the run (it answered the connection check): {e}"),
        ),
        _ => (e.verdict(), format!("cannot open the DUT: {e}")),
    };
    result(case, profile, verdict, message, steps, start)
}

/// Before a case after one whose cleanup failed (a link that broke, a time-out): every
/// inverter of the profile is sent "disable voltage" (0400h: control data valid, nothing else)
/// for one cycle, so the binding counts it as driven, and the binding's cleanup then brings
/// each back to "switch-on disabled", acknowledging faults, with no I/O connection left open:
/// the state every case starts from. What the failed cleanup did not put back (a parameter
/// written) its case's error named; this cannot know it.
fn recover(dut: &mut dyn Binding, profile: &Profile, opts: &RunOptions) -> StepResult {
    label(opts, || format!("{} recovery", profile.name()));
    let mut outcome = Ok(());
    if dut.capabilities().contains(&Capability::ProcessData) {
        for n in 1..=profile.inverters {
            let Ok(inverter) = proto::nord::Inverter::new(n.into()) else {
                continue;
            };
            let stop = Action::Process {
                inverter,
                control: 0x0400,
                setpoints: Vec::new(),
                run: crate::suite::Run::Cycles(1),
            };
            if let Err(e) = dut.perform(&stop) {
                outcome = Err(format!("disable voltage to FI {n}: {e}"));
                break;
            }
        }
    }
    let outcome = outcome.and_then(|()| dut.finish().map_err(|e| e.to_string()));
    let (verdict, message) = match outcome {
        Ok(()) => (Verdict::Pass, String::new()),
        Err(e) => (
            Verdict::Error,
            format!(
                "the drives could not be brought back after the last case's cleanup failed: {e}"
            ),
        ),
    };
    StepResult {
        step: "recovery: bring the drives back, the last case's cleanup having failed".into(),
        verdict,
        observed: Value::Null,
        refusal: None,
        message,
        exchanges: dut.take_exchanges(),
    }
}

/// The case's steps in order, up to the first that does not pass; with it, why that step's
/// outcome says nothing of the device, if the host was late while it waited (see [`excuse`]),
/// or, for a state the device reached on the bus, stalled at any time since the first step
/// ([`stalled`]).
fn run_steps(
    case: &Case,
    profile: &Profile,
    opts: &RunOptions,
    channel: &mut Option<Box<dyn Binding>>,
    start: Instant,
) -> (CaseResult, Option<String>) {
    let mut steps = Vec::new();
    let began = Instant::now();
    for (n, step) in (1..).zip(&case.steps) {
        if n > 1 && opts.stopping() {
            let message = format!(
                "{INTERRUPTED} before step {n} of {}: not judged",
                case.steps.len()
            );
            let r = result(case, profile, Verdict::Inconclusive, message, steps, start);
            return (r, None);
        }
        let (p, id) = (profile.name(), &case.id);
        label(opts, || {
            format!("{p} {id} step {n}: {}", describe(&step.action))
        });
        let (r, timed, window) = run_step(step, profile, channel.as_mut());
        let verdict = r.verdict;
        let message = r.message.clone();
        steps.push(r);
        if verdict != Verdict::Pass {
            let excuse = timed.filter(|_| opts.real_time()).and_then(|timed| {
                excuse(n, timed, window).or_else(|| stalled(n, timed, (began, window.1)))
            });
            return (
                result(case, profile, verdict, message, steps, start),
                excuse,
            );
        }
    }
    let r = result(case, profile, Verdict::Pass, String::new(), steps, start);
    (r, None)
}

/// The time a step's outcome depended on the host keeping.
#[derive(Debug, Clone, Copy)]
enum Timed {
    /// It timed out waiting on the device's limit (zero where the binding does not know it).
    Limit(Duration),
    /// It ran process data this long against the drive's own clock.
    Run(Duration),
    /// A bus's own step ran this long: the bus's cycles against the device's watchdogs, which
    /// fire when a host that lost much of that time stopped the cycles.
    Bus(Duration),
}

/// Why step `n`, whose outcome depended on the host over `window`, says nothing of the device:
/// the host lost a large part of that time meanwhile ([`crate::timing::excuses`]).
fn excuse(n: usize, timed: Timed, window: (Instant, Instant)) -> Option<String> {
    let lost = crate::timing::host_lost(window.0, window.1);
    let ms = crate::timing::ms;
    let (time, against) = match timed {
        Timed::Limit(l) if l.is_zero() => (l, String::new()),
        Timed::Limit(l) => (l, format!(", against the device's limit of {}", ms(l))),
        Timed::Run(d) => (d, format!(", of its {} of process data", ms(d))),
        Timed::Bus(d) => (d, format!(", of its {} on the bus", ms(d))),
    };
    crate::timing::excuses(lost, time)
        .then(|| format!("host late by {} in step {n}{against}", ms(lost)))
}

/// Why step `n`'s outcome, a state the device reached through the bus's cycles (a bus step's,
/// or process data's), says nothing of the device: the host stalled at some time in `span`,
/// since the case's first step, long enough to stop the cycles the state came from
/// ([`crate::timing::STALL_EXCUSE`]). A device that lost the cycles during an earlier step, or
/// between two steps, shows it only in a later one.
fn stalled(n: usize, timed: Timed, span: (Instant, Instant)) -> Option<String> {
    if matches!(timed, Timed::Limit(_)) {
        return None;
    }
    let stall = crate::timing::host_stall(span.0, span.1);
    let ms = crate::timing::ms;
    (stall >= crate::timing::STALL_EXCUSE).then(|| {
        let steps = if n == 1 {
            "in step 1".to_string()
        } else {
            format!("during steps 1–{n}")
        };
        format!(
            "host stalled {} at once {steps}, whose bus cycles the device's state came from",
            ms(stall)
        )
    })
}

/// What every case with a DUT ends with, whatever its verdict: the binding leaves the DUT as
/// the case found it (see [`Binding::finish`]). What it exchanged is a last step, marked as the
/// cleanup, when it did anything; a restore that fails turns a passing case into an error that
/// names what could not be restored (a failed or inconclusive case keeps its verdict, and its
/// message says so too). Whether the cleanup succeeded.
fn finish(r: &mut CaseResult, dut: &mut dyn Binding, opts: &RunOptions) -> bool {
    label(opts, || format!("{} {} cleanup", r.profile, r.id));
    let outcome = dut.finish();
    let exchanges = dut.take_exchanges();
    if outcome.is_ok() && exchanges.is_empty() {
        return true;
    }
    let (verdict, message) = match outcome {
        Ok(()) => (Verdict::Pass, String::new()),
        Err(e) => (
            Verdict::Error,
            format!("cleanup could not leave the DUT as the case found it: {e}"),
        ),
    };
    r.steps.push(StepResult {
        step: "cleanup: leave the DUT as the case found it".into(),
        verdict,
        observed: Value::Null,
        refusal: None,
        message: message.clone(),
        exchanges,
    });
    if verdict == Verdict::Error {
        if r.verdict == Verdict::Pass {
            r.verdict = Verdict::Error;
            r.message = message;
        } else {
            r.message = format!("{}; {message}", r.message);
        }
    }
    verdict == Verdict::Pass
}

/// Labels the run's capture, if there is one, with `text` (made only then).
fn label(opts: &RunOptions, text: impl FnOnce() -> String) {
    if let Some(tap) = &opts.tap {
        tap.borrow_mut().label(&text());
    }
}

/// The step as one line, for reports.
fn describe(action: &Action) -> String {
    match action {
        Action::Compute {
            func,
            args,
            product,
        } => {
            let p = product
                .map(|p| format!(" [{}]", p.name()))
                .unwrap_or_default();
            format!("compute {}{p} {}", func.name, Value::Object(args.clone()))
        }
        Action::Read(o) => format!("read {}", o.describe()),
        Action::Write(o) => format!("write {} = {}", o.describe(), o.value.unwrap_or_default()),
        Action::Pkw { inverter, bytes } => format!("pkw {inverter}: {}", crate::hex::hex(bytes)),
        Action::Process {
            inverter,
            control,
            setpoints,
            run,
        } => {
            let sp: Vec<String> = setpoints.iter().map(|s| format!("{s:04X}h")).collect();
            format!(
                "process {inverter}: control {control:04X}h setpoints [{}] {run:?}",
                sp.join(", ")
            )
        }
        Action::Wait(d) => format!("wait {d:?}"),
        Action::Inject { inverter, error } => format!("inject {inverter}: error {error}"),
        Action::Observe { what, inverter } => format!("observe {inverter}: {what}"),
        Action::Bus(step) => format!("{} {}", step.bus(), step.describe()),
    }
}

/// One step: its result, and when the step ran; with them, for a step whose outcome depends on
/// the host running on time, the time it depended on: the device's limit for a step that timed
/// out waiting on it (zero where the binding does not know it), the step's own duration for
/// process data run against the drive's clock.
fn run_step(
    step: &Step,
    profile: &Profile,
    channel: Option<&mut Box<dyn Binding>>,
) -> (StepResult, Option<Timed>, (Instant, Instant)) {
    let line = describe(&step.action);
    let began = Instant::now();
    let (outcome, exchanges) = match (&step.action, channel) {
        (
            Action::Compute {
                func,
                args,
                product,
            },
            _,
        ) => {
            let Some(product) = product.or(profile.product) else {
                let r = StepResult {
                    step: line,
                    verdict: crate::outcome::Verdict::Error,
                    observed: Value::Null,
                    refusal: None,
                    message: "a reference-model step needs a NORD product".into(),
                    exchanges: Vec::new(),
                };
                return (r, None, (began, Instant::now()));
            };
            let ctx = Ctx { product };
            let out = match (func.run)(&ctx, &Args(args.clone())) {
                Ok(v) => Ok(Observation::from(v)),
                Err(ComputeError::Refused(m)) => Ok(json!({ "error": m }).into()),
                Err(e @ ComputeError::BadArg { .. }) => Err(StepError::Suite(e.into())),
            };
            (out, Vec::new())
        }
        (action, Some(ch)) => {
            let out = ch.perform(action);
            (out, ch.take_exchanges())
        }
        (_, None) => (
            Err(StepError::Suite("a DUT step without a DUT".into())),
            Vec::new(),
        ),
    };
    let window = (began, Instant::now());
    let limit = match (&outcome, &step.action) {
        (Err(StepError::Late { limit, .. }), _) => Some(Timed::Limit(*limit)),
        (Err(StepError::Silent { .. } | StepError::Unanswered { .. }), _) => {
            Some(Timed::Limit(Duration::ZERO))
        }
        // Process data run for a time is judged on what the drive did meanwhile, on its own
        // clock: a host that lost much of that time sent and read it late.
        (Ok(_), Action::Process { .. } | Action::Wait(_)) => Some(Timed::Run(window.1 - window.0)),
        (Ok(_), Action::Bus(_)) => Some(Timed::Bus(window.1 - window.0)),
        _ => None,
    };
    let (verdict, observed, refusal, message) = match outcome {
        Err(e) => (e.verdict(), Value::Null, None, e.to_string()),
        Ok(Observation { fields, refusal }) => {
            // A step that expects nothing expects the device to do it: a refusal fails it.
            let judged = match (&step.expect, &refusal) {
                (Some(m), _) => m.check(&fields).map_err(|e| e.to_string()),
                (None, Some(r)) => Err(format!("the DUT refused the request: {r}")),
                (None, None) => Ok(()),
            };
            match judged {
                Ok(()) => (Verdict::Pass, fields, refusal, String::new()),
                Err(m) if step.setup => (
                    Verdict::Inconclusive,
                    fields,
                    refusal,
                    format!("setup step failed: {m}"),
                ),
                Err(m) => (Verdict::Fail, fields, refusal, m),
            }
        }
    };
    let r = StepResult {
        step: line,
        verdict,
        observed,
        refusal,
        message,
        exchanges,
    };
    (r, limit, window)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::binding::channel::Channel;
    use crate::binding::simulator::ppo_dut;
    use crate::binding::{CleanupError, Dut, DutError};
    use crate::embedded::EmbeddedFactory;
    use crate::profile::Capability;
    use crate::suite::load_text_for_tests;
    use proto::nord::{Inverter, Product};

    /// How the wrapped simulator misbehaves.
    #[derive(Clone, Copy)]
    enum Fault {
        /// Answers nothing (hung or unplugged).
        Silent,
        /// Answers bytes that are not a frame.
        Garbage,
        /// Answers with the order's PKW never processed (always "no response").
        NeverAnswers,
    }

    /// Wraps the real embedded simulator and breaks its answers, as a fault injector on the link.
    struct Faulty {
        inner: Box<dyn Dut>,
        fault: Fault,
    }

    impl Dut for Faulty {
        fn describe(&self) -> String {
            "faulty simulator".into()
        }
        fn capabilities(&self) -> &[Capability] {
            self.inner.capabilities()
        }
        fn cycle_time(&self) -> Duration {
            self.inner.cycle_time()
        }
        fn cycle(&mut self, frame: &[u8]) -> Result<Option<Vec<u8>>, StepError> {
            let answer = self.inner.cycle(frame)?;
            Ok(match self.fault {
                Fault::Silent => None,
                Fault::Garbage => Some(vec![0xDE, 0xAD]),
                Fault::NeverAnswers => answer.map(|mut a| {
                    // Zero the PKW area of the answer (bytes 2..10): "no response", forever.
                    for b in a.iter_mut().skip(2).take(8) {
                        *b = 0;
                    }
                    a
                }),
            })
        }
        fn inject(&mut self, inverter: Inverter, error: &str) -> Result<(), DutError> {
            self.inner.inject(inverter, error)
        }
        fn observe(
            &mut self,
            what: &str,
            inverter: Inverter,
        ) -> Result<serde_json::Value, DutError> {
            self.inner.observe(what, inverter)
        }
    }

    struct FaultyFactory(Fault);

    impl DutFactory for FaultyFactory {
        fn describe(&self) -> String {
            "faulty simulator".into()
        }
        fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
            let dut = Box::new(Faulty {
                inner: ppo_dut(profile)?,
                fault: self.0,
            });
            let product = profile.nord().map_err(OpenError::Profile)?;
            Ok(Box::new(Channel::new(dut, product, retries)))
        }
    }

    const SUITE: &str = r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: read
    title: read P102
    ref: { section: "2.5.6", page: 51 }
    steps:
      - read: { param: 102 }
  - id: process
    title: process data
    ref: { section: "6.1.3", page: 114 }
    steps:
      - process: { control: "047Eh", for: 40ms }
        expect: { status: "xx31h" }
  - id: setup-fails
    title: a failing setup step makes the case inconclusive
    ref: { section: "6.1.3", page: 114 }
    steps:
      - process: { control: "047Eh", for: 40ms }
        expect: { status: "xx37h" }
        setup: true
"#;

    /// The test suite's run: SK 550P, 25 retries, no capture.
    fn sk550p_options() -> RunOptions {
        RunOptions {
            retries: 25,
            ..RunOptions::new(vec![Profile::builtin(Product::Sk550p)])
        }
    }

    fn run_with(fault: Option<Fault>) -> RunResult {
        let loaded = load_text_for_tests(SUITE);
        let opts = sk550p_options();
        match fault {
            None => run(
                &loaded,
                &opts,
                &mut EmbeddedFactory::new(crate::buses::BUSES),
            ),
            Some(f) => run(&loaded, &opts, &mut FaultyFactory(f)),
        }
    }

    fn verdicts(r: &RunResult) -> Vec<(Verdict, &str)> {
        r.cases
            .iter()
            .map(|c| (c.verdict, c.message.as_str()))
            .collect()
    }

    #[test]
    fn a_healthy_dut_passes_and_a_failed_setup_is_inconclusive() {
        let r = run_with(None);
        let v = verdicts(&r);
        assert_eq!(v[0].0, Verdict::Pass, "{v:?}");
        assert_eq!(v[1].0, Verdict::Pass, "{v:?}");
        assert_eq!(v[2].0, Verdict::Inconclusive, "{v:?}");
        assert!(v[2].1.starts_with("setup step failed"), "{v:?}");
    }

    #[test]
    fn a_silent_dut_is_an_error_verdict_not_a_hang() {
        let r = run_with(Some(Fault::Silent));
        for (v, m) in verdicts(&r) {
            assert_eq!(v, Verdict::Error, "{m}");
            assert!(m.contains("no answer from the DUT within"), "{m}");
        }
    }

    /// A DUT that cannot be opened: behind a pulled cable, or answering past its limits.
    struct Unopened(fn() -> OpenError);

    impl DutFactory for Unopened {
        fn describe(&self) -> String {
            "a DUT that cannot be opened".into()
        }
        fn open(&mut self, _: &Profile, _: u32) -> Result<Box<dyn Binding>, OpenError> {
            Err(self.0())
        }
    }

    #[test]
    fn an_unreachable_dut_is_one_connection_check_error_and_the_run_stops() {
        let r = run(
            &load_text_for_tests(SUITE),
            &sk550p_options(),
            &mut Unopened(|| OpenError::Unreachable("connection refused".into())),
        );
        let v = verdicts(&r);
        assert_eq!(
            v,
            [(
                Verdict::Error,
                "cannot reach the DUT: connection refused; the run stopped before its cases"
            )]
        );
        assert_eq!(r.cases[0].id, CONNECTION_CHECK);
    }

    #[test]
    fn a_dut_that_comes_up_only_past_its_limits_fails_the_connection_check() {
        let late = || {
            OpenError::Late(
                "a frame back: no answer within the device's limit of 50 ms (waited 51 ms)".into(),
            )
        };
        let r = run(
            &load_text_for_tests(SUITE),
            &sk550p_options(),
            &mut Unopened(late),
        );
        assert_eq!(
            verdicts(&r),
            [(
                Verdict::Fail,
                "the DUT answers late: a frame back: no answer within the device's limit of 50 \
                 ms (waited 51 ms); given 5 times its limits, it came up; the run stopped \
                 before its cases"
            )]
        );
        assert_eq!(r.cases[0].id, CONNECTION_CHECK);
    }

    #[test]
    fn a_silent_dut_with_an_identity_to_read_fails_the_connection_check() {
        let opts = RunOptions {
            profiles: vec![Profile::builtin(Product::Tu3Pnt)],
            ..sk550p_options()
        };
        let r = run(
            &load_text_for_tests(SUITE),
            &opts,
            &mut FaultyFactory(Fault::Silent),
        );
        assert_eq!(r.cases.len(), 1);
        assert_eq!(r.cases[0].id, CONNECTION_CHECK);
        assert!(
            r.cases[0].message.contains("no answer from the DUT"),
            "{}",
            r.cases[0].message
        );
    }

    #[test]
    fn the_identity_of_each_profile_is_recorded() {
        let opts = RunOptions {
            profiles: vec![
                Profile::builtin(Product::Tu3Pnt),
                Profile::builtin(Product::Sk550p),
            ],
            ..sk550p_options()
        };
        let r = run(
            &load_text_for_tests(SUITE),
            &opts,
            &mut EmbeddedFactory::new(crate::buses::BUSES),
        );
        let pnt = &r.meta.identities["tu3-pnt"];
        assert_eq!(
            pnt.source,
            "P171 software version over the parameter channel"
        );
        assert!(pnt.revision.is_some(), "{pnt:?}");
        assert!(r.meta.identities["sk550p"].source.starts_with("none: "));
    }

    #[test]
    fn every_bus_profile_reads_its_bus_identity_service() {
        let loaded = load_text_for_tests(SUITE);
        let opts = RunOptions::new(crate::buses::catalog().all());
        let r = run(
            &loaded,
            &opts,
            &mut EmbeddedFactory::new(crate::buses::BUSES),
        );
        for p in crate::buses::catalog().all() {
            let id = &r.meta.identities[p.name()];
            eprintln!("{}: {}", p.name(), id.line());
            // Which service each bus asks, and what else it answers, is its own folder's test.
            if p.bus.is_some() {
                assert!(!id.source.starts_with("none"), "{}: {id:?}", p.name());
                assert!(id.vendor.is_some(), "{id:?}");
            }
        }
    }

    #[test]
    fn a_garbage_answer_fails_naming_the_problem() {
        let r = run_with(Some(Fault::Garbage));
        let (v, m) = verdicts(&r)[0];
        assert_eq!(v, Verdict::Fail);
        assert!(
            m.contains("malformed answer from the DUT: data record 222 addresses neither"),
            "{m}"
        );
    }

    #[test]
    fn an_order_never_answered_fails_after_the_bounded_retries() {
        let r = run_with(Some(Fault::NeverAnswers));
        let (v, m) = verdicts(&r)[0];
        assert_eq!(v, Verdict::Fail);
        assert!(
            m.contains("did not answer the order within 25 bus cycles"),
            "{m}"
        );
    }

    /// The embedded simulator, counting the DUTs opened.
    struct Counting(usize);

    impl DutFactory for Counting {
        fn describe(&self) -> String {
            "counting simulator".into()
        }
        fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
            self.0 += 1;
            EmbeddedFactory::new(crate::buses::BUSES).open(profile, retries)
        }
    }

    #[test]
    fn without_allow_motion_a_motion_case_is_not_applicable_before_the_dut_is_opened() {
        let loaded = load_text_for_tests(
            r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: enables
    title: enables operation
    ref: { section: "6.1.3", page: 114 }
    steps:
      - read: { param: 102 }
      - process: { control: "047Fh", setpoints: ["2000h"], for: 40ms }
  - id: writes
    title: writes P102
    ref: { section: "2.5.6", page: 51 }
    steps:
      - write: { param: 102, value: 100 }
"#,
        );
        let opts = RunOptions {
            limits: Some(crate::safety::Limits {
                allow_motion: false,
                max_eeprom_writes: 20,
            }),
            ..sk550p_options()
        };
        let mut factory = Counting(0);
        let r = run(&loaded, &opts, &mut factory);
        let c = &r.cases[0];
        assert_eq!(c.verdict, Verdict::NotApplicable);
        assert!(
            c.message
                .starts_with("motion not allowed (--allow-motion): control word 047Fh"),
            "{}",
            c.message
        );
        assert!(c.steps.is_empty());
        // The connection check and the other case opened the DUT, the motion case never; the
        // write and its restore are counted.
        assert_eq!(factory.0, 2);
        assert_eq!(r.cases[1].verdict, Verdict::Pass, "{}", r.cases[1].message);
        assert!(!r.meta.motion_allowed);
        assert_eq!(r.meta.eeprom_writes, 2);
        // The embedded simulator runs both, and says motion was allowed.
        let r = run(&loaded, &sk550p_options(), &mut Counting(0));
        assert_eq!(r.cases[0].verdict, Verdict::Pass, "{}", r.cases[0].message);
        assert!(r.meta.motion_allowed);
    }

    /// The embedded simulator behind a binding whose cleanup does what the test says.
    struct Restoring {
        inner: Box<dyn Binding>,
        /// What the cleanup returns, and whether it exchanged anything.
        outcome: Result<(), CleanupError>,
        exchanged: bool,
        finished: bool,
        /// Its cleanup undoes its opening (a binding that releases the connection it opened).
        closes: bool,
    }

    impl Binding for Restoring {
        fn describe(&self) -> String {
            self.inner.describe()
        }
        fn capabilities(&self) -> &[Capability] {
            self.inner.capabilities()
        }
        fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
            self.inner.perform(action)
        }
        fn take_exchanges(&mut self) -> Vec<crate::outcome::Exchange> {
            let mut x = self.inner.take_exchanges();
            if self.finished && std::mem::take(&mut self.exchanged) {
                x.push(crate::outcome::Exchange {
                    sent_hex: "10 03 20 65 24 01 30 66 C8 00".into(),
                    sent: "Set_Attribute_Single P102 = 200".into(),
                    received_hex: "90 00 00 00".into(),
                    received: "success".into(),
                });
            }
            x
        }
        fn finish(&mut self) -> Result<(), CleanupError> {
            self.finished = true;
            self.outcome.clone()
        }
        fn finish_closes(&self) -> bool {
            self.closes
        }
    }

    /// Bindings whose cleanup returns `outcome` (those opened for the cases whose numbers,
    /// from 0, `failing` holds; the others' succeed), and whether it exchanged anything.
    struct RestoringFactory {
        outcome: Result<(), CleanupError>,
        exchanged: bool,
        failing: &'static [usize],
        opened: usize,
        closes: bool,
    }

    impl DutFactory for RestoringFactory {
        fn describe(&self) -> String {
            "restoring simulator".into()
        }
        fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
            let inner = EmbeddedFactory::new(crate::buses::BUSES).open(profile, retries)?;
            // The connection check opens one first.
            let case = self.opened.checked_sub(1);
            self.opened += 1;
            let fails = case.is_some_and(|n| self.failing.contains(&n));
            Ok(Box::new(Restoring {
                inner,
                outcome: if fails { self.outcome.clone() } else { Ok(()) },
                exchanged: self.exchanged,
                finished: false,
                closes: self.closes,
            }))
        }
    }

    fn run_restoring(
        outcome: Result<(), CleanupError>,
        exchanged: bool,
        failing: &'static [usize],
    ) -> RunResult {
        let loaded = load_text_for_tests(SUITE);
        let opts = sk550p_options();
        let mut factory = RestoringFactory {
            outcome,
            exchanged,
            failing,
            opened: 0,
            closes: false,
        };
        run(&loaded, &opts, &mut factory)
    }

    #[test]
    fn a_binding_whose_cleanup_closes_its_opening_is_opened_again_after_the_recovery() {
        let loaded = load_text_for_tests(SUITE);
        let opts = sk550p_options();
        let opens = |closes| {
            let mut factory = RestoringFactory {
                outcome: Err(CleanupError("link error: no answer".into())),
                exchanged: false,
                failing: &[0],
                opened: 0,
                closes,
            };
            let r = run(&loaded, &opts, &mut factory);
            assert_eq!(r.cases[1].verdict, Verdict::Pass, "{}", r.cases[1].message);
            factory.opened
        };
        // The connection check and one opening per case; one more for the case that
        // recovered, when the recovery's cleanup closed what its opening set up.
        let plain = opens(false);
        assert_eq!(opens(true), plain + 1);
    }

    /// The embedded simulator behind a binding that asks for a stop (as Ctrl-C does) during
    /// its first step, and counts its cleanups.
    struct Interrupting {
        inner: Box<dyn Binding>,
        stop: &'static AtomicBool,
        cleanups: std::rc::Rc<std::cell::Cell<usize>>,
        /// Not the connection check's opening.
        armed: bool,
    }

    impl Binding for Interrupting {
        fn describe(&self) -> String {
            self.inner.describe()
        }
        fn capabilities(&self) -> &[Capability] {
            self.inner.capabilities()
        }
        fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
            if self.armed {
                self.stop.store(true, Ordering::Relaxed);
            }
            self.inner.perform(action)
        }
        fn take_exchanges(&mut self) -> Vec<crate::outcome::Exchange> {
            self.inner.take_exchanges()
        }
        fn finish(&mut self) -> Result<(), CleanupError> {
            if self.armed {
                self.cleanups.set(self.cleanups.get() + 1);
            }
            self.inner.finish()
        }
    }

    struct InterruptingFactory {
        stop: &'static AtomicBool,
        cleanups: std::rc::Rc<std::cell::Cell<usize>>,
        opened: usize,
    }

    impl DutFactory for InterruptingFactory {
        fn describe(&self) -> String {
            "interrupting simulator".into()
        }
        fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
            let inner = EmbeddedFactory::new(crate::buses::BUSES).open(profile, retries)?;
            self.opened += 1;
            Ok(Box::new(Interrupting {
                inner,
                stop: self.stop,
                cleanups: self.cleanups.clone(),
                armed: self.opened > 1,
            }))
        }
    }

    #[test]
    fn a_stop_ends_the_case_after_its_step_runs_its_cleanup_and_starts_no_other() {
        let loaded = load_text_for_tests(
            r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: two-steps
    title: two reads
    ref: { section: "2.5.6", page: 51 }
    steps:
      - read: { param: 102 }
      - read: { param: 102 }
  - id: never-started
    title: a read
    ref: { section: "2.5.6", page: 51 }
    steps:
      - read: { param: 102 }
"#,
        );
        let stop: &'static AtomicBool = Box::leak(Box::new(AtomicBool::new(false)));
        let opts = RunOptions {
            stop,
            ..sk550p_options()
        };
        let cleanups = std::rc::Rc::new(std::cell::Cell::new(0));
        let mut factory = InterruptingFactory {
            stop,
            cleanups: cleanups.clone(),
            opened: 0,
        };
        let r = run(&loaded, &opts, &mut factory);
        assert_eq!(r.cases.len(), 1, "{:?}", verdicts(&r));
        let c = &r.cases[0];
        assert_eq!(c.verdict, Verdict::Inconclusive);
        assert_eq!(c.message, "interrupted before step 2 of 2: not judged");
        assert_eq!(
            c.steps.len(),
            1,
            "the step under way finished, the next never ran"
        );
        assert_eq!(
            cleanups.get(),
            1,
            "the cut case's cleanup ran (the check's is not counted)"
        );
        assert_eq!(
            factory.opened, 2,
            "the connection check and the cut case only"
        );
        let i = r.meta.interrupted.expect("marked interrupted");
        let named = |n: usize| format!("sk550p {}", loaded.cases[n].id);
        assert_eq!(i.cut, [named(0)]);
        assert_eq!(i.not_run, [named(1)]);

        // Stopped before it began: nothing runs, everything is listed.
        let r = run(
            &loaded,
            &opts,
            &mut EmbeddedFactory::new(crate::buses::BUSES),
        );
        assert!(r.cases.is_empty());
        assert_eq!(r.meta.interrupted.expect("interrupted").not_run.len(), 2);
    }

    #[test]
    fn a_cleanup_that_does_nothing_adds_no_step() {
        let r = run_restoring(Ok(()), false, &[]);
        assert_eq!(r.cases[0].verdict, Verdict::Pass);
        assert_eq!(r.cases[0].steps.len(), 1);
    }

    #[test]
    fn a_cleanup_shows_as_a_last_step_marked_as_such() {
        let r = run_restoring(Ok(()), true, &[]);
        let c = &r.cases[0];
        assert_eq!(c.verdict, Verdict::Pass, "{}", c.message);
        let last = c.steps.last().unwrap();
        assert_eq!(last.step, "cleanup: leave the DUT as the case found it");
        assert_eq!(last.verdict, Verdict::Pass);
        let body = c.transcript.as_deref().unwrap_or_default();
        let cleanup = body.split("\nstep ").last().unwrap_or_default();
        assert!(
            cleanup.contains("\n  -> ")
                && cleanup.contains("\n     Set_Attribute_Single P102 = 200\n"),
            "{body}"
        );
        // Whatever the verdict: the inconclusive case is cleaned up too.
        assert!(r.cases[2].steps.last().unwrap().step.starts_with("cleanup"));
    }

    #[test]
    fn a_failed_restore_makes_a_passing_case_an_error_naming_what_was_not_restored() {
        let r = run_restoring(
            Err(CleanupError("P102 not set back to [C8 00]: 0Eh".into())),
            false,
            &[0, 2],
        );
        let c = &r.cases[0];
        assert_eq!(c.verdict, Verdict::Error);
        assert_eq!(
            c.message,
            "cleanup could not leave the DUT as the case found it: P102 not set back to [C8 00]: 0Eh"
        );
        assert_eq!(c.steps.last().unwrap().verdict, Verdict::Error);
        // A case that did not pass keeps its verdict; its message says both.
        let c = &r.cases[2];
        assert_eq!(c.verdict, Verdict::Inconclusive);
        assert!(c.message.starts_with("setup step failed"), "{}", c.message);
        assert!(
            c.message.contains("; cleanup could not leave the DUT"),
            "{}",
            c.message
        );
    }

    #[test]
    fn after_a_failed_cleanup_the_next_case_brings_the_drives_back_first() {
        let failed = || Err(CleanupError("link error: no answer".into()));
        let recovery = "recovery: bring the drives back, the last case's cleanup having failed";
        let r = run_restoring(failed(), false, &[0]);
        assert_eq!(r.cases[0].verdict, Verdict::Error);
        // The next case starts with the recovery: "disable voltage" to the inverter, then
        // the binding's cleanup; then its own steps, which pass.
        let c = &r.cases[1];
        assert_eq!(c.verdict, Verdict::Pass, "{}", c.message);
        assert_eq!(c.steps[0].step, recovery);
        assert_eq!(c.steps[0].verdict, Verdict::Pass);
        let body = c.transcript.as_deref().unwrap_or_default();
        let first = body.split("\nstep ").nth(1).unwrap_or_default();
        assert!(
            first.starts_with("1: recovery") && first.contains("\n  -> "),
            "{body}"
        );
        assert!(
            c.steps[1].step.starts_with("process"),
            "{}",
            c.steps[1].step
        );
        // Once recovered, the case after it has none.
        assert!(r.cases[2].steps.iter().all(|s| s.step != recovery));

        // A recovery that fails is the case's error, and the next case tries again.
        let r = run_restoring(failed(), false, &[0, 1]);
        let c = &r.cases[1];
        assert_eq!(c.verdict, Verdict::Error);
        assert_eq!(c.steps.len(), 1);
        assert_eq!(
            c.message,
            "the drives could not be brought back after the last case's cleanup failed: link \
             error: no answer"
        );
        assert_eq!(r.cases[2].steps[0].step, recovery);
        assert_eq!(r.cases[2].steps[0].verdict, Verdict::Pass);
    }

    /// The embedded simulator behind a binding whose first `late` steps time out against a
    /// 20 ms limit, the host late by `host_late` meanwhile when that is not zero.
    struct LateFactory {
        late: usize,
        host_late: Duration,
    }

    struct Late {
        inner: Box<dyn Binding>,
        late: bool,
        host_late: Duration,
    }

    impl Binding for Late {
        fn describe(&self) -> String {
            self.inner.describe()
        }
        fn capabilities(&self) -> &[Capability] {
            self.inner.capabilities()
        }
        fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
            if !self.late {
                return self.inner.perform(action);
            }
            if !self.host_late.is_zero() {
                crate::timing::pretend_host_late(self.host_late);
            }
            if matches!(action, Action::Process { .. }) {
                // The drive, seen late, still "switch-on disabled".
                return Ok(crate::binding::process_fields(0x0B40, &[0, 0, 0]).into());
            }
            if matches!(action, Action::Bus(_)) {
                // A node whose bus cycles stopped: back in a state short of the one asked.
                return Ok(serde_json::json!({ "state": "PRE_OPERATIONAL_2" }).into());
            }
            Err(StepError::Late {
                what: "read P102".into(),
                limit: Duration::from_millis(20),
                waited: Duration::from_millis(21) + self.host_late,
            })
        }
        fn take_exchanges(&mut self) -> Vec<crate::outcome::Exchange> {
            self.inner.take_exchanges()
        }
    }

    impl DutFactory for LateFactory {
        fn describe(&self) -> String {
            "late simulator".into()
        }
        fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
            let late = self.late > 0;
            self.late = self.late.saturating_sub(1);
            Ok(Box::new(Late {
                inner: EmbeddedFactory::new(crate::buses::BUSES).open(profile, retries)?,
                late,
                host_late: self.host_late,
            }))
        }
    }

    /// Case `read` of [`SUITE`] on a DUT on the network (real time) whose first `late` openings
    /// time out, the host late by `host_late` meanwhile. The connection check opens it once
    /// before (SK 550P: nothing to read, no step).
    fn run_late(late: usize, host_late: Duration, real_time: bool) -> CaseResult {
        run_late_case("read", late, host_late, real_time)
    }

    /// [`run_late`] for case `id`.
    fn run_late_case(id: &str, late: usize, host_late: Duration, real_time: bool) -> CaseResult {
        let sk550p = Profile::builtin(Product::Sk550p);
        run_late_in((SUITE, sk550p), id, late, host_late, real_time)
    }

    /// [`run_late_case`] of `suite` for `profile`.
    fn run_late_in(
        (suite, profile): (&str, Profile),
        id: &str,
        late: usize,
        host_late: Duration,
        real_time: bool,
    ) -> CaseResult {
        let _one = crate::timing::TESTS
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let opts = RunOptions {
            filter: Some(id.into()),
            limits: real_time.then_some(crate::safety::Limits {
                allow_motion: true,
                max_eeprom_writes: 20,
            }),
            ..RunOptions {
                retries: 25,
                ..RunOptions::new(vec![profile])
            }
        };
        let mut f = LateFactory {
            late: late + 1,
            host_late,
        };
        let r = run(&load_text_for_tests(suite), &opts, &mut f);
        r.cases.into_iter().next().unwrap()
    }

    #[test]
    fn a_time_out_while_the_host_was_late_is_discarded_and_the_case_runs_again() {
        let c = run_late(1, Duration::from_millis(40), true);
        assert_eq!(c.verdict, Verdict::Pass, "{}", c.message);
        assert_eq!(c.discarded.len(), 1);
        let why = &c.discarded[0].why;
        assert!(
            why.starts_with("host late by ")
                && why.ends_with(
                    " in step 1, against the device's limit of 20 ms; the case runs again"
                ),
            "{why}"
        );
        let t = crate::report::transcript_for_tests(&c);
        assert!(t.contains("\nattempt 1 discarded: host late by "), "{t}");
        assert!(t.contains("\nattempt 1, step 1: read P102"), "{t}");
        assert!(
            t.contains("\nattempt 2 (counted):\n\nstep 1: read P102"),
            "{t}"
        );
    }

    #[test]
    fn process_data_judged_while_the_host_was_late_is_run_again() {
        let c = run_late_case("process", 1, Duration::from_millis(40), true);
        assert_eq!(c.verdict, Verdict::Pass, "{}", c.message);
        let why = &c.discarded[0].why;
        assert!(why.starts_with("host late by "), "{why}");
        assert!(why.contains(" in step 1, of its "), "{why}");
        assert!(
            why.ends_with(" of process data; the case runs again"),
            "{why}"
        );
        // With the host on time the drive's answer stands.
        let c = run_late_case("process", 1, Duration::ZERO, true);
        assert_eq!(c.verdict, Verdict::Fail, "{}", c.message);
    }

    /// A bus's own step, whose answer is judged by the node's state (one bus's suite: any bus's
    /// step would do).
    const BUS_SUITE: &str = r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: start-node
    title: start the node
    ref: { section: "2.4.3.3", page: 30 }
    steps:
      - epl: { nmt: start-node }
        expect: { state: OPERATIONAL }
"#;

    #[test]
    fn a_bus_step_judged_while_the_host_was_late_is_run_again() {
        let epl = || {
            (
                BUS_SUITE,
                crate::buses::catalog().by_name("sk550p@epl").unwrap(),
            )
        };
        let c = run_late_in(epl(), "start-node", 1, Duration::from_millis(40), true);
        assert_eq!(c.discarded.len(), 1, "{:?} {}", c.verdict, c.message);
        let why = &c.discarded[0].why;
        assert!(why.starts_with("host late by "), "{why}");
        assert!(why.contains(" in step 1, of its "), "{why}");
        assert!(why.ends_with(" on the bus; the case runs again"), "{why}");
        // With the host on time the node's state stands.
        let c = run_late_in(epl(), "start-node", 1, Duration::ZERO, true);
        assert_eq!(c.verdict, Verdict::Fail, "{}", c.message);
        assert!(c.discarded.is_empty());
    }

    #[test]
    fn a_state_after_a_stall_in_an_earlier_step_is_excused_a_time_out_is_not() {
        let _one = crate::timing::TESTS
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        crate::timing::start_watch();
        let began = Instant::now();
        // Step 1's cycles stalled for 30 ms; step 2, on time, finds the node fallen back.
        crate::timing::pretend_host_late(Duration::from_millis(30));
        let step2 = (Instant::now(), Instant::now() + Duration::from_millis(2));
        let bus = Timed::Bus(Duration::from_millis(2));
        assert_eq!(excuse(2, bus, step2), None, "nothing late in step 2 itself");
        let why = stalled(2, bus, (began, step2.1)).expect("excused");
        assert!(why.starts_with("host stalled "), "{why}");
        assert!(
            why.ends_with(
                " at once during steps 1–2, whose bus cycles the device's state came from"
            ),
            "{why}"
        );
        assert!(stalled(2, Timed::Run(Duration::from_secs(2)), (began, step2.1)).is_some());
        // A time-out is the device's limit against its own window only.
        let limit = Timed::Limit(Duration::from_millis(20));
        assert_eq!(stalled(2, limit, (began, step2.1)), None);
        // A stall shorter than the bound excuses nothing.
        let later = Instant::now();
        crate::timing::pretend_host_late(Duration::from_millis(10));
        assert_eq!(stalled(2, bus, (later, Instant::now())), None);
    }

    #[test]
    fn a_case_never_run_on_time_is_inconclusive_never_fail_or_error() {
        let c = run_late(ATTEMPTS, Duration::from_millis(40), true);
        assert_eq!(c.verdict, Verdict::Inconclusive, "{}", c.message);
        assert!(c.message.starts_with("host late by "), "{}", c.message);
        assert!(
            c.message
                .contains("in each of 3 attempts: no attempt ran on time"),
            "{}",
            c.message
        );
        assert_eq!(c.discarded.len(), ATTEMPTS - 1);
    }

    #[test]
    fn a_device_late_while_the_host_was_on_time_fails_with_both_times() {
        let c = run_late(1, Duration::ZERO, true);
        assert_eq!(c.verdict, Verdict::Fail);
        assert!(c.discarded.is_empty());
        assert!(
            c.message.starts_with(
                "read P102: no answer within the device's limit of 20 ms (waited 21 ms)"
            ),
            "{}",
            c.message
        );
        // The embedded simulator runs on a virtual clock: the host's lateness is not its.
        let c = run_late(1, Duration::from_millis(40), false);
        assert_eq!(c.verdict, Verdict::Fail);
    }

    #[test]
    fn a_shuffled_run_is_the_same_cases_in_an_order_its_seed_repeats() {
        let loaded = load_text_for_tests(SUITE);
        let ids = |shuffle| {
            let opts = RunOptions {
                shuffle,
                ..sk550p_options()
            };
            let r = run(
                &loaded,
                &opts,
                &mut EmbeddedFactory::new(crate::buses::BUSES),
            );
            assert_eq!(r.meta.shuffle, shuffle);
            r.cases.into_iter().map(|c| c.id).collect::<Vec<_>>()
        };
        let plain = ids(None);
        let orders: Vec<_> = (0..8).map(|seed| ids(Some(seed))).collect();
        assert_eq!(orders[3], ids(Some(3)), "a seed repeats its order");
        assert!(orders.iter().any(|o| *o != plain), "{orders:?}");
        for o in &orders {
            let (mut a, mut b) = (o.clone(), plain.clone());
            a.sort();
            b.sort();
            assert_eq!(a, b);
        }
    }

    #[test]
    fn a_shard_runs_its_round_robin_share_numbered_in_the_unsharded_order() {
        let loaded = load_text_for_tests(SUITE);
        let opts = RunOptions {
            profiles: vec![
                Profile::builtin(Product::Sk550p),
                Profile::builtin(Product::Tu3Eip),
            ],
            filter: Some("a".into()),
            ..sk550p_options()
        };
        let whole = run(
            &loaded,
            &opts,
            &mut EmbeddedFactory::new(crate::buses::BUSES),
        );
        let names = |r: &RunResult| -> Vec<(usize, String, String)> {
            r.cases
                .iter()
                .map(|c| (c.seq, c.profile.clone(), c.id.clone()))
                .collect()
        };
        // `read` and `setup-fails` under both profiles, profile-major.
        assert_eq!(
            names(&whole).iter().map(|n| n.0).collect::<Vec<_>>(),
            [0, 1, 2, 3]
        );
        assert_eq!(whole.meta.shard, None);
        let shard: Shard = "2/3".parse().unwrap();
        let part = run_shard(
            &loaded,
            &opts,
            Some(shard),
            &mut EmbeddedFactory::new(crate::buses::BUSES),
        );
        assert_eq!(names(&part), [names(&whole)[1].clone()]);
        assert_eq!(part.cases[0].verdict, whole.cases[1].verdict);
        assert_eq!(part.meta.shard, Some(Shard { of: 4, ..shard }));
    }
}
