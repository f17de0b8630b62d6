//! The master: its configuration, what it knows of each slave, register access and the waiting
//! that keeps the process data running. The other files of the module add the scan, the SII,
//! the AL states, the mailbox, CoE SDO and the process data as further `impl` blocks.
//!
//! Blocking calls over a [`Segment`]: the protocol logic reads no clock but the segment's and
//! sleeps through the segment, so the same master runs instantly on the embedded segment's
//! virtual clock and in real time on a network. Every wait for the slave is its limit
//! ([`crate::net::wait::Wait`]: on the real clock moved by the time the host lost meanwhile);
//! every polling loop lets at least [`MasterConfig::poll_interval`] pass per round, so no loop
//! outlives its limit on either clock. A limit that passes is [`LinkFailure::Timeout`] with
//! the limit and the time waited, which the binding reports as the slave being late.

use std::time::Duration;

use super::error::{Awaited, LinkFailure, MasterError, Result};
use super::pdo::Cyclic;
use super::port::Port;
#[cfg(test)]
use super::port::PortStats;
use super::segment::Segment;
use super::wire;
use crate::outcome::Exchange;
use proto::ecat::coe::Emergency;
use proto::ecat::sii::{SiiRepr, SiiSm, SmType};
use proto::ecat::{Command, DatagramRepr};

/// How the master works; the defaults suit a network segment (1 ms cycle). The limits of the
/// AL state changes are the transitions' own (`super::al`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct MasterConfig {
    /// How long a frame may take to come back: a harness limit (ETG.1000 prints none; an ESC
    /// forwards a frame within microseconds, a slave served by a process on a shared host
    /// within a few milliseconds).
    pub(crate) frame_timeout: Duration,
    /// How long a mailbox message may wait for room in the receive mailbox (SM0): the ESI's
    /// `Mailbox/Timeout/RequestTimeout`, 100 ms by ETG.2000's default (BU 0620 prints none).
    pub(crate) mailbox_request: Duration,
    /// How long the reply may take to show in the send mailbox (SM1): the ESI's
    /// `Mailbox/Timeout/ResponseTimeout`, 2000 ms by ETG.2000's default.
    pub(crate) mailbox_response: Duration,
    /// How long the SII EEPROM interface may stay busy: a harness limit (ETG.1000.4 prints
    /// none; an EEPROM read of 8 bytes takes well under a millisecond).
    pub(crate) eeprom_timeout: Duration,
    /// Pause between two polls of a register.
    pub(crate) poll_interval: Duration,
    /// Process data cycle.
    pub(crate) cycle: Duration,
    /// Configured station address of the first slave; the next ones count up (0010h).
    pub(crate) station_base: u16,
    /// Logical address of the process image.
    pub(crate) logical_base: u32,
}

impl Default for MasterConfig {
    fn default() -> Self {
        MasterConfig {
            frame_timeout: Duration::from_millis(50),
            mailbox_request: Duration::from_millis(100),
            mailbox_response: Duration::from_secs(2),
            eeprom_timeout: Duration::from_millis(100),
            poll_interval: Duration::from_micros(200),
            cycle: Duration::from_millis(1),
            station_base: 0x1001,
            logical_base: 0x0001_0000,
        }
    }
}

/// The ESC's identification registers 0000h–0009h and the alias (0012h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct EscInfo {
    /// Type (0000h).
    pub(crate) kind: u8,
    /// Revision (0001h).
    pub(crate) revision: u8,
    /// Build (0002h).
    pub(crate) build: u16,
    /// FMMUs supported (0004h).
    pub(crate) fmmus: u8,
    /// SyncManagers supported (0005h).
    pub(crate) sync_managers: u8,
    /// Process RAM in KiB (0006h).
    pub(crate) ram_kib: u8,
    /// Port descriptor (0007h).
    pub(crate) ports: u8,
    /// Features supported (0008h).
    pub(crate) features: u16,
    /// Configured station alias (0012h).
    pub(crate) alias: u16,
}

/// A SyncManager as the master configures it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SmSetup {
    /// Physical start address.
    pub(crate) start: u16,
    /// Length.
    pub(crate) len: u16,
    /// Control byte.
    pub(crate) control: u8,
}

/// Where a slave's process data sits in the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ProcessSetup {
    /// SM2, the outputs (none with length 0).
    pub(crate) outputs: SmSetup,
    /// SM3, the inputs.
    pub(crate) inputs: SmSetup,
    /// Offset of the outputs in the image's output part.
    pub(crate) out_offset: usize,
    /// Offset of the inputs in the image's input part.
    pub(crate) in_offset: usize,
}

