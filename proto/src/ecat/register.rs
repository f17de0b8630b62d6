//! ESC registers a master needs (ETG.1000.4 register descriptions; Beckhoff "EtherCAT Slave
//! Controller — Section II Register Description" (ET1100/ET1200/IP core), "Register address
//! space"), with typed reprs for the blocks masters read and write
//! whole: the SyncManager channel (8 bytes), the FMMU (16 bytes), the SII EEPROM
//! control/status word, the DL status. AL control and status live in [`super::al`] and are
//! re-exported here.
//!
//! Every register is little-endian. Addresses are byte offsets in the ESC's physical memory
//! (the ADO of a position or fixed address command).

use std::fmt;

use crate::wire::{Error, Reader};

pub use super::al::{AlControl, AlStatus};

/// 0000h Type (u8): the ESC type (ET1100 = 11h, ET1200 = 12h, IP core = 04h/…).
pub const TYPE: u16 = 0x0000;
/// 0001h Revision (u8).
pub const REVISION: u16 = 0x0001;
/// 0002h Build (u16).
pub const BUILD: u16 = 0x0002;
/// 0004h FMMUs supported (u8).
pub const FMMUS_SUPPORTED: u16 = 0x0004;
/// 0005h SyncManagers supported (u8).
pub const SMS_SUPPORTED: u16 = 0x0005;
/// 0006h RAM size in KiB (u8).
pub const RAM_SIZE: u16 = 0x0006;
/// 0007h Port descriptor (u8: 2 bits per port, 00 not implemented, 01 not configured, 10 EBUS,
/// 11 MII).
pub const PORT_DESCRIPTOR: u16 = 0x0007;
/// 0008h ESC features supported (u16, see [`features`]).
pub const FEATURES: u16 = 0x0008;
/// 0010h Configured station address (u16), set by the master.
pub const STATION_ADDRESS: u16 = 0x0010;
/// 0012h Configured station alias (u16), loaded from SII word 4.
pub const STATION_ALIAS: u16 = 0x0012;
/// 0020h Write register enable (u8).
pub const WRITE_ENABLE: u16 = 0x0020;
/// 0021h Write register protection (u8).
pub const WRITE_PROTECTION: u16 = 0x0021;
/// 0030h ESC write enable (u8).
pub const ESC_WRITE_ENABLE: u16 = 0x0030;
/// 0031h ESC write protection (u8).
pub const ESC_WRITE_PROTECTION: u16 = 0x0031;
/// 0040h ESC reset ECAT (u8): the sequence 52h 45h 53h ('R' 'E' 'S') resets the ESC.
pub const ESC_RESET_ECAT: u16 = 0x0040;
/// 0041h ESC reset PDI (u8).
pub const ESC_RESET_PDI: u16 = 0x0041;
/// 0100h DL control (u32): forwarding rule (bit 0), temporary loop (1), loop port 0..3 (bits
/// 8–15, 2 bits each), RX FIFO size (16–18), station alias enable (24).
pub const DL_CONTROL: u16 = 0x0100;
/// 0108h Physical read/write offset (u16).
pub const PHYSICAL_RW_OFFSET: u16 = 0x0108;
/// 0110h DL status (u16, see [`DlStatus`]).
pub const DL_STATUS: u16 = 0x0110;
/// 0120h AL control (u16, see [`AlControl`]).
pub const AL_CONTROL: u16 = 0x0120;
/// 0130h AL status (u16, see [`AlStatus`]).
pub const AL_STATUS: u16 = 0x0130;
/// 0134h AL status code (u16, see [`super::al::AlStatusCode`]).
pub const AL_STATUS_CODE: u16 = 0x0134;
/// 0138h RUN LED override (u8).
pub const RUN_LED_OVERRIDE: u16 = 0x0138;
/// 0139h ERR LED override (u8).
pub const ERR_LED_OVERRIDE: u16 = 0x0139;
/// 0140h PDI control (u8: the PDI type; 00h none, 04h digital I/O, 05h SPI, 08h/09h µC …).
pub const PDI_CONTROL: u16 = 0x0140;
/// 0141h ESC configuration (u8).
pub const ESC_CONFIG: u16 = 0x0141;
/// 0150h PDI configuration (u8), from SII word 1.
pub const PDI_CONFIG: u16 = 0x0150;
/// 0151h SYNC/LATCH PDI configuration (u8).
pub const SYNC_LATCH_CONFIG: u16 = 0x0151;
/// 0152h Extended PDI configuration (u16), from SII word 3.
pub const PDI_CONFIG_EXT: u16 = 0x0152;
/// 0200h ECAT event mask (u16).
pub const ECAT_EVENT_MASK: u16 = 0x0200;
/// 0204h AL event mask (u32).
pub const AL_EVENT_MASK: u16 = 0x0204;
/// 0210h ECAT event request (u16): the bits ORed into a datagram's IRQ field.
pub const ECAT_EVENT_REQUEST: u16 = 0x0210;
/// 0220h AL event request (u32).
pub const AL_EVENT_REQUEST: u16 = 0x0220;
/// 0300h RX error counters: per port 0..3 an invalid frame counter (u8) and an RX error
/// counter (u8), 0300h–0307h. A write to any of them clears all.
pub const RX_ERROR_COUNTER: u16 = 0x0300;
/// 0308h Forwarded RX error counters, one u8 per port.
pub const FORWARDED_RX_ERROR_COUNTER: u16 = 0x0308;
/// 030Ch ECAT processing unit error counter (u8).
pub const PROCESSING_UNIT_ERROR_COUNTER: u16 = 0x030C;
/// 030Dh PDI error counter (u8).
pub const PDI_ERROR_COUNTER: u16 = 0x030D;
/// 0310h Lost link counters, one u8 per port.
pub const LOST_LINK_COUNTER: u16 = 0x0310;
/// 0400h Watchdog divider (u16): watchdog increment = (divider + 2) × 40 ns (default 09C2h:
/// 100 µs).
pub const WATCHDOG_DIVIDER: u16 = 0x0400;
/// 0410h PDI watchdog time (u16, in divider increments).
pub const WATCHDOG_TIME_PDI: u16 = 0x0410;
/// 0420h SyncManager (process data) watchdog time (u16, in divider increments; default
/// 03E8h = 100 ms).
pub const WATCHDOG_TIME_SM: u16 = 0x0420;
/// 0440h SyncManager watchdog status (u16: bit 0 = 1 watchdog not expired).
pub const WATCHDOG_STATUS_SM: u16 = 0x0440;
/// 0442h SyncManager watchdog counter (u8, counts expirations).
pub const WATCHDOG_COUNTER_SM: u16 = 0x0442;
/// 0443h PDI watchdog counter (u8).
pub const WATCHDOG_COUNTER_PDI: u16 = 0x0443;
/// 0500h SII EEPROM configuration (u8: bit 0 PDI access, bit 1 force ECAT access).
pub const SII_CONFIG: u16 = 0x0500;
/// 0501h SII EEPROM PDI access state (u8).
pub const SII_PDI_ACCESS: u16 = 0x0501;
/// 0502h SII EEPROM control/status (u16, see [`SiiControl`]).
pub const SII_CONTROL: u16 = 0x0502;
/// 0504h SII EEPROM address (u32, in words).
pub const SII_ADDRESS: u16 = 0x0504;
/// 0508h SII EEPROM data (4 bytes, or 8 on a read when 0502h bit 6 says so).
pub const SII_DATA: u16 = 0x0508;
/// 0600h First FMMU (16 bytes each, see [`FmmuRepr`]).
pub const FMMU_BASE: u16 = 0x0600;
/// 0800h First SyncManager channel (8 bytes each, see [`SmRepr`]).
pub const SM_BASE: u16 = 0x0800;
/// 0900h DC receive time port 0 (u32; ports 1..3 follow).
pub const DC_RECEIVE_TIME_PORT0: u16 = 0x0900;
/// 0910h DC system time (u64; optional: only ESCs with distributed clocks).
pub const DC_SYSTEM_TIME: u16 = 0x0910;
/// 0918h DC receive time of the ECAT processing unit (u64).
pub const DC_RECEIVE_TIME_PU: u16 = 0x0918;
/// 0920h DC system time offset (u64).
pub const DC_SYSTEM_TIME_OFFSET: u16 = 0x0920;
/// 0928h DC system time delay (u32).
pub const DC_SYSTEM_TIME_DELAY: u16 = 0x0928;
/// 092Ch DC system time difference (u32).
pub const DC_SYSTEM_TIME_DIFFERENCE: u16 = 0x092C;
/// 0980h DC cyclic unit control (u8).
pub const DC_CYCLIC_UNIT_CONTROL: u16 = 0x0980;
/// 0981h DC activation (u8).
pub const DC_ACTIVATION: u16 = 0x0981;
/// 0990h DC SYNC0 start time (u64).
pub const DC_SYNC0_START_TIME: u16 = 0x0990;
/// 09A0h DC SYNC0 cycle time (u32).
pub const DC_SYNC0_CYCLE_TIME: u16 = 0x09A0;
/// 09A4h DC SYNC1 cycle time (u32).
pub const DC_SYNC1_CYCLE_TIME: u16 = 0x09A4;
/// 1000h Start of the process data RAM.
pub const PROCESS_RAM: u16 = 0x1000;

