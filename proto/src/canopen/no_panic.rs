//! Every parser of `proto::canopen` against mutated and random input: each returns `Ok` or a
//! typed `Err`, none panics (the promise of the module documentation); whatever parses emits
//! back to bytes that parse to the same value.

#[cfg(test)]
use super::{BlockRequest, Cob, Expedited, InitiateData, SegmentData};
use super::{
    BlockSegment, Emergency, ErrorControl, Message, NmtFrame, SdoRequest, SdoResponse, SyncFrame,
};
#[cfg(test)]
use crate::can::no_panic::{mutations, random_inputs};
use crate::can::CanFrame;

/// Runs every CANopen parser (SDO, block SDO, NMT, error control, SYNC, EMCY) on `b`, and the
/// message classifier on `b` as the data of a frame on each object's COB-ID. The fuzz target
/// `canopen` (`fuzz/`) runs it on its inputs.
pub fn parse_all(b: &[u8]) {
    if let Ok(r) = SdoRequest::parse(b) {
        assert_eq!(SdoRequest::parse(&r.emit()), Ok(r));
    }
    if let Ok(r) = SdoResponse::parse(b) {
        assert_eq!(SdoResponse::parse(&r.emit()), Ok(r));
    }
    if let Ok(s) = BlockSegment::parse(b) {
        assert_eq!(BlockSegment::parse(&s.emit()), Ok(s));
    }
    if let Ok(n) = NmtFrame::parse(b) {
        assert_eq!(NmtFrame::parse(&n.emit()), Ok(n));
    }
    if let Ok(e) = ErrorControl::parse(b) {
        assert_eq!(ErrorControl::parse(&e.emit()), Ok(e));
    }
    if let Ok(s) = SyncFrame::parse(b) {
        assert_eq!(SyncFrame::parse(&s.emit()), Ok(s));
    }
    let _ = Emergency::parse(b);
    // The same bytes as the data of a frame on every object's COB-ID.
    if let Some(data) = b.get(..b.len().min(8)) {
        for id in [
            0x000, 0x080, 0x100, 0x085, 0x185, 0x205, 0x585, 0x605, 0x705, 0x680,
        ] {
            let f = CanFrame::new(id, data).expect("id and length in range");
            if let Ok(m) = Message::parse(&f) {
                assert_eq!(m.to_can(), Ok(f), "{m:?}");
            }
        }
    }
}

#[cfg(test)]
fn valid_messages() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = vec![
        SdoRequest::InitiateDownload {
            index: 0x6040,
            sub: 0,
            data: InitiateData::Expedited(Expedited::new(&[0x0F, 0]).expect("2 bytes")),
        }
        .emit()
        .to_vec(),
        SdoResponse::UploadSegment {
            toggle: true,
            last: true,
            data: SegmentData::new(&[1, 2, 3]).expect("3 bytes"),
        }
        .emit()
        .to_vec(),
        SdoRequest::Block(BlockRequest::InitiateUpload {
            index: 0x1008,
            sub: 0,
            crc: true,
            blksize: 127,
            pst: 4,
        })
        .emit()
        .to_vec(),
        NmtFrame::parse(&[0x01, 0x05])
            .expect("start node 5")
            .emit()
            .to_vec(),
        vec![0x85],
        vec![1],
    ];
    for cs in 0..8u8 {
        for low in [0x00, 0x01, 0x02, 0x03, 0x05, 0x0F, 0x1F] {
            v.push(vec![
                cs << 5 | low,
                0x00,
                0x20,
                0x01,
                0x7F,
                0x80,
                0x01,
                0x00,
            ]);
        }
    }
    v
}

#[test]
fn mutated_and_random_input() {
    mutations(&valid_messages())
        .iter()
        .for_each(|b| parse_all(b));
    random_inputs(0x0601_0000_CAFE_F00D, 20_000, 10)
        .iter()
        .for_each(|b| parse_all(b));
    // Every identifier classifies or not, never panics, and classifies back to itself.
    for id in 0..=0xFFFF_u16 {
        if let Some(c) = Cob::classify(id) {
            assert_eq!(c.cob_id(), Ok(id));
        }
    }
}
