//! What a `pnio:` step can do to a real device ([`crate::effect`]): a write of the parameter
//! records (100 the interface, 101..108 FI 1..8: BU 0620 §2.5.6.2; the SK TU3-PNT's record
//! 47: BU 0590 §4.2.2) carries a PKW order; other records, a DCP Set kept over a power cycle
//! and a reset to factory settings may be kept in the device's memory; a raw cyclic frame
//! carries output data. An IODWrite sent as a raw RPC is decoded down to its record.

use proto::nord::pnio::{Record47Repr, RECORD_AXIS, RECORD_INTERFACE};
use proto::pnio::dcp::ServiceId;

use super::step::PnioStep;
use crate::effect::{self, Effect};

/// The RPC operation IODWrite (IEC 61158-6-10 "PNIO interface operations": 0 Connect,
/// 1 Release, 2 Read, 3 Write, 4 Control).
const OPNUM_WRITE: u16 = 3;
/// In an IODWriteReqHeader: where the record index lies (block header 6, SeqNumber 2, ARUUID
/// 16, API 4, slot 2, subslot 2, padding 2) and where the record data start (the header is 64
/// bytes).
const WRITE_INDEX: usize = 34;
const WRITE_DATA: usize = 64;
/// Frame ids of cyclic real-time data (RT classes 1–3: 0100h–FBFFh) and of DCP
/// (FEFCh–FEFFh).
const CYCLIC: std::ops::RangeInclusive<u16> = 0x0100..=0xFBFF;
const DCP: std::ops::RangeInclusive<u16> = 0xFEFC..=0xFEFF;

/// What the step can do.
pub(super) fn of(step: &PnioStep) -> Effect {
    match step {
        PnioStep::Identify(_)
        | PnioStep::IdentifyOwn
        | PnioStep::Signal
        | PnioStep::Connect { .. }
        | PnioStep::Release
        | PnioStep::DeviceAccess
        | PnioStep::Read { .. }
        | PnioStep::Alarm(_)
        | PnioStep::Silence(_)
        | PnioStep::Lldp(_)
        | PnioStep::Cycles(_) => Effect::NONE,
        PnioStep::SetName { permanent, .. } | PnioStep::SetIp { permanent, .. } => {
            Effect::eeprom(u32::from(*permanent))
        }
        PnioStep::ResetFactory => Effect::eeprom(1),
        PnioStep::Write { index, data, .. } => record(*index, data),
        PnioStep::Frame(bytes) => frame(bytes),
        PnioStep::Rpc { opnum, body, .. } if *opnum == OPNUM_WRITE => {
            match body.get(WRITE_INDEX..WRITE_INDEX + 2) {
                Some(i) => record(
                    u16::from_be_bytes([i[0], i[1]]),
                    body.get(WRITE_DATA..).unwrap_or_default(),
                ),
                None => Effect::NONE,
            }
        }
        PnioStep::Rpc { .. } => Effect::NONE,
    }
}

/// A record write.
fn record(index: u16, data: &[u8]) -> Effect {
    match index {
        RECORD_INTERFACE => interface(effect::pkw(data)),
        101..=108 => effect::pkw(data),
        // Label, axis (0 the SK TU3-PNT, 1 the FI), PNU + 1000: BU 0590 §4.2.4.3.
        RECORD_AXIS => match Record47Repr::parse(data) {
            Ok(r) if r.axis == 0 => interface(effect::pkw(&r.pkw().emit_bytes())),
            Ok(r) => effect::pkw(&r.pkw().emit_bytes()),
            Err(_) => Effect::NONE,
        },
        // I&M records and any other the harness does not know may be kept.
        _ => Effect::eeprom(1),
    }
}

/// An order to the interface's own parameters: the same writes, none of them an inverter's.
fn interface(e: Effect) -> Effect {
    Effect { motion: None, ..e }
}

/// A PROFINET frame from its frame id on.
fn frame(bytes: &[u8]) -> Effect {
    let Some((id, rest)) = bytes
        .split_first_chunk::<2>()
        .map(|(id, rest)| (u16::from_be_bytes(*id), rest))
    else {
        return Effect::NONE;
    };
    if CYCLIC.contains(&id) {
        effect::output_data(&format!("RT frame {id:04X}h"), rest)
    } else if DCP.contains(&id) && rest.first() == Some(&ServiceId::SET.0) {
        // A DCP Set may be permanent.
        Effect::eeprom(1)
    } else {
        Effect::NONE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameter_records_carry_pkw_orders() {
        // Record 101 (FI 1), AK 2 P509 + 1000: a start and an EEPROM write.
        let e = record(101, &[0x25, 0xE5, 0, 0, 0, 0, 0, 8]);
        assert!(e.motion.is_some());
        assert_eq!(e.eeprom_writes, 1);
        // Record 100: the interface's P509 is not the inverter's.
        assert_eq!(
            record(100, &[0x25, 0xE5, 0, 0, 0, 0, 0, 8]),
            Effect::eeprom(1)
        );
        // BU 0590 §4.2.4.3's example: record 47, label 2, axis 1, P105 = 60.0 Hz.
        let r47 = [5, 2, 1, 0x04, 0x51, 0, 0, 0, 0, 0x02, 0x58];
        assert_eq!(record(RECORD_AXIS, &r47), Effect::eeprom(1));
        // An I&M1 record.
        assert_eq!(record(0xAFF1, &[0; 54]), Effect::eeprom(1));
    }

    #[test]
    fn raw_frames() {
        assert_eq!(frame(&[0x80, 0x01, 0x00]), Effect::NONE);
        assert!(frame(&[0x80, 0x01, 0x7F, 0x04, 0x80]).motion.is_some());
        // DCP Get, and Set.
        assert_eq!(frame(&[0xFE, 0xFD, 3, 0]), Effect::NONE);
        assert_eq!(frame(&[0xFE, 0xFD, 4, 0]), Effect::eeprom(1));
        assert_eq!(frame(&[0xFE, 0x01, 0x12, 0x34]), Effect::NONE);
    }
}
