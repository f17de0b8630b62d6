//! The EtherNet/IP adapter: the simulated device as a CIP target (sans-IO).
//!
//! Drivers feed it whole encapsulation messages from TCP clients ([`Adapter::handle_tcp`],
//! framed by [`Framer`]), UDP datagrams on 44818 ([`Adapter::handle_udp`]) and class-1 I/O on
//! 2222 ([`Adapter::handle_io`]), and ask [`Adapter::poll`] for the T→O frames that are due.
//! Time is always an argument, so the same adapter runs on the virtual clock of the embedded
//! run and on the real clock when served.
//!
//! Objects: Identity (01h), Message Router (02h), Assembly (04h), Connection Manager (06h),
//! TCP/IP Interface (F5h), Ethernet Link (F6h), and the NORD parameter classes 100–108
//! (BU 0620 §2.3.5, BU 2100 §6.3).

mod connections;
mod endpoint;
mod framer;
mod objects;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::net::{SocketAddr, SocketAddrV4};
use std::time::Duration;

use proto::enip::cip::{GeneralStatus, MrResponse};
use proto::enip::cpf::{item_type, Cpf, Item};
use proto::enip::encap::{Command, EncapRepr, EncapStatus, RegisterSession, SendData};
use proto::enip::identity::{list_services_item, Identity};
use proto::nord::{led, Product};

use crate::device::Device;
pub use connections::IoError;
pub use framer::{Framer, Oversize};

/// A TCP client of the adapter, as the driver numbers them.
pub use crate::endpoint::ClientId;

/// Sessions the adapter holds at once unless told otherwise ([`Adapter::with_max_sessions`]);
/// RegisterSession beyond is refused with "insufficient memory" (encapsulation status 0002h),
/// as devices refuse a session they have no room for.
pub const MAX_SESSIONS: usize = 64;

/// The Encapsulation Inactivity Timeout at power-on, seconds (TCP/IP Interface object
/// attribute 13: default 120, 0 disables, at most [`MAX_INACTIVITY_TIMEOUT`]).
pub const DEFAULT_INACTIVITY_TIMEOUT: u16 = 120;
/// The largest Encapsulation Inactivity Timeout attribute 13 takes, seconds.
pub const MAX_INACTIVITY_TIMEOUT: u16 = 3600;

/// What to do after a TCP message.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct TcpReply {
    /// The reply to send, if any.
    pub reply: Option<Vec<u8>>,
    /// Close the TCP connection (after sending the reply).
    pub close: bool,
}

/// The EtherNet/IP adapter.
#[derive(Debug)]
pub struct Adapter {
    device: Device,
    identity: Identity,
    address: SocketAddrV4,
    sessions: HashMap<u32, ClientId>,
    next_session: u32,
    max_sessions: usize,
    /// TCP/IP Interface attribute 13, seconds; kept across an Identity reset as a device
    /// keeps it in non-volatile memory.
    inactivity_timeout: u16,
    conns: connections::Table,
    /// The gateway read in at power-on (P852 / P164, BU 0620 §4.2.2: "After setting, restart
    /// … so that the parameter setting is read in"), as TCP/IP Interface attribute 5 shows it.
    gateway: [u8; 4],
    /// Frames that could not be understood, per kind (for diagnostics and tests).
    dropped: u64,
}

impl Adapter {
    /// An adapter for `device`, answering ListIdentity with `address`.
    ///
    /// # Panics
    /// If the device's product has no EtherNet/IP interface.
    pub fn new(device: Device, address: SocketAddrV4) -> Adapter {
        let product = device.config().product;
        let info = proto::nord::eip::identity(product)
            .unwrap_or_else(|| panic!("{} has no EtherNet/IP interface", product.name()));
        let identity = Identity {
            vendor: info.vendor,
            device_type: info.device_type,
            product_code: info.product_code,
            revision: info.revision,
            status: 0,
            serial: 0x5A00_0000 | u32::from(info.product_code),
            product_name: info.name.to_string(),
            state: 3,
        };
        let mut a = Adapter {
            device,
            identity,
            address,
            sessions: HashMap::new(),
            next_session: 0x1000,
            max_sessions: MAX_SESSIONS,
            inactivity_timeout: DEFAULT_INACTIVITY_TIMEOUT,
            conns: connections::Table::default(),
            gateway: [0; 4],
            dropped: 0,
        };
        objects::power_on(&mut a);
        a
    }

