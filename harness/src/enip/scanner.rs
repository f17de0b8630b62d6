//! The EtherNet/IP scanner binding: manual-level steps as CIP explicit messages and a class-1
//! I/O connection, over the embedded adapter or a target on the network.
//!
//! - read/write: Get/Set_Attribute_Single on class 100 + FI (100 = a module's own
//!   parameters; the SK 550P's interface parameters sit in class 101), instance from parameter
//!   set and array element, attribute = parameter number (BU 0620 §2.3.5, BU 2100 §6.3); values
//!   INT, or DINT for positions, little-endian.
//! - process data: an Exclusive Owner connection on the product's multi-inverter assemblies
//!   (SK 550P 100/101, TU3-EIP 102/103, TU4/CU4-EIP 110/111), one O→T frame per RPI.
//! - raw encapsulation messages and Forward_Open variants for the EtherNet/IP suites.

use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4};
use std::time::Duration;

use proto::enip::cip::{class, GeneralStatus, MrRequest, MrResponse, Service};
use proto::enip::cm::{kind, ForwardOpen, ForwardOpenReply, NetParams, Transport};
use proto::enip::cpf::{Cpf, Item};
use proto::enip::encap::{Command, EncapRepr, EncapStatus, RegisterSession, SendData};
use proto::enip::epath::EPath;
use proto::enip::io::IoFrame;
use proto::nord::addr::cip_instance;
use proto::nord::eip::{self, Assembly, Direction, WORDS_PER_INVERTER};
use proto::nord::params::{self, Owner, Width};
use proto::nord::{Family, Inverter, Product};
use serde_json::{json, Value};
use sim::device::Device;
use sim::enip::Adapter;

use super::cleanup;
use super::consumer::Consumer;
use super::link::{self, EnipLink, LinkError, Network};
use super::serials::{self, Serials};
use super::step::EnipStep;
use crate::binding::channel::compact;
use crate::binding::simulator::{observe_device, OBSERVABLE};
use crate::binding::{Binding, CleanupError, Observation, OpenError, StepError};
use crate::hex::hex;
use crate::outcome::{Exchange, Identity, Refusal};
use crate::profile::Capability;
use crate::suite::{Action, OrderSpec, Target};
use crate::timing::cycles_for;
use crate::timing::Deadline;

/// RPI of the harness's I/O connection.
pub(super) const RPI: Duration = Duration::from_millis(4);
/// The harness's originator vendor id and serial number in Forward_Open.
pub(super) const VENDOR: u16 = 0x4E48;
pub(super) const ORIGINATOR_SERIAL: u32 = 0x4E48_5331;
/// The embedded adapter's address.
pub(super) const EMBEDDED_ADDR: SocketAddrV4 =
    SocketAddrV4::new(Ipv4Addr::new(192, 168, 1, 100), 44818);

/// An open I/O connection.
pub(super) struct IoConn {
    /// Its key and connection path, for its Forward_Close.
    pub(super) opened: cleanup::Opened,
    pub(super) o_t_id: u32,
    pub(super) t_o_id: u32,
    /// The assemblies behind the connection points, if the product has them.
    pub(super) o_t: Option<&'static Assembly>,
    pub(super) t_o: Option<&'static Assembly>,
    /// O→T application data bytes (a connection may be shorter than its assembly).
    pub(super) o_t_len: usize,
    pub(super) run_idle: bool,
    pub(super) sequence: u32,
    pub(super) count: u16,
    /// The scanner's limit as consumer of the T→O data: the connection's timeout, RPI × the
    /// timeout multiplier of the Forward_Open (CIP Vol 1 §3-5.4.1.4, `4 << multiplier`).
    pub(super) timeout: Duration,
    /// The T→O frames taken and discarded by their sequence numbers.
    pub(super) consumer: Consumer,
}

/// The scanner.
pub(crate) struct Scanner {
    pub(super) link: Box<dyn EnipLink>,
    /// The NORD product; `None` for another maker's adapter (profile `cip`).
    pub(super) product: Option<Product>,
    pub(super) caps: Vec<Capability>,
    /// Registered sessions by client (1 = the scanner's own connection).
    pub(super) sessions: std::collections::BTreeMap<u8, u32>,
    pub(super) context: u64,
    /// Where the connection serial numbers of its Forward_Opens come from.
    pub(super) serials: Serials,
    pub(super) io: Option<IoConn>,
    /// Run (`true`) or idle in the run/idle header of O→T frames.
    pub(super) run: bool,
    pub(super) process: [(u16, Vec<u16>); 9],
    pub(super) exchanges: Vec<Exchange>,
    /// What the case changed on a network target, to put back when it ends; `None` for the
    /// embedded adapter, made afresh for every case.
    pub(super) ledger: Option<cleanup::Ledger>,
    /// The owner connection the adapter's EDS declares (`--description`, or for a NORD
    /// product the EDS the harness writes for it).
    pub(super) declared: Option<crate::description::eds::Connection>,
}

impl Scanner {
    /// The embedded adapter around `device`.
    pub(crate) fn embedded(device: Device, tap: Option<crate::pcap::SharedTap>) -> Scanner {
        let product = device.config().product;
        let adapter = Adapter::new(device, EMBEDDED_ADDR);
        Scanner::new(
            Box::new(link::Embedded::new(adapter, EMBEDDED_ADDR, tap)),
            Some(product),
            Capability::GENERAL
                .into_iter()
                .filter(|c| *c != Capability::ParameterChannel)
                .chain([Capability::Bus(super::BUS.name)])
                .collect(),
        )
    }

