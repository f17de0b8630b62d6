//! COB-IDs of the pre-defined connection set (CiA 301 "Pre-defined connection set": the
//! broadcast objects NMT, SYNC and TIME, and the peer-to-peer objects at a base plus the node
//! id 1..127). A device may be configured away from these (objects 1005h, 1014h, 1400h…,
//! 1800h…); the system bus's devices use them as the NORD manuals print them.
//!
//! | object | COB-ID |
//! |---|---|
//! | NMT | 000h |
//! | SYNC | 080h |
//! | EMCY | 080h + node |
//! | TIME | 100h |
//! | TPDO1, RPDO1 | 180h, 200h + node |
//! | TPDO2, RPDO2 | 280h, 300h + node |
//! | TPDO3, RPDO3 | 380h, 400h + node |
//! | TPDO4, RPDO4 | 480h, 500h + node |
//! | SDO server → client (tx), client → server (rx) | 580h, 600h + node |
//! | NMT error control (heartbeat, boot-up, node guarding) | 700h + node |
//!
//! 780h..7FFh and the unused node-0 ids of each range belong to no object here (CiA 305 LSS
//! uses 7E4h/7E5h, which falls in the NMT error control range of node 100/101).

use crate::wire::Error;

/// The largest node id.
pub const MAX_NODE: u8 = 127;

/// A communication object of the pre-defined connection set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Function {
    /// NMT module control (broadcast, 000h).
    Nmt,
    /// SYNC (broadcast, 080h).
    Sync,
    /// TIME stamp (broadcast, 100h).
    Time,
    /// Emergency (080h + node).
    Emcy,
    /// Transmit PDO (the device sends).
    Tpdo {
        /// 1..4.
        number: u8,
    },
    /// Receive PDO (the device receives).
    Rpdo {
        /// 1..4.
        number: u8,
    },
    /// SDO server → client (580h + node).
    SdoTx,
    /// SDO client → server (600h + node).
    SdoRx,
    /// NMT error control: heartbeat, boot-up, node guarding (700h + node).
    ErrorControl,
}

/// Every object with its COB-ID (broadcast objects) or base (the others), as data.
pub const PREDEFINED: &[(Function, u16)] = &[
    (Function::Nmt, 0x000),
    (Function::Sync, 0x080),
    (Function::Time, 0x100),
    (Function::Emcy, 0x080),
    (Function::Tpdo { number: 1 }, 0x180),
    (Function::Rpdo { number: 1 }, 0x200),
    (Function::Tpdo { number: 2 }, 0x280),
    (Function::Rpdo { number: 2 }, 0x300),
    (Function::Tpdo { number: 3 }, 0x380),
    (Function::Rpdo { number: 3 }, 0x400),
    (Function::Tpdo { number: 4 }, 0x480),
    (Function::Rpdo { number: 4 }, 0x500),
    (Function::SdoTx, 0x580),
    (Function::SdoRx, 0x600),
    (Function::ErrorControl, 0x700),
];

impl Function {
    /// Whether the object is a broadcast one (node 0: NMT, SYNC, TIME).
    pub fn is_broadcast(self) -> bool {
        matches!(self, Function::Nmt | Function::Sync | Function::Time)
    }

    /// The COB-ID of the object for `node` (0 for a broadcast object, 1..127 otherwise).
    pub fn cob_id(self, node: u8) -> Result<u16, Error> {
        let base = PREDEFINED
            .iter()
            .find(|(f, _)| *f == self)
            .map(|(_, b)| *b)
            .ok_or(Error::Invalid {
                field: "PDO number",
                value: match self {
                    Function::Tpdo { number } | Function::Rpdo { number } => u32::from(number),
                    _ => 0,
                },
                why: "the pre-defined connection set has PDOs 1 to 4",
            })?;
        if self.is_broadcast() {
            return match node {
                0 => Ok(base),
                n => Err(Error::Invalid {
                    field: "node id",
                    value: u32::from(n),
                    why: "a broadcast object has no node id",
                }),
            };
        }
        Ok(base + u16::from(check_node(node)?))
    }
}

