//! The way back to "Switch-on block" at the end of a case on a persistent device, the same for
//! every bus that carries process data: each inverter the case commanded, and each one in
//! fault, gets "disable voltage" (0400h), and a fault the bus acknowledgement — control bit 7
//! from 0 to 1, "with the switch from 0 to 1, inactive errors are acknowledged" (BU 0620 §5.2
//! and §6.1.2.1) — until it shows xx40h without a fault. The bus's binding runs the cycles.

use std::time::Duration;

use proto::nord::control::ControlWord;
use proto::nord::status::StatusWord;
use proto::nord::Inverter;

use super::channel::{compact, cycles_left_out};
use crate::binding::ledger::Problem;
use crate::outcome::Exchange;

/// "Control data valid" (bit 10) and nothing else: "disable voltage" (bit 1 = 0), the output
/// off at once, "Switch-on block" (BU 0620 §6.1.2.1).
pub(crate) const DISABLE: u16 = 1 << ControlWord::CONTROL_DATA_VALID;
/// [`DISABLE`] with bit 7 "acknowledge the error": its rising edge acknowledges a fault.
const ACKNOWLEDGE: u16 = DISABLE | 1 << ControlWord::ACKNOWLEDGE;
/// Status bit 3 "Fault" (set in "Error reaction active" too).
const FAULT: u16 = 1 << StatusWord::FAULT;
/// Bound on the cycles of the way back (1 s at EtherNet/IP's 4 ms RPI; 250 ms at EtherCAT's
/// 1 ms cycle, longer than any ramp the cases leave running would need to be cut).
pub(crate) const SETTLE_CYCLES: u32 = 250;
/// Cycles each half of the acknowledgement edge is held (0400h, then 0480h).
const ACK_HOLD: u32 = 3;
/// Cycles in a row an inverter must show xx40h to 0400h before it counts as settled (the inputs
/// may lag the outputs by a cycle).
const CALM: u8 = 2;
/// One inverter's way back to "Switch-on block" at the end of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Settle {
    /// The case commanded it, or it showed a fault: it gets valid control words. The others
    /// get what the case sent them, 0000h (not evaluated, bit 10 clear).
    involved: bool,
    /// Its latest status word.
    status: Option<u16>,
    /// The control word sent last.
    last: u16,
    /// Status words in a row showing xx40h while 0400h is sent.
    calm: u8,
}

impl Settle {
    /// An inverter the case commanded (`true`) or not.
    pub(crate) fn new(commanded: bool) -> Settle {
        Settle {
            involved: commanded,
            status: None,
            last: 0,
            calm: 0,
        }
    }

    /// Takes the status word the inverter answered.
    pub(crate) fn observe(&mut self, status: u16) {
        self.status = Some(status);
        if status & FAULT != 0 {
            self.involved = true;
            self.calm = 0;
        } else if self.involved
            && self.last == DISABLE
            && StatusWord(status).switch_on_block_disabled()
        {
            self.calm = self.calm.saturating_add(1);
        } else {
            self.calm = 0;
        }
    }

    /// The control word for cleanup cycle `n`: 0400h, alternating with 0480h while a fault
    /// shows (each change to 0480h is a rising edge of bit 7).
    pub(crate) fn control(&mut self, n: u32) -> u16 {
        let faulted = self.status.is_some_and(|s| s & FAULT != 0);
        self.last = match (self.involved, faulted) {
            (false, _) => 0,
            (true, true) if (n / ACK_HOLD) % 2 == 1 => ACKNOWLEDGE,
            (true, _) => DISABLE,
        };
        self.last
    }

    /// Whether the inverter is as the next case expects it: seen, and, if it needed anything,
    /// in "Switch-on block" without a fault under 0400h.
    pub(crate) fn done(&self) -> bool {
        self.status.is_some() && (!self.involved || self.calm >= CALM)
    }
}

/// What a bus's master or managing node offers for running process data: the cycle with
/// its transcript, the output words and the status words.
pub(crate) trait Cycling {
    /// The bus's error.
    type Error;
    /// Runs `n` cycles.
    fn run_cycles(&mut self, n: u64) -> Result<(), Self::Error>;
    /// The exchanges recorded since the last call.
    fn take_exchanges(&mut self) -> Vec<Exchange>;
    /// Records exchanges from now on, or not.
    fn set_recording(&mut self, on: bool);
    /// Sets FI `fi`'s six output words (control word, setpoints 1..5) for the next cycles.
    fn set_words(&mut self, fi: Inverter, words: [u16; 6]) -> Result<(), Self::Error>;
    /// FI `fi`'s status word, as the last cycle brought it.
    fn status_word(&mut self, fi: Inverter) -> Result<u16, Self::Error>;
}

