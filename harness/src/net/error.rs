//! What can go wrong on a raw Ethernet link.

use std::io;

/// A raw Ethernet link could not be opened or used.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// No interface of that name (the known names are listed to help the user).
    #[error("no network interface named `{name}` (there are: {})", known.join(", "))]
    NoSuchInterface {
        /// The name asked for.
        name: String,
        /// The interfaces the system has.
        known: Vec<String>,
    },
    /// The system refused a packet socket: raw Ethernet needs root or the `CAP_NET_RAW`
    /// capability.
    #[error("raw Ethernet on `{iface}` needs root or CAP_NET_RAW (e.g. `sudo setcap cap_net_raw+ep` on the binary): {source}")]
    NeedsRoot {
        /// The interface.
        iface: String,
        /// What the system said (EPERM or EACCES).
        source: io::Error,
    },
    /// The interface has no Ethernet address (a tunnel, say): it cannot carry Ethernet frames.
    #[error("network interface `{iface}` has no Ethernet (MAC) address")]
    NoMac {
        /// The interface.
        iface: String,
    },
    /// A frame to send is shorter than an Ethernet header (destination, source, EtherType).
    #[error("a frame of {len} bytes has no room for the 14-byte Ethernet header")]
    FrameTooShort {
        /// Its length.
        len: usize,
    },
    /// A system call on the link failed.
    #[error("{op} on `{iface}`: {source}")]
    Io {
        /// What was being done: "open", "send", "receive"…
        op: &'static str,
        /// The interface.
        iface: String,
        /// What the system said.
        source: io::Error,
    },
}

impl LinkError {
    /// An I/O error of `op` on `iface`; a permission error is [`LinkError::NeedsRoot`].
    pub(crate) fn io(op: &'static str, iface: &str, source: io::Error) -> LinkError {
        let iface = iface.to_string();
        match source.kind() {
            io::ErrorKind::PermissionDenied => LinkError::NeedsRoot { iface, source },
            _ => LinkError::Io { op, iface, source },
        }
    }

    /// Whether the interface went down while it still exists (ENETDOWN): a served device
    /// waits for it to come up again rather than ending.
    pub(crate) fn is_link_down(&self) -> bool {
        match self {
            LinkError::Io { source, iface, .. } => {
                source.raw_os_error() == Some(nix::errno::Errno::ENETDOWN as i32)
                    && super::interface(iface).is_ok()
            }
            _ => false,
        }
    }
}

/// Whether a read with a time-out set ended for the time-out (Linux says `WouldBlock`, other
/// systems `TimedOut`): no data, not a broken link.
pub(crate) fn timed_out(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
    )
}