    /// A target on the network.
    pub(crate) fn network(
        target: SocketAddr,
        local: Option<std::net::IpAddr>,
        product: Option<Product>,
        timeout: Duration,
    ) -> Result<Scanner, LinkError> {
        let link = Network::connect(target, local, timeout)?;
        // NORD's parameter classes and assemblies only on a NORD product.
        let caps = match product {
            Some(_) => vec![
                Capability::ParameterAccess,
                Capability::ProcessData,
                Capability::Bus("enip"),
            ],
            None => vec![Capability::Bus("enip")],
        };
        let mut scanner = Scanner::new(Box::new(link), product, caps);
        scanner.ledger = Some(cleanup::Ledger::default());
        // The device outlives the case: numbered on from the scanners before.
        scanner.serials = Serials::Shared;
        Ok(scanner)
    }

    pub(super) fn new(
        link: Box<dyn EnipLink>,
        product: Option<Product>,
        caps: Vec<Capability>,
    ) -> Scanner {
        Scanner {
            link,
            product,
            caps,
            sessions: Default::default(),
            context: 0,
            serials: Serials::per_case(),
            io: None,
            run: true,
            process: Default::default(),
            exchanges: Vec::new(),
            ledger: None,
            declared: product.and_then(own_connection),
        }
    }

    /// The wait for the reply to a request about to leave: on the network `--timeout`, the
    /// user's limit for one request (moved by the host's lateness); the embedded adapter
    /// answers at once or not at all.
    pub(super) fn wait(&self) -> Deadline {
        Deadline::after(self.link.timeout().unwrap_or_default())
    }

    /// `what` got no reply within `wait`: on the network the device's time-out, with both
    /// times; the embedded adapter's silence a link error.
    fn no_reply(&self, what: &str, wait: &Deadline) -> StepError {
        match self.link.timeout() {
            Some(_) => StepError::late(wait, what),
            None => StepError::Link(format!("no reply to {what}").into()),
        }
    }

    /// One encapsulation message of `client` and its reply, recorded; `what` for the
    /// transcript, `short` for a time-out.
    pub(super) fn send(
        &mut self,
        client: u8,
        msg: EncapRepr,
        what: String,
        short: &str,
    ) -> Result<EncapRepr, StepError> {
        let wait = self.wait();
        self.send_within(client, msg, what, &wait)?
            .ok_or_else(|| self.no_reply(short, &wait))
    }

    /// [`Scanner::send`] with a wait of its own; `None` when no reply came within it.
    fn send_within(
        &mut self,
        client: u8,
        msg: EncapRepr,
        what: String,
        wait: &Deadline,
    ) -> Result<Option<EncapRepr>, StepError> {
        let bytes = msg.emit().map_err(|e| StepError::Suite(e.into()))?;
        let reply = self.send_bytes(client, &bytes, what, wait)?;
        match reply {
            Some(r) if r.command != msg.command => Err(StepError::Garbage(
                format!(
                    "the reply to {} is command {:04X}h",
                    Command(msg.command),
                    r.command
                )
                .into(),
            )),
            _ => Ok(reply),
        }
    }

    /// Raw bytes of `client` and their reply, if one came within `wait`, recorded.
    pub(super) fn send_bytes(
        &mut self,
        client: u8,
        bytes: &[u8],
        what: String,
        wait: &Deadline,
    ) -> Result<Option<EncapRepr>, StepError> {
        let reply = self.link.request(client, bytes, wait);
        let what = if client == 1 {
            what
        } else {
            format!("[client {client}] {what}")
        };
        let (received_hex, received, result) = match reply {
            Err(e) => (
                String::new(),
                format!("link error: {e}"),
                Err(StepError::from(e)),
            ),
            Ok(None) => (String::new(), "(nothing)".into(), Ok(None)),
            Ok(Some(b)) => match EncapRepr::parse(&b) {
                Ok(r) => (hex(&b), describe_reply(&r), Ok(Some(r))),
                Err(e) => (
                    hex(&b),
                    format!("malformed: {e}"),
                    Err(StepError::Protocol(
                        format!("malformed encapsulation reply: {e}").into(),
                    )),
                ),
            },
        };
        self.exchanges.push(Exchange {
            sent_hex: hex(bytes),
            sent: what,
            received_hex,
            received,
        });
        result
    }

    pub(super) fn context(&mut self) -> [u8; 8] {
        self.context += 1;
        self.context.to_le_bytes()
    }

    /// The session of `client`, registered on first use.
    pub(super) fn session(&mut self, client: u8) -> Result<u32, StepError> {
        if let Some(s) = self.sessions.get(&client) {
            return Ok(*s);
        }
        let msg = EncapRepr {
            command: Command::REGISTER_SESSION.0,
            context: self.context(),
            data: RegisterSession::V1.emit(),
            ..EncapRepr::default()
        };
        let reply = self.send(client, msg, "RegisterSession".into(), "RegisterSession")?;
        if reply.status != 0 || reply.session == 0 {
            return Err(StepError::Protocol(
                format!("RegisterSession refused: {}", EncapStatus(reply.status)).into(),
            ));
        }
        self.sessions.insert(client, reply.session);
        Ok(reply.session)
    }

    /// An unconnected explicit request (SendRRData) of the scanner and its message-router
    /// reply.
    pub(super) fn explicit(&mut self, req: &MrRequest) -> Result<MrResponse, StepError> {
        let what = format!("{} {}", Service(req.service), req.path);
        let resp = self.unconnected(1, req.emit(), what)?;
        if resp.service != req.service {
            return Err(StepError::Protocol(
                format!(
                    "reply to service {:02X}h answers service {:02X}h",
                    req.service, resp.service
                )
                .into(),
            ));
        }
        Ok(resp)
    }

