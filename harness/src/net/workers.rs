//! The threads that serve a simulated device on a network interface (`harness serve <bus>`):
//! started together, one ending ends the others (a device half served is not served), and
//! stopped and joined when their handle asks or goes.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

/// The serving threads of one device, each returning `Ok` or the error `E` it stopped on.
#[derive(Debug)]
pub(crate) struct Workers<E> {
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<Result<(), E>>>,
}

impl<E: Send + 'static> Workers<E> {
    /// No threads yet.
    pub(crate) fn new() -> Workers<E> {
        Workers {
            stop: Arc::new(AtomicBool::new(false)),
            threads: Vec::new(),
        }
    }

    /// The flag every thread looks at between waits: set, they return.
    pub(crate) fn stop_flag(&self) -> Arc<AtomicBool> {
        self.stop.clone()
    }

    /// Starts `f` in a thread called `name`; when it returns, the flag stops the others.
    pub(crate) fn spawn(
        &mut self,
        name: String,
        f: impl FnOnce() -> Result<(), E> + Send + 'static,
    ) -> std::io::Result<()> {
        let stop = self.stop.clone();
        let t = thread::Builder::new().name(name).spawn(move || {
            let r = f();
            stop.store(true, Ordering::Relaxed);
            r
        })?;
        self.threads.push(t);
        Ok(())
    }

    /// Whether every thread still serves.
    pub(crate) fn is_running(&self) -> bool {
        !self.threads.is_empty() && self.threads.iter().all(|t| !t.is_finished())
    }

    /// Stops the threads and waits for them: the first error one stopped on, or the message
    /// of one that panicked (a bug) made an `E` by `panicked`.
    pub(crate) fn join(&mut self, panicked: impl Fn(String) -> E) -> Result<(), E> {
        self.stop.store(true, Ordering::Relaxed);
        let mut result = Ok(());
        for t in self.threads.drain(..) {
            let r = t.join().unwrap_or_else(|p| {
                let why = p
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| p.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                Err(panicked(why))
            });
            if result.is_ok() {
                result = r;
            }
        }
        result
    }
}

/// Returns once `duration` has passed (never when `None`) or `running` says the device
/// stopped serving, looking every `check`.
pub(crate) fn serve_for(duration: Option<Duration>, check: Duration, running: impl Fn() -> bool) {
    let end = duration.map(|d| Instant::now() + d);
    while running() && end.is_none_or(|e| Instant::now() < e) {
        let left = end.map_or(check, |e| e.saturating_duration_since(Instant::now()));
        thread::sleep(left.min(check));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_thread_ending_stops_the_others_and_its_error_comes_back() {
        let mut w: Workers<String> = Workers::new();
        let stop = w.stop_flag();
        w.spawn("waits".into(), move || {
            while !stop.load(Ordering::Relaxed) {
                thread::sleep(Duration::from_millis(1));
            }
            Ok(())
        })
        .unwrap();
        w.spawn("fails".into(), || Err("link down".to_string()))
            .unwrap();
        serve_for(
            Some(Duration::from_secs(5)),
            Duration::from_millis(5),
            || w.is_running(),
        );
        assert!(!w.is_running());
        assert_eq!(
            w.join(|p| format!("panicked: {p}")),
            Err("link down".into())
        );
    }

    #[test]
    fn a_panic_is_an_error_naming_it() {
        let mut w: Workers<String> = Workers::new();
        w.spawn("panics".into(), || panic!("a bug")).unwrap();
        assert_eq!(
            w.join(|p| format!("panicked: {p}")),
            Err("panicked: a bug".into())
        );
    }
}
