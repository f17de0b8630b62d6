//! The SII EEPROM ("slave information interface"): a word-addressed image that the ESC loads
//! its configuration from and a master reads through registers 0500h–050Fh (ETG.1000.6
//! "Slave information interface"; ETG.2010 "EtherCAT Slave Information Interface": the fixed
//! header and the category structures).
//!
//! | word | field |
//! |---|---|
//! | 0 | PDI control (→ 0140h) |
//! | 1 | PDI configuration (→ 0150h) |
//! | 2 | SYNC impulse length (10 ns units) |
//! | 3 | extended PDI configuration (→ 0152h) |
//! | 4 | configured station alias (→ 0012h) |
//! | 5–6 | reserved |
//! | 7 | checksum of words 0–6: CRC-8, polynomial x⁸+x²+x+1 (07h), initial FFh, low byte |
//! | 8–9 / Ah–Bh / Ch–Dh / Eh–Fh | vendor id / product code / revision / serial number (u32) |
//! | 10h–13h | execution delay, port 0/1 delay, reserved |
//! | 14h–17h | bootstrap mailbox: receive (master → slave) offset, size; send offset, size |
//! | 18h–1Bh | standard mailbox: receive offset, size; send offset, size |
//! | 1Ch | mailbox protocols ([`protocol`]: AoE 1, EoE 2, CoE 4, FoE 8, SoE 10h, VoE 20h) |
//! | 1Dh–3Dh | reserved |
//! | 3Eh | EEPROM size: (KiBit) − 1 |
//! | 3Fh | version (1) |
//! | 40h… | categories: type (u16), size in words (u16), data; type FFFFh ends the list |
//!
//! [`SiiRepr`] emits a whole image and parses one back (checksum checked, every category's
//! length checked against the image). Strings are bytes as the EEPROM holds them, read as
//! Latin-1 so that any byte round-trips.

use std::fmt;

use super::wire::{fit, le16, le32};
use crate::wire::{Error, Reader};

/// Word addresses of the fixed header.
pub mod word {
    /// PDI control.
    pub const PDI_CONTROL: u16 = 0x00;
    /// PDI configuration.
    pub const PDI_CONFIG: u16 = 0x01;
    /// SYNC impulse length.
    pub const SYNC_IMPULSE: u16 = 0x02;
    /// Extended PDI configuration.
    pub const PDI_CONFIG2: u16 = 0x03;
    /// Configured station alias.
    pub const STATION_ALIAS: u16 = 0x04;
    /// Checksum (low byte).
    pub const CHECKSUM: u16 = 0x07;
    /// Vendor id (2 words).
    pub const VENDOR_ID: u16 = 0x08;
    /// Product code (2 words).
    pub const PRODUCT_CODE: u16 = 0x0A;
    /// Revision number (2 words).
    pub const REVISION: u16 = 0x0C;
    /// Serial number (2 words).
    pub const SERIAL: u16 = 0x0E;
    /// Execution delay.
    pub const EXECUTION_DELAY: u16 = 0x10;
    /// Port 0 delay.
    pub const PORT0_DELAY: u16 = 0x11;
    /// Port 1 delay.
    pub const PORT1_DELAY: u16 = 0x12;
    /// Bootstrap receive mailbox offset.
    pub const BOOT_RX_OFFSET: u16 = 0x14;
    /// Bootstrap receive mailbox size.
    pub const BOOT_RX_SIZE: u16 = 0x15;
    /// Bootstrap send mailbox offset.
    pub const BOOT_TX_OFFSET: u16 = 0x16;
    /// Bootstrap send mailbox size.
    pub const BOOT_TX_SIZE: u16 = 0x17;
    /// Standard receive mailbox offset.
    pub const STD_RX_OFFSET: u16 = 0x18;
    /// Standard receive mailbox size.
    pub const STD_RX_SIZE: u16 = 0x19;
    /// Standard send mailbox offset.
    pub const STD_TX_OFFSET: u16 = 0x1A;
    /// Standard send mailbox size.
    pub const STD_TX_SIZE: u16 = 0x1B;
    /// Mailbox protocols.
    pub const MAILBOX_PROTOCOL: u16 = 0x1C;
    /// EEPROM size.
    pub const SIZE: u16 = 0x3E;
    /// Version.
    pub const VERSION: u16 = 0x3F;
    /// First category.
    pub const CATEGORIES: u16 = 0x40;
}

/// Bits of word 1Ch "mailbox protocol" (ETG.2010 fixed header).
pub mod protocol {
    /// ADS over EtherCAT.
    pub const AOE: u16 = 0x0001;
    /// Ethernet over EtherCAT.
    pub const EOE: u16 = 0x0002;
    /// CANopen over EtherCAT.
    pub const COE: u16 = 0x0004;
    /// File access over EtherCAT.
    pub const FOE: u16 = 0x0008;
    /// Servo profile over EtherCAT.
    pub const SOE: u16 = 0x0010;
    /// Vendor specific over EtherCAT.
    pub const VOE: u16 = 0x0020;
}

/// Bytes of the fixed header (words 0–3Fh).
pub const HEADER_LEN: usize = 128;