    /// A message-router request as bytes, in a SendRRData of `client`'s session.
    pub(super) fn unconnected(
        &mut self,
        client: u8,
        request: Vec<u8>,
        what: String,
    ) -> Result<MrResponse, StepError> {
        let service = request.first().copied().unwrap_or(0);
        let session = self.session(client)?;
        let data = SendData {
            interface: 0,
            timeout: 0,
            cpf: Cpf::new(vec![Item::Null, Item::UnconnectedData(request)]),
        }
        .emit()
        .map_err(|e| StepError::Suite(e.into()))?;
        let msg = EncapRepr {
            command: Command::SEND_RR_DATA.0,
            session,
            context: self.context(),
            data,
            ..EncapRepr::default()
        };
        let reply = self.send(client, msg, what, &Service(service).to_string())?;
        if reply.status != 0 {
            return Err(StepError::Protocol(
                format!(
                    "SendRRData answered with encapsulation status {}",
                    EncapStatus(reply.status)
                )
                .into(),
            ));
        }
        let sd = SendData::parse(&reply.data).map_err(StepError::malformed("SendRRData reply"))?;
        let Some(Item::UnconnectedData(payload)) = sd.cpf.items.get(1) else {
            return Err(StepError::Protocol(
                "SendRRData reply without unconnected data item".into(),
            ));
        };
        MrResponse::parse(payload).map_err(StepError::malformed("message-router reply"))
    }

    /// The NORD product, for steps about its parameters and assemblies.
    pub(super) fn product(&self) -> Result<Product, StepError> {
        self.product
            .ok_or_else(|| StepError::Suite("a NORD step against profile `cip`".into()))
    }

    /// Class, instance and attribute of a parameter, and its catalogue entry.
    pub(super) fn param_path(
        &self,
        o: &OrderSpec,
    ) -> Result<(EPath, Option<&'static params::ParamDef>), StepError> {
        let product = self.product()?;
        let instance = u32::from(cip_instance(o.set, o.element));
        let n = o.number;
        let iface = params::lookup(product, Owner::Interface, n);
        let (class, def) = match (o.target, product.family()) {
            (Target::Interface, Family::Module) => (100, iface),
            (Target::Interface, Family::Integrated) => (101, iface),
            (Target::Inverter(i), fam) => {
                let inv = params::lookup(product, Owner::Inverter, n);
                let def = if fam == Family::Integrated && i.get() == 1 {
                    iface.or(inv)
                } else {
                    inv
                };
                (eip::param_class(Some(i)), def)
            }
        };
        Ok((EPath::attribute(class, instance, n.get()), def))
    }

    pub(super) fn read(&mut self, o: &OrderSpec) -> Result<Observation, StepError> {
        let (path, def) = self.param_path(o)?;
        let resp = self.explicit(&MrRequest {
            service: Service::GET_ATTRIBUTE_SINGLE.0,
            path,
            data: Vec::new(),
        })?;
        if resp.general != 0 {
            return Ok(refused(&resp));
        }
        let signed = def.is_some_and(|d| d.min < 0);
        let value = match resp.data.as_slice() {
            [a, b] if signed => i64::from(i16::from_le_bytes([*a, *b])),
            [a, b] => i64::from(u16::from_le_bytes([*a, *b])),
            [a, b, c, d] => i64::from(i32::from_le_bytes([*a, *b, *c, *d])),
            other => {
                return Err(StepError::Protocol(
                    format!(
                        "a parameter value of {} bytes (INT or DINT expected)",
                        other.len()
                    )
                    .into(),
                ))
            }
        };
        Ok(json!({ "value": value, "cip_status": 0, "bytes": hex(&resp.data) }).into())
    }

    pub(super) fn write(&mut self, o: &OrderSpec) -> Result<Observation, StepError> {
        let (path, def) = self.param_path(o)?;
        let value = o.value.unwrap_or(0);
        let v = i32::try_from(value)
            .map_err(|_| StepError::Suite(format!("value {value} does not fit 32 bits").into()))?;
        let width = match def.map(|d| d.width) {
            Some(Width::Dword) => 4,
            _ => 2,
        };
        let noted = self.before_set(&path)?;
        let resp = self.explicit(&MrRequest {
            service: Service::SET_ATTRIBUTE_SINGLE.0,
            path,
            data: v.to_le_bytes()[..width].to_vec(),
        });
        self.after_set(noted, resp.as_ref());
        let resp = resp?;
        if resp.general != 0 {
            return Ok(refused(&resp));
        }
        Ok(json!({ "cip_status": 0 }).into())
    }

    /// The Forward_Open of the harness's own I/O connection.
    pub(super) fn own_forward_open(&mut self) -> Result<(), StepError> {
        let product = self.product()?;
        let out = eip::assemblies(product)
            .iter()
            .filter(|a| a.direction == Direction::Output)
            .max_by_key(|a| a.len)
            .ok_or_else(|| StepError::Suite("the product has no output assembly".into()))?;
        let inp = eip::assembly(product, out.instance + 1)
            .ok_or_else(|| StepError::Suite("no input assembly beside the output".into()))?;
        let p166 = if let Some(number) = eip::transmission_format(product) {
            let o = OrderSpec::read(Target::Interface, number);
            self.read(&o)?
                .fields
                .get("value")
                .and_then(Value::as_i64)
                .unwrap_or(0) as i32
        } else {
            0
        };
        let (o_t_size, t_o_size) = eip::connection_sizes(product, out.instance, inp.instance, p166);
        let spec = ForwardOpenSpec {
            o_t_point: out.instance,
            t_o_point: inp.instance,
            o_t_size,
            t_o_size,
            run_idle: eip::o_t_run_idle(product, out.instance, p166),
            ..ForwardOpenSpec::default()
        };
        match self.forward_open(&spec)? {
            (_, Some(_)) => Ok(()),
            (resp, None) => Err(StepError::Protocol(
                format!(
                    "Forward_Open refused: {} extended {:04X?}",
                    GeneralStatus(resp.general),
                    resp.extended
                )
                .into(),
            )),
        }
    }

