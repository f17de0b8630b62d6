//! `harness serve epl`: the simulated POWERLINK controlled node on a network interface.
//!
//! The node (`sim::epl::Node`, sans-IO) is reached two ways, as the manuals' devices are
//! (BU 0620 §2.4.1 "asynchronous data transfer (SDO over ASND or UDP/IP)"):
//! - raw Ethernet frames of EtherType 88ABh ([`crate::net::RawLink`], which opens the interface
//!   promiscuous: the node's frames come to its own MAC address F0-5F-5A-00-00-N, BU 0620 §4.4.2
//!   P878, and to the POWERLINK multicast addresses 01-11-1E-00-00-01…04, DS 301 §4.6.1.1.2,
//!   neither of which is the interface's);
//! - UDP datagrams to port 3819 (DS 301 C_SDO_EPL_PORT) on the interface's 192.168.100.N, N
//!   the node id: the MN addresses the node there (BU 0620 §3.7.3, BU 2200 §5.2.5), whatever
//!   other addresses the interface has and in whichever order. An interface with IPv4 addresses
//!   but not that one is refused, naming them (`super::address`); one without any IPv4 address
//!   is served over raw Ethernet only, and a line on stderr says so.
//!
//! One thread of the serve driver ([`crate::net::driver`]) serves both, frames first
//! ([`RawPort`]): each frame goes to [`Node::receive`] and what it returns is sent at once (a
//! PRes within the PReq's cycle), a datagram to [`Node::udp`] once no frame that came before
//! it is left, and [`Node::poll`] runs every [`sim::epl::POLL_PERIOD`] (the Basic Ethernet
//! timeout, the loss of the SoC, the drive model). With a thread each, a datagram sent right
//! after a ResetCommunication frame was answered before the frame was taken, under load. The
//! node is kept under a mutex for [`Served::state`], and the time handed to it (since start)
//! is read with the lock held, so it never goes backwards.
//!
//! `--misbehave late=…` ([`crate::net::misbehave`]) makes the node late on purpose: its SDO
//! answers (ASnd and UDP) leave late, held back without stopping the loop. Its IdentResponse and StatusResponse do not:
//! they carry the state of the moment they are asked, and one held back would show a state
//! the node has left (a wrong answer, not a late one; nothing in them tells the MN which
//! request they answer). Its PRes stay in their cycle: they are the isochronous phase, whose
//! timing the cyclic steps check (`drop=`, `silent=` and `corrupt=state`, [`super::faults`],
//! are what the PRes can be made to do wrong).

use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::time::Duration;

use proto::epl::{MessageType, NmtState, ServiceId, SDO_UDP_PORT};
use proto::eth::ETHERTYPE_POWERLINK;
use proto::nord::epl as def;
use proto::nord::Protocol;
use sim::endpoint::{Input, Output};
use sim::epl::{Node, NodeConfig, NodeError};

use super::address;
use super::faults;
use crate::net::driver::{Options, Serving, Shared};
use crate::net::misbehave::Misbehaviour;
use crate::net::raw_port::RawPort;
use crate::net::serve_args::{RawServeArgs, SystemBusArg};
use crate::net::udp::ipv4s_of;
use crate::net::workers::serve_for;
pub use crate::net::LinkError;
use crate::net::RawLink;

/// How long the raw thread polls the socket after a frame before it sleeps: the next frame of
/// a cycle (SoA after PReq) is taken without a thread wake-up.
const FRAME_POLL: Duration = Duration::from_micros(50);

/// The longest either thread sleeps without looking at its stop flag.
const STOP_CHECK: Duration = Duration::from_millis(20);

/// What `harness serve epl` serves.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServeOptions {
    /// The network interface (`--iface`), e.g. one end of a veth pair.
    pub iface: String,
    /// The product profile (`--profile`, default `sk550p`).
    pub profile: String,
    /// The node id (`--node-id`, default 1; a controlled node's is 1…239, BU 0620 §2.4.3.1).
    pub node_id: u8,
    /// Inverters behind the interface (`--inverters`; default the product's maximum).
    pub inverters: Option<u8>,
    /// What the node does wrong on purpose (`--misbehave`; nothing by default): `late=` holds
    /// its SDO answers back, over ASnd and UDP.
    pub misbehave: Misbehaviour,
}

