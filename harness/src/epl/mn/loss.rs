//! The MN's watch over its node's PRes, sans IO: EPSG DS 301's loss-of-PRes error counters of
//! a managing node (§4.7.4.1 threshold counters; objects DLL_MNCNLossPResCumCnt_AU32 1C07h,
//! DLL_MNCNLossPResThrCnt_AU32 1C08h, DLL_MNCNLossPResThreshold_AU32 1C09h). Each lost PRes
//! adds 8 to the node's threshold counter and each cycle with its PRes takes 1 off; when the
//! counter reaches the threshold (default 15; 0 switches the check off) the MN reports
//! E_DLL_LOSS_PRES_TH (8243h) and takes the node out of the cycle. openPOWERLINK's MN counts
//! the same way (the counter +8 per loss, the error at `count >= threshold`).
//!
//! A PRes is lost only when it never comes, not when the host made it late: the MN notes a
//! cycle whose PRes missed its window as *missing* and decides it [`CONFIRM_CYCLES`] cycles
//! later at the earliest, when the caller says ([`Decision`]) from when its PReq left (`T`,
//! the caller's clock): once the time a node on a loaded host may be held back has passed,
//! and then as excused if the host ran late meanwhile (the node shares the host). A PRes of
//! the node that comes after its own window shows that the oldest missing one came after all.
//! Cycles are decided in the order they ran, so the counter moves as DS 301's does.

use std::collections::VecDeque;

/// DS 301's default loss-of-PRes threshold (DLL_MNCNLossPResThreshold_AU32, 1C09h).
pub(crate) const DEFAULT_THRESHOLD: u32 = 15;

/// What a loss adds to the threshold counter, and a good cycle takes off (DS 301 §4.7.4.1:
/// "incremented by 8 … decremented by 1 each cycle without the error").
const STEP_UP: u32 = 8;

/// Cycles after its own that a missing PRes may still come in, late, before it counts as
/// lost: a node delayed by its host for up to this many cycles is late, not silent.
pub(crate) const CONFIRM_CYCLES: u32 = 3;

/// What the caller makes of a PRes still missing, from when its PReq left.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Decision {
    /// Too soon to tell: it may still come.
    Wait,
    /// The host ran late meanwhile: no loss, not counted.
    Excused,
    /// Lost.
    Lost,
}

/// How one cycle's PRes came.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot<T> {
    /// Within its window.
    InTime,
    /// Not within its window: `age` cycles ago, its PReq having left at `sent`.
    Missing { age: u32, sent: T },
    /// After its window (a later PRes of the node showed it).
    Late,
}

/// The threshold counter reached the threshold: what the MN reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Reached {
    /// PRes lost since the counter was last at 0.
    pub(crate) lost: u32,
    /// Cycles decided since then.
    pub(crate) cycles: u32,
    /// The threshold counter (1C08h) when it reached the threshold.
    pub(crate) count: u32,
    /// The threshold (1C09h).
    pub(crate) threshold: u32,
}

/// One node's loss-of-PRes counters and its undecided cycles, each PReq's time `T`.
#[derive(Debug, Clone)]
pub(crate) struct PresWatch<T> {
    threshold: u32,
    /// DLL_MNCNLossPResCumCnt (1C07h): every PRes lost.
    cumulative: u32,
    /// DLL_MNCNLossPResThrCnt (1C08h).
    count: u32,
    /// Since the counter was last at 0: PRes lost, cycles decided.
    run: (u32, u32),
    /// Losses the host excused, late PRes: recorded, not counted.
    excused: u32,
    late: u32,
    open: VecDeque<Slot<T>>,
}

impl<T: Copy> Default for PresWatch<T> {
    fn default() -> PresWatch<T> {
        PresWatch::new(DEFAULT_THRESHOLD)
    }
}

impl<T: Copy> PresWatch<T> {
    pub(crate) fn new(threshold: u32) -> PresWatch<T> {
        PresWatch {
            threshold,
            cumulative: 0,
            count: 0,
            run: (0, 0),
            excused: 0,
            late: 0,
            open: VecDeque::new(),
        }
    }