/// The SII checksum: CRC-8 with polynomial 07h, initial value FFh, no reflection, no final
/// XOR, over the 14 bytes of words 0–6 (ETG.2010 fixed header; ETG.1000.6 "Slave information
/// interface"). The ESC refuses the configuration area on a mismatch (0502h bit 11).
pub fn crc8(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0xFF, |mut c, b| {
        c ^= b;
        for _ in 0..8 {
            c = if c & 0x80 != 0 { c << 1 ^ 0x07 } else { c << 1 };
        }
        c
    })
}

/// A mailbox's place in the ESC memory (offset and size in bytes), as SII words 14h–1Bh give
/// it: receive = master → slave (SM0), send = slave → master (SM1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct MailboxConfig {
    /// Receive mailbox offset.
    pub rx_offset: u16,
    /// Receive mailbox size.
    pub rx_size: u16,
    /// Send mailbox offset.
    pub tx_offset: u16,
    /// Send mailbox size.
    pub tx_size: u16,
}

/// The fixed header, words 0–3Fh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SiiHeader {
    /// Word 0.
    pub pdi_control: u16,
    /// Word 1.
    pub pdi_config: u16,
    /// Word 2.
    pub sync_impulse: u16,
    /// Word 3.
    pub pdi_config2: u16,
    /// Word 4.
    pub station_alias: u16,
    /// Words 8–9.
    pub vendor_id: u32,
    /// Words Ah–Bh.
    pub product_code: u32,
    /// Words Ch–Dh.
    pub revision: u32,
    /// Words Eh–Fh.
    pub serial: u32,
    /// Word 10h.
    pub execution_delay: u16,
    /// Word 11h.
    pub port0_delay: u16,
    /// Word 12h.
    pub port1_delay: u16,
    /// Words 14h–17h.
    pub bootstrap_mailbox: MailboxConfig,
    /// Words 18h–1Bh.
    pub standard_mailbox: MailboxConfig,
    /// Word 1Ch ([`protocol`] bits).
    pub mailbox_protocols: u16,
    /// Word 3Eh: EEPROM size in KiBit − 1.
    pub eeprom_size: u16,
    /// Word 3Fh.
    pub version: u16,
}

impl SiiHeader {
    /// Parses the first 128 bytes of an image (more are allowed and ignored); the checksum in
    /// word 7 must match.
    pub fn parse(bytes: &[u8]) -> Result<SiiHeader, Error> {
        let b = Reader::new(bytes).bytes(HEADER_LEN, "SII header")?;
        let computed = crc8(&b[..14]);
        if b[14] != computed {
            return Err(Error::SiiChecksum {
                stored: b[14],
                computed,
            });
        }
        let w = |n: u16| le16(b, 2 * usize::from(n));
        let d = |n: u16| le32(b, 2 * usize::from(n));
        Ok(SiiHeader {
            pdi_control: w(word::PDI_CONTROL),
            pdi_config: w(word::PDI_CONFIG),
            sync_impulse: w(word::SYNC_IMPULSE),
            pdi_config2: w(word::PDI_CONFIG2),
            station_alias: w(word::STATION_ALIAS),
            vendor_id: d(word::VENDOR_ID),
            product_code: d(word::PRODUCT_CODE),
            revision: d(word::REVISION),
            serial: d(word::SERIAL),
            execution_delay: w(word::EXECUTION_DELAY),
            port0_delay: w(word::PORT0_DELAY),
            port1_delay: w(word::PORT1_DELAY),
            bootstrap_mailbox: MailboxConfig {
                rx_offset: w(word::BOOT_RX_OFFSET),
                rx_size: w(word::BOOT_RX_SIZE),
                tx_offset: w(word::BOOT_TX_OFFSET),
                tx_size: w(word::BOOT_TX_SIZE),
            },
            standard_mailbox: MailboxConfig {
                rx_offset: w(word::STD_RX_OFFSET),
                rx_size: w(word::STD_RX_SIZE),
                tx_offset: w(word::STD_TX_OFFSET),
                tx_size: w(word::STD_TX_SIZE),
            },
            mailbox_protocols: w(word::MAILBOX_PROTOCOL),
            eeprom_size: w(word::SIZE),
            version: w(word::VERSION),
        })
    }

    /// The 128 header bytes, checksum computed.
    pub fn emit(&self) -> [u8; HEADER_LEN] {
        let mut b = [0; HEADER_LEN];
        let mut w = |n: u16, v: u16| {
            let at = 2 * usize::from(n);
            b[at..at + 2].copy_from_slice(&v.to_le_bytes());
        };
        w(word::PDI_CONTROL, self.pdi_control);
        w(word::PDI_CONFIG, self.pdi_config);
        w(word::SYNC_IMPULSE, self.sync_impulse);
        w(word::PDI_CONFIG2, self.pdi_config2);
        w(word::STATION_ALIAS, self.station_alias);
        for (n, v) in [
            (word::VENDOR_ID, self.vendor_id),
            (word::PRODUCT_CODE, self.product_code),
            (word::REVISION, self.revision),
            (word::SERIAL, self.serial),
        ] {
            w(n, v as u16);
            w(n + 1, (v >> 16) as u16);
        }
        w(word::EXECUTION_DELAY, self.execution_delay);
        w(word::PORT0_DELAY, self.port0_delay);
        w(word::PORT1_DELAY, self.port1_delay);
        let (bm, sm) = (self.bootstrap_mailbox, self.standard_mailbox);
        w(word::BOOT_RX_OFFSET, bm.rx_offset);
        w(word::BOOT_RX_SIZE, bm.rx_size);
        w(word::BOOT_TX_OFFSET, bm.tx_offset);
        w(word::BOOT_TX_SIZE, bm.tx_size);
        w(word::STD_RX_OFFSET, sm.rx_offset);
        w(word::STD_RX_SIZE, sm.rx_size);
        w(word::STD_TX_OFFSET, sm.tx_offset);
        w(word::STD_TX_SIZE, sm.tx_size);
        w(word::MAILBOX_PROTOCOL, self.mailbox_protocols);
        w(word::SIZE, self.eeprom_size);
        w(word::VERSION, self.version);
        b[14] = crc8(&b[..14]);
        b
    }

