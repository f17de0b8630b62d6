//! Process data: SyncManagers 2/3 and two FMMUs per slave map its outputs and inputs into one
//! logical process image, which one LRW datagram exchanges per cycle (ETG.1000.4 §5.4.3,
//! §6.6–§6.7).
//!
//! The image is all outputs first, then all inputs. An LRW through a slave with both adds 3 to
//! the working counter (read + 2 × write, ETG.1000.4 table 14): 3 for the SK 550P.
//! Per inverter the SK 550P maps 12 bytes each way (BU 0620 §2.2.6.1): control word and
//! setpoints 1–5 out, status word and actual values 1–5 in, 16-bit little-endian words in
//! that order ([`proto::nord::ecat::WORDS_PER_INVERTER`]).

use std::time::Duration;

use proto::ecat::register::{self, fmmu_type, FmmuRepr, SmRepr};
use proto::ecat::sii::SmType;
use proto::nord::ecat::{BYTES_PER_INVERTER, WORDS_PER_INVERTER};

use super::engine::{Master, ProcessSetup, SmSetup};
use super::error::{Result, UsageError};
use super::port::check_wkc;
use super::segment::Segment;
use super::wire;
use proto::ecat::{Command, DatagramRepr};

/// Counters of the cyclic exchange.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct CyclicStats {
    /// Cycles exchanged (with any working counter).
    pub(crate) cycles: u64,
    /// Cycles whose working counter was not the expected one.
    pub(crate) wkc_errors: u64,
    /// Cycles whose frame did not come back (timeout, malformed, link error).
    pub(crate) lost: u64,
    /// The last working counter seen.
    pub(crate) last_wkc: u16,
}

/// The process image and the cycle's timing.
#[derive(Debug, Clone, Default)]
pub(crate) struct Cyclic {
    running: bool,
    next: Duration,
    outputs: Vec<u8>,
    inputs: Vec<u8>,
    expected_wkc: u16,
    stats: CyclicStats,
}

impl Cyclic {
    /// When the next cycle is due while the cycle runs.
    pub(super) fn due(&self) -> Option<Duration> {
        self.running.then_some(self.next)
    }
}

/// The register block of a SyncManager the master configures (enabled unless its length is 0).
pub(super) fn sm_block(sm: SmSetup) -> [u8; 8] {
    let mut r = SmRepr::enabled(sm.start, sm.len, sm.control);
    r.activate = u8::from(sm.len > 0);
    r.emit()
}

/// The byte offset of word `word` (0 = control/status word, 1..=5 values) of FI `inverter`
/// (1..=8) within a slave's process data, if both are in range.
fn word_offset(inverter: u8, word: u8) -> Option<usize> {
    (1..=8).contains(&inverter).then_some(())?;
    (word < WORDS_PER_INVERTER).then_some(())?;
    Some(usize::from(inverter - 1) * usize::from(BYTES_PER_INVERTER) + 2 * usize::from(word))
}

