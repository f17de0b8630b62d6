//! The EtherCAT Slave Controller's memory: registers 0000h–0FFFh and 8 KiB of process RAM
//! (1000h–2FFFh), accessed by the master's datagrams physically (by register address) or
//! logically (through the FMMUs), with the SyncManagers guarding their buffers.
//!
//! Register layout and access rights after ETG.1000.4 §6 and the ET1100 datasheet section II
//! ("ECAT" column): a write to a register the master may not write is ignored without failing
//! the datagram (its working counter still counts), as the ESC does. The SyncManager rules
//! (mailbox: a write to a full buffer or a read of an empty one is refused and not counted;
//! the buffer changes hands when its last byte is accessed) are in [`super::sm`].

use std::time::Duration;

use proto::ecat::register::{fmmu_type, FmmuRepr};

use super::sm::{SmAccess, SmEvent, SyncManagers};

/// First address after the process RAM.
pub(crate) const RAM_END: usize = 0x3000;
/// Start of the process RAM.
pub(crate) const RAM_START: usize = 0x1000;
/// FMMUs the ESC has (register 0004h).
pub(crate) const FMMU_COUNT: usize = 8;
/// SyncManagers the ESC has (register 0005h).
pub(crate) const SM_COUNT: usize = 8;

/// Register addresses the simulator gives meaning to (ETG.1000.4 table 31 ff.), from
/// `proto::ecat::register` as memory offsets.
pub(crate) mod reg {
    use proto::ecat::register as r;

    pub(crate) const TYPE: usize = r::TYPE as usize;
    pub(crate) const FMMUS: usize = r::FMMUS_SUPPORTED as usize;
    pub(crate) const SMS: usize = r::SMS_SUPPORTED as usize;
    pub(crate) const RAM_SIZE: usize = r::RAM_SIZE as usize;
    pub(crate) const PORTS: usize = r::PORT_DESCRIPTOR as usize;
    pub(crate) const FEATURES: usize = r::FEATURES as usize;
    pub(crate) const STATION_ADDRESS: usize = r::STATION_ADDRESS as usize;
    pub(crate) const STATION_ALIAS: usize = r::STATION_ALIAS as usize;
    pub(crate) const DL_CONTROL: usize = r::DL_CONTROL as usize;
    pub(crate) const DL_STATUS: usize = r::DL_STATUS as usize;
    pub(crate) const AL_CONTROL: usize = r::AL_CONTROL as usize;
    pub(crate) const AL_STATUS: usize = r::AL_STATUS as usize;
    pub(crate) const AL_STATUS_CODE: usize = r::AL_STATUS_CODE as usize;
    pub(crate) const PDI_CONTROL: usize = r::PDI_CONTROL as usize;
    pub(crate) const PDI_CONFIG: usize = r::PDI_CONFIG as usize;
    pub(crate) const RX_ERRORS: usize = r::RX_ERROR_COUNTER as usize;
    pub(crate) const WD_DIVIDER: usize = r::WATCHDOG_DIVIDER as usize;
    pub(crate) const WD_PDI: usize = r::WATCHDOG_TIME_PDI as usize;
    pub(crate) const WD_SM: usize = r::WATCHDOG_TIME_SM as usize;
    pub(crate) const WD_SM_STATUS: usize = r::WATCHDOG_STATUS_SM as usize;
    pub(crate) const WD_SM_COUNTER: usize = r::WATCHDOG_COUNTER_SM as usize;
    pub(crate) const EEPROM_CONTROL: usize = r::SII_CONTROL as usize;
    pub(crate) const EEPROM_ADDRESS: usize = r::SII_ADDRESS as usize;
    pub(crate) const EEPROM_DATA: usize = r::SII_DATA as usize;
    pub(crate) const FMMU0: usize = r::FMMU_BASE as usize;
    pub(crate) const SM0: usize = r::SM_BASE as usize;
}

/// Which way a datagram accesses memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Op {
    /// Read into the datagram.
    Read,
    /// Write from the datagram.
    Write,
    /// Read, then write what the datagram carried.
    ReadWrite,
}