/// Runs `n` cycles of `c`; the transcript (`pending`, the exchanges taken so far) keeps the
/// first two and the last, and the cycles between are not even recorded.
pub(crate) fn run_cycles<C: Cycling>(
    c: &mut C,
    pending: &mut Vec<Exchange>,
    n: u64,
) -> Result<(), C::Error> {
    const HEAD: u64 = 2;
    c.run_cycles(n.min(HEAD))?;
    let middle = n.saturating_sub(HEAD + 1);
    if middle > 0 {
        pending.extend(c.take_exchanges());
        c.set_recording(false);
        let r = c.run_cycles(middle);
        c.set_recording(true);
        r?;
        pending.push(cycles_left_out(middle));
    }
    if n > HEAD {
        c.run_cycles(1)?;
    }
    Ok(())
}

/// A cycle that runs on a clock of its own (the segment's, the link's): a step "for" a time
/// runs cycles until that time has passed on it.
pub(crate) trait Clocked: Cycling {
    /// The clock's time now.
    fn now(&self) -> Duration;
    /// Runs cycles one period apart until `end` on the clock; returns how many ran. A run
    /// behind its schedule (slow round trips, a loaded host) ends on time with fewer cycles:
    /// the time stands for what the drive model runs on, not a number of cycles.
    fn run_cycles_until(&mut self, end: Duration) -> Result<u64, Self::Error>;
}

/// Runs cycles of `c` for `d` on its clock and one more, the transcript compacted as
/// [`run_cycles`] compacts it: the first two cycles, the number left out, the last.
pub(crate) fn run_cycles_for<C: Clocked>(
    c: &mut C,
    pending: &mut Vec<Exchange>,
    d: Duration,
) -> Result<(), C::Error> {
    let end = c.now() + d;
    c.run_cycles(2)?;
    pending.extend(c.take_exchanges());
    c.set_recording(false);
    let middle = c.run_cycles_until(end);
    c.set_recording(true);
    match middle? {
        0 => {}
        n => pending.push(cycles_left_out(n)),
    }
    c.run_cycles(1)
}

/// Every inverter of a device on its way back.
#[derive(Debug, Clone)]
pub(crate) struct Drives {
    fis: Vec<(Inverter, Settle)>,
}

impl Drives {
    /// FI 1..=`inverters`; `commanded` are those the case sent control words.
    pub(crate) fn new(inverters: u8, commanded: &[Inverter]) -> Drives {
        Drives {
            fis: (1..=inverters)
                .filter_map(|n| Inverter::new(n.into()).ok())
                .map(|fi| (fi, Settle::new(commanded.contains(&fi))))
                .collect(),
        }
    }

    /// Only the inverters `commanded` (a bus that carries no others' process data).
    pub(crate) fn only(commanded: &[Inverter]) -> Drives {
        Drives {
            fis: commanded
                .iter()
                .map(|fi| (*fi, Settle::new(true)))
                .collect(),
        }
    }

    /// The control word of each inverter for cycle `n`.
    pub(crate) fn controls(&mut self, n: u32) -> Vec<(Inverter, u16)> {
        self.fis
            .iter_mut()
            .map(|(fi, s)| (*fi, s.control(n)))
            .collect()
    }

    /// The status word `fi` answered.
    pub(crate) fn observe(&mut self, fi: Inverter, status: u16) {
        if let Some((_, s)) = self.fis.iter_mut().find(|(f, _)| *f == fi) {
            s.observe(status);
        }
    }

    /// The inverters, to read their status words.
    pub(crate) fn inverters(&self) -> Vec<Inverter> {
        self.fis.iter().map(|(fi, _)| *fi).collect()
    }

    /// Whether every inverter is as the next case expects it.
    pub(crate) fn done(&self) -> bool {
        self.fis.iter().all(|(_, s)| s.done())
    }

    /// Cycles `c` until every inverter is back ([`Settle`]), [`SETTLE_CYCLES`] of `period` at
    /// most; the exchanges go to `pending`, compacted. `what` names a bus error as the
    /// cleanup's problem.
    pub(crate) fn settle<C: Cycling>(
        &mut self,
        c: &mut C,
        pending: &mut Vec<Exchange>,
        period: Duration,
        what: impl Fn(C::Error) -> Problem,
    ) -> Result<(), Problem> {
        pending.extend(c.take_exchanges());
        let from = pending.len();
        for n in 0..SETTLE_CYCLES {
            for (fi, control) in self.controls(n) {
                let mut words = [0; 6];
                words[0] = control;
                c.set_words(fi, words).map_err(&what)?;
            }
            c.run_cycles(1).map_err(&what)?;
            for fi in self.inverters() {
                let status = c.status_word(fi).map_err(&what)?;
                self.observe(fi, status);
            }
            if self.done() {
                break;
            }
        }
        let outcome = if self.done() {
            Ok(())
        } else {
            Err(self.stuck(period * SETTLE_CYCLES))
        };
        pending.extend(c.take_exchanges());
        compact(pending, from);
        outcome
    }

