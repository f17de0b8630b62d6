//! Frames on the segment: the master's datagrams go out in one EtherCAT frame with an index,
//! and the frame that comes back with that index and the same datagrams is their answer
//! (ETG.1000.4 §5.4: the index "is a key for the master to identify the datagram").
//!
//! - Frames of another index (stale answers of an earlier frame, duplicates, another master's
//!   frames) and frames of another EtherType are skipped.
//! - A frame that comes back byte for byte as sent was processed by no slave (every ESC sets
//!   the locally administered bit of the source address, and the master's own address has it
//!   clear): "no slave answered", at once.
//! - An EtherCAT frame that cannot be parsed, or has the index but not the datagrams sent, is
//!   remembered; when nothing good came by the deadline it is the error (malformed), else the
//!   timeout is.
//!
//! Every exchange is recorded with its bytes and one decoded line each way.

use std::time::Duration;

use super::error::{Awaited, LinkFailure, MasterError, NoSlave, ProtocolError, Result, UsageError};
use super::record::Recorder;
use super::segment::Segment;
use super::wire;
use crate::net::wait::Wait;
use proto::ecat::DatagramRepr;

/// The master's source address: a unicast address with the locally administered bit clear, so
/// that a frame some ESC processed (which sets that bit, ETG.1000.4 §5.3) differs from one that
/// came back unprocessed. Any address works on a raw link; this one is ethercrab's choice too.
pub(crate) const MASTER_MAC: [u8; 6] = [0x10, 0x10, 0x10, 0x10, 0x10, 0x10];

/// Largest Ethernet frame the master builds or receives (no 802.1Q tag, no FCS).
pub(crate) const MAX_FRAME: usize = 1514;

/// Statistics of the port.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct PortStats {
    /// Frames sent.
    pub(crate) sent: u64,
    /// Frames matched to what was sent.
    pub(crate) matched: u64,
    /// Frames skipped (other index, other type, stale).
    pub(crate) skipped: u64,
    /// Malformed EtherCAT frames received.
    pub(crate) malformed: u64,
    /// Exchanges that timed out.
    pub(crate) timeouts: u64,
}

/// The segment with the master's framing on top.
#[derive(Debug)]
pub(crate) struct Port<S> {
    segment: S,
    index: u8,
    mac: [u8; 6],
    timeout: Duration,
    /// What every wait's limit is multiplied by ([`Port::set_patience`]).
    patience: u32,
    rx: Vec<u8>,
    pub(crate) recorder: Recorder,
    stats: PortStats,
    /// The receive stamp of the last frame matched.
    last_stamp: Option<Duration>,
    /// A scan counted slaves on the segment: a frame of a suite's own (datagrams as given, a
    /// raw frame) that comes back as it was sent is then one that no slave changed (a NOP, a
    /// datagram for no one), not a looped cable. Marking a returned frame (bit 1 of the
    /// source address's first octet) is what Beckhoff's ESCs do (ESC datasheet, section I,
    /// "frame processing"); ETG.1000.4 does not require it, and an emulated ESC (KickCAT's)
    /// returns frames unmarked. The master's own frames, which a slave always processes, still
    /// call an unchanged return a looped segment.
    slaves_seen: bool,
    /// The exchange under way is a suite's frame as given.
    as_given: bool,
}

impl<S: Segment> Port<S> {
    /// A port over `segment` that waits `timeout` for each frame.
    pub(crate) fn new(segment: S, timeout: Duration) -> Port<S> {
        Port {
            segment,
            index: 0,
            mac: MASTER_MAC,
            timeout,
            patience: 1,
            rx: vec![0; MAX_FRAME + 4],
            recorder: Recorder::new(),
            stats: PortStats::default(),
            last_stamp: None,
            slaves_seen: false,
            as_given: false,
        }
    }

    /// A scan counted slaves behind this port (see `slaves_seen`).
    pub(crate) fn set_slaves_seen(&mut self) {
        self.slaves_seen = true;
    }