/// Length of one FMMU block.
pub const FMMU_LEN: usize = 16;
/// Length of one SyncManager block.
pub const SM_LEN: usize = 8;

/// Address of FMMU `n` (0600h + 10h·n).
pub const fn fmmu(n: u8) -> u16 {
    FMMU_BASE + 16 * n as u16
}

/// Address of SyncManager `n` (0800h + 8·n).
pub const fn sm(n: u8) -> u16 {
    SM_BASE + 8 * n as u16
}

/// Bits of register 0008h "ESC features supported".
pub mod features {
    /// Bit 0: FMMU bit-wise (0) or byte-oriented (1).
    pub const FMMU_BYTE_ORIENTED: u16 = 0x0001;
    /// Bit 2: distributed clocks available.
    pub const DISTRIBUTED_CLOCKS: u16 = 0x0004;
    /// Bit 3: DC width 64 bits.
    pub const DC_64BIT: u16 = 0x0008;
    /// Bit 4: low-jitter EBUS.
    pub const LOW_JITTER_EBUS: u16 = 0x0010;
    /// Bit 5: enhanced link detection EBUS.
    pub const ENHANCED_LINK_EBUS: u16 = 0x0020;
    /// Bit 6: enhanced link detection MII.
    pub const ENHANCED_LINK_MII: u16 = 0x0040;
    /// Bit 7: separate handling of FCS errors.
    pub const SEPARATE_FCS_ERRORS: u16 = 0x0080;
    /// Bit 8: enhanced DC SYNC activation.
    pub const ENHANCED_DC_SYNC: u16 = 0x0100;
    /// Bit 9: LRW not supported.
    pub const NO_LRW: u16 = 0x0200;
    /// Bit 10: BRW, APRW, FPRW not supported.
    pub const NO_READ_WRITE: u16 = 0x0400;
    /// Bit 11: fixed FMMU/SM configuration.
    pub const FIXED_FMMU_SM: u16 = 0x0800;
}

