//! What a case changed on a persistent device, and putting it back when the case ends: the
//! same for every binding that talks to a device on the network ([`Binding::finish`]).
//!
//! A simulator opened afresh for every case needs none of this. A device on the network is
//! one device for the whole run, so its binding keeps a [`Ledger`] of the values the case
//! wrote, keyed as the bus addresses them (an EtherNet/IP attribute's EPath, an EtherCAT CoE
//! object's index and sub-index):
//!
//! 1. before the first write of a key in the case it reads the value
//!    ([`Ledger::wants_original`], [`Ledger::original`]), and notes a value it could not read
//!    as such;
//! 2. after every write it notes whether the write may have taken effect ([`Ledger::wrote`],
//!    [`may_have_taken_effect`]): a write the device accepted, and one whose answer was lost,
//!    cut off or unreadable, since the device may have carried it out; a refused one did
//!    nothing;
//! 3. at the end of the case it writes back the value before of every key whose write may
//!    have taken effect, in the reverse order of the first writes ([`Ledger::restore`]); a key
//!    whose value before could not be read is reported, not guessed.
//!
//! The restore, and whatever else a binding puts back at the end of a case, runs under an
//! [`Account`]: it stops at the first link error (every further request would only wait out
//! its time-out) and names what it did not attempt.
//!
//! [`Binding::finish`]: crate::binding::Binding::finish

use std::fmt;

use crate::binding::StepError;

/// A key the case wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Written<K> {
    key: K,
    /// Its value before the case's first write, or why it could not be read.
    before: Result<Vec<u8>, String>,
    /// A write was accepted, or went without a readable answer: the value may differ from
    /// `before`.
    changed: bool,
}

/// The values a case wrote on a persistent device, keyed by `K` (`EPath` for EtherNet/IP,
/// `(index, sub-index)` for EtherCAT SDO writes), each with its value before the case's first
/// write of it, in the order of the first writes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Ledger<K> {
    written: Vec<Written<K>>,
}

impl<K> Default for Ledger<K> {
    fn default() -> Ledger<K> {
        Ledger {
            written: Vec::new(),
        }
    }
}

impl<K: PartialEq> Ledger<K> {
    /// Whether the value of `key` must be read before the write about to be made: the first
    /// write of each key in the case.
    pub(crate) fn wants_original(&self, key: &K) -> bool {
        !self.written.iter().any(|w| w.key == *key)
    }

    /// The value of `key` before the case's first write of it, or why it could not be read
    /// (the error text goes into the report if the write then takes effect). A later call for
    /// the same key changes nothing.
    pub(crate) fn original(&mut self, key: K, before: Result<Vec<u8>, String>) {
        if self.wants_original(&key) {
            self.written.push(Written {
                key,
                before,
                changed: false,
            });
        }
    }

    /// A write of `key` was sent; `may_have_taken_effect` as [`may_have_taken_effect`] says.
    /// A later refusal does not undo an earlier change. A key whose original was never noted
    /// is not restored.
    pub(crate) fn wrote(&mut self, key: &K, may_have_taken_effect: bool) {
        if let Some(w) = self.written.iter_mut().find(|w| w.key == *key) {
            w.changed |= may_have_taken_effect;
        }
    }

    /// Whether no key was noted.
    #[allow(dead_code)] // used by tests; a binding may skip its restore with it
    pub(crate) fn is_empty(&self) -> bool {
        self.written.is_empty()
    }

    /// The keys to write back, in the order to write them (the reverse of the first writes),
    /// each with its value before or why there is none; keys whose every write was refused
    /// are left out.
    pub(crate) fn restores(&self) -> impl Iterator<Item = (&K, Result<&[u8], &str>)> {
        self.written
            .iter()
            .rev()
            .filter(|w| w.changed)
            .map(|w| (&w.key, w.before.as_deref().map_err(String::as_str)))
    }

