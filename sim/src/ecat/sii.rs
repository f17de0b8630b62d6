//! The SII EEPROM (ETG.2010) and the ESC's EEPROM interface (registers 0500h–050Fh, ETG.1000.4
//! §6.4).
//!
//! The image is built from `proto::nord::ecat`: the configuration area (words 0–7, CRC-8 in
//! word 7), identity (8–0Fh), mailboxes (14h–1Ch), size and version (3Eh/3Fh), then the
//! categories strings, general, FMMU, SyncM, TxPDO, RxPDO and the end marker, emitted by
//! `proto::ecat::sii::SiiRepr`.
//!
//! The interface: the master writes the word address (0504h) and a command (0502h bits 8–10:
//! 1 read, 2 write, 4 reload); a read fills 0508h–050Fh with four words (bit 6 "8-byte reads"
//! set); a write takes the word at 0508h and needs the write enable bit (0502h bit 0) in the
//! same access, else error bit 14; an address beyond the EEPROM or an unknown command sets
//! error bit 13 ("missing acknowledge / invalid command"). Commands complete at once, so the
//! busy bit (15) never shows.

use proto::ecat::register::SiiControl;
use proto::ecat::sii::{
    Category, FmmuUsage, General, MailboxConfig, SiiHeader, SiiPdo, SiiPdoEntry, SiiRepr, SiiSm,
    SmType,
};
use proto::nord::ecat::{self as def, Pdo};

use super::esc::{reg, Esc};

/// Strings of the strings category, numbered from 1.
#[derive(Default)]
struct Strings(Vec<String>);

impl Strings {
    fn index(&mut self, s: &str) -> u8 {
        if let Some(i) = self.0.iter().position(|x| x == s) {
            return i as u8 + 1;
        }
        self.0.push(s.chars().take(255).collect());
        self.0.len() as u8
    }
}

/// The SII image of a device with `inverters` inverters and station alias `alias`, as
/// little-endian words (the whole EEPROM, unused words FFFFh).
pub(crate) fn image(inverters: u8, alias: u16) -> Vec<u16> {
    let (boot_out, boot_in) = def::BOOTSTRAP_MAILBOX;
    let mailbox = |out: def::SyncManager, inp: def::SyncManager| MailboxConfig {
        rx_offset: out.start,
        rx_size: out.len,
        tx_offset: inp.start,
        tx_size: inp.len,
    };
    let header = SiiHeader {
        pdi_control: def::PDI_CONTROL,
        pdi_config: def::PDI_CONFIG,
        station_alias: alias,
        vendor_id: def::VENDOR_ID,
        product_code: def::PRODUCT_CODE,
        revision: def::REVISION,
        serial: def::SERIAL_NUMBER,
        bootstrap_mailbox: mailbox(boot_out, boot_in),
        standard_mailbox: mailbox(def::SM_MAILBOX_OUT, def::SM_MAILBOX_IN),
        mailbox_protocols: def::MAILBOX_PROTOCOLS,
        // Size in KiBit − 1 (ETG.2010 word 3Eh).
        eeprom_size: (def::EEPROM_BYTES * 8 / 1024 - 1) as u16,
        version: 1,
        ..SiiHeader::default()
    };

    // String 1 is the device name: masters take the first string as the name (SOEM).
    let mut strings = Strings::default();
    strings.index(def::DEVICE_NAME);
    let rx = pdos(&def::rx_pdos(inverters), &mut strings);
    let tx = pdos(&def::tx_pdos(inverters), &mut strings);
    let coe = def::COE;
    let general = General {
        group: strings.index(def::GROUP),
        order: strings.index(def::ORDER_NUMBER),
        name: strings.index(def::DEVICE_NAME),
        coe_details: u8::from(coe.sdo)
            | u8::from(coe.sdo_info) << 1
            | u8::from(coe.pdo_assign) << 2
            | u8::from(coe.pdo_config) << 3
            | u8::from(coe.complete_access) << 5,
        // Current on E-bus 0 mA; ports 0 and 1 MII.
        physical_port: 0x0011,
        ..General::default()
    };
    let sms = def::sync_managers(inverters)
        .iter()
        .map(|sm| SiiSm {
            start: sm.start,
            length: sm.len,
            control: sm.control,
            status: 0,
            enable: u8::from(sm.enable),
            kind: SmType(sm.role.com_type()),
        })
        .collect();
    let sii = SiiRepr {
        header,
        categories: vec![
            Category::Strings(strings.0),
            Category::General(general),
            Category::Fmmu(def::FMMUS.iter().map(|f| FmmuUsage(f.code())).collect()),
            Category::SyncM(sms),
            Category::TxPdo(tx),
            Category::RxPdo(rx),
        ],
    };
    // The definition fits its EEPROM (sii tests); an erased EEPROM otherwise.
    sii.emit_words()
        .unwrap_or_else(|_| vec![0xFFFF; def::EEPROM_BYTES as usize / 2])
}