/// The name of the register at `addr` (a block's member is named with its number: "SM 2
/// control"), for transcripts.
pub fn name(addr: u16) -> Option<String> {
    const NAMES: &[(u16, &str)] = &[
        (TYPE, "type"),
        (REVISION, "revision"),
        (BUILD, "build"),
        (FMMUS_SUPPORTED, "FMMUs supported"),
        (SMS_SUPPORTED, "SyncManagers supported"),
        (RAM_SIZE, "RAM size"),
        (PORT_DESCRIPTOR, "port descriptor"),
        (FEATURES, "ESC features"),
        (STATION_ADDRESS, "configured station address"),
        (STATION_ALIAS, "configured station alias"),
        (WRITE_ENABLE, "write register enable"),
        (WRITE_PROTECTION, "write register protection"),
        (ESC_WRITE_ENABLE, "ESC write enable"),
        (ESC_WRITE_PROTECTION, "ESC write protection"),
        (ESC_RESET_ECAT, "ESC reset ECAT"),
        (ESC_RESET_PDI, "ESC reset PDI"),
        (DL_CONTROL, "DL control"),
        (PHYSICAL_RW_OFFSET, "physical read/write offset"),
        (DL_STATUS, "DL status"),
        (AL_CONTROL, "AL control"),
        (AL_STATUS, "AL status"),
        (AL_STATUS_CODE, "AL status code"),
        (RUN_LED_OVERRIDE, "RUN LED override"),
        (ERR_LED_OVERRIDE, "ERR LED override"),
        (PDI_CONTROL, "PDI control"),
        (ESC_CONFIG, "ESC configuration"),
        (PDI_CONFIG, "PDI configuration"),
        (SYNC_LATCH_CONFIG, "SYNC/LATCH PDI configuration"),
        (PDI_CONFIG_EXT, "extended PDI configuration"),
        (ECAT_EVENT_MASK, "ECAT event mask"),
        (AL_EVENT_MASK, "AL event mask"),
        (ECAT_EVENT_REQUEST, "ECAT event request"),
        (AL_EVENT_REQUEST, "AL event request"),
        (RX_ERROR_COUNTER, "RX error counters"),
        (FORWARDED_RX_ERROR_COUNTER, "forwarded RX error counters"),
        (
            PROCESSING_UNIT_ERROR_COUNTER,
            "ECAT processing unit error counter",
        ),
        (PDI_ERROR_COUNTER, "PDI error counter"),
        (LOST_LINK_COUNTER, "lost link counters"),
        (WATCHDOG_DIVIDER, "watchdog divider"),
        (WATCHDOG_TIME_PDI, "PDI watchdog time"),
        (WATCHDOG_TIME_SM, "SyncManager watchdog time"),
        (WATCHDOG_STATUS_SM, "SyncManager watchdog status"),
        (WATCHDOG_COUNTER_SM, "SyncManager watchdog counter"),
        (WATCHDOG_COUNTER_PDI, "PDI watchdog counter"),
        (SII_CONFIG, "SII EEPROM configuration"),
        (SII_PDI_ACCESS, "SII EEPROM PDI access state"),
        (SII_CONTROL, "SII EEPROM control/status"),
        (SII_ADDRESS, "SII EEPROM address"),
        (SII_DATA, "SII EEPROM data"),
        (DC_RECEIVE_TIME_PORT0, "DC receive time port 0"),
        (DC_SYSTEM_TIME, "DC system time"),
        (DC_RECEIVE_TIME_PU, "DC receive time ECAT processing unit"),
        (DC_SYSTEM_TIME_OFFSET, "DC system time offset"),
        (DC_SYSTEM_TIME_DELAY, "DC system time delay"),
        (DC_SYSTEM_TIME_DIFFERENCE, "DC system time difference"),
        (DC_CYCLIC_UNIT_CONTROL, "DC cyclic unit control"),
        (DC_ACTIVATION, "DC activation"),
        (DC_SYNC0_START_TIME, "DC SYNC0 start time"),
        (DC_SYNC0_CYCLE_TIME, "DC SYNC0 cycle time"),
        (DC_SYNC1_CYCLE_TIME, "DC SYNC1 cycle time"),
        (PROCESS_RAM, "process data RAM"),
    ];
    if let Some((_, n)) = NAMES.iter().find(|(a, _)| *a == addr) {
        return Some((*n).to_string());
    }
    match addr {
        0x0600..=0x06FF => {
            let (n, off) = ((addr - FMMU_BASE) / 16, (addr - FMMU_BASE) % 16);
            let f = match off {
                0 => "logical start",
                4 => "length",
                6 => "logical start bit",
                7 => "logical stop bit",
                8 => "physical start",
                10 => "physical start bit",
                11 => "type",
                12 => "activate",
                _ => "reserved",
            };
            Some(format!("FMMU {n} {f}"))
        }
        0x0800..=0x087F => {
            let (n, off) = ((addr - SM_BASE) / 8, (addr - SM_BASE) % 8);
            let f = [
                "start",
                "start (high)",
                "length",
                "length (high)",
                "control",
                "status",
                "activate",
                "PDI control",
            ][usize::from(off)];
            Some(format!("SM {n} {f}"))
        }
        _ => None,
    }
}

