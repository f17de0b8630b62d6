//! Case isolation on a persistent target: what a case changes on a device on the network, and
//! how the scanner puts it back when the case ends ([`Binding::finish`](super::Binding)).
//!
//! The embedded adapter is made afresh for every case and needs none of this. A device on the
//! network is one device for the whole run, so the scanner keeps a [`Ledger`] while a case runs
//! (the attributes it set, in the shared [`crate::binding::ledger::Ledger`], and the connections it
//! opened) and, when it ends, whatever its verdict:
//!
//! 1. stops the inverters the case commanded through the case's own I/O connection while that
//!    is still open: control word 0400h, "control data valid" with "disable voltage"
//!    (BU 0620 §6.1.2.1, BU 2100 §6.2.2: bit 1 = 0 switches the output voltage off, "Switch-on
//!    block");
//! 2. writes back every attribute the case set (parameters first of all), with the value read
//!    before its first write in the case, in the reverse order of the first writes; when the
//!    case made an Identity Reset (type 0, the emulated power cycle that reads the addressing
//!    parameters in: BU 0620 §4.2.2, BU 2100 §7.1.2), one more after the write-backs, so that
//!    what the device uses (the TCP/IP object's gateway of P852, the mask P876 shows) is again
//!    what the restored parameters say, not what the case set;
//! 3. closes every connection the case opened and did not close (Forward_Close; one already
//!    gone, by its time-out or with its owner, counts as closed);
//! 4. if the case ran I/O, brings every inverter it commanded, and every one in fault, back to
//!    "Switch-on block" (xx40h) over a connection of its own: disable voltage, and for a fault
//!    (the E10.2 of a connection time-out, the E10.3 of P151/P513) the bus acknowledgement —
//!    control bit 7 from 0 to 1, "with the switch from 0 to 1, inactive errors are
//!    acknowledged" (BU 0620 §5.2 and §6.1.2.1, BU 2100 §6.2.2 and §8.2) — then closes it,
//!    and waits until the interface no longer shows cyclic process data (P872 bit 1 of the
//!    SK 550P, BU 0620 §4.3; P173 [-01] bit 1 of the modules, BU 2100 §7.1.3), so that what
//!    needs "no communication via Ethernet" (the P899 protocol change, BU 0620 §3.3) holds in
//!    the next case as it did before this one;
//! 5. unregisters its sessions.
//!
//! A write or a Forward_Open whose reply was lost, cut off or unreadable counts as made: the
//! target may have carried it out, so the cleanup writes the attribute back and closes the
//! connection (one the target never opened answers "connection not found", which counts as
//! closed). Once the target stops answering the cleanup stops too, at its first link error,
//! and names what it did not attempt: every further request would only wait out its time-out.
//!
//! A case's own observations are unchanged: the one exchange inside a step is the read of an
//! attribute before its first write, marked as such in the transcript; everything else happens
//! after the last step and shows as the case's cleanup step.

use std::time::Duration;

use proto::enip::cip::{class, GeneralStatus, MrRequest, MrResponse, Service};
use proto::enip::cm::{ext, ConnectionKey, ForwardClose, ForwardOpen};
use proto::enip::encap::{Command, EncapRepr};
use proto::enip::epath::EPath;
use proto::nord::{ArrayElement, Family, Inverter, ParamNumber};
use serde_json::Value;

use super::scanner::{Scanner, RPI};
use crate::binding::ledger::{self, Account, Problem};
use crate::binding::settle::{Drives, DISABLE, SETTLE_CYCLES};
use crate::binding::StepError;
use crate::hex::hex;
use crate::outcome::Exchange;
use crate::suite::{OrderSpec, Target};
use crate::timing::Deadline;

/// Cycles the stop of step 1 runs on the case's connection.
const STOP_CYCLES: u32 = 5;
/// How long the interface may go on showing cyclic communication after the last connection
/// closed, and how often the cleanup looks.
const QUIET_TIME: Duration = Duration::from_secs(2);
const QUIET_POLL: Duration = Duration::from_millis(10);
/// Bus status bit 1 "cyclic (PZD) communication" (P872, P173 [-01]).
const CYCLIC: i64 = 1 << 1;

/// A connection the case opened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Opened {
    key: ConnectionKey,
    /// The connection path of its Forward_Open, which its Forward_Close repeats.
    path: EPath,
}

impl Opened {
    /// The connection `fo` opens.
    pub(super) fn of(fo: &ForwardOpen) -> Opened {
        Opened {
            key: fo.key(),
            path: fo.path.clone(),
        }
    }
}

/// What a case changed on the target, as far as the scanner saw it.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub(super) struct Ledger {
    /// Attributes set, with their values before.
    written: ledger::Ledger<EPath>,
    /// Connections still open, in the order opened.
    opened: Vec<Opened>,
    /// An I/O (class 1) connection was opened: the drive may have moved, or faulted when the
    /// connection timed out.
    io: bool,
    /// An Identity Reset was made, or may have been: parameters written before it were read
    /// in.
    reset: bool,
}