impl ServeOptions {
    /// `iface` with the defaults: SK 550P, node 1, the product's maximum of inverters.
    pub fn new(iface: &str) -> ServeOptions {
        ServeOptions {
            iface: iface.into(),
            profile: "sk550p".into(),
            node_id: 1,
            inverters: None,
            misbehave: Misbehaviour::default(),
        }
    }
}

/// Why the node cannot be served, or stopped serving.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The profile is unknown or its product has no POWERLINK interface.
    #[error("{0}")]
    Profile(String),
    /// The node id is not a controlled node's, or the product has no POWERLINK.
    #[error(transparent)]
    Node(#[from] NodeError),
    /// The raw Ethernet link failed (no such interface, no root, I/O).
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The interface has IPv4 addresses, but not the node's 192.168.100.N.
    #[error("{0}")]
    Address(String),
    /// The UDP socket for SDO over UDP/IP could not be bound or failed.
    #[error("UDP {addr} (SDO over UDP/IP): {source}")]
    Udp {
        /// The address it was bound (or to be bound) to.
        addr: SocketAddr,
        /// What the system said.
        source: std::io::Error,
    },
    /// A serving thread panicked (a bug).
    #[error("the POWERLINK node's thread panicked: {0}")]
    Panicked(String),
    /// The system bus could not be published (`--system-bus`).
    #[error("--system-bus: {0}")]
    SystemBus(crate::net::serve_error::ServeError),
}

pub use crate::net::driver::Counts as Stats;

/// A node served in threads by [`start`]; dropping it stops them.
#[derive(Debug)]
pub struct Served {
    iface: String,
    mac: [u8; 6],
    udp: Option<SocketAddr>,
    node: Arc<Shared<Node>>,
    serving: Serving<ServeError>,
}

impl Served {
    /// The interface it serves on.
    pub fn iface(&self) -> &str {
        &self.iface
    }

    /// The node's own Ethernet address, the source of what it sends (F0-5F-5A-00-00-N, not the
    /// interface's).
    pub fn mac(&self) -> [u8; 6] {
        self.mac
    }

    /// Where SDO over UDP/IP is served (`None`: the interface had no IPv4 address).
    pub fn udp_addr(&self) -> Option<SocketAddr> {
        self.udp
    }

    /// The node's NMT state now.
    pub fn state(&self) -> NmtState {
        self.node.lock().0.state()
    }

    /// What the thread counted so far.
    pub fn stats(&self) -> Stats {
        self.serving.counts()
    }

    /// Whether the thread still serves (it ends on a link or socket error).
    pub fn is_running(&self) -> bool {
        self.serving.is_running()
    }

    /// Stops the threads (within [`STOP_CHECK`]) and returns what they counted, or why they had
    /// stopped before.
    pub fn stop(mut self) -> Result<Stats, ServeError> {
        self.join()
    }

    fn join(&mut self) -> Result<Stats, ServeError> {
        self.serving.stop(ServeError::Panicked)
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.join();
    }
}

