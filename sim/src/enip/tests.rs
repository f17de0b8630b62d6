//! Unit tests of the sans-IO adapter: requests are built with `proto::enip`'s Repr types and
//! fed with virtual time, replies are parsed back with the same types.
//!
//! Sources: encapsulation and connection-manager codes from the CIP/EtherNet/IP specification
//! as `proto::enip` cites them; assemblies, parameter classes and watchdog behaviour from
//! BU 0620 §2.3 (SK 550P) and BU 2100 §6–§7 (TU3/TU4/CU4-EIP).

use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4};
use std::time::Duration;

use proto::enip::cip::{class, GeneralStatus as GS, MrRequest, MrResponse, Service};
use proto::enip::cm::{
    ext, failure_data, kind, ForwardClose, ForwardOpen, ForwardOpenReply, NetParams, Transport,
    UnconnectedSend,
};
use proto::enip::cpf::{item_type, Cpf, Item};
use proto::enip::encap::{Command, EncapRepr, EncapStatus, RegisterSession, SendData};
use proto::enip::epath::{EPath, Segment};
use proto::enip::identity::Identity;
use proto::enip::io::{IoFrame, IO_PORT};
use proto::nord::addr::{self, cip_instance};
use proto::nord::{eip, led, ArrayElement, Inverter, ParamAddress, ParamNumber, ParamSet, Product};
use proto::wire::Error;
use rstest::rstest;

use super::{
    no_room_reply, Adapter, ClientId, IoError, TcpReply, DEFAULT_INACTIVITY_TIMEOUT, MAX_SESSIONS,
};
use crate::device::{Device, DeviceConfig};

/// Where the adapter says it is (ListIdentity); deliberately not the P160/P850 factory address.
const ADDRESS: SocketAddrV4 = SocketAddrV4::new(Ipv4Addr::new(10, 0, 0, 5), 44818);
/// The scanner's TCP endpoint.
const PEER: SocketAddr = SocketAddr::V4(SocketAddrV4::new(Ipv4Addr::new(10, 0, 0, 1), 50_000));
const CONTEXT: [u8; 8] = *b"unittest";
const CLIENT: ClientId = 1;
/// Originator vendor and serial of the Forward_Opens.
const VENDOR: u16 = 0x0001;
const ORIGINATOR_SERIAL: u32 = 0x1234_5678;
/// RPI of the connections, µs.
const RPI_US: u32 = 10_000;
/// A control word (bit 10 "control data valid" set) and the data of one inverter's slot.
const CONTROL: u16 = 0x047E;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn adapter(product: Product) -> Adapter {
    Adapter::new(Device::new(DeviceConfig::new(product)), ADDRESS)
}

fn encap(command: Command, session: u32, data: Vec<u8>) -> Vec<u8> {
    EncapRepr {
        command: command.0,
        session,
        status: 0,
        context: CONTEXT,
        options: 0,
        data,
    }
    .emit()
    .unwrap()
}

/// The reply to a message that keeps the connection open.
fn answer(r: TcpReply) -> EncapRepr {
    assert!(!r.close, "the adapter closed the connection");
    let m = EncapRepr::parse(&r.reply.expect("a reply")).unwrap();
    assert_eq!(m.context, CONTEXT, "sender context echoed");
    m
}

fn register(a: &mut Adapter, client: ClientId) -> EncapRepr {
    let msg = encap(Command::REGISTER_SESSION, 0, RegisterSession::V1.emit());
    answer(a.handle_tcp(client, PEER, &msg, Duration::ZERO))
}

fn send_rr_data(req: &MrRequest) -> Vec<u8> {
    SendData {
        interface: 0,
        timeout: 0,
        cpf: Cpf::new(vec![Item::Null, Item::UnconnectedData(req.emit())]),
    }
    .emit()
    .unwrap()
}

fn np(size: u16, kind: u8) -> NetParams {
    NetParams::fixed(size, kind)
}

/// A class-1 Forward_Open: `20 04 24 01 2C o→t 2C t→o`, RPI 10 ms both ways.
fn io_open(
    serial: u16,
    o_t_point: u16,
    t_o_point: u16,
    o_t_size: u16,
    t_o_size: u16,
) -> ForwardOpen {
    ForwardOpen {
        large: false,
        priority_tick: 0x0A,
        timeout_ticks: 0x0E,
        o_t_id: 0,
        t_o_id: 0x5343_0000 | u32::from(serial),
        serial,
        vendor: VENDOR,
        originator_serial: ORIGINATOR_SERIAL,
        timeout_multiplier: 0,
        o_t_rpi: RPI_US,
        o_t: np(o_t_size, kind::POINT_TO_POINT),
        t_o_rpi: RPI_US,
        t_o: np(t_o_size, kind::POINT_TO_POINT),
        transport: Transport::CLASS1_CYCLIC,
        path: EPath::io_connection(o_t_point, t_o_point),
    }
}

/// The TU3-EIP's fixed 12-byte assemblies 100/101: O→T 2 + 4 (run/idle) + 12, T→O 2 + 12.
fn tu3_owner(serial: u16) -> ForwardOpen {
    io_open(serial, 100, 101, 18, 14)
}

/// A class-3 Forward_Open to the message router.
fn explicit_open(serial: u16) -> ForwardOpen {
    ForwardOpen {
        transport: Transport::CLASS3,
        o_t: np(504, kind::POINT_TO_POINT),
        t_o: np(504, kind::POINT_TO_POINT),
        path: EPath::object(class::MESSAGE_ROUTER, 1),
        ..io_open(serial, 0, 0, 0, 0)
    }
}

/// O→T data of the TU3's assembly 100: control word, five setpoints.
fn outputs(control: u16) -> Vec<u8> {
    let mut d = control.to_le_bytes().to_vec();
    d.resize(12, 0);
    d
}

fn io(connection: u32, count: u16, run_idle: Option<u32>, data: Vec<u8>) -> Vec<u8> {
    IoFrame {
        connection,
        sequence: u32::from(count),
        count,
        run_idle,
        data,
    }
    .emit()
    .unwrap()
}

fn word(r: &MrResponse) -> i16 {
    assert_eq!(r.status(), GS::SUCCESS, "{r:?}");
    let [lo, hi] = r.data[..] else {
        panic!("a 16-bit value, got {:?}", r.data)
    };
    i16::from_le_bytes([lo, hi])
}

fn set_of(n: i64) -> Option<ParamSet> {
    Some(ParamSet::new(n).unwrap())
}

fn element(n: i64) -> Option<ArrayElement> {
    Some(ArrayElement::new(n).unwrap())
}

/// An adapter with one registered TCP client, at a virtual time.
struct Bench {
    a: Adapter,
    session: u32,
    now: Duration,
}

impl Bench {
    fn new(product: Product) -> Bench {
        let mut a = adapter(product);
        let session = register(&mut a, CLIENT).session;
        Bench {
            a,
            session,
            now: Duration::ZERO,
        }
    }

    fn tcp(&mut self, command: Command, data: Vec<u8>) -> EncapRepr {
        let msg = encap(command, self.session, data);
        answer(self.a.handle_tcp(CLIENT, PEER, &msg, self.now))
    }

    /// One UCMM request (SendRRData).
    fn request(&mut self, req: &MrRequest) -> MrResponse {
        let r = self.tcp(Command::SEND_RR_DATA, send_rr_data(req));
        assert_eq!(EncapStatus(r.status), EncapStatus::SUCCESS);
        let sd = SendData::parse(&r.data).unwrap();
        let [Item::Null, Item::UnconnectedData(b)] = &sd.cpf.items[..] else {
            panic!("reply items {:?}", sd.cpf.items)
        };
        MrResponse::parse(b).unwrap()
    }

    fn call(&mut self, service: Service, path: EPath, data: Vec<u8>) -> MrResponse {
        let r = self.request(&MrRequest {
            service: service.0,
            path,
            data,
        });
        assert_eq!(r.service, service.0, "reply to the request's service");
        r
    }

    fn get(&mut self, class: u16, instance: u32, attribute: u16) -> MrResponse {
        let path = EPath::attribute(class, instance, attribute);
        self.call(Service::GET_ATTRIBUTE_SINGLE, path, Vec::new())
    }

    fn set(&mut self, class: u16, instance: u32, attribute: u16, data: &[u8]) -> MrResponse {
        let path = EPath::attribute(class, instance, attribute);
        self.call(Service::SET_ATTRIBUTE_SINGLE, path, data.to_vec())
    }

    /// A parameter of the bus module (class 100), instance per BU 2100 §6.3.
    fn module_param(&mut self, number: u16, element: Option<ArrayElement>) -> MrResponse {
        self.get(100, u32::from(cip_instance(None, element)), number)
    }