impl<S: Segment> Master<S> {
    /// Configures SM2/SM3 (from the SII's SyncM category) and FMMU 0 (outputs, write) and
    /// FMMU 1 (inputs, read) of `station`, and places its data in the process image.
    pub(crate) fn configure_process_data(&mut self, station: u16) -> Result<ProcessSetup> {
        let slave = self
            .slave(station)
            .ok_or(UsageError::NoSuchSlave { station })?
            .clone();
        let find = |kind: SmType| {
            slave.sync_manager(kind).map_or(
                SmSetup {
                    start: 0,
                    len: 0,
                    control: 0,
                },
                |s| SmSetup {
                    start: s.start,
                    len: s.length,
                    control: s.control,
                },
            )
        };
        let (outputs, inputs) = (find(SmType::OUTPUTS), find(SmType::INPUTS));
        // Other slaves keep their place; this one goes after them (or where it was).
        let (out_offset, in_offset) = match slave.process {
            Some(p) if p.outputs.len == outputs.len && p.inputs.len == inputs.len => {
                (p.out_offset, p.in_offset)
            }
            _ => (self.cyclic.outputs.len(), self.cyclic.inputs.len()),
        };
        let setup = ProcessSetup {
            outputs,
            inputs,
            out_offset,
            in_offset,
        };
        let sms: Vec<u8> = [outputs, inputs]
            .iter()
            .flat_map(|sm| sm_block(*sm))
            .collect();
        self.write_register(station, register::sm(2), &sms)?;
        let out_len = (out_offset + usize::from(outputs.len)).max(self.cyclic.outputs.len());
        let in_len = (in_offset + usize::from(inputs.len)).max(self.cyclic.inputs.len());
        let base = self.config.logical_base;
        let fmmus: Vec<u8> = [
            (base + out_offset as u32, outputs, fmmu_type::WRITE),
            (base + (out_len + in_offset) as u32, inputs, fmmu_type::READ),
        ]
        .iter()
        .flat_map(|(log, sm, kind)| {
            let mut f = FmmuRepr::bytes(*log, sm.len, sm.start, *kind);
            f.activate = u8::from(sm.len > 0);
            f.emit()
        })
        .collect();
        self.write_register(station, register::fmmu(0), &fmmus)?;
        if let Some(s) = self.slave_mut(station) {
            s.process = Some(setup);
        }
        self.cyclic.outputs.resize(out_len, 0);
        self.cyclic.inputs.resize(in_len, 0);
        self.cyclic.expected_wkc = self
            .slaves
            .iter()
            .filter_map(|s| s.process)
            .map(|p| 2 * u16::from(p.outputs.len > 0) + u16::from(p.inputs.len > 0))
            .sum();
        Ok(setup)
    }

    /// The working counter a cycle must come back with.
    #[cfg(test)]
    pub(crate) fn expected_wkc(&self) -> u16 {
        self.cyclic.expected_wkc
    }

    /// One cycle now: the LRW of the whole image; the inputs are taken over whatever the
    /// working counter. A working counter other than the expected one is an error (0: no slave).
    pub(crate) fn cycle(&mut self) -> Result<u16> {
        let out_len = self.cyclic.outputs.len();
        let mut data = self.cyclic.outputs.clone();
        data.resize(out_len + self.cyclic.inputs.len(), 0);
        let d = DatagramRepr::logical(Command::LRW, 0, self.config.logical_base, data);
        let access = wire::Access::of(&d);
        let now = self.now();
        self.cyclic.next = now + self.config.cycle;
        let r = match self.port.one(d) {
            Ok(r) => r,
            Err(e) => {
                self.cyclic.stats.lost += 1;
                return Err(e);
            }
        };
        self.cyclic.stats.cycles += 1;
        self.cyclic.stats.last_wkc = r.wkc;
        if let Some(i) = r.data.get(out_len..) {
            let n = i.len().min(self.cyclic.inputs.len());
            self.cyclic.inputs[..n].copy_from_slice(&i[..n]);
        }
        if r.wkc != self.cyclic.expected_wkc {
            self.cyclic.stats.wkc_errors += 1;
        }
        check_wkc(access, &r, self.cyclic.expected_wkc)?;
        Ok(r.wkc)
    }

    /// A cycle while the master waits for something else: not recorded, errors counted.
    pub(super) fn background_cycle(&mut self) {
        let was = self.port.recorder.is_on();
        self.port.recorder.set_on(false);
        let _ = self.cycle();
        self.port.recorder.set_on(was);
    }

    /// Starts the cycle: from now on every wait of the master keeps exchanging the image
    /// every [`super::MasterConfig::cycle`].
    pub(crate) fn start_cycling(&mut self) {
        if !self.cyclic.running {
            self.cyclic.running = true;
            self.cyclic.next = self.now();
        }
    }

    /// Stops the cycle (the slave's SM watchdog will notice).
    pub(crate) fn stop_cycling(&mut self) {
        self.cyclic.running = false;
    }

    /// Whether the cycle runs.
    pub(crate) fn is_cycling(&self) -> bool {
        self.cyclic.running
    }

