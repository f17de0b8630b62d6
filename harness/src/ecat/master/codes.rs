//! The codes a slave refuses with in the mailbox. Stopgap until `proto::ecat::{mailbox, coe}`
//! land: then these become re-exports of their open newtypes.

use std::fmt;

/// An SDO abort code (ETG.1000.6 §5.6.2.7.2; BU 0620 §2.2.7.2).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct SdoAbortCode(pub(crate) u32);

impl fmt::Display for SdoAbortCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:08X}h", self.0)
    }
}

impl fmt::Debug for SdoAbortCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SdoAbortCode({:08X}h)", self.0)
    }
}

/// A mailbox error detail (ETG.1000.6 table 30).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct MailboxErrorCode(pub(crate) u16);

impl fmt::Display for MailboxErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X}h", self.0)
    }
}

impl fmt::Debug for MailboxErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MailboxErrorCode({:04X}h)", self.0)
    }
}