    /// A parameter of an inverter, addressed by `proto::nord::addr::cip`.
    fn inverter_param(
        &mut self,
        fi: u8,
        number: u16,
        set: Option<ParamSet>,
        element: Option<ArrayElement>,
    ) -> MrResponse {
        let p = self.a.product();
        let c = addr::cip(p, param(fi, number, set, element)).unwrap();
        self.get(c.class, u32::from(c.instance), c.attribute)
    }

    fn open(&mut self, fo: &ForwardOpen) -> MrResponse {
        let service = if fo.large {
            Service::LARGE_FORWARD_OPEN
        } else {
            Service::FORWARD_OPEN
        };
        self.call(
            service,
            EPath::object(class::CONNECTION_MANAGER, 1),
            fo.emit(),
        )
    }

    fn open_ok(&mut self, fo: &ForwardOpen) -> ForwardOpenReply {
        let r = self.open(fo);
        assert_eq!(r.status(), GS::SUCCESS, "{r:?}");
        let reply = ForwardOpenReply::parse(&r.data).unwrap();
        assert_eq!(
            (reply.serial, reply.vendor, reply.originator_serial),
            fo.key()
        );
        reply
    }

    fn close(&mut self, serial: u16) -> MrResponse {
        let fc = ForwardClose {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            serial,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            path: EPath::object(class::ASSEMBLY, 1),
        };
        let path = EPath::object(class::CONNECTION_MANAGER, 1);
        self.call(Service::FORWARD_CLOSE, path, fc.emit())
    }

    fn io(&mut self, datagram: &[u8]) -> Result<(), IoError> {
        self.a.handle_io(PEER, datagram, self.now)
    }

    /// P700 [-01] "present error" of every inverter.
    fn present_errors(&mut self) -> Vec<i16> {
        (1..=self.a.device_mut().config().inverters)
            .map(|fi| word(&self.inverter_param(fi, 700, None, element(1))))
            .collect()
    }
}

fn param(
    fi: u8,
    number: u16,
    set: Option<ParamSet>,
    element: Option<ArrayElement>,
) -> ParamAddress {
    ParamAddress {
        inverter: Inverter::new(i64::from(fi)).unwrap(),
        number: ParamNumber::new(i64::from(number)).unwrap(),
        set,
        element,
    }
}

fn assert_refused(r: &MrResponse, extended: &[u16], fo: &ForwardOpen) {
    assert_eq!(r.status(), GS::CONNECTION_FAILURE, "{r:?}");
    assert_eq!(r.extended, extended);
    assert_eq!(r.data, failure_data(fo.key()), "the triple echoed");
}

// --- Sessions and encapsulation ----------------------------------------------------------------

#[test]
fn register_session_hands_out_a_handle_and_echoes_the_request() {
    let mut a = adapter(Product::Tu3Eip);
    let r = register(&mut a, CLIENT);
    assert_eq!(Command(r.command), Command::REGISTER_SESSION);
    assert_eq!(EncapStatus(r.status), EncapStatus::SUCCESS);
    assert_ne!(r.session, 0);
    assert_eq!(
        RegisterSession::parse(&r.data).unwrap(),
        RegisterSession::V1
    );
    assert_eq!(a.session_count(), 1);

    let other = register(&mut a, 2);
    assert_eq!(EncapStatus(other.status), EncapStatus::SUCCESS);
    assert_ne!(other.session, r.session);
    assert_eq!(a.session_count(), 2);
}

#[rstest]
#[case::second_on_the_same_client(RegisterSession::V1, 0, true, EncapStatus::INCORRECT_DATA)]
#[case::non_zero_session_field(RegisterSession::V1, 0x77, false, EncapStatus::INCORRECT_DATA)]
#[case::version_2(RegisterSession { version: 2, options: 0 }, 0, false, EncapStatus::UNSUPPORTED_PROTOCOL)]
#[case::options_set(RegisterSession { version: 1, options: 1 }, 0, false, EncapStatus::UNSUPPORTED_PROTOCOL)]
fn register_session_refusals(
    #[case] rs: RegisterSession,
    #[case] session: u32,
    #[case] registered_before: bool,
    #[case] status: EncapStatus,
) {
    let mut a = adapter(Product::Tu3Eip);
    if registered_before {
        register(&mut a, CLIENT);
    }
    let before = a.session_count();
    let msg = encap(Command::REGISTER_SESSION, session, rs.emit());
    let r = answer(a.handle_tcp(CLIENT, PEER, &msg, Duration::ZERO));
    assert_eq!(EncapStatus(r.status), status);
    assert_eq!(a.session_count(), before);
}

#[test]
fn sessions_beyond_the_maximum_are_refused_with_insufficient_memory() {
    let mut a = adapter(Product::Tu3Eip);
    for client in 0..MAX_SESSIONS as ClientId {
        assert_eq!(register(&mut a, client).status, 0);
    }
    let r = register(&mut a, MAX_SESSIONS as ClientId);
    assert_eq!(EncapStatus(r.status), EncapStatus::INSUFFICIENT_MEMORY);
    assert_eq!(a.session_count(), MAX_SESSIONS);
}

#[test]
fn unregister_session_closes_and_the_handle_dies() {
    let mut b = Bench::new(Product::Tu3Eip);
    let bye = encap(Command::UNREGISTER_SESSION, b.session, Vec::new());
    let r = b.a.handle_tcp(CLIENT, PEER, &bye, Duration::ZERO);
    assert_eq!(
        r,
        TcpReply {
            reply: None,
            close: true
        }
    );
    assert_eq!(b.a.session_count(), 0);
    let get = MrRequest {
        service: Service::GET_ATTRIBUTE_SINGLE.0,
        path: EPath::attribute(class::IDENTITY, 1, 1),
        data: Vec::new(),
    };
    let r = b.tcp(Command::SEND_RR_DATA, send_rr_data(&get));
    assert_eq!(EncapStatus(r.status), EncapStatus::INVALID_SESSION);
    assert!(r.data.is_empty());
}

#[test]
fn unregistering_a_session_of_another_client_is_refused() {
    let mut b = Bench::new(Product::Tu3Eip);
    let bye = encap(Command::UNREGISTER_SESSION, b.session, Vec::new());
    let r = answer(b.a.handle_tcp(2, PEER, &bye, Duration::ZERO));
    assert_eq!(EncapStatus(r.status), EncapStatus::INVALID_SESSION);
    assert_eq!(b.a.session_count(), 1);
}

#[rstest]
#[case::send_rr_data_without_session(Command::SEND_RR_DATA, Some(0))]
#[case::send_rr_data_unknown_handle(Command::SEND_RR_DATA, Some(0xDEAD))]
#[case::send_unit_data_unknown_handle(Command::SEND_UNIT_DATA, Some(0xDEAD))]
#[case::send_rr_data_of_another_client(Command::SEND_RR_DATA, None)]
fn requests_outside_the_clients_session_are_invalid_session(
    #[case] command: Command,
    #[case] session: Option<u32>,
) {
    let mut b = Bench::new(Product::Tu3Eip);
    let get = MrRequest {
        service: Service::GET_ATTRIBUTE_SINGLE.0,
        path: EPath::attribute(class::IDENTITY, 1, 1),
        data: Vec::new(),
    };
    // `None`: client 2 presents client 1's valid handle.
    let (client, session) = match session {
        Some(s) => (CLIENT, s),
        None => (2, b.session),
    };
    let msg = encap(command, session, send_rr_data(&get));
    let r = answer(b.a.handle_tcp(client, PEER, &msg, Duration::ZERO));
    assert_eq!(Command(r.command), command);
    assert_eq!(EncapStatus(r.status), EncapStatus::INVALID_SESSION);
}

#[test]
fn an_unknown_command_is_invalid_command_and_the_connection_stays() {
    let mut b = Bench::new(Product::Tu3Eip);
    let r = b.tcp(Command(0x0099), Vec::new());
    assert_eq!(r.command, 0x0099);
    assert_eq!(EncapStatus(r.status), EncapStatus::INVALID_COMMAND);
    // The session still serves.
    assert_eq!(
        b.get(class::IDENTITY, 1, 1).data,
        eip::VENDOR_ID.to_le_bytes()
    );
}

