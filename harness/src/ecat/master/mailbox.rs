//! The mailbox (ETG.1000.6 §5.5; ETG.1000.4 §6.7.2): the master writes a message into the
//! slave's receive mailbox (SM0, the whole buffer: the SyncManager hands it over when its last
//! byte is written), polls the send mailbox's status (SM1 status bit 3 "mailbox full") and
//! reads the reply (the whole buffer, which empties it).
//!
//! Each message carries the master's counter, 1..7 cycling (0 is reserved for "no counter");
//! a slave takes a message with the same counter as the one before for a repetition.
//! The first frame of an exchange reads a message left in SM1 (an emergency, a stale reply),
//! writes the request and tries to read the reply at once; a slave that needs longer is
//! polled. CoE emergencies that arrive meanwhile are kept ([`Master::take_emergencies`]).
//! A mailbox error reply (type 0) is the slave's refusal ([`Refusal::Mailbox`]).
//!
//! The slave numbers its messages the same way, and a message with the counter of the one it
//! sent before is a repeat (ETG.1000.6 §5.6 "Cnt"; ETG.1000.4 §6.7.3, the repeat the master
//! asks for after a lost read): discarded, it is no answer. An exchange that meets only
//! repeats ends as [`ProtocolError::RepeatedCounter`], naming the counter. The slave starts
//! counting again when its mailbox starts (Init → Pre-Operational).

use proto::ecat::coe::{CoeHeader, CoeMessage, CoeService, Emergency, SdoRequest, SdoResponse};
use proto::ecat::mailbox::{self, MailboxError, MailboxRepr, MailboxType};
use proto::ecat::register::{self, sm_control, sm_status};
use proto::ecat::sii::SmType;
use proto::ecat::Command;

use super::engine::{Master, SmSetup};
use super::error::{Awaited, LinkFailure, MasterError, ProtocolError, Refusal, Result, UsageError};
use super::pdo::sm_block;
use super::port::check_wkc;
use super::segment::Segment;
use super::wire;

/// Control byte of SM0 when the SII has none: mailbox, written by the master, AL event.
const SM0_CONTROL: u8 = sm_control::MODE_MAILBOX | sm_control::DIRECTION_WRITE | sm_control::IRQ_AL;
/// Control byte of SM1: mailbox, read by the master, AL event.
const SM1_CONTROL: u8 = sm_control::MODE_MAILBOX | sm_control::DIRECTION_READ | sm_control::IRQ_AL;

/// The emergency a mailbox message carries, if it is one (CoE service 1).
fn emergency(m: &MailboxRepr) -> Option<Emergency> {
    if m.kind != MailboxType::COE {
        return None;
    }
    match CoeHeader::split(&m.data) {
        Ok((h, rest)) if h.service == CoeService::EMERGENCY => Emergency::parse(rest).ok(),
        _ => None,
    }
}

/// One line for a mailbox message: `mailbox #3 CoE SDO upload request 3066h:01h`.
pub(crate) fn describe(m: &MailboxRepr) -> String {
    let what = match m.kind {
        MailboxType::ERR => match MailboxError::parse(&m.data) {
            Ok(e) => format!("error reply {}", e.detail),
            Err(e) => format!("error reply, malformed: {e}"),
        },
        MailboxType::COE => match CoeMessage::parse(&m.data) {
            Ok(c) => describe_coe(&c),
            Err(e) => format!("CoE, malformed: {e}"),
        },
        k => format!("{k}, {} bytes", m.data.len()),
    };
    format!("mailbox #{} {what}", m.counter)
}

fn ca(on: bool) -> &'static str {
    if on {
        " complete access"
    } else {
        ""
    }
}

/// One line for a CoE message.
fn describe_coe(c: &CoeMessage) -> String {
    let t = u8::from;
    match c {
        CoeMessage::Emergency(e) => format!(
            "CoE emergency {:04X}h, register {:02X}h, {}",
            e.code,
            e.register,
            crate::hex::hex(&e.data)
        ),
        CoeMessage::SdoRequest(r) => match r {
            SdoRequest::Download {
                index,
                sub,
                complete_access,
                data,
            } => format!(
                "CoE SDO download request {index:04X}h:{sub:02X}h{} = {}",
                ca(*complete_access),
                crate::hex::hex(data.data())
            ),
            SdoRequest::DownloadSegment { toggle, last, data } => format!(
                "CoE SDO download segment, toggle {}, {} bytes{}",
                t(*toggle),
                data.len(),
                if *last { ", last" } else { "" }
            ),
            SdoRequest::Upload {
                index,
                sub,
                complete_access,
            } => format!(
                "CoE SDO upload request {index:04X}h:{sub:02X}h{}",
                ca(*complete_access)
            ),
            SdoRequest::UploadSegment { toggle } => {
                format!("CoE SDO upload segment request, toggle {}", t(*toggle))
            }
            SdoRequest::Abort { index, sub, code } => {
                format!("CoE SDO abort {index:04X}h:{sub:02X}h {code}")
            }
        },
        CoeMessage::SdoResponse(r) => match r {
            SdoResponse::Download {
                index,
                sub,
                complete_access,
            } => format!(
                "CoE SDO download response {index:04X}h:{sub:02X}h{}",
                ca(*complete_access)
            ),
            SdoResponse::DownloadSegment { toggle } => {
                format!("CoE SDO download segment response, toggle {}", t(*toggle))
            }
            SdoResponse::Upload {
                index,
                sub,
                complete_access,
                data,
            } => format!(
                "CoE SDO upload response {index:04X}h:{sub:02X}h{} = {}",
                ca(*complete_access),
                crate::hex::hex(data.data())
            ),
            SdoResponse::UploadSegment { toggle, last, data } => format!(
                "CoE SDO upload segment, toggle {}, {} bytes{}",
                t(*toggle),
                data.len(),
                if *last { ", last" } else { "" }
            ),
            SdoResponse::Abort { index, sub, code } => {
                format!("CoE SDO abort {index:04X}h:{sub:02X}h {code}")
            }
        },
        CoeMessage::SdoInfo(i) => format!("CoE SDO information {:?}", i.opcode),
        CoeMessage::Other { header, data } => {
            format!("CoE {}, {} bytes", header.service, data.len())
        }
    }
}