    /// The same adapter holding at most `max` sessions at once.
    pub fn with_max_sessions(mut self, max: usize) -> Adapter {
        self.max_sessions = max;
        self
    }

    /// The Encapsulation Inactivity Timeout (TCP/IP Interface attribute 13), `None` when
    /// disabled. The driver enforces it, as only it sees the TCP connections: one without
    /// encapsulation traffic for this long, and without CIP connections open through it
    /// ([`Adapter::holds_connections`]), is closed.
    pub fn inactivity_timeout(&self) -> Option<Duration> {
        (self.inactivity_timeout != 0)
            .then(|| Duration::from_secs(u64::from(self.inactivity_timeout)))
    }

    /// Whether CIP connections opened by TCP client `client` (class 1 or class 3) are open:
    /// such a TCP connection outlives the inactivity timeout.
    pub fn holds_connections(&self, client: ClientId) -> bool {
        self.conns.any_of(client)
    }

    /// The product simulated.
    pub fn product(&self) -> Product {
        self.device.config().product
    }

    /// The simulated device (for fault injection and observation).
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// The identity the adapter reports.
    pub fn identity(&self) -> &Identity {
        &self.identity
    }

    /// Frames dropped as malformed or for unknown connections.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Open sessions.
    pub fn session_count(&self) -> usize {
        self.sessions.len()
    }

    /// One whole encapsulation message from TCP client `client` at `peer`.
    pub fn handle_tcp(
        &mut self,
        client: ClientId,
        peer: SocketAddr,
        msg: &[u8],
        now: Duration,
    ) -> TcpReply {
        self.poll_timeouts(now);
        let req = match EncapRepr::parse(msg) {
            Ok(r) => r,
            Err(_) => {
                // A framed message always parses; anything else cannot be answered in kind.
                self.dropped += 1;
                return TcpReply {
                    reply: None,
                    close: true,
                };
            }
        };
        if req.options != 0 {
            // "the receiver shall discard the packet" (non-zero options).
            self.dropped += 1;
            return TcpReply::default();
        }
        let reply = |status: EncapStatus, data: Vec<u8>| TcpReply {
            reply: req.reply(status, data).emit().ok(),
            close: false,
        };
        match Command(req.command) {
            Command::NOP => TcpReply::default(),
            Command::LIST_IDENTITY | Command::LIST_SERVICES | Command::LIST_INTERFACES => {
                let (status, data) = self.list(Command(req.command), &req.data);
                reply(status, data)
            }
            Command::REGISTER_SESSION => match self.register(client, &req) {
                Ok(handle) => TcpReply {
                    reply: EncapRepr {
                        session: handle,
                        ..req.reply(EncapStatus::SUCCESS, RegisterSession::V1.emit())
                    }
                    .emit()
                    .ok(),
                    close: false,
                },
                Err(status) => reply(status, RegisterSession::V1.emit()),
            },
            Command::UNREGISTER_SESSION => {
                if self.sessions.get(&req.session) == Some(&client) {
                    self.sessions.remove(&req.session);
                    self.conns.client_closed(client);
                    TcpReply {
                        reply: None,
                        close: true,
                    }
                } else {
                    reply(EncapStatus::INVALID_SESSION, Vec::new())
                }
            }
            Command::SEND_RR_DATA | Command::SEND_UNIT_DATA => {
                if self.sessions.get(&req.session) != Some(&client) {
                    return reply(EncapStatus::INVALID_SESSION, Vec::new());
                }
                let connected = Command(req.command) == Command::SEND_UNIT_DATA;
                match self.send_data(client, peer, &req.data, connected, now) {
                    Ok(Some(data)) => reply(EncapStatus::SUCCESS, data),
                    Ok(None) => TcpReply::default(),
                    Err(status) => reply(status, Vec::new()),
                }
            }
            _ => reply(EncapStatus::INVALID_COMMAND, Vec::new()),
        }
    }

