//! The IO device driven by hand-made frames and datagrams, as a controller sends them.

use std::net::{Ipv4Addr, SocketAddr};
use std::time::Duration;

use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_PROFINET};
use proto::nord::pnio::{self as def, ModuleKind};
use proto::nord::ppo::PpoType;
use proto::nord::{Inverter, Product};
use proto::pnio::alarm::{AlarmAck, AlarmRepr, AlarmType, RtaBody, RtaPduType};
use proto::pnio::block::{
    iocr_properties, AlarmCrBlockReq, AlarmCrType, ArBlockReq, ArType, Block, IocrBlockReq,
    IocrType, IodControl, IodReadReq, IodWriteReq, RecordAddress,
};
use proto::pnio::dcp::{BlockValue, DcpOption, DcpRepr};
use proto::pnio::plan::Plan;
use proto::pnio::rpc::{NdrRequest, NdrResponse, Opnum, PacketType, RpcRepr, Uuid};
use proto::pnio::rt::{DataStatus, Iox, RtRepr};
use proto::pnio::{FrameId, PnioStatus, MULTICAST_DCP_IDENTIFY};

use super::{IoConfig, IoDevice, Out};
use crate::device::{Device, DeviceConfig};
use crate::link::Unit;

const PLC_MAC: MacAddr = MacAddr([0x02, 0, 0, 0, 0, 0xC1]);
const AR_UUID: Uuid = Uuid([0xA1; 16]);
const PLC_REF: u16 = 0x0003;
const DEVICE_MAC: MacAddr = MacAddr([0x02, 0, 0, 0, 0, 0xD1]);

fn plc() -> SocketAddr {
    SocketAddr::from((Ipv4Addr::new(192, 168, 20, 1), 34964))
}

fn io(product: Product, name: &str) -> IoDevice {
    let config = IoConfig {
        name: name.into(),
        mac: DEVICE_MAC,
        ..IoConfig::new(product)
    };
    IoDevice::new(Device::new(DeviceConfig::new(product)), config).unwrap()
}

fn eth(dst: MacAddr, payload: &[u8]) -> Vec<u8> {
    EthernetRepr {
        dst,
        src: PLC_MAC,
        ethertype: ETHERTYPE_PROFINET,
    }
    .emit(payload)
}

/// The PROFINET payloads of the frames among `out`.
fn frames(out: &[Out]) -> Vec<Vec<u8>> {
    out.iter()
        .filter_map(|o| match o {
            Out::Frame(f) => Some(
                EthernetFrame::new_checked(f)
                    .unwrap()
                    .inner_payload()
                    .to_vec(),
            ),
            Out::Datagram { .. } => None,
        })
        .collect()
}

fn datagrams(out: &[Out]) -> Vec<RpcRepr> {
    out.iter()
        .filter_map(|o| match o {
            Out::Datagram { bytes, .. } => Some(RpcRepr::parse_bytes(bytes).unwrap()),
            Out::Frame(_) => None,
        })
        .collect()
}

fn call(
    io: &mut IoDevice,
    opnum: Opnum,
    blocks: &[Block],
    now: Duration,
) -> (PnioStatus, Vec<Block>, Vec<Out>) {
    let body = NdrRequest::new(4096, Block::emit_all(blocks).unwrap()).unwrap();
    let req = RpcRepr::request(
        def_object(),
        Uuid::PNIO_DEVICE_INTERFACE,
        Uuid([opnum.0 as u8; 16]),
        0,
        opnum,
        body.emit(proto::pnio::rpc::Drep::LITTLE_ENDIAN),
    );
    let out = io.datagram(plc(), &req.emit().unwrap(), now);
    let replies = datagrams(&out);
    let reply = replies
        .iter()
        .find(|r| r.packet_type == PacketType::RESPONSE && r.opnum == opnum)
        .expect("a response");
    let ndr = NdrResponse::parse(&reply.body, reply.drep).unwrap();
    (
        ndr.status,
        Block::parse_all(&ndr.data).unwrap_or_default(),
        out,
    )
}

fn def_object() -> Uuid {
    Uuid::pnio_object(0, def::device_id(Product::Sk550p).unwrap(), def::VENDOR_ID)
}