impl<S: Segment> Master<S> {
    /// Configures SM0/SM1 of `station` as its SII's standard mailbox says (the SyncM
    /// category's control bytes when it has them).
    pub(crate) fn configure_mailbox(&mut self, station: u16) -> Result<(SmSetup, SmSetup)> {
        let slave = self
            .slave(station)
            .ok_or(UsageError::NoSuchSlave { station })?;
        if !slave.has_mailbox() {
            return Err(UsageError::NoMailbox { station }.into());
        }
        let control =
            |kind: SmType, default: u8| slave.sync_manager(kind).map_or(default, |s| s.control);
        let m = slave.sii.header.standard_mailbox;
        let out = SmSetup {
            start: m.rx_offset,
            len: m.rx_size,
            control: control(SmType::MAILBOX_OUT, SM0_CONTROL),
        };
        let inn = SmSetup {
            start: m.tx_offset,
            len: m.tx_size,
            control: control(SmType::MAILBOX_IN, SM1_CONTROL),
        };
        let regs: Vec<u8> = [out, inn].iter().flat_map(|sm| sm_block(*sm)).collect();
        self.write_register(station, register::sm(0), &regs)?;
        if let Some(s) = self.slave_mut(station) {
            s.mailbox = Some((out, inn));
            s.received = None;
        }
        Ok((out, inn))
    }

    fn mailboxes(&self, station: u16) -> Result<(SmSetup, SmSetup)> {
        self.slave(station)
            .ok_or(UsageError::NoSuchSlave { station })?
            .mailbox
            .ok_or_else(|| UsageError::NoMailbox { station }.into())
    }

    /// The next counter of `station`'s messages, 1..7.
    pub(crate) fn next_counter(&mut self, station: u16) -> u8 {
        match self.slave_mut(station) {
            Some(s) => {
                s.counter = mailbox::next_counter(s.counter);
                s.counter
            }
            None => 1,
        }
    }

    /// Sends a message of `kind` with `data` and the next counter, and returns the slave's
    /// reply (emergencies set aside). A mailbox error reply is [`Refusal::Mailbox`].
    pub(crate) fn mailbox_request(
        &mut self,
        station: u16,
        kind: MailboxType,
        data: Vec<u8>,
    ) -> Result<MailboxRepr> {
        let counter = self.next_counter(station);
        let msg = MailboxRepr::new(kind, counter, data)
            .emit()
            .map_err(UsageError::Mailbox)?;
        let reply = self.mailbox_transfer(station, &msg)?;
        let m = MailboxRepr::parse_bytes(&reply).map_err(ProtocolError::Mailbox)?;
        if m.kind == MailboxType::ERR {
            let e = MailboxError::parse(&m.data).map_err(ProtocolError::Mailbox)?;
            return Err(Refusal::Mailbox(e.detail).into());
        }
        Ok(m)
    }

