//! Every parser of `proto::ecat` and `proto::eth` against mutated and random input: each
//! returns `Ok` or a typed `Err`, none panics (the promise of the module documentation).

use super::al;
use super::coe::{CoeMessage, Emergency, SdoInfo, SdoRequest, SdoResponse};
use super::datagram::DatagramRepr;
use super::frame::{EcatFrame, EcatFrameRepr};
use super::mailbox::{MailboxError, MailboxRepr};
use super::register::{FmmuRepr, SmRepr};
use super::sii::{Category, CategoryType, General, SiiHeader, SiiRepr};
use crate::eth::{EthernetFrame, EthernetRepr};
#[cfg(test)]
use {
    super::coe::SdoData, super::datagram::Command, super::mailbox::MailboxType,
    crate::eth::MacAddr, crate::wire::Error,
};

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
    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

/// Runs every parser on `b`, including the in-place paths a slave takes.
pub fn parse_all(b: &[u8]) {
    if let Ok(e) = EthernetFrame::new_checked(b) {
        let _ = EthernetRepr::parse(&e);
        let _ = (e.inner_ethertype(), e.inner_payload().len(), e.vlan_tci());
    }
    if let Ok(f) = EcatFrame::new_checked(b) {
        let _ = (f.payload().len(), f.padding().len(), f.frame_type());
        for d in f.datagrams().flatten() {
            let _ = (d.data().len(), d.wkc(), d.adp(), d.command().name());
            let _ = DatagramRepr::parse(&d);
        }
        let mut owned = b.to_vec();
        let mut m = EcatFrame::new_unchecked(&mut owned[..]);
        if let Ok(ds) = m.datagrams_mut() {
            for mut d in ds {
                d.add_wkc(1);
                let n = d.data().len();
                d.data_mut().fill(n as u8);
                d.set_len(0x7FF);
                let _ = (d.data().len(), d.wkc(), d.check_len());
            }
        }
    }
    let _ = EcatFrameRepr::parse_bytes(b);
    let _ = DatagramRepr::parse_bytes(b);
    if let Ok(m) = MailboxRepr::parse_bytes(b) {
        let _ = CoeMessage::parse(&m.data);
        let _ = MailboxError::parse(&m.data);
    }
    let _ = CoeMessage::parse(b);
    let _ = SdoRequest::parse(b);
    let _ = SdoResponse::parse(b);
    let _ = SdoRequest::parse_coe(b);
    let _ = SdoResponse::parse_coe(b);
    let _ = Emergency::parse_coe(b);
    if let Ok(i) = SdoInfo::parse(b) {
        let _ = i.abort_code();
    }
    let _ = SmRepr::parse(b);
    let _ = FmmuRepr::parse(b);
    let _ = al::AlStatus::parse_with_code(b);
    let _ = al::AlControl::parse(b);
    let _ = SiiHeader::parse(b);
    let _ = SiiRepr::parse(b);
    for t in [10, 20, 30, 40, 41, 50, 51, 60] {
        let _ = Category::parse(CategoryType(t), b);
    }
    let _ = General::parse(b);
}

#[cfg(test)]
fn valid_messages() -> Vec<Vec<u8>> {
    let frame = EcatFrameRepr::new(vec![
        DatagramRepr::physical(Command::BRD, 1, 0, 0x0130, vec![0; 2]),
        DatagramRepr::physical(Command::FPWR, 2, 0x1001, 0x1000, vec![9; 16]),
        DatagramRepr::logical(Command::LRW, 3, 0x1_0000, vec![5; 12]),
    ]);
    let sdo = SdoRequest::Download {
        index: 0x3066,
        sub: 1,
        complete_access: false,
        data: SdoData::auto(vec![1; 20]),
    };
    let mbx = sdo.to_mailbox(3).unwrap().emit_padded(128).unwrap();
    let seg = SdoResponse::UploadSegment {
        toggle: true,
        last: true,
        data: vec![1, 2],
    }
    .to_mailbox(1)
    .unwrap()
    .emit()
    .unwrap();
    let err = MailboxError::new(super::mailbox::MailboxErrorCode::SYNTAX)
        .to_mailbox(2)
        .emit()
        .unwrap();
    let mut sii_header = SiiHeader {
        vendor_id: 0x538,
        eeprom_size: 3,
        ..SiiHeader::default()
    }
    .emit()
    .to_vec();
    sii_header.extend([10, 0, 2, 0, 1, 2, b'a', b'b', 0xFF, 0xFF]);
    vec![
        frame
            .emit_ethernet(MacAddr::BROADCAST, MacAddr([2, 0, 0, 0, 0, 1]))
            .unwrap(),
        frame.emit().unwrap(),
        mbx,
        seg,
        err,
        sii_header,
        MailboxRepr::new(MailboxType::COE, 1, Emergency::default().emit_coe())
            .emit()
            .unwrap(),
    ]
}

#[test]
fn every_byte_mutation_of_valid_messages() {
    for m in valid_messages() {
        parse_all(&m);
        for n in 0..=m.len() {
            parse_all(&m[..n]);
        }
        for i in 0..m.len() {
            for x in [0x01, 0x10, 0x80, 0xFF] {
                let mut b = m.clone();
                b[i] ^= x;
                parse_all(&b);
            }
        }
    }
}

#[test]
fn random_bytes() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for len in 0..300 {
        for _ in 0..20 {
            parse_all(&rng.bytes(len));
        }
    }
}

#[test]
fn errors_print_their_field() {
    let e = EcatFrameRepr::parse_bytes(&[0x20, 0x10, 1]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "EtherCAT length: length 32 but 1 bytes available"
    );
    let e = Error::DatagramTruncated {
        index: 1,
        need: 32,
        got: 14,
    };
    assert_eq!(
        e.to_string(),
        "datagram 1: needs 32 bytes, only 14 left in the EtherCAT frame"
    );
}
