//! What an `ecat:` step can do to a real device ([`crate::effect`]): an SDO download writes
//! the object it names (a NORD parameter from 2000h on, the outputs from 7000h on: BU 0620
//! §2.2.7); a write into the ESC's process memory (from 1000h on, where the sync managers'
//! output and mailbox buffers lie) or to a logical address writes output data, or a mailbox,
//! which the harness cannot tell apart; a write to the ESC registers below 1000h (AL control,
//! sync manager and FMMU set-up) is neither. A mailbox message is decoded down to its SDO, or
//! its RxPDO, or its file write.

use proto::ecat::coe::{CoeHeader, CoeService, SdoData, SdoRequest};
use proto::ecat::datagram::Command;
use proto::ecat::frame::EcatFrameRepr;
use proto::ecat::mailbox::{MailboxRepr, MailboxType};

use super::step::EcatStep;
use crate::effect::{self, Effect};

/// The first address of the ESC's process memory (ETG.1000.4: registers below 1000h).
const PROCESS_MEMORY: u16 = 0x1000;

/// What the step can do.
pub(super) fn of(step: &EcatStep) -> Effect {
    match step {
        EcatStep::State { .. }
        | EcatStep::ReadRegister { .. }
        | EcatStep::Sii { .. }
        | EcatStep::Upload { .. }
        | EcatStep::StopPdo { .. }
        | EcatStep::Identify
        | EcatStep::Emergencies => Effect::NONE,
        EcatStep::Download { index, data, .. } => effect::sdo_download(*index, data),
        EcatStep::WriteRegister { address, data } => datagram(Command::FPWR, *address, data),
        EcatStep::Datagram {
            command, ado, data, ..
        } => datagram(Command(*command), *ado, data),
        EcatStep::Frame { bytes } => match EcatFrameRepr::parse_bytes(bytes) {
            Ok(f) => f
                .datagrams
                .iter()
                .map(|d| datagram(d.command, d.ado(), &d.data))
                .fold(Effect::NONE, Effect::and),
            Err(_) => effect::output_data("an EtherCAT frame the harness cannot decode", bytes),
        },
        EcatStep::Mailbox { bytes } => mailbox(bytes),
    }
}

/// One datagram: `ado` the register of a physical command.
fn datagram(command: Command, ado: u16, data: &[u8]) -> Effect {
    match command {
        Command::NOP | Command::APRD | Command::FPRD | Command::BRD | Command::LRD => Effect::NONE,
        Command::APWR
        | Command::APRW
        | Command::FPWR
        | Command::FPRW
        | Command::BWR
        | Command::BRW
        | Command::ARMW
        | Command::FRMW
            if ado < PROCESS_MEMORY =>
        {
            Effect::NONE
        }
        c => effect::output_data(
            &format!("datagram command {:02X}h at {ado:04X}h", c.0),
            data,
        ),
    }
}

/// A mailbox message as written. A header that lies about its length is read as far as the
/// bytes go: a slave that refuses it acts on nothing, one that does not is what the case tests.
fn mailbox(bytes: &[u8]) -> Effect {
    let (kind, data) = match MailboxRepr::parse_bytes(bytes) {
        Ok(m) => (m.kind, m.data),
        Err(_) => match bytes.get(5) {
            Some(b) => (MailboxType(b & 0x0F), bytes[6..].to_vec()),
            None => return Effect::NONE,
        },
    };
    match kind {
        MailboxType::COE => coe(&data),
        MailboxType::FOE => foe(&data),
        _ => Effect::NONE,
    }
}

/// CoE data: an SDO request may download an object; an RxPDO carries output data; the other
/// services (emergency, SDO response, TxPDO, SDO information) write nothing.
fn coe(data: &[u8]) -> Effect {
    let Ok((header, rest)) = CoeHeader::split(data) else {
        return Effect::NONE;
    };
    match header.service {
        CoeService::SDO_REQUEST => sdo_request(rest),
        CoeService::RXPDO => effect::output_data("an RxPDO over the mailbox", rest),
        _ => Effect::NONE,
    }
}

/// An SDO request, decoded as leniently as a tolerant slave does. One that does not decode is
/// a download if its command specifier says so (0 segment, 1 initiate, 6 block download:
/// CiA 301 §7.2.4.3).
fn sdo_request(b: &[u8]) -> Effect {
    match SdoRequest::parse_lenient(b) {
        Ok(SdoRequest::Download {
            index,
            data: SdoData::Expedited { data, .. } | SdoData::Normal { data, .. },
            ..
        }) => effect::sdo_download(index, &data),
        // The initiate that named the object counted the write; its segments may carry
        // output data.
        Ok(SdoRequest::DownloadSegment { data, .. }) => {
            effect::output_data("an SDO download segment", &data)
        }
        Ok(_) => Effect::NONE,
        Err(_) => match b.split_first() {
            Some((c, rest)) if matches!(c >> 5, 0 | 1 | 6) => {
                effect::output_data("an SDO download the harness cannot decode", rest)
            }
            _ => Effect::NONE,
        },
    }
}

/// FoE data (ETG.1000.6 §5.8: opcode 1 read request, 2 write request, 3 data): a file written
/// to the slave may replace its firmware, a write of its memory.
fn foe(data: &[u8]) -> Effect {
    match data.first() {
        Some(2 | 3) => Effect::eeprom(1),
        _ => Effect::NONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::ecat::coe::CoeService;

    #[test]
    fn register_writes_below_the_process_memory_are_neither() {
        // AL control (0120h) = OP.
        assert_eq!(datagram(Command::FPWR, 0x0120, &[8, 0]), Effect::NONE);
        // Into the process memory, or to a logical address: output data.
        assert!(datagram(Command::FPWR, 0x1100, &[0x7F, 0x04])
            .motion
            .is_some());
        assert!(datagram(Command::LWR, 0, &[0x7F, 0x04]).motion.is_some());
        assert_eq!(datagram(Command::LRW, 0, &[0, 0]), Effect::NONE);
        assert_eq!(datagram(Command::LRD, 0, &[0x7F, 0x04]), Effect::NONE);
    }

    #[test]
    fn an_sdo_download_in_a_mailbox_is_decoded() {
        // P509 of FI 1 on an SK 550P: 2000h + 509 = 21FDh, value 8.
        let req = SdoRequest::Download {
            index: 0x21FD,
            sub: 0,
            complete_access: false,
            data: SdoData::auto(vec![8, 0]),
        };
        let mut coe = vec![0, (CoeService::SDO_REQUEST.0) << 4];
        coe.extend(req.emit().unwrap());
        let m = MailboxRepr::new(MailboxType::COE, 1, coe).emit().unwrap();
        let e = mailbox(&m);
        assert!(e.motion.unwrap().contains("P509"));
        assert_eq!(e.eeprom_writes, 1);
        // The suites' malformed mailboxes: an FoE read request whose header lies about its
        // length, a CoE header alone, an SDO upload cut short.
        let hex = |t: &str| -> Vec<u8> {
            let t: String = t.split_whitespace().collect();
            (0..t.len())
                .step_by(2)
                .map(|i| u8::from_str_radix(&t[i..i + 2], 16).unwrap())
                .collect()
        };
        for m in [
            "0A00 0000 00 04 01 00 00000000 4E4F",
            "0200 0000 00 03 0020",
            "0600 0000 00 03 0020 40 1810 01",
        ] {
            assert_eq!(mailbox(&hex(m)), Effect::NONE, "{m}");
        }
    }
}