impl Ledger {
    /// Whether the value of `path` must be read before the write about to be made: the first
    /// write of each attribute in the case.
    pub(super) fn wants_original(&self, path: &EPath) -> bool {
        self.written.wants_original(path)
    }

    /// The value of `path` before the case's first write of it.
    pub(super) fn original(&mut self, path: EPath, before: Result<Vec<u8>, String>) {
        self.written.original(path, before);
    }

    /// A write of `path` was sent; `accepted` when it may have taken effect (see
    /// [`may_have_taken_effect`]).
    pub(super) fn wrote(&mut self, path: &EPath, accepted: bool) {
        self.written.wrote(path, accepted);
    }

    /// A Forward_Open was accepted, or may have been.
    pub(super) fn opened(&mut self, fo: &ForwardOpen) {
        self.io |= fo.transport.class() == 1;
        self.opened.push(Opened::of(fo));
    }

    /// A Forward_Close was accepted.
    pub(super) fn closed(&mut self, key: ConnectionKey) {
        self.opened.retain(|o| o.key != key);
    }

    /// The attributes to write back, in the order to write them (the reverse of the first
    /// writes), each with its original value or why there is none.
    #[cfg(test)]
    fn restores(&self) -> impl Iterator<Item = (&EPath, Result<&[u8], &str>)> {
        self.written.restores()
    }
}

/// A request of a raw or structured EtherNet/IP step, as the ledger sees it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Noted {
    /// Set_Attribute_Single of this path.
    Set(EPath),
    /// Forward_Open or Large_Forward_Open.
    Open(Box<ForwardOpen>),
    /// Forward_Close of this connection.
    Close(ConnectionKey),
    /// Identity Reset of type 0.
    Reset,
}

impl Noted {
    /// What a message-router request as bytes does to the target, if the ledger cares.
    pub(super) fn of(request: &[u8]) -> Option<Noted> {
        let req = MrRequest::parse(request).ok()?;
        match Service(req.service) {
            Service::SET_ATTRIBUTE_SINGLE => Some(Noted::Set(req.path)),
            s @ (Service::FORWARD_OPEN | Service::LARGE_FORWARD_OPEN) => {
                let large = s == Service::LARGE_FORWARD_OPEN;
                let fo = ForwardOpen::parse(&req.data, large).ok()?;
                Some(Noted::Open(Box::new(fo)))
            }
            Service::FORWARD_CLOSE => {
                Some(Noted::Close(ForwardClose::parse(&req.data).ok()?.key()))
            }
            Service::RESET if req.path == identity() && matches!(req.data.as_slice(), [] | [0]) => {
                Some(Noted::Reset)
            }
            _ => None,
        }
    }
}

/// The Identity object's instance 1, which an Identity Reset addresses.
fn identity() -> EPath {
    EPath::object(class::IDENTITY, 1)
}

/// Marks the exchanges from `first` on with `tag`.
fn mark(exchanges: &mut [Exchange], first: usize, tag: &str) {
    for x in exchanges.iter_mut().skip(first) {
        x.sent = format!("{tag} {}", x.sent);
    }
}

/// Keeps the first two and the last of a long run of cleanup cycles.
fn shorten(exchanges: &mut Vec<Exchange>, from: usize) {
    let n = exchanges.len().saturating_sub(from);
    if n <= 4 {
        return;
    }
    let last = exchanges.pop();
    exchanges.truncate(from + 2);
    exchanges.push(Exchange {
        sent_hex: String::new(),
        sent: format!("… {} more cleanup exchanges …", n - 3),
        received_hex: String::new(),
        received: String::new(),
    });
    exchanges.extend(last);
}

/// Whether a request that got `resp` may have taken effect on the target: it was accepted, or
/// it went out and no answer the scanner could read came back (none in time, the connection
/// cut, a malformed reply, the reply of another service). A refusal did nothing, and so did a
/// request the scanner could not even build (a suite error).
pub(super) fn may_have_taken_effect(resp: Result<&MrResponse, &StepError>) -> bool {
    ledger::may_have_taken_effect(resp.map(|r| r.general == 0))
}