#[test]
fn the_dlr_object_is_listed_and_answers_topology_and_status() {
    // BU 2100 §3.1 "Supported functions: UCMM, DLR": DLR object 47h, instance 1.
    let mut b = Bench::new(Product::Tu4Eip);
    let list = b.get(class::MESSAGE_ROUTER, 1, 1);
    assert!(
        list.data.chunks(2).skip(1).any(|c| c == [0x47, 0x00]),
        "{list:?}"
    );
    assert_eq!(b.get(class::DLR, 1, 1).data, [0], "linear topology");
    assert_eq!(b.get(class::DLR, 1, 2).data, [0], "status normal");
    assert_eq!(
        b.get(class::DLR, 1, 9).status(),
        GS::ATTRIBUTE_NOT_SUPPORTED
    );
    assert_eq!(
        b.get(class::DLR, 2, 1).status(),
        GS::PATH_DESTINATION_UNKNOWN
    );
}

#[test]
fn assembly_110_drives_the_tu4_relays_and_p176() {
    // BU 2100 §6.2.1 (p. 32): the interface word of 110, DO1 bit 0, DO2 bit 1 → P175, P176 [-01].
    let mut b = Bench::new(Product::Tu4Eip);
    let r = b.set(class::ASSEMBLY, 110, 3, &[0x02, 0x00]);
    assert_eq!(r.status(), GS::SUCCESS, "{r:?}");
    assert_eq!(word(&b.module_param(175, None)), 2);
    assert_eq!(word(&b.module_param(176, element(1))), 2);
}

#[test]
fn nop_and_non_zero_options_get_no_reply() {
    let mut b = Bench::new(Product::Tu3Eip);
    let nop = encap(Command::NOP, 0, vec![1, 2, 3]);
    assert_eq!(
        b.a.handle_tcp(CLIENT, PEER, &nop, Duration::ZERO),
        TcpReply::default()
    );
    let mut opts = EncapRepr::parse(&encap(Command::LIST_IDENTITY, 0, Vec::new())).unwrap();
    opts.options = 1;
    let dropped = b.a.dropped();
    let r =
        b.a.handle_tcp(CLIENT, PEER, &opts.emit().unwrap(), Duration::ZERO);
    assert_eq!(r, TcpReply::default());
    assert_eq!(b.a.dropped(), dropped + 1);
}

#[test]
fn a_message_with_a_lying_length_closes_the_connection() {
    let mut a = adapter(Product::Tu3Eip);
    let mut msg = encap(Command::REGISTER_SESSION, 0, RegisterSession::V1.emit());
    msg[2] = 8; // length field: 8, but 4 bytes follow the header.
    let r = a.handle_tcp(CLIENT, PEER, &msg, Duration::ZERO);
    assert_eq!(
        r,
        TcpReply {
            reply: None,
            close: true
        }
    );
    assert_eq!(a.session_count(), 0);
}

#[test]
fn send_rr_data_with_a_connected_address_item_is_incorrect_data() {
    let mut b = Bench::new(Product::Tu3Eip);
    let data = SendData {
        interface: 0,
        timeout: 0,
        cpf: Cpf::new(vec![
            Item::ConnectedAddress(1),
            Item::UnconnectedData(vec![0x0E, 0]),
        ]),
    };
    let r = b.tcp(Command::SEND_RR_DATA, data.emit().unwrap());
    assert_eq!(EncapStatus(r.status), EncapStatus::INCORRECT_DATA);
}

// --- Discovery ---------------------------------------------------------------------------------

#[rstest]
#[case(Product::Sk550p)]
#[case(Product::Tu3Eip)]
#[case(Product::Tu4Eip)]
#[case(Product::Cu4Eip)]
fn list_identity_over_udp_reports_the_products_identity(#[case] product: Product) {
    let mut a = adapter(product);
    let r = a
        .handle_udp(&encap(Command::LIST_IDENTITY, 0, Vec::new()))
        .expect("a reply");
    let r = EncapRepr::parse(&r).unwrap();
    assert_eq!(Command(r.command), Command::LIST_IDENTITY);
    assert_eq!(EncapStatus(r.status), EncapStatus::SUCCESS);
    assert_eq!(r.context, CONTEXT);
    let cpf = Cpf::parse(&r.data).unwrap();
    let [Item::Other { type_id, data }] = &cpf.items[..] else {
        panic!("items {:?}", cpf.items)
    };
    assert_eq!(*type_id, item_type::LIST_IDENTITY);
    let (id, at) = Identity::parse_list_identity_item(data).unwrap();
    let info = eip::identity(product).unwrap();
    assert_eq!(at, ADDRESS);
    assert_eq!(
        (id.vendor, id.device_type, id.product_code, id.revision),
        (eip::VENDOR_ID, 0x0C, info.product_code, info.revision)
    );
    assert_eq!(id.product_name, info.name);
    assert_eq!(id.state, 3);
    assert_eq!(&id, a.identity());
}

#[test]
fn list_identity_with_data_is_invalid_length() {
    let mut a = adapter(Product::Tu3Eip);
    let r = a
        .handle_udp(&encap(Command::LIST_IDENTITY, 0, vec![0, 0]))
        .unwrap();
    let r = EncapRepr::parse(&r).unwrap();
    assert_eq!(EncapStatus(r.status), EncapStatus::INVALID_LENGTH);
    assert!(r.data.is_empty());
}

#[rstest]
#[case::register_session(Command::REGISTER_SESSION, RegisterSession::V1.emit())]
#[case::send_rr_data(Command::SEND_RR_DATA, vec![0; 8])]
#[case::unknown(Command(0x0099), Vec::new())]
fn udp_drops_what_needs_a_session(#[case] command: Command, #[case] data: Vec<u8>) {
    let mut a = adapter(Product::Tu3Eip);
    assert_eq!(a.handle_udp(&encap(command, 0, data)), None);
    assert_eq!(a.dropped(), 1);
    assert_eq!(a.session_count(), 0);
}

// --- Parameter classes 100..108 ----------------------------------------------------------------

#[rstest]
// P102 "Acceleration time", set-dependent, factory 2.00 s; instance = set - 1.
#[case::p102_set1_fi1(Product::Tu3Eip, 101, 0, 102, 200)]
#[case::p102_set4_fi8(Product::Tu3Eip, 108, 3, 102, 200)]
// P543 [-01] "Actual bus value" has its own factory setting 1; instance = element - 1.
#[case::p543_element1(Product::Tu3Eip, 101, 0, 543, 1)]
#[case::p465_element31(Product::Tu3Eip, 101, 30, 465, 0)]
// Module parameters in class 100: P160 [-01] = 192 (factory 192.168.1.100), P172 TU3 = 2.
#[case::p160_element1(Product::Tu3Eip, 100, 0, 160, 192)]
#[case::p172_tu3(Product::Tu3Eip, 100, 0, 172, 2)]
#[case::p172_cu4(Product::Cu4Eip, 100, 0, 172, 0)]
#[case::p153_element2(Product::Tu4Eip, 100, 1, 153, 5)]
// SK 550P: the interface is built into FI 1, so P850 answers in class 101.
#[case::sk550p_p850_element4(Product::Sk550p, 101, 3, 850, 100)]
fn get_attribute_single_reads_parameters(
    #[case] product: Product,
    #[case] class: u16,
    #[case] instance: u32,
    #[case] number: u16,
    #[case] value: i16,
) {
    let mut b = Bench::new(product);
    assert_eq!(word(&b.get(class, instance, number)), value);
}

#[rstest]
#[case::no_such_parameter(Product::Tu3Eip, 101, 0, 999, GS::ATTRIBUTE_NOT_SUPPORTED)]
#[case::beyond_p999(Product::Tu3Eip, 101, 0, 1000, GS::ATTRIBUTE_NOT_SUPPORTED)]
#[case::inverter_parameter_in_class_100(Product::Tu3Eip, 100, 0, 102, GS::ATTRIBUTE_NOT_SUPPORTED)]
#[case::module_parameter_of_tu4_only(Product::Tu3Eip, 100, 0, 151, GS::ATTRIBUTE_NOT_SUPPORTED)]
#[case::plain_parameter_instance_1(Product::Tu3Eip, 101, 1, 509, GS::PATH_DESTINATION_UNKNOWN)]
#[case::set_5(Product::Tu3Eip, 101, 4, 102, GS::PATH_DESTINATION_UNKNOWN)]
#[case::element_32_of_31(Product::Tu3Eip, 101, 31, 465, GS::PATH_DESTINATION_UNKNOWN)]
#[case::element_10_of_9(Product::Tu3Eip, 101, 36, 400, GS::PATH_DESTINATION_UNKNOWN)]
#[case::fi5_of_four(Product::Tu4Eip, 105, 0, 102, GS::PATH_DESTINATION_UNKNOWN)]
#[case::class_109(Product::Tu3Eip, 109, 0, 102, GS::PATH_DESTINATION_UNKNOWN)]
#[case::class_100_on_sk550p(Product::Sk550p, 100, 0, 850, GS::PATH_DESTINATION_UNKNOWN)]
#[case::class_99(Product::Tu3Eip, 99, 0, 102, GS::PATH_DESTINATION_UNKNOWN)]
fn get_attribute_single_refusals(
    #[case] product: Product,
    #[case] class: u16,
    #[case] instance: u32,
    #[case] number: u16,
    #[case] status: GS,
) {
    let mut b = Bench::new(product);
    let r = b.get(class, instance, number);
    assert_eq!(r.status(), status, "{r:?}");
    assert!(r.data.is_empty());
}

