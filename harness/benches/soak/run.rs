//! One bus's soak, the same for every bus: good clients alone (the idle phase), then good
//! clients beside fuzzed clients (the mixed phase), the served process's memory sampled all
//! along. Each good client asks at a steady pace and times every answer; each fuzzed client
//! sends broken frames at a bounded rate.

use std::sync::atomic::{AtomicU64, AtomicU8, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use harness::stats::percentile;

use super::rss::{cpu_time, Samples};

/// What a good request got.
#[derive(Debug)]
pub(crate) enum Answer {
    /// The known answer.
    Right,
    /// An answer, not the known one (a refusal, another value): what it was.
    Wrong(String),
    /// No answer: no reply in time, or the connection failed.
    Lost(String),
}

/// A served bus the soak drives: how its good and fuzzed clients are made and what one step
/// of each does.
pub(crate) trait Bus: Sync {
    /// A good client's connection or socket.
    type Good: Send;
    /// A fuzzed client's sockets and generator.
    type Fuzz: Send;
    /// A good client (number `n`), connected.
    fn good(&self, n: usize) -> Result<Self::Good, String>;
    /// One good request and its answer checked (the soak times it).
    fn ask(&self, client: &mut Self::Good) -> Answer;
    /// A fuzzed client whose generator starts from `seed`.
    fn fuzzer(&self, seed: u64) -> Result<Self::Fuzz, String>;
    /// Sends a few broken frames (reading whatever comes back); how many.
    fn fuzz(&self, client: &mut Self::Fuzz) -> u64;
}

/// How long and how hard.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    pub(crate) idle: Duration,
    pub(crate) mixed: Duration,
    pub(crate) good_clients: usize,
    /// Each good client's pace: one request per period.
    pub(crate) period: Duration,
    pub(crate) fuzz_clients: usize,
    /// Broken frames per second, all fuzzed clients together, at most.
    pub(crate) fuzz_rate: u64,
    pub(crate) seed: u64,
    pub(crate) rss_every: Duration,
}

/// The good clients' record of one phase.
#[derive(Debug, Default)]
pub(crate) struct Phase {
    /// Times of the right answers, ascending once the phase is done.
    pub(crate) times: Vec<Duration>,
    pub(crate) wrong: u64,
    pub(crate) lost: u64,
    /// The first few wrong or lost answers, said.
    pub(crate) said: Vec<String>,
}

impl Phase {
    pub(crate) fn requests(&self) -> u64 {
        self.times.len() as u64 + self.wrong + self.lost
    }

    pub(crate) fn p(&self, p: f64) -> Option<Duration> {
        percentile(&self.times, p)
    }

    fn add(&mut self, other: Phase) {
        self.times.extend(other.times);
        self.wrong += other.wrong;
        self.lost += other.lost;
        for s in other.said {
            if self.said.len() < SAID {
                self.said.push(s);
            }
        }
    }

    fn record(&mut self, answer: Answer, took: Duration) {
        let said = match answer {
            Answer::Right => {
                self.times.push(took);
                return;
            }
            Answer::Wrong(s) => {
                self.wrong += 1;
                format!("wrong: {s}")
            }
            Answer::Lost(s) => {
                self.lost += 1;
                format!("lost: {s}")
            }
        };
        if self.said.len() < SAID {
            self.said.push(said);
        }
    }
}

/// Wrong or lost answers quoted per phase.
const SAID: usize = 5;

/// What one soak measured.
#[derive(Debug)]
pub(crate) struct Soaked {
    pub(crate) idle: Phase,
    pub(crate) mixed: Phase,
    /// The served process's memory over the whole soak.
    pub(crate) rss: Samples,
    /// When the mixed phase began, from the start of the soak.
    pub(crate) mixed_from: Duration,
    /// How long it lasted.
    pub(crate) mixed_for: Duration,
    /// Broken frames sent.
    pub(crate) fuzzed: u64,
    /// Whether the served process was still there at the end.
    pub(crate) alive: bool,
    /// The processor time the served process used in the idle and the mixed phase.
    pub(crate) cpu: (Duration, Duration),
    /// What a good client made after the soak got (a device that leaked sessions or
    /// connections to the fuzzed clients refuses a new one); `Err` when it could not connect.
    pub(crate) fresh: Result<Answer, String>,
}

const IDLE: u8 = 0;
const MIXED: u8 = 1;
const STOP: u8 = 2;

