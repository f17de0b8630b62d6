//! The slave fed byte-level frames as a master sends them.
//!
//! Frames: Ethernet II (destination FF..FF, source 00:11:22:33:44:55, EtherType 88A4h), the
//! EtherCAT header (length, type 1), datagrams (command, index, ADP, ADO, length with the
//! "more" bit, IRQ 0, data, working counter 0) — ETG.1000.4 §5.3–§5.4.

use std::time::Duration;

use proto::nord::led::Pattern;
use proto::nord::nmt::EcState;
use proto::nord::Product;

use super::*;
use crate::device::{Device, DeviceConfig};

mod coe;
mod pdo;

const STATION: u16 = 0x1001;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

/// One datagram of a frame: command, ADP, ADO, data.
#[derive(Debug, Clone)]
struct Dg {
    cmd: u8,
    adp: u16,
    ado: u16,
    data: Vec<u8>,
}

fn dg(cmd: u8, adp: u16, ado: u16, data: &[u8]) -> Dg {
    Dg {
        cmd,
        adp,
        ado,
        data: data.to_vec(),
    }
}

/// What came back for a datagram.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Back {
    adp: u16,
    data: Vec<u8>,
    wkc: u16,
}

fn frame(dgs: &[Dg]) -> Vec<u8> {
    let mut f = vec![0xFF; 6]; // destination: broadcast
    f.extend([0x00, 0x11, 0x22, 0x33, 0x44, 0x55]); // source: the master
    f.extend([0x88, 0xA4]); // EtherType EtherCAT
    let len: usize = dgs.iter().map(|d| 12 + d.data.len()).sum();
    f.extend((len as u16 | 0x1000).to_le_bytes()); // length, type 1 (DLPDU)
    for (i, d) in dgs.iter().enumerate() {
        f.push(d.cmd);
        f.push(i as u8); // index
        f.extend(d.adp.to_le_bytes());
        f.extend(d.ado.to_le_bytes());
        let more = if i + 1 < dgs.len() { 0x8000 } else { 0 };
        f.extend((d.data.len() as u16 | more).to_le_bytes());
        f.extend([0, 0]); // IRQ
        f.extend(&d.data);
        f.extend([0, 0]); // working counter
    }
    f
}

fn parse_back(f: &[u8]) -> Vec<Back> {
    let mut out = Vec::new();
    let mut at = 16;
    loop {
        let len = usize::from(u16::from_le_bytes([f[at + 6], f[at + 7]]) & 0x7FF);
        let w = at + 10 + len;
        out.push(Back {
            adp: u16::from_le_bytes([f[at + 2], f[at + 3]]),
            data: f[at + 10..w].to_vec(),
            wkc: u16::from_le_bytes([f[w], f[w + 1]]),
        });
        if f[at + 7] & 0x80 == 0 {
            break;
        }
        at = w + 2;
    }
    out
}

/// The data of an upload response (expedited or normal), or the abort code.
fn sdo_result(resp: &[u8]) -> Result<Vec<u8>, u32> {
    let code = u32::from_le_bytes([resp[4], resp[5], resp[6], resp[7]]);
    match resp[0] {
        0x80 => Err(code),
        c if c & 0xE3 == 0x43 => Ok(resp[4..8 - usize::from((c >> 2) & 3)].to_vec()),
        c if c & 0xE3 == 0x41 => Ok(resp[8..8 + code as usize].to_vec()),
        c => panic!("unexpected response {c:02X}"),
    }
}

struct Master {
    slave: Slave,
    now: Duration,
    counter: u8,
}

impl Master {
    fn new(inverters: u8) -> Master {
        Master::with(inverters, SlaveConfig::default())
    }

    fn with(inverters: u8, config: SlaveConfig) -> Master {
        let device = Device::new(DeviceConfig {
            inverters,
            ..DeviceConfig::new(Product::Sk550p)
        });
        Master {
            slave: Slave::with_config(device, config).unwrap(),
            now: ms(100),
            counter: 0,
        }
    }

    fn send(&mut self, dgs: &[Dg]) -> Vec<Back> {
        self.now += ms(1);
        let mut f = frame(dgs);
        assert_eq!(self.slave.process(&mut f, self.now), Processed::Forwarded);
        assert_eq!(f[6], 0x02, "locally administered bit set");
        parse_back(&f)
    }

