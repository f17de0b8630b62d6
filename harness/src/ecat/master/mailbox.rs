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

use super::codes::MailboxErrorCode;
use proto::ecat::register::{self, sm_status};

use super::engine::{Master, SmSetup};
use super::error::{Awaited, LinkFailure, ProtocolError, Refusal, Result, UsageError};
use super::pdo::sm_block;
use super::port::check_wkc;
use super::segment::Segment;
use super::sii::SmKind;
use super::wire;
use proto::ecat::Command;

/// Mailbox header bytes (ETG.1000.6 table 29).
pub(crate) const HEADER: usize = 6;
/// Mailbox type: error reply.
pub(crate) const TYPE_ERROR: u8 = 0;
/// Mailbox type: CoE.
pub(crate) const TYPE_COE: u8 = 3;
/// CoE service: emergency.
const COE_EMERGENCY: u8 = 1;
/// Control byte of SM0 when the SII has none: mailbox, written by the master, AL event.
const SM0_CONTROL: u8 = 0x26;
/// Control byte of SM1: mailbox, read by the master, AL event.
const SM1_CONTROL: u8 = 0x22;

/// A mailbox message taken apart (stopgap until `proto::ecat::mailbox` lands).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Message {
    /// Mailbox type (0 error, 3 CoE…).
    pub(crate) kind: u8,
    /// The sender's counter.
    pub(crate) counter: u8,
    /// The body (the header's length of it).
    pub(crate) body: Vec<u8>,
}

impl Message {
    /// Parses a whole mailbox buffer.
    pub(crate) fn parse(buf: &[u8]) -> std::result::Result<Message, ProtocolError> {
        let h = buf.get(..HEADER).ok_or_else(|| {
            ProtocolError::Mailbox(format!("truncated: need {HEADER} bytes, got {}", buf.len()))
        })?;
        let len = usize::from(u16::from_le_bytes([h[0], h[1]]));
        let body = buf.get(HEADER..HEADER + len).ok_or_else(|| {
            ProtocolError::Mailbox(format!(
                "length {len} exceeds the {} bytes of the mailbox",
                buf.len() - HEADER
            ))
        })?;
        Ok(Message {
            kind: h[5] & 0x0F,
            counter: (h[5] >> 4) & 0x07,
            body: body.to_vec(),
        })
    }

    /// The header and body of a message.
    pub(crate) fn emit(kind: u8, counter: u8, body: &[u8]) -> Vec<u8> {
        let mut m = Vec::with_capacity(HEADER + body.len());
        m.extend((body.len() as u16).to_le_bytes());
        m.extend([0, 0, 0, (kind & 0x0F) | (counter & 0x07) << 4]);
        m.extend(body);
        m
    }

    /// A CoE emergency (CoE service 1).
    fn is_emergency(&self) -> bool {
        self.kind == TYPE_COE && self.body.get(1).map(|b| b >> 4) == Some(COE_EMERGENCY)
    }
}

/// One line for a mailbox message: `mailbox #3 CoE SDO upload request 3066h:01h`.
pub(crate) fn describe(m: &Message) -> String {
    let b = &m.body;
    let what = match m.kind {
        TYPE_ERROR => match b.get(2..4) {
            Some(d) => format!("error reply {:04X}h", u16::from_le_bytes([d[0], d[1]])),
            None => "error reply (truncated)".into(),
        },
        TYPE_COE => describe_coe(b),
        k => format!("type {k}, {} bytes", b.len()),
    };
    format!("mailbox #{} {what}", m.counter)
}

/// One line for a CoE body (ETG.1000.6 §5.6: CoE header, then the SDO command byte).
fn describe_coe(b: &[u8]) -> String {
    let service = b.get(1).map_or(0, |x| x >> 4);
    let (Some(&cmd), obj) = (b.get(2), b.get(3..6)) else {
        return format!("CoE service {service}, {} bytes", b.len());
    };
    let obj = obj.map_or(String::new(), |o| {
        format!(" {:04X}h:{:02X}h", u16::from_le_bytes([o[0], o[1]]), o[2])
    });
    let toggle = (cmd >> 4) & 1;
    let what = match (service, cmd >> 5) {
        (1, _) => return format!("CoE emergency {}", crate::runner::hex(&b[2..])),
        (2 | 3, 4) => {
            let code = b
                .get(6..10)
                .map_or(0, |c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]));
            return format!("CoE SDO abort{obj} {code:08X}h");
        }
        (2, 1) => format!("download request{obj}"),
        (2, 0) => format!("download segment, toggle {toggle}"),
        (2, 2) => format!("upload request{obj}"),
        (2, 3) => format!("upload segment request, toggle {toggle}"),
        (3, 3) => format!("download response{obj}"),
        (3, 1) => format!("download segment response, toggle {toggle}"),
        (3, 2) => format!("upload response{obj}"),
        (3, 0) => format!("upload segment, toggle {toggle}"),
        (s, c) => format!("service {s} command {c}"),
    };
    let initiate = matches!((service, cmd >> 5), (2, 1) | (2, 2) | (3, 2));
    let ca = if initiate && cmd & 0x10 != 0 {
        " complete access"
    } else {
        ""
    };
    format!("CoE SDO {what}{ca}")
}