    /// The problem of drives that did not settle within `waited`.
    pub(crate) fn stuck(&self, waited: Duration) -> Problem {
        let stuck: Vec<String> = self
            .fis
            .iter()
            .filter(|(_, s)| !s.done())
            .map(|(fi, s)| match s.status {
                Some(w) => format!("{fi} status {w:04X}h"),
                None => format!("{fi} no status word"),
            })
            .collect();
        Problem::other(format!(
            "the drive did not return to 'Switch-on block' (xx40h, no fault) within {waited:?}: {}",
            stuck.join(", ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs `s` against statuses the drive answers, one per cycle; returns the controls sent.
    fn drive(s: &mut Settle, answers: &[u16]) -> Vec<u16> {
        let mut sent = Vec::new();
        for (n, a) in (0..).zip(answers) {
            sent.push(s.control(n));
            s.observe(*a);
        }
        sent
    }

    #[test]
    fn an_inverter_the_case_did_not_touch_gets_what_it_got_and_is_left_alone() {
        let mut s = Settle::new(false);
        assert!(!s.done(), "not seen yet");
        // Ready for switch-on (xx31h): not the cleanup's business when the case never sent it
        // a control word.
        assert_eq!(drive(&mut s, &[0x0B31]), vec![0]);
        assert!(s.done());
    }

    #[test]
    fn a_commanded_inverter_gets_0400h_until_it_shows_xx40h_twice() {
        let mut s = Settle::new(true);
        // Operation enabled, then (one cycle late) switch-on block.
        let sent = drive(&mut s, &[0x0337, 0x0B40]);
        assert_eq!(sent, vec![DISABLE, DISABLE]);
        assert!(!s.done());
        drive(&mut s, &[0x0B40]);
        assert!(s.done());
    }

    #[test]
    fn switch_on_block_with_a_command_bit_shown_is_not_yet_settled() {
        // xx60h: switch-on block, status bit 5 from the last evaluated control word.
        let mut s = Settle::new(true);
        drive(&mut s, &[0x0B60, 0x0B60, 0x0B60]);
        assert!(!s.done());
    }

    #[test]
    fn a_fault_is_acknowledged_by_a_rising_edge_of_bit_7_and_ends_under_0400h() {
        let mut s = Settle::new(false);
        // Fault (xx08h) for a while: 0400h and 0480h alternate, ACK_HOLD cycles each.
        let sent = drive(&mut s, &[0x0208; 8]);
        assert_eq!(
            sent,
            vec![
                0,
                DISABLE,
                DISABLE,
                ACKNOWLEDGE,
                ACKNOWLEDGE,
                ACKNOWLEDGE,
                DISABLE,
                DISABLE
            ]
        );
        assert!(s.involved && !s.done());
        // Still in fault at cycle 8 (0400h); acknowledged by the 0480h edge of cycle 9:
        // switch-on block (xx40h), and 0400h from then on until it shows so twice.
        let answers = [(0x0208, DISABLE), (0x0240, ACKNOWLEDGE), (0x0240, DISABLE)];
        for (n, (answer, control)) in (8..).zip(answers) {
            assert_eq!(s.control(n), control, "cycle {n}");
            s.observe(answer);
            assert!(
                !s.done(),
                "cycle {n}: the words sent so far end with bit 7 or a fault"
            );
        }
        assert_eq!(s.control(11), DISABLE);
        s.observe(0x0240);
        assert!(s.done());
    }

    #[test]
    fn the_control_words_are_the_manuals() {
        // Bit 10 "control data valid" alone, then with bit 7 "acknowledge" (BU 0620 §6.1.2.1).
        assert_eq!(DISABLE, 0x0400);
        assert_eq!(ACKNOWLEDGE, 0x0480);
        assert_eq!(FAULT, 0x0008);
    }

    #[test]
    fn the_way_back_never_sends_a_word_that_can_turn_a_motor() {
        // The cleanup runs against a DUT without `--allow-motion` too.
        assert_eq!(crate::effect::control_word(DISABLE), None);
        assert_eq!(crate::effect::control_word(ACKNOWLEDGE), None);
    }
}