    /// Writes back every key of [`Ledger::restores`] with `put_back(key, value before)`, under
    /// `account`: after a link error the rest is listed as not attempted (`setting back KEY`),
    /// and a key whose value before could not be read is a problem (`KEY was set but its
    /// value before could not be read (WHY)`).
    pub(crate) fn restore(
        &self,
        account: &mut Account,
        mut put_back: impl FnMut(&K, &[u8]) -> Result<(), Problem>,
    ) where
        K: fmt::Display,
    {
        for (key, before) in self.restores() {
            if account.attempt(|| format!("setting back {key}")) {
                let outcome = match before {
                    Ok(before) => put_back(key, before),
                    Err(e) => Err(Problem::other(format!(
                        "{key} was set but its value before could not be read ({e})"
                    ))),
                };
                account.note(outcome);
            }
        }
    }
}

/// Whether a request may have taken effect on the device, given what came of it: `Ok(true)`
/// the device accepted it, `Ok(false)` it refused it (a CIP general status, an SDO abort: it
/// did nothing); an error means it went out and no answer the binding could read came back
/// (none in time, the link cut, a malformed reply), so it may have been carried out — but for
/// a request the binding could not even build (a suite error), which never went out.
pub(crate) fn may_have_taken_effect(outcome: Result<bool, &StepError>) -> bool {
    match outcome {
        Ok(accepted) => accepted,
        Err(StepError::Suite(_)) => false,
        Err(_) => true,
    }
}

/// What one cleanup action could not do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Problem {
    text: String,
    /// The device did not answer or the link broke: nothing more is attempted.
    link: bool,
}

impl Problem {
    /// `e` of a request made for `what`: a link problem for [`StepError::Link`] and for a
    /// device past its limit ([`StepError::Late`]): each further request would wait as long.
    pub(crate) fn step(what: impl fmt::Display, e: StepError) -> Problem {
        Problem {
            link: matches!(
                e,
                StepError::Link(_) | StepError::Closed(_) | StepError::Late { .. }
            ),
            text: format!("{what}: {e}"),
        }
    }

    /// A refusal, or something the cleanup cannot do: the device still answers.
    pub(crate) fn other(text: String) -> Problem {
        Problem { text, link: false }
    }
}

/// The cleanup's account of its actions: the problems, and after the first link error, what
/// was left undone.
#[derive(Debug, Default)]
pub(crate) struct Account {
    problems: Vec<String>,
    /// A link error came: the rest is only listed.
    down: bool,
    undone: Vec<String>,
}

impl Account {
    /// Whether to go on with `what`: not after a link error, when it is listed as undone.
    pub(crate) fn attempt(&mut self, what: impl FnOnce() -> String) -> bool {
        if self.down {
            self.undone.push(what());
        }
        !self.down
    }

    /// The outcome of an action attempted.
    pub(crate) fn note(&mut self, outcome: Result<(), Problem>) {
        if let Err(p) = outcome {
            self.down |= p.link;
            self.problems.push(p.text);
        }
    }

