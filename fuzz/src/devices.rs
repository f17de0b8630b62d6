//! The device targets: each builds one simulated device (`sim`), drives it through the
//! session the fuzzer's bytes encode ([`crate::session`]) as the `serve` driver does — inputs
//! at the current time, polls when the device's deadline comes, TCP bytes cut into messages by
//! the device's framing — and then sends it a known-good request, which it must still answer:
//! a device that stops answering good requests after bad ones is a crash, as a panic is.
//!
//! Time is virtual and bounded: an advance polls at most [`POLLS_PER_ADVANCE`] deadlines and
//! then jumps, as a driver that was late does (the devices' timers allow for a late poll).

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::time::Duration;

use proto::can::CanFrame;
use proto::ecat::register::AL_STATUS;
use proto::ecat::{Command as EcatCommand, DatagramRepr, EcatFrameRepr};
use proto::enip::encap::{Command as EncapCommand, EncapRepr};
use proto::enip::io::{ENCAP_PORT, IO_PORT};
use proto::epl::frame::{Body, Soa};
use proto::epl::{EplRepr, RequestedService, ServiceId, MN_NODE_ID, MULTICAST_SOC};
use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_POWERLINK, ETHERTYPE_PROFINET};
use proto::nord::Product;
use proto::pnio::dcp::DcpRepr;
use proto::pnio::{MULTICAST_DCP_IDENTIFY, RPC_PORT};
use sim::device::{Device, DeviceConfig};
use sim::endpoint::{Endpoint, Input, Output};
use sim::enip::{Adapter, Framer};
use sim::epl::{Node, NodeConfig};
use sim::pnio::{IoConfig, IoDevice};

use crate::session::{decode, Step};

/// Deadlines an advance polls before it jumps to its end.
pub const POLLS_PER_ADVANCE: usize = 64;

/// How long the device has to answer the known-good request.
const ANSWER_WITHIN: Duration = Duration::from_secs(2);

/// The product every device target simulates: the SK 550P speaks all four Ethernet buses and
/// has the system bus.
const PRODUCT: Product = Product::Sk550p;

/// The tester's MAC address in the good requests.
const TESTER_MAC: MacAddr = MacAddr([0x02, 0, 0, 0, 0, 0xF0]);

/// The peers of datagrams and TCP clients: two, picked by the step's argument.
fn peer(arg: u8) -> SocketAddr {
    SocketAddr::from(([192, 168, 1, 100 + (arg & 1)], 50_000 + u16::from(arg & 1)))
}

/// A device under a session: the driver's side of it.
struct Driver<E> {
    device: E,
    now: Duration,
    /// The UDP ports the device serves; a datagram step picks one by index.
    ports: &'static [u16],
    /// Whether frames are CAN frames (11-bit id little-endian, then up to 8 data bytes).
    can: bool,
    /// Each TCP client's framing of its stream.
    framers: BTreeMap<u8, Framer>,
}

impl<E: Endpoint> Driver<E> {
    fn new(device: E, ports: &'static [u16], can: bool) -> Driver<E> {
        Driver {
            device,
            now: Duration::ZERO,
            ports,
            can,
            framers: BTreeMap::new(),
        }
    }

    /// Runs every step of `data`.
    fn session(&mut self, data: &[u8]) {
        for step in decode(data) {
            self.step(step);
        }
    }

    /// Runs one step; what the device sends.
    fn step(&mut self, step: Step<'_>) -> Vec<Output> {
        let mut out = Vec::new();
        match step {
            Step::Frame(bytes) if self.can => {
                if let Some(frame) = can_frame(bytes) {
                    out = self.input(Input::Can(&frame));
                }
            }
            Step::Frame(bytes) => out = self.input(Input::Frame(bytes)),
            Step::Datagram(arg, bytes) => {
                if let Some(&port) = self.ports.get(usize::from(arg) % self.ports.len().max(1)) {
                    let from = peer(arg);
                    out = self.input(Input::Datagram { port, from, bytes });
                }
            }
            Step::Stream(client, bytes) => {
                let framer = self.framers.entry(client).or_default();
                match framer.push(bytes) {
                    Ok(messages) => {
                        for bytes in messages {
                            let peer = peer(client);
                            let client = u64::from(client);
                            out.extend(self.input(Input::Message {
                                client,
                                peer,
                                bytes: &bytes,
                            }));
                        }
                    }
                    // The driver closes a connection whose message is too big to frame.
                    Err(_) => out = self.close(client),
                }
            }
            Step::Closed(client) => out = self.close(client),
            Step::Advance(by) => out = self.advance(by),
            Step::Poll => out = self.poll(),
            Step::Alarm => {
                if let Some(raised) = self.device.raise_alarm(self.now) {
                    out = raised.outputs;
                }
            }
        }
        out
    }

