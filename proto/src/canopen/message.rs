//! CANopen messages in CAN 2.0A frames: a frame sorted by its COB-ID
//! ([`super::Cob::classify`]) and read as the object it belongs to, and the frames that carry
//! SDO messages to and from a node.
//!
//! SDO frames stay 8 raw bytes here: whether a frame on 600h + node is an [`SdoRequest`] or a
//! [`super::BlockSegment`] depends on the transfer under way, which only the client or server
//! knows.

use super::cob_id::{Cob, Function};
use super::{Emergency, ErrorControl, NmtFrame, SdoRequest, SdoResponse, SyncFrame};
use crate::can::CanFrame;
use crate::wire::{Error, Reader};

/// Length of the TIME object (CiA 301 TIME_OF_DAY: ms after midnight, 28 bits, 4 reserved;
/// days since 1 January 1984, u16).
pub const TIME_LEN: usize = 6;

/// A CAN frame read as a CANopen object of the pre-defined connection set.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Message {
    /// NMT module control (000h).
    Nmt(NmtFrame),
    /// SYNC (080h).
    Sync(SyncFrame),
    /// TIME (100h), its 6 bytes.
    Time {
        /// TIME_OF_DAY, not interpreted.
        data: [u8; TIME_LEN],
    },
    /// Emergency from `node`.
    Emergency {
        /// The producer.
        node: u8,
        /// The message.
        emergency: Emergency,
    },
    /// A PDO (TPDO or RPDO 1..4 of `node`), its data not interpreted (the mapping says).
    Pdo {
        /// Which PDO.
        function: Function,
        /// The node.
        node: u8,
        /// 0..8 bytes.
        data: Vec<u8>,
    },
    /// An SDO frame to ([`Function::SdoRx`]) or from ([`Function::SdoTx`]) `node`.
    Sdo {
        /// The direction.
        function: Function,
        /// The server's node.
        node: u8,
        /// The 8 bytes.
        data: [u8; 8],
    },
    /// Heartbeat, boot-up or node guarding response of `node`.
    ErrorControl {
        /// The node.
        node: u8,
        /// The message.
        message: ErrorControl,
    },
    /// A remote frame on 700h + node: node guarding asks `node` for its state.
    GuardRequest {
        /// The node asked.
        node: u8,
    },
    /// A remote frame on a TPDO: the PDO is asked for.
    PdoRequest {
        /// Which TPDO.
        function: Function,
        /// The node.
        node: u8,
    },
}

fn exact<const N: usize>(data: &[u8], what: &'static str) -> Result<[u8; N], Error> {
    let mut r = Reader::new(data);
    let b = r.bytes(N, what)?;
    r.finish(what)?;
    let mut out = [0; N];
    out.copy_from_slice(b);
    Ok(out)
}

impl Message {
    /// Reads `frame`. An identifier outside the pre-defined connection set is
    /// [`Error::CobId`]; a remote frame on an object that is not requested so, or a frame of
    /// the wrong length, is an error as the object's parser says.
    pub fn parse(frame: &CanFrame) -> Result<Message, Error> {
        let Cob { function, node } = Cob::classify(frame.id()).ok_or(Error::CobId {
            what: "CANopen message",
            cob_id: frame.id(),
            expected: "in the pre-defined connection set",
        })?;
        let data = frame.data();
        if frame.is_remote() {
            return match function {
                Function::ErrorControl => Ok(Message::GuardRequest { node }),
                Function::Tpdo { .. } => Ok(Message::PdoRequest { function, node }),
                _ => Err(Error::CobId {
                    what: "remote frame",
                    cob_id: frame.id(),
                    expected: "700h + node (node guarding) or a TPDO",
                }),
            };
        }
        Ok(match function {
            Function::Nmt => Message::Nmt(NmtFrame::parse(data)?),
            Function::Sync => Message::Sync(SyncFrame::parse(data)?),
            Function::Time => Message::Time {
                data: exact(data, "TIME")?,
            },
            Function::Emcy => Message::Emergency {
                node,
                emergency: Emergency::from_bytes(exact(data, "emergency")?),
            },
            Function::Tpdo { .. } | Function::Rpdo { .. } => Message::Pdo {
                function,
                node,
                data: data.to_vec(),
            },
            Function::SdoTx | Function::SdoRx => Message::Sdo {
                function,
                node,
                data: exact(data, "SDO frame")?,
            },
            Function::ErrorControl => Message::ErrorControl {
                node,
                message: ErrorControl::parse(data)?,
            },
        })
    }

    /// The CAN frame carrying the message: its COB-ID from the function and node (checked),
    /// its data as the object's `emit` writes it.
    pub fn to_can(&self) -> Result<CanFrame, Error> {
        let (function, node, data): (Function, u8, Vec<u8>) = match self {
            Message::Nmt(n) => (Function::Nmt, 0, n.emit().to_vec()),
            Message::Sync(s) => (Function::Sync, 0, s.emit()),
            Message::Time { data } => (Function::Time, 0, data.to_vec()),
            Message::Emergency { node, emergency } => {
                (Function::Emcy, *node, emergency.emit().to_vec())
            }
            Message::Pdo {
                function,
                node,
                data,
            } => (pdo(*function)?, *node, data.clone()),
            Message::Sdo {
                function,
                node,
                data,
            } => (sdo(*function)?, *node, data.to_vec()),
            Message::ErrorControl { node, message } => {
                (Function::ErrorControl, *node, message.emit().to_vec())
            }
            Message::GuardRequest { node } => {
                return CanFrame::remote(Function::ErrorControl.cob_id(*node)?, 1)
            }
            Message::PdoRequest { function, node } => {
                return CanFrame::remote(pdo(*function)?.cob_id(*node)?, 0)
            }
        };
        CanFrame::new(function.cob_id(node)?, &data)
    }
}