    fn one(&mut self, d: Dg) -> Back {
        self.send(&[d]).remove(0)
    }

    fn fprd(&mut self, ado: u16, len: usize) -> Back {
        self.one(dg(4, STATION, ado, &vec![0; len]))
    }

    fn fpwr(&mut self, ado: u16, data: &[u8]) -> u16 {
        self.one(dg(5, STATION, ado, data)).wkc
    }

    fn u16_at(&mut self, ado: u16) -> u16 {
        let b = self.fprd(ado, 2).data;
        u16::from_le_bytes([b[0], b[1]])
    }

    /// Writes AL control and returns (AL status, AL status code).
    fn request(&mut self, control: u16) -> (u16, u16) {
        assert_eq!(self.fpwr(0x0120, &control.to_le_bytes()), 1);
        (self.u16_at(0x0130), self.u16_at(0x0134))
    }

    /// Station address, then SM0/SM1 as the SII says (mailbox sizes `out`/`inn`).
    fn mailbox_sms(&mut self, out: u16, inn: u16) {
        assert_eq!(self.one(dg(2, 0, 0x0010, &STATION.to_le_bytes())).wkc, 1);
        let mut sm = Vec::new();
        sm.extend([0x00, 0x10]); // SM0 start 1000h
        sm.extend(out.to_le_bytes()); // length
        sm.extend([0x26, 0x00, 0x01, 0x00]); // control, status, activate, PDI
        sm.extend([0x80, 0x10]); // SM1 start 1080h
        sm.extend(inn.to_le_bytes());
        sm.extend([0x22, 0x00, 0x01, 0x00]);
        assert_eq!(self.fpwr(0x0800, &sm), 1);
    }

    fn preop(&mut self) {
        self.mailbox_sms(128, 128);
        assert_eq!(self.request(0x02), (0x02, 0));
    }

    /// SM2/SM3 (12 bytes per inverter) and FMMU0 (logical 0 → outputs), FMMU1 (logical 100h
    /// → inputs).
    fn pd_sms(&mut self, inverters: u8) {
        let len = u16::from(inverters) * 12;
        let mut sm = Vec::new();
        sm.extend([0x00, 0x11]); // SM2 start 1100h
        sm.extend(len.to_le_bytes());
        sm.extend([0x64, 0x00, 0x01, 0x00]);
        sm.extend([0x00, 0x14]); // SM3 start 1400h
        sm.extend(len.to_le_bytes());
        sm.extend([0x20, 0x00, 0x01, 0x00]);
        assert_eq!(self.fpwr(0x0810, &sm), 1);
        let fmmu = |log: u32, phys: u16, ty: u8| {
            let mut f = log.to_le_bytes().to_vec(); // logical start
            f.extend(len.to_le_bytes()); // length
            f.extend([0, 7]); // start bit, stop bit
            f.extend(phys.to_le_bytes()); // physical start
            f.extend([0, ty, 1, 0, 0, 0]); // bit, type, activate, reserved
            f
        };
        let mut both = fmmu(0, 0x1100, 2);
        both.extend(fmmu(0x100, 0x1400, 1));
        assert_eq!(self.fpwr(0x0600, &both), 1);
    }

    /// Writes a mailbox message (header and body) into SM0, padded to its 128 bytes.
    fn mbx_write(&mut self, msg: &[u8]) -> u16 {
        let mut buf = msg.to_vec();
        buf.resize(self.sm_len(0), 0);
        self.fpwr(0x1000, &buf)
    }

    fn sm_len(&mut self, n: u16) -> usize {
        usize::from(self.u16_at(0x0802 + 8 * n))
    }

    /// Reads SM1 whole; `None` when empty (working counter 0).
    fn mbx_read(&mut self) -> Option<Vec<u8>> {
        let len = self.sm_len(1);
        let b = self.fprd(0x1080, len);
        (b.wkc == 1).then_some(b.data)
    }

