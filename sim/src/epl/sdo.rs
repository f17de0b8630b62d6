//! The node's SDO server (EPSG DS 301 §6.3): one sequence-layer connection per client — the
//! MN over ASnd, any UDP peer over UDP/IP — and the command layer's ReadByIndex and
//! WriteByIndex, expedited or segmented, on the [`Dictionary`].
//!
//! Sequence layer: a client opens with SendCon "initialisation"; the server answers
//! ReceiveCon and SendCon "initialisation"; the client's confirmation is answered "valid"
//! both ways (a client may also send its first command at once); frames then carry SendCon
//! "valid" and a send
//! sequence number one above the last (mod 64). A repeated number is a retransmission: the
//! last answer is sent again. Any other number, or a command without a connection, is an
//! error of the sequence layer: ReceiveCon 3 (retransmission request) and, when the frame
//! carried a command, its abort with 05040003h "Error in sequence layer" (BU 0620 §2.4.7).
//! SendCon "no connection" closes.
//!
//! Command layer: unknown or unsupported commands abort with 05040001h "SDO command
//! invalid/unknown"; a read whose segment is not the 4 bytes of index, sub-index and reserved
//! byte with 05040002h; a segmented write whose segments do not add up to its DataSize with
//! 05040002h "Impermissible size of transferred data"; one larger than the node takes with
//! 05040005h "No memory"; a segment of another transaction than the one in progress with
//! 05040001h. An abort from the client ends its transfer without an answer.

use proto::epl::sdo::{Command, CommandId, Con, SdoFrame, Segmentation, Seq, SEQ_MODULO};
use proto::nord::errors::SdoAbort;

use super::od::{Context, Dictionary};
use crate::objects::abort;

/// Abort codes of the SDO protocol itself (BU 0620 §2.4.7, BU 2200 §6.4.1).
pub(crate) mod protocol {
    use proto::nord::errors::SdoAbort;
    /// SDO command invalid/unknown.
    pub(crate) const COMMAND: SdoAbort = SdoAbort(0x0504_0001);
    /// Impermissible size of transferred data.
    pub(crate) const SIZE: SdoAbort = SdoAbort(0x0504_0002);
    /// Error in sequence layer.
    pub(crate) const SEQUENCE: SdoAbort = SdoAbort(0x0504_0003);
}

/// The data bytes one segment carries (the MTU of 300 bytes less the ASnd, sequence and
/// command headers, rounded down).
pub(crate) const SEGMENT_DATA: usize = 256;
/// The largest segmented write the node buffers.
pub(crate) const MAX_TRANSFER: usize = 1024;

/// Who the client is.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) enum Peer {
    /// A node over ASnd (the MN, 240).
    Asnd(u8),
    /// A UDP/IP client.
    Udp(std::net::SocketAddr),
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Link {
    Init,
    Valid,
}

/// A segmented write in progress.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Download {
    transaction: u8,
    index: u16,
    sub: u8,
    size: usize,
    data: Vec<u8>,
}

#[derive(Debug, Clone, PartialEq, Eq)]
struct Connection {
    peer: Peer,
    link: Link,
    /// The client's last send sequence number.
    received: u8,
    /// Ours.
    sent: u8,
    last: Vec<SdoFrame>,
    download: Option<Download>,
}

/// The server: its connections.
#[derive(Debug, Clone, Default)]
pub(crate) struct Server {
    connections: Vec<Connection>,
}

fn next(n: u8) -> u8 {
    (n + 1) % SEQ_MODULO
}

impl Server {
    /// Drops every connection (a reset of the node).
    pub(crate) fn reset(&mut self) {
        self.connections.clear();
    }

    /// Handles one frame of `peer`; returns the frames to send back, in order.
    pub(crate) fn handle(
        &mut self,
        peer: Peer,
        frame: &SdoFrame,
        od: &Dictionary,
        cx: &mut Context<'_>,
    ) -> Vec<SdoFrame> {
        let seq = frame.seq;
        let at = self.connections.iter().position(|c| c.peer == peer);
        match (seq.scon, at) {
            (Con::None, Some(i)) => {
                self.connections.remove(i);
                return Vec::new();
            }
            // Closing a connection there is not: nothing to do, nothing to answer.
            (Con::None, None) if frame.command.is_none() => return Vec::new(),
            (Con::None, None) => return refuse(seq, frame.command.as_ref()),
            (Con::Init, _) => {
                if let Some(i) = at {
                    self.connections.remove(i);
                }
                let c = Connection {
                    peer,
                    link: Link::Init,
                    received: seq.ssnr,
                    sent: 0,
                    last: Vec::new(),
                    download: None,
                };
                let answer = vec![SdoFrame {
                    seq: Seq {
                        rsnr: seq.ssnr,
                        rcon: Con::Init,
                        ssnr: c.sent,
                        scon: Con::Init,
                    },
                    command: None,
                }];
                self.connections.push(c);
                return answer;
            }
            (_, None) => return refuse(seq, frame.command.as_ref()),
            (_, Some(_)) => {}
        }
        let Some(i) = at else { return Vec::new() };
        let c = &mut self.connections[i];
        let Some(command) = &frame.command else {
            // The client's confirmation of the initialisation is answered "connection valid"
            // (DS 301 §6.3.2.2 connection set-up, the fourth frame), as is an acknowledge
            // request; a plain acknowledgement needs no answer.
            let answer = c.link == Link::Init || seq.scon == Con::ErrorOrAckRequest;
            c.link = Link::Valid;
            if !answer {
                return Vec::new();
            }
            return vec![SdoFrame {
                seq: Seq {
                    rsnr: c.received,
                    rcon: Con::Valid,
                    ssnr: c.sent,
                    scon: Con::Valid,
                },
                command: None,
            }];
        };
        if seq.ssnr == c.received && c.link == Link::Valid {
            return c.last.clone();
        }
        if seq.ssnr != next(c.received) {
            let answer = SdoFrame {
                seq: Seq {
                    rsnr: c.received,
                    rcon: Con::ErrorOrAckRequest,
                    ssnr: c.sent,
                    scon: Con::Valid,
                },
                command: Some(abort_of(command, protocol::SEQUENCE)),
            };
            return vec![answer];
        }
        c.received = seq.ssnr;
        c.link = Link::Valid;
        let commands = execute(c, command, od, cx);
        let mut out = Vec::with_capacity(commands.len());
        for cmd in commands {
            c.sent = next(c.sent);
            out.push(SdoFrame {
                seq: Seq {
                    rsnr: c.received,
                    rcon: Con::Valid,
                    ssnr: c.sent,
                    scon: Con::Valid,
                },
                command: Some(cmd),
            });
        }
        c.last = out.clone();
        out
    }
}

