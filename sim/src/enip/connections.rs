//! Connections: Forward_Open/Forward_Close, class-1 I/O on the assemblies, class-3 explicit
//! connections, and the watchdogs that end them.
//!
//! BU 0620 §2.3.4 and BU 2100 §6.2: "1 Exclusive Owner, 2 Listen Only". A listen-only
//! connection needs an owner to listen to (CIP: extended status 0119h otherwise) and ends with
//! it. An owner whose O→T data stops for its timeout (RPI · 4 << multiplier) is closed, the NS
//! LED flashes red, and the inverters raise E10.2 "EtherNet/IP watchdog timeout" unless
//! monitoring is off (BU 2100 §7.1.1 P151 = -1; SK 550P: P513 [-04] off).

use std::net::SocketAddr;
use std::time::Duration;

use proto::enip::cip::{class, GeneralStatus as GS, MrRequest, MrResponse, Service};
use proto::enip::cm::{
    ext, failure_data, forward_close_reply, kind, ConnectionKey, ForwardClose, ForwardOpen,
    ForwardOpenReply,
};
use proto::enip::epath::Segment;
use proto::enip::io::{IoFrame, IO_PORT};
use proto::nord::eip::{
    self, Assembly, Direction, LISTEN_ONLY_POINT, RPI_RANGE, WORDS_PER_INVERTER,
};
use proto::nord::{Family, Inverter};
use proto::wire::Error;

use super::objects;
use super::{Adapter, ClientId};
use crate::drive::FaultCode;
use crate::link::Unit;

/// Class-3 (explicit) connections the adapter accepts at once.
pub(crate) const MAX_EXPLICIT: usize = 6;
/// Listen-only connections (BU 0620 §2.3.1: "2 Listen Only").
pub(crate) const MAX_LISTEN_ONLY: usize = eip::LISTEN_ONLY_MAX;

const E10_2: FaultCode = FaultCode { group: 10, sub: 2 };