    /// A CoE SDO request (the 8+ bytes after the CoE header) in a mailbox with the next
    /// counter; the reply's bytes after the CoE header, or the whole reply if not CoE.
    fn sdo(&mut self, request: &[u8]) -> Vec<u8> {
        self.counter = self.counter % 7 + 1;
        let mut msg = ((request.len() + 2) as u16).to_le_bytes().to_vec(); // length
        msg.extend([0, 0, 0, 0x03 | self.counter << 4]); // address, channel, CoE + counter
        msg.extend([0x00, 0x20]); // CoE: number 0, service 2 (SDO request)
        msg.extend(request);
        assert_eq!(self.mbx_write(&msg), 1, "receive mailbox free");
        let reply = self.mbx_read().expect("a reply");
        let len = usize::from(u16::from_le_bytes([reply[0], reply[1]]));
        assert_eq!(reply[5] & 0x0F, 3, "CoE reply: {reply:02X?}");
        let service = if reply[8] == 0x80 { 2 } else { 3 };
        assert_eq!(
            reply[7] >> 4,
            service,
            "SDO response, an abort as SDO request"
        );
        reply[8..6 + len].to_vec()
    }

    /// Expedited or normal upload; the data or the abort code.
    fn upload(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
        let mut r = vec![0x40]; // initiate upload
        r.extend(index.to_le_bytes());
        r.extend([sub, 0, 0, 0, 0]);
        sdo_result(&self.sdo(&r))
    }

    /// Expedited download with size; `Ok` or the abort code.
    fn download(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let n = 4 - data.len().min(4) as u8;
        let mut r = vec![0x23 | n << 2]; // initiate download, expedited, size indicated
        r.extend(index.to_le_bytes());
        r.push(sub);
        let mut d = data.to_vec();
        d.resize(4, 0);
        r.extend(d);
        let resp = self.sdo(&r);
        match resp[0] {
            0x60 => Ok(()),
            0x80 => Err(u32::from_le_bytes([resp[4], resp[5], resp[6], resp[7]])),
            c => panic!("unexpected response {c:02X}"),
        }
    }

    fn go_op(&mut self, inverters: u8) {
        self.preop();
        self.pd_sms(inverters);
        assert_eq!(self.request(0x04), (0x04, 0));
        assert_eq!(self.request(0x08), (0x08, 0));
    }
}

#[test]
fn auto_increment_addressing_and_working_counters() {
    let mut m = Master::new(1);
    // APRD 0000h: ADP 0 addresses the slave, which increments ADP.
    let b = m.one(dg(1, 0, 0x0000, &[0; 8]));
    assert_eq!(
        (b.adp, b.wkc, b.data[0], b.data[4], b.data[5]),
        (1, 1, 0x80, 8, 8)
    );
    // ADP FFFFh (the second slave's position): not addressed, incremented to 0.
    let b = m.one(dg(1, 0xFFFF, 0x0000, &[0; 2]));
    assert_eq!((b.adp, b.wkc, b.data.clone()), (0, 0, vec![0, 0]));
    // APWR the station address, then FPRD with it.
    assert_eq!(m.one(dg(2, 0, 0x0010, &STATION.to_le_bytes())).wkc, 1);
    assert_eq!(m.fprd(0x0010, 2).data, STATION.to_le_bytes());
    assert_eq!(
        m.one(dg(4, 0x2222, 0x0010, &[0; 2])).wkc,
        0,
        "other station"
    );
    // FPRW: +1 read, +2 write; the old value comes back.
    let b = m.one(dg(6, STATION, 0x0200, &[0x34, 0x12]));
    assert_eq!((b.wkc, b.data.clone()), (3, vec![0, 0]));
    assert_eq!(m.u16_at(0x0200), 0x1234);
    // BRD ORs the register into the data; BWR/BRW count as writes.
    let b = m.one(dg(7, 0, 0x0130, &[0x10, 0x00]));
    assert_eq!((b.adp, b.wkc, b.data.clone()), (1, 1, vec![0x11, 0x00]));
    assert_eq!(m.one(dg(8, 0, 0x0200, &[0, 0])).wkc, 1);
    assert_eq!(m.one(dg(9, 0, 0x0200, &[1, 0])).wkc, 3);
    // A write to a read-only register is ignored but counted.
    assert_eq!(m.fpwr(0x0130, &[8, 0]), 1);
    assert_eq!(m.u16_at(0x0130), 1);
    // ARMW: ADP 0 reads; FRMW from another station writes.
    let b = m.one(dg(13, 0, 0x0200, &[0; 2]));
    assert_eq!((b.wkc, b.adp, b.data.clone()), (1, 1, vec![1, 0]));
    assert_eq!(m.one(dg(14, 0x0999, 0x0200, &[7, 0])).wkc, 1);
    assert_eq!(m.u16_at(0x0200), 7);
    // Unknown command 0Fh: not processed.
    assert_eq!(m.one(dg(0x0F, 0, 0x0000, &[0; 2])).wkc, 0);
    // Several datagrams in one frame.
    let backs = m.send(&[dg(4, STATION, 0x0000, &[0]), dg(1, 0, 0x0005, &[0])]);
    assert_eq!(backs.iter().map(|b| b.wkc).collect::<Vec<_>>(), [1, 1]);
}