/// What the master knows of one slave.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SlaveInfo {
    /// Position on the segment, 0 first.
    pub(crate) position: u16,
    /// Configured station address (0010h).
    pub(crate) station: u16,
    /// ESC identification.
    pub(crate) esc: EscInfo,
    /// The SII contents (identity, mailbox, SyncManagers, PDOs).
    pub(crate) sii: SiiRepr,
    /// The SII image as read (header and categories up to the end marker).
    pub(crate) sii_raw: Vec<u8>,
    /// Mailbox SyncManagers (SM0 receive, SM1 send) once configured.
    pub(crate) mailbox: Option<(SmSetup, SmSetup)>,
    /// Process data once configured.
    pub(crate) process: Option<ProcessSetup>,
    /// The master's mailbox counter, 1..7 (0 before the first message).
    pub(crate) counter: u8,
    /// The counter of the last message read from the slave's send mailbox (`None`: none
    /// since its mailbox started): one that comes again is a repeat (ETG.1000.6 §5.6).
    pub(crate) received: Option<u8>,
}

impl SlaveInfo {
    /// Vendor ID (SII word 08h).
    pub(crate) fn vendor(&self) -> u32 {
        self.sii.header.vendor_id
    }

    /// Product code (SII word 0Ah).
    pub(crate) fn product(&self) -> u32 {
        self.sii.header.product_code
    }

    /// The device name: the general category's name string.
    pub(crate) fn name(&self) -> Option<&str> {
        self.sii.general().and_then(|g| self.sii.string(g.name))
    }

    /// Whether the SII gives a standard mailbox (both sizes not 0).
    pub(crate) fn has_mailbox(&self) -> bool {
        let m = self.sii.header.standard_mailbox;
        m.rx_size > 0 && m.tx_size > 0
    }

    /// The first SyncManager of the SII's SyncM category used as `kind`.
    pub(crate) fn sync_manager(&self, kind: SmType) -> Option<&SiiSm> {
        self.sii.sync_managers().iter().find(|s| s.kind == kind)
    }
}

/// The EtherCAT master over a segment.
#[derive(Debug)]
pub(crate) struct Master<S> {
    pub(super) port: Port<S>,
    pub(super) config: MasterConfig,
    pub(super) slaves: Vec<SlaveInfo>,
    pub(super) cyclic: Cyclic,
    /// CoE emergencies read from the mailbox while waiting for something else.
    pub(super) emergencies: Vec<Emergency>,
    /// Messages of the exchange under way discarded as repeats: their counter and how many.
    pub(super) repeats: Option<(u8, u32)>,
}

impl<S: Segment> Master<S> {
    /// A master over `segment`; nothing is sent until the first call.
    pub(crate) fn new(segment: S, config: MasterConfig) -> Master<S> {
        Master {
            port: Port::new(segment, config.frame_timeout),
            config,
            slaves: Vec::new(),
            cyclic: Cyclic::default(),
            emergencies: Vec::new(),
            repeats: None,
        }
    }

    /// Multiplies the limit of every wait from now on by `factor` (1: the slave's own limits;
    /// see [`Port::set_patience`]).
    pub(crate) fn set_patience(&mut self, factor: u32) {
        self.port.set_patience(factor);
    }

    /// The configuration.
    pub(crate) fn config(&self) -> &MasterConfig {
        &self.config
    }

    /// The slaves found by the last scan.
    pub(crate) fn slaves(&self) -> &[SlaveInfo] {
        &self.slaves
    }

    /// The segment.
    #[cfg(test)]
    pub(crate) fn segment(&self) -> &S {
        self.port.segment()
    }

    /// The segment, mutable (fault injection, the embedded slave's device).
    pub(crate) fn segment_mut(&mut self) -> &mut S {
        self.port.segment_mut()
    }

    /// Gives the segment back.
    #[cfg(test)]
    pub(crate) fn into_segment(self) -> S {
        self.port.into_segment()
    }

    /// Time on the segment's clock.
    pub(crate) fn now(&self) -> Duration {
        self.port.now()
    }

    /// Whether the segment runs on the real clock (a network), not a virtual one.
    pub(crate) fn real_time(&self) -> bool {
        self.port.real_time()
    }

    /// Frame counters.
    #[cfg(test)]
    pub(crate) fn port_stats(&self) -> PortStats {
        self.port.stats()
    }

    /// When the kernel received the last frame that came back (real-time clock; network
    /// segments only): for jitter figures of the cycle.
    pub(crate) fn last_receive_stamp(&self) -> Option<Duration> {
        self.port.last_stamp()
    }