impl<S: Segment> Master<S> {
    /// Configures SM0/SM1 of `station` as its SII's standard mailbox says (the SyncM
    /// category's control bytes when it has them).
    pub(crate) fn configure_mailbox(&mut self, station: u16) -> Result<(SmSetup, SmSetup)> {
        let sii = &self
            .slave(station)
            .ok_or(UsageError::NoSuchSlave { station })?
            .sii;
        if !sii.has_mailbox() {
            return Err(UsageError::NoMailbox { station }.into());
        }
        let control = |kind: SmKind, default: u8| {
            sii.sync_managers
                .iter()
                .find(|s| s.kind == kind)
                .map_or(default, |s| s.control)
        };
        let out = SmSetup {
            start: sii.mailbox.out_start,
            len: sii.mailbox.out_len,
            control: control(SmKind::MailboxOut, SM0_CONTROL),
        };
        let inn = SmSetup {
            start: sii.mailbox.in_start,
            len: sii.mailbox.in_len,
            control: control(SmKind::MailboxIn, SM1_CONTROL),
        };
        let regs: Vec<u8> = [out, inn].iter().flat_map(|sm| sm_block(*sm)).collect();
        self.write_register(station, register::sm(0), &regs)?;
        if let Some(s) = self.slave_mut(station) {
            s.mailbox = Some((out, inn));
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
                s.counter = s.counter % 7 + 1;
                s.counter
            }
            None => 1,
        }
    }

    /// Sends a message of `kind` with `body` and the next counter, and returns the slave's
    /// reply (emergencies set aside). A mailbox error reply is [`Refusal::Mailbox`].
    pub(crate) fn mailbox_request(
        &mut self,
        station: u16,
        kind: u8,
        body: &[u8],
    ) -> Result<Message> {
        let counter = self.next_counter(station);
        let msg = Message::emit(kind, counter, body);
        let reply = self
            .mailbox_transfer(station, &msg)?
            .ok_or(LinkFailure::Timeout {
                awaited: Awaited::MailboxReply,
                after: self.config.mailbox_timeout,
            })?;
        let m = Message::parse(&reply)?;
        if m.kind == TYPE_ERROR {
            let detail = m.body.get(2..4).map(|b| u16::from_le_bytes([b[0], b[1]]));
            return match detail {
                Some(d) => Err(Refusal::Mailbox(MailboxErrorCode(d)).into()),
                None => Err(ProtocolError::Mailbox("error reply without its detail".into()).into()),
            };
        }
        Ok(m)
    }

    /// Writes `bytes` (a mailbox message as given, maybe malformed) into the receive mailbox
    /// of `station` and returns the reply in the send mailbox (emergencies set aside), or
    /// `None` when none came within [`super::MasterConfig::mailbox_timeout`].
    pub(crate) fn mailbox_raw(&mut self, station: u16, bytes: &[u8]) -> Result<Option<Vec<u8>>> {
        self.mailbox_transfer(station, bytes)
    }

    /// The mailbox exchange: write `msg` (padded to SM0's length), wait for the reply.
    fn mailbox_transfer(&mut self, station: u16, msg: &[u8]) -> Result<Option<Vec<u8>>> {
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
        let access = wire::describe(&write);
        let note = match Message::parse(msg) {
            Ok(m) => describe(&m),
            Err(_) => format!("mailbox {} bytes as given", msg.len()),
        };
        self.port.recorder.note_next(note);
        let r = self.exchange(&[read.clone(), write.clone(), read.clone()])?;
        if r[0].wkc == 1 {
            self.set_aside(&r[0].data);
        }
        if r[1].wkc == 0 {
            // The receive mailbox is still full: wait for room.
            let timeout = self.config.mailbox_timeout;
            self.poll(timeout, Awaited::MailboxRoom, |m| {
                let r = m.one(write.clone())?;
                Ok((r.wkc == 1).then_some(()))
            })?;
        } else {
            check_wkc(&access, &r[1], 1)?;
            if r[2].wkc == 1 {
                if let Some(reply) = self.keep_reply(&r[2].data) {
                    return Ok(Some(reply));
                }
            }
        }
        let timeout = self.config.mailbox_timeout;
        let status = register::sm(1) + 5;
        let got = self.poll(timeout, Awaited::MailboxReply, |m| {
            let s = m.one(wire::read(Command::FPRD, station, status, 1))?;
            if s.wkc != 1 || s.data[0] & sm_status::MAILBOX_FULL == 0 {
                return Ok(None);
            }
            let r = m.one(read.clone())?;
            if r.wkc != 1 {
                return Ok(None);
            }
            Ok(m.keep_reply(&r.data))
        });
        match got {
            Ok(reply) => Ok(Some(reply)),
            Err(super::error::MasterError::Link(LinkFailure::Timeout {
                awaited: Awaited::MailboxReply,
                ..
            })) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// A message read from SM1 while looking for a reply: an emergency is set aside (`None`),
    /// anything else is the reply.
    fn keep_reply(&mut self, buf: &[u8]) -> Option<Vec<u8>> {
        match Message::parse(buf) {
            Ok(m) if m.is_emergency() => {
                self.port
                    .recorder
                    .annotate("", &format!("CoE emergency set aside ({})", describe(&m)));
                self.emergencies.push(m.body);
                None
            }
            Ok(m) => {
                self.port.recorder.annotate("", &describe(&m));
                Some(buf.to_vec())
            }
            Err(_) => Some(buf.to_vec()),
        }
    }

    /// A message left in SM1 before the request went out: emergencies are kept, anything
    /// else (a stale reply) is dropped.
    fn set_aside(&mut self, buf: &[u8]) {
        if let Ok(m) = Message::parse(buf) {
            if m.is_emergency() {
                self.emergencies.push(m.body);
            }
        }
    }
}