impl Scanner {
    /// Before a Set_Attribute_Single of `path`: the first in the case reads the value to put
    /// back (a network target only). Returns the path to pass to [`Scanner::after_set`]; a
    /// link error or time-out of the read, for a target that does not answer it would not
    /// answer the write either.
    pub(super) fn before_set(&mut self, path: &EPath) -> Result<Option<EPath>, StepError> {
        let Some(ledger) = self.ledger.as_ref() else {
            return Ok(None);
        };
        if !ledger.wants_original(path) {
            return Ok(Some(path.clone()));
        }
        // The session first, unmarked: the write would register it anyway.
        if let Err(e @ (StepError::Link(_) | StepError::Closed(_) | StepError::Late { .. })) =
            self.session(1)
        {
            return Err(e);
        }
        let first = self.exchanges.len();
        let read = self.explicit(&MrRequest {
            service: Service::GET_ATTRIBUTE_SINGLE.0,
            path: path.clone(),
            data: Vec::new(),
        });
        mark(
            &mut self.exchanges,
            first,
            "[cleanup: the value before the write]",
        );
        let before = match read {
            Err(e @ (StepError::Link(_) | StepError::Closed(_) | StepError::Late { .. })) => {
                return Err(e)
            }
            Err(e) => Err(e.to_string()),
            Ok(r) => match r.general {
                0 => Ok(r.data),
                g => Err(format!("Get_Attribute_Single: {}", GeneralStatus(g))),
            },
        };
        if let Some(ledger) = self.ledger.as_mut() {
            ledger.original(path.clone(), before);
        }
        Ok(Some(path.clone()))
    }

    /// After the Set_Attribute_Single of [`Scanner::before_set`], whatever came of it (called
    /// before an error ends the step: a write without a readable answer may have been made).
    pub(super) fn after_set(&mut self, path: Option<EPath>, resp: Result<&MrResponse, &StepError>) {
        if let (Some(ledger), Some(path)) = (self.ledger.as_mut(), path) {
            ledger.wrote(&path, may_have_taken_effect(resp));
        }
    }

    /// Before a message-router request of a step, as bytes.
    pub(super) fn before_request(&mut self, request: &[u8]) -> Result<Option<Noted>, StepError> {
        if self.ledger.is_none() {
            return Ok(None);
        }
        let Some(noted) = Noted::of(request) else {
            return Ok(None);
        };
        if let Noted::Set(path) = &noted {
            self.before_set(path)?;
        }
        Ok(Some(noted))
    }

    /// After the request of [`Scanner::before_request`], whatever came of it (called before an
    /// error ends the step). A Forward_Open without a readable answer counts as opened, a
    /// Forward_Close only accepted as closed.
    pub(super) fn after_request(
        &mut self,
        noted: Option<Noted>,
        resp: Result<&MrResponse, &StepError>,
    ) {
        let (Some(ledger), Some(noted)) = (self.ledger.as_mut(), noted) else {
            return;
        };
        match noted {
            Noted::Set(path) => ledger.wrote(&path, may_have_taken_effect(resp)),
            Noted::Open(fo) if may_have_taken_effect(resp) => ledger.opened(&fo),
            Noted::Close(key) if resp.is_ok_and(|r| r.general == 0) => ledger.closed(key),
            Noted::Reset if may_have_taken_effect(resp) => ledger.reset = true,
            _ => {}
        }
    }

    /// A Forward_Open of the scanner's own was accepted, or may have been.
    pub(super) fn note_opened(&mut self, fo: &ForwardOpen) {
        if let Some(ledger) = self.ledger.as_mut() {
            ledger.opened(fo);
        }
    }

    /// Leaves a network target as the case found it (the module's steps 1–5); `Ok` at once
    /// for the embedded adapter, which keeps no ledger. Stops at the first link error: what
    /// is left shows in the error as not attempted.
    pub(super) fn restore(&mut self) -> Result<(), String> {
        let Some(ledger) = self.ledger.take() else {
            return Ok(());
        };
        let mut account = Account::default();
        let commanded: Vec<Inverter> = (1..=8u8)
            .filter(|n| self.process[usize::from(*n)] != (0, Vec::new()))
            .filter_map(|n| Inverter::new(n.into()).ok())
            .collect();
        let drive = self.product.is_some() && ledger.io;
        self.run = true;
        if drive && self.io.is_some() && !commanded.is_empty() {
            let outcome = self
                .stop(&commanded)
                .map_err(|e| Problem::step("stopping the drive on the case's connection", e));
            account.note(outcome);
        }
        ledger
            .written
            .restore(&mut account, |path, before| self.put_back(path, before));
        if ledger.reset
            && ledger.written.restores().next().is_some()
            && account.attempt(|| "the Identity Reset that reads the restored values in".into())
        {
            let outcome = self.identity_reset();
            account.note(outcome);
        }
        self.io = None;
        self.close_each(&ledger.opened, &mut account);
        if drive {
            if account.attempt(|| "settling the drive".into()) {
                let (outcome, own) = self.settle(&commanded);
                account.note(outcome);
                self.close_each(&own, &mut account);
            }
            if account.attempt(|| "waiting for the end of cyclic communication".into()) {
                let outcome = self.quiet();
                account.note(outcome);
            }
        }
        if account.attempt(|| "UnRegisterSession".into()) {
            self.unregister();
        } else {
            // Gone with the link; not repeated when the scanner is dropped.
            self.sessions.clear();
        }
        account.into_result()
    }

