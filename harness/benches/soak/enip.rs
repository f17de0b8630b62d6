//! The EtherNet/IP soak over loopback: `harness serve enip` as a process of its own, good
//! clients reading the Identity object's product name (Get_Attribute_Single, class 01h
//! instance 1 attribute 7: a read-only attribute whose answer is known from the product, so a
//! fuzzed Set_Attribute_Single cannot change it), and fuzzed clients sending broken
//! encapsulation messages over TCP (a few connections each, some with a registered session,
//! opened and closed at random) and broken datagrams to UDP 44818 and the class-1 port 2222.

use std::io::{ErrorKind, Read, Write};
use std::net::{SocketAddr, TcpStream, UdpSocket};
use std::ops::Range;
use std::time::Duration;

use proto::enip::cip::{class, MrRequest, Service};
use proto::enip::encap::{Command as EncapCommand, EncapRepr, RegisterSession};
use proto::enip::epath::EPath;
use proto::enip::identity::short_string;
use proto::enip::io::IoFrame;
use proto::nord::{eip, Product};

use super::common::enip_client::{send_rr_data, Client};
use super::common::served::Served;
use super::mutate::Mutator;
use super::run::{Answer, Bus};

/// The product served.
const PRODUCT: Product = Product::Tu3Eip;
/// Product name: attribute 7 of the Identity object (`proto::enip::identity::Identity`).
const PRODUCT_NAME: u16 = 7;
/// TCP connections each fuzzed client keeps at most.
const CONNECTIONS: usize = 8;
/// Where the encapsulation length lies: bytes 2–3 of the header (`proto::enip::encap`).
const LENGTH: Range<usize> = 2..4;
/// Broken messages are at most this long.
const MAX_LEN: usize = 600;
/// How long a fuzzed client waits on a connection, a registration or a write.
const PATIENCE: Duration = Duration::from_millis(200);

/// The served adapter and what its answers must be.
pub(crate) struct Enip {
    listen: SocketAddr,
    io: SocketAddr,
    path: EPath,
    expected: Vec<u8>,
}

/// Starts `harness serve enip` on `listen` (127.0.0.x:port) for `seconds` at most, with
/// `start` (which runs `harness serve BUS ARGS…`).
pub(crate) fn serve(
    listen: SocketAddr,
    seconds: u64,
    start: impl FnOnce(&str, &[&str]) -> Result<(Served, String), String>,
) -> Result<(Served, String, Enip), String> {
    let name = eip::identity(PRODUCT)
        .ok_or("the product has no EtherNet/IP identity")?
        .name;
    let (listen_arg, seconds) = (listen.to_string(), seconds.to_string());
    let (served, line) = start(
        "enip",
        &[
            "--listen",
            &listen_arg,
            "--profile",
            "tu3-eip",
            "--seconds",
            &seconds,
        ],
    )?;
    let bus = Enip {
        listen,
        io: SocketAddr::new(listen.ip(), proto::enip::io::IO_PORT),
        path: EPath::attribute(class::IDENTITY, 1, PRODUCT_NAME),
        expected: short_string(name),
    };
    Ok((served, line, bus))
}

/// A fuzzed client: its generator, its TCP connections (with the session each registered, or
/// 0), a UDP socket, and the good messages it breaks.
pub(crate) struct Fuzzer {
    mutator: Mutator,
    tcp: Vec<Option<(TcpStream, u32)>>,
    udp: UdpSocket,
    messages: Vec<EncapRepr>,
    io_frames: Vec<Vec<u8>>,
}

impl Bus for Enip {
    type Good = Client;
    type Fuzz = Fuzzer;

    fn good(&self, _: usize) -> Result<Client, String> {
        Client::connect(self.listen)
    }

    fn ask(&self, client: &mut Client) -> Answer {
        match client.get(&self.path) {
            Ok(v) if v == self.expected => Answer::Right,
            Ok(v) => Answer::Wrong(format!("product name {v:02x?}")),
            // A refusal is counted here too: either way no right answer came.
            Err(e) => Answer::Lost(e),
        }
    }

    fn fuzzer(&self, seed: u64) -> Result<Fuzzer, String> {
        let udp = UdpSocket::bind("127.0.0.1:0").map_err(|e| format!("UDP socket: {e}"))?;
        udp.set_nonblocking(true).map_err(|e| e.to_string())?;
        Ok(Fuzzer {
            mutator: Mutator::new(seed),
            tcp: (0..CONNECTIONS).map(|_| None).collect(),
            udp,
            messages: good_messages(&self.path)?,
            io_frames: io_frames()?,
        })
    }

    fn fuzz(&self, f: &mut Fuzzer) -> u64 {
        match f.mutator.rng().u8(..10) {
            0..=7 => self.fuzz_tcp(f),
            8 => {
                let msgs = emitted(&f.messages, 0);
                let m = f
                    .mutator
                    .mutate(&msgs, std::slice::from_ref(&LENGTH), MAX_LEN);
                let _ = f.udp.send_to(&m, self.listen);
                drain_udp(&f.udp);
                1
            }
            _ => {
                let m = f.mutator.mutate(&f.io_frames, &[], MAX_LEN);
                let _ = f.udp.send_to(&m, self.io);
                drain_udp(&f.udp);
                1
            }
        }
    }
}