    /// A TCP client went away: its sessions and explicit connections end.
    pub fn client_closed(&mut self, client: ClientId) {
        self.sessions.retain(|_, c| *c != client);
        self.conns.client_closed(client);
    }

    /// One UDP datagram on port 44818: ListIdentity, ListServices and ListInterfaces are
    /// answered (broadcast discovery); anything else is dropped, as UDP carries no sessions.
    pub fn handle_udp(&mut self, msg: &[u8]) -> Option<Vec<u8>> {
        let req = EncapRepr::parse(msg).ok()?;
        let command = Command(req.command);
        if req.options != 0
            || !matches!(
                command,
                Command::LIST_IDENTITY | Command::LIST_SERVICES | Command::LIST_INTERFACES
            )
        {
            self.dropped += 1;
            return None;
        }
        let (status, data) = self.list(command, &req.data);
        req.reply(status, data).emit().ok()
    }

    fn list(&self, command: Command, data: &[u8]) -> (EncapStatus, Vec<u8>) {
        if !data.is_empty() {
            return (EncapStatus::INVALID_LENGTH, Vec::new());
        }
        let items = match command {
            Command::LIST_IDENTITY => vec![Item::Other {
                type_id: item_type::LIST_IDENTITY,
                data: self.identity.list_identity_item(self.address),
            }],
            Command::LIST_SERVICES => vec![Item::Other {
                type_id: item_type::LIST_SERVICES,
                data: list_services_item(),
            }],
            _ => Vec::new(),
        };
        match Cpf::new(items).emit() {
            Ok(b) => (EncapStatus::SUCCESS, b),
            Err(_) => (EncapStatus::INSUFFICIENT_MEMORY, Vec::new()),
        }
    }

    /// A new session for `client`, or why not.
    fn register(&mut self, client: ClientId, req: &EncapRepr) -> Result<u32, EncapStatus> {
        let rs = RegisterSession::parse(&req.data).map_err(|_| EncapStatus::INVALID_LENGTH)?;
        if rs.version != 1 || rs.options != 0 {
            return Err(EncapStatus::UNSUPPORTED_PROTOCOL);
        }
        if req.session != 0 || self.sessions.values().any(|c| *c == client) {
            return Err(EncapStatus::INCORRECT_DATA);
        }
        if self.sessions.len() >= self.max_sessions {
            return Err(EncapStatus::INSUFFICIENT_MEMORY);
        }
        let handle = self.next_session;
        self.next_session = self.next_session.wrapping_add(1).max(1);
        self.sessions.insert(handle, client);
        Ok(handle)
    }

    /// SendRRData (UCMM) or SendUnitData (class-3 connected): the CIP request inside, answered.
    fn send_data(
        &mut self,
        client: ClientId,
        peer: SocketAddr,
        data: &[u8],
        connected: bool,
        now: Duration,
    ) -> Result<Option<Vec<u8>>, EncapStatus> {
        let sd = SendData::parse(data).map_err(|_| EncapStatus::INCORRECT_DATA)?;
        if sd.interface != 0 {
            return Err(EncapStatus::INCORRECT_DATA);
        }
        let items = &sd.cpf.items;
        let reply_items = if connected {
            let (Some(Item::ConnectedAddress(id)), Some(Item::ConnectedData(payload))) =
                (items.first(), items.get(1))
            else {
                return Err(EncapStatus::INCORRECT_DATA);
            };
            if items.len() != 2 || payload.len() < 2 {
                return Err(EncapStatus::INCORRECT_DATA);
            }
            let Some(t_o_id) = self.conns.explicit(*id, client, now) else {
                // Data for a connection that does not exist is discarded.
                self.dropped += 1;
                return Ok(None);
            };
            let seq = [payload[0], payload[1]];
            let resp = objects::request(self, client, peer, &payload[2..], now);
            let mut out = seq.to_vec();
            out.extend(resp.emit());
            vec![Item::ConnectedAddress(t_o_id), Item::ConnectedData(out)]
        } else {
            let (Some(Item::Null), Some(Item::UnconnectedData(req))) =
                (items.first(), items.get(1))
            else {
                return Err(EncapStatus::INCORRECT_DATA);
            };
            if items[2..]
                .iter()
                .any(|i| !matches!(i, Item::SockaddrOT(_) | Item::SockaddrTO(_)))
            {
                return Err(EncapStatus::INCORRECT_DATA);
            }
            let resp = objects::request(self, client, peer, req, now);
            vec![Item::Null, Item::UnconnectedData(resp.emit())]
        };
        let out = SendData {
            interface: 0,
            timeout: 0,
            cpf: Cpf::new(reply_items),
        };
        out.emit()
            .map(Some)
            .map_err(|_| EncapStatus::INSUFFICIENT_MEMORY)
    }

