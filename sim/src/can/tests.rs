//! The segment frame by frame, as a CANopen master sees it.

use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::nmt::NmtCommand;
use proto::canopen::sdo::{InitiateData, SdoResponse};
use proto::nord::{Inverter, Product};

use super::Segment;
use crate::device::DeviceConfig;

const MS: Duration = Duration::from_millis(1);

fn segment() -> Segment {
    let mut s = Segment::new(DeviceConfig::new(Product::Sk550p)).unwrap();
    s.poll(Duration::ZERO);
    s
}

fn frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::new(id, data).unwrap()
}

/// The one SDO answer of `node` to `request`.
fn sdo(s: &mut Segment, node: u8, request: [u8; 8]) -> SdoResponse {
    let out = s.receive(&frame(0x600 + u16::from(node), &request), MS);
    assert_eq!(out.len(), 1, "{out:?}");
    assert_eq!(out[0].id(), 0x580 + u16::from(node));
    SdoResponse::parse(out[0].data()).unwrap()
}

fn upload(index: u16, sub: u8) -> [u8; 8] {
    let i = index.to_le_bytes();
    [0x40, i[0], i[1], sub, 0, 0, 0, 0]
}

fn abort_code(r: SdoResponse) -> u32 {
    match r {
        SdoResponse::Abort(a) => a.code.0,
        other => panic!("no abort: {other:?}"),
    }
}

#[test]
fn every_inverter_boots_at_its_system_bus_address() {
    let mut s = Segment::new(DeviceConfig::new(Product::Sk550p)).unwrap();
    assert_eq!(s.nodes(), vec![32, 34, 36, 38, 40, 42, 44, 46]);
    let boot = s.poll(Duration::ZERO);
    let ids: Vec<u16> = boot.iter().map(CanFrame::id).collect();
    assert_eq!(
        ids,
        vec![0x720, 0x722, 0x724, 0x726, 0x728, 0x72A, 0x72C, 0x72E]
    );
    assert!(boot.iter().all(|f| f.data() == [0x00]), "boot-up messages");
    assert!(s.poll(MS).is_empty(), "once, and no heartbeat at 1017h = 0");
}

#[test]
fn p102_of_fi_3_is_read_and_written_at_its_nord_object() {
    let mut s = segment();
    let factory = s
        .device_mut()
        .store(crate::link::Unit::Inverter(Inverter::new(3).unwrap()))
        .unwrap()
        .read(proto::nord::ParamNumber::new(102).unwrap(), None, None)
        .unwrap();
    // P102 has four parameter sets: sub-index 0 their count, 1..4 the sets.
    let read = |s: &mut Segment| match sdo(s, 36, upload(0x2066, 1)) {
        SdoResponse::InitiateUpload {
            index: 0x2066,
            sub: 1,
            data: InitiateData::Expedited(e),
        } => {
            let mut b = [0u8; 4];
            b[..e.data().len()].copy_from_slice(e.data());
            i32::from_le_bytes(b)
        }
        other => panic!("{other:?}"),
    };
    assert_eq!(read(&mut s), factory);
    // 2.5 s in hundredths, as the P102 write example of BU 0620 writes it: 250.
    let written = sdo(&mut s, 36, [0x2B, 0x66, 0x20, 0x01, 0xFA, 0x00, 0, 0]);
    assert_eq!(
        written,
        SdoResponse::InitiateDownload {
            index: 0x2066,
            sub: 1
        }
    );
    assert_eq!(read(&mut s), 250);
    // FI 1 (node 32) keeps its own.
    assert_ne!(
        sdo(&mut s, 32, upload(0x2066, 1)),
        sdo(&mut s, 36, upload(0x2066, 1))
    );
    assert_eq!(
        abort_code(sdo(&mut s, 36, [0x2B, 0x66, 0x20, 0x00, 4, 0, 0, 0])),
        0x0601_0002,
        "the count of sets is read-only"
    );
}

#[test]
fn bad_requests_get_the_standards_abort_codes_and_the_node_serves_on() {
    let mut s = segment();
    assert_eq!(
        abort_code(sdo(&mut s, 36, upload(0x3000, 0))),
        0x0602_0000,
        "no object"
    );
    assert_eq!(
        abort_code(sdo(&mut s, 36, upload(0x1017, 5))),
        0x0609_0011,
        "no sub-index"
    );
    assert_eq!(
        abort_code(sdo(&mut s, 36, [0xE0, 0, 0, 0, 0, 0, 0, 0])),
        0x0504_0001,
        "unknown command specifier"
    );
    assert_eq!(
        abort_code(sdo(&mut s, 36, [0x60, 0, 0, 0, 0, 0, 0, 0])),
        0x0504_0001,
        "a segment with no transfer"
    );
    assert_eq!(
        abort_code(sdo(&mut s, 36, [0x23, 0x18, 0x10, 0x01, 1, 0, 0, 0])),
        0x0601_0002,
        "identity is read-only"
    );
    assert_eq!(
        abort_code(sdo(&mut s, 36, [0xC0, 0x66, 0x20, 0, 0, 0, 0, 0])),
        0x0504_0001,
        "block transfers are not served"
    );
    // A short frame is no SDO request: silence.
    assert!(s.receive(&frame(0x624, &[0x40, 0x66, 0x20]), MS).is_empty());
    // An abort from the client is not answered.
    assert!(s
        .receive(&frame(0x624, &[0x80, 0x66, 0x20, 0, 0, 0, 0, 0x08]), MS)
        .is_empty());
    assert!(matches!(
        sdo(&mut s, 36, upload(0x1000, 0)),
        SdoResponse::InitiateUpload { .. }
    ));
}