    /// A `forward_open: declared` step made concrete from the device's EDS.
    fn as_declared(&self, s: &ForwardOpenSpec) -> Result<ForwardOpenSpec, StepError> {
        let Some((o_t_delta, t_o_delta)) = s.declared else {
            return Ok(s.clone());
        };
        let c = self.declared.as_ref().ok_or_else(|| {
            StepError::NotApplicable(
                "needs the connection the adapter declares: give its EDS with `--description`"
                    .into(),
            )
        })?;
        let size = |data: u16, header: u16, delta: i32| -> Result<u16, StepError> {
            u16::try_from(i32::from(data) + i32::from(header) + delta).map_err(|_| {
                StepError::Suite(format!("a size change of {delta} leaves no size").into())
            })
        };
        // Network sizes: the 2-byte sequence count, and O→T the run/idle header.
        let run_idle = if c.run_idle { 4 } else { 0 };
        Ok(ForwardOpenSpec {
            rpi_us: planned_rpi(s, c.rpi_us),
            config_point: c.config,
            o_t_point: c.o_t,
            t_o_point: c.t_o,
            o_t_size: size(c.o_t_size, 2 + run_idle, o_t_delta)?,
            t_o_size: size(c.t_o_size, 2, t_o_delta)?,
            run_idle: c.run_idle,
            declared: None,
            ..s.clone()
        })
    }

    pub(super) fn forward_open(
        &mut self,
        s: &ForwardOpenSpec,
    ) -> Result<(MrResponse, Option<ForwardOpenReply>), StepError> {
        let s = &self.as_declared(s)?;
        self.link.prepare_io().map_err(StepError::from)?;
        // The session first: a Forward_Open that never left opened nothing to close.
        self.session(1)?;
        let serial = self.serials.next();
        let np = NetParams::fixed;
        let fo = ForwardOpen {
            large: s.large,
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            o_t_id: 0,
            t_o_id: serials::t_o_id(serial),
            serial,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            timeout_multiplier: s.multiplier,
            o_t_rpi: s.rpi_us,
            o_t: np(s.o_t_size, kind::POINT_TO_POINT),
            t_o_rpi: s.rpi_us,
            t_o: np(s.t_o_size, kind::POINT_TO_POINT),
            transport: Transport(s.transport),
            path: EPath::io_connection_configured(s.config_point, s.o_t_point, s.t_o_point),
        };
        let service = if s.large {
            Service::LARGE_FORWARD_OPEN
        } else {
            Service::FORWARD_OPEN
        };
        let resp = self.explicit(&MrRequest {
            service: service.0,
            path: EPath::object(class::CONNECTION_MANAGER, 1),
            data: fo.emit(),
        });
        // Noted before its reply is parsed: a connection the target may have opened is closed
        // in the cleanup, when the reply was lost or does not parse too.
        if cleanup::may_have_taken_effect(resp.as_ref()) {
            self.note_opened(&fo);
        }
        let resp = resp?;
        if resp.general != 0 {
            return Ok((resp, None));
        }
        let reply = ForwardOpenReply::parse(&resp.data)
            .map_err(StepError::malformed("Forward_Open reply"))?;
        if s.o_t_point != eip::LISTEN_ONLY_POINT {
            // An owner connection: the following process-data steps run over it.
            self.io = Some(IoConn {
                opened: cleanup::Opened::of(&fo),
                o_t_id: reply.o_t_id,
                t_o_id: reply.t_o_id,
                o_t: self.product.and_then(|p| eip::assembly(p, s.o_t_point)),
                t_o: self.product.and_then(|p| eip::assembly(p, s.t_o_point)),
                o_t_len: usize::from(eip::connection_data(s.o_t_size, s.run_idle).unwrap_or(0)),
                run_idle: s.run_idle,
                sequence: 0,
                count: 0,
                // One RPI both ways: the O→T timeout is the T→O one.
                timeout: Duration::from_micros(fo.timeout_us()),
                consumer: Consumer::default(),
            });
        }
        Ok((resp, Some(reply)))
    }

    /// One I/O cycle: O→T with every inverter's process data, T→O back.
    pub(super) fn io_cycle(&mut self) -> Result<Option<Vec<u8>>, StepError> {
        if self.io.is_none() {
            self.own_forward_open()?;
        }
        let Some(io) = self.io.as_mut() else {
            return Err(StepError::Suite("no I/O connection".into()));
        };
        let mut data = vec![0u8; io.o_t_len];
        let asm = io.o_t;
        for fi in (1..=asm.map_or(0, |a| a.inverters)).filter_map(|n| Inverter::new(n.into()).ok())
        {
            let Some(off) = asm.and_then(|a| a.offset(fi)) else {
                continue;
            };
            let (control, setpoints) = &self.process[usize::from(fi.get())];
            let mut words = vec![*control];
            words.extend(setpoints.iter().copied());
            words.resize(WORDS_PER_INVERTER, 0);
            // A truncated connection carries the words that fit (BU 2100 §6.2.1).
            for (k, w) in words.iter().enumerate() {
                if let Some(d) = data.get_mut(off + 2 * k..off + 2 * k + 2) {
                    d.copy_from_slice(&w.to_le_bytes());
                }
            }
        }
        io.sequence = io.sequence.wrapping_add(1);
        io.count = io.count.wrapping_add(1);
        let frame = IoFrame {
            connection: io.o_t_id,
            sequence: io.sequence,
            count: io.count,
            run_idle: io.run_idle.then_some(u32::from(self.run)),
            data,
        };
        let bytes = frame.emit().map_err(|e| StepError::Suite(e.into()))?;
        let t_o_id = io.t_o_id;
        let received = self
            .link
            .io_cycle(Some(&bytes), RPI)
            .map_err(StepError::from)?;
        let io = self
            .io
            .as_mut()
            .ok_or_else(|| StepError::Suite("no I/O connection".into()))?;
        let mut last = None;
        let mut discarded = None;
        for f in received
            .iter()
            .filter_map(|d| IoFrame::parse(d, false).ok())
            .filter(|f| f.connection == t_o_id)
        {
            if io.consumer.take(f.sequence, io.timeout) {
                last = Some(f);
            } else {
                discarded = Some(f.sequence);
            }
        }
        let checked = io.consumer.check(t_o_id);
        let stale = io.consumer.discarded();
        self.exchanges.push(Exchange {
            sent_hex: hex(&bytes),
            sent: format!("I/O O→T count {} ({} bytes)", frame.count, frame.data.len()),
            received_hex: received.last().map(|d| hex(d)).unwrap_or_default(),
            received: match (&last, discarded) {
                (Some(f), _) => format!("I/O T→O count {} ({} bytes)", f.count, f.data.len()),
                (None, Some(s)) => format!(
                    "I/O T→O sequence number {s} discarded: not past the last taken ({stale} \
                     so far)"
                ),
                (None, None) => "(nothing)".into(),
            },
        });
        checked?;
        Ok(last.map(|f| f.data))
    }