/// Runs `plan` against `bus`, whose served process is `pid`.
pub(crate) fn soak<B: Bus>(bus: &B, pid: u32, plan: &Plan) -> Result<Soaked, String> {
    let phase = AtomicU8::new(IDLE);
    let fuzzed = AtomicU64::new(0);
    let goods = (0..plan.good_clients)
        .map(|n| bus.good(n))
        .collect::<Result<Vec<_>, _>>()?;
    let fuzzers = (0..plan.fuzz_clients)
        .map(|n| bus.fuzzer(plan.seed.wrapping_add(n as u64)))
        .collect::<Result<Vec<_>, _>>()?;
    let per_fuzzer = plan.fuzz_rate as f64 / plan.fuzz_clients.max(1) as f64;
    thread::scope(|scope| {
        let good_threads: Vec<_> = goods
            .into_iter()
            .enumerate()
            .map(|(n, client)| {
                let phase = &phase;
                scope.spawn(move || good_client(bus, n, client, phase, plan.period))
            })
            .collect();
        for mut client in fuzzers {
            let (phase, fuzzed) = (&phase, &fuzzed);
            scope.spawn(move || {
                while phase.load(Ordering::Acquire) == IDLE {
                    thread::sleep(Duration::from_millis(5));
                }
                let start = Instant::now();
                let (mut steps, mut sent) = (0u64, 0u64);
                while phase.load(Ordering::Acquire) == MIXED {
                    sent += bus.fuzz(&mut client);
                    // Never ahead of the rate, counting steps that sent nothing too (a
                    // connection refused), so that such a step does not spin.
                    steps += 1;
                    let due = Duration::from_secs_f64(steps as f64 / per_fuzzer);
                    if let Some(wait) = due.checked_sub(start.elapsed()) {
                        thread::sleep(wait);
                    }
                }
                fuzzed.fetch_add(sent, Ordering::Relaxed);
            });
        }

        let start = Instant::now();
        let cpu_start = cpu_time(pid).unwrap_or_default();
        let mut cpu_mixed = None;
        let mut rss = Samples::default();
        let mut alive = true;
        let end = plan.idle + plan.mixed;
        while start.elapsed() < end && alive {
            if start.elapsed() >= plan.idle && cpu_mixed.is_none() {
                cpu_mixed = cpu_time(pid);
                phase.store(MIXED, Ordering::Release);
            }
            alive = rss.take(pid, start);
            thread::sleep(plan.rss_every);
        }
        if alive {
            alive = rss.take(pid, start);
        }
        let cpu_end = cpu_time(pid).unwrap_or_default();
        phase.store(STOP, Ordering::Release);
        let cpu_mixed = cpu_mixed.unwrap_or(cpu_end);

        let (mut idle, mut mixed) = (Phase::default(), Phase::default());
        for t in good_threads {
            let (i, m) = t
                .join()
                .map_err(|_| "a good client's thread panicked".to_string())?;
            idle.add(i);
            mixed.add(m);
        }
        idle.times.sort_unstable();
        mixed.times.sort_unstable();
        let fresh = bus
            .good(plan.good_clients)
            .map(|mut client| bus.ask(&mut client));
        Ok(Soaked {
            idle,
            mixed,
            rss,
            mixed_from: plan.idle,
            mixed_for: plan.mixed,
            fuzzed: 0,
            alive,
            cpu: (
                cpu_mixed.saturating_sub(cpu_start),
                cpu_end.saturating_sub(cpu_mixed),
            ),
            fresh,
        })
    })
    .map(|s| Soaked {
        fuzzed: fuzzed.load(Ordering::Relaxed),
        ..s
    })
}

/// A good client asking once every `period` (a late request is not made up for) until the
/// soak stops; its idle and mixed phases' records. A lost answer reconnects it.
fn good_client<B: Bus>(
    bus: &B,
    n: usize,
    mut client: B::Good,
    phase: &AtomicU8,
    period: Duration,
) -> (Phase, Phase) {
    let mut record = [Phase::default(), Phase::default()];
    let mut next = Instant::now();
    loop {
        let now_phase = phase.load(Ordering::Acquire);
        if now_phase == STOP {
            break;
        }
        let t = Instant::now();
        let answer = bus.ask(&mut client);
        let took = t.elapsed();
        let lost = matches!(answer, Answer::Lost(_));
        record[usize::from(now_phase)].record(answer, took);
        if lost {
            if let Ok(c) = bus.good(n) {
                client = c;
            }
        }
        next = (next + period).max(Instant::now());
        thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    let [idle, mixed] = record;
    (idle, mixed)
}
