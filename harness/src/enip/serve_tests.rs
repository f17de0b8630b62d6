//! `harness serve enip` over real sockets on loopback: the inactivity timeout on the real
//! clock, the session, connection and Forward_Open limits answered with the protocols' own
//! refusals, and idle clients that cost no thread. Each test serves its own adapter on an
//! address of its own (127.0.7.21–.28; other tests and the benches take 127.0.0.x).

use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use proto::enip::cip::{class, GeneralStatus as GS, MrRequest, MrResponse, Service};
use proto::enip::cm::{ext, kind, ForwardClose, ForwardOpen, NetParams, Transport};
use proto::enip::cpf::{Cpf, Item};
use proto::enip::encap::{frame_len, Command, EncapRepr, EncapStatus, RegisterSession, SendData};
use proto::enip::epath::EPath;
use proto::nord::Product;
use sim::device::DeviceConfig;

use super::serve::{start_enip, Limits};
use crate::net::misbehave::Misbehaviour;

/// How long a test waits for any one reply.
const REPLY: Duration = Duration::from_secs(3);

fn serve(last_octet: u8, limits: Limits) -> SocketAddr {
    serve_late(last_octet, limits, Duration::ZERO)
}

/// An adapter whose replies leave `delay` late (`--misbehave late=…`; none when zero).
fn serve_late(last_octet: u8, limits: Limits, delay: Duration) -> SocketAddr {
    let listen = SocketAddr::from((Ipv4Addr::new(127, 0, 7, last_octet), 44818));
    let misbehave = if delay.is_zero() {
        Misbehaviour::default()
    } else {
        Misbehaviour::late(delay)
    };
    start_enip(
        listen,
        DeviceConfig::new(Product::Tu3Eip),
        limits,
        misbehave,
    )
    .expect("serve on a loopback address of its own")
    .listen
}

/// A bare encapsulation client on a blocking socket.
struct Client {
    tcp: TcpStream,
    session: u32,
    buf: Vec<u8>,
}

impl Client {
    fn connect(at: SocketAddr) -> Client {
        let tcp = TcpStream::connect(at).expect("connect");
        tcp.set_read_timeout(Some(REPLY)).unwrap();
        Client {
            tcp,
            session: 0,
            buf: Vec::new(),
        }
    }

    /// The next whole message, or why none came: `Ok(None)` is the adapter's close.
    fn receive(&mut self) -> std::io::Result<Option<EncapRepr>> {
        let mut chunk = [0u8; 4096];
        loop {
            if let Some(n) = frame_len(&self.buf).filter(|n| self.buf.len() >= *n) {
                let m = EncapRepr::parse(&self.buf[..n]).expect("a well-formed reply");
                self.buf.drain(..n);
                return Ok(Some(m));
            }
            match self.tcp.read(&mut chunk)? {
                0 => return Ok(None),
                n => self.buf.extend_from_slice(&chunk[..n]),
            }
        }
    }

    fn exchange(&mut self, command: Command, data: Vec<u8>) -> EncapRepr {
        let msg = EncapRepr {
            command: command.0,
            session: self.session,
            data,
            ..EncapRepr::default()
        };
        self.tcp.write_all(&msg.emit().unwrap()).expect("send");
        self.receive()
            .expect("a reply in time")
            .expect("a reply, not a close")
    }

    /// RegisterSession: its reply, the handle kept when granted.
    fn register(&mut self) -> EncapRepr {
        let r = self.exchange(Command::REGISTER_SESSION, RegisterSession::V1.emit());
        if r.status == 0 {
            self.session = r.session;
        }
        r
    }

    fn registered(at: SocketAddr) -> Client {
        let mut c = Client::connect(at);
        assert_eq!(EncapStatus(c.register().status), EncapStatus::SUCCESS);
        c
    }