/// Bits of a SyncManager's control byte (offset 4 of the block; ET1100 section II, register
/// 0804h).
pub mod sm_control {
    /// Bits 0–1: operation mode mask.
    pub const MODE_MASK: u8 = 0x03;
    /// Mode 00: buffered (3-buffer), for process data.
    pub const MODE_BUFFERED: u8 = 0x00;
    /// Mode 10: mailbox (1-buffer).
    pub const MODE_MAILBOX: u8 = 0x02;
    /// Bits 2–3: direction mask.
    pub const DIRECTION_MASK: u8 = 0x0C;
    /// Direction 00: read — the master reads, the PDI writes (inputs, mailbox in).
    pub const DIRECTION_READ: u8 = 0x00;
    /// Direction 01: write — the master writes, the PDI reads (outputs, mailbox out).
    pub const DIRECTION_WRITE: u8 = 0x04;
    /// Bit 4: interrupt in the ECAT event request register.
    pub const IRQ_ECAT: u8 = 0x10;
    /// Bit 5: interrupt in the AL event request register.
    pub const IRQ_AL: u8 = 0x20;
    /// Bit 6: watchdog trigger enable.
    pub const WATCHDOG: u8 = 0x40;
}

/// Bits of a SyncManager's status byte (offset 5).
pub mod sm_status {
    /// Bit 0: interrupt write (a write completed).
    pub const IRQ_WRITE: u8 = 0x01;
    /// Bit 1: interrupt read (a read completed).
    pub const IRQ_READ: u8 = 0x02;
    /// Bit 3: mailbox full (mailbox mode).
    pub const MAILBOX_FULL: u8 = 0x08;
    /// Bits 4–5: last written buffer (buffered mode: 00 buffer 1, 01 buffer 2, 10 buffer 3, 11
    /// none written yet).
    pub const BUFFER_STATE_MASK: u8 = 0x30;
    /// Bit 6: read buffer in use (opened).
    pub const READ_BUFFER_OPEN: u8 = 0x40;
    /// Bit 7: write buffer in use (opened).
    pub const WRITE_BUFFER_OPEN: u8 = 0x80;
}