    /// Step 1: 0400h to the commanded inverters over the case's open connection.
    fn stop(&mut self, commanded: &[Inverter]) -> Result<(), StepError> {
        for fi in commanded {
            self.process[usize::from(fi.get())] = (DISABLE, Vec::new());
        }
        let first = self.exchanges.len();
        let result = (0..STOP_CYCLES).try_for_each(|_| self.io_cycle().map(|_| ()));
        shorten(&mut self.exchanges, first);
        result
    }

    /// Step 2 for one attribute.
    fn put_back(&mut self, path: &EPath, before: &[u8]) -> Result<(), Problem> {
        let what = || format!("{path} not set back to [{}]", hex(before));
        let resp = self
            .explicit(&MrRequest {
                service: Service::SET_ATTRIBUTE_SINGLE.0,
                path: path.clone(),
                data: before.to_vec(),
            })
            .map_err(|e| Problem::step(what(), e))?;
        match resp.general {
            0 => Ok(()),
            g => Err(Problem::other(format!("{}: {}", what(), GeneralStatus(g)))),
        }
    }

    /// Step 2, last: an Identity Reset of type 0 (its connections end with it: those the case
    /// left open are then found gone in step 3).
    fn identity_reset(&mut self) -> Result<(), Problem> {
        let what = "the restored values not read in by an Identity Reset";
        let resp = self
            .explicit(&MrRequest {
                service: Service::RESET.0,
                path: identity(),
                data: Vec::new(),
            })
            .map_err(|e| Problem::step(what, e))?;
        match resp.general {
            0 => Ok(()),
            g => Err(Problem::other(format!("{what}: {}", GeneralStatus(g)))),
        }
    }

    /// Step 3, and the end of step 4: Forward_Close of each connection, the latest first.
    fn close_each(&mut self, opened: &[Opened], account: &mut Account) {
        for o in opened.iter().rev() {
            if account.attempt(|| format!("closing connection {:04X}h", o.key.0)) {
                let outcome = self.forward_close(o);
                account.note(outcome);
            }
        }
    }

    /// Forward_Close of `o`: `Ok` when closed, or already gone (by its time-out or with its
    /// owner).
    pub(super) fn forward_close(&mut self, o: &Opened) -> Result<(), Problem> {
        let fc = ForwardClose {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            serial: o.key.0,
            vendor: o.key.1,
            originator_serial: o.key.2,
            path: o.path.clone(),
        };
        let what = || format!("connection {:04X}h not closed", o.key.0);
        let r = self
            .explicit(&MrRequest {
                service: Service::FORWARD_CLOSE.0,
                path: EPath::object(class::CONNECTION_MANAGER, 1),
                data: fc.emit(),
            })
            .map_err(|e| Problem::step(what(), e))?;
        let gone = r.general == GeneralStatus::CONNECTION_FAILURE.0
            && r.extended.first() == Some(&ext::CONNECTION_NOT_FOUND);
        match r.general == 0 || gone {
            true => Ok(()),
            false => Err(Problem::other(format!(
                "{}: {} extended {:04X?}",
                what(),
                GeneralStatus(r.general),
                r.extended
            ))),
        }
    }

    /// Step 4: every inverter the case commanded, and every one in fault, to "Switch-on
    /// block" over a connection of the cleanup's own; returns the connections it opened, to
    /// close.
    fn settle(&mut self, commanded: &[Inverter]) -> (Result<(), Problem>, Vec<Opened>) {
        self.process = Default::default();
        // The cleanup's connection goes into a ledger of its own.
        self.ledger = Some(Ledger::default());
        let first = self.exchanges.len();
        let outcome = self.settle_cycles(commanded);
        shorten(&mut self.exchanges, first);
        self.io = None;
        let own = self.ledger.take().unwrap_or_default();
        (outcome, own.opened)
    }

    fn settle_cycles(&mut self, commanded: &[Inverter]) -> Result<(), Problem> {
        let what = |e: StepError| Problem::step("settling the drive", e);
        if self.io.is_none() {
            self.own_forward_open().map_err(what)?;
        }
        let asm = self.io.as_ref().and_then(|io| io.t_o).ok_or_else(|| {
            Problem::other("settling the drive: the connection has no input assembly".into())
        })?;
        let mut drives = Drives::new(asm.inverters, commanded);
        for n in 0..SETTLE_CYCLES {
            for (fi, control) in drives.controls(n) {
                self.process[usize::from(fi.get())] = (control, Vec::new());
            }
            let Some(data) = self.io_cycle().map_err(what)? else {
                continue;
            };
            for fi in drives.inverters() {
                let word = asm
                    .offset(fi)
                    .and_then(|off| data.get(off..off + 2))
                    .map(|w| u16::from_le_bytes([w[0], w[1]]));
                if let Some(w) = word {
                    drives.observe(fi, w);
                }
            }
            if drives.done() {
                return Ok(());
            }
        }
        Err(drives.stuck(RPI * SETTLE_CYCLES))
    }

