//! Every parser of the PROFINET link layer (`frame`, `dcp`, `rt`, `alarm`) against mutated,
//! truncated and random input: each returns `Ok` or a typed `Err`, none panics, and what
//! parses emits.

use super::alarm::AlarmRepr;
use super::dcp::{DcpBlock, DcpPacket, DcpRepr, HeadKind};
use super::frame::PnRepr;
use super::rt::RtRepr;

/// A small deterministic generator (xorshift).
#[cfg(test)]
struct Rng(u64);

#[cfg(test)]
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Runs the frame, DCP, RT and alarm parsers on `b`. The fuzz target `pnio` (`fuzz/`) runs it
/// on its inputs.
pub fn parse_all(b: &[u8]) {
    if let Ok(r) = PnRepr::parse(b) {
        let _ = r.emit();
    }
    if let Ok(r) = DcpRepr::parse(b) {
        let e = r.emit().expect("a parsed DCP telegram emits");
        // Re-parsing what was emitted gives the same telegram (padding normalised).
        assert_eq!(DcpRepr::parse(&e).as_ref(), Ok(&r), "{b:02X?}");
    }
    if let Ok(p) = DcpPacket::new_checked(b) {
        let _ = p.selectors();
        for raw in p.blocks().flatten() {
            for kind in [HeadKind::None, HeadKind::Info, HeadKind::Qualifier] {
                let _ = DcpBlock::parse(kind, raw);
            }
        }
    }
    for len in [
        None,
        Some(0),
        Some(40),
        Some(b.len().saturating_sub(6)),
        Some(usize::MAX),
    ] {
        if let Ok(r) = RtRepr::parse(b, len) {
            let _ = r.emit();
        }
    }
    if let Ok(a) = AlarmRepr::parse(b) {
        let e = a.emit().expect("a parsed alarm emits");
        assert_eq!(AlarmRepr::parse(&e).as_ref(), Ok(&a), "{b:02X?}");
    }
}

/// Valid frames of each kind, to mutate.
#[cfg(test)]
fn seeds() -> Vec<Vec<u8>> {
    use super::alarm::*;
    use super::dcp::*;
    use super::frame::FrameId;
    use super::PnioStatus;
    let name = DcpRepr::identify_name(1, 1, "sk550p-1");
    let set = DcpRepr::set(
        2,
        vec![
            DcpBlock::set(
                BlockQualifier::PERMANENT,
                BlockValue::NameOfStation("drive".into()),
            ),
            DcpBlock::set(BlockQualifier::TEMPORARY, BlockValue::Signal(0x100)),
        ],
    );
    let res = name.response(vec![
        DcpBlock::info(
            BlockInfo::IP_SET,
            BlockValue::IpParameter(IpParameter::default()),
        ),
        DcpBlock::info(
            BlockInfo::NONE,
            BlockValue::DeviceOptions(vec![DcpOption::ALL]),
        ),
        DcpBlock::response(DcpOption::IP_MAC, BlockError::OK),
    ]);
    let get = DcpRepr::get(3, vec![DcpOption::IP_FULL_SUITE, DcpOption::DEVICE_ID]);
    let n = AlarmNotification {
        high: true,
        alarm_type: AlarmType::DIAGNOSIS,
        api: 0,
        slot: 1,
        subslot: 1,
        module_ident: 1,
        submodule_ident: 1,
        specifier: AlarmSpecifier(0x0801),
        items: vec![
            AlarmItem::Maintenance(1),
            AlarmItem::ChannelDiagnosis(ChannelDiagnosis::default()),
        ],
    };
    let ack = AlarmAck::of(&n, PnioStatus::OK);
    let mut rt = vec![0x80, 0x01];
    rt.extend([0x80; 40]);
    rt.extend([0, 1, 0x35, 0]);
    vec![
        name.emit().unwrap(),
        set.emit().unwrap(),
        res.emit().unwrap(),
        get.emit().unwrap(),
        AlarmRepr::data(1, 2, 0, 0xFFFF, RtaBody::Notification(n))
            .emit()
            .unwrap(),
        AlarmRepr::data(2, 1, 0, 0, RtaBody::Ack(ack))
            .emit()
            .unwrap(),
        AlarmRepr::ack(FrameId::ALARM_LOW, 1, 2, 3, 4)
            .emit()
            .unwrap(),
        rt,
    ]
}

#[test]
fn mutated_seeds_never_panic() {
    let mut rng = Rng(0x5EED_0892);
    let seeds = seeds();
    for s in &seeds {
        parse_all(s);
    }
    for _ in 0..20_000 {
        let mut b = seeds[(rng.next() % seeds.len() as u64) as usize].clone();
        for _ in 0..1 + rng.next() % 4 {
            let i = (rng.next() % b.len() as u64) as usize;
            match rng.next() % 3 {
                0 => b[i] = rng.next() as u8,
                1 => b[i] ^= 1 << (rng.next() % 8),
                _ => b[i] = [0, 1, 2, 3, 4, 5, 6, 0x80, 0xFF][(rng.next() % 9) as usize],
            }
        }
        let cut = (rng.next() % (b.len() as u64 + 1)) as usize;
        parse_all(&b);
        parse_all(&b[..cut]);
    }
}

#[test]
fn random_and_truncated_input_never_panics() {
    let mut rng = Rng(0x5EED_8892);
    let ids: [[u8; 2]; 8] = [
        [0xFE, 0xFC],
        [0xFE, 0xFD],
        [0xFE, 0xFE],
        [0xFE, 0xFF],
        [0xFC, 0x01],
        [0xFE, 0x01],
        [0xC0, 0x00],
        [0x80, 0x00],
    ];
    for _ in 0..20_000 {
        let n = (rng.next() % 120) as usize;
        let mut b: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
        if b.len() >= 2 {
            b[..2].copy_from_slice(&ids[(rng.next() % 8) as usize]);
        }
        if b.len() >= 14 {
            // A plausible DCP data length (bytes 10-11) / RTA var part length (12-13).
            b[10] = 0;
            b[11] = (rng.next() % (n as u64)) as u8;
            b[12] = 0;
            b[13] = (rng.next() % (n as u64)) as u8;
        }
        for cut in [0, n / 2, n] {
            parse_all(&b[..cut]);
        }
    }
}