/// Bits of a SyncManager's activate byte (offset 6) and PDI control byte (offset 7).
pub mod sm_activate {
    /// Activate bit 0: SyncManager enabled.
    pub const ENABLE: u8 = 0x01;
    /// Activate bit 1: repeat request (mailbox repeat).
    pub const REPEAT: u8 = 0x02;
    /// Activate bit 6: latch event ECAT.
    pub const LATCH_ECAT: u8 = 0x40;
    /// Activate bit 7: latch event PDI.
    pub const LATCH_PDI: u8 = 0x80;
    /// PDI control bit 0: deactivate the SyncManager.
    pub const PDI_DEACTIVATE: u8 = 0x01;
    /// PDI control bit 1: repeat acknowledge.
    pub const PDI_REPEAT_ACK: u8 = 0x02;
}

/// A SyncManager channel block (0800h + 8·n; ETG.1000.4 "SyncManager"; ET1100 section II
/// registers 0800h–0807h).
///
/// | byte | field |
/// |---|---|
/// | 0–1 | physical start address |
/// | 2–3 | length |
/// | 4 | control ([`sm_control`]) |
/// | 5 | status ([`sm_status`], read-only) |
/// | 6 | activate ([`sm_activate`]) |
/// | 7 | PDI control (read-only for the master) |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SmRepr {
    /// Physical start address.
    pub start: u16,
    /// Length in bytes.
    pub length: u16,
    /// Control byte.
    pub control: u8,
    /// Status byte.
    pub status: u8,
    /// Activate byte.
    pub activate: u8,
    /// PDI control byte.
    pub pdi_control: u8,
}

impl SmRepr {
    /// An enabled SyncManager with this start, length and control byte.
    pub fn enabled(start: u16, length: u16, control: u8) -> Self {
        SmRepr {
            start,
            length,
            control,
            activate: sm_activate::ENABLE,
            ..SmRepr::default()
        }
    }

    /// Parses the 8 bytes of one block.
    pub fn parse(bytes: &[u8]) -> Result<SmRepr, Error> {
        let mut r = Reader::new(bytes);
        let sm = SmRepr {
            start: r.u16("SM physical start address")?,
            length: r.u16("SM length")?,
            control: r.u8("SM control")?,
            status: r.u8("SM status")?,
            activate: r.u8("SM activate")?,
            pdi_control: r.u8("SM PDI control")?,
        };
        r.finish("SM block")?;
        Ok(sm)
    }

    /// The 8 bytes.
    pub fn emit(&self) -> [u8; 8] {
        let s = self.start.to_le_bytes();
        let l = self.length.to_le_bytes();
        [
            s[0],
            s[1],
            l[0],
            l[1],
            self.control,
            self.status,
            self.activate,
            self.pdi_control,
        ]
    }

    /// Mailbox mode (control bits 0–1 = 10).
    pub fn is_mailbox(&self) -> bool {
        self.control & sm_control::MODE_MASK == sm_control::MODE_MAILBOX
    }
    /// Buffered (3-buffer) mode.
    pub fn is_buffered(&self) -> bool {
        self.control & sm_control::MODE_MASK == sm_control::MODE_BUFFERED
    }
    /// The master writes (direction 01).
    pub fn is_master_write(&self) -> bool {
        self.control & sm_control::DIRECTION_MASK == sm_control::DIRECTION_WRITE
    }
    /// The master reads (direction 00).
    pub fn is_master_read(&self) -> bool {
        self.control & sm_control::DIRECTION_MASK == sm_control::DIRECTION_READ
    }
    /// Enabled (activate bit 0).
    pub fn is_enabled(&self) -> bool {
        self.activate & sm_activate::ENABLE != 0
    }
    /// Mailbox full (status bit 3).
    pub fn is_mailbox_full(&self) -> bool {
        self.status & sm_status::MAILBOX_FULL != 0
    }
    /// The physical addresses covered (`start..start + length`, in u32 so the end cannot
    /// overflow).
    pub fn range(&self) -> std::ops::Range<u32> {
        u32::from(self.start)..u32::from(self.start) + u32::from(self.length)
    }
}

/// Bits of an FMMU's type byte (offset 11).
pub mod fmmu_type {
    /// Bit 0: mapping used for reads (LRD, LRW read part).
    pub const READ: u8 = 0x01;
    /// Bit 1: mapping used for writes (LWR, LRW write part).
    pub const WRITE: u8 = 0x02;
}