    pub(super) fn run_process(
        &mut self,
        inverter: Inverter,
        cycles: u32,
    ) -> Result<Value, StepError> {
        // A device on the network produces its T→O frames on its own timer: the one that comes
        // within a cycle may have left before the device took that cycle's O→T frame. One
        // more cycle brings its answer to the last of them, as the PRes and the EtherCAT
        // inputs come a cycle later (a loaded host showed 0940h where 047Eh had been sent
        // for one cycle).
        let cycles = if self.link.timeout().is_some() {
            cycles + 1
        } else {
            cycles
        };
        self.run_process_until(inverter, cycles, None)
    }

    /// Process data for `d`: on the embedded link's virtual clock as many RPIs; on a network
    /// target `d` of real time, however long a cycle there lasts (a drive runs on its own
    /// clock: a ramp or a watchdog sees the real time, not the cycles sent).
    pub(super) fn run_for(&mut self, inverter: Inverter, d: Duration) -> Result<Value, StepError> {
        let deadline = self
            .link
            .adapter()
            .is_none()
            .then(|| std::time::Instant::now() + d);
        self.run_process_until(inverter, cycles_for(d, RPI), deadline)
    }

    /// `cycles` I/O cycles, or with a `deadline` as many as it takes to pass it (at least
    /// one); the status word and actual values of `inverter` last received.
    ///
    /// On a network target the cycles go on until a T→O frame came, for as long as the
    /// device may take: the connection's timeout from the step's first O→T frame (moved by
    /// the host's lateness). A T→O frame that misses one RPI says nothing of the device (the
    /// host may have held either side back); one that misses the connection's timeout is the
    /// device's time-out.
    pub(super) fn run_process_until(
        &mut self,
        inverter: Inverter,
        cycles: u32,
        deadline: Option<std::time::Instant>,
    ) -> Result<Value, StepError> {
        let first = self.exchanges.len();
        if self.io.is_none() {
            self.own_forward_open()?;
        }
        let first_frame = match (self.link.timeout(), &self.io) {
            (Some(_), Some(io)) => Some(Deadline::after(io.timeout)),
            _ => None,
        };
        let mut last = None;
        let mut n = 0;
        while deadline.map_or(n < cycles, |t| n == 0 || std::time::Instant::now() < t)
            || (last.is_none() && first_frame.is_some_and(|d| !d.passed()))
        {
            n += 1;
            if let Some(d) = self.io_cycle()? {
                last = Some(d);
            }
        }
        compact(&mut self.exchanges, first);
        let io = self
            .io
            .as_ref()
            .ok_or_else(|| StepError::Suite("no I/O connection".into()))?;
        let data = last.ok_or_else(|| match first_frame {
            Some(d) => StepError::late(
                &d,
                format!(
                    "T→O data of I/O connection {:08X}h after {n} O→T frames",
                    io.t_o_id
                ),
            ),
            None => StepError::Silent { cycles: n },
        })?;
        let off = io.t_o.and_then(|a| a.offset(inverter)).ok_or_else(|| {
            StepError::Suite(
                format!("{inverter} is not in the input assembly of the connection").into(),
            )
        })?;
        let words: Vec<u16> = data
            .get(off..)
            .unwrap_or_default()
            .chunks_exact(2)
            .take(WORDS_PER_INVERTER)
            .map(|w| u16::from_le_bytes([w[0], w[1]]))
            .collect();
        let (status, actuals) = words
            .split_first()
            .ok_or_else(|| StepError::Protocol("T→O data without a status word".into()))?;
        Ok(crate::binding::process_fields(*status, actuals))
    }