    fn request(&mut self, service: Service, path: EPath, data: Vec<u8>) -> MrResponse {
        let req = MrRequest {
            service: service.0,
            path,
            data,
        };
        let sd = SendData {
            interface: 0,
            timeout: 0,
            cpf: Cpf::new(vec![Item::Null, Item::UnconnectedData(req.emit())]),
        };
        let r = self.exchange(Command::SEND_RR_DATA, sd.emit().unwrap());
        assert_eq!(EncapStatus(r.status), EncapStatus::SUCCESS);
        let sd = SendData::parse(&r.data).unwrap();
        let Some(Item::UnconnectedData(b)) = sd.cpf.items.get(1) else {
            panic!("reply items {:?}", sd.cpf.items)
        };
        MrResponse::parse(b).unwrap()
    }

    fn inactivity_timeout(&mut self) -> u16 {
        let path = EPath::attribute(class::TCP_IP, 1, 13);
        let r = self.request(Service::GET_ATTRIBUTE_SINGLE, path, Vec::new());
        assert_eq!(r.status(), GS::SUCCESS, "{r:?}");
        u16::from_le_bytes(r.data[..].try_into().expect("a UINT"))
    }

    fn set_inactivity_timeout(&mut self, seconds: u16) -> MrResponse {
        let path = EPath::attribute(class::TCP_IP, 1, 13);
        let data = seconds.to_le_bytes().to_vec();
        self.request(Service::SET_ATTRIBUTE_SINGLE, path, data)
    }

    /// A class-3 connection to the message router, RPI 10 s (its own watchdog 40 s away).
    fn explicit_open(&mut self, serial: u16) -> MrResponse {
        let np = NetParams::fixed(504, kind::POINT_TO_POINT);
        let fo = ForwardOpen {
            large: false,
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            o_t_id: 0,
            t_o_id: 0x5345_0000 | u32::from(serial),
            serial,
            vendor: 1,
            originator_serial: 0x5345_5256,
            timeout_multiplier: 0,
            o_t_rpi: 10_000_000,
            o_t: np,
            t_o_rpi: 10_000_000,
            t_o: np,
            transport: Transport::CLASS3,
            path: EPath::object(class::MESSAGE_ROUTER, 1),
        };
        let cm = EPath::object(class::CONNECTION_MANAGER, 1);
        self.request(Service::FORWARD_OPEN, cm, fo.emit())
    }

    fn forward_close(&mut self, serial: u16) -> MrResponse {
        let fc = ForwardClose {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            serial,
            vendor: 1,
            originator_serial: 0x5345_5256,
            path: EPath::object(class::MESSAGE_ROUTER, 1),
        };
        let cm = EPath::object(class::CONNECTION_MANAGER, 1);
        self.request(Service::FORWARD_CLOSE, cm, fc.emit())
    }

    /// How long after `since` the adapter closed the connection, waiting up to `limit`;
    /// `None` when it was still open then. Nothing may arrive meanwhile.
    fn closed_after(&mut self, since: Instant, limit: Duration) -> Option<Duration> {
        self.tcp
            .set_read_timeout(Some(limit.saturating_sub(since.elapsed()).max(MS)))
            .unwrap();
        let r = self.receive();
        self.tcp.set_read_timeout(Some(REPLY)).unwrap();
        match r {
            Ok(None) => Some(since.elapsed()),
            Err(e) if e.kind() == ErrorKind::ConnectionReset => Some(since.elapsed()),
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => None,
            other => panic!("unexpected while idle: {other:?}"),
        }
    }
}

const MS: Duration = Duration::from_millis(1);