#[test]
fn set_then_get_addresses_set_and_element_by_the_manuals_formula() {
    let mut b = Bench::new(Product::Tu3Eip);
    // P102 set 2 of FI 3 (BU 0620 §2.5.6.4: 2.5 s = 250).
    let c = addr::cip(Product::Tu3Eip, param(3, 102, set_of(2), None)).unwrap();
    assert_eq!((c.class, c.instance, c.attribute), (103, 1, 102));
    let r = b.set(
        c.class,
        c.instance.into(),
        c.attribute,
        &250u16.to_le_bytes(),
    );
    assert_eq!(
        r,
        MrResponse::ok(Service::SET_ATTRIBUTE_SINGLE.0, Vec::new())
    );
    assert_eq!(word(&b.inverter_param(3, 102, set_of(2), None)), 250);
    assert_eq!(word(&b.inverter_param(3, 102, set_of(1), None)), 200);
    assert_eq!(word(&b.inverter_param(2, 102, set_of(2), None)), 200);

    // P400 set 3, element 2: instance (2 - 1) · 4 + (3 - 1) = 6.
    let c = addr::cip(Product::Tu3Eip, param(1, 400, set_of(3), element(2))).unwrap();
    assert_eq!(c.instance, 6);
    assert_eq!(b.set(101, 6, 400, &[7, 0]).status(), GS::SUCCESS);
    assert_eq!(word(&b.inverter_param(1, 400, set_of(3), element(2))), 7);
    assert_eq!(word(&b.inverter_param(1, 400, set_of(2), element(2))), 0);

    // P465 is signed: -100 travels as INT 9CFFh.
    assert_eq!(
        b.set(101, 2, 465, &(-100i16).to_le_bytes()).status(),
        GS::SUCCESS
    );
    assert_eq!(b.get(101, 2, 465).data, [0x9C, 0xFF]);
}

#[rstest]
#[case::information_parameter(Product::Tu3Eip, 101, 0, 700, vec![0, 0], GS::ATTRIBUTE_NOT_SETTABLE)]
#[case::module_information(Product::Tu3Eip, 100, 0, 172, vec![1, 0], GS::ATTRIBUTE_NOT_SETTABLE)]
#[case::sk550p_p853_usb_only(Product::Sk550p, 101, 0, 853, vec![1, 0], GS::ATTRIBUTE_NOT_SETTABLE)]
#[case::above_max(Product::Tu3Eip, 101, 0, 102, 32001u16.to_le_bytes().to_vec(), GS::INVALID_ATTRIBUTE_VALUE)]
#[case::below_min(Product::Tu3Eip, 101, 0, 105, vec![0, 0], GS::INVALID_ATTRIBUTE_VALUE)]
#[case::p151_below_minus_1(Product::Tu4Eip, 100, 0, 151, (-2i16).to_le_bytes().to_vec(), GS::INVALID_ATTRIBUTE_VALUE)]
#[case::one_byte(Product::Tu3Eip, 101, 0, 102, vec![1], GS::NOT_ENOUGH_DATA)]
#[case::three_bytes(Product::Tu3Eip, 101, 0, 102, vec![1, 0, 0], GS::TOO_MUCH_DATA)]
#[case::no_such_parameter(Product::Tu3Eip, 101, 0, 999, vec![1, 0], GS::ATTRIBUTE_NOT_SUPPORTED)]
#[case::fi5_of_four(Product::Cu4Eip, 105, 0, 102, vec![1, 0], GS::PATH_DESTINATION_UNKNOWN)]
fn set_attribute_single_refusals(
    #[case] product: Product,
    #[case] class: u16,
    #[case] instance: u32,
    #[case] number: u16,
    #[case] data: Vec<u8>,
    #[case] status: GS,
) {
    let mut b = Bench::new(product);
    let before = b.get(class, instance, number);
    let r = b.set(class, instance, number, &data);
    assert_eq!(r.status(), status, "{r:?}");
    assert_eq!(b.get(class, instance, number), before, "value unchanged");
}

#[rstest]
#[case::get_attributes_all(Service::GET_ATTRIBUTES_ALL, EPath::attribute(101, 0, 102))]
#[case::reset(Service::RESET, EPath::attribute(101, 0, 102))]
#[case::vendor_specific(Service(0x4C), EPath::attribute(100, 0, 160))]
fn other_services_on_parameter_classes_are_not_supported(
    #[case] service: Service,
    #[case] path: EPath,
) {
    let mut b = Bench::new(Product::Tu3Eip);
    let r = b.call(service, path, Vec::new());
    assert_eq!(r.status(), GS::SERVICE_NOT_SUPPORTED);
}

#[test]
fn get_with_data_is_too_much_data() {
    let mut b = Bench::new(Product::Tu3Eip);
    let r = b.call(
        Service::GET_ATTRIBUTE_SINGLE,
        EPath::attribute(101, 0, 102),
        vec![0],
    );
    assert_eq!(r.status(), GS::TOO_MUCH_DATA);
}

#[test]
fn unconnected_send_to_the_backplane_slot_0_is_answered_here() {
    let mut b = Bench::new(Product::Tu3Eip);
    let inner = MrRequest {
        service: Service::GET_ATTRIBUTE_SINGLE.0,
        path: EPath::attribute(101, 0, 102),
        data: Vec::new(),
    };
    let us = |link: u8| UnconnectedSend {
        priority_tick: 0x0A,
        timeout_ticks: 0x0E,
        request: inner.emit(),
        route: EPath {
            segments: vec![Segment::Port {
                port: 1,
                link: vec![link],
            }],
        },
    };
    let send = |link| MrRequest {
        service: Service::UNCONNECTED_SEND.0,
        path: EPath::object(class::CONNECTION_MANAGER, 1),
        data: us(link).emit(),
    };
    let r = b.request(&send(0));
    assert_eq!(
        r.service,
        Service::GET_ATTRIBUTE_SINGLE.0,
        "the embedded reply"
    );
    assert_eq!(word(&r), 200);
    let r = b.request(&send(3));
    assert_eq!(r.service, Service::UNCONNECTED_SEND.0);
    assert_eq!(r.status(), GS::CONNECTION_FAILURE);
    assert_eq!(r.extended, [ext::PORT_NOT_AVAILABLE]);
}

// --- Forward_Open / Forward_Close --------------------------------------------------------------

#[rstest]
// BU 2100 §6.2.1: TU3 100/101 12 bytes fixed with the run/idle header (P166 irrelevant).
#[case::tu3_100_101(Product::Tu3Eip, 100, 101, 18, 14, 100)]
// TU3 102/103: 96 bytes variable, header per P166 (factory 0 = header).
#[case::tu3_102_103(Product::Tu3Eip, 102, 103, 102, 98, 102)]
#[case::tu3_102_103_truncated(Product::Tu3Eip, 102, 103, 30, 26, 102)]
#[case::tu4_100_101(Product::Tu4Eip, 100, 101, 18, 14, 100)]
// TU4/CU4 110/111: 50 bytes variable, "truncated … from the end" (10, 14, 26 of 50 bytes).
#[case::tu4_110_111(Product::Tu4Eip, 110, 111, 56, 52, 110)]
#[case::cu4_110_111_10_bytes(Product::Cu4Eip, 110, 111, 16, 12, 110)]
// BU 0620 §2.3.4.1: SK 550P 100/101, 96 bytes variable, header always.
#[case::sk550p_100_101(Product::Sk550p, 100, 101, 102, 98, 100)]
#[case::sk550p_truncated(Product::Sk550p, 100, 101, 18, 14, 100)]
fn forward_open_accepts_the_products_assemblies(
    #[case] product: Product,
    #[case] o_t: u16,
    #[case] t_o: u16,
    #[case] o_t_size: u16,
    #[case] t_o_size: u16,
    #[case] active: i16,
) {
    let mut b = Bench::new(product);
    let fo = io_open(1, o_t, t_o, o_t_size, t_o_size);
    let reply = b.open_ok(&fo);
    assert_eq!(
        reply.t_o_id, fo.t_o_id,
        "point-to-point T→O id is the originator's"
    );
    assert_ne!(reply.o_t_id, 0);
    assert_eq!((reply.o_t_api, reply.t_o_api), (RPI_US, RPI_US));
    assert_eq!(b.a.connection_counts(), (1, 0, 0));
    assert_eq!(b.a.ns_led().pattern, led::Pattern::Green);
    // P180 / P879 "Active assembly" [-01] consumed, [-02] produced.
    let (class, number) = match product {
        Product::Sk550p => (101, 879),
        _ => (100, 180),
    };
    assert_eq!(word(&b.get(class, 0, number)), active);
    assert_eq!(word(&b.get(class, 1, number)), i16::try_from(t_o).unwrap());
    // The whole exchange of the O→T size: a frame of that size is accepted.
    let run_idle = eip::o_t_run_idle(product, o_t, 0);
    let header = run_idle.then_some(1);
    let data_len = usize::from(eip::connection_data(o_t_size, run_idle).unwrap());
    assert_eq!(
        b.io(&io(reply.o_t_id, 1, header, vec![0; data_len])),
        Ok(())
    );
}

