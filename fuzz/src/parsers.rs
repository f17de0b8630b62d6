//! The codec targets: each runs one protocol family's parsers of `proto` on the fuzzer's
//! bytes, through the family's `no_panic::parse_all`, the function its own no-panic unit test
//! runs on mutated and random input. Which parsers each reaches is listed in
//! `docs/fuzzing.md`.

use proto::lldp::Lldpdu;

/// EtherCAT: Ethernet II, frames and datagrams (also processed in place), mailbox, CoE (SDO,
/// SDO information, emergency), SM/FMMU registers, AL control and status, SII.
pub fn ecat(data: &[u8]) {
    proto::ecat::no_panic::parse_all(data);
}

/// POWERLINK: frames (SoC, PReq, PRes, SoA, ASnd), the ASnd services (IdentResponse,
/// StatusResponse, NMT command and request), SDO over ASnd and over UDP, error entries.
pub fn epl(data: &[u8]) {
    proto::epl::no_panic::parse_all(data);
}

/// PROFINET link layer: frame ids, DCP (telegrams and blocks), RT frames, alarms (RTA).
pub fn pnio(data: &[u8]) {
    proto::pnio::no_panic::parse_all(data);
}

/// PROFINET over UDP: DCE/RPC, NDR requests and responses, PNIO-CM blocks (connect, record,
/// control, release).
pub fn pnio_rpc(data: &[u8]) {
    proto::pnio::block::no_panic::rpc(data);
    proto::pnio::block::no_panic::blocks(data);
}

/// EtherNet/IP: encapsulation, CPF, CIP message router, EPath, connection manager,
/// identity, class-1 I/O.
pub fn enip(data: &[u8]) {
    proto::enip::no_panic::parse_all(data);
}

/// The NORD parameter channel (PKW) and PPO telegrams.
pub fn nord(data: &[u8]) {
    proto::nord::no_panic::parse_all(data);
}

/// CAN: SocketCAN frames and socketcand's text protocol.
pub fn can(data: &[u8]) {
    proto::can::no_panic::parse_all(data);
}

/// CANopen: SDO (expedited, segmented, block), NMT, error control, SYNC, EMCY, and the
/// message classifier on every object's COB-ID.
pub fn canopen(data: &[u8]) {
    proto::canopen::no_panic::parse_all(data);
}

/// LLDP: the mandatory TLVs; what parses emits and parses back the same.
pub fn lldp(data: &[u8]) {
    if let Ok(l) = Lldpdu::parse(data) {
        assert_eq!(Lldpdu::parse(&l.emit()), Ok(l));
    }
}