    /// The exchanges recorded since the last call (for a step's transcript).
    pub(crate) fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.port.recorder.take()
    }

    /// Turns the recording of exchanges on or off (on by default; the cyclic process data
    /// that runs while the master waits is never recorded).
    pub(crate) fn set_recording(&mut self, on: bool) {
        self.port.recorder.set_on(on);
    }

    /// CoE emergencies set aside and not taken yet, oldest first.
    pub(crate) fn pending_emergencies(&self) -> &[Emergency] {
        &self.emergencies
    }

    /// CoE emergencies that arrived since the last call.
    pub(crate) fn take_emergencies(&mut self) -> Vec<Emergency> {
        std::mem::take(&mut self.emergencies)
    }

    /// The slave with station address `station`.
    pub(crate) fn slave(&self, station: u16) -> Option<&SlaveInfo> {
        self.slaves.iter().find(|s| s.station == station)
    }

    pub(super) fn slave_mut(&mut self, station: u16) -> Option<&mut SlaveInfo> {
        self.slaves.iter_mut().find(|s| s.station == station)
    }

    /// Reads `len` bytes of ESC registers (or process RAM) of `station` (FPRD, working
    /// counter 1).
    pub(crate) fn read_register(
        &mut self,
        station: u16,
        address: u16,
        len: usize,
    ) -> Result<Vec<u8>> {
        self.expect(wire::read(Command::FPRD, station, address, len), 1)
    }

    /// Writes ESC registers of `station` (FPWR, working counter 1).
    pub(crate) fn write_register(&mut self, station: u16, address: u16, data: &[u8]) -> Result<()> {
        self.expect(
            wire::write(Command::FPWR, station, address, data.to_vec()),
            1,
        )
        .map(drop)
    }

    /// A 16-bit register.
    pub(crate) fn read_u16(&mut self, station: u16, address: u16) -> Result<u16> {
        let d = self.read_register(station, address, 2)?;
        Ok(u16::from_le_bytes([d[0], d[1]]))
    }

    /// Sends `datagrams` as given (any command, address and length) in one frame and returns
    /// what came back for each, working counters as they are; `None` when no frame came back
    /// within the frame timeout. A frame that comes back unprocessed is an error before a
    /// scan counted slaves, and the slaves' answer after.
    pub(crate) fn raw_datagrams(
        &mut self,
        datagrams: &[DatagramRepr],
    ) -> Result<Option<Vec<DatagramRepr>>> {
        self.keep_cycle();
        match self.port.exchange_as_given(datagrams) {
            Ok(r) => Ok(Some(r)),
            Err(MasterError::Link(LinkFailure::Timeout { .. })) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// Sends `payload` — an EtherCAT frame header and datagrams as given, maybe lying about
    /// their lengths — behind the master's Ethernet header, and returns the EtherCAT payload
    /// that came back (`None`: nothing within the frame timeout; an ESC destroys frames it
    /// finds malformed).
    pub(crate) fn raw_frame(&mut self, payload: &[u8]) -> Result<Option<Vec<u8>>> {
        self.keep_cycle();
        self.port.exchange_raw(payload)
    }

    /// Runs the process data cycle if it runs and is due: called before every other frame,
    /// so that a long burst of requests (SDO after SDO) does not starve the SM watchdog.
    pub(super) fn keep_cycle(&mut self) {
        if self.cyclic.due().is_some_and(|due| due <= self.now()) {
            self.background_cycle();
        }
    }

    /// [`Port::exchange`] after a due cycle.
    pub(super) fn exchange(&mut self, datagrams: &[DatagramRepr]) -> Result<Vec<DatagramRepr>> {
        self.keep_cycle();
        self.port.exchange(datagrams)
    }

    /// [`Port::one`] after a due cycle.
    pub(super) fn one(&mut self, d: DatagramRepr) -> Result<DatagramRepr> {
        self.keep_cycle();
        self.port.one(d)
    }

    /// [`Port::expect`] after a due cycle.
    pub(super) fn expect(&mut self, d: DatagramRepr, wkc: u16) -> Result<Vec<u8>> {
        self.keep_cycle();
        self.port.expect(d, wkc)
    }

    /// Lets `time` pass, running the process data cycle if it runs.
    pub(crate) fn idle(&mut self, time: Duration) {
        let until = self.now() + time;
        self.idle_until(until);
    }

    /// Lets time pass until `until`, running the process data cycle if it runs (its errors
    /// are counted in [`super::pdo::CyclicStats`], not returned).
    pub(crate) fn idle_until(&mut self, until: Duration) {
        loop {
            let now = self.now();
            if now >= until {
                return;
            }
            match self.cyclic.due() {
                Some(due) if due <= until => {
                    self.port.wait_until(due);
                    self.background_cycle();
                }
                _ => {
                    self.port.wait_until(until);
                    return;
                }
            }
        }
    }

    /// One pause of a polling loop.
    pub(super) fn pause(&mut self) {
        let t = self.config.poll_interval.max(Duration::from_micros(1));
        self.idle(t);
    }

    /// Polls `probe` until it gives a value or `timeout` passes (then `awaited` timed out).
    pub(super) fn poll<T>(
        &mut self,
        timeout: Duration,
        awaited: Awaited,
        mut probe: impl FnMut(&mut Self) -> Result<Option<T>>,
    ) -> Result<T> {
        let wait = self.port.wait(timeout);
        loop {
            if let Some(v) = probe(self)? {
                return Ok(v);
            }
            let now = self.now();
            if wait.passed(now) {
                return Err(LinkFailure::timeout(awaited, &wait, now).into());
            }
            self.pause();
        }
    }
}