/// The Connect of the DAP and `modules` (slot, kind), 1 ms cycle, watchdog 3.
fn connect_blocks(product: Product, modules: &[(u16, ModuleKind)]) -> (Vec<Block>, Plan) {
    let mut subs = def::expected_dap();
    for (slot, kind) in modules {
        subs.push(def::expected_module(
            *slot,
            &def::module(product, *kind).unwrap(),
        ));
    }
    let plan = Plan::new(&subs).unwrap();
    let iocr = |iocr_type, layout: &proto::pnio::plan::CrLayout, frame_id| {
        Block::IocrReq(IocrBlockReq {
            iocr_type,
            reference: iocr_type.0,
            lt: ETHERTYPE_PROFINET,
            properties: iocr_properties::RT_CLASS_2,
            data_length: layout.data_length,
            frame_id,
            send_clock_factor: 32,
            reduction_ratio: 1,
            phase: 1,
            frame_send_offset: 0xFFFF_FFFF,
            watchdog_factor: 3,
            data_hold_factor: 3,
            tag_header: 0xC000,
            apis: vec![layout.api.clone()],
            ..IocrBlockReq::default()
        })
    };
    let blocks = vec![
        Block::ArReq(ArBlockReq {
            ar_type: ArType::IOC_AR_SINGLE,
            ar_uuid: AR_UUID,
            session_key: 1,
            initiator_mac: PLC_MAC,
            initiator_object: Uuid([0xC0; 16]),
            properties: 0x11,
            activity_timeout_factor: 100,
            udp_rt_port: ETHERTYPE_PROFINET,
            station_name: b"plc".to_vec(),
        }),
        iocr(IocrType::INPUT, &plan.input, 0x8000),
        iocr(IocrType::OUTPUT, &plan.output, 0x8001),
        Block::AlarmCrReq(AlarmCrBlockReq {
            alarm_cr_type: AlarmCrType::ALARM_CR,
            lt: ETHERTYPE_PROFINET,
            rta_timeout_factor: 1,
            rta_retries: 3,
            local_alarm_reference: PLC_REF,
            max_alarm_data_length: 200,
            ..AlarmCrBlockReq::default()
        }),
        Block::ExpectedSubmoduleReq(plan.expected.clone()),
    ];
    (blocks, plan)
}

/// Connect, PrmEnd, ApplicationReady confirmed: the AR runs. Returns the plan.
fn run_ar(io: &mut IoDevice, modules: &[(u16, ModuleKind)]) -> Plan {
    let product = io.product;
    let (blocks, plan) = connect_blocks(product, modules);
    let (status, _, _) = call(io, Opnum::CONNECT, &blocks, Duration::ZERO);
    assert!(status.is_ok(), "{status:?}");
    let (status, _, out) = call(
        io,
        Opnum::CONTROL,
        &[Block::Control(IodControl::prm_end(AR_UUID, 1))],
        Duration::ZERO,
    );
    assert!(status.is_ok(), "{status:?}");
    let ready = datagrams(&out)
        .into_iter()
        .find(|r| r.packet_type == PacketType::REQUEST)
        .expect("ApplicationReady");
    assert_eq!(ready.interface, Uuid::PNIO_CONTROLLER_INTERFACE);
    let ndr = NdrRequest::parse(&ready.body, ready.drep).unwrap();
    let Ok(blocks) = Block::parse_all(&ndr.data) else {
        panic!()
    };
    let Some(Block::Control(c)) = blocks.first() else {
        panic!()
    };
    let answer = NdrResponse::answering(
        &ndr,
        PnioStatus::OK,
        Block::emit_all(&[Block::Control(c.done())]).unwrap(),
    )
    .unwrap();
    let reply = ready.reply(PacketType::RESPONSE, answer.emit(ready.drep));
    io.datagram(plc(), &reply.emit().unwrap(), Duration::ZERO);
    assert!(io.in_data_exchange());
    plan
}

/// The output frame carrying `ppo` for the module in `slot`.
fn output(plan: &Plan, slot: u16, ppo: &[u8], cycle: u16) -> Vec<u8> {
    let mut c_sdu = vec![0u8; usize::from(plan.output.data_length)];
    for p in &plan.output.data {
        if p.slot == slot {
            c_sdu[p.offset..p.offset + ppo.len()].copy_from_slice(ppo);
        }
        c_sdu[p.offset + p.len] = Iox::GOOD.0;
    }
    for p in &plan.output.iocs {
        c_sdu[p.offset] = Iox::GOOD.0;
    }
    let rt = RtRepr {
        frame_id: FrameId(0x8001),
        data: c_sdu,
        cycle_counter: cycle,
        data_status: DataStatus::GOOD,
        transfer_status: 0,
    };
    eth(DEVICE_MAC, &rt.emit())
}

/// The input data of `slot` in the last input frame among `out`.
fn input_of(plan: &Plan, out: &[Out], slot: u16) -> Option<(Vec<u8>, Iox)> {
    let rt = frames(out)
        .into_iter()
        .filter_map(|f| RtRepr::parse(&f, Some(usize::from(plan.input.data_length))).ok())
        .last()?;
    let p = plan.input.data.iter().find(|p| p.slot == slot)?;
    Some((
        rt.data[p.offset..p.offset + p.len].to_vec(),
        Iox(rt.data[p.offset + p.len]),
    ))
}

#[test]
fn identify_all_answers_with_name_ip_and_ids() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let req = DcpRepr::identify_all(7, 1).emit().unwrap();
    let out = io.frame(&eth(MULTICAST_DCP_IDENTIFY, &req), Duration::ZERO);
    let answers = frames(&out);
    assert_eq!(answers.len(), 1);
    let res = DcpRepr::parse(&answers[0]).unwrap();
    assert_eq!(res.xid, 7);
    let name = res
        .find(DcpOption::NAME_OF_STATION)
        .map(|b| b.value.clone());
    assert_eq!(name, Some(BlockValue::NameOfStation("sk550p-1".into())));
    assert!(matches!(
        res.find(DcpOption::DEVICE_ID).map(|b| &b.value),
        Some(BlockValue::DeviceId { vendor_id, device_id })
            if *vendor_id == def::VENDOR_ID && Some(*device_id) == def::device_id(Product::Sk550p)
    ));
}

