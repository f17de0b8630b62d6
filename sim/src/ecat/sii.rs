//! The SII EEPROM (ETG.2010) and the ESC's EEPROM interface (registers 0500h–050Fh, ETG.1000.4
//! §6.4).
//!
//! The image is built from `proto::nord::ecat`: the configuration area (words 0–7, CRC-8 in
//! word 7), identity (8–0Fh), mailboxes (14h–1Ch), size and version (3Eh/3Fh), then the
//! categories strings, general, FMMU, SyncM, TxPDO, RxPDO and the end marker. (`proto::ecat`'s
//! SII representation was not in the tree when this was written; the layout moves there.)
//!
//! The interface: the master writes the word address (0504h) and a command (0502h bits 8–10:
//! 1 read, 2 write, 4 reload); a read fills 0508h–050Fh with four words (bit 6 "8-byte reads"
//! set); a write takes the word at 0508h and needs the write enable bit (0502h bit 0) in the
//! same access, else error bit 14; an address beyond the EEPROM or an unknown command sets
//! error bit 13 ("missing acknowledge / invalid command"). Commands complete at once, so the
//! busy bit (15) never shows.

use proto::nord::ecat::{self as def, Pdo};

use super::esc::{reg, Esc};

/// Category types (ETG.2010 table 6).
mod cat {
    pub(super) const STRINGS: u16 = 10;
    pub(super) const GENERAL: u16 = 30;
    pub(super) const FMMU: u16 = 40;
    pub(super) const SYNCM: u16 = 41;
    pub(super) const TXPDO: u16 = 50;
    pub(super) const RXPDO: u16 = 51;
    pub(super) const END: u16 = 0xFFFF;
}

/// CRC-8 of the configuration area (polynomial x⁸+x²+x+1, initial FFh; ETG.2010 §2.1).
pub(crate) fn crc8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0xFF, |mut c, b| {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 { c << 1 ^ 0x07 } else { c << 1 };
        }
        c
    })
}

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

fn push_category(words: &mut Vec<u16>, kind: u16, mut bytes: Vec<u8>) {
    if bytes.len() % 2 == 1 {
        bytes.push(0);
    }
    words.push(kind);
    words.push((bytes.len() / 2) as u16);
    words.extend(
        bytes
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]])),
    );
}

fn pdo_category(pdos: &[Pdo], strings: &mut Strings) -> Vec<u8> {
    let mut b = Vec::new();
    for p in pdos {
        b.extend(p.index.to_le_bytes());
        b.extend([p.entries.len() as u8, p.sm, 0, strings.index(&p.name)]);
        // Flags: mandatory (bit 0) for FI 1, fixed content (bit 4).
        let flags: u16 = 0x0010 | u16::from(p.inverter.get() == 1);
        b.extend(flags.to_le_bytes());
        for e in &p.entries {
            b.extend(e.index.to_le_bytes());
            b.extend([
                e.sub,
                strings.index(&e.name),
                e.data_type.code() as u8,
                e.bits,
            ]);
            b.extend([0, 0]);
        }
    }
    b
}

/// The SII image of a device with `inverters` inverters and station alias `alias`.
pub(crate) fn image(inverters: u8, alias: u16) -> Vec<u16> {
    let mut w = vec![0u16; 0x40];
    w[0] = def::PDI_CONTROL;
    w[1] = def::PDI_CONFIG;
    w[4] = alias;
    let bytes: Vec<u8> = w[..7].iter().flat_map(|x| x.to_le_bytes()).collect();
    w[7] = u16::from(crc8(&bytes));
    for (at, v) in [
        (0x08, def::VENDOR_ID),
        (0x0A, def::PRODUCT_CODE),
        (0x0C, def::REVISION),
        (0x0E, def::SERIAL_NUMBER),
    ] {
        w[at] = v as u16;
        w[at + 1] = (v >> 16) as u16;
    }
    let (boot_out, boot_in) = def::BOOTSTRAP_MAILBOX;
    for (at, sm) in [
        (0x14, boot_out),
        (0x16, boot_in),
        (0x18, def::SM_MAILBOX_OUT),
        (0x1A, def::SM_MAILBOX_IN),
    ] {
        w[at] = sm.start;
        w[at + 1] = sm.len;
    }
    w[0x1C] = def::MAILBOX_PROTOCOLS;
    w[0x3E] = (def::EEPROM_BYTES * 8 / 1024 - 1) as u16;
    w[0x3F] = 1;

    // String 1 is the device name: masters take the first string as the name (SOEM).
    let mut strings = Strings::default();
    strings.index(def::DEVICE_NAME);
    let rx = def::rx_pdos(inverters);
    let tx = def::tx_pdos(inverters);
    let rx_bytes = pdo_category(&rx, &mut strings);
    let tx_bytes = pdo_category(&tx, &mut strings);
    let coe = def::COE;
    let details = u8::from(coe.sdo)
        | u8::from(coe.sdo_info) << 1
        | u8::from(coe.pdo_assign) << 2
        | u8::from(coe.pdo_config) << 3
        | u8::from(coe.complete_access) << 5;
    let mut general = vec![
        strings.index(def::GROUP),
        0,
        strings.index(def::ORDER_NUMBER),
        strings.index(def::DEVICE_NAME),
        0,
        details,
        0,
        0,
        0,
        0,
        0,
        0,
    ];
    general.extend([0, 0]); // current on E-bus: 0 mA
    general.extend([strings.index(def::GROUP), 0]);
    general.extend(0x0011u16.to_le_bytes()); // ports 0 and 1 MII
    general.resize(32, 0);
    let fmmu: Vec<u8> = def::FMMUS.iter().map(|f| f.code()).collect();
    let mut syncm = Vec::new();
    for sm in def::sync_managers(inverters) {
        syncm.extend(sm.start.to_le_bytes());
        syncm.extend(sm.len.to_le_bytes());
        syncm.extend([sm.control, 0, u8::from(sm.enable), sm.role.com_type()]);
    }
    let mut s = vec![strings.0.len() as u8];
    for x in &strings.0 {
        s.push(x.len() as u8);
        s.extend(x.as_bytes());
    }
    push_category(&mut w, cat::STRINGS, s);
    push_category(&mut w, cat::GENERAL, general);
    push_category(&mut w, cat::FMMU, fmmu);
    push_category(&mut w, cat::SYNCM, syncm);
    push_category(&mut w, cat::TXPDO, tx_bytes);
    push_category(&mut w, cat::RXPDO, rx_bytes);
    w.push(cat::END);
    w.resize(def::EEPROM_BYTES as usize / 2, 0xFFFF);
    w
}