/// An FMMU block (0600h + 10h·n; ETG.1000.4 "FMMU"; ET1100 section II registers
/// 0600h–060Fh): maps a logical address range bit-wise onto physical memory.
///
/// | byte | field |
/// |---|---|
/// | 0–3 | logical start address |
/// | 4–5 | length in bytes |
/// | 6 | logical start bit (0–7) |
/// | 7 | logical stop bit (0–7) |
/// | 8–9 | physical start address |
/// | 10 | physical start bit (0–7) |
/// | 11 | type ([`fmmu_type`]) |
/// | 12 | activate (bit 0) |
/// | 13–15 | reserved |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FmmuRepr {
    /// Logical start address.
    pub logical_start: u32,
    /// Length in bytes.
    pub length: u16,
    /// Logical start bit.
    pub logical_start_bit: u8,
    /// Logical stop bit.
    pub logical_stop_bit: u8,
    /// Physical start address.
    pub physical_start: u16,
    /// Physical start bit.
    pub physical_start_bit: u8,
    /// Type byte: read (bit 0), write (bit 1).
    pub kind: u8,
    /// Activate byte (bit 0).
    pub activate: u8,
}

impl FmmuRepr {
    /// A byte-aligned, activated mapping of `length` bytes.
    pub fn bytes(logical_start: u32, length: u16, physical_start: u16, kind: u8) -> Self {
        FmmuRepr {
            logical_start,
            length,
            logical_start_bit: 0,
            logical_stop_bit: 7,
            physical_start,
            physical_start_bit: 0,
            kind,
            activate: 1,
        }
    }

    /// Parses the 16 bytes of one block (the 3 reserved bytes are not kept).
    pub fn parse(bytes: &[u8]) -> Result<FmmuRepr, Error> {
        let mut r = Reader::new(bytes);
        let f = FmmuRepr {
            logical_start: r.u32("FMMU logical start address")?,
            length: r.u16("FMMU length")?,
            logical_start_bit: r.u8("FMMU logical start bit")?,
            logical_stop_bit: r.u8("FMMU logical stop bit")?,
            physical_start: r.u16("FMMU physical start address")?,
            physical_start_bit: r.u8("FMMU physical start bit")?,
            kind: r.u8("FMMU type")?,
            activate: r.u8("FMMU activate")?,
        };
        r.bytes(3, "FMMU reserved")?;
        r.finish("FMMU block")?;
        Ok(f)
    }

    /// The 16 bytes.
    pub fn emit(&self) -> [u8; 16] {
        let mut b = [0; 16];
        b[0..4].copy_from_slice(&self.logical_start.to_le_bytes());
        b[4..6].copy_from_slice(&self.length.to_le_bytes());
        b[6] = self.logical_start_bit;
        b[7] = self.logical_stop_bit;
        b[8..10].copy_from_slice(&self.physical_start.to_le_bytes());
        b[10] = self.physical_start_bit;
        b[11] = self.kind;
        b[12] = self.activate;
        b
    }

    /// Activated (bit 0).
    pub fn is_active(&self) -> bool {
        self.activate & 1 != 0
    }
    /// Used for reads.
    pub fn reads(&self) -> bool {
        self.kind & fmmu_type::READ != 0
    }
    /// Used for writes.
    pub fn writes(&self) -> bool {
        self.kind & fmmu_type::WRITE != 0
    }
    /// The logical addresses covered (`start..start + length`, in u64 so the end cannot
    /// overflow).
    pub fn logical_range(&self) -> std::ops::Range<u64> {
        u64::from(self.logical_start)..u64::from(self.logical_start) + u64::from(self.length)
    }
}

/// The SII EEPROM control/status word (0502h; ETG.1000.4 "SII access"; ET1100 section II
/// register 0502h). Open: every bit is kept.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SiiControl(pub u16);

impl SiiControl {
    /// Bit 0: ECAT write enable (needed in the same access as a write command).
    pub const WRITE_ENABLE: u16 = 0x0001;
    /// Bit 5: EEPROM emulation (the PDI serves the commands).
    pub const EMULATION: u16 = 0x0020;
    /// Bit 6: reads return 8 bytes (0: 4 bytes).
    pub const READ_8_BYTES: u16 = 0x0040;
    /// Bit 7: 2 address bytes (EEPROMs above 16 Kbit).
    pub const TWO_ADDRESS_BYTES: u16 = 0x0080;
    /// Bits 8–10: command mask.
    pub const COMMAND_MASK: u16 = 0x0700;
    /// Command 000: idle.
    pub const CMD_IDLE: u16 = 0x0000;
    /// Command 001: read.
    pub const CMD_READ: u16 = 0x0100;
    /// Command 010: write.
    pub const CMD_WRITE: u16 = 0x0200;
    /// Command 100: reload the ESC configuration from the EEPROM.
    pub const CMD_RELOAD: u16 = 0x0400;
    /// Bit 11: checksum error in the ESC configuration area (words 0–7).
    pub const CHECKSUM_ERROR: u16 = 0x0800;
    /// Bit 12: device information loading error (EEPROM not loaded).
    pub const LOAD_ERROR: u16 = 0x1000;
    /// Bit 13: missing acknowledge or invalid command.
    pub const ACK_ERROR: u16 = 0x2000;
    /// Bit 14: write enable error (a write without bit 0).
    pub const WRITE_ENABLE_ERROR: u16 = 0x4000;
    /// Bit 15: busy.
    pub const BUSY: u16 = 0x8000;
    /// The error bits 11–14.
    pub const ERRORS: u16 = 0x7800;

