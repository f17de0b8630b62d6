//! The POWERLINK soak over a veth pair: `harness serve epl` (a process of its own) in a network
//! namespace on one end at node 1's address 192.168.100.1 (BU 0620 §3.7.3), the clients in a
//! second namespace on the other end at the MN's 192.168.100.240, as `harness run` and the
//! POWERLINK bench put them (neither end in the root namespace, where a test may have the
//! POWERLINK subnet on a veth end of its own).
//!
//! The node is stateful (NMT state, SDO connections), and what it sends in the isochronous
//! phase (PRes, IdentResponse, StatusResponse) carries no request's id, so the good clients
//! use the one exchange that does: SDO over UDP (EPSG DS 301 §6.3.2.1), each client with a
//! connection of its own (the node keys them by address and port) reading the vendor id
//! 1018h:01h (BU 0620 §2.4.6) with its own transaction id, an object no write changes. The
//! node answers UDP once it has left NOT_ACTIVE (BU 0620 §2.4.4: after its Basic Ethernet
//! time-out when no MN is cycling), which the first read waits for. Fuzzed clients send
//! broken POWERLINK frames (SoC, PReq, SoA, ASnd) and broken SDO datagrams from ports of
//! their own; none of the good frames they break is an NMT command, so the node's state
//! moves only as a broken frame happens to make it.

use std::net::{SocketAddr, UdpSocket};
use std::ops::Range;
use std::time::{Duration, Instant};

use proto::epl::frame::{Asnd, Body, Preq, Soa, Soc};
use proto::epl::sdo::{Command, Con, SdoFrame, Segmentation, Seq, SEQ_MODULO};
use proto::epl::{
    EplRepr, NmtState, RequestedService, ServiceId, BROADCAST_NODE_ID, MULTICAST_SOC, SDO_UDP_PORT,
};
use proto::eth::ETHERTYPE_POWERLINK;

use super::common::ClientNs;
use super::mutate::Mutator;
use super::raw::{client_mac, RawSocket};
use super::run::{Answer, Bus};

/// The node id served (`harness serve epl`'s default).
const NODE: u8 = 1;
/// The object read: the identity object's vendor id.
const VENDOR_ID: (u16, u8) = (0x1018, 1);
/// How long a good client waits for an answer.
const TIMEOUT: Duration = Duration::from_secs(1);
/// How long the first read waits for the node to leave NOT_ACTIVE.
const FIRST_READ: Duration = Duration::from_secs(15);
/// Length fields of a frame: the PReq/PRes payload size (bytes 8–9 after the Ethernet
/// header) and an SDO command's segment size (bytes 12–13 of a datagram): broken to lie.
const LENGTHS: [Range<usize>; 2] = [8..10, 12..14];
/// Broken payloads are at most this long (a full Ethernet payload).
const MAX_LEN: usize = 1500;

/// The clients' namespace and the node's SDO address, and what its answer must be.
pub(crate) struct Epl {
    clients: ClientNs,
    node: SocketAddr,
    expected: Vec<u8>,
}

/// A good client: its socket, its connection (sequence numbers sent and received; `None`
/// until opened, or after an answer was lost) and its last transaction id.
pub(crate) struct Good {
    socket: UdpSocket,
    connection: Option<(u8, u8)>,
    transaction: u8,
}

/// A fuzzed client: a packet socket and a UDP socket of its own.
pub(crate) struct Fuzzer {
    raw: RawSocket,
    udp: UdpSocket,
    mutator: Mutator,
    frames: Vec<Vec<u8>>,
    datagrams: Vec<Vec<u8>>,
}

impl Epl {
    /// The bus on `root_if` (moved into the clients' namespace at the MN's address); the
    /// known answer is read once, before any broken frame is sent.
    pub(crate) fn new(root_if: &str) -> Result<Epl, String> {
        let mn_ip = proto::nord::epl::ip_address(proto::epl::MN_NODE_ID);
        let clients = ClientNs::new(root_if, "soak-epl-clients", &format!("{mn_ip}/24"))?;
        let node = SocketAddr::from((proto::nord::epl::ip_address(NODE), SDO_UDP_PORT));
        let mut bus = Epl {
            clients,
            node,
            expected: Vec::new(),
        };
        let mut good = bus.good(0)?;
        let until = Instant::now() + FIRST_READ;
        bus.expected = loop {
            match read(&mut good, node) {
                Ok(data) => break data,
                Err(e) if Instant::now() >= until => {
                    return Err(format!(
                        "no answer to the first read within {} s: {e}",
                        FIRST_READ.as_secs()
                    ))
                }
                Err(_) => {}
            }
        };
        Ok(bus)
    }