    /// `Ok` without problems; else every problem, then what was not attempted, in one line.
    pub(crate) fn into_result(mut self) -> Result<(), String> {
        if !self.undone.is_empty() {
            self.problems.push(format!(
                "not attempted after the link error: {}",
                self.undone.join(", ")
            ));
        }
        match self.problems.is_empty() {
            true => Ok(()),
            false => Err(self.problems.join("; ")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CoE object entry as EtherCAT keys its SDO writes: index and sub-index.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    struct Entry(u16, u8);

    impl fmt::Display for Entry {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "{:04X}h:{:02X}h", self.0, self.1)
        }
    }

    /// Parameter P`n` of FI 1 (BU 0620 §2.2.7.1: 2000h + 800h·(FI − 1) + P, sub-index 1).
    fn p(n: u16) -> Entry {
        Entry(0x2000 + n, 1)
    }

    #[test]
    fn only_the_first_write_of_a_key_reads_its_value() {
        let mut l = Ledger::default();
        assert!(l.is_empty());
        assert!(l.wants_original(&p(102)));
        l.original(p(102), Ok(vec![0xC8, 0x00]));
        assert!(!l.wants_original(&p(102)));
        assert!(
            l.wants_original(&Entry(0x3066, 1)),
            "another inverter's P102"
        );
        // A second original (a later write) does not replace the first.
        l.original(p(102), Ok(vec![0xE8, 0x03]));
        l.wrote(&p(102), true);
        l.wrote(&p(102), true);
        let r: Vec<_> = l.restores().collect();
        assert_eq!(r, vec![(&p(102), Ok(&[0xC8u8, 0x00][..]))]);
    }

    #[test]
    fn restores_run_in_reverse_order_of_the_first_writes_and_skip_refused_ones() {
        let mut l = Ledger::default();
        for (n, v) in [(102, 1u8), (165, 2), (151, 3), (166, 4)] {
            l.original(p(n), Ok(vec![v, 0]));
        }
        l.wrote(&p(102), true);
        l.wrote(&p(165), true);
        l.wrote(&p(151), false); // refused: the value did not change
        l.wrote(&p(166), true);
        l.wrote(&p(102), false); // a later refusal does not undo the earlier change
        l.wrote(&p(900), true); // never read: not restored
        let order: Vec<u16> = l.restores().map(|(e, _)| e.0 - 0x2000).collect();
        assert_eq!(order, vec![166, 165, 102]);
    }

    #[test]
    fn an_unreadable_original_is_reported_when_the_write_was_accepted() {
        let mut l = Ledger::default();
        l.original(p(900), Err("SDO abort 06020000h".into()));
        assert_eq!(l.restores().count(), 0);
        l.wrote(&p(900), true);
        let r: Vec<_> = l.restores().collect();
        assert_eq!(r, vec![(&p(900), Err("SDO abort 06020000h"))]);
    }

    #[test]
    fn a_lost_answer_may_have_taken_effect_a_refusal_or_a_suite_error_not() {
        assert!(may_have_taken_effect(Ok(true)));
        assert!(!may_have_taken_effect(Ok(false)));
        let lost = StepError::Link("no reply to SDO download".into());
        assert!(may_have_taken_effect(Err(&lost)));
        let garbled = StepError::Protocol("mailbox too short".into());
        assert!(may_have_taken_effect(Err(&garbled)));
        let suite = StepError::Suite("no such parameter".into());
        assert!(!may_have_taken_effect(Err(&suite)));
    }

    #[test]
    fn restore_puts_back_latest_first_and_reports_what_it_could_not() {
        let mut l = Ledger::default();
        l.original(p(102), Ok(vec![1, 0]));
        l.original(p(900), Err("SDO abort 06020000h".into()));
        l.original(p(105), Ok(vec![5, 0]));
        for n in [102, 900, 105] {
            l.wrote(&p(n), true);
        }
        let mut put = Vec::new();
        let mut account = Account::default();
        l.restore(&mut account, |e, v| {
            put.push((*e, v.to_vec()));
            match e.0 {
                0x2069 => Err(Problem::other(format!("{e}: SDO abort 06090030h"))),
                _ => Ok(()),
            }
        });
        assert_eq!(put, vec![(p(105), vec![5, 0]), (p(102), vec![1, 0])]);
        assert_eq!(
            account.into_result().unwrap_err(),
            "2069h:01h: SDO abort 06090030h; 2384h:01h was set but its value before could not \
             be read (SDO abort 06020000h)"
        );
    }

    #[test]
    fn restore_stops_at_the_first_link_error_and_lists_the_rest() {
        let mut l = Ledger::default();
        for n in [102, 103, 104] {
            l.original(p(n), Ok(vec![1, 0]));
            l.wrote(&p(n), true);
        }
        let mut account = Account::default();
        let mut tries = 0;
        l.restore(&mut account, |e, _| {
            tries += 1;
            Err(Problem::step(
                format!("{e} not set back"),
                StepError::Link("no reply".into()),
            ))
        });
        assert_eq!(tries, 1);
        assert!(!account.attempt(|| "leaving Op".into()));
        assert_eq!(
            account.into_result().unwrap_err(),
            "2068h:01h not set back: link error: no reply; not attempted after the link error: \
             setting back 2067h:01h, setting back 2066h:01h, leaving Op"
        );
    }

    #[test]
    fn an_account_without_problems_is_ok() {
        let mut account = Account::default();
        assert!(account.attempt(|| "anything".into()));
        account.note(Ok(()));
        assert_eq!(account.into_result(), Ok(()));
        assert_eq!(Ledger::<Entry>::default().restores().count(), 0);
    }
}