    /// Notes a cycle whose PRes came within its window, and decides what is due;
    /// `decide(sent)`: the caller's decision on a PRes missing since a PReq left at `sent`.
    pub(crate) fn in_time(&mut self, decide: impl Fn(T) -> Decision) -> Option<Reached> {
        self.open.push_back(Slot::InTime);
        self.decide(decide)
    }

    /// Notes a cycle whose PRes did not come within its window, its PReq having left at
    /// `sent`, and decides what is due.
    pub(crate) fn missing(&mut self, sent: T, decide: impl Fn(T) -> Decision) -> Option<Reached> {
        self.open.push_back(Slot::Missing { age: 0, sent });
        self.decide(decide)
    }

    /// `n` PRes of the node came outside any cycle's window: the oldest missing ones came late.
    pub(crate) fn came_late(&mut self, n: u32) {
        let mut n = n;
        for s in self.open.iter_mut() {
            if n == 0 {
                break;
            }
            if matches!(s, Slot::Missing { .. }) {
                *s = Slot::Late;
                n -= 1;
            }
        }
    }

    /// Forgets the undecided cycles: the node stopped answering PReq on purpose (NMT stop or
    /// reset, the MN's own silence), so a PRes missing now is no loss.
    pub(crate) fn forget(&mut self) {
        self.open.clear();
    }

    /// DLL_MNCNLossPResCumCnt (1C07h).
    pub(crate) fn cumulative(&self) -> u32 {
        self.cumulative
    }

    /// DLL_MNCNLossPResThrCnt (1C08h).
    pub(crate) fn count(&self) -> u32 {
        self.count
    }

    /// PRes that came late, and PRes missing while the host was late: noted, not counted.
    pub(crate) fn uncounted(&self) -> (u32, u32) {
        (self.late, self.excused)
    }

    /// Ages the missing cycles by the one just noted and decides the oldest, in order.
    fn decide(&mut self, decide: impl Fn(T) -> Decision) -> Option<Reached> {
        let n = self.open.len();
        for (i, s) in self.open.iter_mut().enumerate() {
            if let Slot::Missing { age, .. } = s {
                // The cycle just noted is not one after itself.
                if i + 1 < n {
                    *age += 1;
                }
            }
        }
        let mut reached = None;
        while let Some(&s) = self.open.front() {
            match s {
                Slot::Missing { age, .. } if age < CONFIRM_CYCLES => break,
                Slot::Missing { sent, .. } => match decide(sent) {
                    Decision::Wait => break,
                    Decision::Excused => self.excused += 1,
                    Decision::Lost => reached = reached.or(self.lost()),
                },
                Slot::InTime => self.good(),
                Slot::Late => self.late += 1,
            }
            self.open.pop_front();
        }
        reached
    }

    fn good(&mut self) {
        self.count = self.count.saturating_sub(1);
        if self.count == 0 {
            self.run = (0, 0);
        } else {
            self.run.1 += 1;
        }
    }