    /// Step 4, last: waits until the bus status no longer shows cyclic communication.
    fn quiet(&mut self) -> Result<(), Problem> {
        let product = self
            .product
            .ok_or_else(|| Problem::other("no NORD product".into()))?;
        let (number, element) = match product.family() {
            Family::Integrated => (872, None),
            Family::Module => (173, ArrayElement::new(1).ok()),
        };
        let number = ParamNumber::new(number).map_err(|e| Problem::other(e.to_string()))?;
        let spec = OrderSpec {
            element,
            ..OrderSpec::read(Target::Interface, number)
        };
        let first = self.exchanges.len();
        let deadline = Deadline::after(QUIET_TIME);
        let outcome = loop {
            let v = match self.read(&spec) {
                Ok(v) => v.fields,
                Err(e) => break Err(Problem::step(format!("reading {}", spec.describe()), e)),
            };
            match v.get("value").and_then(Value::as_i64) {
                Some(w) if w & CYCLIC == 0 => break Ok(()),
                Some(w) if deadline.passed() => {
                    break Err(Problem::other(format!(
                        "{} still shows cyclic communication (bit 1) {QUIET_TIME:?} after the \
                         connections closed: {w:04X}h",
                        spec.describe()
                    )))
                }
                Some(_) => std::thread::sleep(QUIET_POLL),
                None => break Err(Problem::other(format!("reading {}: {v}", spec.describe()))),
            }
        };
        shorten(&mut self.exchanges, first);
        outcome
    }

