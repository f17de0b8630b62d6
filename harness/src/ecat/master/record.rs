//! What the master exchanged, for transcripts: each frame sent and what came back, as bytes and
//! as one decoded line each.

use crate::hex::hex;
use crate::outcome::Exchange;

/// The exchanges recorded since the caller last took them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Recorder {
    exchanges: Vec<Exchange>,
    /// Whether to record at all.
    on: bool,
    /// What the next exchange's request means one layer up.
    note: Option<String>,
}

impl Recorder {
    /// A recorder that records.
    pub(crate) fn new() -> Recorder {
        Recorder {
            exchanges: Vec::new(),
            on: true,
            note: None,
        }
    }

    /// Turns recording on or off.
    pub(crate) fn set_on(&mut self, on: bool) {
        self.on = on;
    }

    /// Whether it records.
    pub(crate) fn is_on(&self) -> bool {
        self.on
    }

    /// Records one pair; `received` empty and its line saying why when nothing came back.
    pub(crate) fn push(
        &mut self,
        sent: &[u8],
        sent_line: String,
        received: &[u8],
        received_line: String,
    ) {
        let sent_line = match self.note.take() {
            Some(n) => format!("{n}: {sent_line}"),
            None => sent_line,
        };
        if self.on {
            self.exchanges.push(Exchange {
                sent_hex: hex(sent),
                sent: sent_line,
                received_hex: hex(received),
                received: received_line,
            });
        }
    }

    /// An exchange not recorded (recording is off): a note meant for it goes with it.
    pub(crate) fn skip(&mut self) {
        self.note = None;
    }

    /// Says what the next exchange's request means one layer up ("mailbox CoE SDO upload
    /// 3066h:01h"); it prefixes that exchange's decoded request.
    pub(crate) fn note_next(&mut self, note: String) {
        self.note = Some(note);
    }

    /// Adds a note to the last exchange's decoded lines (the meaning one layer up: "CoE SDO
    /// upload request 3066h:01h").
    pub(crate) fn annotate(&mut self, sent: &str, received: &str) {
        if let Some(e) = self.exchanges.last_mut() {
            if !sent.is_empty() {
                e.sent = format!("{sent}: {}", e.sent);
            }
            if !received.is_empty() {
                e.received = format!("{received}: {}", e.received);
            }
        }
    }

    /// Takes the exchanges recorded so far.
    pub(crate) fn take(&mut self) -> Vec<Exchange> {
        std::mem::take(&mut self.exchanges)
    }
}