#[test]
fn the_device_name_is_uploaded_in_segments_with_the_toggle_checked() {
    let mut s = segment();
    match sdo(&mut s, 34, upload(0x1008, 0)) {
        SdoResponse::InitiateUpload {
            data: InitiateData::Segmented { size: Some(6) },
            ..
        } => {}
        other => panic!("{other:?}"),
    }
    match sdo(&mut s, 34, [0x60, 0, 0, 0, 0, 0, 0, 0]) {
        SdoResponse::UploadSegment {
            toggle: false,
            last: true,
            data,
        } => assert_eq!(data.data(), Product::Sk550p.name().as_bytes()),
        other => panic!("{other:?}"),
    }
    sdo(&mut s, 34, upload(0x1008, 0));
    assert_eq!(
        abort_code(sdo(&mut s, 34, [0x70, 0, 0, 0, 0, 0, 0, 0])),
        0x0503_0000,
        "toggle bit not alternated"
    );
}

#[test]
fn a_segmented_download_is_assembled_and_checked() {
    let mut s = segment();
    // 1017h:00 (2 bytes) in one segment after an initiate announcing 2 bytes.
    sdo(&mut s, 36, [0x21, 0x17, 0x10, 0x00, 2, 0, 0, 0]);
    let done = sdo(&mut s, 36, [0x0B, 0xE8, 0x03, 0, 0, 0, 0, 0]);
    assert_eq!(done, SdoResponse::DownloadSegment { toggle: false });
    // The heartbeat starts: 1000 ms.
    let beats = s.poll(2 * MS);
    assert_eq!(beats, vec![frame(0x724, &[0x7F])]);
    assert!(s.poll(500 * MS).is_empty());
    assert_eq!(s.poll(1002 * MS), vec![frame(0x724, &[0x7F])]);
    // 3 bytes announced, 2 sent: too short.
    sdo(&mut s, 36, [0x21, 0x17, 0x10, 0x00, 3, 0, 0, 0]);
    assert_eq!(
        abort_code(sdo(&mut s, 36, [0x0B, 0xE8, 0x03, 0, 0, 0, 0, 0])),
        0x0607_0013
    );
}

#[test]
fn nmt_commands_move_the_state_and_stopped_nodes_leave_sdo_unanswered() {
    let mut s = segment();
    sdo(&mut s, 36, [0x2B, 0x17, 0x10, 0x00, 0x64, 0x00, 0, 0]);
    s.poll(2 * MS);
    // Start all: heartbeats say 05h.
    s.receive(&frame(0, &[NmtCommand::START.0, 0]), 3 * MS);
    assert_eq!(s.poll(110 * MS), vec![frame(0x724, &[0x05])]);
    // Stop node 36: no SDO answer, heartbeat 04h; the others still answer.
    s.receive(&frame(0, &[NmtCommand::STOP.0, 36]), 111 * MS);
    assert!(s
        .receive(&frame(0x624, &upload(0x1000, 0)), 112 * MS)
        .is_empty());
    assert_eq!(s.poll(210 * MS), vec![frame(0x724, &[0x04])]);
    assert!(matches!(
        sdo(&mut s, 38, upload(0x1000, 0)),
        SdoResponse::InitiateUpload { .. }
    ));
    // Reset communication: boot-up again, 1017h back to 0.
    s.receive(
        &frame(0, &[NmtCommand::RESET_COMMUNICATION.0, 36]),
        220 * MS,
    );
    assert_eq!(s.poll(221 * MS), vec![frame(0x724, &[0x00])]);
    assert!(s.poll(400 * MS).is_empty());
    // An NMT frame with an unknown command changes nothing and is not answered.
    assert!(s.receive(&frame(0, &[0x55, 36]), 401 * MS).is_empty());
}

#[test]
fn node_guarding_answers_with_an_alternating_toggle() {
    let mut s = segment();
    let guard = CanFrame::remote(0x724, 1).unwrap();
    assert_eq!(s.receive(&guard, MS), vec![frame(0x724, &[0x7F])]);
    assert_eq!(s.receive(&guard, 2 * MS), vec![frame(0x724, &[0xFF])]);
    assert_eq!(s.receive(&guard, 3 * MS), vec![frame(0x724, &[0x7F])]);
}