impl Op {
    fn reads(self) -> bool {
        matches!(self, Op::Read | Op::ReadWrite)
    }
    fn writes(self) -> bool {
        matches!(self, Op::Write | Op::ReadWrite)
    }
}

/// What one access did: whether its read and its write succeeded (for the working counter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Done {
    /// The read part was served.
    pub(crate) read: bool,
    /// The write part was performed.
    pub(crate) write: bool,
}

/// Something the application must react to after an access.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Event {
    /// AL control (0120h) was written.
    AlControl,
    /// The EEPROM control register (0502h) was written.
    EepromCommand,
    /// A SyncManager buffer changed hands.
    Sm(SmEvent),
}

/// The ESC's memory and SyncManager states.
#[derive(Debug, Clone)]
pub(crate) struct Esc {
    mem: Vec<u8>,
    pub(crate) sms: SyncManagers,
    /// When the process-data watchdog was last triggered (a complete write of an output
    /// SyncManager with the watchdog trigger bit), or armed by the application.
    pub(crate) wd_trigger: Option<Duration>,
}

impl Esc {
    /// An ESC after power-on: the identification registers and the watchdog defaults
    /// (divider 09C2h = 100 µs, SM and PDI watchdog 1000 × 100 µs = 100 ms).
    pub(crate) fn new() -> Esc {
        let mut e = Esc {
            mem: vec![0; RAM_END],
            sms: SyncManagers::default(),
            wd_trigger: None,
        };
        // ESC type: an on-chip ESC of the netX (P872 bit 4 "netX"); the code is an assumption.
        e.mem[reg::TYPE] = 0x80;
        e.mem[reg::FMMUS] = FMMU_COUNT as u8;
        e.mem[reg::SMS] = SM_COUNT as u8;
        e.mem[reg::RAM_SIZE] = ((RAM_END - RAM_START) / 1024) as u8;
        // Ports 0 and 1 MII (11b each), ports 2 and 3 not implemented.
        e.mem[reg::PORTS] = 0x0F;
        // No distributed clocks, no further features.
        e.set_u16(reg::FEATURES, 0);
        // PDI operational (EEPROM loaded), PDI watchdog reloaded, link and communication on port
        // 0 (open), ports 1..3 closed: the slave is the last on its segment.
        e.set_u16(reg::DL_STATUS, 0x5613);
        e.set_u16(reg::WD_DIVIDER, 0x09C2);
        e.set_u16(reg::WD_PDI, 1000);
        e.set_u16(reg::WD_SM, 1000);
        e.set_u16(reg::WD_SM_STATUS, 1);
        e.set_u16(reg::AL_STATUS, 1);
        // SyncManagers start deactivated by the application (PDI control bit 0).
        for n in 0..SM_COUNT {
            e.mem[reg::SM0 + 8 * n + 7] = 1;
        }
        e
    }

    /// A register's bytes.
    pub(crate) fn bytes(&self, addr: usize, len: usize) -> &[u8] {
        let end = (addr + len).min(RAM_END);
        &self.mem[addr.min(end)..end]
    }

    /// A 16-bit register.
    pub(crate) fn u16(&self, addr: usize) -> u16 {
        u16::from_le_bytes([self.mem[addr], self.mem[addr + 1]])
    }

    /// Sets a 16-bit register (application side).
    pub(crate) fn set_u16(&mut self, addr: usize, v: u16) {
        self.mem[addr..addr + 2].copy_from_slice(&v.to_le_bytes());
    }

    /// A byte of memory.
    pub(crate) fn u8(&self, addr: usize) -> u8 {
        self.mem[addr]
    }

    /// Sets a byte (application side).
    pub(crate) fn set_u8(&mut self, addr: usize, v: u8) {
        self.mem[addr] = v;
    }

    /// Writes bytes into memory from the application side (no SyncManager rules).
    pub(crate) fn put(&mut self, addr: usize, data: &[u8]) {
        let end = (addr + data.len()).min(RAM_END);
        if addr < end {
            self.mem[addr..end].copy_from_slice(&data[..end - addr]);
        }
    }

