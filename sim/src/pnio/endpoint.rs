//! The IO device as an [`Endpoint`]: Ethernet frames (DCP, RT, alarms) to
//! [`IoDevice::frame`], datagrams to the RPC port 34964 to [`IoDevice::call`], answered from
//! it, and the timers ([`IoDevice::poll`]) on a grid of [`POLL_PERIOD`], the send clock: a
//! late poll does not shift the next, and one more than a period late starts the grid anew.
//!
//! A call runs no timers: they run on their grid, so the input CR's frames keep their cycle
//! however many calls come between.

use std::time::Duration;

use proto::pnio::RPC_PORT;

use super::{IoDevice, Out, POLL_PERIOD};
use crate::endpoint::{Endpoint, Input, Output, Raised};

impl From<Out> for Output {
    fn from(out: Out) -> Output {
        match out {
            Out::Frame(f) => Output::Frame(f),
            Out::Datagram { to, bytes } => Output::Datagram {
                port: RPC_PORT,
                to,
                bytes,
            },
        }
    }
}

impl Endpoint for IoDevice {
    fn input(&mut self, input: Input<'_>, now: Duration) -> Vec<Output> {
        let out = match input {
            Input::Frame(frame) => self.frame(frame, now),
            Input::Datagram { port, from, bytes } if port == RPC_PORT => {
                self.call(from, bytes, now)
            }
            _ => Vec::new(),
        };
        out.into_iter().map(Output::from).collect()
    }

    fn poll(&mut self, now: Duration) -> Vec<Output> {
        if now < self.next_poll {
            return Vec::new();
        }
        let out = IoDevice::poll(self, now);
        self.next_poll = if now - self.next_poll > POLL_PERIOD {
            now + POLL_PERIOD
        } else {
            self.next_poll + POLL_PERIOD
        };
        out.into_iter().map(Output::from).collect()
    }

    fn next_deadline(&self) -> Option<Duration> {
        Some(self.next_poll)
    }

    /// A process alarm on the alarm CR ([`IoDevice::spurious_alarm`]), sent now unless an
    /// alarm before it awaits the controller's acknowledgement.
    fn raise_alarm(&mut self, now: Duration) -> Option<Raised> {
        let (slot, subslot) = self.spurious_alarm()?;
        let outputs: Vec<Output> = self.alarms_due(now).into_iter().map(Output::from).collect();
        let waits = if outputs.is_empty() {
            " (queued behind an alarm not yet acknowledged)"
        } else {
            ""
        };
        Some(Raised {
            what: format!("process alarm from slot {slot} subslot {subslot}{waits}"),
            outputs,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::{Device, DeviceConfig};
    use crate::pnio::IoConfig;
    use proto::nord::Product;

    #[test]
    fn the_timers_keep_their_grid() {
        let product = Product::Sk550p;
        let mut io = IoDevice::new(
            Device::new(DeviceConfig::new(product)),
            IoConfig::new(product),
        )
        .unwrap();
        let ms = Duration::from_millis;
        Endpoint::poll(&mut io, Duration::ZERO);
        assert_eq!(io.next_deadline(), Some(ms(1)));
        // Late by less than a period: the grid holds.
        Endpoint::poll(&mut io, ms(1) + ms(1) / 2);
        assert_eq!(io.next_deadline(), Some(ms(2)));
        // Early: nothing runs.
        assert!(Endpoint::poll(&mut io, ms(1) + ms(3) / 4).is_empty());
        assert_eq!(io.next_deadline(), Some(ms(2)));
        // Late by more than a period: a new grid from now.
        Endpoint::poll(&mut io, ms(5));
        assert_eq!(io.next_deadline(), Some(ms(6)));
    }
}