    /// A raw or structured EtherNet/IP step of the protocol suites.
    pub(super) fn enip_step(&mut self, step: &EnipStep) -> Result<Value, StepError> {
        match step {
            EnipStep::Raw {
                bytes,
                session,
                client,
                split,
            } => {
                let mut b = bytes.clone();
                if *session && b.len() >= 8 {
                    let s = self.session(*client)?;
                    b[4..8].copy_from_slice(&s.to_le_bytes());
                }
                let wait = self.wait();
                let mut what = format!("raw {} bytes", b.len());
                // After the session's registration: only the step's own message is split.
                if let Some(p) = split {
                    self.link.split_next(*p).map_err(StepError::from)?;
                    what = format!(
                        "{what} in two TCP segments: {} + {} bytes, {:?} apart",
                        p.at,
                        b.len().saturating_sub(p.at),
                        p.gap
                    );
                }
                let reply = self.send_bytes(*client, &b, what, &wait);
                Ok(match reply {
                    Ok(None) => json!({ "reply": false, "closed": false }),
                    Ok(Some(r)) => reply_fields(&r),
                    Err(StepError::Link(e) | StepError::Closed(e)) => {
                        json!({ "reply": false, "closed": true, "link": e.to_string() })
                    }
                    Err(StepError::Protocol(e)) => {
                        json!({ "reply": true, "malformed": e.to_string() })
                    }
                    Err(e) => return Err(e),
                })
            }
            EnipStep::Mr { bytes, client } => {
                let what = format!("message-router request {}", hex(bytes));
                let noted = self.before_request(bytes)?;
                let resp = self.unconnected(*client, bytes.clone(), what);
                self.after_request(noted, resp.as_ref());
                Ok(mr_fields(&resp?))
            }
            EnipStep::Request {
                service,
                path,
                data,
                client,
            } => {
                let path = EPath::parse(path)
                    .map_err(|e| StepError::Suite(format!("path: {e}").into()))?;
                let what = format!("{} {path}", Service(*service));
                let req = MrRequest {
                    service: *service,
                    path,
                    data: data.clone(),
                };
                let bytes = req.emit();
                let noted = self.before_request(&bytes)?;
                let resp = self.unconnected(*client, bytes, what);
                self.after_request(noted, resp.as_ref());
                Ok(mr_fields(&resp?))
            }
            EnipStep::Run(run) => {
                self.run = *run;
                Ok(json!({ "run": run }))
            }
            EnipStep::ForwardOpen(spec) => {
                let (resp, reply) = self.forward_open(spec)?;
                let mut v = mr_fields(&resp);
                if let Some(r) = reply {
                    v["o_t_id"] = json!(r.o_t_id);
                    v["t_o_id"] = json!(r.t_o_id);
                }
                Ok(v)
            }
            EnipStep::StopIo { time, foreign_id } => {
                // The scanner goes quiet: time passes without O→T frames of the connection
                // (with `foreign_id`, frames whose connection ID is not the connection's).
                let cycles = cycles_for(*time, RPI);
                let mut frames = 0;
                for _ in 0..cycles {
                    let sent = match (foreign_id, self.io.as_mut()) {
                        (true, Some(io)) => {
                            io.sequence = io.sequence.wrapping_add(1);
                            io.count = io.count.wrapping_add(1);
                            let frame = IoFrame {
                                connection: !io.o_t_id,
                                sequence: io.sequence,
                                count: io.count,
                                run_idle: io.run_idle.then_some(u32::from(self.run)),
                                data: vec![0; io.o_t_len],
                            };
                            Some(frame.emit().map_err(|e| StepError::Suite(e.into()))?)
                        }
                        _ => None,
                    };
                    frames += self
                        .link
                        .io_cycle(sent.as_deref(), RPI)
                        .map_err(StepError::from)?
                        .len();
                }
                self.io = None;
                Ok(json!({ "t_o_frames": frames }))
            }
        }
    }
}

/// Opens a new connection to a network target per case.
pub(crate) struct NetworkFactory {
    /// Encapsulation address of the target.
    pub(crate) target: SocketAddr,
    /// The scanner's own address (`--local`): TCP from it, T→O data to its UDP 2222.
    pub(crate) local: Option<std::net::IpAddr>,
    /// How long one request may take.
    pub(crate) timeout: Duration,
    /// Where `--pcap` collects the run's traffic.
    pub(crate) tap: Option<crate::pcap::SharedTap>,
    /// The run's clock: captured packets are stamped with the time since the run started.
    pub(crate) clock: std::rc::Rc<sim::clock::RealClock>,
    /// The owner connection of the device's EDS (`--description`), which replaces the one of
    /// the profile's own.
    pub(crate) declared: Option<crate::description::eds::Connection>,
}

impl crate::binding::DutFactory for NetworkFactory {
    fn describe(&self) -> String {
        format!("EtherNet/IP target at {}", self.target)
    }

    fn open(
        &mut self,
        profile: &crate::profile::Profile,
        _retries: u32,
    ) -> Result<Box<dyn Binding>, OpenError> {
        let mut scanner = Scanner::network(self.target, self.local, profile.product, self.timeout)
            .map_err(|e| OpenError::Unreachable(e.to_string()))?;
        if self.declared.is_some() {
            scanner.declared = self.declared.clone();
        }
        if let Some(tap) = &self.tap {
            scanner
                .link
                .record(tap.clone(), self.clock.clone())
                .map_err(|e| OpenError::Unreachable(e.to_string()))?;
        }
        Ok(Box::new(scanner))
    }
}

/// The owner connection of the EDS the harness writes for a NORD product, read back by the
/// planner that reads another maker's. Written and parsed once per product and process: a
/// scanner is made for every case, and the EDS is the same each time.
fn own_connection(product: Product) -> Option<crate::description::eds::Connection> {
    type Known = Vec<(Product, Option<crate::description::eds::Connection>)>;
    static KNOWN: std::sync::Mutex<Known> = std::sync::Mutex::new(Vec::new());
    let mut known = KNOWN
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, c)) = known.iter().find(|(p, _)| *p == product) {
        return c.clone();
    }
    let text = super::eds::eds(product, product.max_inverters()).ok();
    let owner = match text.and_then(|t| crate::description::Description::parse(&t, "own EDS").ok())
    {
        Some(crate::description::Description::Eds(e)) => e.owner().cloned(),
        _ => None,
    };
    known.push((product, owner.clone()));
    owner
}

/// Parameters of a Forward_Open step.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ForwardOpenSpec {
    /// The configuration instance of the path.
    pub(crate) config_point: u16,
    /// Points, sizes, configuration instance and run/idle header come from the connection
    /// the device's EDS declares for an owner, each size changed by its delta (bytes) — for
    /// any maker's adapter as for NORD's, whose own EDS the harness reads the same way.
    pub(crate) declared: Option<(i32, i32)>,
    /// O→T connection point (assembly, or 255 listen only).
    pub(crate) o_t_point: u16,
    /// T→O connection point.
    pub(crate) t_o_point: u16,
    /// O→T network connection size.
    pub(crate) o_t_size: u16,
    /// T→O network connection size.
    pub(crate) t_o_size: u16,
    /// RPI both ways, µs.
    pub(crate) rpi_us: u32,
    /// The step gave the RPI; otherwise a declared connection's is the default moved into
    /// the RPI range the EDS declares.
    pub(crate) rpi_given: bool,
    /// Transport type/trigger byte.
    pub(crate) transport: u8,
    /// Timeout multiplier.
    pub(crate) multiplier: u8,
    /// Large_Forward_Open.
    pub(crate) large: bool,
    /// O→T frames carry the 32-bit run/idle header (CIP's default for class-1 O→T).
    pub(crate) run_idle: bool,
}