fn pdo(function: Function) -> Result<Function, Error> {
    match function {
        Function::Tpdo { .. } | Function::Rpdo { .. } => Ok(function),
        _ => Err(Error::Invalid {
            field: "PDO function",
            value: 0,
            why: "a PDO message needs a TPDO or RPDO function",
        }),
    }
}

fn sdo(function: Function) -> Result<Function, Error> {
    match function {
        Function::SdoTx | Function::SdoRx => Ok(function),
        _ => Err(Error::Invalid {
            field: "SDO function",
            value: 0,
            why: "an SDO message needs the SdoTx or SdoRx function",
        }),
    }
}

impl SdoRequest {
    /// The frame carrying the request to the server `node` (600h + node).
    pub fn to_can(&self, node: u8) -> Result<CanFrame, Error> {
        CanFrame::new(Function::SdoRx.cob_id(node)?, &self.emit())
    }
}

impl SdoResponse {
    /// The frame carrying the response of the server `node` (580h + node).
    pub fn to_can(&self, node: u8) -> Result<CanFrame, Error> {
        CanFrame::new(Function::SdoTx.cob_id(node)?, &self.emit())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::{NmtCommand, StateCode};

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(id, data).unwrap()
    }

    #[test]
    fn frames_are_sorted_by_cob_id() {
        let cases = [
            (
                frame(0x000, &[0x01, 0x00]),
                Message::Nmt(NmtFrame {
                    command: NmtCommand::START,
                    node: 0,
                }),
            ),
            (
                frame(0x080, &[]),
                Message::Sync(SyncFrame { counter: None }),
            ),
            (
                frame(0x100, &[1, 2, 3, 4, 5, 6]),
                Message::Time {
                    data: [1, 2, 3, 4, 5, 6],
                },
            ),
            (
                frame(0x085, &[0x00, 0x10, 0x01, 0, 0, 0, 0, 0]),
                Message::Emergency {
                    node: 5,
                    emergency: Emergency {
                        code: 0x1000,
                        register: 1,
                        data: [0; 5],
                    },
                },
            ),
            (
                frame(0x185, &[0x37, 0x06]),
                Message::Pdo {
                    function: Function::Tpdo { number: 1 },
                    node: 5,
                    data: vec![0x37, 0x06],
                },
            ),
            (
                frame(0x605, &[0x40, 0, 0x10, 0, 0, 0, 0, 0]),
                Message::Sdo {
                    function: Function::SdoRx,
                    node: 5,
                    data: [0x40, 0, 0x10, 0, 0, 0, 0, 0],
                },
            ),
            (
                frame(0x705, &[0x7F]),
                Message::ErrorControl {
                    node: 5,
                    message: ErrorControl {
                        state: StateCode::PRE_OPERATIONAL,
                        toggle: false,
                    },
                },
            ),
            (
                CanFrame::remote(0x705, 1).unwrap(),
                Message::GuardRequest { node: 5 },
            ),
            (
                CanFrame::remote(0x285, 0).unwrap(),
                Message::PdoRequest {
                    function: Function::Tpdo { number: 2 },
                    node: 5,
                },
            ),
        ];
        for (f, m) in cases {
            assert_eq!(Message::parse(&f).unwrap(), m, "{f:?}");
            assert_eq!(m.to_can().unwrap(), f, "{m:?}");
        }
    }

    #[test]
    fn wrong_ids_lengths_and_remote_frames() {
        assert_eq!(
            Message::parse(&frame(0x680, &[])),
            Err(Error::CobId {
                what: "CANopen message",
                cob_id: 0x680,
                expected: "in the pre-defined connection set"
            })
        );
        assert!(matches!(
            Message::parse(&frame(0x605, &[0x40; 7])),
            Err(Error::Truncated {
                what: "SDO frame",
                ..
            })
        ));
        assert!(matches!(
            Message::parse(&frame(0x085, &[0; 7])),
            Err(Error::Truncated { .. })
        ));
        assert!(matches!(
            Message::parse(&CanFrame::remote(0x605, 8).unwrap()),
            Err(Error::CobId {
                what: "remote frame",
                ..
            })
        ));
        assert!(Message::Pdo {
            function: Function::SdoTx,
            node: 1,
            data: vec![]
        }
        .to_can()
        .is_err());
        assert!(Message::Pdo {
            function: Function::Rpdo { number: 1 },
            node: 1,
            data: vec![0; 9]
        }
        .to_can()
        .is_err());
    }

    #[test]
    fn sdo_frames_to_and_from_a_node() {
        let req = SdoRequest::InitiateUpload {
            index: 0x1000,
            sub: 0,
        };
        let f = req.to_can(5).unwrap();
        assert_eq!(f.id(), 0x605);
        assert_eq!(SdoRequest::parse(f.data()), Ok(req));
        let resp = SdoResponse::InitiateDownload {
            index: 0x1017,
            sub: 0,
        };
        assert_eq!(resp.to_can(127).unwrap().id(), 0x5FF);
        assert!(matches!(
            resp.to_can(0),
            Err(Error::Invalid {
                field: "node id",
                ..
            })
        ));
    }
}
