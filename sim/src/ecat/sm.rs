//! SyncManagers (ETG.1000.4 §6.7, ET1100 datasheet section I §8): the registers 0800h + 8·n
//! (start, length, control, status, activate, PDI control) and the buffer rules.
//!
//! - Mailbox mode (control bits 0–1 = 10b): one buffer. Written by the master (SM0): a write
//!   to a full buffer is refused; the buffer is full once its last byte is written. Read by the
//!   master (SM1): a read of an empty buffer is refused; the buffer is empty once its last byte
//!   is read. A refused access does not count in the working counter.
//! - Buffered (3-buffer) mode (00b): never refused; a write is complete when its last byte is
//!   written, a read always gets the latest buffer the application completed.
//!
//! A SyncManager works when the master has activated it (0806h bit 0), the application has not
//! deactivated it (0807h bit 0) and its length is not 0. The application deactivates all of
//! them in Init and activates them as it accepts their configuration (ETG.1000.6 §6.4.2).

use proto::ecat::register::{sm_activate, sm_control, SmRepr, SM_BASE};

/// The register block of SyncManager `n`.
pub(crate) fn register(n: usize) -> usize {
    usize::from(SM_BASE) + 8 * n
}

/// A SyncManager's configuration as the master wrote it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SmConfig {
    /// Physical start address.
    pub(crate) start: usize,
    /// Length in bytes.
    pub(crate) len: usize,
    /// Control byte.
    pub(crate) control: u8,
    /// Activated by the master (0806h bit 0).
    pub(crate) enabled: bool,
    /// Deactivated by the application (0807h bit 0).
    pub(crate) deactivated: bool,
}

impl SmConfig {
    /// Reads SyncManager `n`'s registers.
    pub(crate) fn read(mem: &[u8], n: usize) -> SmConfig {
        let sm = mem
            .get(register(n)..register(n) + 8)
            .and_then(|r| SmRepr::parse(r).ok())
            .unwrap_or_default();
        SmConfig {
            start: usize::from(sm.start),
            len: usize::from(sm.length),
            control: sm.control,
            enabled: sm.activate & sm_activate::ENABLE != 0,
            deactivated: sm.pdi_control & sm_activate::PDI_DEACTIVATE != 0,
        }
    }

    /// Working: activated, not deactivated, length not 0.
    pub(crate) fn active(&self) -> bool {
        self.enabled && !self.deactivated && self.len > 0
    }

    /// Mailbox mode (control bits 0–1 = 10b).
    pub(crate) fn mailbox(&self) -> bool {
        self.control & sm_control::MODE_MASK == sm_control::MODE_MAILBOX
    }

    /// Written by the master (control bits 2–3 = 01b).
    pub(crate) fn master_writes(&self) -> bool {
        self.control & sm_control::DIRECTION_MASK == sm_control::DIRECTION_WRITE
    }

    fn overlaps(&self, start: usize, len: usize) -> bool {
        len > 0 && start < self.start + self.len && self.start < start + len
    }

    fn covers_last(&self, start: usize, len: usize) -> bool {
        let last = self.start + self.len - 1;
        start <= last && last < start + len
    }
}

/// Whether a SyncManager lets an access through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SmAccess {
    /// Go ahead.
    Allowed,
    /// Refused (mailbox full/empty, wrong direction): not performed, not counted.
    Refused,
}

/// The verdict for the two halves of an access.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Check {
    /// For the read half.
    pub(crate) read: SmAccess,
    /// For the write half.
    pub(crate) write: SmAccess,
}

/// A buffer that changed hands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SmEvent {
    /// The master completed the receive mailbox of SyncManager n.
    MailboxWritten(usize),
    /// The master read the send mailbox of SyncManager n completely.
    MailboxRead(usize),
    /// The master completed an output buffer of SyncManager n.
    OutputsWritten(usize),
    /// The master toggled SyncManager n's repeat request (0806h bit 1).
    Repeat(usize),
}

/// The buffer states of the eight SyncManagers.
#[derive(Debug, Clone, Default)]
pub(crate) struct SyncManagers {
    full: [bool; 8],
}

impl SyncManagers {
    /// What the SyncManagers say to an access of `len` bytes at `start`.
    pub(crate) fn check(
        &self,
        mem: &[u8],
        start: usize,
        len: usize,
        reads: bool,
        writes: bool,
    ) -> Check {
        let mut c = Check {
            read: SmAccess::Allowed,
            write: SmAccess::Allowed,
        };
        for n in 0..self.full.len() {
            let sm = SmConfig::read(mem, n);
            if !sm.active() || !sm.overlaps(start, len) {
                continue;
            }
            let refuse_write = !sm.master_writes() || (sm.mailbox() && self.full[n]);
            let refuse_read = sm.mailbox() && !sm.master_writes() && !self.full[n];
            if writes && refuse_write {
                c.write = SmAccess::Refused;
            }
            if reads && refuse_read {
                c.read = SmAccess::Refused;
            }
        }
        c
    }