#[test]
fn p166_modeless_drops_the_run_idle_header_of_110_only() {
    let mut b = Bench::new(Product::Tu4Eip);
    assert_eq!(b.set(100, 0, 166, &[1, 0]).status(), GS::SUCCESS);
    // 110 is now modeless: 2 + 50.
    let r = b.open(&io_open(1, 110, 111, 56, 52));
    assert_refused(
        &r,
        &[ext::INVALID_O_T_SIZE, 52],
        &io_open(1, 110, 111, 56, 52),
    );
    let reply = b.open_ok(&io_open(2, 110, 111, 52, 52));
    assert_eq!(b.io(&io(reply.o_t_id, 1, None, vec![0; 50])), Ok(()));
    assert_eq!(b.close(2).status(), GS::SUCCESS);
    // 100 keeps the header whatever P166 says.
    b.open_ok(&io_open(3, 100, 101, 18, 14));
}

#[rstest]
#[case::o_t_size_of_fixed_100(Product::Tu3Eip, io_open(1, 100, 101, 16, 14), vec![ext::INVALID_O_T_SIZE, 18])]
#[case::t_o_size_of_fixed_101(Product::Tu3Eip, io_open(1, 100, 101, 18, 12), vec![ext::INVALID_T_O_SIZE, 14])]
#[case::o_t_odd_of_variable_110(Product::Tu4Eip, io_open(1, 110, 111, 17, 52), vec![ext::INVALID_O_T_SIZE, 56])]
#[case::o_t_beyond_110(Product::Cu4Eip, io_open(1, 110, 111, 58, 52), vec![ext::INVALID_O_T_SIZE, 56])]
#[case::t_o_beyond_sk550p(Product::Sk550p, io_open(1, 100, 101, 102, 100), vec![ext::INVALID_T_O_SIZE, 98])]
#[case::t_o_without_data(Product::Sk550p, io_open(1, 100, 101, 102, 2), vec![ext::INVALID_T_O_SIZE, 98])]
#[case::rpi_below_1ms(Product::Tu3Eip, ForwardOpen { o_t_rpi: 500, ..tu3_owner(1) }, vec![ext::RPI_NOT_SUPPORTED])]
#[case::rpi_above_10s(Product::Tu3Eip, ForwardOpen { t_o_rpi: 10_000_001, ..tu3_owner(1) }, vec![ext::RPI_NOT_SUPPORTED])]
#[case::input_as_consumer(Product::Tu3Eip, io_open(1, 101, 101, 18, 14), vec![ext::INVALID_CONSUMING_PATH])]
#[case::output_as_producer(Product::Tu3Eip, io_open(1, 100, 100, 18, 14), vec![ext::INVALID_PRODUCING_PATH])]
#[case::tu4_has_no_102(Product::Tu4Eip, io_open(1, 102, 103, 102, 98), vec![ext::INVALID_PRODUCING_PATH])]
#[case::listen_only_without_owner(Product::Tu3Eip, io_open(1, 255, 101, 0, 14), vec![ext::NON_LISTEN_ONLY_NOT_OPENED])]
#[case::multiplier_8(Product::Tu3Eip, ForwardOpen { timeout_multiplier: 8, ..tu3_owner(1) }, vec![ext::TIMEOUT_MULTIPLIER_NOT_ACCEPTABLE])]
#[case::class_0(Product::Tu3Eip, ForwardOpen { transport: Transport(0x00), ..tu3_owner(1) }, vec![ext::TRANSPORT_CLASS_NOT_SUPPORTED])]
fn forward_open_refusals(
    #[case] product: Product,
    #[case] fo: ForwardOpen,
    #[case] extended: Vec<u16>,
) {
    let mut b = Bench::new(product);
    assert_refused(&b.open(&fo), &extended, &fo);
    assert_eq!(b.a.connection_counts(), (0, 0, 0));
    assert_eq!(
        b.a.ns_led().pattern,
        led::Pattern::FlashingGreen { tenths_hz: 10 }
    );
}

#[test]
fn a_second_owner_is_an_ownership_conflict_and_a_repeat_is_a_duplicate() {
    let mut b = Bench::new(Product::Tu3Eip);
    b.open_ok(&tu3_owner(1));
    assert_refused(
        &b.open(&tu3_owner(1)),
        &[ext::CONNECTION_IN_USE],
        &tu3_owner(1),
    );
    assert_refused(
        &b.open(&tu3_owner(2)),
        &[ext::OWNERSHIP_CONFLICT],
        &tu3_owner(2),
    );
    // A different assembly pair of the same product is still the one exclusive owner.
    let big = io_open(3, 102, 103, 102, 98);
    assert_refused(&b.open(&big), &[ext::OWNERSHIP_CONFLICT], &big);
    assert_eq!(b.a.connection_counts(), (1, 0, 0));
}

#[test]
fn listen_only_connections_follow_their_owner() {
    let mut b = Bench::new(Product::Tu3Eip);
    b.open_ok(&tu3_owner(1));
    // BU 2100 §3.1 "1 Exclusive Owner, 2 Listen Only"; O→T size 0 or 2 (heartbeat).
    b.open_ok(&io_open(2, 255, 101, 0, 14));
    b.open_ok(&io_open(3, 255, 101, 2, 14));
    assert_eq!(b.a.connection_counts(), (1, 2, 0));
    let third = io_open(4, 255, 101, 0, 14);
    assert_refused(&b.open(&third), &[ext::TARGET_OUT_OF_CONNECTIONS], &third);
    let sized = io_open(5, 255, 101, 18, 14);
    assert_refused(&b.open(&sized), &[ext::INVALID_O_T_SIZE, 2], &sized);
    // Closing the owner ends the listeners.
    let r = b.close(1);
    assert_eq!(r.status(), GS::SUCCESS);
    assert_eq!(r.data, failure_data(tu3_owner(1).key()));
    assert_eq!(b.a.connection_counts(), (0, 0, 0));
}

#[test]
fn forward_close_of_an_unknown_connection_is_0107h() {
    let mut b = Bench::new(Product::Tu3Eip);
    let r = b.close(9);
    assert_eq!(r.status(), GS::CONNECTION_FAILURE);
    assert_eq!(r.extended, [ext::CONNECTION_NOT_FOUND]);
    assert_eq!(r.data, failure_data((9, VENDOR, ORIGINATOR_SERIAL)));
    // Closing twice: the second finds nothing.
    b.open_ok(&tu3_owner(1));
    assert_eq!(b.close(1).status(), GS::SUCCESS);
    assert_eq!(b.close(1).extended, [ext::CONNECTION_NOT_FOUND]);
    assert_eq!(word(&b.get(100, 0, 180)), 0, "P180 cleared by the close");
}

#[test]
fn a_class_3_connection_carries_explicit_messages_until_the_client_goes() {
    let mut b = Bench::new(Product::Tu3Eip);
    let reply = b.open_ok(&explicit_open(1));
    b.open_ok(&tu3_owner(2));
    assert_eq!(b.a.connection_counts(), (1, 0, 1));

    let get = MrRequest {
        service: Service::GET_ATTRIBUTE_SINGLE.0,
        path: EPath::attribute(class::IDENTITY, 1, 3),
        data: Vec::new(),
    };
    let mut payload = 7u16.to_le_bytes().to_vec(); // connection sequence count
    payload.extend(get.emit());
    let data = SendData {
        interface: 0,
        timeout: 0,
        cpf: Cpf::new(vec![
            Item::ConnectedAddress(reply.o_t_id),
            Item::ConnectedData(payload),
        ]),
    };
    let r = b.tcp(Command::SEND_UNIT_DATA, data.emit().unwrap());
    assert_eq!(EncapStatus(r.status), EncapStatus::SUCCESS);
    let sd = SendData::parse(&r.data).unwrap();
    let [Item::ConnectedAddress(id), Item::ConnectedData(out)] = &sd.cpf.items[..] else {
        panic!("items {:?}", sd.cpf.items)
    };
    assert_eq!(*id, reply.t_o_id);
    assert_eq!(out[..2], [7, 0], "the sequence count echoed");
    let resp = MrResponse::parse(&out[2..]).unwrap();
    let code = eip::identity(Product::Tu3Eip).unwrap().product_code;
    assert_eq!(
        resp,
        MrResponse::ok(get.service, code.to_le_bytes().to_vec())
    );

    // The TCP connection goes: its session and class-3 connection end, the I/O stays.
    b.a.client_closed(CLIENT);
    assert_eq!(b.a.session_count(), 0);
    assert_eq!(b.a.connection_counts(), (1, 0, 0));
    let r = b.tcp(Command::SEND_UNIT_DATA, data.emit().unwrap());
    assert_eq!(EncapStatus(r.status), EncapStatus::INVALID_SESSION);
}