#[test]
fn identify_by_another_name_is_not_answered() {
    let mut io = io(Product::Tu3Pnt, "tu3");
    let req = DcpRepr::identify_name(8, 1, "other").emit().unwrap();
    assert!(frames(&io.frame(&eth(MULTICAST_DCP_IDENTIFY, &req), Duration::ZERO)).is_empty());
}

/// Connect with FI 1's PPO 3 in slot 3 and a module the SK 550P has no slot 1 for: the AR
/// comes up, the ModuleDiffBlock names slot 1; P879 [-01] shows the PPO 3 module.
#[test]
fn connect_answers_a_module_difference_and_shows_the_ppo() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let ppo3 = ModuleKind::Ppo(PpoType::TYPE_3);
    let (blocks, _) = connect_blocks(Product::Sk550p, &[(3, ppo3), (1, ppo3)]);
    let (status, res, _) = call(&mut io, Opnum::CONNECT, &blocks, Duration::ZERO);
    assert!(status.is_ok());
    let diff = res.iter().find_map(|b| match b {
        Block::ModuleDiff(d) => Some(d.clone()),
        _ => None,
    });
    let slots: Vec<u16> = diff.unwrap().apis[0]
        .modules
        .iter()
        .map(|m| m.slot)
        .collect();
    assert_eq!(slots, [1]);
    let shown = io
        .device_mut()
        .store(Unit::Interface)
        .unwrap()
        .read(
            proto::nord::ParamNumber::new(879).unwrap(),
            None,
            proto::nord::ArrayElement::new(1).ok(),
        )
        .unwrap();
    assert_eq!(
        Some(shown as u16),
        def::slot_display(Product::Sk550p, Some(ppo3))
    );
}

#[test]
fn a_second_controller_is_refused_out_of_ar_resources() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let ppo3 = ModuleKind::Ppo(PpoType::TYPE_3);
    run_ar(&mut io, &[(3, ppo3)]);
    let (mut blocks, _) = connect_blocks(Product::Sk550p, &[(3, ppo3)]);
    if let Block::ArReq(a) = &mut blocks[0] {
        a.ar_uuid = Uuid([0xB2; 16]);
    }
    let (status, _, _) = call(&mut io, Opnum::CONNECT, &blocks, Duration::ZERO);
    assert_eq!(
        status,
        PnioStatus::cm(
            proto::pnio::status::cm::CONNECT,
            proto::pnio::status::cm::CMRPC,
            proto::pnio::status::cm::CMRPC_OUT_OF_AR
        )
    );
}

/// The switching example over RT: control word 047Eh then 047Fh with setpoint 4000h bring FI
/// 1 to "operation enabled", the status word in the input frame follows; the input frames
/// come every millisecond.
#[test]
fn cyclic_data_drives_the_inverter_and_comes_back_every_millisecond() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let plan = run_ar(&mut io, &[(3, ModuleKind::Ppo(PpoType::TYPE_3))]);
    let mut status = 0;
    let mut inputs = 0;
    for ms in 1..=200u64 {
        let now = Duration::from_millis(ms);
        let control: u16 = if ms < 100 { 0x047E } else { 0x047F };
        let ppo = [control.to_be_bytes(), 0x4000u16.to_be_bytes()].concat();
        let mut out = io.frame(&output(&plan, 3, &ppo, ms as u16), now);
        out.extend(io.poll(now));
        if let Some((data, iops)) = input_of(&plan, &out, 3) {
            inputs += 1;
            assert_eq!(iops, Iox::GOOD);
            status = u16::from_be_bytes([data[0], data[1]]);
        }
    }
    assert!(inputs >= 199, "{inputs} input frames in 200 ms");
    assert_eq!(status & 0x006F, 0x0027, "status word {status:04X}h");
}

/// No output frame for WatchdogFactor cycles: the AR ends and FI 1, monitoring on (P513
/// [-04]), raises E10.2 (BU 0620 §5.3).
#[test]
fn the_watchdog_ends_the_ar_and_raises_the_documented_error() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let fi1 = Inverter::new(1).unwrap();
    let store = io.device_mut().store(Unit::Inverter(fi1)).unwrap();
    store
        .write(
            proto::nord::ParamNumber::new(513).unwrap(),
            None,
            proto::nord::ArrayElement::new(4).ok(),
            5,
            crate::store::Persist::RamOnly,
        )
        .unwrap();
    let plan = run_ar(&mut io, &[(3, ModuleKind::Ppo(PpoType::TYPE_3))]);
    io.frame(
        &output(&plan, 3, &[0x04, 0x7E, 0, 0], 1),
        Duration::from_millis(1),
    );
    for ms in 2..20 {
        io.poll(Duration::from_millis(ms));
    }
    assert!(!io.in_data_exchange());
    let p700 = io
        .device_mut()
        .store(Unit::Inverter(fi1))
        .unwrap()
        .read(
            proto::nord::ParamNumber::new(700).unwrap(),
            None,
            proto::nord::ArrayElement::new(1).ok(),
        )
        .unwrap();
    assert_eq!(
        Some(p700 as u16),
        def::controller_loss_error(Product::Sk550p)
    );
}

