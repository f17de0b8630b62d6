//! CoE over the mailbox: SDO transfers of P102 of FI 3 at 3066h (BU 0620 §2.2.7), the objects
//! of §2.2.7.1, every abort code the slave answers, mailbox errors.

use super::*;

/// P102 "Acceleration time" of FI 3: index 2000h + 1000h + 66h = 3066h (§2.2.7 example);
/// set-dependent, so sub-index 1..4 = parameter set 1..4 and sub-index 0 = 4.
const P102_FI3: u16 = 0x3066;

fn code(m: &mut Master, index: u16, sub: u8, data: &[u8]) -> u32 {
    m.download(index, sub, data).unwrap_err()
}

#[test]
fn expedited_upload_and_download_of_p102_fi3() {
    let mut m = Master::new(3);
    m.preop();
    assert_eq!(
        m.upload(P102_FI3, 0),
        Ok(vec![4]),
        "sub-index 0: the array size"
    );
    assert_eq!(m.upload(P102_FI3, 1), Ok(vec![200, 0]), "2.00 s");
    assert_eq!(m.download(P102_FI3, 3, &[0xE8, 0x03]), Ok(()));
    assert_eq!(
        m.upload(P102_FI3, 3),
        Ok(vec![0xE8, 0x03]),
        "set 3: 10.00 s"
    );
    assert_eq!(m.upload(P102_FI3, 1), Ok(vec![200, 0]), "set 1 unchanged");
    // The same parameter seen by the store: FI 3, set 3.
    let fi3 = proto::nord::Inverter::new(3).unwrap();
    let store = m
        .slave
        .device_mut()
        .store(crate::link::Unit::Inverter(fi3))
        .unwrap();
    let p102 = proto::nord::ParamNumber::new(102).unwrap();
    assert_eq!(
        store.read(p102, proto::nord::ParamSet::new(3).ok(), None),
        Ok(1000)
    );
    // An expedited download without size indicated takes the object's 2 bytes of the 4.
    let resp = m.sdo(&[0x22, 0x66, 0x30, 0x02, 0x2C, 0x01, 0xAA, 0xBB]);
    assert_eq!(resp[0], 0x60);
    assert_eq!(m.upload(P102_FI3, 2), Ok(vec![0x2C, 0x01]));
}

#[test]
fn normal_and_segmented_transfers_of_p102_fi3() {
    let mut m = Master::new(3);
    m.preop();
    // Normal download: size 2 indicated, the data in the request.
    let resp = m.sdo(&[0x21, 0x66, 0x30, 0x01, 0x02, 0, 0, 0, 0xF4, 0x01]);
    assert_eq!(resp[..4], [0x60, 0x66, 0x30, 0x01]);
    assert_eq!(m.upload(P102_FI3, 1), Ok(vec![0xF4, 0x01]), "5.00 s");
    // Segmented download: size 2, one byte in the request, one in a segment (toggle 0).
    let resp = m.sdo(&[0x21, 0x66, 0x30, 0x04, 0x02, 0, 0, 0, 0x58]);
    assert_eq!(resp[0], 0x60);
    // Segment: toggle 0, 6 unused bytes (n = 6 << 1), last; 7 data bytes with padding.
    let resp = m.sdo(&[0x0D, 0x02, 0, 0, 0, 0, 0, 0]);
    assert_eq!(resp[0], 0x20, "segment response, toggle 0");
    assert_eq!(m.upload(P102_FI3, 4), Ok(vec![0x58, 0x02]), "6.00 s");
    // Complete access upload: sub-index 0 (U8 + padding) and the four sets: 10 bytes, a
    // normal upload.
    let resp = m.sdo(&[0x50, 0x66, 0x30, 0x00, 0, 0, 0, 0]);
    assert_eq!(resp[0], 0x51, "normal, size indicated, complete access");
    assert_eq!(
        resp[4..18],
        [10, 0, 0, 0, 4, 0, 0xF4, 0x01, 200, 0, 200, 0, 0x58, 0x02]
    );
    // Complete access download of the four sets from sub-index 1.
    let mut req = vec![0x31, 0x66, 0x30, 0x01, 8, 0, 0, 0];
    req.extend([1, 0, 2, 0, 3, 0, 4, 0]);
    assert_eq!(m.sdo(&req)[0], 0x70);
    assert_eq!(m.upload(P102_FI3, 4), Ok(vec![4, 0]));
}