/// The timeout multiplier of a Forward_Open no step sets: 4, ×64, a connection timeout of 256 ms
/// at the 4 ms RPI. Not the ×16 (64 ms) a PLC with a real-time scheduler asks for: the harness
/// is a process on a shared host, and being descheduled for a few tens of milliseconds is not
/// losing the connection (with ×16 a loaded CI host lost one, and the adapter its T→O data).
/// The steps that stop the I/O wait longer than this.
const DEFAULT_MULTIPLIER: u8 = 4;

impl Default for ForwardOpenSpec {
    fn default() -> Self {
        ForwardOpenSpec {
            config_point: 1,
            declared: None,
            o_t_point: 100,
            t_o_point: 101,
            o_t_size: 0,
            t_o_size: 0,
            rpi_us: RPI.as_micros() as u32,
            rpi_given: false,
            transport: Transport::CLASS1_CYCLIC.0,
            multiplier: DEFAULT_MULTIPLIER,
            large: false,
            run_idle: true,
        }
    }
}

/// A parameter request the target refused with a CIP general status.
fn refused(resp: &MrResponse) -> Observation {
    let text = GeneralStatus(resp.general).to_string();
    Observation::refused(
        json!({
            "value": null,
            "cip_status": resp.general,
            "extended": resp.extended,
            "refused": text,
        }),
        Refusal {
            kind: "CIP general status".into(),
            code: u32::from(resp.general),
            text,
        },
    )
}

/// A request step's fields, as a refusal when the reply's general status is not 00h: the
/// request was not carried out (a refused Set wrote nothing, so counts no EEPROM write).
fn status_refusal(fields: Value) -> Observation {
    match fields["cip_status"].as_u64() {
        Some(code) if code != 0 => {
            let text = GeneralStatus(code as u8).to_string();
            Observation::refused(
                fields,
                Refusal {
                    kind: "CIP general status".into(),
                    code: code as u32,
                    text,
                },
            )
        }
        _ => fields.into(),
    }
}

fn mr_fields(resp: &MrResponse) -> Value {
    json!({
        "service": resp.service,
        "cip_status": resp.general,
        "extended": resp.extended,
        // The first extended word alone: the table's code, whatever follows it (a size).
        "extended_status": resp.extended.first(),
        "status_name": GeneralStatus(resp.general).name(),
        "data": hex(&resp.data),
    })
}

/// An encapsulation reply as step fields; an unconnected CIP reply inside is decoded too.
fn reply_fields(r: &EncapRepr) -> Value {
    let mut v = json!({
        "reply": true,
        "command": r.command,
        "encap_status": r.status,
        "session": r.session,
        "context": hex(&r.context),
        "length": r.data.len(),
        "data": hex(&r.data),
    });
    if let Ok(sd) = SendData::parse(&r.data) {
        if let Some(Item::UnconnectedData(p)) = sd.cpf.items.get(1) {
            if let Ok(resp) = MrResponse::parse(p) {
                v["cip_status"] = json!(resp.general);
                v["extended"] = json!(resp.extended);
            }
        }
    }
    v
}

fn describe_reply(r: &EncapRepr) -> String {
    use std::fmt::Write as _;
    // Written into one string: this runs once per exchange, on the scanner's hot path.
    let mut s = String::with_capacity(96);
    let _ = write!(s, "{}", Command(r.command));
    if r.status != 0 {
        let _ = write!(s, " status {}", EncapStatus(r.status));
    }
    if let Ok(sd) = SendData::parse(&r.data) {
        if let Some(Item::UnconnectedData(p)) = sd.cpf.items.get(1) {
            if let Ok(resp) = MrResponse::parse(p) {
                let _ = write!(s, ": {}", GeneralStatus(resp.general));
                if !resp.extended.is_empty() {
                    let _ = write!(s, " extended {:04X?}", resp.extended);
                }
                if !resp.data.is_empty() && resp.data.len() <= 16 {
                    s.push_str(" data ");
                    s.push_str(&hex(&resp.data));
                }
            }
        }
    }
    s
}

impl Drop for Scanner {
    /// Leaves the target as found: the I/O connection closed, the sessions unregistered (by
    /// the cleanup's own Forward_Close and UnRegisterSession; after a network target's
    /// cleanup there is nothing left to do).
    fn drop(&mut self) {
        if let Some(io) = self.io.take() {
            if self.sessions.contains_key(&1) {
                let _ = self.forward_close(&io.opened);
            }
        }
        self.unregister();
    }
}