/// An inverter error raises a diagnosis alarm with P700 + 100h; the device repeats it until
/// acknowledged, then takes the controller's AlarmAck.
#[test]
fn an_inverter_error_raises_a_diagnosis_alarm_that_the_controller_acknowledges() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let plan = run_ar(&mut io, &[(3, ModuleKind::Ppo(PpoType::TYPE_3))]);
    let fi1 = Inverter::new(1).unwrap();
    io.device_mut().inject_fault(fi1, "10.3").unwrap();
    let now = Duration::from_millis(1);
    // The outputs every millisecond from `from` to `to`, and what came back.
    let keep = |io: &mut IoDevice, from: u64, to: u64| {
        let mut out = Vec::new();
        for ms in from..=to {
            let now = Duration::from_millis(ms);
            out.extend(io.frame(&output(&plan, 3, &[0, 0, 0, 0], ms as u16), now));
            out.extend(io.poll(now));
        }
        out
    };
    let alarms = |out: &[Out]| {
        frames(out)
            .into_iter()
            .filter(|f| f[..2] == [0xFE, 0x01])
            .map(|f| AlarmRepr::parse(&f).unwrap())
            .collect::<Vec<_>>()
    };
    let first = alarms(&io.poll(now));
    assert_eq!(first.len(), 1);
    let RtaBody::Notification(n) = &first[0].body else {
        panic!("{first:?}")
    };
    assert_eq!(n.alarm_type, AlarmType::DIAGNOSIS);
    assert_eq!((n.slot, n.subslot), (3, 1));
    let items = format!("{:?}", n.items);
    assert!(
        items.contains(&format!("error_type: {}", def::fi_error_alarm(103))),
        "{items}"
    );
    // Not acknowledged: again after RTATimeoutFactor × 100 ms.
    let again = alarms(&keep(&mut io, 2, 150));
    assert_eq!(again.len(), 1);
    assert_eq!(again[0].send_seq, first[0].send_seq);
    // Transport ACK, then the AlarmAck as DATA.
    let seq = first[0].send_seq;
    let ack = AlarmRepr::ack(FrameId::ALARM_LOW, 1, PLC_REF, 0xFFFF, seq);
    io.frame(
        &eth(io.mac(), &ack.emit().unwrap()),
        Duration::from_millis(151),
    );
    let data = AlarmRepr::data(
        1,
        PLC_REF,
        0,
        seq,
        RtaBody::Ack(AlarmAck::of(n, PnioStatus::OK)),
    );
    let out = io.frame(
        &eth(io.mac(), &data.emit().unwrap()),
        Duration::from_millis(152),
    );
    let answers = alarms(&out);
    assert_eq!(answers.len(), 1);
    assert_eq!(answers[0].pdu_type, RtaPduType::ACK);
    assert_eq!(answers[0].ack_seq, 0);
    // Nothing outstanding any more: no repetition.
    assert!(alarms(&keep(&mut io, 153, 400)).is_empty());
    assert!(io.in_data_exchange());
}

/// A spurious alarm (`Endpoint::raise_alarm`): nothing without an AR; in one, a process
/// alarm from FI 1's slot as a DATA-RTA-PDU on FE01h with the alarm CR's sequence numbers, the
/// next queued until the controller's AlarmAck for it came, then sent with the next number.
#[test]
fn a_spurious_alarm_is_a_process_alarm_on_the_alarm_cr() {
    use crate::endpoint::{Endpoint, Output};
    let mut io = io(Product::Sk550p, "sk550p-1");
    assert_eq!(
        io.raise_alarm(Duration::ZERO),
        None,
        "no AR: nowhere to raise it"
    );
    run_ar(&mut io, &[(3, ModuleKind::Ppo(PpoType::TYPE_3))]);
    let pdus = |out: &[Output]| {
        out.iter()
            .filter_map(|o| match o {
                Output::Frame(f) => AlarmRepr::parse(f.get(14..)?).ok(),
                _ => None,
            })
            .collect::<Vec<_>>()
    };
    let now = Duration::from_millis(1);
    let raised = io.raise_alarm(now).expect("an AR to raise it in");
    assert_eq!(raised.what, "process alarm from slot 3 subslot 1");
    let sent = pdus(&raised.outputs);
    assert_eq!(sent.len(), 1);
    let (pdu, n) = match &sent[0] {
        AlarmRepr {
            body: RtaBody::Notification(n),
            ..
        } => (&sent[0], n.clone()),
        other => panic!("{other:?}"),
    };
    assert_eq!(pdu.frame_id, FrameId::ALARM_LOW);
    assert_eq!(
        (pdu.pdu_type, pdu.dst_endpoint, pdu.src_endpoint),
        (RtaPduType::DATA, PLC_REF, 1)
    );
    // The alarm CR's first SendSeqNum; nothing received from the controller yet (FFFEh).
    assert_eq!((pdu.send_seq, pdu.ack_seq), (0, 0xFFFE));
    assert_eq!(
        (n.alarm_type, n.slot, n.subslot, n.high),
        (AlarmType::PROCESS, 3, 1, false)
    );
    assert_eq!(n.specifier.sequence(), 0);
    // A second one waits for the first's AlarmAck.
    let queued = io.raise_alarm(now).unwrap();
    assert!(queued.outputs.is_empty());
    assert!(queued
        .what
        .ends_with("(queued behind an alarm not yet acknowledged)"));
    let ack = AlarmRepr::ack(FrameId::ALARM_LOW, 1, PLC_REF, 0xFFFF, 0);
    io.frame(&eth(io.mac(), &ack.emit().unwrap()), now);
    let data = AlarmRepr::data(
        1,
        PLC_REF,
        0,
        0,
        RtaBody::Ack(AlarmAck::of(&n, PnioStatus::OK)),
    );
    let answered = io.frame(&eth(io.mac(), &data.emit().unwrap()), now);
    let acks = frames(&answered)
        .into_iter()
        .filter_map(|f| AlarmRepr::parse(&f).ok())
        .filter(|p| p.pdu_type == RtaPduType::ACK)
        .count();
    assert_eq!(
        acks, 1,
        "the device acknowledges the AlarmAck at transport level"
    );
    let next = pdus(&Endpoint::poll(&mut io, Duration::from_millis(2)));
    let next: Vec<_> = next
        .iter()
        .filter(|p| p.pdu_type == RtaPduType::DATA)
        .collect();
    assert_eq!(next.len(), 1);
    assert_eq!((next[0].send_seq, next[0].ack_seq), (1, 0));
}