#[test]
fn a_lowered_session_limit_refuses_the_next_with_insufficient_memory() {
    let mut a = adapter(Product::Tu3Eip).with_max_sessions(2);
    assert_eq!(register(&mut a, 1).status, 0);
    assert_eq!(register(&mut a, 2).status, 0);
    let r = register(&mut a, 3);
    assert_eq!(EncapStatus(r.status), EncapStatus::INSUFFICIENT_MEMORY);
    assert_eq!(r.session, 0, "no handle with the refusal");
    a.client_closed(1);
    assert_eq!(register(&mut a, 3).status, 0, "room again once one went");
}

#[test]
fn a_client_without_room_is_told_insufficient_memory() {
    let msg = encap(Command::REGISTER_SESSION, 0, RegisterSession::V1.emit());
    let r = EncapRepr::parse(&no_room_reply(&msg).unwrap()).unwrap();
    assert_eq!(Command(r.command), Command::REGISTER_SESSION);
    assert_eq!(EncapStatus(r.status), EncapStatus::INSUFFICIENT_MEMORY);
    assert_eq!((r.session, r.context), (0, CONTEXT));
    assert_eq!(r.data, RegisterSession::V1.emit());
    let r = no_room_reply(&encap(Command::LIST_IDENTITY, 0, Vec::new())).unwrap();
    let r = EncapRepr::parse(&r).unwrap();
    assert_eq!(EncapStatus(r.status), EncapStatus::INSUFFICIENT_MEMORY);
    assert!(r.data.is_empty());
    assert_eq!(no_room_reply(&encap(Command::NOP, 0, Vec::new())), None);
    assert_eq!(no_room_reply(&msg[..10]), None);
}

#[test]
fn class_3_connections_beyond_the_limit_are_refused_with_0113h() {
    let mut b = Bench::new(Product::Tu3Eip);
    for serial in 1..=super::connections::MAX_EXPLICIT as u16 {
        b.open_ok(&explicit_open(serial));
    }
    let one_more = explicit_open(100);
    // CIP general status 01h, extended 0113h "connection manager cannot support any more
    // connections".
    assert_refused(&b.open(&one_more), &[ext::OUT_OF_CONNECTIONS], &one_more);
    assert_eq!(ext::OUT_OF_CONNECTIONS, 0x0113);
    assert_eq!(b.close(1).status(), GS::SUCCESS);
    b.open_ok(&one_more);
}

// --- TCP/IP Interface attribute 13: Encapsulation Inactivity Timeout --------------------------

fn inactivity_timeout(b: &mut Bench) -> u16 {
    let r = b.get(class::TCP_IP, 1, 13);
    assert_eq!(r.status(), GS::SUCCESS, "{r:?}");
    u16::from_le_bytes(r.data[..].try_into().expect("a UINT"))
}

#[test]
fn the_inactivity_timeout_is_120_s_and_settable_from_0_to_3600() {
    let mut b = Bench::new(Product::Tu3Eip);
    assert_eq!(inactivity_timeout(&mut b), DEFAULT_INACTIVITY_TIMEOUT);
    assert_eq!(DEFAULT_INACTIVITY_TIMEOUT, 120);
    assert_eq!(b.a.inactivity_timeout(), Some(Duration::from_secs(120)));
    for value in [1u16, 3600] {
        let r = b.set(class::TCP_IP, 1, 13, &value.to_le_bytes());
        assert_eq!(
            r,
            MrResponse::ok(Service::SET_ATTRIBUTE_SINGLE.0, Vec::new())
        );
        assert_eq!(inactivity_timeout(&mut b), value);
        assert_eq!(
            b.a.inactivity_timeout(),
            Some(Duration::from_secs(u64::from(value)))
        );
    }
    assert_eq!(b.set(class::TCP_IP, 1, 13, &[0, 0]).status(), GS::SUCCESS);
    assert_eq!(b.a.inactivity_timeout(), None, "0 disables it");
    assert_eq!(inactivity_timeout(&mut b), 0);
}

#[rstest]
#[case::above_3600(&[0x11, 0x0E], GS::INVALID_ATTRIBUTE_VALUE)]
#[case::maximum_uint(&[0xFF, 0xFF], GS::INVALID_ATTRIBUTE_VALUE)]
#[case::one_byte(&[1], GS::NOT_ENOUGH_DATA)]
#[case::empty(&[], GS::NOT_ENOUGH_DATA)]
#[case::udint(&[1, 0, 0, 0], GS::TOO_MUCH_DATA)]
fn inactivity_timeout_refusals_leave_it_unchanged(#[case] data: &[u8], #[case] status: GS) {
    let mut b = Bench::new(Product::Tu3Eip);
    assert_eq!(b.set(class::TCP_IP, 1, 13, data).status(), status);
    assert_eq!(inactivity_timeout(&mut b), DEFAULT_INACTIVITY_TIMEOUT);
}

#[test]
fn the_inactivity_timeout_survives_an_identity_reset() {
    let mut b = Bench::new(Product::Tu3Eip);
    b.set(class::TCP_IP, 1, 13, &[5, 0]);
    let r = b.call(
        Service::RESET,
        EPath::object(class::IDENTITY, 1),
        Vec::new(),
    );
    assert_eq!(r.status(), GS::SUCCESS);
    assert_eq!(inactivity_timeout(&mut b), 5);
}

#[test]
fn a_client_holds_connections_while_its_class_1_or_class_3_connections_are_open() {
    let mut b = Bench::new(Product::Tu3Eip);
    assert!(!b.a.holds_connections(CLIENT));
    b.open_ok(&explicit_open(1));
    assert!(b.a.holds_connections(CLIENT));
    assert!(
        !b.a.holds_connections(CLIENT + 1),
        "only the client that opened it"
    );
    assert_eq!(b.close(1).status(), GS::SUCCESS);
    assert!(!b.a.holds_connections(CLIENT));
    b.open_ok(&tu3_owner(2));
    assert!(b.a.holds_connections(CLIENT));
    assert_eq!(b.close(2).status(), GS::SUCCESS);
    assert!(!b.a.holds_connections(CLIENT));
}

#[test]
fn client_closed_leaves_other_clients_alone() {
    let mut a = adapter(Product::Tu3Eip);
    register(&mut a, 1);
    register(&mut a, 2);
    a.client_closed(1);
    assert_eq!(a.session_count(), 1);
    a.client_closed(1);
    assert_eq!(a.session_count(), 1);
}

// --- Class-1 I/O -------------------------------------------------------------------------------

#[test]
fn o_t_data_drives_the_inverter_once_per_sequence_count_and_idle_clears_it() {
    let mut b = Bench::new(Product::Tu3Eip);
    let id = b.open_ok(&tu3_owner(1)).o_t_id;
    // P740 [-01] "PZD bus in" shows the control word as received.
    let p740 = |b: &mut Bench| word(&b.inverter_param(1, 740, None, element(1))) as u16;

    b.now = ms(1);
    assert_eq!(b.io(&io(id, 1, Some(1), outputs(CONTROL))), Ok(()));
    assert_eq!(p740(&mut b), CONTROL);
    // The same sequence count again is a repeat: not applied.
    b.now = ms(2);
    assert_eq!(b.io(&io(id, 1, Some(1), outputs(CONTROL | 1))), Ok(()));
    assert_eq!(p740(&mut b), CONTROL);
    // Idle (run/idle bit 0 clear): an invalid control word reaches the inverter, at the next
    // system-bus cycle (5 ms after the last: `crate::system_bus::ProcessData`).
    b.now = ms(10);
    assert_eq!(b.io(&io(id, 2, Some(0), outputs(CONTROL | 1))), Ok(()));
    assert_eq!(p740(&mut b), 0);
    b.now = ms(20);
    assert_eq!(b.io(&io(id, 3, Some(1), outputs(CONTROL | 1))), Ok(()));
    assert_eq!(p740(&mut b), CONTROL | 1);
    // The assembly shows the data consumed last.
    assert_eq!(b.get(class::ASSEMBLY, 100, 3).data, outputs(CONTROL | 1));
}