/// Opens `opts.iface` (raw Ethernet, and UDP 3819 on its 192.168.100.N when it has IPv4
/// addresses; refused when it has others but not that one) and
/// serves the simulated node of `opts.profile` there in threads of this process, until the
/// returned handle is stopped or dropped.
pub fn start(opts: &ServeOptions) -> Result<Served, ServeError> {
    let config = device_config(opts)?;
    let node = Node::new(
        sim::device::Device::new(config),
        NodeConfig::new(opts.node_id),
    )?;
    let mut link = RawLink::open(&opts.iface, Some(ETHERTYPE_POWERLINK))?;
    link.set_spin(FRAME_POLL);
    let have = ipv4s_of(&opts.iface).unwrap_or_default();
    let udp = match address::node_address(&opts.iface, opts.node_id, &have)
        .map_err(ServeError::Address)?
    {
        Some(ip) => {
            let addr = SocketAddr::from((ip, SDO_UDP_PORT));
            let socket =
                udp_socket(addr, &opts.iface).map_err(|source| ServeError::Udp { addr, source })?;
            Some((addr, socket))
        }
        None => None,
    };
    let mac = node.mac().0;
    let udp_addr = udp.as_ref().map(|(a, _)| *a);
    let port = match udp {
        Some((addr, socket)) => RawPort::new(link).with_udp(socket, addr)?,
        None => RawPort::new(link),
    };
    let node = Shared::new(node);
    let mut serving = Serving::new();
    serving
        .spawn(
            format!("epl-node-{}", opts.iface),
            node.clone(),
            port,
            Options::new(STOP_CHECK).misbehaving(opts.misbehave, late, faults::corrupt),
        )
        .map_err(|e| ServeError::Panicked(format!("cannot start a thread: {e}")))?;
    Ok(Served {
        iface: opts.iface.clone(),
        mac,
        udp: udp_addr,
        node,
        serving,
    })
}

/// What `late=` holds back: the node's SDO answers, over ASnd and UDP (its PRes,
/// IdentResponse and StatusResponse carry the state of the moment: see the module's
/// documentation).
fn late(_: &Input<'_>, out: &Output) -> bool {
    match out {
        Output::Frame(f) => is_sdo(f),
        Output::Datagram { .. } => true,
        _ => false,
    }
}

/// The node's UDP socket on `addr`, tied to `iface`: its answers leave there whatever the
/// routes say, and nodes served on several interfaces of one host can all have the address
/// the manuals give (192.168.100.N, BU 0620 §3.7.3), each on its own interface. Read only when
/// ready ([`RawPort::with_udp`]).
fn udp_socket(addr: SocketAddr, iface: &str) -> std::io::Result<UdpSocket> {
    use socket2::{Domain, Protocol, Socket, Type};
    let s = Socket::new(Domain::for_address(addr), Type::DGRAM, Some(Protocol::UDP))?;
    s.bind_device(Some(iface.as_bytes()))?;
    s.bind(&addr.into())?;
    Ok(s.into())
}

/// Serves until `duration` has passed (forever when `None`), after a line on stdout that says
/// what is served where (and one on stderr when SDO over UDP/IP is not served).
pub(crate) fn serve(
    opts: &ServeOptions,
    duration: Option<Duration>,
    system_bus: Option<&str>,
) -> Result<(), ServeError> {
    let served = start(opts)?;
    let relay = system_bus
        .map(|addr| crate::can::relay_served(addr, served.node.clone(), Node::device_mut))
        .transpose()
        .map_err(ServeError::SystemBus)?;
    let config = device_config(opts)?;
    let m = served.mac();
    let expected = def::ip_address(opts.node_id);
    let udp = match served.udp_addr() {
        Some(a) => format!(", SDO over UDP on {a}"),
        None => String::new(),
    };
    outln!(
        "serving POWERLINK node {} ({}, {} inverters) on {} (node MAC {:02x}:{:02x}:{:02x}:{:02x}:{:02x}:{:02x}){udp}",
        opts.node_id,
        config.product.name(),
        config.inverters,
        opts.iface,
        m[0],
        m[1],
        m[2],
        m[3],
        m[4],
        m[5]
    );
    crate::can::announce_relay(relay.as_ref());
    crate::net::misbehave::announce(&opts.misbehave);
    if served.udp_addr().is_none() {
        eprintln!(
            "note: {} has no IPv4 address: serving raw Ethernet only (SDO over ASnd); give it \
             {expected}/24 (BU 0620 §3.7.3) for SDO over UDP/IP",
            opts.iface
        );
    }
    serve_for(duration, STOP_CHECK * 10, || served.is_running());
    let stats = served.stop()?;
    crate::net::misbehave::summarize(&opts.misbehave, stats.misbehaved);
    Ok(())
}