    /// Step 5, and the scanner's last act when dropped: UnRegisterSession of every session; the
    /// target answers none and may close the connection (CIP Vol 2 §2-4.5), so neither counts
    /// as a problem.
    pub(super) fn unregister(&mut self) {
        for (client, session) in std::mem::take(&mut self.sessions) {
            let bye = EncapRepr {
                command: Command::UNREGISTER_SESSION.0,
                session,
                ..EncapRepr::default()
            };
            let Ok(bytes) = bye.emit() else { continue };
            let wait = self.wait();
            let reply = self.link.request(client, &bytes, &wait);
            let client_note = if client == 1 {
                String::new()
            } else {
                format!("[client {client}] ")
            };
            self.exchanges.push(Exchange {
                sent_hex: hex(&bytes),
                sent: format!("{client_note}UnRegisterSession"),
                received_hex: match &reply {
                    Ok(Some(b)) => hex(b),
                    _ => String::new(),
                },
                received: match reply {
                    Ok(Some(_)) => "an answer, where none is due".into(),
                    Ok(None) => "(nothing, as due)".into(),
                    Err(e) => format!("(nothing: {e})"),
                },
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::link::{Embedded, EnipLink, LinkError};
    use super::super::scanner::{EMBEDDED_ADDR, ORIGINATOR_SERIAL, VENDOR};
    use super::*;
    use proto::enip::cm::{NetParams, Transport};
    use proto::enip::cpf::Item;
    use proto::enip::encap::SendData;
    use proto::nord::Product;
    use serde_json::json;
    use sim::device::{Device, DeviceConfig};
    use sim::enip::Adapter;
    use std::cell::{Cell, RefCell};
    use std::rc::Rc;

    fn param(n: u16) -> EPath {
        EPath::attribute(101, 1, n)
    }

    #[test]
    fn only_the_first_write_of_an_attribute_reads_its_value() {
        let mut l = Ledger::default();
        assert!(l.wants_original(&param(102)));
        l.original(param(102), Ok(vec![0xC8, 0x00]));
        assert!(!l.wants_original(&param(102)));
        // A second original (a later write) does not replace the first.
        l.original(param(102), Ok(vec![0xE8, 0x03]));
        l.wrote(&param(102), true);
        l.wrote(&param(102), true);
        let r: Vec<_> = l.restores().collect();
        assert_eq!(r, vec![(&param(102), Ok(&[0xC8u8, 0x00][..]))]);
    }

    #[test]
    fn restores_run_in_reverse_order_of_the_first_writes_and_skip_refused_ones() {
        let mut l = Ledger::default();
        for (n, v) in [(102, 1u8), (165, 2), (151, 3), (166, 4)] {
            l.original(param(n), Ok(vec![v, 0]));
        }
        l.wrote(&param(102), true);
        l.wrote(&param(165), true);
        l.wrote(&param(151), false); // refused: the value did not change
        l.wrote(&param(166), true);
        l.wrote(&param(102), false); // a later refusal does not undo the earlier change
        let order: Vec<u16> = l
            .restores()
            .map(|(p, _)| p.attribute_id().unwrap())
            .collect();
        assert_eq!(order, vec![166, 165, 102]);
    }

    #[test]
    fn an_unreadable_original_is_reported_when_the_write_was_accepted() {
        let mut l = Ledger::default();
        l.original(param(900), Err("Get_Attribute_Single: 14h".into()));
        assert_eq!(l.restores().count(), 0);
        l.wrote(&param(900), true);
        let r: Vec<_> = l.restores().collect();
        assert_eq!(r, vec![(&param(900), Err("Get_Attribute_Single: 14h"))]);
    }

    fn forward_open(serial: u16, transport: Transport) -> ForwardOpen {
        let np = NetParams {
            size: 18,
            variable: false,
            priority: 0,
            kind: 2,
            redundant_owner: false,
        };
        ForwardOpen {
            large: false,
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            o_t_id: 0,
            t_o_id: 1,
            serial,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            timeout_multiplier: 2,
            o_t_rpi: 4000,
            o_t: np,
            t_o_rpi: 4000,
            t_o: np,
            transport,
            path: EPath::io_connection(100, 101),
        }
    }

    #[test]
    fn connections_are_kept_until_closed_and_io_marks_the_drive() {
        let mut l = Ledger::default();
        l.opened(&forward_open(7, Transport::CLASS3));
        assert!(!l.io, "an explicit connection does not touch the drive");
        l.opened(&forward_open(8, Transport::CLASS1_CYCLIC));
        assert!(l.io);
        l.closed(forward_open(7, Transport::CLASS3).key());
        let keys: Vec<u16> = l.opened.iter().map(|o| o.key.0).collect();
        assert_eq!(keys, vec![8]);
        assert_eq!(l.opened[0].path.connection_points(), vec![100, 101]);
    }

    #[test]
    fn requests_as_bytes_are_noted_by_service() {
        // Set_Attribute_Single class 64h instance 1 attribute 66h (P102 of FI 1... as bytes).
        let set = [0x10, 0x03, 0x20, 0x65, 0x24, 0x01, 0x30, 0x66, 0xE8, 0x03];
        assert_eq!(
            Noted::of(&set),
            Some(Noted::Set(EPath::attribute(0x65, 1, 0x66)))
        );
        // The duplicate-forward-open case's Forward_Open (suites/cip/connection-manager.yaml).
        let fo = forward_open(0x7701, Transport::CLASS1_CYCLIC);
        let mut bytes = vec![0x54, 0x02, 0x20, 0x06, 0x24, 0x01];
        bytes.extend(fo.emit());
        assert_eq!(Noted::of(&bytes), Some(Noted::Open(Box::new(fo.clone()))));
        let fc = ForwardClose {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            serial: 0x7701,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            path: EPath::object(class::ASSEMBLY, 1),
        };
        let mut bytes = vec![0x4E, 0x02, 0x20, 0x06, 0x24, 0x01];
        bytes.extend(fc.emit());
        assert_eq!(Noted::of(&bytes), Some(Noted::Close(fo.key())));
        // An Identity Reset of type 0, as the P852 read-in case makes it; one of type 1 (the
        // harness never sends it), a Get, a reset of another object, a malformed request:
        // nothing to note.
        assert_eq!(
            Noted::of(&[0x05, 0x02, 0x20, 0x01, 0x24, 0x01]),
            Some(Noted::Reset)
        );
        assert_eq!(Noted::of(&[0x05, 0x02, 0x20, 0x01, 0x24, 0x01, 0x01]), None);
        assert_eq!(
            Noted::of(&[0x0E, 0x03, 0x20, 0x01, 0x24, 0x01, 0x30, 0x01]),
            None
        );
        assert_eq!(Noted::of(&[0x05, 0x02, 0x20, 0xF5, 0x24, 0x01]), None);
        assert_eq!(Noted::of(&[0x10]), None);
    }

    #[test]
    fn long_cleanup_runs_are_shortened_in_the_transcript() {
        let x = |i: usize| Exchange {
            sent_hex: format!("{i}"),
            sent: format!("cycle {i}"),
            received_hex: String::new(),
            received: String::new(),
        };
        let mut v: Vec<Exchange> = (0..10).map(x).collect();
        shorten(&mut v, 1);
        let sent: Vec<&str> = v.iter().map(|e| e.sent.as_str()).collect();
        assert_eq!(
            sent,
            vec![
                "cycle 0",
                "cycle 1",
                "cycle 2",
                "… 6 more cleanup exchanges …",
                "cycle 9"
            ]
        );
        mark(&mut v, 4, "[cleanup]");
        assert_eq!(v[4].sent, "[cleanup] cycle 9");
    }

    /// Each request a link sent, with its reply if one came.
    type Log = Vec<(Vec<u8>, Option<Vec<u8>>)>;

    /// The embedded adapter behind a link that loses replies: those to the message-router
    /// services in `lose` (the adapter still carries the requests out), and, once `hung`,
    /// every one, as a target that stopped answering. Counts and logs the requests.
    struct Lossy {
        inner: Embedded,
        lose: Rc<RefCell<Vec<u8>>>,
        hung: Rc<Cell<bool>>,
        log: Rc<RefCell<Log>>,
    }

    /// The message-router request in a SendRRData `msg`, or the reply in its answer.
    fn routed(msg: &[u8]) -> Option<Vec<u8>> {
        let e = EncapRepr::parse(msg).ok()?;
        match SendData::parse(&e.data).ok()?.cpf.items.get(1)? {
            Item::UnconnectedData(p) => Some(p.clone()),
            _ => None,
        }
    }

    impl EnipLink for Lossy {
        fn describe(&self) -> String {
            "the embedded adapter, losing replies".into()
        }

        fn request(
            &mut self,
            client: u8,
            msg: &[u8],
            wait: &Deadline,
        ) -> Result<Option<Vec<u8>>, LinkError> {
            let reply = match self.hung.get() {
                true => Ok(None),
                false => self.inner.request(client, msg, wait),
            };
            let service = routed(msg).and_then(|r| r.first().copied());
            let lost = service.is_some_and(|s| self.lose.borrow().contains(&s));
            let reply = reply.map(|r| r.filter(|_| !lost));
            let logged = reply.as_ref().ok().cloned().flatten();
            self.log.borrow_mut().push((msg.to_vec(), logged));
            reply
        }

        fn io_cycle(
            &mut self,
            datagram: Option<&[u8]>,
            rpi: Duration,
        ) -> Result<Vec<Vec<u8>>, LinkError> {
            match self.hung.get() {
                true => Ok(Vec::new()),
                false => self.inner.io_cycle(datagram, rpi),
            }
        }

        fn adapter(&mut self) -> Option<(&mut Adapter, Duration)> {
            self.inner.adapter()
        }
    }

    struct Rig {
        scanner: Scanner,
        lose: Rc<RefCell<Vec<u8>>>,
        hung: Rc<Cell<bool>>,
        log: Rc<RefCell<Log>>,
    }

    impl Rig {
        /// An SK 550P kept like a network target (with a ledger), losing the replies to
        /// `lose`.
        fn new(lose: &[Service]) -> Rig {
            let product = Product::Sk550p;
            let adapter = Adapter::new(Device::new(DeviceConfig::new(product)), EMBEDDED_ADDR);
            let lose = Rc::new(RefCell::new(lose.iter().map(|s| s.0).collect()));
            let hung = Rc::new(Cell::new(false));
            let log = Rc::new(RefCell::new(Vec::new()));
            let link = Lossy {
                inner: Embedded::new(adapter, EMBEDDED_ADDR, None),
                lose: Rc::clone(&lose),
                hung: Rc::clone(&hung),
                log: Rc::clone(&log),
            };
            let mut scanner = Scanner::new(Box::new(link), Some(product), Vec::new());
            scanner.ledger = Some(Ledger::default());
            Rig {
                scanner,
                lose,
                hung,
                log,
            }
        }

        /// The message-router requests sent of `service`, each with its reply if one came.
        fn routed(&self, service: Service) -> Vec<(MrRequest, Option<MrResponse>)> {
            routed_of(&self.log.borrow(), service)
        }
    }

    /// The message-router requests in `log` of `service`, each with its reply if one came.
    fn routed_of(log: &Log, service: Service) -> Vec<(MrRequest, Option<MrResponse>)> {
        log.iter()
            .filter_map(|(m, r)| {
                let req = MrRequest::parse(&routed(m)?).ok()?;
                let resp = r.as_deref().and_then(routed);
                let resp = resp.and_then(|p| MrResponse::parse(&p).ok());
                (req.service == service.0).then_some((req, resp))
            })
            .collect()
    }

    fn p102(value: Option<i64>) -> OrderSpec {
        let fi1 = Target::Inverter(Inverter::new(1).unwrap());
        OrderSpec {
            value,
            ..OrderSpec::read(fi1, ParamNumber::new(102).unwrap())
        }
    }

    #[test]
    fn a_write_whose_reply_was_lost_is_set_back() {
        let mut r = Rig::new(&[Service::SET_ATTRIBUTE_SINGLE]);
        let before = r.scanner.read(&p102(None)).unwrap().fields["value"].clone();
        assert_ne!(before, json!(9999));
        let e = r.scanner.write(&p102(Some(9999))).unwrap_err();
        assert!(matches!(e, StepError::Link(_)), "{e}");
        assert_eq!(
            r.scanner.read(&p102(None)).unwrap().fields["value"],
            json!(9999),
            "the adapter took the write"
        );
        r.lose.borrow_mut().clear();
        r.scanner.restore().unwrap();
        let sets = r.routed(Service::SET_ATTRIBUTE_SINGLE);
        let (last, resp) = sets.last().unwrap();
        assert_eq!(sets.len(), 2);
        let value = i64::from(u16::from_le_bytes([last.data[0], last.data[1]]));
        assert_eq!(json!(value), before, "set back to the value before");
        assert_eq!(resp.as_ref().map(|r| r.general), Some(0));
    }

    #[test]
    fn a_forward_open_whose_reply_was_lost_is_closed() {
        let mut r = Rig::new(&[Service::FORWARD_OPEN]);
        let e = r.scanner.own_forward_open().unwrap_err();
        assert!(matches!(e, StepError::Link(_)), "{e}");
        let ledger = r.scanner.ledger.as_ref().unwrap();
        assert!(ledger.io);
        let lost = ledger.opened.clone();
        assert_eq!(lost.len(), 1);
        r.lose.borrow_mut().clear();
        r.scanner.restore().unwrap();
        let closes = r.routed(Service::FORWARD_CLOSE);
        let (first, resp) = closes.first().unwrap();
        let fc = ForwardClose::parse(&first.data).unwrap();
        assert_eq!((fc.key(), fc.path), (lost[0].key, lost[0].path.clone()));
        assert_eq!(resp.as_ref().map(|r| r.general), Some(0), "it was open");
        let (adapter, _) = r.scanner.link.adapter().unwrap();
        assert_eq!(adapter.connection_counts(), (0, 0, 0));
    }

    #[test]
    fn a_target_that_does_not_answer_costs_a_write_one_time_out() {
        let mut r = Rig::new(&[]);
        r.hung.set(true);
        let e = r.scanner.write(&p102(Some(9999))).unwrap_err();
        assert!(matches!(e, StepError::Link(_)), "{e}");
        assert_eq!(r.log.borrow().len(), 1, "the RegisterSession only");
        assert!(r.scanner.ledger.as_ref().unwrap().written.is_empty());
    }

    #[test]
    fn the_cleanup_stops_at_its_first_link_error() {
        let mut r = Rig::new(&[]);
        r.scanner.read(&p102(None)).unwrap();
        let ledger = r.scanner.ledger.as_mut().unwrap();
        for n in [102, 103, 104] {
            ledger.original(param(n), Ok(vec![1, 0]));
            ledger.wrote(&param(n), true);
        }
        ledger.opened(&forward_open(7, Transport::CLASS3));
        r.hung.set(true);
        let sent = r.log.borrow().len();
        let e = r.scanner.restore().unwrap_err();
        assert_eq!(r.log.borrow().len(), sent + 1, "{e}");
        assert_eq!(
            e,
            "class 101 / instance 1 / attribute 104 not set back to [01 00]: link error: no reply \
             to Set_Attribute_Single; not attempted after the link error: setting back class \
             101 / instance 1 / attribute 103, setting back class 101 / instance 1 / attribute \
             102, closing connection 0007h, UnRegisterSession"
        );
        assert!(r.scanner.sessions.is_empty());
    }

    #[test]
    fn a_case_that_reset_the_device_resets_it_again_after_its_write_backs() {
        use super::super::step::EnipStep;
        let mut r = Rig::new(&[]);
        // The P852 read-in case: the SK 550P's gateway P852 [-01] set, read in by a Reset.
        let p852 = OrderSpec {
            element: ArrayElement::new(1).ok(),
            value: Some(192),
            ..OrderSpec::read(Target::Interface, ParamNumber::new(852).unwrap())
        };
        r.scanner.write(&p852).unwrap();
        let reset = EnipStep::Request {
            service: Service::RESET.0,
            path: vec![0x20, 0x01, 0x24, 0x01],
            data: Vec::new(),
            client: 1,
        };
        r.scanner.enip_step(&reset).unwrap();
        // The TCP/IP object's gateway, asked by `client` (the cleanup ends the scanner's own
        // session).
        let gateway = |r: &mut Rig, client| {
            let get = MrRequest {
                service: Service::GET_ATTRIBUTE_SINGLE.0,
                path: EPath::attribute(class::TCP_IP, 1, 5),
                data: Vec::new(),
            };
            let resp = r.scanner.unconnected(client, get.emit(), "gateway".into());
            resp.unwrap().data[8..12].to_vec()
        };
        // 192.0.0.0 as a UDINT, little-endian.
        assert_eq!(gateway(&mut r, 1), [0, 0, 0, 192]);
        r.scanner.restore().unwrap();
        assert_eq!(r.routed(Service::RESET).len(), 2);
        let read_in = gateway(&mut r, 2);
        assert_eq!(read_in, [0, 0, 0, 0], "read in again after the write-back");
    }

    #[test]
    fn dropping_the_scanner_closes_its_connection_with_the_path_it_opened_it_with() {
        let mut r = Rig::new(&[]);
        r.scanner.ledger = None;
        r.scanner.io_cycle().unwrap();
        let log = Rc::clone(&r.log);
        let opens = r.routed(Service::FORWARD_OPEN);
        drop(r);
        let fo = ForwardOpen::parse(&opens[0].0.data, false).unwrap();
        let closes = routed_of(&log.borrow(), Service::FORWARD_CLOSE);
        assert_eq!(closes.len(), 1);
        let fc = ForwardClose::parse(&closes[0].0.data).unwrap();
        assert_eq!((fc.key(), fc.path), (fo.key(), fo.path));
        assert_eq!(closes[0].1.as_ref().map(|r| r.general), Some(0));
        let last = log.borrow().last().cloned().unwrap();
        let bye = EncapRepr::parse(&last.0).unwrap();
        assert_eq!(Command(bye.command), Command::UNREGISTER_SESSION);
    }
}
