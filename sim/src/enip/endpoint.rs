//! The adapter as an [`Endpoint`]: TCP clients' encapsulation messages to
//! [`Adapter::handle_tcp`] (a reply, and the connection closed when the adapter says so), UDP
//! datagrams to its encapsulation port (44818 unless it was given another) to
//! [`Adapter::handle_udp`], answered from that port, class-1 datagrams to UDP 2222 to
//! [`Adapter::handle_io`], and the T→O frames from 2222 when [`Adapter::poll`] makes them.

use std::time::Duration;

use proto::enip::io::IO_PORT;

use super::Adapter;
use crate::endpoint::{Endpoint, Input, Output};

impl Endpoint for Adapter {
    fn input(&mut self, input: Input<'_>, now: Duration) -> Vec<Output> {
        match input {
            Input::Message {
                client,
                peer,
                bytes,
            } => {
                let r = self.handle_tcp(client, peer, bytes, now);
                let reply = r.reply.map(|bytes| Output::Message { client, bytes });
                let close = r.close.then_some(Output::Close(client));
                reply.into_iter().chain(close).collect()
            }
            Input::Closed(client) => {
                self.client_closed(client);
                Vec::new()
            }
            Input::Datagram { port, from, bytes } if port == self.address.port() => self
                .handle_udp(bytes)
                .map(|bytes| Output::Datagram {
                    port,
                    to: from,
                    bytes,
                })
                .into_iter()
                .collect(),
            Input::Datagram { port, from, bytes } if port == IO_PORT => {
                // A datagram that is no class-1 frame of an open connection is counted in
                // `dropped`: nothing to answer.
                let _ = self.handle_io(from, bytes, now);
                Vec::new()
            }
            _ => Vec::new(),
        }
    }

    fn poll(&mut self, now: Duration) -> Vec<Output> {
        Adapter::poll(self, now)
            .into_iter()
            .map(|(to, bytes)| Output::Datagram {
                port: IO_PORT,
                to,
                bytes,
            })
            .collect()
    }

    fn next_deadline(&self) -> Option<Duration> {
        self.next_due()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::{Device, DeviceConfig};
    use proto::enip::encap::{Command, EncapRepr};
    use proto::nord::Product;
    use std::net::SocketAddr;

    fn adapter() -> Adapter {
        let device = Device::new(DeviceConfig::new(Product::Sk550p));
        Adapter::new(device, "127.0.0.2:44818".parse().unwrap())
    }

    /// An encapsulation message of `command` without data (ODVA CIP vol. 2 §2-3).
    fn message(command: Command) -> Vec<u8> {
        EncapRepr {
            command: command.0,
            session: 0,
            status: 0,
            context: [7; 8],
            options: 0,
            data: Vec::new(),
        }
        .emit()
        .unwrap()
    }

    #[test]
    fn list_identity_is_answered_over_tcp_and_udp_from_where_it_came() {
        let peer: SocketAddr = "127.0.0.1:50000".parse().unwrap();
        let m = message(Command::LIST_IDENTITY);
        let direct = adapter()
            .handle_tcp(3, peer, &m, Duration::ZERO)
            .reply
            .unwrap();
        let tcp = Input::Message {
            client: 3,
            peer,
            bytes: &m,
        };
        assert_eq!(
            adapter().input(tcp, Duration::ZERO),
            vec![Output::Message {
                client: 3,
                bytes: direct.clone()
            }]
        );
        let udp = Input::Datagram {
            port: 44818,
            from: peer,
            bytes: &m,
        };
        assert_eq!(
            adapter().input(udp, Duration::ZERO),
            vec![Output::Datagram {
                port: 44818,
                to: peer,
                bytes: direct
            }]
        );
    }

    #[test]
    fn a_message_that_ends_the_connection_closes_it() {
        let peer: SocketAddr = "127.0.0.1:50000".parse().unwrap();
        let mut a = adapter();
        let input = Input::Message {
            client: 3,
            peer,
            bytes: &[0xFF; 30],
        };
        assert_eq!(a.input(input, Duration::ZERO), vec![Output::Close(3)]);
    }
}