#[test]
fn an_inverter_error_sends_an_emergency_and_sets_the_error_register() {
    let mut s = segment();
    s.device_mut()
        .inject_fault(Inverter::new(3).unwrap(), "10.0")
        .unwrap();
    // The drive takes the error with its next cycle; the segment sees P700 change.
    let mut emcy = Vec::new();
    for t in 1..50 {
        s.device_mut()
            .process(Inverter::new(3).unwrap(), 0, &[], t * MS)
            .unwrap();
        emcy.extend(s.poll(t * MS).into_iter().filter(|f| f.id() == 0x0A4));
    }
    assert_eq!(emcy.len(), 1, "{emcy:?}");
    let data = emcy[0].data();
    assert_eq!(u16::from_le_bytes([data[3], data[4]]), 100, "P700 = 10.0");
    assert_eq!(data[5], 3, "FI 3");
    match sdo(&mut s, 36, upload(0x1001, 0)) {
        SdoResponse::InitiateUpload {
            data: InitiateData::Expedited(e),
            ..
        } => assert_ne!(e.data()[0], 0),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_node_off_the_bus_is_silent_and_the_others_serve_on() {
    let mut s = segment();
    // FI 3 (node 36) produces a heartbeat every 10 ms (1017h).
    let heartbeat = [0x2B, 0x17, 0x10, 0x00, 10, 0, 0, 0];
    assert!(matches!(
        sdo(&mut s, 36, heartbeat),
        SdoResponse::InitiateDownload { .. }
    ));
    let beats = |s: &mut Segment, from: u32, to: u32| {
        (from..to)
            .flat_map(|t| s.poll(t * MS))
            .filter(|f| f.id() == 0x724)
            .count()
    };
    assert!(beats(&mut s, 2, 50) >= 4);
    assert_eq!(
        s.inject_fault(Inverter::new(3).unwrap(), super::OFF_BUS),
        Ok(())
    );
    assert_eq!(beats(&mut s, 50, 100), 0, "no heartbeat off the bus");
    assert_eq!(s.next_due(), None, "nothing scheduled on the bus");
    let request = frame(0x624, &upload(0x1000, 0));
    assert!(s.receive(&request, 100 * MS).is_empty(), "no SDO answer");
    // FI 2 (node 34) still answers.
    assert!(matches!(
        sdo(&mut s, 34, upload(0x1000, 0)),
        SdoResponse::InitiateUpload { .. }
    ));
    let e = s.inject_fault(Inverter::new(8).unwrap(), super::OFF_BUS);
    assert!(e.is_ok(), "the SK 550P has 8 inverters: {e:?}");
    let mut config = DeviceConfig::new(Product::Tu3Eip);
    config.inverters = 1;
    let mut one = Segment::new(config).unwrap();
    let e = one.inject_fault(Inverter::new(2).unwrap(), super::OFF_BUS);
    assert_eq!(e, Err("FI 2 is not on the system bus".into()));
}

/// CiA 301's answers to malformed and misplaced requests, each followed by a request the node
/// still serves.
#[test]
fn bad_input_is_refused_by_the_standards_code_or_silence_and_the_node_serves_on() {
    let mut s = segment();
    let serves = |s: &mut Segment| {
        assert!(
            matches!(
                sdo(s, 36, upload(0x1000, 0)),
                SdoResponse::InitiateUpload { .. }
            ),
            "node 36 still serves"
        )
    };
    let aborted = |s: &mut Segment, request: [u8; 8], code: u32, why: &str| {
        assert_eq!(abort_code(sdo(s, 36, request)), code, "{why}");
        serves(s);
    };
    let silent = |s: &mut Segment, frame: CanFrame, why: &str| {
        assert!(s.receive(&frame, MS).is_empty(), "{why}");
        serves(s);
    };
    // Wrong lengths of an SDO frame: no SDO request, no answer.
    for len in [0, 1, 4, 7] {
        silent(
            &mut s,
            frame(0x624, &upload(0x1000, 0)[..len]),
            "short SDO frame",
        );
    }
    // A remote frame on the SDO channel.
    silent(&mut s, CanFrame::remote(0x624, 8).unwrap(), "RTR on 624h");
    // Command specifier 7 and block transfers.
    aborted(&mut s, [0xE0, 0, 0x10, 0, 0, 0, 0, 0], 0x0504_0001, "ccs 7");
    aborted(
        &mut s,
        [0xA0, 0x00, 0x10, 0, 0, 0, 0, 0],
        0x0504_0001,
        "block upload",
    );
    aborted(
        &mut s,
        [0xC6, 0x17, 0x10, 0, 2, 0, 0, 0],
        0x0504_0001,
        "block download",
    );
    // Segments outside a transfer.
    aborted(
        &mut s,
        [0x00, 1, 2, 3, 4, 5, 6, 7],
        0x0504_0001,
        "download segment",
    );
    aborted(
        &mut s,
        [0x70, 0, 0, 0, 0, 0, 0, 0],
        0x0504_0001,
        "upload segment, toggle 1",
    );
    // Objects and sub-indices that are not there.
    aborted(
        &mut s,
        upload(0x2000, 0),
        0x0602_0000,
        "P000 does not exist",
    );
    aborted(
        &mut s,
        upload(0x23E7, 0),
        0x0602_0000,
        "P999 does not exist",
    );
    aborted(&mut s, upload(0x5FFF, 0), 0x0602_0000, "manufacturer area");
    aborted(&mut s, upload(0x2066, 5), 0x0609_0011, "P102 has 4 sets");
    aborted(&mut s, upload(0x1018, 2), 0x0609_0011, "1018h:02");
    aborted(&mut s, upload(0x1001, 1), 0x0609_0011, "1001h:01");
    // Writes the object refuses.
    aborted(
        &mut s,
        [0x23, 0x00, 0x10, 0, 1, 0, 0, 0],
        0x0601_0002,
        "1000h is read-only",
    );
    aborted(
        &mut s,
        [0x2F, 0x01, 0x10, 0, 1, 0, 0, 0],
        0x0601_0002,
        "1001h is read-only",
    );
    aborted(
        &mut s,
        [0x2B, 0x17, 0x10, 1, 1, 0, 0, 0],
        0x0609_0011,
        "1017h:01",
    );
    aborted(
        &mut s,
        [0x2F, 0x17, 0x10, 0, 1, 0, 0, 0],
        0x0607_0013,
        "1 byte to a UNSIGNED16",
    );
    aborted(
        &mut s,
        [0x23, 0x17, 0x10, 0, 1, 0, 0, 0],
        0x0607_0012,
        "4 bytes to a UNSIGNED16",
    );
    aborted(
        &mut s,
        [0x2B, 0x66, 0x20, 1, 0x01, 0x7D, 0, 0],
        0x0609_0031,
        "P102 above 320.00 s",
    );
    aborted(
        &mut s,
        [0x2B, 0x66, 0x20, 1, 0xFF, 0xFF, 0, 0],
        0x0609_0032,
        "P102 below 0",
    );
    // A segmented download announcing more than the server takes.
    aborted(
        &mut s,
        [0x21, 0x17, 0x10, 0, 0, 4, 0, 0],
        0x0504_0005,
        "1024 bytes announced",
    );
    // A toggle error in a download: the transfer ends, the next request is served.
    sdo(&mut s, 36, [0x21, 0x17, 0x10, 0x00, 2, 0, 0, 0]);
    aborted(
        &mut s,
        [0x1B, 0xE8, 0x03, 0, 0, 0, 0, 0],
        0x0503_0000,
        "first segment toggle 1",
    );
    // Two segments where the size said one: too long.
    sdo(&mut s, 36, [0x21, 0x17, 0x10, 0x00, 2, 0, 0, 0]);
    sdo(&mut s, 36, [0x0A, 0xE8, 0x03, 0, 0, 0, 0, 0]);
    aborted(
        &mut s,
        [0x1D, 0x01, 0, 0, 0, 0, 0, 0],
        0x0607_0012,
        "3 bytes for 2",
    );
    // The client aborts a transfer: no answer, and a new one starts clean.
    sdo(&mut s, 36, upload(0x1008, 0));
    silent(
        &mut s,
        frame(0x624, &[0x80, 0x08, 0x10, 0, 0, 0, 0x04, 0x05]),
        "abort from the client",
    );
    aborted(
        &mut s,
        [0x60, 0, 0, 0, 0, 0, 0, 0],
        0x0504_0001,
        "no upload after the abort",
    );
    // NMT to nodes not on the segment, with a bad length or an unknown command.
    silent(
        &mut s,
        frame(0, &[0x02, 0x33]),
        "stop node 51: no such node",
    );
    silent(&mut s, frame(0, &[0x02]), "NMT of 1 byte");
    silent(&mut s, frame(0, &[0x02, 36, 0]), "NMT of 3 bytes");
    silent(&mut s, frame(0, &[0x03, 36]), "NMT command 03h");
    silent(&mut s, frame(0, &[0x02, 0x80]), "NMT node 128");
    // Frames of no object of the pre-defined set, and a babbling node's heartbeat.
    silent(&mut s, frame(0x7E5, &[0x04, 0, 0, 0, 0, 0, 0, 0]), "LSS");
    silent(&mut s, frame(0x100, &[1, 2, 3, 4, 5, 6]), "TIME");
    for _ in 0..100 {
        assert!(s.receive(&frame(0x77F, &[0x05]), MS).is_empty());
    }
    serves(&mut s);
}

/// RPDO1 of `node`: control word and three setpoints.
fn rpdo(node: u8, words: [u16; 4]) -> CanFrame {
    let data: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    frame(0x200 + u16::from(node), &data)
}

const SYNC: u16 = 0x080;

#[test]
fn process_data_run_on_sync_in_operational_only() {
    let mut s = segment();
    // Pre-operational: no PDO taken, none sent.
    assert!(s.receive(&rpdo(32, [0x047E, 0, 0, 0]), MS).is_empty());
    assert!(s.receive(&frame(SYNC, &[]), 2 * MS).is_empty());
    s.receive(&frame(0, &[NmtCommand::START.0, 0]), 3 * MS);
    // Operational, but no RPDO1 yet: SYNC gets no TPDO.
    assert!(s.receive(&frame(SYNC, &[]), 4 * MS).is_empty());
    // The RPDO1 is taken at the SYNC, after the charging time: "Ready to switch on".
    assert!(s.receive(&rpdo(32, [0x047E, 0, 0, 0]), 30 * MS).is_empty());
    let out = s.receive(&frame(SYNC, &[]), 31 * MS);
    let ids: Vec<u16> = out.iter().map(CanFrame::id).collect();
    assert_eq!(
        ids,
        [0x1A0, 0x2A0],
        "FI 1 alone had an RPDO1: its TPDO1 and TPDO2"
    );
    let status = u16::from_le_bytes([out[0].data()[0], out[0].data()[1]]);
    assert_eq!(status & 0x00FF, 0x31, "{status:04X}h");
    assert_eq!(out[0].data().len(), 8, "status word, actual values 1-3");
    assert_eq!(out[1].data().len(), 4, "actual values 4-5 of an SK 5x0P");
    // A SYNC with a counter works the same; every SYNC brings the TPDOs.
    assert_eq!(s.receive(&frame(SYNC, &[1]), 32 * MS).len(), 2);
    // Stopped: no PDO, and the process data start again with an RPDO1 in Operational.
    s.receive(&frame(0, &[NmtCommand::STOP.0, 32]), 33 * MS);
    assert!(s.receive(&frame(SYNC, &[]), 34 * MS).is_empty());
    s.receive(&frame(0, &[NmtCommand::START.0, 32]), 35 * MS);
    assert!(s.receive(&frame(SYNC, &[]), 36 * MS).is_empty());
}

#[test]
fn setpoints_reach_the_drive_and_actual_values_come_back() {
    let mut s = segment();
    s.receive(&frame(0, &[NmtCommand::START.0, 0]), MS);
    let mut t = 30;
    let mut cycle = |s: &mut Segment, words: [u16; 4]| {
        s.receive(&rpdo(36, words), t * MS);
        let out = s.receive(&frame(SYNC, &[]), (t + 1) * MS);
        t += 5;
        assert_eq!(out.len(), 2, "{out:?}");
        assert_eq!(out[0].id(), 0x1A4, "TPDO1 of node 36, FI 3");
        let d = out[0].data();
        [0, 1, 2, 3].map(|i| u16::from_le_bytes([d[2 * i], d[2 * i + 1]]))
    };
    cycle(&mut s, [0x047E, 0, 0, 0]);
    // Enable operation with 50 % setpoint: the drive ramps up, the first actual value (the
    // actual frequency, P543 [-01] = 1) follows.
    let mut last = [0; 4];
    for _ in 0..400 {
        last = cycle(&mut s, [0x047F, 0x2000, 0, 0]);
    }
    assert_eq!(
        last[0] & 0x00FF,
        0x37,
        "operation enabled: {:04X}h",
        last[0]
    );
    assert!(last[1] > 0x1000, "actual frequency: {:04X}h", last[1]);
}

#[test]
fn an_rpdo_of_the_wrong_length_gives_an_emcy_and_a_short_one_is_not_taken() {
    let mut s = segment();
    s.receive(&frame(0, &[NmtCommand::START.0, 0]), MS);
    let out = s.receive(&frame(0x220, &[0x7E, 0x04]), 30 * MS);
    assert_eq!(out.len(), 1, "{out:?}");
    assert_eq!(out[0].id(), 0x0A0, "EMCY of node 32");
    assert_eq!(out[0].data(), [0x10, 0x82, 0x11, 0, 0, 0, 0, 0], "8210h");
    assert!(
        s.receive(&frame(SYNC, &[]), 31 * MS).is_empty(),
        "the short RPDO1 was not taken"
    );
    // RPDO2 (setpoints 4-5) is 4 bytes: 6 are taken, with EMCY 8220h.
    let out = s.receive(&frame(0x320, &[0, 0x10, 0, 0x20, 0xFF, 0xFF]), 32 * MS);
    assert_eq!(out.len(), 1, "{out:?}");
    assert_eq!(out[0].data()[..3], [0x20, 0x82, 0x11], "8220h");
    // A SYNC with a counter out of range is no SYNC.
    s.receive(&rpdo(32, [0x047E, 0, 0, 0]), 33 * MS);
    assert!(s.receive(&frame(SYNC, &[0]), 34 * MS).is_empty());
    assert_eq!(s.receive(&frame(SYNC, &[]), 35 * MS).len(), 2);
}

#[test]
fn behind_a_module_the_inverters_are_sk_54xe_with_five_values() {
    let mut s = Segment::new(DeviceConfig::new(Product::Tu3Eip)).unwrap();
    s.poll(Duration::ZERO);
    s.receive(&frame(0, &[NmtCommand::START.0, 0]), MS);
    s.receive(&rpdo(32, [0x047E, 0, 0, 0]), 30 * MS);
    let ids: Vec<u16> = s
        .receive(&frame(SYNC, &[]), 31 * MS)
        .iter()
        .map(CanFrame::id)
        .collect();
    assert_eq!(ids, [0x1A0, 0x2A0]);
}

/// An expedited download of a 16-bit value.
fn download_u16(index: u16, sub: u8, value: u16) -> [u8; 8] {
    let (i, v) = (index.to_le_bytes(), value.to_le_bytes());
    [0x2B, i[0], i[1], sub, v[0], v[1], 0, 0]
}

/// P700 [-01] and [-04] of `fi`.
fn p700(s: &mut Segment, fi: i64) -> (i32, i32) {
    let store = s
        .device_mut()
        .store(crate::link::Unit::Inverter(Inverter::new(fi).unwrap()))
        .unwrap();
    let number = proto::nord::ParamNumber::new(700).unwrap();
    let at = |e| store.read(number, None, proto::nord::ArrayElement::new(e).ok());
    (at(1).unwrap(), at(4).unwrap())
}

/// Every frame the segment sends on its own from `from` to `to`, polled each millisecond.
fn run(s: &mut Segment, from: u64, to: u64) -> Vec<(u64, CanFrame)> {
    (from..=to)
        .flat_map(|t| {
            s.poll(Duration::from_millis(t))
                .into_iter()
                .map(move |f| (t, f))
        })
        .collect()
}

#[test]
fn p120_watches_the_interfaces_heartbeat_and_loses_it_as_the_manual_says() {
    // Behind the SK 550P the interface is FI 1 (node 32): FI 2 (node 34) watches its
    // heartbeat. P120 [-01] = 2: from boot-up, so 600 ms of silence is E10.0, 7583h
    // "HeartBeat telegram timeout" (BU 0620 §5.3), and an EMCY with that code.
    let mut s = segment();
    assert!(matches!(
        sdo(&mut s, 34, download_u16(0x2078, 1, 2)),
        SdoResponse::InitiateDownload { .. }
    ));
    let out = run(&mut s, 2, 700);
    let emcy: Vec<_> = out.iter().filter(|(_, f)| f.id() == 0x0A2).collect();
    assert_eq!(emcy.len(), 1, "{out:?}");
    assert_eq!(emcy[0].0, 600, "600 ms after boot-up");
    assert_eq!(&emcy[0].1.data()[..2], &[0x83, 0x75]);
    assert_eq!(p700(&mut s, 2), (100, 0x7583));
    assert_eq!(
        p700(&mut s, 3),
        (0, 0),
        "FI 3 has P120 = 1 (Auto) and heard nothing"
    );

    // P120 = 1 "Auto": from FI 1's first heartbeat. FI 1 beats every 100 ms, then stops.
    let mut s = segment();
    assert!(run(&mut s, 1, 1000).is_empty());
    assert_eq!(p700(&mut s, 3), (0, 0));
    assert!(matches!(
        sdo(&mut s, 32, [0x2B, 0x17, 0x10, 0, 100, 0, 0, 0]),
        SdoResponse::InitiateDownload { .. }
    ));
    let beats = run(&mut s, 1001, 2000);
    assert!(beats.iter().all(|(_, f)| f.id() == 0x720), "{beats:?}");
    assert_eq!(p700(&mut s, 3), (0, 0), "heartbeats keep it quiet");
    s.receive(&frame(0x620, &[0x2B, 0x17, 0x10, 0, 0, 0, 0, 0]), 2000 * MS);
    let out = run(&mut s, 2001, 3000);
    let lost: Vec<u16> = out.iter().map(|(_, f)| f.id()).collect();
    // Every further inverter (nodes 34…46) reports it.
    assert_eq!(lost, (0x0A2..=0x0AE).step_by(2).collect::<Vec<u16>>());
    assert!(
        out.iter().all(|(t, _)| *t == 2501),
        "last beat at 1901 ms + 600 ms"
    );
    assert_eq!(p700(&mut s, 3), (100, 0x7583));
    assert_eq!(p700(&mut s, 1), (0, 0), "FI 1 is the interface");
}

#[test]
fn p120_off_and_p513_no_error_keep_the_inverter_running() {
    // P120 [-01] = 0; P513 [-03] = -0.1 s "no error" (−1) with P120 = 2.
    for (index, sub, value) in [(0x2078, 1, 0), (0x2201, 3, 0xFFFF)] {
        let mut s = segment();
        if value == 0xFFFF {
            sdo(&mut s, 34, download_u16(0x2078, 1, 2));
        }
        let request = download_u16(index, sub, value);
        assert!(matches!(
            sdo(&mut s, 34, request),
            SdoResponse::InitiateDownload { .. }
        ));
        assert!(run(&mut s, 2, 2000).is_empty());
        assert_eq!(p700(&mut s, 2), (0, 0));
    }
}

#[test]
fn behind_a_module_p120_loses_node_1_as_e10_9_or_e10_8() {
    for (product, error) in [(Product::Tu4Eip, 109u16), (Product::Tu3Pol, 108)] {
        let mut s = Segment::new(DeviceConfig::new(product)).unwrap();
        s.poll(Duration::ZERO);
        // The module's heartbeat (node 1, operational) arms "Auto"; 1016h names it.
        assert_eq!(
            sdo(&mut s, 32, upload(0x1016, 1)),
            SdoResponse::InitiateUpload {
                index: 0x1016,
                sub: 1,
                data: InitiateData::Expedited(
                    proto::canopen::sdo::Expedited::new(&[0x58, 0x02, 0x01, 0x00]).unwrap()
                ),
            }
        );
        s.receive(&frame(0x701, &[0x05]), 10 * MS);
        // Each of its inverters reports it, 600 ms after the beat: the SK TU4-EIP's four
        // (nodes 32…38), the SK TU3-POL's eight (32…46, BU 2200 §4.1).
        let out = run(&mut s, 11, 700);
        let ids: Vec<(u64, u16)> = out.iter().map(|(t, f)| (*t, f.id())).collect();
        let want: Vec<(u64, u16)> = (0..u16::from(product.max_inverters()))
            .map(|k| (610, 0x0A0 + 2 * k))
            .collect();
        assert_eq!(want.len(), if product == Product::Tu3Pol { 8 } else { 4 });
        assert_eq!(ids, want);
        assert_eq!(&out[0].1.data()[3..5], &error.to_le_bytes());
        assert_eq!(p700(&mut s, 1).0, i32::from(error));
    }
}

#[test]
fn p748_shows_the_nodes_nmt_state() {
    let mut s = segment();
    let p748 = |s: &mut Segment| match sdo(s, 36, upload(0x22EC, 1)) {
        SdoResponse::InitiateUpload {
            data: InitiateData::Expedited(e),
            ..
        } => e.data()[0],
        other => panic!("{other:?}"),
    };
    assert_eq!(p748(&mut s), 127);
    s.receive(&frame(0, &[NmtCommand::START.0, 36]), MS);
    assert_eq!(p748(&mut s), 5);
    s.receive(&frame(0, &[NmtCommand::ENTER_PRE_OPERATIONAL.0, 36]), MS);
    assert_eq!(p748(&mut s), 127);
}

/// Node `node`'s heartbeat every 10 ms (1017h), then the segment polled up to 50 ms.
fn heartbeat_every_10ms(s: &mut Segment, node: u8) {
    let heartbeat = [0x2B, 0x17, 0x10, 0x00, 10, 0, 0, 0];
    assert!(matches!(
        sdo(s, node, heartbeat),
        SdoResponse::InitiateDownload { .. }
    ));
}

/// What the segment sends on its own from `from` to `to` ms, polled every ms.
fn sent(s: &mut Segment, from: u32, to: u32) -> Vec<CanFrame> {
    (from..to).flat_map(|t| s.poll(t * MS)).collect()
}

/// ISO 11898-1 fault confinement: a node bus off takes no part in the bus (no heartbeat, no
/// SDO answer) while the others serve on; after the recovery time it sends CiA 301's EMCY
/// 8140h "recovered from bus off" and its heartbeat again.
#[test]
fn a_node_bus_off_is_silent_then_recovers_with_emcy_8140h() {
    let mut s = segment();
    heartbeat_every_10ms(&mut s, 34);
    assert!(sent(&mut s, 2, 30).iter().any(|f| f.id() == 0x722));
    let fi2 = Inverter::new(2).unwrap();
    assert_eq!(s.inject_fault(fi2, super::BUS_OFF), Ok(()));
    // Bus off from 29 ms (the last time the segment was given) to 229 ms.
    let quiet = sent(&mut s, 30, 150);
    assert!(!quiet.iter().any(|f| f.id() & 0x7F == 34), "{quiet:?}");
    let request = frame(0x622, &upload(0x1000, 0));
    assert!(s.receive(&request, 150 * MS).is_empty(), "no SDO answer");
    assert!(matches!(
        sdo(&mut s, 32, upload(0x1000, 0)),
        SdoResponse::InitiateUpload { .. }
    ));
    assert_eq!(s.next_due(), Some(29 * MS + super::RECOVERY));
    assert!(s.take_error_frames().is_empty(), "bus off is silent");
    let back = sent(&mut s, 150, 260);
    let from_34: Vec<&CanFrame> = back.iter().filter(|f| f.id() & 0x7F == 34).collect();
    // EMCY 0A2h: 8140h, error register generic + communication (11h), then the heartbeat.
    assert_eq!(
        from_34[0],
        &frame(0x0A2, &[0x40, 0x81, 0x11, 0, 0, 0, 0, 0])
    );
    assert_eq!(from_34[1], &frame(0x722, &[0x7F]));
    assert!(from_34.len() >= 4, "heartbeats again: {from_34:?}");
    // And the EMCY of the E10.0 the SK 5x0P reported when it went bus off (7585h, BU 0620
    // §5.3), held back until then.
    assert_eq!(from_34[2].id(), 0x0A2);
    assert_eq!(from_34[2].data()[..2], [0x85, 0x75]);
    assert_eq!(
        from_34.iter().filter(|f| f.id() == 0x0A2).count(),
        2,
        "two EMCY"
    );
    assert!(matches!(
        sdo(&mut s, 34, upload(0x1000, 0)),
        SdoResponse::InitiateUpload { .. }
    ));
}

/// A transceiver that destroys FI 3's frames: every other node, and a listener, sees error
/// frames; the frame goes through once retransmitted, and the nodes serve on.
#[test]
fn error_frames_are_kept_apart_and_the_nodes_serve_on() {
    let mut s = segment();
    let fi3 = Inverter::new(3).unwrap();
    assert_eq!(s.inject_fault(fi3, super::ERROR_FRAMES), Ok(()));
    assert!(s.take_error_frames().is_empty(), "nothing sent yet");
    // Its SDO answer is destroyed 8 times, then goes through.
    assert!(matches!(
        sdo(&mut s, 36, upload(0x1000, 0)),
        SdoResponse::InitiateUpload { .. }
    ));
    let errors = s.take_error_frames();
    assert_eq!(errors.len(), usize::from(super::BURST));
    assert!(errors
        .iter()
        .all(|(t, e)| *t == MS && *e == super::bus_error()));
    assert_eq!(super::bus_error().class.0, 0x088);
    // The next frames go through untouched, the other nodes' too.
    sdo(&mut s, 36, upload(0x1000, 0));
    sdo(&mut s, 32, upload(0x1000, 0));
    assert!(s.take_error_frames().is_empty());
}

/// Error passive: CiA 301's EMCY 8120h "CAN in error passive mode"; the node keeps
/// communicating.
#[test]
fn error_passive_sends_emcy_8120h_and_serves_on() {
    let mut s = segment();
    let fi3 = Inverter::new(3).unwrap();
    assert_eq!(s.inject_fault(fi3, super::ERROR_PASSIVE), Ok(()));
    assert_eq!(s.next_due(), Some(Duration::ZERO), "the EMCY is due");
    let out = s.poll(MS);
    assert_eq!(out, vec![frame(0x0A4, &[0x20, 0x81, 0x11, 0, 0, 0, 0, 0])]);
    assert!(s.poll(2 * MS).is_empty(), "once");
    assert!(matches!(
        sdo(&mut s, 36, upload(0x1000, 0)),
        SdoResponse::InitiateUpload { .. }
    ));
    // An unknown node's fault is refused; the interface's own `bus-off` is not the node's.
    let mut config = DeviceConfig::new(Product::Tu3Eip);
    config.inverters = 1;
    let mut one = Segment::new(config).unwrap();
    one.poll(Duration::ZERO);
    let e = one.inject_fault(Inverter::new(2).unwrap(), super::BUS_OFF);
    assert_eq!(e, Err("FI 2 is not on the system bus".into()));
    assert_eq!(
        one.inject_fault(Inverter::new(1).unwrap(), "bus-off"),
        Ok(())
    );
    let request = frame(0x620, &upload(0x1000, 0));
    assert_eq!(one.receive(&request, MS).len(), 1, "node 32 still answers");
}

/// Bus off, a node hears nothing either: its inverter's P120 monitoring counts that silence
/// as it counts any, here where the consumer time (150 ms) is shorter than the time bus off;
/// with the factory 600 ms it does not trip. Behind a module (SK TU3-EIP: E10.8), whose SK 54xE
/// reports nothing for its own bus off.
#[test]
fn a_node_bus_off_hears_nothing_and_its_p120_monitoring_counts_the_silence() {
    let mut s = Segment::new(DeviceConfig::new(Product::Tu3Eip)).unwrap();
    s.poll(Duration::ZERO);
    // FI 1 (node 32) watches the module's heartbeat (node 1) for 150 ms (1016h:01), FI 2
    // (node 34) for the factory 600 ms; both P120 [-01] = 1 "Auto". The module beats every
    // 50 ms (operational, 05h).
    let consumer = [0x23, 0x16, 0x10, 0x01, 150, 0, 1, 0];
    assert!(matches!(
        sdo(&mut s, 32, consumer),
        SdoResponse::InitiateDownload { .. }
    ));
    let mut out = Vec::new();
    let beat_until = |s: &mut Segment, from: u64, to: u64, out: &mut Vec<(u64, CanFrame)>| {
        for t in from..=to {
            if t % 50 == 0 {
                out.extend(
                    s.receive(&frame(0x701, &[0x05]), Duration::from_millis(t))
                        .into_iter()
                        .map(|f| (t, f)),
                );
            }
            out.extend(s.poll(Duration::from_millis(t)).into_iter().map(|f| (t, f)));
        }
    };
    beat_until(&mut s, 2, 300, &mut out);
    assert!(out.is_empty(), "{out:?}");
    for fi in [1, 2] {
        let fi = Inverter::new(fi).unwrap();
        assert_eq!(s.inject_fault(fi, super::BUS_OFF), Ok(()));
    }
    assert_eq!(
        p700(&mut s, 1),
        (0, 0),
        "an SK 54xE reports nothing for bus off"
    );
    beat_until(&mut s, 301, 700, &mut out);
    assert_eq!(p700(&mut s, 1).0, 108, "E10.8 after 150 ms unheard");
    assert_eq!(p700(&mut s, 2), (0, 0), "200 ms bus off < 600 ms");
    // Neither sent anything while bus off; back at 500 ms each sends EMCY 8140h (FI 1's error
    // register with its error and the communication bit), then FI 1 the EMCY of E10.8.
    assert!(out.iter().all(|(t, _)| *t == 500), "{out:?}");
    let ids: Vec<u16> = out.iter().map(|(_, f)| f.id()).collect();
    assert_eq!(ids, [0x0A0, 0x0A2, 0x0A0]);
    assert!(out[..2].iter().all(|(_, f)| f.data()[..2] == [0x40, 0x81]));
    assert_eq!(out[1].1.data()[2], 0x11);
    assert_eq!(out[0].1.data()[2] & 0x11, 0x11);
    assert_ne!(out[2].1.data()[..2], [0x40, 0x81]);
    assert_eq!(&out[2].1.data()[3..5], &108u16.to_le_bytes());
}

/// BU 0620 §5.3 (p. 94): an SK 5x0P whose CAN is bus off reports E10.0 with 7585h "CAN in Bus
/// Off state"; its EMCY cannot go while bus off: it follows 8140h once the node is back.
#[test]
fn behind_the_sk_550p_an_inverter_bus_off_reports_e10_0_with_7585h() {
    let mut s = segment();
    let fi2 = Inverter::new(2).unwrap();
    assert_eq!(s.inject_fault(fi2, super::BUS_OFF), Ok(()));
    assert_eq!(p700(&mut s, 2), (100, 0x7585));
    assert_eq!(p700(&mut s, 3), (0, 0));
    let out = run(&mut s, 1, 300);
    let from_34: Vec<&(u64, CanFrame)> = out.iter().filter(|(_, f)| f.id() == 0x0A2).collect();
    assert_eq!(from_34.len(), 2, "{out:?}");
    assert!(from_34.iter().all(|(t, _)| *t == 200));
    assert_eq!(from_34[0].1.data()[..2], [0x40, 0x81]);
    assert_eq!(from_34[0].1.data()[2] & 0x11, 0x11);
    // 7585h, error register, then P700 = 100 and FI 2 (the EMCY of `objects::emergency_of`).
    assert_eq!(from_34[1].1.data()[..2], [0x85, 0x75]);
    // A second bus off while the error stands changes nothing in P700.
    s.inject_fault(fi2, super::BUS_OFF).unwrap();
    assert_eq!(p700(&mut s, 2), (100, 0x7585));
}