/// A class-1 datagram the adapter could not use.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IoError {
    /// Malformed datagram.
    #[error("malformed I/O frame: {0}")]
    Malformed(#[from] Error),
    /// No open connection has this O→T id.
    #[error("no connection with O→T id {0:08X}h")]
    UnknownConnection(u32),
    /// The data length differs from the connection's size.
    #[error("I/O data of {got} bytes on a connection of {want}")]
    WrongLength {
        /// The connection's data length.
        want: usize,
        /// What arrived.
        got: usize,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Owner,
    ListenOnly,
    Explicit,
}

#[derive(Debug, Clone)]
struct Conn {
    key: ConnectionKey,
    kind: Kind,
    client: ClientId,
    o_t_id: u32,
    t_o_id: u32,
    t_o_rpi: Duration,
    timeout: Duration,
    last_rx: Duration,
    next_tx: Duration,
    o_t_asm: Option<&'static Assembly>,
    t_o_asm: Option<&'static Assembly>,
    o_t_len: usize,
    t_o_len: usize,
    run_idle: bool,
    dest: SocketAddr,
    t_o_seq: u32,
    t_o_count: u16,
    last_count: Option<u16>,
}

/// The connection table and the data the assemblies hold.
#[derive(Debug, Default)]
pub(super) struct Table {
    conns: Vec<Conn>,
    next_id: u32,
    timed_out: bool,
    /// Latest status word and actual values per FI 1..8.
    inputs: [[u16; WORDS_PER_INVERTER]; 8],
    /// Last data consumed per output assembly.
    outputs: Vec<(u16, Vec<u8>)>,
}

impl Table {
    fn id(&mut self) -> u32 {
        self.next_id = self.next_id.wrapping_add(1);
        0x4E00_0000 | (self.next_id & 0x00FF_FFFF)
    }

    pub(super) fn client_closed(&mut self, client: ClientId) {
        self.conns
            .retain(|c| !(c.kind == Kind::Explicit && c.client == client));
    }

    /// Whether a connection opened by `client` is open.
    pub(super) fn any_of(&self, client: ClientId) -> bool {
        self.conns.iter().any(|c| c.client == client)
    }

    /// A class-3 message on O→T id `id` from `client`: its T→O id, watchdog refreshed.
    pub(super) fn explicit(&mut self, id: u32, client: ClientId, now: Duration) -> Option<u32> {
        let c = self
            .conns
            .iter_mut()
            .find(|c| c.kind == Kind::Explicit && c.o_t_id == id && c.client == client)?;
        c.last_rx = now;
        Some(c.t_o_id)
    }

    pub(super) fn next_due(&self) -> Option<Duration> {
        self.conns
            .iter()
            .filter(|c| c.t_o_asm.is_some())
            .map(|c| c.next_tx)
            .chain(self.conns.iter().map(|c| c.last_rx + c.timeout))
            .min()
    }

    pub(super) fn any_open(&self) -> bool {
        !self.conns.is_empty()
    }

    pub(super) fn owner_timed_out(&self) -> bool {
        self.timed_out
    }

    pub(super) fn counts(&self) -> (usize, usize, usize) {
        let n = |k| self.conns.iter().filter(|c| c.kind == k).count();
        (n(Kind::Owner), n(Kind::ListenOnly), n(Kind::Explicit))
    }

    fn has_owner(&self) -> bool {
        self.conns.iter().any(|c| c.kind == Kind::Owner)
    }

    fn remove(&mut self, key: ConnectionKey) -> Option<Conn> {
        let i = self.conns.iter().position(|c| c.key == key)?;
        let c = self.conns.remove(i);
        if c.kind == Kind::Owner {
            self.conns.retain(|c| c.kind != Kind::ListenOnly);
        }
        Some(c)
    }
}

fn refuse(req: &MrRequest, key: ConnectionKey, extended: Vec<u16>) -> MrResponse {
    MrResponse {
        service: req.service,
        general: GS::CONNECTION_FAILURE.0,
        extended,
        data: failure_data(key),
    }
}

/// P166 where the product has it (0 = run/idle header), else 0 ([`eip::transmission_format`]).
fn p166(a: &mut Adapter) -> i32 {
    let Some(n) = eip::transmission_format(a.product()) else {
        return 0;
    };
    a.device
        .store(Unit::Interface)
        .ok()
        .and_then(|s| s.read(n, None, None).ok())
        .unwrap_or(0)
}

/// Forward_Open and Large_Forward_Open.
pub(super) fn forward_open(
    a: &mut Adapter,
    client: ClientId,
    peer: SocketAddr,
    req: &MrRequest,
    now: Duration,
) -> MrResponse {
    let large = Service(req.service) == Service::LARGE_FORWARD_OPEN;
    let fo = match ForwardOpen::parse(&req.data, large) {
        Ok(f) => f,
        Err(Error::Truncated { .. }) => return MrResponse::error(req.service, GS::NOT_ENOUGH_DATA),
        Err(Error::Trailing { .. }) => return MrResponse::error(req.service, GS::TOO_MUCH_DATA),
        Err(_) => {
            let key = forward_open_key(&req.data);
            return refuse(req, key, vec![ext::INVALID_SEGMENT]);
        }
    };
    let key = fo.key();
    match open(a, client, peer, &fo, now) {
        Ok(reply) => MrResponse::ok(req.service, reply.emit()),
        Err(extended) => refuse(req, key, extended),
    }
}

/// The connection triple of a Forward_Open whose path did not parse (bytes 10..18).
fn forward_open_key(data: &[u8]) -> ConnectionKey {
    let g = |r: std::ops::Range<usize>| data.get(r).map(<[u8]>::to_vec).unwrap_or_default();
    let u16_at = |i| {
        let b = g(i..i + 2);
        if b.len() == 2 {
            u16::from_le_bytes([b[0], b[1]])
        } else {
            0
        }
    };
    let s = g(14..18);
    let orig = if s.len() == 4 {
        u32::from_le_bytes([s[0], s[1], s[2], s[3]])
    } else {
        0
    };
    (u16_at(10), u16_at(12), orig)
}

fn open(
    a: &mut Adapter,
    client: ClientId,
    peer: SocketAddr,
    fo: &ForwardOpen,
    now: Duration,
) -> Result<ForwardOpenReply, Vec<u16>> {
    let key = fo.key();
    if a.conns.conns.iter().any(|c| c.key == key) {
        return Err(vec![ext::CONNECTION_IN_USE]);
    }
    if fo.timeout_multiplier > 7 {
        return Err(vec![ext::TIMEOUT_MULTIPLIER_NOT_ACCEPTABLE]);
    }
    check_key(a, fo)?;
    let class_path = fo.path.class_id();
    let transport = fo.transport;
    let kind_ = match transport.class() {
        3 => Kind::Explicit,
        1 => Kind::Owner,
        _ => return Err(vec![ext::TRANSPORT_CLASS_NOT_SUPPORTED]),
    };
    if kind_ == Kind::Owner && transport.trigger() != 0 {
        return Err(vec![ext::TRIGGER_NOT_SUPPORTED]);
    }
    for rpi in [fo.o_t_rpi, fo.t_o_rpi] {
        if !RPI_RANGE.contains(&rpi) {
            return Err(vec![ext::RPI_NOT_SUPPORTED]);
        }
    }
    if fo.o_t.kind != kind::POINT_TO_POINT {
        return Err(vec![ext::INVALID_O_T_TYPE]);
    }
    if !matches!(fo.t_o.kind, kind::POINT_TO_POINT | kind::MULTICAST) {
        return Err(vec![ext::INVALID_T_O_TYPE]);
    }
    let o_t_id = a.conns.id();
    let t_o_id = if fo.t_o.kind == kind::MULTICAST {
        a.conns.id()
    } else {
        fo.t_o_id
    };
    let timeout = Duration::from_micros(fo.timeout_us());
    let base = Conn {
        key,
        kind: kind_,
        client,
        o_t_id,
        t_o_id,
        t_o_rpi: Duration::from_micros(u64::from(fo.t_o_rpi)),
        timeout,
        last_rx: now,
        next_tx: now,
        o_t_asm: None,
        t_o_asm: None,
        o_t_len: 0,
        t_o_len: 0,
        run_idle: false,
        dest: SocketAddr::new(peer.ip(), IO_PORT),
        t_o_seq: 0,
        t_o_count: 0,
        last_count: None,
    };
    let conn = if kind_ == Kind::Explicit {
        let to_router = class_path == Some(class::MESSAGE_ROUTER)
            && fo.path.instance_id() == Some(1)
            && fo.path.connection_points().is_empty();
        if !to_router {
            return Err(vec![ext::INVALID_CONSUMING_PATH]);
        }
        if a.conns.counts().2 >= MAX_EXPLICIT {
            return Err(vec![ext::OUT_OF_CONNECTIONS]);
        }
        base
    } else {
        io_connection(a, fo, base)?
    };
    let reply = ForwardOpenReply {
        o_t_id,
        t_o_id,
        serial: fo.serial,
        vendor: fo.vendor,
        originator_serial: fo.originator_serial,
        o_t_api: fo.o_t_rpi,
        t_o_api: fo.t_o_rpi,
    };
    if conn.kind == Kind::Owner {
        a.conns.timed_out = false;
        a.device.set_fieldbus_timeout(false);
        let consumed = conn.o_t_asm.map_or(0, |x| x.instance);
        let produced = conn.t_o_asm.map_or(0, |x| x.instance);
        objects::show_active_assembly(a, consumed, produced);
    }
    a.conns.conns.push(conn);
    Ok(reply)
}

/// The electronic key, when the path has one (zero fields match anything).
fn check_key(a: &Adapter, fo: &ForwardOpen) -> Result<(), Vec<u16>> {
    let id = &a.identity;
    for s in &fo.path.segments {
        if let Segment::Key(k) = s {
            if (k.vendor != 0 && k.vendor != id.vendor)
                || (k.product_code != 0 && k.product_code != id.product_code)
            {
                return Err(vec![ext::VENDOR_OR_PRODUCT_MISMATCH]);
            }
            if k.device_type != 0 && k.device_type != id.device_type {
                return Err(vec![ext::DEVICE_TYPE_MISMATCH]);
            }
            if k.major & 0x7F != 0 && k.major & 0x7F != id.revision.0 {
                return Err(vec![ext::REVISION_MISMATCH]);
            }
        }
    }
    Ok(())
}

/// Checks an I/O connection's path and sizes against the product's assemblies.
fn io_connection(a: &mut Adapter, fo: &ForwardOpen, mut c: Conn) -> Result<Conn, Vec<u16>> {
    let product = a.product();
    if fo.path.class_id() != Some(class::ASSEMBLY)
        || fo.path.segments.iter().any(|s| {
            !matches!(
                s,
                Segment::Key(_)
                    | Segment::Class(_)
                    | Segment::Instance(_)
                    | Segment::ConnectionPoint(_)
                    | Segment::Data(_)
                    | Segment::Port { .. }
            )
        })
    {
        return Err(vec![ext::INVALID_SEGMENT]);
    }
    // `20 04 24 cfg 2C o→t 2C t→o`, or the instance segments standing for the points.
    let mut points = fo.path.connection_points();
    if points.is_empty() {
        points = fo
            .path
            .segments
            .iter()
            .filter_map(|s| match s {
                Segment::Instance(i) => u16::try_from(*i).ok(),
                _ => None,
            })
            .skip(1)
            .collect();
    }
    let [o_t, t_o] = points[..] else {
        return Err(vec![ext::INVALID_SEGMENT]);
    };
    let t_o_asm = eip::assembly(product, t_o)
        .filter(|x| x.direction == Direction::Input)
        .ok_or(vec![ext::INVALID_PRODUCING_PATH])?;
    let t_o_len = eip::connection_data(fo.t_o.size, false)
        .map(usize::from)
        .filter(|n| t_o_asm.accepts(*n))
        .ok_or(vec![
            ext::INVALID_T_O_SIZE,
            eip::connection_size(t_o_asm.len, false),
        ])?;
    if o_t == LISTEN_ONLY_POINT {
        c.kind = Kind::ListenOnly;
        // Heartbeats: the sequence count alone, or a size of 0.
        let heartbeat = eip::connection_size(0, false);
        if fo.o_t.size != 0 && fo.o_t.size != heartbeat {
            return Err(vec![ext::INVALID_O_T_SIZE, heartbeat]);
        }
        if !a.conns.has_owner() {
            return Err(vec![ext::NON_LISTEN_ONLY_NOT_OPENED]);
        }
        if a.conns.counts().1 >= MAX_LISTEN_ONLY {
            return Err(vec![ext::TARGET_OUT_OF_CONNECTIONS]);
        }
    } else {
        let o_t_asm = eip::assembly(product, o_t)
            .filter(|x| x.direction == Direction::Output)
            .ok_or(vec![ext::INVALID_CONSUMING_PATH])?;
        let run_idle = eip::o_t_run_idle(product, o_t, p166(a));
        let o_t_len = eip::connection_data(fo.o_t.size, run_idle)
            .map(usize::from)
            .filter(|n| o_t_asm.accepts(*n))
            .ok_or(vec![
                ext::INVALID_O_T_SIZE,
                eip::connection_size(o_t_asm.len, run_idle),
            ])?;
        if a.conns.has_owner() {
            return Err(vec![ext::OWNERSHIP_CONFLICT]);
        }
        c.o_t_asm = Some(o_t_asm);
        c.o_t_len = o_t_len;
        c.run_idle = run_idle;
    }
    c.t_o_asm = Some(t_o_asm);
    c.t_o_len = t_o_len;
    Ok(c)
}

/// Forward_Close.
pub(super) fn forward_close(a: &mut Adapter, req: &MrRequest) -> MrResponse {
    let fc = match ForwardClose::parse(&req.data) {
        Ok(f) => f,
        Err(Error::Truncated { .. }) => return MrResponse::error(req.service, GS::NOT_ENOUGH_DATA),
        Err(Error::Trailing { .. }) => return MrResponse::error(req.service, GS::TOO_MUCH_DATA),
        Err(_) => return refuse(req, forward_open_key(&[]), vec![ext::INVALID_SEGMENT]),
    };
    match a.conns.remove(fc.key()) {
        Some(c) => {
            if c.kind == Kind::Owner {
                objects::show_active_assembly(a, 0, 0);
            }
            MrResponse::ok(req.service, forward_close_reply(fc.key()))
        }
        None => refuse(req, fc.key(), vec![ext::CONNECTION_NOT_FOUND]),
    }
}

/// Ends every connection and forgets a time-out (Identity Reset emulates a power cycle: NS
/// starts again flashing green, "no CIP connection").
pub(super) fn close_all(a: &mut Adapter) {
    a.conns.conns.clear();
    a.conns.timed_out = false;
}

/// The inverter in slot `n` (1-based) of an assembly, if the device has it.
fn slot(n: usize) -> Option<Inverter> {
    Inverter::new(n as i64).ok()
}

/// Applies output data (O→T or a Set_Attribute_Single on an output assembly) to the inverters.
fn apply_outputs(a: &mut Adapter, asm: &Assembly, data: &[u8], run: bool, now: Duration) {
    let inverters = usize::from(a.device.config().inverters);
    a.device.tick(now);
    for n in 1..=usize::from(asm.inverters).min(inverters) {
        let Some(fi) = slot(n) else { continue };
        let Some(off) = asm.offset(fi) else { continue };
        let mut words: Vec<u16> = data
            .get(off..data.len().min(off + WORDS_PER_INVERTER * 2))
            .unwrap_or_default()
            .chunks_exact(2)
            .map(|w| u16::from_le_bytes([w[0], w[1]]))
            .collect();
        let Some(control) = words.first_mut() else {
            continue;
        };
        // Idle (PLC in program mode) counts as an invalid control word (bit 10 clear).
        if !run {
            *control = 0;
        }
        if let Ok(out) = a.device.process_monitored(fi, words[0], &words[1..], now) {
            // P873 / P874 (BU 0620 §4.3) show the words exchanged, as on the other buses.
            a.device.show_process_data(fi, None, &words, &out);
            let dst = &mut a.conns.inputs[n - 1];
            *dst = [0; WORDS_PER_INVERTER];
            for (d, s) in dst.iter_mut().zip(out) {
                *d = s;
            }
        }
    }
    // The interface word of 110 sets the SK xU4-EIP's outputs (BU 2100 §6.2.1, p. 32).
    if let (true, Some([lo, hi])) = (asm.io_word, data.get(..2)) {
        a.device.set_module_outputs(u16::from_le_bytes([*lo, *hi]));
    }
    match a.conns.outputs.iter_mut().find(|(i, _)| *i == asm.instance) {
        Some((_, d)) => *d = data.to_vec(),
        None => a.conns.outputs.push((asm.instance, data.to_vec())),
    }
}

/// The data of an input assembly: the interface word (inputs valid, bit 15), then status
/// word and actual values per inverter.
fn input_data(a: &Adapter, asm: &Assembly) -> Vec<u8> {
    let mut out = Vec::with_capacity(usize::from(asm.len));
    if asm.io_word {
        out.extend(0x8000u16.to_le_bytes());
    }
    for n in 0..usize::from(asm.inverters) {
        for w in a.conns.inputs[n] {
            out.extend(w.to_le_bytes());
        }
    }
    out
}

/// One class-1 datagram.
pub(super) fn consume(
    a: &mut Adapter,
    _peer: SocketAddr,
    datagram: &[u8],
    now: Duration,
) -> Result<(), IoError> {
    let id = IoFrame::connection_of(datagram)?;
    let i = a
        .conns
        .conns
        .iter()
        .position(|c| c.o_t_id == id && c.kind != Kind::Explicit)
        .ok_or(IoError::UnknownConnection(id))?;
    let c = &a.conns.conns[i];
    let frame = IoFrame::parse(datagram, c.run_idle && c.kind == Kind::Owner)?;
    if c.kind == Kind::ListenOnly {
        // Heartbeat: sequence count only.
        a.conns.conns[i].last_rx = now;
        return Ok(());
    }
    if frame.data.len() != c.o_t_len {
        return Err(IoError::WrongLength {
            want: c.o_t_len,
            got: frame.data.len(),
        });
    }
    let fresh = c.last_count != Some(frame.count);
    let asm = c.o_t_asm;
    {
        let c = &mut a.conns.conns[i];
        c.last_rx = now;
        c.last_count = Some(frame.count);
    }
    if let (true, Some(asm)) = (fresh, asm) {
        apply_outputs(a, asm, &frame.data, frame.is_run(), now);
    }
    Ok(())
}

/// T→O frames due.
pub(super) fn produce(a: &mut Adapter, now: Duration) -> Vec<(SocketAddr, Vec<u8>)> {
    let mut out = Vec::new();
    for i in 0..a.conns.conns.len() {
        let c = &a.conns.conns[i];
        let Some(asm) = c.t_o_asm else { continue };
        if c.next_tx > now {
            continue;
        }
        let mut data = input_data(a, asm);
        data.truncate(c.t_o_len);
        let c = &mut a.conns.conns[i];
        c.t_o_seq = c.t_o_seq.wrapping_add(1);
        c.t_o_count = c.t_o_count.wrapping_add(1);
        while c.next_tx <= now {
            c.next_tx += c.t_o_rpi;
        }
        let frame = IoFrame {
            connection: c.t_o_id,
            sequence: c.t_o_seq,
            count: c.t_o_count,
            run_idle: None,
            data,
        };
        if let Ok(b) = frame.emit() {
            out.push((c.dest, b));
        }
    }
    out
}

/// Ends connections whose consumer watchdog expired.
pub(super) fn watchdogs(a: &mut Adapter, now: Duration) {
    let expired: Vec<(ConnectionKey, Kind)> = a
        .conns
        .conns
        .iter()
        .filter(|c| now.saturating_sub(c.last_rx) > c.timeout)
        .map(|c| (c.key, c.kind))
        .collect();
    for (key, k) in expired {
        a.conns.remove(key);
        if k == Kind::Owner {
            a.conns.timed_out = true;
            owner_timed_out(a);
        }
    }
}

/// E10.2 on every inverter whose monitoring is on; P872/P173 bit 2 "Timeout (Ethernet/IP)".
fn owner_timed_out(a: &mut Adapter) {
    a.device.set_fieldbus_timeout(true);
    objects::show_active_assembly(a, 0, 0);
    let module = a.product().family() == Family::Module;
    // BU 2100 §7.1.1: P151 = -1 "Monitoring Off"; 0 keeps the bus-communication monitoring
    // ("Connection to EtherNet/IP-Busmaster lost | 0 sec | Error E10.2").
    let interface_off = module && a.device.fieldbus_monitoring_off();
    for n in 1..=a.device.config().inverters {
        let Some(fi) = slot(usize::from(n)) else {
            continue;
        };
        let monitored = if module {
            !interface_off
        } else {
            a.device.ethernet_timeout(fi).is_some()
        };
        if monitored {
            let _ = a.device.raise(fi, E10_2);
        }
    }
}

/// Get/Set_Attribute_Single on an assembly: attribute 3 is the data, 4 its size.
pub(super) fn assembly_service(a: &mut Adapter, req: &MrRequest, now: Duration) -> MrResponse {
    let s = req.service;
    let Some(asm) = req
        .path
        .instance_id()
        .and_then(|i| u16::try_from(i).ok())
        .and_then(|i| eip::assembly(a.product(), i))
    else {
        return MrResponse::error(s, GS::PATH_DESTINATION_UNKNOWN);
    };
    match (Service(s), req.path.attribute_id()) {
        (Service::GET_ATTRIBUTE_SINGLE, Some(3)) => {
            let data = match asm.direction {
                Direction::Input => input_data(a, asm),
                Direction::Output => a
                    .conns
                    .outputs
                    .iter()
                    .find(|(i, _)| *i == asm.instance)
                    .map(|(_, d)| d.clone())
                    .unwrap_or_else(|| vec![0; usize::from(asm.len)]),
            };
            MrResponse::ok(s, data)
        }
        (Service::GET_ATTRIBUTE_SINGLE, Some(4)) => {
            MrResponse::ok(s, asm.len.to_le_bytes().to_vec())
        }
        (Service::GET_ATTRIBUTE_SINGLE, _) => MrResponse::error(s, GS::ATTRIBUTE_NOT_SUPPORTED),
        (Service::SET_ATTRIBUTE_SINGLE, Some(3)) => {
            if asm.direction == Direction::Input {
                return MrResponse::error(s, GS::ATTRIBUTE_NOT_SETTABLE);
            }
            if a.conns.has_owner() {
                // The exclusive owner's I/O writes this assembly.
                return MrResponse::error(s, GS::OBJECT_STATE_CONFLICT);
            }
            if !asm.accepts(req.data.len()) {
                return MrResponse::error(
                    s,
                    if req.data.len() > usize::from(asm.len) {
                        GS::TOO_MUCH_DATA
                    } else {
                        GS::NOT_ENOUGH_DATA
                    },
                );
            }
            apply_outputs(a, asm, &req.data, true, now);
            MrResponse::ok(s, Vec::new())
        }
        (Service::SET_ATTRIBUTE_SINGLE, Some(4)) => {
            MrResponse::error(s, GS::ATTRIBUTE_NOT_SETTABLE)
        }
        (Service::SET_ATTRIBUTE_SINGLE, _) => MrResponse::error(s, GS::ATTRIBUTE_NOT_SUPPORTED),
        _ => MrResponse::error(s, GS::SERVICE_NOT_SUPPORTED),
    }
}