#[test]
fn io_frames_that_do_not_fit_are_dropped_with_a_reason() {
    let mut b = Bench::new(Product::Tu3Eip);
    let id = b.open_ok(&tu3_owner(1)).o_t_id;
    assert_eq!(
        b.io(&io(id, 1, Some(1), vec![0; 10])),
        Err(IoError::WrongLength { want: 12, got: 10 })
    );
    assert_eq!(
        b.io(&io(id ^ 1, 1, Some(1), outputs(CONTROL))),
        Err(IoError::UnknownConnection(id ^ 1))
    );
    let no_header = io(id, 1, None, vec![]);
    assert!(matches!(
        b.io(&no_header),
        Err(IoError::Malformed(Error::Truncated { .. }))
    ));
    assert!(matches!(b.io(&[1, 0]), Err(IoError::Malformed(_))));
    assert_eq!(b.a.dropped(), 4);
    assert_eq!(word(&b.inverter_param(1, 740, None, element(1))), 0);
}

#[test]
fn t_o_frames_are_produced_at_the_rpi() {
    let mut b = Bench::new(Product::Tu3Eip);
    let fo = tu3_owner(1);
    let reply = b.open_ok(&fo);
    assert_eq!(
        b.a.next_due(),
        Some(Duration::ZERO),
        "the first frame at once"
    );

    let frames = b.a.poll(Duration::ZERO);
    let [(to, bytes)] = &frames[..] else {
        panic!("one frame, got {frames:?}")
    };
    assert_eq!(*to, SocketAddr::new(PEER.ip(), IO_PORT));
    let f = IoFrame::parse(bytes, false).unwrap();
    assert_eq!((f.connection, f.sequence, f.count), (reply.t_o_id, 1, 1));
    assert_eq!(f.data.len(), 12);

    assert_eq!(b.a.next_due(), Some(ms(10)));
    assert!(b.a.poll(ms(9)).is_empty());
    let frames = b.a.poll(ms(10));
    assert_eq!(frames.len(), 1);
    assert_eq!(IoFrame::parse(&frames[0].1, false).unwrap().count, 2);
    // A late poll sends one frame, not a burst for the missed intervals.
    b.now = ms(35);
    b.io(&io(reply.o_t_id, 1, Some(1), outputs(CONTROL)))
        .unwrap();
    let frames = b.a.poll(ms(35));
    assert_eq!(frames.len(), 1);
    let f = IoFrame::parse(&frames[0].1, false).unwrap();
    assert_eq!(f.count, 3);
    assert_eq!(b.a.next_due(), Some(ms(40)));
    // The data is the inverter's status word and actual values (P741 mirrors them).
    let status = word(&b.inverter_param(1, 741, None, element(1))) as u16;
    assert_eq!(f.data[..2], status.to_le_bytes());
}

#[test]
fn a_truncated_t_o_connection_sends_the_front_of_the_assembly() {
    let mut b = Bench::new(Product::Tu4Eip);
    let reply = b.open_ok(&io_open(1, 110, 111, 16, 12));
    let frames = b.a.poll(Duration::ZERO);
    let f = IoFrame::parse(&frames[0].1, false).unwrap();
    assert_eq!(f.connection, reply.t_o_id);
    // 111: the interface word (bit 15 "inputs valid") first, then FI 1's status word …
    assert_eq!(f.data.len(), 10);
    assert_eq!(f.data[..2], 0x8000u16.to_le_bytes());
}

#[rstest]
#[case::multiplier_0(0, 40)]
#[case::multiplier_1(1, 80)]
#[case::multiplier_3(3, 320)]
fn an_owner_without_o_t_data_times_out_after_4_rpi_shifted_by_the_multiplier(
    #[case] multiplier: u8,
    #[case] timeout_ms: u64,
) {
    let mut b = Bench::new(Product::Tu3Eip);
    b.open_ok(&ForwardOpen {
        timeout_multiplier: multiplier,
        ..tu3_owner(1)
    });
    b.a.poll(ms(timeout_ms));
    assert_eq!(
        b.a.connection_counts(),
        (1, 0, 0),
        "at the limit still open"
    );
    b.a.poll(ms(timeout_ms + 1));
    assert_eq!(b.a.connection_counts(), (0, 0, 0));
    assert!(
        b.a.poll(ms(timeout_ms + 100)).is_empty(),
        "no more T→O frames"
    );
    assert_eq!(b.a.next_due(), None);
    assert_eq!(
        b.a.ns_led().pattern,
        led::Pattern::FlashingRed { tenths_hz: 10 }
    );
}

#[test]
fn o_t_data_feeds_the_watchdog() {
    let mut b = Bench::new(Product::Tu3Eip);
    let id = b.open_ok(&tu3_owner(1)).o_t_id;
    for (count, t) in (1..).zip([30, 60, 90]) {
        b.now = ms(t);
        b.io(&io(id, count, Some(1), outputs(CONTROL))).unwrap();
        b.a.poll(b.now);
    }
    b.a.poll(ms(130));
    assert_eq!(b.a.connection_counts(), (1, 0, 0));
    assert_eq!(b.a.next_due(), Some(ms(130)), "the watchdog's deadline");
    b.a.poll(ms(131));
    assert_eq!(b.a.connection_counts(), (0, 0, 0));
}

// BU 2100 §7.1.1 P151 = -1: all monitoring off; SK 550P: P513 [-04] (factory off).
#[rstest]
#[case::tu3_has_no_p151(Product::Tu3Eip, None, 8)]
#[case::tu4_p151_factory(Product::Tu4Eip, None, 4)]
#[case::tu4_p151_off(Product::Tu4Eip, Some((100, 0, 151, -1)), 0)]
#[case::cu4_p151_off(Product::Cu4Eip, Some((100, 0, 151, -1)), 0)]
#[case::sk550p_p513_factory_off(Product::Sk550p, None, 0)]
// P513 [-04] = -0.1 "No error": the FI "ignores all communication errors on both the field
// bus and the system bus level" (BU 2100 §7.1.1 "Parameter P513"; BU 0620 §4.5).
#[case::sk550p_p513_no_error(Product::Sk550p, Some((101, 3, 513, -1)), 0)]
// P513 [-04] = 1.0 s on FI 1 only: FI 2..8 keep monitoring off.
#[case::sk550p_p513_on_fi1(Product::Sk550p, Some((101, 3, 513, 10)), 1)]
fn an_owner_timeout_raises_e10_2_unless_monitoring_is_off(
    #[case] product: Product,
    #[case] setting: Option<(u16, u32, u16, i16)>,
    #[case] raised: u8,
) {
    let mut b = Bench::new(product);
    if let Some((class, instance, number, value)) = setting {
        let r = b.set(class, instance, number, &value.to_le_bytes());
        assert_eq!(r.status(), GS::SUCCESS);
    }
    let (o_t, t_o, o_t_size, t_o_size) = match product {
        Product::Sk550p => (100, 101, 102, 98),
        _ => (100, 101, 18, 14),
    };
    b.open_ok(&io_open(1, o_t, t_o, o_t_size, t_o_size));
    b.now = ms(41);
    b.a.poll(b.now);
    assert_eq!(b.a.connection_counts(), (0, 0, 0));
    let n = b.a.device_mut().config().inverters;
    // P700 [-01] shows E10.2 as 102.
    let want: Vec<i16> = (1..=n)
        .map(|fi| if fi <= raised { 102 } else { 0 })
        .collect();
    assert_eq!(b.present_errors(), want);
    // A new owner clears the NS LED's time-out indication.
    b.open_ok(&io_open(2, o_t, t_o, o_t_size, t_o_size));
    assert_eq!(b.a.ns_led().pattern, led::Pattern::Green);
}

#[test]
fn a_listen_only_connection_ends_with_its_timed_out_owner() {
    let mut b = Bench::new(Product::Tu3Eip);
    b.open_ok(&tu3_owner(1));
    let lo = b.open_ok(&io_open(2, 255, 101, 0, 14));
    // The listener's heartbeat keeps it alive, the owner's silence does not.
    b.now = ms(30);
    b.io(&io(lo.o_t_id, 1, None, vec![])).unwrap();
    b.a.poll(ms(41));
    assert_eq!(b.a.connection_counts(), (0, 0, 0));
}

// --- Identity ----------------------------------------------------------------------------------