    /// What the soak found, for the report.
    pub(crate) fn said(&self) -> String {
        format!(
            "clients in {} on {}; known answer of 1018h:01h {:02x?}",
            self.clients.name, self.clients.iface, self.expected
        )
    }

    /// A UDP socket in the clients' namespace, on a port of its own.
    fn udp(&self) -> Result<UdpSocket, String> {
        let socket = self
            .clients
            .run(|| UdpSocket::bind(("0.0.0.0", 0)))?
            .map_err(|e| format!("UDP socket: {e}"))?;
        socket
            .set_read_timeout(Some(Duration::from_millis(5)))
            .map_err(|e| e.to_string())?;
        Ok(socket)
    }
}

impl Bus for Epl {
    type Good = Good;
    type Fuzz = Fuzzer;

    fn good(&self, _: usize) -> Result<Good, String> {
        Ok(Good {
            socket: self.udp()?,
            connection: None,
            transaction: 0,
        })
    }

    fn ask(&self, client: &mut Good) -> Answer {
        match read(client, self.node) {
            Ok(data) if data == self.expected => Answer::Right,
            Ok(data) => Answer::Wrong(format!("1018h:01h read {data:02x?}")),
            Err(e) => {
                client.connection = None;
                Answer::Lost(e)
            }
        }
    }

    fn fuzzer(&self, seed: u64) -> Result<Fuzzer, String> {
        let iface = self.clients.iface.clone();
        let raw = self
            .clients
            .run(|| RawSocket::open(&iface, client_mac(0x46, seed as u8)))??;
        let udp = self.udp()?;
        // Its answers are drained without waiting.
        udp.set_nonblocking(true).map_err(|e| e.to_string())?;
        Ok(Fuzzer {
            raw,
            udp,
            mutator: Mutator::new(seed),
            frames: good_frames()?,
            datagrams: good_datagrams()?,
        })
    }

    fn fuzz(&self, f: &mut Fuzzer) -> u64 {
        if f.mutator.rng().bool() {
            let m = f.mutator.mutate(&f.frames, &LENGTHS, MAX_LEN);
            u64::from(f.raw.send(MULTICAST_SOC, ETHERTYPE_POWERLINK, &m))
        } else {
            let m = f.mutator.mutate(&f.datagrams, &LENGTHS, MAX_LEN);
            let sent = f.udp.send_to(&m, self.node).is_ok();
            // Whatever the node answers is read and dropped, so the socket never fills.
            let mut buf = [0; 1500];
            while f.udp.recv(&mut buf).is_ok() {}
            u64::from(sent)
        }
    }
}

/// One read of 1018h:01h over the client's connection (opened first if need be): its data,
/// or why there was none.
fn read(client: &mut Good, node: SocketAddr) -> Result<Vec<u8>, String> {
    let (sent, received) = match client.connection {
        Some(c) => c,
        None => open(client, node)?,
    };
    client.transaction = (client.transaction + 1) % 16;
    let tid = client.transaction;
    let sent = (sent + 1) % SEQ_MODULO;
    let request = SdoFrame {
        seq: Seq {
            rsnr: received,
            rcon: Con::Valid,
            ssnr: sent,
            scon: Con::Valid,
        },
        command: Some(Command::read_by_index(tid, VENDOR_ID.0, VENDOR_ID.1)),
    };
    let answer = exchange(client, node, &request, |f| {
        f.command.as_ref().is_some_and(|c| c.transaction == tid)
    })?;
    client.connection = Some((sent, answer.seq.ssnr));
    match answer.command {
        Some(c) if c.abort => Err(format!("aborted: {:08X}h", c.abort_code().unwrap_or(0))),
        Some(c) if c.response && c.segmentation == Segmentation::Expedited => Ok(c.payload),
        Some(c) => Err(format!("an answer not expedited: {c:?}")),
        None => Err("an answer without a command".into()),
    }
}