/// Records over the AR: the P102 example of BU 0620 §2.5.6.4 written to record 101, then the
/// answer read; an unknown index gets its PNIO status.
#[test]
fn records_carry_the_parameter_channel() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    run_ar(&mut io, &[(3, ModuleKind::Ppo(PpoType::TYPE_3))]);
    let addr = |index| RecordAddress {
        seq_number: index,
        ar_uuid: AR_UUID,
        api: 0,
        slot: 3,
        subslot: 1,
        index,
    };
    // BU 0620 §2.5.6.4: P102 [-02] = 2.5 s, "24 4E 01 00 00 00 00 FA" (AK 2, PNU 102 + 1000).
    let order = vec![0x24, 0x4E, 0x01, 0x00, 0x00, 0x00, 0x00, 0xFA];
    let write = Block::WriteReq(IodWriteReq {
        addr: addr(101),
        data: order,
    });
    let (status, _, _) = call(&mut io, Opnum::WRITE, &[write], Duration::ZERO);
    assert!(status.is_ok(), "{status:?}");
    let read = Block::ReadReq(IodReadReq {
        addr: addr(101),
        record_data_length: 8,
        target_ar_uuid: Uuid::default(),
    });
    let mut answer = None;
    for ms in 1..10 {
        io.poll(Duration::from_millis(ms));
        let (status, res, _) = call(
            &mut io,
            Opnum::READ,
            &[read.clone()],
            Duration::from_millis(ms),
        );
        if status.is_ok() {
            answer = res.into_iter().find_map(|b| match b {
                Block::ReadRes(r) => Some(r.data),
                _ => None,
            });
            break;
        }
        assert_eq!(status, def::busy_status());
    }
    let answer = answer.expect("an answer");
    // Response label 1, PNU 1102.
    assert_eq!(&answer[..2], &[0x14, 0x4E]);
    let bad = Block::ReadReq(IodReadReq {
        addr: addr(99),
        record_data_length: 8,
        target_ar_uuid: Uuid::default(),
    });
    let (status, _, _) = call(&mut io, Opnum::READ, &[bad], Duration::ZERO);
    assert!(!status.is_ok());
}

#[test]
fn release_ends_the_ar_and_a_wrong_session_key_is_refused() {
    let mut io = io(Product::Tu3Pnt, "tu3");
    run_ar(&mut io, &[(3, ModuleKind::Ppo(PpoType::TYPE_1))]);
    let (status, _, _) = call(
        &mut io,
        Opnum::RELEASE,
        &[Block::Control(IodControl::release(AR_UUID, 9))],
        Duration::ZERO,
    );
    assert!(!status.is_ok());
    assert!(io.in_data_exchange());
    let (status, _, _) = call(
        &mut io,
        Opnum::RELEASE,
        &[Block::Control(IodControl::release(AR_UUID, 1))],
        Duration::ZERO,
    );
    assert!(status.is_ok());
    assert!(!io.in_data_exchange());
}

/// The ARBlockReq of a DeviceAccess AR (IOSAR, ARProperties.DeviceAccess), as engineering
/// tools open it.
fn access_req(uuid: Uuid, ar_type: ArType, properties: u32, timeout_factor: u16) -> Block {
    Block::ArReq(ArBlockReq {
        ar_type,
        ar_uuid: uuid,
        session_key: 7,
        initiator_mac: PLC_MAC,
        initiator_object: Uuid([0xC0; 16]),
        properties,
        activity_timeout_factor: timeout_factor,
        udp_rt_port: ETHERTYPE_PROFINET,
        station_name: b"tool".to_vec(),
    })
}

