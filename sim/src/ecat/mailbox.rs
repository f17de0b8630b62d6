//! The mailbox layer (ETG.1000.6 §5.5): messages the master writes into the receive mailbox
//! (SM0) and the slave's replies, queued until the send mailbox (SM1) is free.
//!
//! - The header's length must fit the SyncManager: otherwise a mailbox error "invalid size"
//!   (0008h); a CoE message too short for its header or its SDO, "size too short" (0006h).
//! - Types other than CoE (the only protocol of BU 0620 §2.2.7; SII word 1Ch) get "unsupported
//!   protocol" (0002h), as does CoE in Bootstrap; CoE services other than SDO requests get
//!   "service not supported" (0004h), a service number CoE does not define (0, 9…15)
//!   "invalid header" (0005h).
//! - A message with the same non-zero counter as the one before is the master's retry of a
//!   message already served: it is dropped (ETG.1000.6 §5.5.1 "Cnt").
//! - The slave numbers its own messages 1..7 and keeps the last one for the repeat request
//!   (SM1 activate bit 1, ETG.1000.4 §6.7.3).

use std::collections::VecDeque;

use proto::ecat::coe::{CoeHeader, CoeService, SdoRequest};
use proto::ecat::mailbox::{
    Mailbox as MailboxView, MailboxError, MailboxErrorCode, MailboxRepr, MailboxType,
};
use proto::nord::nmt::EcState;
use proto::wire::Error;

use super::coe::SdoServer;
use super::od::{Context, Dictionary};

/// Replies kept while the send mailbox is full; older ones are dropped beyond this.
const QUEUE_MAX: usize = 16;

/// The mailbox state.
#[derive(Debug, Clone, Default)]
pub(crate) struct Mailbox {
    last_counter: Option<u8>,
    counter: u8,
    queue: VecDeque<Vec<u8>>,
    /// The last message put into the send mailbox (for a repeat request).
    pub(crate) last_sent: Option<Vec<u8>>,
    sdo: SdoServer,
    /// Messages the slave could not understand (answered with a mailbox error).
    pub(crate) errors: u64,
}

impl Mailbox {
    /// Forgets everything (the mailbox was switched off: Init).
    pub(crate) fn reset(&mut self) {
        *self = Mailbox {
            errors: self.errors,
            ..Mailbox::default()
        };
    }

    /// Queues a message of `kind` with the next counter.
    pub(crate) fn send(&mut self, kind: MailboxType, body: Vec<u8>) {
        self.counter = proto::ecat::mailbox::next_counter(self.counter);
        if self.queue.len() >= QUEUE_MAX {
            self.queue.pop_front();
        }
        // A body is at most a mailbox long (far below the 16-bit length field).
        if let Ok(m) = MailboxRepr::new(kind, self.counter, body).emit() {
            self.queue.push_back(m);
        }
    }

    /// The counter of the message queued last (0: none yet).
    pub(crate) fn counter(&self) -> u8 {
        self.counter
    }

    /// The next message for the send mailbox.
    pub(crate) fn next(&mut self) -> Option<Vec<u8>> {
        self.queue.pop_front()
    }

    /// Puts a message back in front (the send mailbox was not free).
    pub(crate) fn unsend(&mut self, m: Vec<u8>) {
        self.queue.push_front(m);
    }

    fn fail(&mut self, detail: MailboxErrorCode) {
        self.errors += 1;
        self.send(MailboxType::ERR, MailboxError::new(detail).emit().to_vec());
    }

    /// One message the master completed in the receive mailbox (`buf`, the whole buffer);
    /// `room` is the send mailbox's size.
    pub(crate) fn receive(
        &mut self,
        buf: &[u8],
        room: usize,
        state: EcState,
        od: &Dictionary,
        cx: &mut Context<'_>,
    ) {
        let m = MailboxView::new_unchecked(buf);
        match m.check_len() {
            Ok(()) => {}
            Err(Error::Truncated { .. }) => return self.fail(MailboxErrorCode::SIZE_TOO_SHORT),
            Err(_) => return self.fail(MailboxErrorCode::INVALID_SIZE),
        }
        let counter = m.counter();
        if counter != 0 && self.last_counter == Some(counter) {
            return;
        }
        self.last_counter = Some(counter);
        if m.kind() != MailboxType::COE || state == EcState::Bootstrap {
            return self.fail(MailboxErrorCode::UNSUPPORTED_PROTOCOL);
        }
        let Ok((coe, sdo)) = CoeHeader::split(m.data()) else {
            return self.fail(MailboxErrorCode::SIZE_TOO_SHORT);
        };
        if coe.service.name().is_none() {
            // A service number CoE does not define (0, 9…15): the header itself is wrong.
            return self.fail(MailboxErrorCode::INVALID_HEADER);
        }
        if coe.service != CoeService::SDO_REQUEST {
            return self.fail(MailboxErrorCode::SERVICE_NOT_SUPPORTED);
        }
        let resp = match SdoRequest::parse_lenient(sdo) {
            Ok(req) => self.sdo.serve(od, cx, req, room),
            // A command specifier 5..7: the 8 bytes are there, index and sub-index with them.
            Err(Error::Unknown { .. }) => Some(
                self.sdo
                    .unknown(u16::from_le_bytes([sdo[1], sdo[2]]), sdo[3]),
            ),
            Err(_) => return self.fail(MailboxErrorCode::SIZE_TOO_SHORT),
        };
        if let Some(body) = resp.and_then(|r| r.emit_coe().ok()) {
            self.send(MailboxType::COE, body);
        }
    }
}