    /// A command word: `cmd` is one of the `CMD_*` constants.
    pub fn command(cmd: u16) -> SiiControl {
        SiiControl(cmd & Self::COMMAND_MASK)
    }
    /// The command bits.
    pub fn cmd(self) -> u16 {
        self.0 & Self::COMMAND_MASK
    }
    /// Whether `bit` (a mask constant) is set.
    pub fn has(self, bit: u16) -> bool {
        self.0 & bit == bit
    }
    /// Busy.
    pub fn busy(self) -> bool {
        self.has(Self::BUSY)
    }
    /// Any of the error bits 11–14.
    pub fn error(self) -> bool {
        self.0 & Self::ERRORS != 0
    }
    /// Bytes a read returns at 0508h (4 or 8).
    pub fn read_len(self) -> usize {
        if self.has(Self::READ_8_BYTES) {
            8
        } else {
            4
        }
    }
}

impl fmt::Debug for SiiControl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SiiControl({:04X}h", self.0)?;
        for (bit, n) in [
            (Self::WRITE_ENABLE, "write-enable"),
            (Self::READ_8_BYTES, "8-byte-reads"),
            (Self::CMD_READ, "read"),
            (Self::CMD_WRITE, "write"),
            (Self::CMD_RELOAD, "reload"),
            (Self::CHECKSUM_ERROR, "checksum-error"),
            (Self::LOAD_ERROR, "load-error"),
            (Self::ACK_ERROR, "ack-error"),
            (Self::WRITE_ENABLE_ERROR, "write-enable-error"),
            (Self::BUSY, "busy"),
        ] {
            if self.0 & bit != 0 {
                write!(f, " {n}")?;
            }
        }
        f.write_str(")")
    }
}

/// The DL status word (0110h; ETG.1000.4 "DL status"; ET1100 section II register 0110h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct DlStatus(pub u16);

