//! A device session as the fuzzer's bytes: a list of steps (what reaches the device, and time
//! passing), in a framing simple enough that a seed can be written from a capture
//! ([`encode`]) and that any bytes decode ([`decode`] never fails: a record cut short keeps
//! the bytes left and is the last).
//!
//! A record is a tag byte, whose low 3 bits are the kind and high 5 bits its argument, then
//! for the kinds that carry bytes a 16-bit little-endian length and the bytes:
//!
//! | kind | step | argument |
//! |---|---|---|
//! | 0 | [`Step::Frame`]: an Ethernet frame, or on CAN a frame as 11-bit id (LE) + data | — |
//! | 1 | [`Step::Datagram`] to one of the device's UDP ports | port index |
//! | 2 | [`Step::Stream`]: bytes on a TCP connection | client |
//! | 3 | [`Step::Closed`]: the TCP client goes away | client |
//! | 4 | [`Step::Advance`]: time passes, 16-bit LE count of 100 µs | — |
//! | 5–6 | [`Step::Poll`]: the driver polls without time passing | — |
//! | 7 | [`Step::Alarm`]: the device raises a spurious alarm or emergency (`--misbehave alarm=`) | — |

use std::time::Duration;

/// One step of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step<'a> {
    /// A frame from the network: an Ethernet II frame, or a CAN frame.
    Frame(&'a [u8]),
    /// A UDP datagram to the device's port of this index (modulo the ports it has).
    Datagram(u8, &'a [u8]),
    /// Bytes from TCP client `.0`, cut into messages by the device's framing as a driver
    /// cuts them.
    Stream(u8, &'a [u8]),
    /// TCP client `.0` closed its connection.
    Closed(u8),
    /// Time passes by this much.
    Advance(Duration),
    /// The driver polls the device now.
    Poll,
    /// The device is asked to raise an alarm or emergency now
    /// (`sim::endpoint::Endpoint::raise_alarm`, what `harness serve --misbehave alarm=` does).
    Alarm,
}

/// The unit of [`Step::Advance`].
const TICK: Duration = Duration::from_micros(100);

/// The steps `data` encodes, up to its first cut record.
pub fn decode(mut data: &[u8]) -> Vec<Step<'_>> {
    let mut steps = Vec::new();
    while let Some((&tag, rest)) = data.split_first() {
        let (kind, arg) = (tag & 7, tag >> 3);
        let (step, rest) = match kind {
            0..=2 => {
                let Some((len, rest)) = split_u16(rest) else {
                    break;
                };
                let (bytes, rest) = rest.split_at(usize::from(len).min(rest.len()));
                let step = match kind {
                    0 => Step::Frame(bytes),
                    1 => Step::Datagram(arg, bytes),
                    _ => Step::Stream(arg, bytes),
                };
                (step, rest)
            }
            3 => (Step::Closed(arg), rest),
            4 => {
                let Some((ticks, rest)) = split_u16(rest) else {
                    break;
                };
                (Step::Advance(TICK * u32::from(ticks)), rest)
            }
            7 => (Step::Alarm, rest),
            _ => (Step::Poll, rest),
        };
        steps.push(step);
        data = rest;
    }
    steps
}

/// The bytes of `steps` (what [`decode`] reads back; an advance is rounded down to 100 µs and
/// cut at 6.5 s, bytes are cut at 65535).
pub fn encode(steps: &[Step<'_>]) -> Vec<u8> {
    let mut out = Vec::new();
    let bytes = |out: &mut Vec<u8>, tag: u8, b: &[u8]| {
        let b = &b[..b.len().min(usize::from(u16::MAX))];
        out.push(tag);
        out.extend((b.len() as u16).to_le_bytes());
        out.extend_from_slice(b);
    };
    for step in steps {
        match *step {
            Step::Frame(b) => bytes(&mut out, 0, b),
            Step::Datagram(port, b) => bytes(&mut out, 1 | port << 3, b),
            Step::Stream(client, b) => bytes(&mut out, 2 | client << 3, b),
            Step::Closed(client) => out.push(3 | client << 3),
            Step::Advance(d) => {
                let ticks = (d.as_micros() / TICK.as_micros()).min(u128::from(u16::MAX));
                out.push(4);
                out.extend((ticks as u16).to_le_bytes());
            }
            Step::Poll => out.push(5),
            Step::Alarm => out.push(7),
        }
    }
    out
}

fn split_u16(b: &[u8]) -> Option<(u16, &[u8])> {
    let (head, rest) = b.split_first_chunk::<2>()?;
    Some((u16::from_le_bytes(*head), rest))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_encode_and_decode_back() {
        let steps = [
            Step::Frame(&[1, 2, 3]),
            Step::Datagram(1, &[4]),
            Step::Stream(3, &[]),
            Step::Closed(3),
            Step::Advance(Duration::from_millis(250)),
            Step::Poll,
            Step::Alarm,
        ];
        assert_eq!(decode(&encode(&steps)), steps);
    }

    #[test]
    fn a_cut_record_ends_the_session_and_keeps_what_came_before() {
        // A frame of 3 bytes, then a frame that announces 9 and has 2, then a cut advance.
        let data = [0, 3, 0, 1, 2, 3, 0, 9, 0, 7, 7];
        assert_eq!(
            decode(&data),
            [Step::Frame(&[1, 2, 3]), Step::Frame(&[7, 7])]
        );
        assert_eq!(decode(&[4, 1]), []);
        assert_eq!(decode(&[0x2D]), [Step::Poll]);
        assert_eq!(decode(&[0x2F]), [Step::Alarm]);
    }
}