    /// EEPROM size in bytes from word 3Eh ((value + 1) KiBit).
    pub fn eeprom_bytes(&self) -> usize {
        (usize::from(self.eeprom_size) + 1) * 128
    }
}

/// A category type (ETG.2010 category types; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct CategoryType(pub u16);

impl CategoryType {
    /// No operation.
    pub const NOP: CategoryType = CategoryType(0);
    /// Strings.
    pub const STRINGS: CategoryType = CategoryType(10);
    /// Data types.
    pub const DATA_TYPES: CategoryType = CategoryType(20);
    /// General.
    pub const GENERAL: CategoryType = CategoryType(30);
    /// FMMU usage.
    pub const FMMU: CategoryType = CategoryType(40);
    /// SyncManagers.
    pub const SYNCM: CategoryType = CategoryType(41);
    /// FMMU extension (ETG.2010).
    pub const FMMU_EX: CategoryType = CategoryType(42);
    /// SyncUnit assignment (ETG.2010).
    pub const SYNC_UNIT: CategoryType = CategoryType(43);
    /// TxPDOs (inputs).
    pub const TXPDO: CategoryType = CategoryType(50);
    /// RxPDOs (outputs).
    pub const RXPDO: CategoryType = CategoryType(51);
    /// Distributed clock.
    pub const DC: CategoryType = CategoryType(60);
    /// End of the category list.
    pub const END: CategoryType = CategoryType(0xFFFF);

    /// The type's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self.0 {
            0 => "NOP",
            10 => "STRINGS",
            20 => "DATATYPES",
            30 => "GENERAL",
            40 => "FMMU",
            41 => "SYNCM",
            42 => "FMMU_EX",
            43 => "SYNCUNIT",
            50 => "TXPDO",
            51 => "RXPDO",
            60 => "DC",
            0xFFFF => "END",
            _ => return None,
        })
    }
}

impl fmt::Debug for CategoryType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "CategoryType::{n}"),
            None => write!(f, "CategoryType({})", self.0),
        }
    }
}

/// Bits of the general category's "CoE details" byte (ETG.2010 category General).
pub mod coe_details {
    /// Bit 0: SDO supported.
    pub const SDO: u8 = 0x01;
    /// Bit 1: SDO information.
    pub const SDO_INFO: u8 = 0x02;
    /// Bit 2: PDO assignment (1C12h/1C13h writable).
    pub const PDO_ASSIGN: u8 = 0x04;
    /// Bit 3: PDO configuration (mapping writable).
    pub const PDO_CONFIG: u8 = 0x08;
    /// Bit 4: PDO upload at startup.
    pub const UPLOAD_AT_STARTUP: u8 = 0x10;
    /// Bit 5: SDO complete access.
    pub const COMPLETE_ACCESS: u8 = 0x20;
}

/// Bits of the general category's "flags" byte (ETG.2010 category General).
pub mod general_flags {
    /// Bit 0: enable SAFE-OP.
    pub const ENABLE_SAFEOP: u8 = 0x01;
    /// Bit 1: enable not LRW (LRD/LWR instead).
    pub const ENABLE_NOT_LRW: u8 = 0x02;
    /// Bit 2: mailbox data link layer.
    pub const MBOX_DLL: u8 = 0x04;
    /// Bit 3: identification value in AL status code (explicit device id).
    pub const IDENT_AL_STS: u8 = 0x08;
    /// Bit 4: identification value in physical memory.
    pub const IDENT_PHY_M: u8 = 0x10;
}

/// The general category (type 30, 32 bytes; ETG.2010 category General). String indices count from 1
/// (0 = none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct General {
    /// Group string index.
    pub group: u8,
    /// Image string index.
    pub image: u8,
    /// Order number string index.
    pub order: u8,
    /// Device name string index.
    pub name: u8,
    /// CoE details ([`coe_details`]).
    pub coe_details: u8,
    /// FoE details (bit 0: supported).
    pub foe_details: u8,
    /// EoE details (bit 0: supported).
    pub eoe_details: u8,
    /// SoE channels.
    pub soe_channels: u8,
    /// DS402 channels.
    pub ds402_channels: u8,
    /// SysmanClass.
    pub sysman_class: u8,
    /// Flags ([`general_flags`]).
    pub flags: u8,
    /// Current consumption on E-bus in mA (negative: feeds current).
    pub ebus_current: i16,
    /// Physical port types, 4 bits per port 0..3 (0 none, 1 MII, 2 reserved, 3 EBUS).
    pub physical_port: u16,
    /// Physical memory address of the identification value.
    pub physical_memory_address: u16,
}

impl General {
    /// Length of the category data.
    pub const LEN: usize = 32;