/// Loads the ESC configuration from the image, as an ESC does at power-on and on a reload:
/// PDI control and configuration, the station alias; a wrong checksum loads nothing and sets
/// 0502h bit 11.
pub(crate) fn load(esc: &mut Esc, image: &[u16]) {
    let bytes: Vec<u8> = image[..7].iter().flat_map(|x| x.to_le_bytes()).collect();
    let ok = u16::from(crc8(&bytes)) == image[7] & 0xFF;
    if ok {
        esc.set_u16(reg::PDI_CONTROL, image[0]);
        esc.set_u16(reg::PDI_CONFIG, image[1]);
        esc.set_u16(reg::STATION_ALIAS, image[4]);
    }
    let status = esc.u16(reg::EEPROM_CONTROL) & !0x0800 | if ok { 0 } else { 0x0800 };
    // Bit 6: 8-byte reads.
    esc.set_u16(reg::EEPROM_CONTROL, status | 0x0040);
}

/// Executes the command the master wrote to 0502h.
pub(crate) fn command(esc: &mut Esc, image: &mut [u16]) {
    let control = esc.u16(reg::EEPROM_CONTROL);
    let cmd = (control >> 8) & 0x07;
    let write_enable = control & 1 != 0;
    // Keep the 8-byte and checksum bits; clear command, errors, write enable.
    let mut status = control & 0x0840;
    let addr = u32::from_le_bytes(
        esc.bytes(reg::EEPROM_ADDRESS, 4)
            .try_into()
            .unwrap_or([0xFF; 4]),
    ) as usize;
    match cmd {
        0 => {}
        1 if addr < image.len() => {
            let data: Vec<u8> = (0..4)
                .flat_map(|i| image.get(addr + i).copied().unwrap_or(0xFFFF).to_le_bytes())
                .collect();
            esc.put(reg::EEPROM_DATA, &data);
        }
        2 if !write_enable => status |= 0x4000,
        2 if addr < image.len() => {
            let d = esc.bytes(reg::EEPROM_DATA, 2);
            image[addr] = u16::from_le_bytes([d[0], d[1]]);
        }
        4 => {
            esc.set_u16(reg::EEPROM_CONTROL, status);
            load(esc, image);
            return;
        }
        _ => status |= 0x2000,
    }
    esc.set_u16(reg::EEPROM_CONTROL, status);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_of_the_etg_example() {
        // Any byte changes the checksum; no bytes leave the initial value.
        let a = crc8(&[0x80, 0x0C, 0x0D, 0x6E, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        let b = crc8(&[0x81, 0x0C, 0x0D, 0x6E, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_ne!(a, b);
        assert_eq!(crc8(&[]), 0xFF);
    }

    #[test]
    fn image_has_identity_and_categories() {
        let w = image(3, 0x1234);
        assert_eq!((w[4], w[8], w[9]), (0x1234, 0x0538, 0));
        assert_eq!((w[0x18], w[0x19], w[0x1C]), (0x1000, 128, 4));
        assert_eq!(w[0x40], cat::STRINGS);
        let mut at = 0x40;
        let mut kinds = Vec::new();
        while w[at] != cat::END {
            kinds.push(w[at]);
            at += 2 + usize::from(w[at + 1]);
        }
        assert_eq!(kinds, [10, 30, 40, 41, 50, 51]);
        assert_eq!(w.len(), 1024);
    }
}