#[test]
fn the_alias_answers_once_enabled_in_dl_control() {
    let mut m = Master::new(1);
    m.one(dg(2, 0, 0x0010, &STATION.to_le_bytes()));
    // Alias 0 in the SII; write word 4, its checksum in word 7, and reload.
    let mut config: Vec<u8> = m.slave.sii_image()[..14].to_vec();
    config[8..10].copy_from_slice(&[0x34, 0x12]);
    let crc = proto::ecat::sii::crc8(&config);
    for (word, data) in [(4u32, [0x34, 0x12]), (7, [crc, 0])] {
        m.fpwr(0x0504, &word.to_le_bytes()); // word address
        m.fpwr(0x0508, &data); // data
        m.fpwr(0x0502, &[0x01, 0x02]); // write enable + write
    }
    m.fpwr(0x0502, &[0x00, 0x04]); // reload
    assert_eq!(m.u16_at(0x0502) & 0x0800, 0, "checksum right");
    assert_eq!(m.u16_at(0x0012), 0x1234);
    assert_eq!(
        m.one(dg(4, 0x1234, 0x0000, &[0])).wkc,
        0,
        "alias not enabled"
    );
    m.fpwr(0x0100, &[0, 0, 0, 1]); // DL control bit 24: station alias
    assert_eq!(m.one(dg(4, 0x1234, 0x0000, &[0])).wkc, 1);
    assert_eq!(m.slave.registers(0x0012, 2), vec![0x34, 0x12]);
}

#[test]
fn other_frames_pass_and_malformed_ones_are_dropped_and_counted() {
    let mut m = Master::new(1);
    let mut ip = frame(&[dg(1, 0, 0, &[0; 2])]);
    ip[12..14].copy_from_slice(&[0x08, 0x00]);
    let mut before = ip.clone();
    assert_eq!(m.slave.process(&mut ip, ms(1)), Processed::Passed);
    // Unprocessed: only the source address is marked, as on every frame leaving port 0.
    before[6] |= 0x02;
    assert_eq!(ip, before, "unchanged but for the source address");
    // EtherCAT header says 200 bytes, 14 follow.
    let mut lying = frame(&[dg(2, 0, 0x0010, &[0x05, 0x00])]);
    lying[14..16].copy_from_slice(&(200u16 | 0x1000).to_le_bytes());
    assert!(matches!(
        m.slave.process(&mut lying, ms(2)),
        Processed::Dropped(DropReason::Length { value: 200, .. })
    ));
    // Datagram length 100 in a frame of 2 data bytes.
    let mut long = frame(&[dg(2, 0, 0x0010, &[0x05, 0x00])]);
    long[22..24].copy_from_slice(&100u16.to_le_bytes());
    assert!(!m.slave.process(&mut long, ms(3)).send_back());
    // "More" bit on the last datagram.
    let mut more = frame(&[dg(1, 0, 0, &[0; 2])]);
    more[23] |= 0x80;
    assert!(matches!(
        m.slave.process(&mut more, ms(4)),
        Processed::Dropped(DropReason::DatagramTruncated { index: 1, .. })
    ));
    // Truncated after the Ethernet header.
    assert!(!m
        .slave
        .process(&mut lying[..15].to_vec(), ms(5))
        .send_back());
    assert_eq!(m.slave.dropped(), 4);
    // Nothing of the dropped frames took effect; the next frame is served.
    assert_eq!(m.fprd(0x0010, 2).wkc, 0, "no station address was written");
    let b = m.one(dg(1, 0, 0x0300, &[0; 2]));
    assert_eq!(
        (b.wkc, b.data.clone()),
        (1, vec![4, 0]),
        "invalid frame counter"
    );
    m.one(dg(2, 0, 0x0300, &[0]));
    assert_eq!(
        m.one(dg(1, 0, 0x0300, &[0; 2])).data,
        vec![0, 0],
        "cleared by a write"
    );
}