    /// Runs `n` cycles one period apart (recorded), the first when the cycle is next due
    /// (at once when it is not running), each a period after the start of the one before
    /// (not after its end: the round trip must not stretch the period); the first error ends
    /// them.
    pub(crate) fn run_cycles(&mut self, n: u64) -> Result<()> {
        let mut due = self.cyclic.next.max(self.now());
        for i in 0..n {
            if i > 0 {
                due += self.config.cycle;
            }
            self.port.wait_until(due);
            self.cycle()?;
        }
        Ok(())
    }

    /// Runs cycles one period apart, as [`Master::run_cycles`], until `end` on the segment's
    /// clock; returns how many ran. A run behind its schedule (slow round trips, a loaded
    /// host) ends on time with fewer cycles: a step "for" a time stands for that time, which
    /// the slave's drive model runs on, not for a number of cycles.
    pub(crate) fn run_cycles_until(&mut self, end: Duration) -> Result<u64> {
        let mut due = self.cyclic.next.max(self.now());
        let mut n = 0;
        while due < end && self.now() < end {
            self.port.wait_until(due);
            self.cycle()?;
            n += 1;
            due += self.config.cycle;
        }
        Ok(n)
    }

    /// Runs the cycle for `time` (not recorded); returns the counters of those cycles.
    #[cfg(test)]
    pub(crate) fn run_for(&mut self, time: Duration) -> CyclicStats {
        let before = self.cyclic.stats;
        let was = self.cyclic.running;
        self.start_cycling();
        self.idle(time);
        self.cyclic.running = was;
        let after = self.cyclic.stats;
        CyclicStats {
            cycles: after.cycles - before.cycles,
            wkc_errors: after.wkc_errors - before.wkc_errors,
            lost: after.lost - before.lost,
            last_wkc: after.last_wkc,
        }
    }

    /// Counters since the master started.
    pub(crate) fn cyclic_stats(&self) -> CyclicStats {
        self.cyclic.stats
    }

    /// The input part of the image as of the last cycle.
    pub(crate) fn inputs(&self) -> &[u8] {
        &self.cyclic.inputs
    }

    /// Sets output word `word` (0 control word, 1..=5 setpoints) of FI `inverter` of the slave
    /// `station`. Errors when the slave has no process data or the word is out of range.
    pub(crate) fn set_output_word(
        &mut self,
        station: u16,
        inverter: u8,
        word: u8,
        value: u16,
    ) -> Result<()> {
        let at = self.word_at(station, inverter, word, true)?;
        self.cyclic.outputs[at..at + 2].copy_from_slice(&value.to_le_bytes());
        Ok(())
    }

    /// Input word `word` (0 status word, 1..=5 actual values) of FI `inverter` of `station`
    /// as of the last cycle.
    pub(crate) fn input_word(&self, station: u16, inverter: u8, word: u8) -> Result<u16> {
        let at = self.word_at(station, inverter, word, false)?;
        Ok(u16::from_le_bytes([
            self.cyclic.inputs[at],
            self.cyclic.inputs[at + 1],
        ]))
    }

    /// Control word and setpoints 1–5 of FI `inverter` at once.
    pub(crate) fn set_inverter_outputs(
        &mut self,
        station: u16,
        inverter: u8,
        words: [u16; 6],
    ) -> Result<()> {
        for (w, v) in words.iter().enumerate() {
            self.set_output_word(station, inverter, w as u8, *v)?;
        }
        Ok(())
    }

    /// Status word and actual values 1–5 of FI `inverter`.
    pub(crate) fn inverter_inputs(&self, station: u16, inverter: u8) -> Result<[u16; 6]> {
        let mut out = [0; 6];
        for (w, v) in out.iter_mut().enumerate() {
            *v = self.input_word(station, inverter, w as u8)?;
        }
        Ok(out)
    }

    fn word_at(&self, station: u16, inverter: u8, word: u8, output: bool) -> Result<usize> {
        let p = self
            .slave(station)
            .and_then(|s| s.process)
            .ok_or(UsageError::NoProcessData { station })?;
        let (sm, base) = if output {
            (p.outputs, p.out_offset)
        } else {
            (p.inputs, p.in_offset)
        };
        let at = word_offset(inverter, word)
            .filter(|a| a + 2 <= usize::from(sm.len))
            .ok_or(UsageError::NoSuchWord { inverter, word })?;
        Ok(base + at)
    }
}
