//! What an `epl:` step can do to a real device ([`crate::effect`]): an SDO write names the
//! object it writes (a NORD parameter from 2000h on, the process-data objects 5000h–5003h:
//! BU 2200 §6.3), a PReq carries output process data, an ASnd may carry an SDO. A write that
//! does not decode counts as able to make a motor turn.

use proto::epl::frame::{Body, EplRepr, MessageType};
use proto::epl::sdo::{CommandId, SdoFrame, Segmentation, CMD_HEADER_LEN, SEQ_LEN};
use proto::epl::ServiceId;

use super::step::EplStep;
use crate::effect::{self, Effect};

/// The SDO commands that only read (DS 301 §6.3.2.4.2): harmless even when they do not
/// decode.
const READS: [CommandId; 6] = [
    CommandId::NIL,
    CommandId::READ_BY_INDEX,
    CommandId::READ_ALL_BY_INDEX,
    CommandId::READ_BY_NAME,
    CommandId::FILE_READ,
    CommandId::READ_MULTIPLE_BY_INDEX,
];

/// Where a PReq's payload starts (message type, destination, source, 5 header bytes, size).
const PREQ_PAYLOAD: usize = 10;
/// Where an ASnd's service payload starts (message type, destination, source, ServiceID).
const ASND_PAYLOAD: usize = 4;

/// What the step can do.
pub(super) fn of(step: &EplStep) -> Effect {
    match step {
        EplStep::Nmt(_)
        | EplStep::State(_)
        | EplStep::Ident(_)
        | EplStep::Status
        | EplStep::Upload { .. }
        | EplStep::Silence(_)
        | EplStep::Cycles(_) => Effect::NONE,
        EplStep::Download { index, data, .. } => effect::sdo_download(*index, data),
        EplStep::Frame(bytes) => frame(bytes),
        EplStep::Sdo { bytes, .. } => sdo(bytes),
    }
}

/// A POWERLINK frame from its message type on.
fn frame(bytes: &[u8]) -> Effect {
    match EplRepr::parse_bytes(bytes) {
        Ok(EplRepr {
            body: Body::Preq(p),
            ..
        }) => effect::output_data("a PReq", &p.payload),
        Ok(EplRepr {
            body: Body::Asnd(a),
            ..
        }) if a.service == ServiceId::SDO => sdo(&a.payload),
        Ok(_) => Effect::NONE,
        Err(_) => match bytes.first().map(|t| MessageType(t & 0x7F)) {
            Some(MessageType::PREQ) => effect::output_data(
                "a PReq the harness cannot decode",
                bytes.get(PREQ_PAYLOAD..).unwrap_or_default(),
            ),
            Some(MessageType::ASND) if bytes.get(3) == Some(&ServiceId::SDO.0) => {
                sdo(bytes.get(ASND_PAYLOAD..).unwrap_or_default())
            }
            _ => Effect::NONE,
        },
    }
}

/// SDO bytes: sequence layer, command layer.
fn sdo(bytes: &[u8]) -> Effect {
    let command = match SdoFrame::parse(bytes) {
        Ok(SdoFrame { command: None, .. }) => return Effect::NONE,
        Ok(SdoFrame {
            command: Some(c), ..
        }) => c,
        Err(_) => {
            let id = bytes.get(SEQ_LEN + 3).map(|c| CommandId(*c));
            return match id {
                None => Effect::NONE,
                Some(id) if READS.contains(&id) => Effect::NONE,
                Some(_) => effect::output_data(
                    "an SDO write the harness cannot decode",
                    bytes.get(SEQ_LEN + CMD_HEADER_LEN..).unwrap_or_default(),
                ),
            };
        }
    };
    if command.response || command.abort || READS.contains(&command.command) {
        return Effect::NONE;
    }
    let by_index = matches!(
        command.command,
        CommandId::WRITE_BY_INDEX | CommandId::WRITE_ALL_BY_INDEX
    );
    match (by_index, command.segmentation, command.by_index()) {
        (true, Segmentation::Expedited | Segmentation::Initiate, Ok((index, _, data))) => {
            effect::sdo_download(index, data)
        }
        (true, Segmentation::Segment | Segmentation::Complete, _) => {
            effect::output_data("an SDO write segment", &command.payload).and(Effect::eeprom(1))
        }
        (_, _, _) if command.command == CommandId::FILE_WRITE => Effect::eeprom(1),
        _ => Effect::motion(format!(
            "an SDO command {:02X}h the harness does not decode",
            command.command.0
        ))
        .and(Effect::eeprom(1)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bytes(hex: &str) -> Vec<u8> {
        let s: String = hex.split_whitespace().collect();
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
            .collect()
    }

    #[test]
    fn the_suites_sdo_writes_decode() {
        // WriteByIndex 2066h sub 1 = 1000: P102 of FI 1 on an SK TU3-POL (BU 2200).
        let e = sdo(&bytes(
            "02 06 00 00  00 01 00 01 0600 0000  6620 01 00 E803",
        ));
        assert_eq!(e, Effect::eeprom(1));
        // A ReadByIndex, and a truncated one.
        assert_eq!(
            sdo(&bytes("02 06 00 00  00 01 00 02 0400 0000  1810 01 00")),
            Effect::NONE
        );
        assert_eq!(sdo(&bytes("02 06 00 00  00 01 00 02")), Effect::NONE);
    }

    #[test]
    fn a_preq_with_047eh_may_be_a_setpoint() {
        let e = frame(&bytes("03 01 F0 00 01 00 20 00 0400 7E04 0000"));
        assert!(e.motion.is_some());
        assert_eq!(frame(&bytes("03 01 F0 00 00 00 20 00 0000")), Effect::NONE);
        // SoA: nothing.
        assert_eq!(frame(&bytes("05 FF F0 1D 00 00 00 00 20")), Effect::NONE);
    }
}