    fn lost(&mut self) -> Option<Reached> {
        self.cumulative = self.cumulative.saturating_add(1);
        if self.threshold == 0 {
            return None;
        }
        self.count = self.count.saturating_add(STEP_UP);
        self.run.0 += 1;
        self.run.1 += 1;
        if self.count < self.threshold {
            return None;
        }
        let r = Reached {
            lost: self.run.0,
            cycles: self.run.1,
            count: self.count,
            threshold: self.threshold,
        };
        // The MN takes the node out of the cycle and starts it over (openPOWERLINK: ResetNode):
        // its counter starts again from 0.
        self.count = 0;
        self.run = (0, 0);
        Some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs `cycles` ('.' in time, 'x' missing, 'h' missing with the host late since, 'l' a
    /// late PRes after the cycle before) and returns the first threshold reached, with the
    /// cycle it was reported in. A cycle's time is whether the host ran late after it.
    fn run(w: &mut PresWatch<bool>, cycles: &str) -> Option<(usize, Reached)> {
        let late = |host_late: bool| {
            if host_late {
                Decision::Excused
            } else {
                Decision::Lost
            }
        };
        for (i, c) in cycles.chars().enumerate() {
            let r = match c {
                '.' => w.in_time(late),
                'x' => w.missing(false, late),
                'h' => w.missing(true, late),
                'l' => {
                    w.came_late(1);
                    w.in_time(late)
                }
                _ => unreachable!(),
            };
            if let Some(r) = r {
                return Some((i, r));
            }
        }
        None
    }

    #[test]
    fn two_losses_in_a_row_reach_the_default_threshold() {
        // 8, then 16 ≥ 15, decided three cycles after the second loss.
        let mut w = PresWatch::<bool>::default();
        let (at, r) = run(&mut w, "xx....").unwrap();
        assert_eq!(at, 4);
        assert_eq!(
            r,
            Reached {
                lost: 2,
                cycles: 2,
                count: 16,
                threshold: 15
            }
        );
        assert_eq!(w.cumulative(), 2);
        assert_eq!(w.count(), 0, "starts over after reporting");
    }

    #[test]
    fn a_loss_in_three_cycles_reaches_it_at_the_third_as_ds_301_counts() {
        // drop=every:3: 8, 7, 6, 14, 13, 12, 20.
        let mut w = PresWatch::<bool>::default();
        let (at, r) = run(&mut w, "..x..x..x...").unwrap();
        assert_eq!(at, 8 + CONFIRM_CYCLES as usize);
        assert_eq!((r.lost, r.cycles, r.count), (3, 7, 20));
    }

    #[test]
    fn losses_far_apart_are_counted_but_never_reach_it() {
        let mut w = PresWatch::<bool>::default();
        assert_eq!(run(&mut w, &"x........".repeat(20)), None);
        assert_eq!(w.cumulative(), 20);
        assert_eq!(w.count(), 0);
    }

    #[test]
    fn a_pres_that_comes_late_is_no_loss_nor_one_missing_while_the_host_was_late() {
        let mut w = PresWatch::<bool>::default();
        // Each missing PRes comes in the next cycle, after that cycle's own.
        assert_eq!(run(&mut w, &"xl".repeat(20)), None);
        assert_eq!(run(&mut w, &"h".repeat(20)), None);
        assert_eq!(run(&mut w, "...."), None);
        assert_eq!(w.cumulative(), 0);
        assert_eq!(w.uncounted(), (20, 20));
    }

    #[test]
    fn a_missing_pres_waits_while_the_caller_says_it_may_come_and_those_after_it_too() {
        let mut w = PresWatch::<u32>::default();
        // Cycle numbers as times: decided once ten cycles have passed (at cycle 12 and 13).
        let mut now = 0;
        let mut at = None;
        for (i, c) in "xx............".chars().enumerate() {
            now = i as u32;
            let decide = |sent: u32| {
                if now - sent < 10 {
                    Decision::Wait
                } else {
                    Decision::Lost
                }
            };
            let r = if c == 'x' {
                w.missing(now, decide)
            } else {
                w.in_time(decide)
            };
            if r.is_some() && at.is_none() {
                at = Some(i);
                assert_eq!(w.cumulative(), 2);
            }
        }
        assert_eq!((at, now), (Some(11), 13));
        assert_eq!(
            w.count(),
            0,
            "the cycles after decided in order: none left open"
        );
        assert!(w.open.is_empty());
    }

    #[test]
    fn a_threshold_of_0_switches_the_check_off_and_forgotten_cycles_count_nothing() {
        let mut w = PresWatch::<bool>::new(0);
        assert_eq!(run(&mut w, &"x".repeat(10)), None);
        let mut w = PresWatch::<bool>::default();
        assert_eq!(run(&mut w, "xx"), None);
        w.forget();
        assert_eq!(run(&mut w, "......"), None);
        assert_eq!(w.cumulative(), 0);
    }
}