impl Enip {
    /// One broken message on one of the client's connections (opened first if need be, and
    /// now and then closed after), its replies read and dropped.
    fn fuzz_tcp(&self, f: &mut Fuzzer) -> u64 {
        let slot = f.mutator.rng().usize(..CONNECTIONS);
        if f.tcp[slot].is_none() {
            let register = f.mutator.rng().bool();
            f.tcp[slot] = open(self.listen, register);
        }
        let Some((tcp, session)) = &mut f.tcp[slot] else {
            return 0;
        };
        let msgs = emitted(&f.messages, *session);
        let m = f
            .mutator
            .mutate(&msgs, std::slice::from_ref(&LENGTH), MAX_LEN);
        let alive = tcp.write_all(&m).is_ok() && drain_tcp(tcp);
        if !alive || f.mutator.rng().u8(..8) == 0 {
            f.tcp[slot] = None;
        }
        1
    }
}

/// A connection to `at`, with a session registered when `register` (0 when not, or when the
/// registration was not answered).
fn open(at: SocketAddr, register: bool) -> Option<(TcpStream, u32)> {
    let mut tcp = TcpStream::connect_timeout(&at, PATIENCE).ok()?;
    tcp.set_write_timeout(Some(PATIENCE)).ok()?;
    tcp.set_read_timeout(Some(PATIENCE)).ok()?;
    let mut session = 0;
    if register {
        let msg = EncapRepr {
            command: EncapCommand::REGISTER_SESSION.0,
            data: RegisterSession::V1.emit(),
            ..EncapRepr::default()
        };
        tcp.write_all(&msg.emit().ok()?).ok()?;
        let mut reply = [0u8; 28];
        if tcp.read_exact(&mut reply).is_ok() {
            session = EncapRepr::parse(&reply).map_or(0, |r| r.session);
        }
    }
    tcp.set_nonblocking(true).ok()?;
    Some((tcp, session))
}

/// Reads and drops what has come back; `false` once the adapter has closed the connection.
fn drain_tcp(tcp: &mut TcpStream) -> bool {
    let mut buf = [0u8; 4096];
    loop {
        match tcp.read(&mut buf) {
            Ok(0) => return false,
            Ok(_) => {}
            Err(e) if e.kind() == ErrorKind::WouldBlock => return true,
            Err(_) => return false,
        }
    }
}

fn drain_udp(udp: &UdpSocket) {
    let mut buf = [0u8; 2048];
    while udp.recv(&mut buf).is_ok() {}
}

/// The good messages broken: the list and registration commands, and unconnected requests
/// (the product name, a parameter, all of the Identity object) in SendRRData.
fn good_messages(path: &EPath) -> Result<Vec<EncapRepr>, String> {
    let plain = |c: EncapCommand| EncapRepr {
        command: c.0,
        ..EncapRepr::default()
    };
    let mut out = vec![
        plain(EncapCommand::NOP),
        plain(EncapCommand::LIST_IDENTITY),
        plain(EncapCommand::LIST_SERVICES),
        plain(EncapCommand::LIST_INTERFACES),
        plain(EncapCommand::UNREGISTER_SESSION),
        EncapRepr {
            command: EncapCommand::REGISTER_SESSION.0,
            data: RegisterSession::V1.emit(),
            ..EncapRepr::default()
        },
    ];
    let requests = [
        (Service::GET_ATTRIBUTE_SINGLE, path.clone()),
        (
            Service::GET_ATTRIBUTE_SINGLE,
            EPath::attribute(eip::param_class(None), 0, 102),
        ),
        (
            Service::GET_ATTRIBUTES_ALL,
            EPath::object(class::IDENTITY, 1),
        ),
    ];
    for (service, path) in requests {
        let req = MrRequest {
            service: service.0,
            path,
            data: Vec::new(),
        };
        out.push(send_rr_data(&req, 0)?);
    }
    Ok(out)
}

/// `messages` in session `session`, as bytes.
fn emitted(messages: &[EncapRepr], session: u32) -> Vec<Vec<u8>> {
    messages
        .iter()
        .filter_map(|m| {
            EncapRepr {
                session,
                ..m.clone()
            }
            .emit()
            .ok()
        })
        .collect()
}

/// Class-1 datagrams to connections that may or may not exist.
fn io_frames() -> Result<Vec<Vec<u8>>, String> {
    [0u32, 1, 0x4245_0001]
        .into_iter()
        .map(|connection| {
            IoFrame {
                connection,
                sequence: 1,
                count: 1,
                run_idle: Some(1),
                data: vec![0; 96],
            }
            .emit()
            .map_err(|e| e.to_string())
        })
        .collect()
}