#[test]
fn an_idle_connection_is_closed_after_the_inactivity_timeout_set_over_tcp() {
    let at = serve(21, Limits::default());
    // Connected before the change, silent ever since: its clock started at accept.
    let mut silent = Client::connect(at);
    let mut idle = Client::registered(at);
    assert_eq!(idle.inactivity_timeout(), 120, "the default");
    let set = idle.set_inactivity_timeout(1);
    assert_eq!(set.status(), GS::SUCCESS, "{set:?}");
    let mut busy = Client::registered(at);

    // The adapter's clock for `idle` starts when this request arrives, after `since`.
    let since = Instant::now();
    assert_eq!(idle.inactivity_timeout(), 1, "read back");
    let keep_busy = std::thread::spawn(move || {
        let start = Instant::now();
        while start.elapsed() < Duration::from_millis(2500) {
            assert_eq!(busy.inactivity_timeout(), 1);
            std::thread::sleep(Duration::from_millis(300));
        }
        busy
    });

    let closed = idle.closed_after(since, Duration::from_secs(5));
    let closed = closed.expect("the idle connection closed within 5 s");
    assert!(closed >= Duration::from_secs(1), "closed early: {closed:?}");
    assert!(
        closed < Duration::from_millis(2500),
        "closed late: {closed:?}"
    );
    let silent_closed = silent.closed_after(since, Duration::from_secs(3));
    assert!(silent_closed.is_some(), "a silent connection is closed too");

    // A connection with traffic stays open past it.
    let mut busy = keep_busy
        .join()
        .expect("the busy client kept its connection");
    assert_eq!(busy.inactivity_timeout(), 1);
}

#[test]
fn a_connection_with_a_cip_connection_open_outlives_the_inactivity_timeout() {
    let at = serve(22, Limits::default());
    let mut c = Client::registered(at);
    assert_eq!(c.set_inactivity_timeout(1).status(), GS::SUCCESS);
    assert_eq!(c.explicit_open(7).status(), GS::SUCCESS);
    let since = Instant::now();
    assert_eq!(c.closed_after(since, Duration::from_millis(2500)), None);
    assert_eq!(c.inactivity_timeout(), 1, "still served");

    // Closed once nothing holds it: 1 s after its last message at the earliest.
    let since = Instant::now();
    assert_eq!(c.forward_close(7).status(), GS::SUCCESS);
    let closed = c.closed_after(since, Duration::from_secs(5));
    let closed = closed.expect("closed once the class-3 connection was");
    assert!(closed >= Duration::from_secs(1), "closed early: {closed:?}");
}

#[test]
fn a_timeout_of_0_keeps_idle_connections_and_3601_is_refused() {
    let at = serve(23, Limits::default());
    let mut c = Client::registered(at);
    assert_eq!(
        c.set_inactivity_timeout(3601).status(),
        GS::INVALID_ATTRIBUTE_VALUE
    );
    assert_eq!(c.inactivity_timeout(), 120, "unchanged by the refusal");
    assert_eq!(c.set_inactivity_timeout(0).status(), GS::SUCCESS);
    let since = Instant::now();
    assert_eq!(c.closed_after(since, Duration::from_millis(1500)), None);
    assert_eq!(c.inactivity_timeout(), 0);
}

#[test]
fn register_session_beyond_the_limit_is_refused_with_insufficient_memory() {
    let at = serve(
        24,
        Limits {
            sessions: 2,
            ..Limits::default()
        },
    );
    let _a = Client::registered(at);
    let b = Client::registered(at);
    let mut c = Client::connect(at);
    let r = c.register();
    assert_eq!(EncapStatus(r.status), EncapStatus::INSUFFICIENT_MEMORY);
    assert_eq!(r.session, 0);
    // The connection stays; a session is granted once another client's went.
    drop(b);
    let granted = (0..100).any(|_| {
        std::thread::sleep(Duration::from_millis(10));
        c.register().status == 0
    });
    assert!(granted, "a session once there was room");
}

#[test]
fn forward_open_beyond_the_connection_limit_is_refused_with_0113h() {
    let at = serve(25, Limits::default());
    let mut c = Client::registered(at);
    let mut serial = 1;
    let refused = loop {
        let r = c.explicit_open(serial);
        if r.status() != GS::SUCCESS || serial > 100 {
            break r;
        }
        serial += 1;
    };
    assert_eq!(refused.status(), GS::CONNECTION_FAILURE, "{refused:?}");
    assert_eq!(refused.extended, [ext::OUT_OF_CONNECTIONS]);
    assert!(serial > 1, "some connections were granted first");
}