/// DS 301's connection set-up: initialisation, the node's initialisation back, valid, the
/// node's valid back; the sequence numbers (sent, received) to go on with.
fn open(client: &mut Good, node: SocketAddr) -> Result<(u8, u8), String> {
    let init = SdoFrame {
        seq: Seq {
            scon: Con::Init,
            ..Seq::default()
        },
        command: None,
    };
    let ack = exchange(client, node, &init, |f| f.seq.rcon == Con::Init)?;
    let confirm = SdoFrame {
        seq: Seq {
            rsnr: ack.seq.ssnr,
            rcon: Con::Init,
            ssnr: 0,
            scon: Con::Valid,
        },
        command: None,
    };
    let valid = exchange(client, node, &confirm, |f| {
        f.seq.rcon == Con::Valid && f.seq.scon == Con::Valid
    })?;
    Ok((0, valid.seq.ssnr))
}

/// Sends `frame` to the node and waits for the first SDO datagram from it that `ours` takes.
fn exchange(
    client: &mut Good,
    node: SocketAddr,
    frame: &SdoFrame,
    ours: impl Fn(&SdoFrame) -> bool,
) -> Result<SdoFrame, String> {
    let bytes = frame.emit_udp().map_err(|e| e.to_string())?;
    client
        .socket
        .send_to(&bytes, node)
        .map_err(|e| format!("send: {e}"))?;
    let deadline = Instant::now() + TIMEOUT;
    let mut buf = [0; 1500];
    while Instant::now() < deadline {
        let Ok((n, from)) = client.socket.recv_from(&mut buf) else {
            continue;
        };
        let parsed = SdoFrame::strip_udp(&buf[..n]).and_then(SdoFrame::parse);
        match parsed {
            Ok(f) if from == node && ours(&f) => return Ok(f),
            _ => {}
        }
    }
    Err(format!("no answer within {} ms", TIMEOUT.as_millis()))
}

/// The good frames broken (the payloads after the Ethernet header): a SoC, a PReq to the
/// node, SoAs inviting its IdentResponse and StatusResponse, and the start of another node's
/// IdentResponse.
fn good_frames() -> Result<Vec<Vec<u8>>, String> {
    let mn = proto::epl::MN_NODE_ID;
    let frame = |dst, src, body| EplRepr { dst, src, body };
    let soa = |service| {
        Body::Soa(Soa {
            state: NmtState::PRE_OPERATIONAL_1,
            service,
            target: NODE,
            epl_version: 0x20,
            ..Soa::default()
        })
    };
    [
        frame(BROADCAST_NODE_ID, mn, Body::Soc(Soc::default())),
        frame(
            NODE,
            mn,
            Body::Preq(Preq {
                payload: vec![0; 8],
                ..Preq::default()
            }),
        ),
        frame(BROADCAST_NODE_ID, mn, soa(RequestedService::IDENT_REQUEST)),
        frame(BROADCAST_NODE_ID, mn, soa(RequestedService::STATUS_REQUEST)),
        frame(
            BROADCAST_NODE_ID,
            2,
            Body::Asnd(Asnd {
                service: ServiceId::IDENT_RESPONSE,
                payload: vec![0; 16],
            }),
        ),
    ]
    .iter()
    .map(|f| f.emit().map_err(|e| e.to_string()))
    .collect()
}

/// The good datagrams broken: an initialisation, a read and a write of a connection never
/// opened.
fn good_datagrams() -> Result<Vec<Vec<u8>>, String> {
    let seq = |scon| Seq {
        scon,
        ..Seq::default()
    };
    [
        SdoFrame {
            seq: seq(Con::Init),
            command: None,
        },
        SdoFrame {
            seq: seq(Con::Valid),
            command: Some(Command::read_by_index(3, VENDOR_ID.0, VENDOR_ID.1)),
        },
        SdoFrame {
            seq: seq(Con::Valid),
            command: Some(Command::write_by_index(
                4,
                0x1006,
                0,
                &1000u32.to_le_bytes(),
            )),
        },
    ]
    .iter()
    .map(|f| f.emit_udp().map_err(|e| e.to_string()))
    .collect()
}