#[test]
fn segmented_upload_with_a_small_mailbox_and_toggle_checking() {
    let mut m = Master::new(3);
    m.mailbox_sms(128, 20);
    assert_eq!(m.request(0x02), (0x02, 0));
    // Complete access to 3066h: 10 bytes, of which a 20-byte mailbox carries 4 in the
    // initiate response and 11 per segment.
    let resp = m.sdo(&[0x50, 0x66, 0x30, 0x00, 0, 0, 0, 0]);
    assert_eq!(resp[..8], [0x51, 0x66, 0x30, 0x00, 10, 0, 0, 0]);
    assert_eq!(resp[8..12], [4, 0, 200, 0]);
    let seg = m.sdo(&[0x60, 0, 0, 0, 0, 0, 0, 0]);
    // Toggle 0, last, 6 bytes: n = 1 unused of 7.
    assert_eq!(seg[0], 0x03);
    assert_eq!(seg[1..7], [200, 0, 200, 0, 200, 0]);
    // The device name, 18 bytes: segments of 11, then 7 − toggle alternating.
    let first = m.sdo(&[0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0]);
    assert_eq!((first[0], first[4]), (0x41, 18));
    let mut name = first[8..12].to_vec();
    let s1 = m.sdo(&[0x60, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(s1[0] & 0x11, 0x00, "toggle 0, not last");
    name.extend(&s1[1..]);
    // Wrong toggle (0 again): 05030000h.
    let abort = m.sdo(&[0x60, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(
        (abort[0], abort[4..8].to_vec()),
        (0x80, 0x0503_0000u32.to_le_bytes().to_vec())
    );
    assert_eq!(String::from_utf8_lossy(&name[..15]), "NORDAC PRO SK 5");
}

#[test]
fn the_objects_of_2_2_7_1() {
    let mut m = Master::new(2);
    m.preop();
    assert_eq!(m.upload(0x1018, 0), Ok(vec![4]));
    assert_eq!(m.upload(0x1018, 1), Ok(0x538u32.to_le_bytes().to_vec()));
    assert_eq!(m.upload(0x1018, 2), Ok(0x550u32.to_le_bytes().to_vec()));
    assert_eq!(m.upload(0x1000, 0), Ok(vec![0; 4]));
    assert_eq!(m.upload(0x1008, 0), Ok(b"NORDAC PRO SK 550P".to_vec()));
    assert_eq!(m.upload(0x1600, 0), Ok(vec![6]));
    assert_eq!(
        m.upload(0x1601, 1),
        Ok(0x7010_0110u32.to_le_bytes().to_vec())
    );
    assert_eq!(
        m.upload(0x1A00, 6),
        Ok(0x6000_0610u32.to_le_bytes().to_vec())
    );
    assert_eq!(
        m.upload(0x1602, 0),
        Err(0x0602_0000),
        "two inverters: no 1602h"
    );
    assert_eq!(m.upload(0x1C00, 3), Ok(vec![3]));
    assert_eq!(m.upload(0x1C12, 0), Ok(vec![2]));
    assert_eq!(m.upload(0x1C13, 2), Ok(vec![0x01, 0x1A]));
    assert_eq!(m.upload(0x1C10, 0), Ok(vec![0]));
    // Complete access as SOEM reads the assignment: count, padding, indices.
    let resp = m.sdo(&[0x50, 0x12, 0x1C, 0x00, 0, 0, 0, 0]);
    assert_eq!(resp[0], 0x51);
    assert_eq!(resp[8..14], [2, 0, 0x00, 0x16, 0x01, 0x16]);
    // The interface's own parameters answer on FI 1: P870 = 2 (EtherCAT), P850 is the
    // second address.
    assert_eq!(m.upload(0x2000 + 870, 0), Ok(vec![2, 0]));
    assert_eq!(m.upload(0x2000 + 850, 0), Ok(vec![0, 0]));
    assert_eq!(m.download(0x2000 + 850, 0, &[0x10, 0x00]), Ok(()));
    assert_eq!(m.slave.second_address_setting(), 0x10);
    assert_eq!(m.slave.device_id(), 0, "adopted at the next power-on");
}

#[test]
fn every_abort_code_the_slave_answers() {
    let mut m = Master::new(4);
    m.preop();
    // 06020000h: no such object (and P1000-ish indices beyond 999 of FI 1).
    assert_eq!(m.upload(0x1234, 0), Err(0x0602_0000));
    assert_eq!(code(&mut m, 0x1234, 0, &[1, 0]), 0x0602_0000);
    assert_eq!(m.upload(0x2000 + 1000, 0), Err(0x0602_0000));
    // 06090011h: no such sub-index (1018h:09; P102 has sets 1..4).
    assert_eq!(m.upload(0x1018, 9), Err(0x0609_0011));
    assert_eq!(m.upload(P102_FI3, 5), Err(0x0609_0011));
    assert_eq!(
        m.upload(0x2000 + 870, 1),
        Err(0x0609_0011),
        "plain: value at 0"
    );
    // 06010002h: write to read-only (BU 0620 §2.2.7.2 prints 06020002h).
    assert_eq!(code(&mut m, 0x1018, 1, &[0; 4]), 0x0601_0002);
    assert_eq!(code(&mut m, 0x1000, 0, &[0; 4]), 0x0601_0002);
    assert_eq!(
        code(&mut m, P102_FI3, 0, &[4]),
        0x0601_0002,
        "the array size"
    );
    assert_eq!(
        code(&mut m, 0x2000 + 717, 0, &[0, 0]),
        0x0601_0002,
        "P717 display"
    );
    // 06070012h / 06070013h: too long / too short for the 2-byte parameter.
    assert_eq!(code(&mut m, P102_FI3, 1, &[0xE8, 0x03, 0]), 0x0607_0012);
    assert_eq!(code(&mut m, P102_FI3, 1, &[0xE8]), 0x0607_0013);
    let resp = m.sdo(&[0x21, 0x66, 0x30, 0x01, 6, 0, 0, 0, 0xE8, 0x03, 0, 0, 0, 0]);
    assert_eq!(
        sdo_result(&resp),
        Err(0x0607_0012),
        "normal download of 6 bytes"
    );
    // 06090031h / 06090032h: above 320.00 s / below 0.
    assert_eq!(code(&mut m, 0x2066, 1, &[0x01, 0x7D]), 0x0609_0031);
    assert_eq!(code(&mut m, 0x2066, 1, &[0xFF, 0xFF]), 0x0609_0032);
    assert_eq!(code(&mut m, 0x2000 + 850, 0, &[0x01, 0x10]), 0x0609_0031);
    assert_eq!(m.upload(0x2066, 1), Ok(vec![200, 0]), "unchanged");
    // 05040001h: unknown command specifier; a segment without a transfer.
    assert_eq!(
        sdo_result(&m.sdo(&[0xA0, 0x66, 0x30, 1, 0, 0, 0, 0])),
        Err(0x0504_0001)
    );
    assert_eq!(
        sdo_result(&m.sdo(&[0x60, 0, 0, 0, 0, 0, 0, 0])),
        Err(0x0504_0001)
    );
    assert_eq!(
        sdo_result(&m.sdo(&[0x00, 0, 0, 0, 0, 0, 0, 0])),
        Err(0x0504_0001)
    );
    // 05030000h: a download segment with the wrong toggle.
    m.sdo(&[0x21, 0x66, 0x30, 0x01, 0x02, 0, 0, 0]);
    assert_eq!(
        sdo_result(&m.sdo(&[0x1D, 1, 0, 0, 0, 0, 0, 0])),
        Err(0x0503_0000)
    );
    // 05040005h: a download larger than the server takes.
    assert_eq!(
        sdo_result(&m.sdo(&[0x21, 0x66, 0x30, 0x01, 0, 0x10, 0, 0])),
        Err(0x0504_0005)
    );
    // 06010000h: complete access to a plain (VAR) object, or from sub-index 2.
    assert_eq!(
        sdo_result(&m.sdo(&[0x50, 0x00, 0x10, 0, 0, 0, 0, 0])),
        Err(0x0601_0000)
    );
    assert_eq!(
        sdo_result(&m.sdo(&[0x50, 0x66, 0x30, 2, 0, 0, 0, 0])),
        Err(0x0601_0000)
    );
    // 08000020h: FI 5 is not on the system bus of a 4-inverter device (§2.2.7.2 "no
    // communication between the bus interface and the frequency inverter").
    assert_eq!(m.upload(0x4066, 1), Err(0x0800_0020));
}

#[test]
fn mailbox_errors_and_retries() {
    let mut m = Master::new(1);
    m.preop();
    let error = |m: &mut Master, msg: &[u8]| {
        assert_eq!(m.mbx_write(msg), 1);
        let r = m.mbx_read().expect("a reply");
        assert_eq!((r[0], r[5] & 0x0F), (4, 0), "type 0: mailbox error");
        u16::from_le_bytes([r[8], r[9]])
    };
    // SoE (type 5): unsupported protocol 0002h.
    assert_eq!(error(&mut m, &[10, 0, 0, 0, 0, 0x15]), 0x0002);
    // Length 200 in a 128-byte mailbox: invalid size 0008h.
    assert_eq!(error(&mut m, &[200, 0, 0, 0, 0, 0x23]), 0x0008);
    // CoE with only 4 bytes of SDO: size too short 0006h; a bare byte too.
    assert_eq!(
        error(&mut m, &[6, 0, 0, 0, 0, 0x33, 0x00, 0x20, 0x40, 0x66]),
        0x0006
    );
    assert_eq!(error(&mut m, &[1, 0, 0, 0, 0, 0x43, 0x00]), 0x0006);
    // SDO information (service 8): service not supported 0004h.
    assert_eq!(
        error(
            &mut m,
            &[10, 0, 0, 0, 0, 0x53, 0, 0x80, 1, 0, 0, 0, 0, 0, 0, 0]
        ),
        0x0004
    );
    assert_eq!(m.slave.mailbox_errors(), 5);
    // A retry with the same counter is not served twice; a full mailbox refuses a write.
    m.counter = 0;
    assert_eq!(m.upload(0x1018, 1), Ok(0x538u32.to_le_bytes().to_vec()));
    let mut msg = vec![
        10, 0, 0, 0, 0, 0x13, 0x00, 0x20, 0x40, 0x18, 0x10, 1, 0, 0, 0, 0,
    ];
    assert_eq!(m.mbx_write(&msg), 1);
    assert!(m.mbx_read().is_none(), "counter 1 again: dropped");
    msg[5] = 0x23;
    assert_eq!(m.mbx_write(&msg), 1);
    assert_eq!(
        m.mbx_write(&msg),
        1,
        "served at once: the receive mailbox is free again"
    );
    let reply = m.mbx_read().expect("one reply");
    // Reading the empty send mailbox is refused.
    assert!(m.mbx_read().is_none());
    // Repeat request: SM1 activate bit 1 toggled → the last reply again, acknowledged in
    // 080Fh bit 1.
    m.fpwr(0x080E, &[0x03]);
    assert_eq!(m.fprd(0x080F, 1).data[0] & 0x02, 0x02);
    assert_eq!(m.mbx_read(), Some(reply));
}

#[test]
fn an_inverter_fault_sends_an_emergency() {
    let mut m = Master::new(2);
    m.preop();
    let fi2 = proto::nord::Inverter::new(2).unwrap();
    m.slave.device_mut().inject_fault(fi2, "10.3").unwrap();
    m.one(dg(0, 0, 0, &[0])); // any frame runs the timers
    let r = m.mbx_read().expect("an emergency");
    // CoE service 1; 7592h "Time-out through P513" (§5.3), register 11h, P700 = 103, FI 2.
    assert_eq!(r[5] & 0x0F, 3);
    assert_eq!(r[6..15], [0x00, 0x10, 0x92, 0x75, 0x11, 103, 0, 2, 0]);
}

/// `serve ecat --misbehave alarm=`: an emergency for an error the inverter does not have
/// waits in the send mailbox with the slave's next counter, as a real one does; in Init, with
/// no mailbox, there is nowhere to put it; the inverter's P700 stays 0.
#[test]
fn a_spurious_emergency_waits_in_the_send_mailbox() {
    use crate::endpoint::Endpoint;
    let mut m = Master::new(1);
    assert_eq!(m.slave.raise_alarm(ms(0)), None, "Init: no mailbox yet");
    m.preop();
    let raised = m
        .slave
        .raise_alarm(ms(1))
        .expect("raised in Pre-Operational");
    assert!(raised.outputs.is_empty(), "the master fetches it");
    assert!(
        raised
            .what
            .contains("CoE emergency 7591h, error register 11h, data 66 00 01 00 00")
            && raised.what.ends_with("mailbox #1"),
        "{}",
        raised.what
    );
    // SM1 status (080Dh) bit 3: mailbox full.
    assert_eq!(m.fprd(0x080D, 1).data[0] & 0x08, 0x08);
    let r = m.mbx_read().expect("the emergency");
    // Mailbox header: length 10, address 0, channel/priority 0, type 3 (CoE), counter 1 in
    // bits 4..6 (ETG.1000.6 §5.6); CoE service 1 (emergency), 7591h, register 11h, P700 102
    // (66h 00h), FI 1 (BU 0620 §5.3).
    assert_eq!(r[..6], [10, 0, 0, 0, 0, 0x13]);
    assert_eq!(r[6..16], [0x00, 0x10, 0x91, 0x75, 0x11, 102, 0, 1, 0, 0]);
    assert_eq!(m.upload(0x22BC, 1), Ok(vec![0, 0]), "P700 [-01]: no error");
    // The next one counts on: #2 is the SDO answer above, #3 this one.
    assert!(m.slave.raise_alarm(ms(2)).unwrap().what.ends_with("#3"));
}

/// Behind the SK 550P, FI 2…8 are on the system bus: a CoE transfer of FI 3's P102 is an SDO
/// transfer with FI 3's node, whose abort comes back as the CoE abort; FI 1's own parameters
/// (2066h) are the device's, no node's.
#[test]
fn fi3s_parameters_are_served_by_its_node_on_the_system_bus() {
    let mut m = Master::new(3);
    m.preop();
    let fi = |n| proto::nord::Inverter::new(n).unwrap();
    let served = |m: &Master, n| m.slave.device().node_server(fi(n)).map(|s| s.counts());
    assert_eq!(m.download(P102_FI3, 3, &[0xE8, 0x03]), Ok(()));
    assert_eq!(m.upload(P102_FI3, 3), Ok(vec![0xE8, 0x03]));
    assert_eq!(served(&m, 3), Some((2, 0)));
    // 32001 (7D01h) is above P102's 32000: the node's 06090031h.
    assert_eq!(code(&mut m, P102_FI3, 3, &[0x01, 0x7D]), 0x0609_0031);
    assert_eq!(served(&m, 3), Some((3, 1)));
    assert_eq!(m.upload(0x2066, 1), Ok(vec![200, 0]));
    assert_eq!(served(&m, 2), Some((0, 0)));
    assert_eq!(served(&m, 1), Some((0, 0)));
}
