//! Every parser of `rpc` and `block` against random, mutated and truncated input: each
//! returns `Ok` or a typed `Err`, none panics, and what parses emits and parses back the
//! same.

use super::*;
use crate::pnio::rpc::{Drep, NcaStatus, NdrRequest, NdrResponse, RpcPacket, RpcRepr};

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

/// Runs the block parsers (the checked view and the whole list of blocks) on `b`.
pub fn blocks(b: &[u8]) {
    if let Ok(v) = BlockView::new_checked(b) {
        let _ = (v.header(), v.body());
    }
    if let Ok(blocks) = Block::parse_all(b) {
        let again = Block::emit_all(&blocks).expect("a parsed block emits");
        assert_eq!(Block::parse_all(&again).as_ref(), Ok(&blocks));
    }
}

/// Runs the DCE/RPC and NDR parsers on `b`, and the block parsers on what an NDR request
/// carries. The fuzz target `pnio_rpc` (`fuzz/`) runs it on its inputs.
pub fn rpc(b: &[u8]) {
    if let Ok(p) = RpcPacket::new_checked(b) {
        let _ = (p.object(), p.interface(), p.activity(), p.opnum(), p.body());
        let _ = (p.sequence_number(), p.flags1(), p.packet_type());
    }
    if let Ok(r) = RpcRepr::parse_bytes(b) {
        let again = r.emit().expect("a parsed PDU emits");
        assert_eq!(RpcRepr::parse_bytes(&again).as_ref(), Ok(&r));
        let _ = r.nca_status();
    }
    for drep in [Drep::LITTLE_ENDIAN, Drep::BIG_ENDIAN] {
        if let Ok(q) = NdrRequest::parse(b, drep) {
            assert_eq!(NdrRequest::parse(&q.emit(drep), drep).as_ref(), Ok(&q));
            blocks(&q.data);
        }
        if let Ok(q) = NdrResponse::parse(b, drep) {
            assert_eq!(NdrResponse::parse(&q.emit(drep), drep).as_ref(), Ok(&q));
        }
        let _ = NcaStatus::parse(b, drep);
    }
}

/// Valid bodies to mutate: a connect request's blocks, a write request, control blocks.
#[cfg(test)]
fn seeds() -> Vec<Vec<u8>> {
    let ar = Uuid::pnio_object(1, 2, 3);
    let mut connect = Vec::new();
    let exp = ExpectedSubmoduleBlockReq {
        apis: vec![ExpectedApi {
            api: 0,
            slot: 1,
            module_ident: 7,
            module_properties: 0,
            submodules: vec![ExpectedSubmodule {
                subslot: 1,
                ident: 8,
                properties: SubmoduleProperties::INPUT_OUTPUT,
                data: vec![
                    DataDescription::new(DataDirection::INPUT, 4),
                    DataDescription::new(DataDirection::OUTPUT, 4),
                ],
            }],
        }],
    };
    let iocr = IocrBlockReq {
        iocr_type: IocrType::OUTPUT,
        apis: vec![IocrApi {
            api: 0,
            io_data: vec![IocrEntry::default(); 2],
            iocs: vec![IocrEntry::default()],
        }],
        ..IocrBlockReq::default()
    };
    let diff = ModuleDiffBlock {
        apis: vec![DiffApi {
            api: 0,
            modules: vec![DiffModule {
                submodules: vec![DiffSubmodule::default(); 2],
                ..DiffModule::default()
            }],
        }],
    };
    for b in [
        Block::ArReq(ArBlockReq {
            station_name: b"controller".to_vec(),
            ..ArBlockReq::default()
        }),
        Block::IocrReq(iocr),
        Block::AlarmCrReq(AlarmCrBlockReq::default()),
        Block::ExpectedSubmoduleReq(exp),
        Block::ArRes(ArBlockRes::default()),
        Block::IocrRes(IocrBlockRes::default()),
        Block::AlarmCrRes(AlarmCrBlockRes::default()),
        Block::ModuleDiff(diff),
        Block::ArServer(ArServerBlock {
            station_name: b"sk550p".to_vec(),
        }),
    ] {
        b.emit(&mut connect).unwrap();
    }
    let record = Block::emit_all(&[
        Block::WriteReq(IodWriteReq {
            addr: RecordAddress::default(),
            data: vec![1, 2, 3],
        }),
        Block::ReadReq(IodReadReq::default()),
        Block::WriteRes(IodWriteRes::default()),
        Block::ReadRes(IodReadRes {
            data: vec![9; 5],
            ..IodReadRes::default()
        }),
        Block::Control(IodControl::prm_end(ar, 1)),
        Block::Control(IodControl::application_ready(ar, 1).done()),
    ])
    .unwrap();
    let ndr = NdrRequest::new(1000, connect.clone()).unwrap();
    let pdu = RpcRepr::request(
        ar,
        Uuid::PNIO_DEVICE_INTERFACE,
        ar,
        1,
        crate::pnio::rpc::Opnum::CONNECT,
        ndr.emit(Drep::LITTLE_ENDIAN),
    )
    .emit()
    .unwrap();
    vec![connect, record, pdu]
}

#[test]
fn random_mutated_and_truncated_input_never_panics() {
    let seeds = seeds();
    for s in &seeds {
        blocks(s);
        rpc(s);
        for cut in 0..s.len() {
            blocks(&s[..cut]);
            rpc(&s[..cut]);
        }
    }
    let mut rng = Rng(0x5EED_0B10);
    for i in 0..20_000 {
        let mut b = if i % 2 == 0 {
            seeds[(rng.next() % seeds.len() as u64) as usize].clone()
        } else {
            let n = (rng.next() % 200) as usize;
            (0..n).map(|_| rng.next() as u8).collect()
        };
        for _ in 0..(rng.next() % 4) + 1 {
            if b.is_empty() {
                break;
            }
            let at = (rng.next() % b.len() as u64) as usize;
            b[at] = match rng.next() % 4 {
                0 => 0,
                1 => 0xFF,
                2 => b[at].wrapping_add(1),
                _ => rng.next() as u8,
            };
        }
        let cut = (rng.next() % (b.len() as u64 + 1)) as usize;
        blocks(&b);
        blocks(&b[..cut]);
        rpc(&b);
        rpc(&b[..cut]);
    }
}