/// `harness serve epl` arguments.
#[derive(clap::Parser, Debug)]
#[command(
    name = "harness serve epl",
    about = "Serve the simulator as a POWERLINK controlled node on a network interface (raw Ethernet: root or CAP_NET_RAW; SDO over UDP 3819 on the interface's 192.168.100.<node id>)"
)]
struct ServeArgs {
    #[command(flatten)]
    common: RawServeArgs,
    #[command(flatten)]
    system_bus: SystemBusArg,
    /// The node id, 1…239 (BU 0620 §2.4.3.1; 240 is the managing node's). SDO over UDP/IP is
    /// served on the interface's 192.168.100.<node id>; an interface with other IPv4
    /// addresses but not that one is refused.
    #[arg(long, default_value = "1", value_parser = parse_node_id)]
    node_id: u8,
}

/// A controlled node's id: 1…239 (BU 0620 §2.4.3.1, BU 2200 §5.2.4; DS 301 §4.7.4: 0 is
/// invalid, 240 the MN, 241…255 reserved).
fn parse_node_id(s: &str) -> Result<u8, String> {
    let n: u8 = s
        .parse()
        .map_err(|_| format!("`{s}` is not a node id (a number 1…239)"))?;
    match n {
        1..=239 => Ok(n),
        0 => Err("node id 0 is invalid; a controlled node has 1…239 (BU 0620 §2.4.3.1)".into()),
        240 => Err(
            "node id 240 is the managing node's; a controlled node has 1…239 (BU 0620 §2.4.3.1)"
                .into(),
        ),
        _ => Err(format!(
            "node id {n} is reserved; a controlled node has 1…239 (BU 0620 §2.4.3.1)"
        )),
    }
}

/// `harness serve epl ARGS…`; returns the exit code.
pub(crate) fn command(args: &[String]) -> Result<i32, crate::net::serve_error::ServeError> {
    let a = match crate::args::parse_args::<ServeArgs>("harness serve epl", args) {
        Ok(a) => a,
        Err(code) => return Ok(code),
    };
    let misbehave = match a.common.misbehave.for_bus(&faults::FAULTS) {
        Ok(m) => m,
        Err(code) => return Ok(code),
    };
    let opts = ServeOptions {
        iface: a.common.iface,
        profile: a.common.profile,
        node_id: a.node_id,
        inverters: a.common.inverters,
        misbehave,
    };
    let seconds = a.common.seconds.map(Duration::from_secs);
    serve(&opts, seconds, a.system_bus.system_bus.as_deref())
        .map_err(crate::net::serve_error::ServeError::bus)?;
    Ok(crate::exit::EXIT_PASS)
}

/// The simulated device of `opts`: a product with a POWERLINK interface.
fn device_config(opts: &ServeOptions) -> Result<sim::device::DeviceConfig, ServeError> {
    let config = crate::net::serve_args::device_config(
        &opts.profile,
        opts.inverters,
        Protocol::Powerlink,
        "POWERLINK",
    )
    .map_err(ServeError::Profile)?;
    if !(1..=239).contains(&opts.node_id) {
        return Err(NodeError::NodeId(opts.node_id).into());
    }
    Ok(config)
}