/// IEC 61158-6-10: a DeviceAccess AR is an IOSAR with ARProperties.DeviceAccess, its Connect
/// the ARBlockReq alone, answered by the ARBlockRes alone; records are read and written in it
/// beside a running IO AR, Release ends it, and a silent initiator loses it after its
/// activity time-out. ReadImplicit needs no AR.
#[test]
fn a_device_access_ar_reads_records_without_io() {
    use proto::pnio::block::ar_properties::{DEVICE_ACCESS, STATE_ACTIVE};
    let mut io = io(Product::Sk550p, "sk550p-1");
    run_ar(&mut io, &[(3, ModuleKind::Ppo(PpoType::TYPE_1))]);
    let tool = Uuid([0xDA; 16]);
    let props = STATE_ACTIVE | DEVICE_ACCESS;
    let im0 = |uuid| {
        Block::ReadReq(IodReadReq {
            addr: RecordAddress {
                seq_number: 1,
                ar_uuid: uuid,
                api: 0,
                slot: 0,
                subslot: 1,
                index: proto::pnio::im0::INDEX,
            },
            record_data_length: 64,
            target_ar_uuid: Uuid::default(),
        })
    };
    let read_im0 = |io: &mut IoDevice, op, uuid, ms| {
        let (status, res, _) = call(io, op, &[im0(uuid)], Duration::from_millis(ms));
        let data = res.into_iter().find_map(|b| match b {
            Block::ReadRes(r) => Some(r.data),
            _ => None,
        });
        (status, data)
    };

    // Not an IOSAR, or an IOSAR with CRs: refused naming ARProperties (field 9) or the blocks.
    let wrong = access_req(tool, ArType::IOC_AR_SINGLE, props, 10);
    let (status, _, _) = call(&mut io, Opnum::CONNECT, &[wrong], Duration::ZERO);
    assert_eq!(status.to_bytes(), [0xDB, 0x81, 0x01, 9]);
    let (mut with_crs, _) = connect_blocks(Product::Sk550p, &[]);
    with_crs[0] = access_req(tool, ArType::IOS_AR, props, 10);
    let (status, _, _) = call(&mut io, Opnum::CONNECT, &with_crs, Duration::ZERO);
    assert_eq!(status.to_bytes(), [0xDB, 0x81, 0x40, 1]);
    // A supervisor AR without DeviceAccess is not offered: ARType refused (field 4).
    let supervisor = access_req(tool, ArType::IOS_AR, STATE_ACTIVE, 10);
    let (status, _, _) = call(&mut io, Opnum::CONNECT, &[supervisor], Duration::ZERO);
    assert_eq!(status.to_bytes(), [0xDB, 0x81, 0x01, 4]);

    // The DeviceAccess AR: the ARBlockRes alone, then I&M0 read in it.
    let req = access_req(tool, ArType::IOS_AR, props, 10);
    let (status, blocks, _) = call(&mut io, Opnum::CONNECT, &[req], Duration::ZERO);
    assert!(status.is_ok(), "{status:?}");
    assert!(
        matches!(blocks.as_slice(), [Block::ArRes(r)] if r.ar_uuid == tool && r.ar_type == ArType::IOS_AR)
    );
    let (status, data) = read_im0(&mut io, Opnum::READ, tool, 0);
    assert!(status.is_ok(), "{status:?}");
    assert_eq!(
        &data.unwrap()[..8],
        &[0x00, 0x20, 0x00, 0x38, 0x01, 0x00, 0x05, 0x38]
    );
    assert!(io.in_data_exchange(), "the IO AR runs on beside it");
    // A second tool is out of AR resources while the first holds it.
    let other = access_req(Uuid([0xDB; 16]), ArType::IOS_AR, props, 10);
    let (status, _, _) = call(
        &mut io,
        Opnum::CONNECT,
        &[other.clone()],
        Duration::from_millis(600),
    );
    assert_eq!(status.to_bytes(), [0xDB, 0x81, 0x40, 4]);
    // Release ends it: a read under its UUID is then an unknown AR.
    let (status, _, _) = call(
        &mut io,
        Opnum::RELEASE,
        &[Block::Control(IodControl::release(tool, 7))],
        Duration::from_millis(700),
    );
    assert!(status.is_ok(), "{status:?}");
    let (status, _) = read_im0(&mut io, Opnum::READ, tool, 800);
    assert_eq!(status.to_bytes(), [0xDE, 0x81, 0x40, 5]);

    // The second tool's AR (1 s activity time-out) is lost after 1 s without a call.
    let (status, _, _) = call(&mut io, Opnum::CONNECT, &[other], Duration::from_secs(1));
    assert!(status.is_ok(), "{status:?}");
    io.poll(Duration::from_millis(2100));
    let (status, _) = read_im0(&mut io, Opnum::READ, Uuid([0xDB; 16]), 2100);
    assert_eq!(status.to_bytes(), [0xDE, 0x81, 0x40, 5]);

    // ReadImplicit: no AR at all.
    let (status, data) = read_im0(&mut io, Opnum::READ_IMPLICIT, Uuid::default(), 2200);
    assert!(status.is_ok(), "{status:?}");
    assert_eq!(data.unwrap().len(), 60);
}