    /// Parses the category data (at least 16 bytes; the port and address fields read as 0 if
    /// an old 16-byte category lacks them).
    pub fn parse(b: &[u8]) -> Result<General, Error> {
        let mut r = Reader::new(b);
        let h = r.bytes(16, "SII general category")?;
        let physical_port = if b.len() >= 18 { le16(b, 16) } else { 0 };
        let physical_memory_address = if b.len() >= 20 { le16(b, 18) } else { 0 };
        Ok(General {
            group: h[0],
            image: h[1],
            order: h[2],
            name: h[3],
            coe_details: h[5],
            foe_details: h[6],
            eoe_details: h[7],
            soe_channels: h[8],
            ds402_channels: h[9],
            sysman_class: h[10],
            flags: h[11],
            ebus_current: i16::from_le_bytes([h[12], h[13]]),
            physical_port,
            physical_memory_address,
        })
    }

    /// The 32 bytes (byte 14 repeats the group index, as ETG.2010 asks for compatibility).
    pub fn emit(&self) -> Vec<u8> {
        let mut b = vec![
            self.group,
            self.image,
            self.order,
            self.name,
            0,
            self.coe_details,
            self.foe_details,
            self.eoe_details,
            self.soe_channels,
            self.ds402_channels,
            self.sysman_class,
            self.flags,
        ];
        b.extend(self.ebus_current.to_le_bytes());
        b.extend([self.group, 0]);
        b.extend(self.physical_port.to_le_bytes());
        b.extend(self.physical_memory_address.to_le_bytes());
        b.resize(Self::LEN, 0);
        b
    }
}

/// An FMMU usage byte of the FMMU category (type 40; ETG.2010 category FMMU; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FmmuUsage(pub u8);

impl FmmuUsage {
    /// Not used.
    pub const UNUSED: FmmuUsage = FmmuUsage(0x00);
    /// Outputs.
    pub const OUTPUTS: FmmuUsage = FmmuUsage(0x01);
    /// Inputs.
    pub const INPUTS: FmmuUsage = FmmuUsage(0x02);
    /// SyncManager status (mailbox-full polling by logical read).
    pub const SYNCM_STATUS: FmmuUsage = FmmuUsage(0x03);
    /// Not used (FFh).
    pub const UNUSED_FF: FmmuUsage = FmmuUsage(0xFF);
}

impl fmt::Debug for FmmuUsage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = match self.0 {
            0x00 | 0xFF => "unused",
            0x01 => "outputs",
            0x02 => "inputs",
            0x03 => "SyncM status",
            _ => return write!(f, "FmmuUsage({:02X}h)", self.0),
        };
        write!(f, "FmmuUsage({n})")
    }
}

/// The type of a SyncManager in the SyncM category (ETG.2010 category SyncM; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SmType(pub u8);

impl SmType {
    /// Not used or unknown.
    pub const UNUSED: SmType = SmType(0);
    /// Mailbox out (master → slave).
    pub const MAILBOX_OUT: SmType = SmType(1);
    /// Mailbox in (slave → master).
    pub const MAILBOX_IN: SmType = SmType(2);
    /// Process data outputs.
    pub const OUTPUTS: SmType = SmType(3);
    /// Process data inputs.
    pub const INPUTS: SmType = SmType(4);
}

impl fmt::Debug for SmType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = match self.0 {
            0 => "unused",
            1 => "mailbox out",
            2 => "mailbox in",
            3 => "outputs",
            4 => "inputs",
            _ => return write!(f, "SmType({})", self.0),
        };
        write!(f, "SmType({n})")
    }
}

/// Bits of a SyncM category entry's "enable" byte (ETG.2010 category SyncM).
pub mod sm_enable {
    /// Bit 0: enable.
    pub const ENABLE: u8 = 0x01;
    /// Bit 1: fixed content.
    pub const FIXED: u8 = 0x02;
    /// Bit 2: virtual SyncManager (no hardware resource).
    pub const VIRTUAL: u8 = 0x04;
    /// Bit 3: enabled in OP only.
    pub const OP_ONLY: u8 = 0x08;
}

/// One SyncManager of the SyncM category (type 41, 8 bytes each; ETG.2010 category SyncM).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SiiSm {
    /// Physical start address.
    pub start: u16,
    /// Length.
    pub length: u16,
    /// Control byte (as register 0804h).
    pub control: u8,
    /// Status byte (don't care).
    pub status: u8,
    /// Enable byte ([`sm_enable`]).
    pub enable: u8,
    /// Type.
    pub kind: SmType,
}

impl SiiSm {
    /// Length of one entry.
    pub const LEN: usize = 8;

    fn parse(b: &[u8]) -> SiiSm {
        SiiSm {
            start: le16(b, 0),
            length: le16(b, 2),
            control: b[4],
            status: b[5],
            enable: b[6],
            kind: SmType(b[7]),
        }
    }

    fn emit(&self, out: &mut Vec<u8>) {
        out.extend(self.start.to_le_bytes());
        out.extend(self.length.to_le_bytes());
        out.extend([self.control, self.status, self.enable, self.kind.0]);
    }
}

/// One entry of a PDO (8 bytes; ETG.2010 category TxPDO/RxPDO).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SiiPdoEntry {
    /// Mapped object index (0 for a gap).
    pub index: u16,
    /// Mapped sub-index.
    pub sub: u8,
    /// Name string index.
    pub name: u8,
    /// Data type (the CoE data type index of ETG.1000.6 / CiA 301: 05h UNSIGNED8, 06h
    /// UNSIGNED16 …).
    pub data_type: u8,
    /// Length in bits.
    pub bit_len: u8,
    /// Flags (reserved).
    pub flags: u16,
}

