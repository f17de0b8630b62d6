//! The controlled node driven by hand-made frames.

use std::net::SocketAddr;
use std::time::Duration;

use proto::epl::asnd::{IdentResponse, NmtCommandFrame, StatusResponse};
use proto::epl::frame::{Asnd, Body, Preq, Soa, Soc};
use proto::epl::sdo::{Command, Con, SdoFrame, Seq};
use proto::epl::{
    EplRepr, NmtCommand, NmtState, RequestedService, ServiceId, MN_NODE_ID, MULTICAST_SOC,
};
use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_POWERLINK};
use proto::nord::Product;

use super::{Node, NodeConfig};
use crate::device::{Device, DeviceConfig};

const MN_MAC: MacAddr = MacAddr([0x02, 0, 0, 0, 0, 0xF0]);

fn node(product: Product) -> Node {
    Node::new(Device::new(DeviceConfig::new(product)), NodeConfig::new(1)).unwrap()
}

fn frame(dst: u8, body: Body) -> Vec<u8> {
    let repr = EplRepr {
        dst,
        src: MN_NODE_ID,
        body,
    };
    EthernetRepr {
        dst: MULTICAST_SOC,
        src: MN_MAC,
        ethertype: ETHERTYPE_POWERLINK,
    }
    .emit(&repr.emit().unwrap())
}

fn soc() -> Vec<u8> {
    frame(255, Body::Soc(Soc::default()))
}

fn soa(service: RequestedService) -> Vec<u8> {
    frame(
        255,
        Body::Soa(Soa {
            service,
            target: 1,
            epl_version: 0x20,
            ..Soa::default()
        }),
    )
}

fn nmt(command: NmtCommand) -> Vec<u8> {
    let payload = NmtCommandFrame {
        command,
        data: vec![],
    }
    .emit();
    frame(
        1,
        Body::Asnd(Asnd {
            service: ServiceId::NMT_COMMAND,
            payload,
        }),
    )
}

fn preq(payload: Vec<u8>) -> Vec<u8> {
    frame(
        1,
        Body::Preq(Preq {
            rd: true,
            pdo_version: 0x20,
            payload,
            ..Preq::default()
        }),
    )
}

fn parse(b: &[u8]) -> EplRepr {
    let e = EthernetFrame::new_checked(b).unwrap();
    EplRepr::parse_bytes(e.inner_payload()).unwrap()
}

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

/// Boots node 1 to `state` at t = 1..4 ms.
fn boot(n: &mut Node, to: NmtState) {
    n.receive(&soa(RequestedService::NO_SERVICE), ms(1));
    n.receive(&soc(), ms(2));
    if to == NmtState::PRE_OPERATIONAL_2 {
        return;
    }
    n.receive(&nmt(NmtCommand::ENABLE_READY_TO_OPERATE), ms(3));
    if to == NmtState::READY_TO_OPERATE {
        return;
    }
    n.receive(&nmt(NmtCommand::START_NODE), ms(4));
}

#[test]
fn boot_sequence_and_pres() {
    let mut n = node(Product::Sk550p);
    assert_eq!(n.state(), NmtState::NOT_ACTIVE);
    assert!(n
        .receive(&soa(RequestedService::NO_SERVICE), ms(1))
        .is_empty());
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_1);
    n.receive(&soc(), ms(2));
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_2);
    // StartNode before EnableReadyToOperate is no CN transition: ignored.
    n.receive(&nmt(NmtCommand::START_NODE), ms(3));
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_2);
    n.receive(&nmt(NmtCommand::ENABLE_READY_TO_OPERATE), ms(3));
    n.receive(&nmt(NmtCommand::START_NODE), ms(4));
    assert_eq!(n.state(), NmtState::OPERATIONAL);
    n.receive(&soc(), ms(5));
    let out = n.receive(&preq(vec![0; 96]), ms(5));
    assert_eq!(out.len(), 1);
    let Body::Pres(p) = parse(&out[0]).body else {
        panic!()
    };
    assert_eq!(
        (p.state, p.rd, p.payload.len()),
        (NmtState::OPERATIONAL, true, 96)
    );
    // A PReq to another node is not answered.
    let other = frame(2, Body::Preq(Preq::default()));
    assert!(n.receive(&other, ms(6)).is_empty());
}