    /// One class-1 datagram from `peer` (UDP 2222).
    pub fn handle_io(
        &mut self,
        peer: SocketAddr,
        datagram: &[u8],
        now: Duration,
    ) -> Result<(), IoError> {
        self.poll_timeouts(now);
        let r = connections::consume(self, peer, datagram, now);
        if r.is_err() {
            self.dropped += 1;
        }
        r
    }

    /// T→O frames due at `now`, with their destinations; runs the connection watchdogs.
    pub fn poll(&mut self, now: Duration) -> Vec<(SocketAddr, Vec<u8>)> {
        self.poll_timeouts(now);
        connections::produce(self, now)
    }

    /// When [`Adapter::poll`] has something to do next.
    pub fn next_due(&self) -> Option<Duration> {
        self.conns.next_due()
    }

    fn poll_timeouts(&mut self, now: Duration) {
        connections::watchdogs(self, now);
        self.device.tick(now);
    }

    /// LED "MS" (module state): steady green once the interface runs (BU 0620 §5.5.2.2).
    pub fn ms_led(&self) -> led::Row {
        led::ETHERNETIP_MS
            .iter()
            .copied()
            .find(|r| r.pattern == led::Pattern::Green)
            .unwrap_or(led::ETHERNETIP_MS[0])
    }

    /// LED "NS" (network state): green while a CIP connection exists; flashing red after an
    /// exclusive owner timed out (until the next connection); flashing green otherwise —
    /// "IP address configured but no CIP connection available" (BU 0620 §5.5.2.2).
    pub fn ns_led(&self) -> led::Row {
        let want = if self.conns.any_open() {
            led::Pattern::Green
        } else if self.conns.owner_timed_out() {
            led::Pattern::FlashingRed { tenths_hz: 10 }
        } else {
            led::Pattern::FlashingGreen { tenths_hz: 10 }
        };
        led::ETHERNETIP_NS
            .iter()
            .copied()
            .find(|r| r.pattern == want)
            .unwrap_or(led::ETHERNETIP_NS[0])
    }

    /// Open connections by kind: (exclusive owner, listen only, explicit).
    pub fn connection_counts(&self) -> (usize, usize, usize) {
        self.conns.counts()
    }
}

/// What an adapter with no room for another TCP client answers to the client's first message
/// before it closes the connection: "insufficient memory" (encapsulation status 0002h), the
/// status of a RegisterSession it cannot grant, to every command that is answered. `None` for
/// a NOP (never answered) and for bytes that are no message.
pub fn no_room_reply(msg: &[u8]) -> Option<Vec<u8>> {
    let req = EncapRepr::parse(msg).ok()?;
    let data = match Command(req.command) {
        Command::NOP => return None,
        Command::REGISTER_SESSION => RegisterSession::V1.emit(),
        _ => Vec::new(),
    };
    req.reply(EncapStatus::INSUFFICIENT_MEMORY, data)
        .emit()
        .ok()
}

/// An error reply for a request that could not be parsed.
fn malformed(service: u8, status: GeneralStatus) -> MrResponse {
    MrResponse::error(service, status)
}