#[test]
fn sii_reads_through_the_eeprom_interface() {
    let mut m = Master::new(3);
    m.one(dg(2, 0, 0x0010, &STATION.to_le_bytes()));
    assert_eq!(m.u16_at(0x0502) & 0x0040, 0x0040, "8-byte reads");
    let read = |m: &mut Master, word: u32| {
        m.fpwr(0x0504, &word.to_le_bytes());
        m.fpwr(0x0502, &[0x00, 0x01]);
        let status = m.u16_at(0x0502);
        (status, m.fprd(0x0508, 8).data)
    };
    // Words 8–0Bh: vendor 538h, product code 0550h.
    let (status, data) = read(&mut m, 8);
    assert_eq!(status & 0xE700, 0, "idle, no error");
    assert_eq!(data, [0x38, 0x05, 0, 0, 0x50, 0x05, 0, 0]);
    // Words 18h–1Bh: mailbox out 1000h/128, in 1080h/128.
    assert_eq!(
        read(&mut m, 0x18).1,
        [0x00, 0x10, 0x80, 0, 0x80, 0x10, 0x80, 0]
    );
    // A 4-byte read takes the first half.
    m.fpwr(0x0504, &[0x1C, 0, 0, 0]);
    m.fpwr(0x0502, &[0x00, 0x01]);
    assert_eq!(m.fprd(0x0508, 4).data, [0x04, 0, 0, 0], "CoE only");
    // Beyond the 2 KiB EEPROM: error bit 13.
    assert_eq!(read(&mut m, 0x400).0 & 0x2000, 0x2000);
    // Write without write enable: bit 14; an unknown command: bit 13; idle clears.
    m.fpwr(0x0502, &[0x00, 0x02]);
    assert_eq!(m.u16_at(0x0502) & 0x6000, 0x4000);
    m.fpwr(0x0502, &[0x00, 0x03]);
    assert_eq!(m.u16_at(0x0502) & 0x6000, 0x2000);
    m.fpwr(0x0502, &[0x00, 0x00]);
    assert_eq!(m.u16_at(0x0502) & 0xE700, 0);
    // The image from the slave is the one the interface reads.
    let image = m.slave.sii_image();
    assert_eq!(read(&mut m, 0x40).1, image[0x80..0x88]);
}

#[test]
fn al_transitions_and_their_refusals() {
    let mut m = Master::new(2);
    m.one(dg(2, 0, 0x0010, &STATION.to_le_bytes()));
    assert_eq!(
        (m.slave.run_led().pattern, m.slave.err_led().pattern),
        (Pattern::Off, Pattern::Off)
    );
    // Pre-Op without mailbox SyncManagers: 0016h.
    assert_eq!(m.request(0x02), (0x11, 0x0016));
    assert_eq!(
        m.slave.err_led().pattern,
        Pattern::FlashingRed { tenths_hz: 25 }
    );
    m.mailbox_sms(128, 128);
    // Still indicating: a higher state without acknowledge is ignored.
    assert_eq!(m.request(0x02), (0x11, 0x0016));
    assert_eq!(m.request(0x12), (0x02, 0));
    assert_eq!(m.slave.run_led().meaning, "Pre-Operational");
    // Pre-Op → Op skips Safe-Op: 0011h; unknown state 05h: 0012h.
    assert_eq!(m.request(0x08), (0x12, 0x0011));
    assert_eq!(m.request(0x15), (0x12, 0x0012));
    assert_eq!(m.request(0x12), (0x02, 0));
    // Safe-Op without process data SyncManagers: outputs 001Dh; inputs 001Eh.
    assert_eq!(m.request(0x04), (0x12, 0x001D));
    m.pd_sms(2);
    m.fpwr(0x081E, &[0]); // deactivate SM3
    assert_eq!(m.request(0x14), (0x12, 0x001E));
    m.fpwr(0x081E, &[1]);
    assert_eq!(m.request(0x14), (0x04, 0));
    assert_eq!(m.slave.run_led().pattern, Pattern::SingleFlashGreen);
    assert_eq!(m.request(0x08), (0x08, 0));
    assert_eq!(m.slave.run_led().pattern, Pattern::Green);
    // Op → Bootstrap: 0011h, stays in Op; back down to Init is always allowed.
    assert_eq!(m.request(0x03), (0x18, 0x0011));
    assert_eq!(
        m.request(0x01),
        (0x11, 0x0011),
        "lower state entered, indication stays"
    );
    assert_eq!(m.request(0x11), (0x01, 0));
    assert_eq!(m.slave.al_state(), EcState::Init);
    // Init → Bootstrap needs the bootstrap mailbox (the same SyncManagers here).
    m.mailbox_sms(128, 128);
    assert_eq!(m.request(0x03), (0x03, 0));
    assert_eq!(
        m.request(0x02),
        (0x13, 0x0011),
        "Bootstrap → Pre-Op refused"
    );
    assert_eq!(m.request(0x11), (0x01, 0));
    m.fpwr(0x0806, &[0]); // SM0 off
    assert_eq!(m.request(0x03), (0x11, 0x0015));
}