#[test]
fn ident_and_status_responses() {
    let mut n = node(Product::Tu4Pol);
    boot(&mut n, NmtState::PRE_OPERATIONAL_2);
    let out = n.receive(&soa(RequestedService::IDENT_REQUEST), ms(5));
    let Body::Asnd(a) = parse(&out[0]).body else {
        panic!()
    };
    assert_eq!(a.service, ServiceId::IDENT_RESPONSE);
    let id = IdentResponse::parse(&a.payload).unwrap();
    assert_eq!(id.vendor_id, 0xED);
    assert_eq!(id.ip.octets(), [192, 168, 100, 1]);
    assert_eq!(id.gateway.octets(), [192, 168, 100, 254]);
    assert_eq!((id.poll_in_size, id.poll_out_size), (50, 50));
    let out = n.receive(&soa(RequestedService::STATUS_REQUEST), ms(6));
    let Body::Asnd(a) = parse(&out[0]).body else {
        panic!()
    };
    let s = StatusResponse::parse(&a.payload).unwrap();
    assert_eq!(s.state, NmtState::PRE_OPERATIONAL_2);
    // Unknown SoA service: nothing, state unchanged.
    assert!(n.receive(&soa(RequestedService(0x42)), ms(7)).is_empty());
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_2);
}

#[test]
fn basic_ethernet_and_loss_of_the_mn() {
    let mut n = node(Product::Sk550p);
    n.poll(ms(4_999));
    assert_eq!(n.state(), NmtState::NOT_ACTIVE);
    n.poll(ms(5_000));
    assert_eq!(n.state(), NmtState::BASIC_ETHERNET);
    n.receive(&soc(), ms(5_001));
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_1);
    n.receive(&soc(), ms(5_002));
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_2);
    assert_eq!(n.leds().1.meaning, "No POWERLINK error");
    n.poll(ms(5_200));
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_1);
    assert_eq!(n.leds().1.meaning, "General POWERLINK error");
    n.receive(&soc(), ms(5_201));
    assert_eq!(n.state(), NmtState::PRE_OPERATIONAL_2);
    assert_eq!(n.leds().1.meaning, "No POWERLINK error");
}

fn udp(n: &mut Node, seq: Seq, command: Option<Command>) -> SdoFrame {
    let from: SocketAddr = "192.168.100.240:3819".parse().unwrap();
    let d = SdoFrame { seq, command }.emit_udp().unwrap();
    let out = n.udp(from, &d, ms(10));
    SdoFrame::parse(SdoFrame::strip_udp(&out[0]).unwrap()).unwrap()
}

fn seq(ssnr: u8, scon: Con) -> Seq {
    Seq {
        rsnr: 0,
        rcon: Con::Valid,
        ssnr,
        scon,
    }
}

#[test]
fn sdo_over_udp_reads_writes_and_refuses() {
    let mut n = node(Product::Sk550p);
    // Out of Initialisation, where the node does not answer (BU 2200 §6.2).
    n.receive(&soa(RequestedService::NO_SERVICE), ms(1));
    let init = udp(&mut n, seq(5, Con::Init), None);
    assert_eq!(
        (init.seq.rcon, init.seq.scon, init.seq.rsnr),
        (Con::Init, Con::Init, 5)
    );
    let r = udp(
        &mut n,
        seq(6, Con::Valid),
        Some(Command::read_by_index(1, 0x1018, 1)),
    );
    assert_eq!(r.command.unwrap().payload, 0xEDu32.to_le_bytes());
    // P102 of FI 5 (BU 0620 §2.4.6: 3866h), set 1, a 16-bit value; 4 bytes are too long.
    let w = udp(
        &mut n,
        seq(7, Con::Valid),
        Some(Command::write_by_index(2, 0x3866, 1, &500i32.to_le_bytes())),
    );
    assert_eq!(w.command.unwrap().abort_code(), Some(0x0607_0012));
    let w = udp(
        &mut n,
        seq(8, Con::Valid),
        Some(Command::write_by_index(2, 0x3866, 1, &500i16.to_le_bytes())),
    );
    assert_eq!(w.command.unwrap().abort_code(), None);
    let r = udp(
        &mut n,
        seq(9, Con::Valid),
        Some(Command::read_by_index(3, 0x3866, 1)),
    );
    assert_eq!(r.command.unwrap().payload, 500i16.to_le_bytes());
    // FI 5 is on the system bus: its node's SDO server answered all three, the first with its
    // abort 06070012h.
    let fi5 = proto::nord::Inverter::new(5).unwrap();
    let served = n.device_mut().node_server(fi5).map(|s| s.counts());
    assert_eq!(served, Some((3, 1)));
    // Identity is read-only.
    let w = udp(
        &mut n,
        seq(10, Con::Valid),
        Some(Command::write_by_index(4, 0x1018, 1, &[0; 4])),
    );
    assert_eq!(w.command.unwrap().abort_code(), Some(0x0601_0002));
    // A skipped sequence number: error in the sequence layer.
    let e = udp(
        &mut n,
        seq(20, Con::Valid),
        Some(Command::read_by_index(5, 0x1018, 1)),
    );
    assert_eq!(e.seq.rcon, Con::ErrorOrAckRequest);
    assert_eq!(e.command.unwrap().abort_code(), Some(0x0504_0003));
    // No such object; no such FI on a 1-inverter device would be 08000020h.
    let r = udp(
        &mut n,
        seq(11, Con::Valid),
        Some(Command::read_by_index(6, 0x6000, 0)),
    );
    assert_eq!(r.command.unwrap().abort_code(), Some(0x0602_0000));
}