    /// The segment.
    #[cfg(test)]
    pub(crate) fn segment(&self) -> &S {
        &self.segment
    }

    /// The segment, mutable.
    pub(crate) fn segment_mut(&mut self) -> &mut S {
        &mut self.segment
    }

    /// Gives the segment back.
    #[cfg(test)]
    pub(crate) fn into_segment(self) -> S {
        self.segment
    }

    /// Time on the segment's clock.
    pub(crate) fn now(&self) -> Duration {
        self.segment.now()
    }

    /// Lets time pass on the segment.
    pub(crate) fn wait_until(&mut self, t: Duration) {
        self.segment.wait_until(t)
    }

    /// Whether the segment runs on the real clock.
    pub(crate) fn real_time(&self) -> bool {
        self.segment.real_time()
    }

    /// Multiplies the limit of every wait from now on by `factor` (1: the slave's own limits):
    /// a second look at a slave that let a limit pass, to tell a late one from an absent one
    /// (`crate::net::wait::bring_up`).
    pub(crate) fn set_patience(&mut self, factor: u32) {
        self.patience = factor.max(1);
    }

    /// A wait of the slave's `limit` from now, on the segment's clock.
    pub(crate) fn wait(&self, limit: Duration) -> Wait {
        Wait::new(
            self.segment.now(),
            limit * self.patience,
            self.segment.real_time(),
        )
    }

    /// The next frame that came back within `wait` (`None`: none by its end).
    fn recv(&mut self, wait: &Wait) -> Result<Option<super::segment::Arrival>> {
        loop {
            let now = self.segment.now();
            if let Some(a) = self.segment.recv(&mut self.rx, wait.end(now))? {
                return Ok(Some(a));
            }
            if wait.passed(self.segment.now()) {
                return Ok(None);
            }
        }
    }

    /// The kernel's receive stamp of the last frame matched (network segments).
    pub(crate) fn last_stamp(&self) -> Option<Duration> {
        self.last_stamp
    }

    /// The counters.
    #[cfg(test)]
    pub(crate) fn stats(&self) -> PortStats {
        self.stats
    }

    /// Sends `datagrams` in one frame and returns what came back for each, in order. A working
    /// counter of 0 is returned as it came (the caller judges it).
    pub(crate) fn exchange(&mut self, datagrams: &[DatagramRepr]) -> Result<Vec<DatagramRepr>> {
        let index = self.index;
        self.index = self.index.wrapping_add(1);
        let frame = wire::frame(self.mac, index, datagrams).map_err(UsageError::Frame)?;
        // Decoded lines cost more than the exchange: written only while recording.
        let recording = self.recorder.is_on();
        let sent_line = if recording {
            wire::describe_sent(datagrams)
        } else {
            String::new()
        };
        self.segment.send(&frame)?;
        self.stats.sent += 1;
        let wait = self.wait(self.timeout);
        let mut malformed: Option<ProtocolError> = None;
        loop {
            let Some(arrival) = self.recv(&wait)? else {
                self.stats.timeouts += 1;
                let line = match &malformed {
                    Some(m) => format!("only a frame that is not the answer: {m}"),
                    None => format!("nothing came back within {:?}", self.timeout),
                };
                self.recorder.push(&frame, sent_line, &[], line);
                return Err(match malformed {
                    Some(m) => m.into(),
                    None => LinkFailure::timeout(Awaited::Frame, &wait, self.segment.now()).into(),
                });
            };
            let got = &self.rx[..arrival.len];
            if got == frame.as_slice() && !(self.slaves_seen && self.as_given) {
                self.recorder
                    .push(&frame, sent_line, got, "came back unprocessed".into());
                return Err(LinkFailure::NoSlave(NoSlave::Unprocessed).into());
            }
            match wire::parse_reply(got, index, datagrams) {
                wire::Reply::Foreign => self.stats.skipped += 1,
                wire::Reply::Malformed(e) => {
                    self.stats.malformed += 1;
                    malformed = Some(ProtocolError::Malformed(e));
                }
                wire::Reply::Mismatch => {
                    self.stats.malformed += 1;
                    malformed = Some(ProtocolError::Mismatch { index });
                }
                wire::Reply::Ours(returned) => {
                    self.stats.matched += 1;
                    self.last_stamp = arrival.stamp;
                    if recording {
                        let line = wire::describe_returned(&returned);
                        let got = got.to_vec();
                        self.recorder.push(&frame, sent_line, &got, line);
                    } else {
                        self.recorder.skip();
                    }
                    return Ok(returned);
                }
            }
        }
    }