#[test]
fn explicit_device_id_for_hot_connect() {
    let mut m = Master::with(
        1,
        SlaveConfig {
            second_address: 0x0123,
        },
    );
    m.one(dg(2, 0, 0x0010, &STATION.to_le_bytes()));
    // AL control bit 5: the ID in 0134h, AL status bit 5.
    assert_eq!(m.request(0x21), (0x21, 0x0123));
    assert_eq!(m.slave.device_id(), 0x0123);
    assert_eq!(m.request(0x01), (0x01, 0));
    // An error takes the register.
    assert_eq!(m.request(0x28), (0x11, 0x0011));
}

#[test]
fn leds_show_the_watchdog() {
    let mut m = Master::new(1);
    m.go_op(1);
    let t = m.now;
    m.slave.poll(t + ms(50));
    assert_eq!(m.slave.al_state(), EcState::Operational);
    let next = m.slave.poll(t + ms(60)).unwrap();
    assert!(next <= t + ms(111), "wakes for the watchdog: {next:?}");
    m.slave.poll(t + ms(150));
    assert_eq!(m.slave.al_state(), EcState::SafeOperational);
    assert_eq!(
        (m.slave.al_status(), m.slave.al_status_code()),
        (0x14, 0x001B)
    );
    assert_eq!(m.slave.err_led().pattern, Pattern::DoubleFlashRed);
    assert_eq!(m.slave.err_led().meaning, "Application Watchdog Timeout");
}

#[test]
fn no_byte_sequence_panics() {
    let mut m = Master::new(8);
    m.go_op(8);
    let good = frame(&[
        dg(12, 0, 0, &[0; 96]),
        dg(4, STATION, 0x1080, &[0; 128]),
        dg(5, STATION, 0x0120, &[0x08, 0]),
    ]);
    // Every truncation, and every byte set to 00h, FFh or flipped.
    for len in 0..good.len() {
        let mut f = good[..len].to_vec();
        let _ = m.slave.process(&mut f, m.now);
    }
    for i in 0..good.len().min(200) {
        for v in [0x00, 0xFF, !good[i]] {
            let mut f = good.clone();
            f[i] = v;
            let _ = m.slave.process(&mut f, m.now);
        }
    }
    // Mailbox messages of every length with every type nibble.
    m.preop_again();
    for len in 0..24u8 {
        for ty in 0..16u8 {
            let mut msg = vec![len, 0, 0, 0, 0, ty | (0x10 * (len % 7 + 1))];
            msg.extend((0..len).map(|b| b.wrapping_mul(37)));
            m.mbx_write(&msg);
            m.mbx_read();
        }
    }
}

impl Master {
    /// Back to Pre-Op with the error acknowledged.
    fn preop_again(&mut self) {
        self.request(0x12);
        assert_eq!(self.slave.al_state(), EcState::PreOperational);
    }
}