/// `node` if it is a node id, 1..127.
pub fn check_node(node: u8) -> Result<u8, Error> {
    if (1..=MAX_NODE).contains(&node) {
        Ok(node)
    } else {
        Err(Error::Invalid {
            field: "node id",
            value: u32::from(node),
            why: "a node id is 1 to 127",
        })
    }
}

/// What a COB-ID of the pre-defined connection set carries: the object and its node (0 for a
/// broadcast object).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Cob {
    /// The object.
    pub function: Function,
    /// The node, 1..127 (0 for NMT, SYNC, TIME).
    pub node: u8,
}

impl Cob {
    /// Sorts an 11-bit identifier into the pre-defined connection set; `None` for an
    /// identifier no object of the set uses, or one above 7FFh.
    pub fn classify(cob_id: u16) -> Option<Cob> {
        if cob_id > crate::can::frame::MAX_ID {
            return None;
        }
        if let Some((function, _)) = PREDEFINED
            .iter()
            .find(|(f, b)| f.is_broadcast() && *b == cob_id)
        {
            return Some(Cob {
                function: *function,
                node: 0,
            });
        }
        let (base, node) = (cob_id & 0x780, (cob_id & 0x7F) as u8);
        let (function, _) = PREDEFINED
            .iter()
            .find(|(f, b)| !f.is_broadcast() && *b == base)?;
        (node != 0).then_some(Cob {
            function: *function,
            node,
        })
    }

    /// The COB-ID.
    pub fn cob_id(self) -> Result<u16, Error> {
        self.function.cob_id(self.node)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classify_every_object() {
        let cases = [
            (0x000, Function::Nmt, 0),
            (0x080, Function::Sync, 0),
            (0x100, Function::Time, 0),
            (0x081, Function::Emcy, 1),
            (0x0FF, Function::Emcy, 127),
            (0x185, Function::Tpdo { number: 1 }, 5),
            (0x205, Function::Rpdo { number: 1 }, 5),
            (0x285, Function::Tpdo { number: 2 }, 5),
            (0x305, Function::Rpdo { number: 2 }, 5),
            (0x385, Function::Tpdo { number: 3 }, 5),
            (0x405, Function::Rpdo { number: 3 }, 5),
            (0x485, Function::Tpdo { number: 4 }, 5),
            (0x505, Function::Rpdo { number: 4 }, 5),
            (0x585, Function::SdoTx, 5),
            (0x605, Function::SdoRx, 5),
            (0x705, Function::ErrorControl, 5),
            (0x77F, Function::ErrorControl, 127),
        ];
        for (id, function, node) in cases {
            let c = Cob::classify(id).unwrap();
            assert_eq!((c.function, c.node), (function, node), "{id:03X}h");
            assert_eq!(c.cob_id(), Ok(id));
        }
        // Ids no object of the set uses.
        for id in [
            0x001, 0x07F, 0x101, 0x17F, 0x180, 0x580, 0x680, 0x6FF, 0x700, 0x780, 0x7FF, 0x800,
        ] {
            assert_eq!(Cob::classify(id), None, "{id:03X}h");
        }
        // Every id classifies back to itself.
        for id in 0..0x800 {
            if let Some(c) = Cob::classify(id) {
                assert_eq!(c.cob_id(), Ok(id));
            }
        }
    }

    #[test]
    fn cob_ids_check_node_and_pdo_number() {
        assert_eq!(Function::SdoRx.cob_id(0x7F), Ok(0x67F));
        assert!(matches!(
            Function::SdoRx.cob_id(0),
            Err(Error::Invalid {
                field: "node id",
                ..
            })
        ));
        assert!(matches!(
            Function::Emcy.cob_id(128),
            Err(Error::Invalid {
                field: "node id",
                ..
            })
        ));
        assert!(matches!(
            Function::Sync.cob_id(1),
            Err(Error::Invalid {
                field: "node id",
                ..
            })
        ));
        assert_eq!(
            Function::Tpdo { number: 5 }.cob_id(1),
            Err(Error::Invalid {
                field: "PDO number",
                value: 5,
                why: "the pre-defined connection set has PDOs 1 to 4"
            })
        );
    }
}
