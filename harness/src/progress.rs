//! How a run shows that it is moving: a progress bar with the current profile and case on a
//! terminal, a plain line now and then when stderr is a file or a CI log, a line per case with
//! `-v`, nothing with `-q` (whose console after the run, `report::quiet`, is a line per load
//! error and per failed or errored case, then the totals). The runner reports each case-run as
//! it starts and ends; the reports proper are written from the finished run and do not depend
//! on this.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use crate::outcome::{CaseResult, Verdict};

/// How much the run says while it runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Verbosity {
    /// No progress; after the run, the failures and the totals only (`-q`).
    Quiet,
    /// A progress bar on a terminal, a line every [`PLAIN_EVERY`] otherwise.
    #[default]
    Normal,
    /// A line for every case-run with its verdict (`-v`).
    Verbose,
}

/// How often the plain (non-terminal) progress line comes.
const PLAIN_EVERY: Duration = Duration::from_secs(10);

/// What the runner tells as it goes.
pub(crate) trait Progress {
    /// A case-run starts: the `done`th of `total` (0-based).
    fn start(&mut self, profile: &str, id: &str, done: usize, total: usize);
    /// It ended.
    fn end(&mut self, result: &CaseResult);
    /// The run is over.
    fn finish(&mut self) {}
}

/// Shows nothing (library callers, tests, `-q`).
pub(crate) struct Silent;

impl Progress for Silent {
    fn start(&mut self, _: &str, _: &str, _: usize, _: usize) {}
    fn end(&mut self, _: &CaseResult) {}
}

/// The progress of a run on stderr, as `verbosity` and the terminal ask.
pub(crate) fn on_stderr(verbosity: Verbosity) -> Box<dyn Progress> {
    match verbosity {
        Verbosity::Quiet => Box::new(Silent),
        Verbosity::Verbose => Box::new(Lines),
        Verbosity::Normal if std::io::stderr().is_terminal() => Box::new(Bar::default()),
        Verbosity::Normal => Box::new(Plain {
            last: Instant::now(),
        }),
    }
}

/// The bar, made at the first case when the total is known.
#[derive(Default)]
struct Bar(Option<ProgressBar>);

impl Progress for Bar {
    fn start(&mut self, profile: &str, id: &str, done: usize, total: usize) {
        let bar = self.0.get_or_insert_with(|| {
            let b = ProgressBar::new(total as u64);
            if let Ok(style) =
                ProgressStyle::with_template("{bar:30} {pos}/{len} case-runs, {elapsed} [{msg}]")
            {
                b.set_style(style);
            }
            b
        });
        bar.set_position(done as u64);
        bar.set_message(format!("{profile} {id}"));
    }

    fn end(&mut self, _: &CaseResult) {
        if let Some(b) = &self.0 {
            b.inc(1);
        }
    }

    fn finish(&mut self) {
        if let Some(b) = self.0.take() {
            b.finish_and_clear();
        }
    }
}

/// A line every [`PLAIN_EVERY`], for logs.
struct Plain {
    last: Instant,
}

impl Progress for Plain {
    fn start(&mut self, profile: &str, id: &str, done: usize, total: usize) {
        if self.last.elapsed() >= PLAIN_EVERY {
            self.last = Instant::now();
            eprintln!("progress: {done}/{total} case-runs, now {profile} {id}");
        }
    }

    fn end(&mut self, _: &CaseResult) {}
}

/// A line per case-run.
struct Lines;

impl Progress for Lines {
    fn start(&mut self, _: &str, _: &str, _: usize, _: usize) {}

    fn end(&mut self, r: &CaseResult) {
        let why = if r.verdict == Verdict::Pass {
            String::new()
        } else {
            format!(": {}", r.message)
        };
        eprintln!("{:<14} [{}] {}{why}", r.verdict.name(), r.profile, r.id);
    }
}
