//! The mailbox layer (ETG.1000.6 §5.5): messages the master writes into the receive mailbox
//! (SM0) and the slave's replies, queued until the send mailbox (SM1) is free.
//!
//! - The header's length must fit the SyncManager: otherwise a mailbox error "invalid size"
//!   (0008h); a CoE message too short for its header or its SDO, "size too short" (0006h).
//! - Types other than CoE (the only protocol of BU 0620 §2.2.7; SII word 1Ch) get "unsupported
//!   protocol" (0002h), as does CoE in Bootstrap; CoE services other than SDO requests get
//!   "service not supported" (0004h).
//! - A message with the same non-zero counter as the one before is the master's retry of a
//!   message already served: it is dropped (ETG.1000.6 §5.5.1 "Cnt").
//! - The slave numbers its own messages 1..7 and keeps the last one for the repeat request
//!   (SM1 activate bit 1, ETG.1000.4 §6.7.3).

use std::collections::VecDeque;

use proto::nord::nmt::EcState;

use super::coe::SdoServer;
use super::od::{Context, Dictionary};
use super::wire::{self, MailboxHeader, MAILBOX_HEADER};

/// Mailbox types (ETG.1000.6 table 29).
pub(crate) mod kind {
    /// Error reply.
    pub(crate) const ERROR: u8 = 0;
    /// CAN application protocol over EtherCAT.
    pub(crate) const COE: u8 = 3;
}

/// Mailbox error details (ETG.1000.6 table 30).
pub(crate) mod error {
    /// The protocol is not supported.
    pub(crate) const UNSUPPORTED_PROTOCOL: u16 = 0x0002;
    /// The service of the protocol is not supported.
    pub(crate) const SERVICE_NOT_SUPPORTED: u16 = 0x0004;
    /// The data is too short for the protocol's header.
    pub(crate) const SIZE_TOO_SHORT: u16 = 0x0006;
    /// The length does not fit the mailbox.
    pub(crate) const INVALID_SIZE: u16 = 0x0008;
}

/// CoE services (ETG.1000.6 table 33).
mod service {
    pub(super) const SDO_REQUEST: u8 = 2;
}

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
    pub(crate) fn send(&mut self, kind: u8, body: &[u8]) {
        self.counter = self.counter % 7 + 1;
        if self.queue.len() >= QUEUE_MAX {
            self.queue.pop_front();
        }
        self.queue
            .push_back(MailboxHeader::message(kind, self.counter, body));
    }

    /// The next message for the send mailbox.
    pub(crate) fn next(&mut self) -> Option<Vec<u8>> {
        self.queue.pop_front()
    }

    /// Puts a message back in front (the send mailbox was not free).
    pub(crate) fn unsend(&mut self, m: Vec<u8>) {
        self.queue.push_front(m);
    }

    fn fail(&mut self, detail: u16) {
        self.errors += 1;
        self.send(kind::ERROR, &wire::mailbox_error(detail));
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
        let Some(h) = MailboxHeader::parse(buf) else {
            return self.fail(error::SIZE_TOO_SHORT);
        };
        if h.length > buf.len() - MAILBOX_HEADER {
            return self.fail(error::INVALID_SIZE);
        }
        if h.counter != 0 && self.last_counter == Some(h.counter) {
            return;
        }
        self.last_counter = Some(h.counter);
        let body = &buf[MAILBOX_HEADER..MAILBOX_HEADER + h.length];
        if h.kind != kind::COE || state == EcState::Bootstrap {
            return self.fail(error::UNSUPPORTED_PROTOCOL);
        }
        let Some(service) = wire::coe_service(body) else {
            return self.fail(error::SIZE_TOO_SHORT);
        };
        if service != service::SDO_REQUEST {
            return self.fail(error::SERVICE_NOT_SUPPORTED);
        }
        let Some(req) = wire::sdo_request(&body[2..]) else {
            return self.fail(error::SIZE_TOO_SHORT);
        };
        if let Some(resp) = self.sdo.serve(od, cx, req, room) {
            self.send(kind::COE, &wire::sdo_response(&resp));
        }
    }
}