/// A PDO of the TxPDO/RxPDO categories (types 50/51; ETG.2010 category TxPDO/RxPDO).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct SiiPdo {
    /// PDO index (1600h… RxPDO, 1A00h… TxPDO).
    pub index: u16,
    /// SyncManager the PDO is assigned to (FFh: none).
    pub sm: u8,
    /// DC synchronisation.
    pub dc_sync: u8,
    /// Name string index.
    pub name: u8,
    /// Flags (bit 0 mandatory, bit 1 default, bit 4 fixed content, …).
    pub flags: u16,
    /// The mapped entries.
    pub entries: Vec<SiiPdoEntry>,
}

impl SiiPdo {
    /// Total bits of the entries.
    pub fn bit_len(&self) -> u32 {
        self.entries.iter().map(|e| u32::from(e.bit_len)).sum()
    }

    /// Parses every PDO of a category's data.
    pub fn parse_all(b: &[u8]) -> Result<Vec<SiiPdo>, Error> {
        let mut r = Reader::new(b);
        let mut out = Vec::new();
        while r.remaining() > 0 {
            let h = r.bytes(8, "SII PDO header")?;
            let n = h[2];
            let mut entries = Vec::with_capacity(usize::from(n));
            for _ in 0..n {
                let e = r.bytes(8, "SII PDO entry")?;
                entries.push(SiiPdoEntry {
                    index: le16(e, 0),
                    sub: e[2],
                    name: e[3],
                    data_type: e[4],
                    bit_len: e[5],
                    flags: le16(e, 6),
                });
            }
            out.push(SiiPdo {
                index: le16(h, 0),
                sm: h[3],
                dc_sync: h[4],
                name: h[5],
                flags: le16(h, 6),
                entries,
            });
        }
        Ok(out)
    }

    fn emit(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        let n = fit("SII PDO entries", self.entries.len(), 255)?;
        out.extend(self.index.to_le_bytes());
        out.extend([n as u8, self.sm, self.dc_sync, self.name]);
        out.extend(self.flags.to_le_bytes());
        for e in &self.entries {
            out.extend(e.index.to_le_bytes());
            out.extend([e.sub, e.name, e.data_type, e.bit_len]);
            out.extend(e.flags.to_le_bytes());
        }
        Ok(())
    }
}

/// One category of the image.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Category {
    /// Strings (type 10): numbered from 1 in order.
    Strings(Vec<String>),
    /// General (type 30).
    General(General),
    /// FMMU usage (type 40), one byte per FMMU. The category is whole words: an odd count is
    /// emitted with a pad byte 00h, which reads back as one more unused FMMU.
    Fmmu(Vec<FmmuUsage>),
    /// SyncManagers (type 41).
    SyncM(Vec<SiiSm>),
    /// TxPDOs (type 50).
    TxPdo(Vec<SiiPdo>),
    /// RxPDOs (type 51).
    RxPdo(Vec<SiiPdo>),
    /// Any other category (data types, DC, vendor specific), kept as bytes.
    Other {
        /// Its type.
        kind: CategoryType,
        /// Its data (even length).
        data: Vec<u8>,
    },
}

fn latin1(b: &[u8]) -> String {
    b.iter().map(|&c| char::from(c)).collect()
}

impl Category {
    /// The category's type.
    pub fn kind(&self) -> CategoryType {
        match self {
            Category::Strings(_) => CategoryType::STRINGS,
            Category::General(_) => CategoryType::GENERAL,
            Category::Fmmu(_) => CategoryType::FMMU,
            Category::SyncM(_) => CategoryType::SYNCM,
            Category::TxPdo(_) => CategoryType::TXPDO,
            Category::RxPdo(_) => CategoryType::RXPDO,
            Category::Other { kind, .. } => *kind,
        }
    }

    /// Parses the data of a category of type `kind`.
    pub fn parse(kind: CategoryType, data: &[u8]) -> Result<Category, Error> {
        Ok(match kind {
            CategoryType::STRINGS => {
                let mut r = Reader::new(data);
                let n = r.u8("SII string count")?;
                let mut v = Vec::with_capacity(usize::from(n));
                for _ in 0..n {
                    let len = r.u8("SII string length")?;
                    v.push(latin1(r.bytes(usize::from(len), "SII string")?));
                }
                // At most the pad byte to a whole word may follow.
                Category::Strings(v)
            }
            CategoryType::GENERAL => Category::General(General::parse(data)?),
            CategoryType::FMMU => Category::Fmmu(data.iter().map(|&b| FmmuUsage(b)).collect()),
            CategoryType::SYNCM => {
                if !data.len().is_multiple_of(SiiSm::LEN) {
                    return Err(Error::Trailing {
                        what: "SII SyncM category (8 bytes per SyncManager)",
                        extra: data.len() % SiiSm::LEN,
                    });
                }
                Category::SyncM(data.chunks_exact(SiiSm::LEN).map(SiiSm::parse).collect())
            }
            CategoryType::TXPDO => Category::TxPdo(SiiPdo::parse_all(data)?),
            CategoryType::RXPDO => Category::RxPdo(SiiPdo::parse_all(data)?),
            kind => Category::Other {
                kind,
                data: data.to_vec(),
            },
        })
    }