fn pdos(pdos: &[Pdo], strings: &mut Strings) -> Vec<SiiPdo> {
    pdos.iter()
        .map(|p| SiiPdo {
            index: p.index,
            sm: p.sm,
            dc_sync: 0,
            name: strings.index(&p.name),
            // Flags: mandatory (bit 0) for FI 1, fixed content (bit 4).
            flags: 0x0010 | u16::from(p.inverter.get() == 1),
            entries: p
                .entries
                .iter()
                .map(|e| SiiPdoEntry {
                    index: e.index,
                    sub: e.sub,
                    name: strings.index(&e.name),
                    data_type: e.data_type.code() as u8,
                    bit_len: e.bits,
                    flags: 0,
                })
                .collect(),
        })
        .collect()
}

/// Loads the ESC configuration from the image, as an ESC does at power-on and on a reload:
/// PDI control and configuration, the station alias; a wrong checksum loads nothing and sets
/// 0502h bit 11.
pub(crate) fn load(esc: &mut Esc, image: &[u16]) {
    let bytes: Vec<u8> = image
        .iter()
        .take(proto::ecat::sii::HEADER_LEN / 2)
        .flat_map(|x| x.to_le_bytes())
        .collect();
    // A wrong checksum (or an image too short for the header) loads nothing.
    let header = SiiHeader::parse(&bytes).ok();
    if let Some(h) = header {
        esc.set_u16(reg::PDI_CONTROL, h.pdi_control);
        esc.set_u16(reg::PDI_CONFIG, h.pdi_config);
        esc.set_u16(reg::STATION_ALIAS, h.station_alias);
    }
    let failed = if header.is_some() {
        0
    } else {
        SiiControl::CHECKSUM_ERROR
    };
    let status = esc.u16(reg::EEPROM_CONTROL) & !SiiControl::CHECKSUM_ERROR | failed;
    esc.set_u16(reg::EEPROM_CONTROL, status | SiiControl::READ_8_BYTES);
}

/// Executes the command the master wrote to 0502h.
pub(crate) fn command(esc: &mut Esc, image: &mut [u16]) {
    let control = SiiControl(esc.u16(reg::EEPROM_CONTROL));
    let write_enable = control.has(SiiControl::WRITE_ENABLE);
    // Keep the 8-byte and checksum bits; clear command, errors, write enable.
    let mut status = control.0 & (SiiControl::READ_8_BYTES | SiiControl::CHECKSUM_ERROR);
    let addr = u32::from_le_bytes(
        esc.bytes(reg::EEPROM_ADDRESS, 4)
            .try_into()
            .unwrap_or([0xFF; 4]),
    ) as usize;
    match control.cmd() {
        SiiControl::CMD_IDLE => {}
        SiiControl::CMD_READ if addr < image.len() => {
            let data: Vec<u8> = (0..4)
                .flat_map(|i| image.get(addr + i).copied().unwrap_or(0xFFFF).to_le_bytes())
                .collect();
            esc.put(reg::EEPROM_DATA, &data);
        }
        SiiControl::CMD_WRITE if !write_enable => status |= SiiControl::WRITE_ENABLE_ERROR,
        SiiControl::CMD_WRITE if addr < image.len() => {
            let d = esc.bytes(reg::EEPROM_DATA, 2);
            image[addr] = u16::from_le_bytes([d[0], d[1]]);
        }
        SiiControl::CMD_RELOAD => {
            esc.set_u16(reg::EEPROM_CONTROL, status);
            load(esc, image);
            return;
        }
        _ => status |= SiiControl::ACK_ERROR,
    }
    esc.set_u16(reg::EEPROM_CONTROL, status);
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::ecat::sii::CategoryType;

    #[test]
    fn image_reads_back_through_sii_repr() {
        let sii = SiiRepr::parse_words(&image(2, 0x0042)).unwrap();
        assert_eq!(sii.header.station_alias, 0x0042);
        assert_eq!(sii.header.vendor_id, 0x538);
        assert_eq!(sii.strings()[0], def::DEVICE_NAME);
        assert_eq!(sii.rx_pdos().len(), 2);
        assert_eq!(sii.tx_pdos().len(), 2);
    }

    #[test]
    fn image_has_identity_and_categories() {
        let w = image(3, 0x1234);
        assert_eq!((w[4], w[8], w[9]), (0x1234, 0x0538, 0));
        assert_eq!((w[0x18], w[0x19], w[0x1C]), (0x1000, 128, 4));
        assert_eq!(w[0x40], CategoryType::STRINGS.0);
        let mut at = 0x40;
        let mut kinds = Vec::new();
        while w[at] != CategoryType::END.0 {
            kinds.push(w[at]);
            at += 2 + usize::from(w[at + 1]);
        }
        assert_eq!(kinds, [10, 30, 40, 41, 50, 51]);
        assert_eq!(w.len(), 1024);
    }
}