impl DlStatus {
    /// Bit 0: PDI operational (EEPROM loaded).
    pub fn pdi_operational(self) -> bool {
        self.0 & 0x0001 != 0
    }
    /// Bit 1: PDI watchdog status (1 = not expired).
    pub fn pdi_watchdog_ok(self) -> bool {
        self.0 & 0x0002 != 0
    }
    /// Bits 4–7: physical link on port 0..3 (`None` for port > 3).
    pub fn link(self, port: u8) -> Option<bool> {
        (port < 4).then(|| self.0 & (0x0010 << port) != 0)
    }
    /// Bits 8, 10, 12, 14: loop closed on port 0..3.
    pub fn loop_closed(self, port: u8) -> Option<bool> {
        (port < 4).then(|| self.0 & (0x0100 << (2 * port)) != 0)
    }
    /// Bits 9, 11, 13, 15: communication established on port 0..3.
    pub fn communication(self, port: u8) -> Option<bool> {
        (port < 4).then(|| self.0 & (0x0200 << (2 * port)) != 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SM0 as masters configure a mailbox-out channel: 1000h, 128 bytes, mailbox, master
    /// writes, AL interrupt, enabled.
    const SM0: [u8; 8] = [
        0x00, 0x10, // start 1000h
        0x80, 0x00, // length 128
        0x26, // control: mailbox (10), write (01), IRQ AL (bit 5)
        0x00, // status
        0x01, // activate: enable
        0x00, // PDI control
    ];

    /// FMMU 0: logical 00010000h, 12 bytes, bits 0..7, physical 1100h, write, active.
    const FMMU0: [u8; 16] = [
        0x00, 0x00, 0x01, 0x00, // logical start 00010000h
        0x0C, 0x00, // length 12
        0x00, 0x07, // start bit 0, stop bit 7
        0x00, 0x11, // physical 1100h
        0x00, // physical start bit
        0x02, // type: write
        0x01, // activate
        0x00, 0x00, 0x00, // reserved
    ];

    #[test]
    fn sm_block() {
        let sm = SmRepr::parse(&SM0).unwrap();
        assert_eq!(
            sm,
            SmRepr::enabled(
                0x1000,
                128,
                sm_control::MODE_MAILBOX | sm_control::DIRECTION_WRITE | sm_control::IRQ_AL
            )
        );
        assert!(sm.is_mailbox() && sm.is_master_write() && sm.is_enabled());
        assert!(!sm.is_buffered() && !sm.is_master_read() && !sm.is_mailbox_full());
        assert_eq!(sm.range(), 0x1000..0x1080);
        assert_eq!(sm.emit(), SM0);
        for n in 0..8 {
            assert!(matches!(
                SmRepr::parse(&SM0[..n]),
                Err(Error::Truncated { .. })
            ));
        }
        assert_eq!(
            SmRepr::parse(&[0; 9]),
            Err(Error::Trailing {
                what: "SM block",
                extra: 1
            })
        );
    }

    #[test]
    fn fmmu_block() {
        let f = FmmuRepr::parse(&FMMU0).unwrap();
        assert_eq!(
            f,
            FmmuRepr::bytes(0x0001_0000, 12, 0x1100, fmmu_type::WRITE)
        );
        assert!(f.is_active() && f.writes() && !f.reads());
        assert_eq!(f.logical_range(), 0x1_0000..0x1_000C);
        assert_eq!(f.emit(), FMMU0);
        for n in 0..16 {
            assert!(matches!(
                FmmuRepr::parse(&FMMU0[..n]),
                Err(Error::Truncated { .. })
            ));
        }
    }

    #[test]
    fn addresses_and_names() {
        assert_eq!(
            (sm(0), sm(3), fmmu(0), fmmu(2)),
            (0x0800, 0x0818, 0x0600, 0x0620)
        );
        assert_eq!(name(0x0130).as_deref(), Some("AL status"));
        assert_eq!(name(0x0134).as_deref(), Some("AL status code"));
        assert_eq!(name(0x0814).as_deref(), Some("SM 2 control"));
        assert_eq!(name(0x061C).as_deref(), Some("FMMU 1 activate"));
        assert_eq!(name(0x0E00), None);
    }

    #[test]
    fn sii_control_bits() {
        let c = SiiControl(0x0040 | 0x0100 | 0x8000);
        assert_eq!(c.cmd(), SiiControl::CMD_READ);
        assert!(c.busy() && !c.error());
        assert_eq!(c.read_len(), 8);
        assert_eq!(format!("{c:?}"), "SiiControl(8140h 8-byte-reads read busy)");
        assert!(SiiControl(SiiControl::WRITE_ENABLE_ERROR).error());
        assert_eq!(SiiControl::command(0xFFFF).0, 0x0700);
        assert_eq!(SiiControl(0).read_len(), 4);
    }

    #[test]
    fn dl_status_bits() {
        // PDI operational, link on port 0, port 0 loop open with communication, port 1 closed.
        let s = DlStatus(0x0001 | 0x0010 | 0x0200 | 0x0400);
        assert!(s.pdi_operational() && !s.pdi_watchdog_ok());
        assert_eq!(
            (s.link(0), s.link(1), s.link(4)),
            (Some(true), Some(false), None)
        );
        assert_eq!(
            (s.loop_closed(0), s.loop_closed(1)),
            (Some(false), Some(true))
        );
        assert_eq!(
            (s.communication(0), s.communication(1)),
            (Some(true), Some(false))
        );
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        fn sm() -> impl Strategy<Value = SmRepr> {
            any::<(u16, u16, u8, u8, u8, u8)>().prop_map(
                |(start, length, control, status, activate, pdi_control)| SmRepr {
                    start,
                    length,
                    control,
                    status,
                    activate,
                    pdi_control,
                },
            )
        }

        fn fmmu() -> impl Strategy<Value = FmmuRepr> {
            (
                any::<u32>(),
                any::<u16>(),
                any::<u8>(),
                any::<u8>(),
                any::<u16>(),
                any::<u8>(),
                any::<u8>(),
                any::<u8>(),
            )
                .prop_map(
                    |(
                        logical_start,
                        length,
                        logical_start_bit,
                        logical_stop_bit,
                        physical_start,
                        physical_start_bit,
                        kind,
                        activate,
                    )| FmmuRepr {
                        logical_start,
                        length,
                        logical_start_bit,
                        logical_stop_bit,
                        physical_start,
                        physical_start_bit,
                        kind,
                        activate,
                    },
                )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn sm_round_trips(s in sm()) {
                prop_assert_eq!(SmRepr::parse(&s.emit()), Ok(s));
            }

            #[test]
            fn fmmu_round_trips(f in fmmu()) {
                prop_assert_eq!(FmmuRepr::parse(&f.emit()), Ok(f));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..20)) {
                let _ = SmRepr::parse(&bytes);
                let _ = FmmuRepr::parse(&bytes);
            }
        }
    }
}
