//! Why `harness serve BUS` cannot serve: the one error type at the bus boundary
//! (`crate::bus::Bus::serve`), whatever the bus. What only one bus can fail on (its raw link,
//! its CAN interface, a serving thread that panicked) is that bus's own typed error, carried as
//! [`ServeError::Bus`].

/// A serve command's failure (public: the buses' public serve errors carry it for `--system-bus`).
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The profile is unknown, stands for no NORD product, or its product lacks the bus.
    #[error("{0}")]
    Profile(String),
    /// An address given does not parse or does not suit the bus.
    #[error("{0}")]
    Address(String),
    /// A socket could not be opened, bound or listened on.
    #[error("cannot {what} {at}: {source}")]
    Socket {
        /// What was tried (`listen on TCP`, `bind UDP`).
        what: &'static str,
        /// Where.
        at: String,
        /// Why not.
        source: std::io::Error,
    },
    /// A serving thread could not be started.
    #[error("cannot start {what}: {source}")]
    Thread {
        /// The thread's job (`the TCP event loop`).
        what: &'static str,
        /// Why not.
        source: std::io::Error,
    },
    /// `--system-bus`: the socketcand server for the gateway's frames cannot run.
    #[error("--system-bus: {0}")]
    SystemBus(Box<ServeError>),
    /// The bus's own serving failed.
    #[error(transparent)]
    Bus(Box<dyn std::error::Error + Send + Sync>),
}

impl ServeError {
    /// [`ServeError::Socket`] of an I/O error, for `map_err`.
    pub(crate) fn socket(
        what: &'static str,
        at: impl std::fmt::Display,
    ) -> impl FnOnce(std::io::Error) -> ServeError {
        move |source| ServeError::Socket {
            what,
            at: at.to_string(),
            source,
        }
    }

    /// [`ServeError::Bus`] of a bus's own error, for `map_err`.
    pub(crate) fn bus(e: impl std::error::Error + Send + Sync + 'static) -> ServeError {
        ServeError::Bus(Box::new(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_socket_error_says_what_where_and_why() {
        let e = ServeError::socket("bind UDP", "127.0.0.2:2222")(std::io::Error::from(
            std::io::ErrorKind::AddrInUse,
        ));
        assert_eq!(
            e.to_string(),
            "cannot bind UDP 127.0.0.2:2222: address in use"
        );
        let relay = ServeError::SystemBus(Box::new(e));
        assert!(
            relay
                .to_string()
                .starts_with("--system-bus: cannot bind UDP"),
            "{relay}"
        );
    }
}