    fn input(&mut self, input: Input<'_>) -> Vec<Output> {
        let mut out = self.device.input(input, self.now);
        out.extend(self.poll());
        out
    }

    fn close(&mut self, client: u8) -> Vec<Output> {
        self.framers.remove(&client);
        self.input(Input::Closed(u64::from(client)))
    }

    /// Polls the device if its deadline has come.
    fn poll(&mut self) -> Vec<Output> {
        match self.device.next_deadline() {
            Some(due) if due <= self.now => self.device.poll(self.now),
            _ => Vec::new(),
        }
    }

    /// Lets `by` pass, polling at the deadlines on the way ([`POLLS_PER_ADVANCE`] at most).
    fn advance(&mut self, by: Duration) -> Vec<Output> {
        let end = self.now + by;
        let mut out = Vec::new();
        for _ in 0..POLLS_PER_ADVANCE {
            match self.device.next_deadline() {
                Some(due) if due <= end => {
                    self.now = self.now.max(due);
                    out.extend(self.device.poll(self.now));
                }
                _ => break,
            }
        }
        self.now = end;
        out.extend(self.poll());
        out
    }

    /// Sends `request` (a frame, or a datagram to the port of that index) up to `tries` times
    /// a millisecond apart, letting time pass after each for the answer; panics unless
    /// `answered` accepts one of the outputs.
    fn must_answer(
        &mut self,
        request: Step<'_>,
        tries: usize,
        what: &str,
        answered: impl Fn(&Output) -> bool,
    ) {
        for _ in 0..tries {
            let mut out = self.step(request);
            out.extend(self.advance(Duration::from_millis(1)));
            if out.iter().any(&answered) {
                return;
            }
        }
        let out = self.advance(ANSWER_WITHIN);
        assert!(
            out.iter().any(answered),
            "the device no longer answers {what} after the session"
        );
    }
}

/// A CAN frame from a frame step: 11-bit id little-endian, then the data (at most 8 bytes).
fn can_frame(bytes: &[u8]) -> Option<CanFrame> {
    let (id, data) = bytes.split_first_chunk::<2>()?;
    CanFrame::new(u16::from_le_bytes(*id) & 0x7FF, &data[..data.len().min(8)]).ok()
}

/// The Ethernet payload of a frame the device sent, if it is one.
fn payload(out: &Output) -> Option<Vec<u8>> {
    let Output::Frame(f) = out else { return None };
    EthernetFrame::new_checked(f.as_slice())
        .ok()
        .map(|e| e.inner_payload().to_vec())
}

fn device() -> Device {
    Device::new(DeviceConfig::new(PRODUCT))
}

/// The EtherCAT slave; the good request is a BRD of the AL status register, which every ESC
/// answers in every state by counting its working counter (ETG.1000.4 §5.4).
pub fn device_ecat(data: &[u8]) {
    let slave = sim::ecat::Slave::new(device()).expect("the SK 550P is an EtherCAT slave");
    let mut d = Driver::new(slave, &[], false);
    d.session(data);
    let brd = DatagramRepr::physical(EcatCommand::BRD, 0x5A, 0, AL_STATUS, vec![0; 2]);
    let request = EcatFrameRepr::new(vec![brd])
        .emit_ethernet(MacAddr::BROADCAST, TESTER_MAC)
        .expect("a BRD of 2 bytes emits");
    d.must_answer(Step::Frame(&request), 1, "a BRD of the AL status", |out| {
        payload(out)
            .and_then(|p| EcatFrameRepr::parse_bytes(&p).ok())
            .is_some_and(|f| f.datagrams.iter().any(|d| d.index == 0x5A && d.wkc >= 1))
    });
}

/// The POWERLINK controlled node; the good request is a SoA inviting its IdentResponse, which
/// a CN sends from PRE_OPERATIONAL_1 on (the first SoA also takes it out of NOT_ACTIVE or
/// BASIC_ETHERNET: two tries).
pub fn device_epl(data: &[u8]) {
    let node = Node::new(device(), NodeConfig::new(1)).expect("node 1 is valid");
    let mut d = Driver::new(node, &[proto::epl::SDO_UDP_PORT], false);
    d.session(data);
    let soa = EplRepr {
        dst: 255,
        src: MN_NODE_ID,
        body: Body::Soa(Soa {
            service: RequestedService::IDENT_REQUEST,
            target: d.device.node_id(),
            epl_version: 0x20,
            ..Soa::default()
        }),
    };
    let request = EthernetRepr {
        dst: MULTICAST_SOC,
        src: TESTER_MAC,
        ethertype: ETHERTYPE_POWERLINK,
    }
    .emit(&soa.emit().expect("a SoA emits"));
    d.must_answer(Step::Frame(&request), 2, "an IdentRequest", |out| {
        payload(out)
            .and_then(|p| EplRepr::parse_bytes(&p).ok())
            .is_some_and(
                |r| matches!(r.body, Body::Asnd(a) if a.service == ServiceId::IDENT_RESPONSE),
            )
    });
}