/// The answer to a frame that needs a connection and has none.
fn refuse(seq: Seq, command: Option<&Command>) -> Vec<SdoFrame> {
    vec![SdoFrame {
        seq: Seq {
            rsnr: seq.ssnr,
            rcon: Con::ErrorOrAckRequest,
            ssnr: 0,
            scon: Con::None,
        },
        command: command.map(|c| abort_of(c, protocol::SEQUENCE)),
    }]
}

fn abort_of(request: &Command, code: SdoAbort) -> Command {
    Command::abort(request.transaction, request.command, true, code.0)
}

fn response(request: &Command, payload: Vec<u8>) -> Command {
    Command {
        transaction: request.transaction,
        response: true,
        command: request.command,
        payload,
        ..Command::default()
    }
}

/// Runs one command; the responses (several for a segmented read).
fn execute(
    c: &mut Connection,
    request: &Command,
    od: &Dictionary,
    cx: &mut Context<'_>,
) -> Vec<Command> {
    if request.abort {
        if c.download.as_ref().map(|d| d.transaction) == Some(request.transaction) {
            c.download = None;
        }
        return Vec::new();
    }
    if request.response {
        return vec![abort_of(request, protocol::COMMAND)];
    }
    match (request.command, request.segmentation) {
        (CommandId::READ_BY_INDEX, Segmentation::Expedited) => {
            // A read carries index, sub-index and a reserved byte, nothing more.
            let Ok((index, sub, [])) = request.by_index() else {
                return vec![abort_of(request, protocol::SIZE)];
            };
            match od.upload(cx, index, sub) {
                Ok(data) => segments(request, data),
                Err(code) => vec![abort_of(request, code)],
            }
        }
        (CommandId::WRITE_BY_INDEX, Segmentation::Expedited) => {
            let Ok((index, sub, data)) = request.by_index() else {
                return vec![abort_of(request, protocol::SIZE)];
            };
            vec![match od.download(cx, index, sub, data) {
                Ok(()) => response(request, Vec::new()),
                Err(code) => abort_of(request, code),
            }]
        }
        (CommandId::WRITE_BY_INDEX, Segmentation::Initiate) => {
            let Ok((index, sub, data)) = request.by_index() else {
                return vec![abort_of(request, protocol::SIZE)];
            };
            let size = request.data_size.unwrap_or(0) as usize;
            if size > MAX_TRANSFER {
                return vec![abort_of(request, abort::NO_MEMORY)];
            }
            // DataSize counts the data after index and sub-index.
            c.download = Some(Download {
                transaction: request.transaction,
                index,
                sub,
                size: size.saturating_sub(4),
                data: data.to_vec(),
            });
            vec![response(request, Vec::new())]
        }
        (_, Segmentation::Segment | Segmentation::Complete) => {
            let Some(d) = c.download.as_mut() else {
                return vec![abort_of(request, protocol::COMMAND)];
            };
            if d.transaction != request.transaction {
                return vec![abort_of(request, protocol::COMMAND)];
            }
            d.data.extend(&request.payload);
            if d.data.len() > d.size {
                c.download = None;
                return vec![abort_of(request, protocol::SIZE)];
            }
            if request.segmentation == Segmentation::Segment {
                return vec![response(request, Vec::new())];
            }
            let Some(d) = c.download.take() else {
                return Vec::new();
            };
            if d.data.len() != d.size {
                return vec![abort_of(request, protocol::SIZE)];
            }
            vec![match od.download(cx, d.index, d.sub, &d.data) {
                Ok(()) => response(request, Vec::new()),
                Err(code) => abort_of(request, code),
            }]
        }
        _ => vec![abort_of(request, protocol::COMMAND)],
    }
}

/// A read's answer: expedited when it fits one segment, else an initiate with the DataSize,
/// middle segments and a complete one.
fn segments(request: &Command, data: Vec<u8>) -> Vec<Command> {
    if data.len() <= SEGMENT_DATA {
        return vec![response(request, data)];
    }
    let chunks: Vec<&[u8]> = data.chunks(SEGMENT_DATA).collect();
    let last = chunks.len() - 1;
    chunks
        .into_iter()
        .enumerate()
        .map(|(i, chunk)| Command {
            segmentation: match i {
                0 => Segmentation::Initiate,
                n if n == last => Segmentation::Complete,
                _ => Segmentation::Segment,
            },
            data_size: (i == 0).then_some(data.len() as u32),
            ..response(request, chunk.to_vec())
        })
        .collect()
}