impl Scanner {
    /// ListIdentity on the scanner's own connection, for the run's connection check: the
    /// identity item of the reply. It waits [`REACH`](crate::net::wait::REACH) times the limit of one request: a
    /// device that answers, if late, is reachable and says who it is, and its lateness is for
    /// the cases to judge, each against its own limit, with both times (the identity notes
    /// it); one silent for all that time does not answer.
    fn list_identity(&mut self) -> Result<Identity, StepError> {
        let msg = EncapRepr {
            command: Command::LIST_IDENTITY.0,
            context: self.context(),
            ..EncapRepr::default()
        };
        let on_time = self.wait();
        let reach = Deadline::after(on_time.limit() * crate::net::wait::REACH);
        let reply = self
            .send_within(1, msg, "ListIdentity".into(), &reach)?
            .ok_or_else(|| match self.link.timeout() {
                Some(_) => StepError::Link(
                    format!(
                        "no reply to ListIdentity within {} ({} times the limit of one request)",
                        crate::timing::ms(reach.limit()),
                        crate::net::wait::REACH
                    )
                    .into(),
                ),
                None => self.no_reply("ListIdentity", &reach),
            })?;
        let late = (self.link.timeout().is_some() && on_time.passed()).then(|| {
            format!(
                ", answered after {}, past the limit of {}",
                crate::timing::ms(on_time.waited()),
                crate::timing::ms(on_time.limit())
            )
        });
        let malformed = StepError::malformed("malformed ListIdentity reply");
        let cpf = Cpf::parse(&reply.data).map_err(&malformed)?;
        let data = cpf
            .items
            .iter()
            .find_map(|i| match i {
                Item::Other { type_id, data }
                    if *type_id == proto::enip::cpf::item_type::LIST_IDENTITY =>
                {
                    Some(data)
                }
                _ => None,
            })
            .ok_or_else(|| {
                StepError::Protocol("the ListIdentity reply has no identity item (0Ch)".into())
            })?;
        let (id, _) =
            proto::enip::identity::Identity::parse_list_identity_item(data).map_err(&malformed)?;
        Ok(Identity {
            source: format!("ListIdentity{}", late.unwrap_or_default()),
            vendor: Some(format!("vendor id {}", id.vendor)),
            product_code: Some(format!(
                "device type {}, product code {}",
                id.device_type, id.product_code
            )),
            product_name: Some(id.product_name),
            revision: Some(format!("{}.{:03}", id.revision.0, id.revision.1)),
            serial: Some(format!("{:08X}h", id.serial)),
        })
    }
}

impl Binding for Scanner {
    fn describe(&self) -> String {
        self.link.describe()
    }

    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        Some(self.list_identity())
    }

    fn capabilities(&self) -> &[Capability] {
        &self.caps
    }

    fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
        let fields = match action {
            Action::Compute { .. } => Err(StepError::Suite("compute is not a DUT step".into())),
            Action::Read(o) => return self.read(o),
            Action::Write(o) => return self.write(o),
            Action::Pkw { .. } => Err(StepError::NotApplicable(
                "EtherNet/IP has no PKW parameter channel".into(),
            )),
            Action::Process {
                inverter,
                control,
                setpoints,
                run,
            } => {
                self.process[usize::from(inverter.get())] = (*control, setpoints.clone());
                match run {
                    crate::suite::Run::Cycles(n) => self.run_process(*inverter, *n),
                    crate::suite::Run::For(d) => self.run_for(*inverter, *d),
                }
            }
            Action::Wait(d) => {
                let fi = Inverter::new(1).map_err(|e| StepError::Suite(e.into()))?;
                self.run_for(fi, *d)
            }
            Action::Inject { inverter, error } => {
                let (adapter, _) = self.link.adapter().ok_or_else(|| {
                    StepError::Refused("fault injection needs the embedded adapter".into())
                })?;
                adapter
                    .device_mut()
                    .inject_fault(*inverter, error)
                    .map_err(|e| StepError::Refused(e.into()))?;
                Ok(json!({}))
            }
            Action::Observe { what, inverter } => {
                let (adapter, now) = self.link.adapter().ok_or_else(|| {
                    StepError::Refused("observation needs the embedded adapter".into())
                })?;
                observe(adapter, what, *inverter, now).map_err(|e| StepError::Refused(e.into()))
            }
            Action::Bus(step) => {
                let step = crate::binding::own_step::<EnipStep>(step.as_ref(), "EtherNet/IP")?;
                return self.enip_step(step).map(status_refusal);
            }
        };
        fields.map(Observation::from)
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        std::mem::take(&mut self.exchanges)
    }

    fn finish(&mut self) -> Result<(), CleanupError> {
        self.restore().map_err(CleanupError)
    }
}

fn observe(
    a: &mut Adapter,
    what: &str,
    inverter: Inverter,
    now: Duration,
) -> Result<Value, String> {
    if what == "connections" {
        let (owner, listen, explicit) = a.connection_counts();
        return Ok(json!({
            "exclusive_owner": owner,
            "listen_only": listen,
            "explicit": explicit,
            "sessions": a.session_count(),
        }));
    }
    let (ms, ns) = (a.ms_led(), a.ns_led());
    let mut v = observe_device(a.device_mut(), what, inverter, now)?
        .ok_or_else(|| format!("cannot observe `{what}` ({OBSERVABLE}, connections)"))?;
    if what == "leds" {
        v["ms"] = json!(ms);
        v["ns"] = json!(ns);
    }
    Ok(v)
}

/// The RPI of a declared connection: the step's own, or the default moved into the range the
/// EDS declares (min, max in µs), so the device is asked for an interval it says it takes.
fn planned_rpi(s: &ForwardOpenSpec, declared: Option<(u32, u32)>) -> u32 {
    match declared {
        Some((min, max)) if !s.rpi_given && min <= max => s.rpi_us.clamp(min, max),
        _ => s.rpi_us,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_declared_connection_takes_an_rpi_in_the_eds_range_unless_the_step_gives_one() {
        let default = ForwardOpenSpec::default();
        let rpi = default.rpi_us;
        // Within the range: kept; outside: moved to its nearer end; no range: kept.
        assert_eq!(planned_rpi(&default, Some((rpi / 2, rpi * 2))), rpi);
        assert_eq!(planned_rpi(&default, Some((rpi * 4, rpi * 8))), rpi * 4);
        assert_eq!(planned_rpi(&default, Some((1, rpi / 10))), rpi / 10);
        assert_eq!(planned_rpi(&default, None), rpi);
        // A step that gives the RPI gets it, in range or not.
        let given = ForwardOpenSpec {
            rpi_us: 7,
            rpi_given: true,
            ..ForwardOpenSpec::default()
        };
        assert_eq!(planned_rpi(&given, Some((rpi, rpi * 2))), 7);
    }
}