#[test]
fn tcp_clients_beyond_the_limit_are_told_insufficient_memory_and_closed() {
    let at = serve(
        26,
        Limits {
            connections: 2,
            ..Limits::default()
        },
    );
    let a = Client::registered(at);
    let mut b = Client::registered(at);
    let mut c = Client::connect(at);
    let r = c.register();
    assert_eq!(EncapStatus(r.status), EncapStatus::INSUFFICIENT_MEMORY);
    assert_eq!(c.receive().expect("the close"), None);
    assert_eq!(
        b.inactivity_timeout(),
        120,
        "the others are served as before"
    );

    // A client that leaves makes room.
    drop(a);
    let served = (0..100).any(|_| {
        std::thread::sleep(Duration::from_millis(10));
        Client::connect(at).register().status == 0
    });
    assert!(served, "a client is served once there is room");
}

#[test]
fn idle_clients_cost_no_thread() {
    let at = serve(27, Limits::default());
    let threads = || std::fs::read_dir("/proc/self/task").unwrap().count();
    let before = threads();
    // Connections without sessions (300 sessions would pass the limit of 64), each served
    // once so that it is known accepted.
    let idle: Vec<Client> = (0..300)
        .map(|_| {
            let mut c = Client::connect(at);
            let r = c.exchange(Command::LIST_IDENTITY, Vec::new());
            assert_eq!(EncapStatus(r.status), EncapStatus::SUCCESS);
            c
        })
        .collect();
    let during = threads();
    // Other tests of this binary start and end threads meanwhile, a few at a time.
    assert!(
        during < before + 30,
        "{} idle clients: {before} threads before, {during} with them",
        idle.len()
    );
    let mut c = Client::registered(at);
    assert_eq!(c.inactivity_timeout(), 120, "still served");
}

#[test]
fn with_late_every_encapsulation_reply_leaves_late_and_the_request_acts_at_once() {
    let delay = Duration::from_millis(150);
    let at = serve_late(28, Limits::default(), delay);
    let mut c = Client::connect(at);
    let sent = Instant::now();
    assert_eq!(EncapStatus(c.register().status), EncapStatus::SUCCESS);
    assert!(
        sent.elapsed() >= delay,
        "RegisterSession after {:?}",
        sent.elapsed()
    );
    // The request took effect before its reply left: a second client, sent off while the
    // first waits for its reply, finds the inactivity timeout already changed.
    let path = EPath::attribute(class::TCP_IP, 1, 13);
    let req = MrRequest {
        service: Service::SET_ATTRIBUTE_SINGLE.0,
        path,
        data: 0u16.to_le_bytes().to_vec(),
    };
    let sd = SendData {
        interface: 0,
        timeout: 0,
        cpf: Cpf::new(vec![Item::Null, Item::UnconnectedData(req.emit())]),
    };
    let set = EncapRepr {
        command: Command::SEND_RR_DATA.0,
        session: c.session,
        data: sd.emit().unwrap(),
        ..EncapRepr::default()
    };
    c.tcp.write_all(&set.emit().unwrap()).unwrap();
    let mut other = Client::registered(at);
    assert_eq!(other.inactivity_timeout(), 0);
    assert!(c.receive().unwrap().is_some());
    // ListIdentity over UDP leaves late too.
    let udp = std::net::UdpSocket::bind("127.0.7.28:0").unwrap();
    udp.set_read_timeout(Some(REPLY)).unwrap();
    let list = EncapRepr {
        command: Command::LIST_IDENTITY.0,
        ..EncapRepr::default()
    };
    let sent = Instant::now();
    udp.send_to(&list.emit().unwrap(), at).unwrap();
    let mut buf = [0u8; 1500];
    let (n, _) = udp.recv_from(&mut buf).expect("a ListIdentity reply");
    assert!(
        sent.elapsed() >= delay,
        "ListIdentity after {:?}",
        sent.elapsed()
    );
    assert_eq!(
        EncapRepr::parse(&buf[..n]).unwrap().command,
        Command::LIST_IDENTITY.0
    );
}