/// The PROFINET IO device; the good request is a DCP Identify All, which every IO device
/// answers whatever its name and AR state.
pub fn device_pnio(data: &[u8]) {
    let io = IoDevice::new(device(), IoConfig::new(PRODUCT)).expect("the SK 550P is an IO device");
    let mut d = Driver::new(io, &[RPC_PORT], false);
    d.session(data);
    let identify = DcpRepr::identify_all(0x5A5A, 1)
        .emit()
        .expect("Identify All emits");
    let request = EthernetRepr {
        dst: MULTICAST_DCP_IDENTIFY,
        src: TESTER_MAC,
        ethertype: ETHERTYPE_PROFINET,
    }
    .emit(&identify);
    d.must_answer(Step::Frame(&request), 1, "a DCP Identify All", |out| {
        payload(out)
            .and_then(|p| DcpRepr::parse(&p).ok())
            .is_some_and(|r| r.xid == 0x5A5A)
    });
}

/// The EtherNet/IP adapter (encapsulation over TCP and UDP, class-1 I/O on UDP 2222); the
/// good request is a ListIdentity over UDP, which an adapter answers to anyone.
pub fn device_enip(data: &[u8]) {
    let address = "192.168.1.20:44818".parse().expect("an address");
    let mut d = Driver::new(
        Adapter::new(device(), address),
        &[ENCAP_PORT, IO_PORT],
        false,
    );
    d.session(data);
    let request = EncapRepr {
        command: EncapCommand::LIST_IDENTITY.0,
        session: 0,
        status: 0,
        context: [0x5A; 8],
        options: 0,
        data: Vec::new(),
    }
    .emit()
    .expect("ListIdentity emits");
    d.must_answer(Step::Datagram(0, &request), 1, "a ListIdentity", |out| {
        matches!(out, Output::Datagram { bytes, .. }
            if EncapRepr::parse(bytes).is_ok_and(|r| r.context == [0x5A; 8]))
    });
}

/// The system bus's CAN segment (the bus interface and its inverters as CANopen nodes); the
/// good request is NMT Reset Communication to all nodes, after which every node sends its
/// boot-up message (CiA 301 §7.2.8.3.2).
pub fn device_can(data: &[u8]) {
    let segment = sim::can::Segment::new(DeviceConfig::new(PRODUCT)).expect("a system bus");
    let mut d = Driver::new(segment, &[], true);
    d.session(data);
    // NMT (COB-ID 000h): command 82h, node 0 (all).
    let request = [0x00, 0x00, 0x82, 0x00];
    d.must_answer(
        Step::Frame(&request),
        1,
        "an NMT Reset Communication",
        |out| matches!(out, Output::Can(f) if (0x701..=0x77F).contains(&f.id()) && f.data() == [0]),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device that never sends anything.
    struct Silent;

    impl Endpoint for Silent {
        fn input(&mut self, _: Input<'_>, _: Duration) -> Vec<Output> {
            Vec::new()
        }
        fn poll(&mut self, _: Duration) -> Vec<Output> {
            Vec::new()
        }
        fn next_deadline(&self) -> Option<Duration> {
            None
        }
    }

    #[test]
    #[should_panic(expected = "the device no longer answers a ping after the session")]
    fn a_device_that_does_not_answer_the_good_request_is_a_crash() {
        let mut d = Driver::new(Silent, &[], false);
        d.must_answer(Step::Frame(&[0; 60]), 2, "a ping", |_| true);
    }

    #[test]
    fn every_device_answers_its_good_request_after_an_empty_session() {
        for target in [
            device_ecat,
            device_epl,
            device_pnio,
            device_enip,
            device_can,
        ] {
            target(&[]);
        }
    }

    #[test]
    fn an_advance_ends_at_its_end_with_the_device_polled_up_to_it() {
        let io = IoDevice::new(device(), IoConfig::new(PRODUCT)).unwrap();
        let mut d = Driver::new(io, &[RPC_PORT], false);
        // The IO device wants a poll every millisecond: 1 s is 1000 deadlines, 64 are polled,
        // then one at the end.
        d.advance(Duration::from_secs(1));
        assert_eq!(d.now, Duration::from_secs(1));
        assert!(d.device.next_deadline() > Some(d.now));
    }
}