    /// After an access: buffers whose last byte was accessed change hands.
    pub(crate) fn complete(
        &mut self,
        mem: &mut [u8],
        start: usize,
        len: usize,
        read: bool,
        written: bool,
    ) -> Vec<SmEvent> {
        let mut events = Vec::new();
        for n in 0..self.full.len() {
            let sm = SmConfig::read(mem, n);
            if !sm.active() || !sm.overlaps(start, len) || !sm.covers_last(start, len) {
                continue;
            }
            match (sm.mailbox(), sm.master_writes()) {
                (true, true) if written => {
                    self.full[n] = true;
                    events.push(SmEvent::MailboxWritten(n));
                }
                (true, false) if read => {
                    self.full[n] = false;
                    events.push(SmEvent::MailboxRead(n));
                }
                (false, true) if written => events.push(SmEvent::OutputsWritten(n)),
                _ => continue,
            }
            self.show(mem, n);
        }
        events
    }

    /// The status register (0805h + 8·n): bit 3 mailbox full; buffered mode bits 4–5 (11b no
    /// buffer written, 00b buffer 1), bit 0 write event, bit 1 read event.
    fn show(&self, mem: &mut [u8], n: usize) {
        let sm = SmConfig::read(mem, n);
        let status = if sm.mailbox() {
            match (self.full[n], sm.master_writes()) {
                (true, true) => 0x09,
                (true, false) => 0x08,
                (false, true) => 0x00,
                (false, false) => 0x02,
            }
        } else {
            0x01
        };
        mem[register(n) + 5] = status;
    }

    /// The master wrote SyncManager n's activation register: disabling it empties its buffer;
    /// a toggled repeat request is reported.
    pub(crate) fn activation(&mut self, mem: &mut [u8], n: usize) -> Option<SmEvent> {
        let r = register(n);
        if mem[r + 6] & 1 == 0 {
            self.full[n] = false;
            mem[r + 5] = 0;
        }
        ((mem[r + 6] ^ mem[r + 7]) & 0x02 != 0).then_some(SmEvent::Repeat(n))
    }

    /// Acknowledges a repeat request (0807h bit 1 follows 0806h bit 1).
    pub(crate) fn ack_repeat(&self, mem: &mut [u8], n: usize) {
        let r = register(n);
        mem[r + 7] = (mem[r + 7] & !0x02) | (mem[r + 6] & 0x02);
    }

    /// The application deactivates (or releases) SyncManager n (0807h bit 0); a deactivated
    /// mailbox is emptied.
    pub(crate) fn deactivate(&mut self, mem: &mut [u8], n: usize, off: bool) {
        let r = register(n);
        mem[r + 7] = (mem[r + 7] & !1) | u8::from(off);
        if off {
            self.full[n] = false;
            mem[r + 5] = 0;
        }
    }

    /// The application takes the receive mailbox of SyncManager n, emptying it.
    pub(crate) fn take(&mut self, mem: &mut [u8], n: usize) -> Option<Vec<u8>> {
        let sm = SmConfig::read(mem, n);
        if !sm.active() || !self.full[n] {
            return None;
        }
        let end = (sm.start + sm.len).min(mem.len());
        let data = mem[sm.start.min(end)..end].to_vec();
        self.full[n] = false;
        self.show(mem, n);
        Some(data)
    }

    /// Whether SyncManager n's mailbox buffer is full.
    pub(crate) fn is_full(&self, n: usize) -> bool {
        self.full.get(n).copied().unwrap_or(false)
    }

    /// The application fills the send mailbox of SyncManager n (padding with zeros); `false`
    /// when it is full or not working.
    pub(crate) fn put(&mut self, mem: &mut [u8], n: usize, data: &[u8]) -> bool {
        let sm = SmConfig::read(mem, n);
        if !sm.active() || self.full[n] || data.len() > sm.len || sm.start + sm.len > mem.len() {
            return false;
        }
        let buf = &mut mem[sm.start..sm.start + sm.len];
        buf.fill(0);
        buf[..data.len()].copy_from_slice(data);
        self.full[n] = true;
        self.show(mem, n);
        true
    }
}