    /// Counts a frame the ESC discarded as invalid (port 0 invalid frame counter, 0300h,
    /// saturating at FFh, ETG.1000.4 §6.3.2).
    pub(crate) fn count_invalid_frame(&mut self) {
        self.mem[reg::RX_ERRORS] = self.mem[reg::RX_ERRORS].saturating_add(1);
    }

    /// The SM watchdog time, `None` when disabled (0): (divider + 2) × 40 ns × 0420h.
    pub(crate) fn sm_watchdog(&self) -> Option<Duration> {
        let unit = (u64::from(self.u16(reg::WD_DIVIDER)) + 2) * 40;
        let time = u64::from(self.u16(reg::WD_SM));
        (time > 0).then(|| Duration::from_nanos(unit * time))
    }

    /// Whether the master may write register byte `addr` (the "ECAT" access column).
    fn writable(&self, addr: usize) -> bool {
        match addr {
            0x0010..=0x0011 | 0x0020..=0x0021 | 0x0030..=0x0031 => true,
            0x0100..=0x0103 | 0x0108..=0x0109 => true,
            0x0120..=0x0121 | 0x0138..=0x0139 => true,
            0x0200..=0x0201 => true,
            0x0300..=0x0313 => true,
            0x0400..=0x0401 | 0x0410..=0x0411 | 0x0420..=0x0421 | 0x0442..=0x0443 => true,
            0x0500 | 0x0502..=0x050F | 0x0510..=0x0517 => true,
            0x0600..=0x067F => true,
            0x0800..=0x083F => {
                let n = (addr - reg::SM0) / 8;
                match (addr - reg::SM0) % 8 {
                    // Start, length, control: only while the SyncManager is disabled.
                    0..=4 => self.mem[reg::SM0 + 8 * n + 6] & 1 == 0,
                    6 => true,
                    _ => false,
                }
            }
            0x0900..=0x09FF | 0x0F00..=0x0F1F => true,
            a => (RAM_START..RAM_END).contains(&a),
        }
    }

    /// A physical access of `data.len()` bytes at `ado` (APxx, FPxx, BRD/BWR/BRW). Broadcast
    /// reads OR the memory into the datagram (`or`), other reads replace it.
    pub(crate) fn physical(
        &mut self,
        ado: u16,
        data: &mut [u8],
        op: Op,
        or: bool,
        now: Duration,
        events: &mut Vec<Event>,
    ) -> Done {
        let start = usize::from(ado);
        let access = self
            .sms
            .check(&self.mem, start, data.len(), op.reads(), op.writes());
        let mut done = Done::default();
        let written: Vec<u8> = if op.writes() {
            data.to_vec()
        } else {
            Vec::new()
        };
        if op.reads() && access.read == SmAccess::Allowed {
            for (i, d) in data.iter_mut().enumerate() {
                let v = self.mem.get(start + i).copied().unwrap_or(0);
                *d = if or { *d | v } else { v };
            }
            done.read = true;
        }
        if op.writes() && access.write == SmAccess::Allowed {
            self.write_bytes(start, &written, events);
            done.write = true;
        }
        for e in self
            .sms
            .complete(&mut self.mem, start, data.len(), done.read, done.write)
        {
            if let SmEvent::OutputsWritten(n) = e {
                if self.mem[reg::SM0 + 8 * n + 4] & 0x40 != 0 {
                    self.wd_trigger = Some(now);
                    self.set_u16(reg::WD_SM_STATUS, 1);
                }
            }
            events.push(Event::Sm(e));
        }
        done
    }