    /// [`Port::exchange`] of datagrams a suite gave as they are (see `slaves_seen`).
    pub(crate) fn exchange_as_given(
        &mut self,
        datagrams: &[DatagramRepr],
    ) -> Result<Vec<DatagramRepr>> {
        self.as_given = true;
        let r = self.exchange(datagrams);
        self.as_given = false;
        r
    }

    /// Sends one datagram and returns what came back.
    pub(crate) fn one(&mut self, d: DatagramRepr) -> Result<DatagramRepr> {
        let mut r = self.exchange(std::slice::from_ref(&d))?;
        r.pop().ok_or_else(|| {
            MasterError::from(ProtocolError::Mismatch {
                index: self.index.wrapping_sub(1),
            })
        })
    }

    /// Sends one datagram and requires working counter `expected` (0 everywhere: no slave).
    pub(crate) fn expect(&mut self, d: DatagramRepr, expected: u16) -> Result<Vec<u8>> {
        let access = wire::Access::of(&d);
        let r = self.one(d)?;
        check_wkc(access, &r, expected)?;
        Ok(r.data)
    }

    /// Sends an EtherCAT payload (frame header and datagrams, maybe lying about its lengths)
    /// behind the master's Ethernet header as it is, and returns the EtherCAT payload of the
    /// first EtherCAT frame of the same length that comes back (`None`: none by the timeout —
    /// an ESC destroys a frame it finds malformed).
    pub(crate) fn exchange_raw(&mut self, payload: &[u8]) -> Result<Option<Vec<u8>>> {
        let frame = wire::raw_frame(self.mac, payload).map_err(UsageError::Frame)?;
        let sent_line = format!("raw EtherCAT frame, {} bytes", payload.len());
        self.segment.send(&frame)?;
        self.stats.sent += 1;
        let wait = self.wait(self.timeout);
        loop {
            let Some(arrival) = self.recv(&wait)? else {
                self.recorder.push(
                    &frame,
                    sent_line,
                    &[],
                    format!("nothing came back within {:?}", self.timeout),
                );
                return Ok(None);
            };
            let got = &self.rx[..arrival.len];
            if got == frame.as_slice() && !self.slaves_seen {
                self.recorder
                    .push(&frame, sent_line, got, "came back unprocessed".into());
                return Err(LinkFailure::NoSlave(NoSlave::Unprocessed).into());
            }
            match wire::ethercat_payload(got) {
                Some(p) if got.len() == frame.len() => {
                    let p = p.to_vec();
                    let got = got.to_vec();
                    self.recorder.push(
                        &frame,
                        sent_line,
                        &got,
                        format!("EtherCAT frame, {} bytes", p.len()),
                    );
                    return Ok(Some(p));
                }
                _ => self.stats.skipped += 1,
            }
        }
    }
}

/// Checks a working counter: 0 when more was expected is "no slave answered".
pub(crate) fn check_wkc(access: wire::Access, r: &DatagramRepr, expected: u16) -> Result<()> {
    if r.wkc == expected {
        Ok(())
    } else if r.wkc == 0 {
        Err(LinkFailure::NoSlave(NoSlave::WorkingCounters).into())
    } else {
        Err(ProtocolError::WorkingCounter {
            access: access.to_string(),
            expected,
            got: r.wkc,
        }
        .into())
    }
}