#[test]
fn identity_reset_ends_connections_and_reads_in_the_addressing_parameters() {
    let mut b = Bench::new(Product::Tu3Eip);
    let present = |b: &mut Bench| -> Vec<i16> {
        (1..=4)
            .map(|e| word(&b.module_param(185, element(e))))
            .collect()
    };
    // P165 factory 1 (BOOTP): P185 shows the address the adapter is reached at.
    assert_eq!(present(&mut b), [10, 0, 0, 5]);
    b.open_ok(&tu3_owner(1));
    b.open_ok(&explicit_open(2));
    // P165 = 0 "fixed" takes effect only at restart (BU 2100 §7.1.2).
    assert_eq!(b.set(100, 0, 165, &[0, 0]).status(), GS::SUCCESS);
    assert_eq!(present(&mut b), [10, 0, 0, 5]);

    let reset = |b: &mut Bench, data: Vec<u8>| {
        b.call(Service::RESET, EPath::object(class::IDENTITY, 1), data)
    };
    assert_eq!(reset(&mut b, vec![1]).status(), GS::INVALID_PARAMETER);
    assert_eq!(reset(&mut b, vec![0, 0]).status(), GS::TOO_MUCH_DATA);
    assert_eq!(
        b.a.connection_counts(),
        (1, 0, 1),
        "refused resets change nothing"
    );

    let r = reset(&mut b, Vec::new());
    assert_eq!(r, MrResponse::ok(Service::RESET.0, Vec::new()));
    assert_eq!(b.a.connection_counts(), (0, 0, 0));
    assert_eq!(present(&mut b), [192, 168, 1, 100], "P160 factory setting");
    assert_eq!(word(&b.module_param(180, element(1))), 0);
    // The session survives: the reply came over it and the next request is served.
    assert_eq!(b.a.session_count(), 1);
    assert_eq!(b.close(1).extended, [ext::CONNECTION_NOT_FOUND]);
}

#[test]
fn identity_reset_forgets_a_connection_time_out() {
    let mut b = Bench::new(Product::Tu3Eip);
    b.open_ok(&tu3_owner(1));
    b.a.poll(ms(500));
    assert_eq!(
        b.a.ns_led().pattern,
        led::Pattern::FlashingRed { tenths_hz: 10 }
    );
    let r = b.call(
        Service::RESET,
        EPath::object(class::IDENTITY, 1),
        Vec::new(),
    );
    assert_eq!(r.status(), GS::SUCCESS);
    // As after a power cycle: an IP address, no CIP connection (BU 0620 §5.5.2.2).
    assert_eq!(
        b.a.ns_led().pattern,
        led::Pattern::FlashingGreen { tenths_hz: 10 }
    );
}

#[test]
fn identity_attributes_are_read_only() {
    let mut b = Bench::new(Product::Cu4Eip);
    let info = eip::identity(Product::Cu4Eip).unwrap();
    assert_eq!(
        b.get(class::IDENTITY, 1, 3).data,
        info.product_code.to_le_bytes()
    );
    let all = b.call(
        Service::GET_ATTRIBUTES_ALL,
        EPath::object(class::IDENTITY, 1),
        vec![],
    );
    assert_eq!(all.data, b.a.identity().all());
    assert_eq!(
        b.set(class::IDENTITY, 1, 1, &[0, 0]).status(),
        GS::ATTRIBUTE_NOT_SETTABLE
    );
    assert_eq!(
        b.get(class::IDENTITY, 1, 99).status(),
        GS::ATTRIBUTE_NOT_SUPPORTED
    );
    assert_eq!(
        b.get(class::IDENTITY, 2, 1).status(),
        GS::PATH_DESTINATION_UNKNOWN
    );
}

#[test]
fn dlr_object_is_a_ring_node() {
    // BU 0620 §2.3.1 "Supported functions UCMM, DLR": class 47h, revision 3, instance 1 with
    // the attributes of a non-supervisor ring node.
    let mut b = Bench::new(Product::Sk550p);
    let get = |instance: u32, attribute: u16| MrRequest {
        service: Service::GET_ATTRIBUTE_SINGLE.0,
        path: EPath::attribute(class::DLR, instance, attribute),
        data: Vec::new(),
    };
    let r = b.request(&get(0, 1));
    assert_eq!((r.status(), r.data.clone()), (GS::SUCCESS, vec![3, 0]));
    assert_eq!(b.request(&get(1, 1)).data, [0], "linear topology");
    assert_eq!(b.request(&get(1, 2)).data, [0], "normal");
    assert_eq!(b.request(&get(1, 10)).data, [0; 10], "no active supervisor");
    assert_eq!(b.request(&get(1, 12)).data, [0x82, 0, 0, 0]);
    // A supervisor's attribute is not there; the object cannot be written.
    assert_eq!(b.request(&get(1, 3)).status(), GS::ATTRIBUTE_NOT_SUPPORTED);
    let set = MrRequest {
        service: Service::SET_ATTRIBUTE_SINGLE.0,
        path: EPath::attribute(class::DLR, 1, 1),
        data: vec![1],
    };
    assert_eq!(b.request(&set).status(), GS::SERVICE_NOT_SUPPORTED);
}

#[test]
fn p873_p874_show_the_words_of_the_assemblies() {
    // BU 0620 §4.3: P873 "Process data bus In", P874 "Process data bus Out", 6 words per FI.
    let mut b = Bench::new(Product::Sk550p);
    let fo = b.open_ok(&io_open(1, 100, 101, 102, 98));
    let mut data = outputs(0x047E);
    data.resize(96, 0);
    // FI 2: control word 047Eh, setpoint 1 = 1000 (words 7, 8).
    data[12..14].copy_from_slice(&0x047Eu16.to_le_bytes());
    data[14..16].copy_from_slice(&1000u16.to_le_bytes());
    for k in 1..=5u16 {
        b.now = ms(u64::from(k) * 5);
        b.io(&io(fo.o_t_id, k, Some(1), data.clone())).unwrap();
    }
    let iface = |b: &mut Bench, number: u16, e: u32| word(&b.get(101, e - 1, number));
    assert_eq!(iface(&mut b, 873, 1) as u16, 0x047E);
    assert_eq!(iface(&mut b, 873, 7) as u16, 0x047E);
    assert_eq!(iface(&mut b, 873, 8), 1000);
    let status = iface(&mut b, 874, 1) as u16;
    assert_eq!(
        status & 0x00FF,
        0x31,
        "ready for operation after 047Eh: {status:04X}"
    );
    assert_eq!(iface(&mut b, 874, 7) as u16 & 0x00FF, 0x31);
}

/// A parameter of FI 3 behind an SK TU4-EIP, written and read over CIP, is an SDO transfer
/// with FI 3's node on the system bus: the node's server answers it, and a refusal of the
/// node comes back as CIP's own status.
#[test]
fn inverter_parameters_go_through_the_nodes_sdo_server() {
    let mut b = Bench::new(Product::Tu4Eip);
    let fi3 = Inverter::new(3).unwrap();
    let served = |b: &Bench| b.a.device.node_server(fi3).map(|s| s.counts());
    assert!(b.a.device.tap_system_bus().is_empty());
    let c = addr::cip(Product::Tu4Eip, param(3, 102, set_of(1), None)).unwrap();
    let ok = b.set(
        c.class,
        u32::from(c.instance),
        c.attribute,
        &250i16.to_le_bytes(),
    );
    assert_eq!(ok.status(), GS::SUCCESS);
    assert_eq!(served(&b), Some((1, 0)));
    assert_eq!(word(&b.inverter_param(3, 102, set_of(1), None)), 250);
    assert_eq!(served(&b), Some((2, 0)));
    // P102 above its 32000: the node aborts 06090031h, CIP answers "invalid attribute value".
    let refused = b.set(
        c.class,
        u32::from(c.instance),
        c.attribute,
        &32001i16.to_le_bytes(),
    );
    assert_eq!(refused.status(), GS::INVALID_ATTRIBUTE_VALUE);
    assert_eq!(served(&b), Some((3, 1)));
    let frames: Vec<String> =
        b.a.device
            .tap_system_bus()
            .iter()
            .map(|(_, f)| format!("{:03X} {:02X?}", f.id(), f.data()))
            .collect();
    assert_eq!(
        frames[4..],
        [
            "624 [2B, 66, 20, 01, 01, 7D, 00, 00]",
            "5A4 [80, 66, 20, 01, 31, 00, 09, 06]",
        ]
    );
    // The module's own parameters stay the module's: no node answers them.
    assert_eq!(b.module_param(150, None).status(), GS::SUCCESS);
    assert_eq!(served(&b), Some((3, 1)));
}
