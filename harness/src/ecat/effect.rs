//! What an `ecat:` step can do to a real device ([`crate::safety`]): an SDO download writes
//! the object it names (a NORD parameter from 2000h on, the outputs from 7000h on: BU 0620
//! §2.2.7); a write into the ESC's process memory (from 1000h on, where the sync managers'
//! output and mailbox buffers lie) or to a logical address writes output data, or a mailbox,
//! which the harness cannot tell apart; a write to the ESC registers below 1000h (AL control,
//! sync manager and FMMU set-up) is neither. A mailbox message is decoded down to its SDO.

use proto::ecat::coe::{SdoData, SdoRequest};
use proto::ecat::datagram::Command;
use proto::ecat::frame::EcatFrameRepr;
use proto::ecat::mailbox::{MailboxRepr, MailboxType};

use super::step::EcatStep;
use crate::safety::{self, Effect};

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
        EcatStep::Download { index, data, .. } => safety::sdo_download(*index, data),
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
            Err(_) => safety::output_data("an EtherCAT frame the harness cannot decode", bytes),
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
        c => safety::output_data(
            &format!("datagram command {:02X}h at {ado:04X}h", c.0),
            data,
        ),
    }
}

/// A mailbox message as written.
fn mailbox(bytes: &[u8]) -> Effect {
    let Ok(m) = MailboxRepr::parse_bytes(bytes) else {
        // A slave that refuses the header acts on nothing; one that does not is what the case
        // tests, so its CoE data count as if it took them.
        return coe(bytes.get(6..).unwrap_or_default());
    };
    match m.kind {
        MailboxType::COE => coe(&m.data),
        // A file download may replace the firmware: a write of the device's memory.
        MailboxType::FOE => Effect::eeprom(1),
        _ => Effect::NONE,
    }
}

/// CoE data: an SDO download is a write of its object.
fn coe(data: &[u8]) -> Effect {
    match SdoRequest::parse_coe(data) {
        Ok(SdoRequest::Download {
            index,
            data: SdoData::Expedited { data, .. } | SdoData::Normal { data, .. },
            ..
        }) => safety::sdo_download(index, &data),
        Ok(SdoRequest::DownloadSegment { data, .. }) => {
            safety::output_data("an SDO download segment", &data)
                .and(Effect::eeprom(u32::from(data.iter().any(|b| *b != 0))))
        }
        Ok(_) => Effect::NONE,
        Err(_) => safety::output_data("CoE data the harness cannot decode", data),
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
    }
}