#[test]
fn garbage_is_dropped_and_the_device_keeps_answering() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let junk: [&[u8]; 3] = [
        // DCP Set whose DCPDataLength (FFFFh) runs past the frame.
        &[0xFE, 0xFD, 0x04, 0x00, 0, 0, 0, 1, 0, 0, 0xFF, 0xFF],
        // RT and alarm frames without an AR.
        &[0x80, 0x01, 1, 2, 3],
        &[0xFC, 0x01, 0, 1],
    ];
    for junk in junk {
        assert!(frames(&io.frame(&eth(io.mac(), junk), Duration::ZERO)).is_empty());
    }
    assert!(io.datagram(plc(), &[4, 0, 0], Duration::ZERO).is_empty());
    assert!(io.dropped() >= 4);
    let req = DcpRepr::identify_all(9, 1).emit().unwrap();
    assert_eq!(
        frames(&io.frame(&eth(MULTICAST_DCP_IDENTIFY, &req), Duration::ZERO)).len(),
        1
    );
}

/// ApplicationReady unanswered: repeated every 500 ms, not sooner; after the last try the
/// device gives the AR up and takes a new Connect.
#[test]
fn an_unanswered_application_ready_is_repeated_then_the_ar_is_given_up() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let (blocks, _) = connect_blocks(Product::Sk550p, &[(3, ModuleKind::Ppo(PpoType::TYPE_3))]);
    let at = Duration::from_secs(7);
    assert!(call(&mut io, Opnum::CONNECT, &blocks, at).0.is_ok());
    let prm_end = [Block::Control(IodControl::prm_end(AR_UUID, 1))];
    let (_, _, out) = call(&mut io, Opnum::CONTROL, &prm_end, at);
    let calls = |out: &[Out]| {
        datagrams(out)
            .iter()
            .filter(|r| r.packet_type == PacketType::REQUEST)
            .count()
    };
    assert_eq!(calls(&out), 1);
    let mut repeats = Vec::new();
    for ms in (10..=3000).step_by(10) {
        let now = at + Duration::from_millis(ms);
        if calls(&io.poll(now)) > 0 {
            repeats.push(ms);
        }
    }
    assert_eq!(repeats, [500, 1000, 1500, 2000]);
    assert!(!io.in_data_exchange());
    let later = at + Duration::from_secs(4);
    assert!(call(&mut io, Opnum::CONNECT, &blocks, later).0.is_ok());
}

/// An inverter lost from the system bus: alarm 1256 from its slot (BU 0620 §5.4.2), its
/// module's IOPS bad from then on.
#[test]
fn a_lost_inverter_raises_alarm_1256_and_its_data_goes_bad() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let ppo3 = ModuleKind::Ppo(PpoType::TYPE_3);
    let plan = run_ar(&mut io, &[(3, ppo3), (4, ppo3)]);
    io.lose_inverter(Inverter::new(2).unwrap()).unwrap();
    let out = io.poll(Duration::from_millis(1));
    let alarm = frames(&out)
        .into_iter()
        .filter(|f| f[..2] == [0xFE, 0x01])
        .map(|f| AlarmRepr::parse(&f).unwrap())
        .next()
        .expect("an alarm");
    let RtaBody::Notification(n) = &alarm.body else {
        panic!("{alarm:?}")
    };
    assert_eq!((n.slot, n.alarm_type), (4, AlarmType::DIAGNOSIS));
    assert!(
        format!("{:?}", n.items).contains("error_type: 1256"),
        "{:?}",
        n.items
    );
    let (_, iops) = input_of(&plan, &out, 4).expect("an input frame");
    assert_eq!(iops, Iox::BAD_BY_DEVICE);
    let (_, iops) = input_of(&plan, &out, 3).expect("FI 1 still there");
    assert_eq!(iops, Iox::GOOD);
}

/// An IOCR whose DataLength cannot hold its data (or is below the 40-byte minimum) is refused
/// with the PNIO status naming the IOCRBlockReq and its field 8, DataLength; the device stays
/// free for a proper Connect.
#[test]
fn impossible_iocr_sizes_are_refused_naming_data_length() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let ppo6 = ModuleKind::Ppo(PpoType::TYPE_6);
    for data_length in [20u16, 40, 1441] {
        let (mut blocks, _) = connect_blocks(Product::Sk550p, &[(3, ppo6), (4, ppo6), (5, ppo6)]);
        for b in &mut blocks {
            if let Block::IocrReq(c) = b {
                c.data_length = data_length;
            }
        }
        let (status, _, _) = call(&mut io, Opnum::CONNECT, &blocks, Duration::ZERO);
        assert_eq!(
            status,
            PnioStatus::cm(
                proto::pnio::status::cm::CONNECT,
                proto::pnio::status::cm::FAULTY_IOCR_BLOCK,
                8
            ),
            "DataLength {data_length}"
        );
        assert!(!io.in_data_exchange());
    }
    run_ar(&mut io, &[(3, ppo6)]);
}