    /// The category's data, padded to a whole number of words.
    pub fn emit_data(&self) -> Result<Vec<u8>, Error> {
        let mut out = Vec::new();
        match self {
            Category::Strings(v) => {
                out.push(fit("SII string count", v.len(), 255)? as u8);
                for s in v {
                    let bytes = s
                        .chars()
                        .map(|c| {
                            u8::try_from(u32::from(c)).map_err(|_| Error::Invalid {
                                field: "SII string",
                                value: u32::from(c),
                                why: "not a Latin-1 character",
                            })
                        })
                        .collect::<Result<Vec<u8>, _>>()?;
                    out.push(fit("SII string length", bytes.len(), 255)? as u8);
                    out.extend(bytes);
                }
            }
            Category::General(g) => out = g.emit(),
            Category::Fmmu(v) => out.extend(v.iter().map(|f| f.0)),
            Category::SyncM(v) => v.iter().for_each(|s| s.emit(&mut out)),
            Category::TxPdo(v) | Category::RxPdo(v) => {
                for p in v {
                    p.emit(&mut out)?;
                }
            }
            Category::Other { data, .. } => out.extend(data),
        }
        if out.len() % 2 == 1 {
            out.push(0);
        }
        Ok(out)
    }
}

/// A whole SII image: the fixed header and the categories in order.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct SiiRepr {
    /// Words 0–3Fh.
    pub header: SiiHeader,
    /// Categories from word 40h, in order (the END marker is implied).
    pub categories: Vec<Category>,
}

impl SiiRepr {
    /// Parses an image (bytes, little-endian words): header with checksum, then categories up
    /// to the END marker. Every category's size is checked against the image.
    pub fn parse(bytes: &[u8]) -> Result<SiiRepr, Error> {
        let header = SiiHeader::parse(bytes)?;
        let mut r = Reader::new(&bytes[HEADER_LEN..]);
        let mut categories = Vec::new();
        loop {
            let kind = CategoryType(r.u16("SII category type")?);
            if kind == CategoryType::END {
                break;
            }
            let words = usize::from(r.u16("SII category size")?);
            let available = r.remaining();
            let data = r
                .bytes(2 * words, "SII category data")
                .map_err(|_| Error::Length {
                    field: "SII category size (bytes)",
                    value: 2 * words,
                    available,
                })?;
            categories.push(Category::parse(kind, data)?);
        }
        Ok(SiiRepr { header, categories })
    }

    /// Parses an image given as words.
    pub fn parse_words(words: &[u16]) -> Result<SiiRepr, Error> {
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        SiiRepr::parse(&bytes)
    }