    /// Writes `bytes` (a mailbox message as given, maybe malformed) into the receive mailbox
    /// of `station` and returns the reply in the send mailbox (emergencies set aside), or
    /// `None` when none came within [`super::MasterConfig::mailbox_response`]. A counter in
    /// the message's header (1..7) becomes the station's last: the master's next message
    /// counts on from it, so the slave does not take it for a repeat (ETG.1000.6 §5.6.1).
    pub(crate) fn mailbox_raw(&mut self, station: u16, bytes: &[u8]) -> Result<Option<Vec<u8>>> {
        let counter = bytes.get(5).map(|b| (b >> 4) & 0x07).filter(|c| *c != 0);
        let reply = self.mailbox_transfer(station, bytes);
        if let (Some(c), Some(s)) = (counter, self.slave_mut(station)) {
            s.counter = c;
        }
        match reply {
            Ok(reply) => Ok(Some(reply)),
            Err(MasterError::Link(LinkFailure::Timeout {
                awaited: Awaited::MailboxReply,
                ..
            })) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// The mailbox exchange: write `msg` (padded to SM0's length), wait for the reply.
    fn mailbox_transfer(&mut self, station: u16, msg: &[u8]) -> Result<Vec<u8>> {
        let (out, inn) = self.mailboxes(station)?;
        if msg.len() > usize::from(out.len) {
            return Err(UsageError::TooLong {
                what: "mailbox message",
                len: msg.len(),
                max: usize::from(out.len),
            }
            .into());
        }
        let mut padded = msg.to_vec();
        padded.resize(usize::from(out.len), 0);
        let read = wire::read(Command::FPRD, station, inn.start, usize::from(inn.len));
        let write = wire::write(Command::FPWR, station, out.start, padded);
        let access = wire::Access::of(&write);
        let note = match MailboxRepr::parse_bytes(msg) {
            Ok(m) => describe(&m),
            Err(_) => format!("mailbox {} bytes as given", msg.len()),
        };
        self.port.recorder.note_next(note);
        self.repeats = None;
        let r = self.exchange(&[read.clone(), write.clone(), read.clone()])?;
        if r[0].wkc == 1 {
            self.set_aside(station, &r[0].data);
        }
        if r[1].wkc == 0 {
            // The receive mailbox is still full: wait for room.
            let timeout = self.config.mailbox_request;
            self.poll(timeout, Awaited::MailboxRoom, |m| {
                let r = m.one(write.clone())?;
                Ok((r.wkc == 1).then_some(()))
            })?;
        } else {
            check_wkc(access, &r[1], 1)?;
            if r[2].wkc == 1 {
                if let Some(reply) = self.keep_reply(station, &r[2].data) {
                    return Ok(reply);
                }
            }
        }
        let timeout = self.config.mailbox_response;
        let status = register::sm(1) + 5;
        let reply = self.poll(timeout, Awaited::MailboxReply, |m| {
            let s = m.one(wire::read(Command::FPRD, station, status, 1))?;
            if s.wkc != 1 || s.data[0] & sm_status::MAILBOX_FULL == 0 {
                return Ok(None);
            }
            let r = m.one(read.clone())?;
            if r.wkc != 1 {
                return Ok(None);
            }
            Ok(m.keep_reply(station, &r.data))
        });
        match (reply, self.repeats.take()) {
            (
                Err(MasterError::Link(LinkFailure::Timeout {
                    awaited: Awaited::MailboxReply,
                    limit,
                    ..
                })),
                Some((counter, discarded)),
            ) => Err(ProtocolError::RepeatedCounter {
                counter,
                discarded,
                limit,
            }
            .into()),
            (reply, _) => reply,
        }
    }

    /// Whether `m`, read from `station`'s send mailbox, is new: a counter (1..7) equal to the
    /// last one read is a repeat, discarded and counted in [`Master::repeats`].
    fn fresh(&mut self, station: u16, m: &MailboxRepr) -> bool {
        let Some(s) = self.slave_mut(station) else {
            return true;
        };
        let last = s.received;
        if m.counter != 0 {
            s.received = Some(m.counter);
        }
        if m.counter == 0 || last != Some(m.counter) {
            return true;
        }
        let n = self.repeats.map_or(0, |(_, n)| n) + 1;
        self.repeats = Some((m.counter, n));
        let line = format!("discarded as a repeat: {}", describe(m));
        self.port.recorder.annotate("", &line);
        false
    }

    /// A message read from SM1 while looking for a reply: a repeat is discarded and an
    /// emergency set aside (`None`), anything else is the reply.
    fn keep_reply(&mut self, station: u16, buf: &[u8]) -> Option<Vec<u8>> {
        match MailboxRepr::parse_bytes(buf) {
            Ok(m) if !self.fresh(station, &m) => None,
            Ok(m) => match emergency(&m) {
                Some(e) => {
                    let line = format!("set aside: {}", describe(&m));
                    self.port.recorder.annotate("", &line);
                    self.emergencies.push(e);
                    None
                }
                None => {
                    self.port.recorder.annotate("", &describe(&m));
                    Some(buf.to_vec())
                }
            },
            Err(_) => Some(buf.to_vec()),
        }
    }

    /// The CoE emergencies `station` sent since the last call: those set aside during
    /// mailbox transfers, and one waiting in its send mailbox now (read once).
    pub(crate) fn collect_emergencies(&mut self, station: u16) -> Result<Vec<Emergency>> {
        let (_, inn) = self.mailboxes(station)?;
        let read = wire::read(Command::FPRD, station, inn.start, usize::from(inn.len));
        let r = self.one(read)?;
        if r.wkc == 1 {
            self.set_aside(station, &r.data);
        }
        Ok(self.take_emergencies())
    }

    /// A message left in SM1 before the request went out: a new emergency is kept, anything
    /// else (a stale reply, a repeat) is dropped.
    fn set_aside(&mut self, station: u16, buf: &[u8]) {
        let Ok(m) = MailboxRepr::parse_bytes(buf) else {
            return;
        };
        if let (true, Some(e)) = (self.fresh(station, &m), emergency(&m)) {
            self.emergencies.push(e);
        }
    }
}