/// A data hold time past 1.92 s (DataHoldFactor × ReductionRatio × 1 ms here, IEC
/// 61158-6-10) is refused naming the IOCRBlockReq's field 16, DataHoldFactor, as p-net
/// refuses it; 1.92 s itself is taken.
#[test]
fn a_data_hold_time_past_1_92_s_is_refused() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let ppo3 = ModuleKind::Ppo(PpoType::TYPE_3);
    for (rr, factor, ok) in [(128u16, 16u16, false), (128, 15, true)] {
        let (mut blocks, _) = connect_blocks(Product::Sk550p, &[(3, ppo3)]);
        for b in &mut blocks {
            if let Block::IocrReq(c) = b {
                c.reduction_ratio = rr;
                c.data_hold_factor = factor;
            }
        }
        let (status, _, _) = call(&mut io, Opnum::CONNECT, &blocks, Duration::ZERO);
        if ok {
            assert!(status.is_ok(), "{status:?}");
        } else {
            assert_eq!(status.to_bytes(), [0xDB, 0x81, 0x02, 16], "factor {factor}");
        }
    }
}

/// The frame ids of an IOCR belong to the RT class its IOCRProperties declare (IEC 61158-6-10,
/// the FrameID table): RT_CLASS_2 takes 8000h–BBFFh, RT_CLASS_1 (the legacy value)
/// C000h–F7FFh. A mismatch is refused naming the IOCRBlockReq's field 9, FrameID, as p-net
/// refuses it; an output CR left open (FFFFh) gets a frame id of its class from the device.
#[test]
fn frame_ids_must_be_those_of_the_declared_rt_class() {
    let mut io = io(Product::Sk550p, "sk550p-1");
    let ppo3 = ModuleKind::Ppo(PpoType::TYPE_3);
    let faulty_frame_id = PnioStatus::cm(
        proto::pnio::status::cm::CONNECT,
        proto::pnio::status::cm::FAULTY_IOCR_BLOCK,
        9,
    );
    let connect = |io: &mut IoDevice, class: u32, input: u16, output: u16| {
        let (mut blocks, _) = connect_blocks(Product::Sk550p, &[(3, ppo3)]);
        for b in &mut blocks {
            if let Block::IocrReq(c) = b {
                c.properties = class;
                c.frame_id = if c.iocr_type == IocrType::INPUT {
                    input
                } else {
                    output
                };
            }
        }
        let (status, res, _) = call(io, Opnum::CONNECT, &blocks, Duration::ZERO);
        let ids: Vec<(IocrType, u16)> = res
            .iter()
            .filter_map(|b| match b {
                Block::IocrRes(r) => Some((r.iocr_type, r.frame_id)),
                _ => None,
            })
            .collect();
        (status, ids)
    };
    let (rt1, rt2) = (iocr_properties::RT_CLASS_1, iocr_properties::RT_CLASS_2);
    // RT_CLASS_2 with RT_CLASS_1's ids, and the other way round, on either CR.
    for (class, input, output) in [
        (rt2, 0xC000, 0x8001),
        (rt2, 0x8000, 0xC001),
        (rt1, 0x8000, 0xC001),
        (rt1, 0xC000, 0x8001),
        (rt2, 0xBC00, 0x8001),
    ] {
        let (status, _) = connect(&mut io, class, input, output);
        assert_eq!(
            status, faulty_frame_id,
            "{class} {input:04X}h {output:04X}h"
        );
        assert!(!io.in_data_exchange());
    }
    // Matching ids are taken as proposed.
    let (status, ids) = connect(&mut io, rt1, 0xC000, 0xC001);
    assert!(status.is_ok(), "{status:?}");
    assert_eq!(ids, [(IocrType::INPUT, 0xC000), (IocrType::OUTPUT, 0xC001)]);
    let mut io = self::io(Product::Sk550p, "sk550p-1");
    // An output CR left open gets an id of its class, not the input's.
    let (status, ids) = connect(&mut io, rt2, 0x8000, 0xFFFF);
    assert!(status.is_ok(), "{status:?}");
    assert_eq!(ids, [(IocrType::INPUT, 0x8000), (IocrType::OUTPUT, 0x8001)]);
}

#[test]
fn lldp_names_the_station_every_5_s() {
    // BU 0620 §2.5.3 CC-B: topology detection with LLDP.
    let mut d = io(Product::Sk550p, "nord-device");
    let lldp = |out: Vec<Out>| -> Vec<proto::lldp::Lldpdu> {
        out.into_iter()
            .filter_map(|o| match o {
                Out::Frame(f) => Some(f),
                Out::Datagram { .. } => None,
            })
            .filter_map(|f| {
                let eth = EthernetFrame::new_checked(f).ok()?;
                (eth.inner_ethertype() == proto::eth::ETHERTYPE_LLDP)
                    .then(|| proto::lldp::Lldpdu::parse(eth.inner_payload()).ok())?
            })
            .collect()
    };
    assert!(lldp(d.poll(Duration::from_millis(4_999))).is_empty());
    let got = lldp(d.poll(Duration::from_secs(5)));
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].chassis, (7, b"nord-device".to_vec()));
    assert_eq!(got[0].port, (7, b"port-001".to_vec()));
    assert_eq!(got[0].ttl, 20);
    assert!(lldp(d.poll(Duration::from_millis(9_999))).is_empty());
    assert_eq!(lldp(d.poll(Duration::from_secs(10))).len(), 1);
}