    /// The image's bytes: header, categories, END marker (no padding).
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut out = self.header.emit().to_vec();
        for c in &self.categories {
            let data = c.emit_data()?;
            let words = fit("SII category size (words)", data.len() / 2, 0xFFFF)?;
            out.extend(c.kind().0.to_le_bytes());
            out.extend((words as u16).to_le_bytes());
            out.extend(data);
        }
        out.extend(CategoryType::END.0.to_le_bytes());
        Ok(out)
    }

    /// The image padded with FFh (erased EEPROM) to the size word 3Eh declares.
    pub fn emit_image(&self) -> Result<Vec<u8>, Error> {
        let mut out = self.emit()?;
        let size = self.header.eeprom_bytes();
        fit("SII image", out.len(), size)?;
        out.resize(size, 0xFF);
        Ok(out)
    }

    /// The padded image as words (what an ESC's EEPROM interface serves).
    pub fn emit_words(&self) -> Result<Vec<u16>, Error> {
        Ok(self
            .emit_image()?
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect())
    }

    /// The strings category's strings (empty if there is none).
    pub fn strings(&self) -> &[String] {
        self.categories
            .iter()
            .find_map(|c| match c {
                Category::Strings(v) => Some(v.as_slice()),
                _ => None,
            })
            .unwrap_or(&[])
    }

    /// String `index` (from 1; 0 or out of range: `None`).
    pub fn string(&self, index: u8) -> Option<&str> {
        let i = usize::from(index).checked_sub(1)?;
        self.strings().get(i).map(String::as_str)
    }

    /// The general category.
    pub fn general(&self) -> Option<&General> {
        self.categories.iter().find_map(|c| match c {
            Category::General(g) => Some(g),
            _ => None,
        })
    }

    /// The FMMU category's entries.
    pub fn fmmus(&self) -> &[FmmuUsage] {
        self.categories
            .iter()
            .find_map(|c| match c {
                Category::Fmmu(v) => Some(v.as_slice()),
                _ => None,
            })
            .unwrap_or(&[])
    }

    /// The SyncM category's entries.
    pub fn sync_managers(&self) -> &[SiiSm] {
        self.categories
            .iter()
            .find_map(|c| match c {
                Category::SyncM(v) => Some(v.as_slice()),
                _ => None,
            })
            .unwrap_or(&[])
    }

    /// Every TxPDO (all TxPDO categories).
    pub fn tx_pdos(&self) -> Vec<&SiiPdo> {
        self.categories
            .iter()
            .flat_map(|c| match c {
                Category::TxPdo(v) => v.iter().collect(),
                _ => Vec::new(),
            })
            .collect()
    }

    /// Every RxPDO (all RxPDO categories).
    pub fn rx_pdos(&self) -> Vec<&SiiPdo> {
        self.categories
            .iter()
            .flat_map(|c| match c {
                Category::RxPdo(v) => v.iter().collect(),
                _ => Vec::new(),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Words 0–7 of a Beckhoff EK1100's EEPROM (a real device's dump): PDI control 0D00h,
    /// words 1–6 zero, checksum 46h.
    const EK1100_CONFIG: [u8; 16] = [
        0x00, 0x0D, // PDI control
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // words 1–6
        0x46, 0x00, // checksum
    ];

    fn sample() -> SiiRepr {
        SiiRepr {
            header: SiiHeader {
                pdi_control: 0x0C08,
                pdi_config: 0x0000,
                station_alias: 0x1234,
                vendor_id: 0x0000_0538,
                product_code: 0x0000_0550,
                revision: 0x0001_0000,
                serial: 7,
                standard_mailbox: MailboxConfig {
                    rx_offset: 0x1000,
                    rx_size: 128,
                    tx_offset: 0x1080,
                    tx_size: 128,
                },
                mailbox_protocols: protocol::COE,
                eeprom_size: 15,
                version: 1,
                ..SiiHeader::default()
            },
            categories: vec![
                Category::Strings(vec!["SK 550P".into(), "Drives".into(), "ä".into()]),
                Category::General(General {
                    group: 2,
                    order: 1,
                    name: 1,
                    coe_details: coe_details::SDO
                        | coe_details::SDO_INFO
                        | coe_details::COMPLETE_ACCESS,
                    physical_port: 0x0011,
                    ..General::default()
                }),
                Category::Fmmu(vec![
                    FmmuUsage::OUTPUTS,
                    FmmuUsage::INPUTS,
                    FmmuUsage::SYNCM_STATUS,
                    FmmuUsage::UNUSED_FF,
                ]),
                Category::SyncM(vec![
                    SiiSm {
                        start: 0x1000,
                        length: 128,
                        control: 0x26,
                        status: 0,
                        enable: sm_enable::ENABLE,
                        kind: SmType::MAILBOX_OUT,
                    },
                    SiiSm {
                        start: 0x1080,
                        length: 128,
                        control: 0x22,
                        status: 0,
                        enable: sm_enable::ENABLE,
                        kind: SmType::MAILBOX_IN,
                    },
                ]),
                Category::RxPdo(vec![SiiPdo {
                    index: 0x1600,
                    sm: 2,
                    dc_sync: 0,
                    name: 0,
                    flags: 0x0011,
                    entries: vec![
                        SiiPdoEntry {
                            index: 0x7000,
                            sub: 1,
                            name: 0,
                            data_type: 6,
                            bit_len: 16,
                            flags: 0,
                        };
                        6
                    ],
                }]),
                Category::Other {
                    kind: CategoryType::DC,
                    data: vec![0; 24],
                },
            ],
        }
    }

    #[test]
    fn crc_of_a_real_device() {
        assert_eq!(crc8(&EK1100_CONFIG[..14]), 0x46);
        assert_eq!(crc8(b"123456789"), 0xFB);
        assert_eq!(crc8(&[]), 0xFF);
        let mut image = EK1100_CONFIG.to_vec();
        image.resize(HEADER_LEN, 0);
        let h = SiiHeader::parse(&image).unwrap();
        assert_eq!(h.pdi_control, 0x0D00);
        assert_eq!(&h.emit()[..16], EK1100_CONFIG);
    }

    #[test]
    fn header_words() {
        let b = sample().header.emit();
        // Word 4 alias, words 8–9 vendor 538h, word 18h/19h mailbox, word 1Ch CoE.
        assert_eq!(&b[8..10], [0x34, 0x12]);
        assert_eq!(&b[16..20], [0x38, 0x05, 0x00, 0x00]);
        assert_eq!(&b[0x30..0x34], [0x00, 0x10, 0x80, 0x00]);
        assert_eq!(&b[0x38..0x3A], [0x04, 0x00]);
        assert_eq!(&b[0x7C..0x80], [15, 0, 1, 0]);
        assert_eq!(sample().header.eeprom_bytes(), 2048);
    }

    #[test]
    fn round_trip() {
        let s = sample();
        let img = s.emit_image().unwrap();
        assert_eq!(img.len(), 2048);
        let back = SiiRepr::parse(&img).unwrap();
        assert_eq!(back, s);
        assert_eq!(SiiRepr::parse_words(&s.emit_words().unwrap()).unwrap(), s);
        assert_eq!(back.string(1), Some("SK 550P"));
        assert_eq!(back.string(3), Some("ä"));
        assert_eq!((back.string(0), back.string(4)), (None, None));
        assert_eq!(back.general().unwrap().coe_details, 0x23);
        assert_eq!(back.sync_managers().len(), 2);
        assert_eq!(back.fmmus().len(), 4);
        // An odd FMMU count reads back with the pad byte as an unused FMMU.
        let odd = Category::Fmmu(vec![FmmuUsage::OUTPUTS])
            .emit_data()
            .unwrap();
        assert_eq!(odd, [0x01, 0x00]);
        assert_eq!(back.rx_pdos()[0].bit_len(), 96);
        assert!(back.tx_pdos().is_empty());
        // The categories start at word 40h: strings, 9 words (count, 1+7, 1+6, 1+1 bytes),
        // "SK 550P" first.
        assert_eq!(&img[128..134], [10, 0, 9, 0, 3, 7]);
        assert_eq!(&img[134..141], b"SK 550P");
    }

    #[test]
    fn checksum_and_lengths_are_checked() {
        let img = sample().emit_image().unwrap();
        let mut bad = img.clone();
        bad[8] ^= 1; // alias changed, checksum not
        assert!(matches!(
            SiiRepr::parse(&bad),
            Err(Error::SiiChecksum { .. })
        ));
        // Truncation at every length up to the END marker is an error.
        let end = sample().emit().unwrap().len();
        for n in 0..end {
            assert!(SiiRepr::parse(&img[..n]).is_err(), "{n}");
        }
        assert!(SiiRepr::parse(&img[..end]).is_ok());
        // A category claiming more words than the image has.
        let mut lie = sample().emit().unwrap();
        lie[130] = 0xFF;
        lie[131] = 0x7F;
        assert!(matches!(
            SiiRepr::parse(&lie),
            Err(Error::Length {
                field: "SII category size (bytes)",
                ..
            })
        ));
        // A SyncM category of 6 bytes.
        assert!(matches!(
            Category::parse(CategoryType::SYNCM, &[0; 6]),
            Err(Error::Trailing { .. })
        ));
        // A PDO claiming more entries than present.
        assert!(matches!(
            Category::parse(CategoryType::TXPDO, &[0, 0x1A, 2, 3, 0, 0, 0, 0, 1, 2]),
            Err(Error::Truncated {
                what: "SII PDO entry",
                ..
            })
        ));
        assert!(Category::parse(CategoryType::STRINGS, &[2, 3, b'a']).is_err());
        assert!(Category::parse(CategoryType::GENERAL, &[0; 15]).is_err());
    }

    #[test]
    fn emit_errors() {
        let mut s = sample();
        s.header.eeprom_size = 0; // 128 bytes: the categories do not fit
        assert!(matches!(s.emit_image(), Err(Error::TooLong { .. })));
        let c = Category::Strings(vec!["€".into()]);
        assert!(matches!(c.emit_data(), Err(Error::Invalid { .. })));
    }

    #[test]
    fn names() {
        assert_eq!(format!("{:?}", CategoryType::SYNCM), "CategoryType::SYNCM");
        assert_eq!(format!("{:?}", CategoryType(0x0800)), "CategoryType(2048)");
        assert_eq!(format!("{:?}", SmType::INPUTS), "SmType(inputs)");
        assert_eq!(format!("{:?}", FmmuUsage(9)), "FmmuUsage(09h)");
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn mailbox_config() -> impl Strategy<Value = MailboxConfig> {
            any::<(u16, u16, u16, u16)>().prop_map(|(rx_offset, rx_size, tx_offset, tx_size)| {
                MailboxConfig {
                    rx_offset,
                    rx_size,
                    tx_offset,
                    tx_size,
                }
            })
        }

        fn header() -> impl Strategy<Value = SiiHeader> {
            (
                any::<(u16, u16, u16, u16, u16)>(),
                any::<(u32, u32, u32, u32)>(),
                any::<(u16, u16, u16)>(),
                (mailbox_config(), mailbox_config()),
                any::<(u16, u16, u16)>(),
            )
                .prop_map(
                    |(p, ids, delays, (bootstrap_mailbox, standard_mailbox), tail)| SiiHeader {
                        pdi_control: p.0,
                        pdi_config: p.1,
                        sync_impulse: p.2,
                        pdi_config2: p.3,
                        station_alias: p.4,
                        vendor_id: ids.0,
                        product_code: ids.1,
                        revision: ids.2,
                        serial: ids.3,
                        execution_delay: delays.0,
                        port0_delay: delays.1,
                        port1_delay: delays.2,
                        bootstrap_mailbox,
                        standard_mailbox,
                        mailbox_protocols: tail.0,
                        eeprom_size: tail.1,
                        version: tail.2,
                    },
                )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn header_round_trips(h in header()) {
                prop_assert_eq!(SiiHeader::parse(&h.emit()), Ok(h));
                let image = SiiRepr { header: h, categories: Vec::new() };
                prop_assert_eq!(SiiRepr::parse(&image.emit().unwrap()), Ok(image));
            }

            /// Whatever the image parser accepts (a valid header, then arbitrary category words)
            /// emits to an image that parses to the same value; no category parser panics.
            #[test]
            fn parsed_images_reparse_to_themselves(
                h in header(),
                kinds in vec(prop_oneof![0u16..=60, any::<u16>()], 0..4),
                data in vec(vec(any::<u8>(), 0..24), 0..4),
            ) {
                let mut b = h.emit().to_vec();
                for (k, d) in kinds.iter().zip(&data) {
                    b.extend(k.to_le_bytes());
                    b.extend(((d.len() / 2) as u16).to_le_bytes());
                    b.extend(&d[..d.len() / 2 * 2]);
                }
                b.extend(CategoryType::END.0.to_le_bytes());
                if let Ok(image) = SiiRepr::parse(&b) {
                    let again = image.emit().unwrap();
                    prop_assert_eq!(SiiRepr::parse(&again), Ok(image));
                }
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..160)) {
                let _ = SiiHeader::parse(&bytes);
                let _ = SiiRepr::parse(&bytes);
            }
        }
    }
}