    /// Writes register/RAM bytes with the master's access rights and side effects.
    fn write_bytes(&mut self, start: usize, data: &[u8], events: &mut Vec<Event>) {
        let mut clear_errors = false;
        for (i, v) in data.iter().enumerate() {
            let a = start + i;
            if a >= RAM_END || !self.writable(a) {
                continue;
            }
            match a {
                reg::RX_ERRORS..=0x0313 => clear_errors = true,
                0x0442..=0x0443 => self.mem[a] = 0,
                reg::EEPROM_CONTROL => {
                    // Bit 0 write enable; the other low bits are status.
                    self.mem[a] = (self.mem[a] & !1) | (v & 1);
                }
                0x0503 => {
                    // Bits 8–10 the command; the error/busy bits are status.
                    self.mem[a] = (self.mem[a] & !0x07) | (v & 0x07);
                }
                _ => self.mem[a] = *v,
            }
        }
        if clear_errors {
            // A write to any error counter clears them all (ETG.1000.4 §6.3.2).
            self.mem[reg::RX_ERRORS..0x0314].fill(0);
        }
        let end = start + data.len();
        let touches = |a: usize, n: usize| start < a + n && a < end;
        if touches(reg::AL_CONTROL, 2) {
            events.push(Event::AlControl);
        }
        if touches(reg::EEPROM_CONTROL + 1, 1) {
            events.push(Event::EepromCommand);
        }
        for n in 0..SM_COUNT {
            if touches(reg::SM0 + 8 * n + 6, 1) {
                if let Some(e) = self.sms.activation(&mut self.mem, n) {
                    events.push(Event::Sm(e));
                }
            }
        }
    }

    /// A logical access (LRD/LWR/LRW) at `address`: every active FMMU whose logical window
    /// overlaps maps its bytes onto physical memory; returns whether a read FMMU and a write
    /// FMMU served it.
    pub(crate) fn logical(
        &mut self,
        address: u32,
        data: &mut [u8],
        op: Op,
        now: Duration,
        events: &mut Vec<Event>,
    ) -> Done {
        let original = data.to_vec();
        let mut done = Done::default();
        for f in 0..FMMU_COUNT {
            let b = reg::FMMU0 + 16 * f;
            let Some(fmmu) = self
                .mem
                .get(b..b + 16)
                .and_then(|r| FmmuRepr::parse(r).ok())
            else {
                continue;
            };
            if fmmu.activate & 1 == 0 {
                continue;
            }
            let log = fmmu.logical_start;
            let len = u32::from(fmmu.length);
            let phys = usize::from(fmmu.physical_start);
            let can_read = fmmu.kind & fmmu_type::READ != 0;
            let can_write = fmmu.kind & fmmu_type::WRITE != 0;
            let lo = log.max(address);
            let hi = (log.saturating_add(len)).min(address.saturating_add(data.len() as u32));
            if lo >= hi {
                continue;
            }
            let (d0, n) = ((lo - address) as usize, (hi - lo) as usize);
            let p = phys + (lo - log) as usize;
            let Ok(ado) = u16::try_from(p) else { continue };
            if can_read && op.reads() {
                let mut buf = vec![0; n];
                if self
                    .physical(ado, &mut buf, Op::Read, false, now, events)
                    .read
                {
                    data[d0..d0 + n].copy_from_slice(&buf);
                    done.read = true;
                }
            }
            if can_write && op.writes() {
                let mut buf = original[d0..d0 + n].to_vec();
                if self
                    .physical(ado, &mut buf, Op::Write, false, now, events)
                    .write
                {
                    done.write = true;
                }
            }
        }
        done
    }
}

impl Esc {
    /// The whole memory (for the application's configuration checks).
    pub(crate) fn mem(&self) -> &[u8] {
        &self.mem
    }

    /// The application takes the receive mailbox of SyncManager `n`.
    pub(crate) fn take_mailbox(&mut self, n: usize) -> Option<Vec<u8>> {
        self.sms.take(&mut self.mem, n)
    }

    /// The application fills the send mailbox of SyncManager `n`.
    pub(crate) fn put_mailbox(&mut self, n: usize, data: &[u8]) -> bool {
        self.sms.put(&mut self.mem, n, data)
    }

    /// The application (de)activates SyncManager `n`.
    pub(crate) fn deactivate(&mut self, n: usize, off: bool) {
        self.sms.deactivate(&mut self.mem, n, off);
    }

    /// The application acknowledges SyncManager `n`'s repeat request.
    pub(crate) fn ack_repeat(&mut self, n: usize) {
        self.sms.ack_repeat(&mut self.mem, n);
    }
}