/// Whether a frame of the node is an ASnd carrying SDO: after the 14-byte Ethernet header,
/// message type 06h, destination, source, service id 05h (DS 301 §4.6.1.1.6).
fn is_sdo(frame: &[u8]) -> bool {
    frame.get(14).map(|t| MessageType(t & 0x7F)) == Some(MessageType::ASND)
        && frame.get(17).copied().map(ServiceId) == Some(ServiceId::SDO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::veth::Veth;
    use crate::net::MAX_FRAME;
    use proto::epl::asnd::IdentResponse;
    use proto::epl::frame::{Body, Preq, Soa, Soc};
    use proto::epl::sdo::{Command, Con, SdoFrame, Seq};
    use proto::epl::{
        EplRepr, RequestedService, ServiceId, MN_NODE_ID, MULTICAST_PRES, MULTICAST_SOA,
    };
    use proto::eth::{EthernetFrame, EthernetRepr, MacAddr};
    use std::thread;
    use std::time::Instant;

    /// The harness MN's source address in these tests (locally administered).
    const MN_MAC: MacAddr = MacAddr([0x02, 0, 0, 0, 0, 0xF0]);

    /// A frame from the MN (node 240) to `dst` with `body`.
    fn frame(dst: u8, body: Body) -> Vec<u8> {
        let repr = EplRepr {
            dst,
            src: MN_NODE_ID,
            body,
        };
        EthernetRepr {
            dst: MULTICAST_SOA,
            src: MN_MAC,
            ethertype: ETHERTYPE_POWERLINK,
        }
        .emit(&repr.emit().unwrap())
    }

    /// SoA asking node `target` for `service` (DS 301 §4.6.1.1.5).
    fn soa(service: RequestedService, target: u8) -> Vec<u8> {
        frame(
            255,
            Body::Soa(Soa {
                service,
                target,
                epl_version: 0x20,
                ..Soa::default()
            }),
        )
    }

    /// Sends `f` and waits up to `wait` for the node's IdentResponse.
    fn ident(mn: &mut RawLink, f: &[u8], wait: Duration) -> Option<(IdentResponse, [u8; 6])> {
        mn.send(f).unwrap();
        let mut buf = [0u8; MAX_FRAME];
        let until = Instant::now() + wait;
        while let Some(r) = mn.recv(&mut buf, until).unwrap() {
            let eth = EthernetFrame::new_checked(&buf[..r.len]).unwrap();
            let Ok(repr) = EplRepr::parse_bytes(eth.inner_payload()) else {
                continue;
            };
            if let Body::Asnd(a) = repr.body {
                assert_eq!(a.service, ServiceId::IDENT_RESPONSE);
                let mut src = [0u8; 6];
                src.copy_from_slice(&buf[6..12]);
                return Some((IdentResponse::parse(&a.payload).unwrap(), src));
            }
        }
        None
    }

    #[test]
    fn node_ids_outside_1_to_239_are_refused_by_name() {
        assert_eq!(parse_node_id("1"), Ok(1));
        assert_eq!(parse_node_id("239"), Ok(239));
        for (arg, says) in [
            ("0", "invalid"),
            ("240", "managing node"),
            ("241", "reserved"),
            ("255", "reserved"),
            ("256", "not a node id"),
            ("x", "not a node id"),
        ] {
            let e = parse_node_id(arg).unwrap_err();
            assert!(e.contains(says), "{arg}: {e}");
        }
        let opts = ServeOptions {
            node_id: 0,
            ..ServeOptions::new("lo")
        };
        match start(&opts) {
            Err(ServeError::Node(NodeError::NodeId(0))) => {}
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn profiles_without_powerlink_are_refused_before_any_socket() {
        for (profile, says) in [("tu3-eip", "no POWERLINK"), ("no-such", "unknown profile")] {
            let opts = ServeOptions {
                profile: profile.into(),
                ..ServeOptions::new("no-such-if0")
            };
            match start(&opts) {
                Err(ServeError::Profile(e)) => assert!(e.contains(says), "{e}"),
                other => panic!("{profile}: {other:?}"),
            }
        }
        for profile in ["sk550p", "tu3-pol", "tu4-pol", "cu4-pol", "tu4-pol@epl"] {
            let opts = ServeOptions {
                profile: profile.into(),
                ..ServeOptions::new("x")
            };
            assert!(device_config(&opts).is_ok(), "{profile}");
        }
    }

    #[test]
    fn an_unknown_interface_is_refused_before_any_thread() {
        match start(&ServeOptions::new("no-such-if0")) {
            Err(ServeError::Link(LinkError::NoSuchInterface { .. })) => {}
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_served_node_answers_an_ident_request_over_a_veth_pair() {
        let Some(v) = Veth::new("p") else { return };
        let served = start(&ServeOptions {
            node_id: 7,
            ..ServeOptions::new(&v.0)
        })
        .expect("serve");
        assert!(served.is_running());
        assert_eq!(served.udp_addr(), None, "the veth end has no IPv4 address");
        assert_eq!(served.state(), NmtState::NOT_ACTIVE);
        let mut mn = RawLink::open(&v.1, Some(ETHERTYPE_POWERLINK)).unwrap();
        // An SoA of the MN takes the node from NOT_ACTIVE to PRE_OPERATIONAL_1 (DS 301
        // §7.1.4.1.1) without an answer; an IdentRequest to another node gets none either.
        let (none, some) = (Duration::from_millis(200), Duration::from_secs(2));
        assert!(ident(&mut mn, &soa(RequestedService::NO_SERVICE, 255), none).is_none());
        assert_eq!(served.state(), NmtState::PRE_OPERATIONAL_1);
        assert!(ident(&mut mn, &soa(RequestedService::IDENT_REQUEST, 8), none).is_none());
        let (id, src) =
            ident(&mut mn, &soa(RequestedService::IDENT_REQUEST, 7), some).expect("ident");
        assert_eq!(id.vendor_id, def::VENDOR_ID);
        assert_eq!(
            id.product_code,
            def::product_code(proto::nord::Product::Sk550p)
        );
        assert_eq!(id.state, NmtState::PRE_OPERATIONAL_1);
        assert_eq!(id.ip, def::ip_address(7));
        assert_eq!(src, served.mac(), "sent from the node's own address");
        assert_eq!(served.mac(), [0xF0, 0x5F, 0x5A, 0, 0, 7]);
        // A SoC: PRE_OPERATIONAL_2.
        mn.send(&frame(255, Body::Soc(Soc::default()))).unwrap();
        let t = Instant::now();
        while served.state() != NmtState::PRE_OPERATIONAL_2 && t.elapsed().as_secs() < 2 {
            thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(served.state(), NmtState::PRE_OPERATIONAL_2);
        // A PReq to the node's own (unicast) address, not the interface's: a PRes to the
        // multicast 01-11-1E-00-00-02 (DS 301 C_DLL_MULTICAST_PRES) with 96 bytes (§2.4.5).
        let mut preq = frame(7, Body::Preq(Preq::default()));
        preq[..6].copy_from_slice(&served.mac());
        mn.send(&preq).unwrap();
        let mut buf = [0u8; MAX_FRAME];
        let r = mn
            .recv(&mut buf, Instant::now() + Duration::from_secs(2))
            .unwrap()
            .expect("a PRes");
        assert_eq!(&buf[..6], &MULTICAST_PRES.0);
        let eth = EthernetFrame::new_checked(&buf[..r.len]).unwrap();
        let Body::Pres(p) = EplRepr::parse_bytes(eth.inner_payload()).unwrap().body else {
            panic!("not a PRes: {:02x?}", &buf[..r.len]);
        };
        assert_eq!(
            (p.state, p.payload.len()),
            (NmtState::PRE_OPERATIONAL_2, 96)
        );
        let stats = served.stop().expect("stops cleanly");
        // Three SoAs, a SoC and a PReq in; an IdentResponse and a PRes out.
        assert_eq!((stats.frames_in, stats.frames_out), (5, 2), "{stats:?}");
    }

    /// Adds `ip`/32 to `iface`.
    fn add_address(iface: &str, ip: std::net::Ipv4Addr) {
        let ok = std::process::Command::new("ip")
            .args(["addr", "add", &format!("{ip}/32"), "dev", iface])
            .status()
            .map(|s| s.success());
        assert!(matches!(ok, Ok(true)), "ip addr add {ip}: {ok:?}");
    }

    /// Addresses of this process's own: another address first, then the node's
    /// 192.168.100.N, N = `node`, each /32 (no route to the subnet in this namespace).
    fn own_addresses() -> (std::net::Ipv4Addr, u8) {
        let pid = std::process::id();
        let first = std::net::Ipv4Addr::new(10, 229, (pid >> 8) as u8, (pid as u8).clamp(1, 254));
        // 2…201: not the 192.168.100.1 and .240 other tests give their veth ends.
        (first, (2 + pid % 200) as u8)
    }

    #[test]
    fn an_interface_without_the_nodes_address_is_refused_naming_its_addresses() {
        let Some(v) = Veth::new("a") else { return };
        let (first, node) = own_addresses();
        add_address(&v.0, first);
        let opts = ServeOptions {
            node_id: node,
            ..ServeOptions::new(&v.0)
        };
        match start(&opts) {
            Err(ServeError::Address(e)) => {
                assert!(
                    e.contains(&format!(
                        "{} has {first}/32 but not 192.168.100.{node}",
                        v.0
                    )),
                    "{e}"
                );
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn sdo_over_udp_on_the_interfaces_address() {
        let Some(v) = Veth::new("u") else { return };
        // The node's address second, after another: the node serves on its own, not the
        // interface's first. (Not 192.168.100.1: another test binding that address and port
        // 3819 at the same time would collide.)
        let (first, node) = own_addresses();
        let ip = def::ip_address(node);
        add_address(&v.0, first);
        add_address(&v.0, ip);
        let served = start(&ServeOptions {
            profile: "tu4-pol".into(),
            node_id: node,
            ..ServeOptions::new(&v.0)
        })
        .expect("serve");
        let addr = served.udp_addr().expect("UDP on the node's address");
        assert_eq!(addr, SocketAddr::from((ip, SDO_UDP_PORT)));
        let client = UdpSocket::bind(("0.0.0.0", 0)).unwrap();
        // No MN: the node answers over UDP once it has left Initialisation for Basic Ethernet
        // (its timeout, 5 s; BU 2200 §6.2: no parameter communication in Initialisation).
        client
            .set_read_timeout(Some(Duration::from_millis(500)))
            .unwrap();
        let hello = SdoFrame {
            seq: Seq {
                rsnr: 0,
                rcon: Con::Valid,
                ssnr: 1,
                scon: Con::Init,
            },
            command: None,
        }
        .emit_udp()
        .unwrap();
        let tries = (1..=20u64).find(|_| {
            client.send_to(&hello, addr).unwrap();
            client.recv_from(&mut [0u8; 1500]).is_ok()
        });
        let tries = tries.expect("an answer over UDP within 10 s");
        client
            .set_read_timeout(Some(Duration::from_secs(2)))
            .unwrap();
        let mut buf = [0u8; 1500];
        let mut ask = |seq: Seq, command: Option<Command>| {
            let d = SdoFrame { seq, command }.emit_udp().unwrap();
            client.send_to(&d, addr).unwrap();
            let (n, from) = client.recv_from(&mut buf).expect("an answer within 2 s");
            assert_eq!(from, addr);
            SdoFrame::parse(SdoFrame::strip_udp(&buf[..n]).unwrap()).unwrap()
        };
        let seq = |ssnr, scon| Seq {
            rsnr: 0,
            rcon: Con::Valid,
            ssnr,
            scon,
        };
        // Sequence layer initialisation, then 1018h.1 (vendor id, DS 301 §6.3).
        let init = ask(seq(1, Con::Init), None);
        assert_eq!(init.seq.scon, Con::Init);
        let r = ask(
            seq(2, Con::Valid),
            Some(Command::read_by_index(1, 0x1018, 1)),
        );
        assert_eq!(r.command.unwrap().payload, def::VENDOR_ID.to_le_bytes());
        let stats = served.stop().expect("stops cleanly");
        // The tries until the first answer (the silent ones in Initialisation), then the two.
        assert_eq!(
            (stats.datagrams_in, stats.datagrams_out),
            (tries + 2, 1 + 2)
        );
    }

    #[test]
    fn a_vanished_interface_ends_the_threads_with_an_error() {
        let Some(v) = Veth::new("q") else { return };
        let served = start(&ServeOptions::new(&v.0)).expect("serve");
        drop(v);
        let t = Instant::now();
        while served.is_running() && t.elapsed() < Duration::from_secs(2) {
            thread::sleep(Duration::from_millis(10));
        }
        match served.stop() {
            Err(ServeError::Link(LinkError::Io { .. })) => {}
            other => panic!("{other:?}"),
        }
    }
}