#[test]
fn no_parameter_communication_during_initialisation() {
    // BU 2200 §6.2 Initialisation: "Keine Prozessdaten- und Parameterkommunikation".
    let mut n = node(Product::Tu3Pol);
    assert_eq!(n.state(), NmtState::NOT_ACTIVE);
    let from: SocketAddr = "192.168.100.240:3819".parse().unwrap();
    let d = SdoFrame {
        seq: seq(0, Con::Init),
        command: None,
    }
    .emit_udp()
    .unwrap();
    assert!(n.udp(from, &d, ms(10)).is_empty());
    // Out of it (Pre-Operational 1 after an SoA) the same datagram is answered.
    n.receive(&soa(RequestedService::NO_SERVICE), ms(11));
    assert_eq!(n.udp(from, &d, ms(12)).len(), 1);
}

#[test]
fn a_lost_inverter_answers_08000020h() {
    // BU 2200 §5.2.4 / §6.4.1: no connection between bus interface and FI.
    let mut n = node(Product::Tu3Pol);
    n.receive(&soa(RequestedService::NO_SERVICE), ms(1));
    udp(&mut n, seq(5, Con::Init), None);
    n.lose_inverter(proto::nord::Inverter::new(2).unwrap());
    // FI 2's P102 (3066h) cannot be stored; FI 1's (2866h) still can.
    let w = udp(
        &mut n,
        seq(6, Con::Valid),
        Some(Command::write_by_index(1, 0x3066, 1, &300i16.to_le_bytes())),
    );
    assert_eq!(w.command.unwrap().abort_code(), Some(0x0800_0020));
    let w = udp(
        &mut n,
        seq(7, Con::Valid),
        Some(Command::write_by_index(2, 0x2866, 1, &300i16.to_le_bytes())),
    );
    assert_eq!(w.command.unwrap().abort_code(), None);
}

#[test]
fn the_mapping_is_the_mns_to_configure_in_pre_operational_only() {
    // BU 0620 §2.4.5 / BU 2200 §6.3.6: the SK 550P and the SK TU3-POL map dynamically while the
    // MN configures them; from Ready To Operate on the mapping stays (08000022h). The SK
    // TU4-POL's mapping is static: its mapping objects are read-only (06010002h).
    let off = |product, state| {
        let mut n = node(product);
        boot(&mut n, state);
        assert_eq!(n.state(), state);
        udp(&mut n, seq(5, Con::Init), None);
        let w = udp(
            &mut n,
            seq(6, Con::Valid),
            Some(Command::write_by_index(1, 0x1A00, 0, &[0])),
        );
        w.command.unwrap().abort_code()
    };
    for product in [Product::Sk550p, Product::Tu3Pol] {
        assert_eq!(
            off(product, NmtState::PRE_OPERATIONAL_2),
            None,
            "{product:?}"
        );
        assert_eq!(
            off(product, NmtState::READY_TO_OPERATE),
            Some(0x0800_0022),
            "{product:?}"
        );
    }
    assert_eq!(
        off(Product::Tu4Pol, NmtState::PRE_OPERATIONAL_2),
        Some(0x0601_0002)
    );
}
