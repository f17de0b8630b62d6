//! The ASCII protocol of socketcand (Linux-CAN project, `doc/protocol.md`; the behaviour of
//! its `src/state_*.c` where the document is silent), which carries CAN frames over one TCP
//! connection. Every message is `<`, space-separated words, `>`:
//!
//! | message | direction | meaning |
//! |---|---|---|
//! | `< hi >` | server | greeting after the TCP connect (mode NO_BUS) |
//! | `< open can0 >` | client | select a bus; the server answers `< ok >` or `< error … >` and closes |
//! | `< rawmode >`, `< bcmmode >` | client | switch mode; the server answers `< ok >` |
//! | `< echo >` | either | the server returns it unchanged |
//! | `< send 123 2 1 f1 >` | client | send a frame: identifier, decimal length, one hex word per byte |
//! | `< frame 123 23.424242 1A220344 >` | server | a frame received at seconds.microseconds |
//! | `< error … >` | server | a refusal (`< error unknown command >`) or an error frame |
//!
//! The server writes a base identifier as 3 upper-case hex digits and an extended one as 8
//! (`%03X`, `%08X`); in `send` it takes any hex case and width and calls an 8-digit identifier
//! extended. Raw mode writes the data as one word of upper-case hex pairs (no word at all for
//! a frame without data: `< frame 123 1.000000  >`); BCM mode writes one word per byte. The
//! document asks for lower-case, unpadded data bytes in `send` ("1 f1"). Remote frames appear
//! in neither direction: socketcand's raw mode drops received RTR frames and `send` cannot
//! set the RTR flag, so emitting one is [`Error::SocketcandRemote`]. An error frame is written
//! as `< error CLASS SECS.USECS >` in raw mode (class = `can_id` & `CAN_ERR_MASK`) and with
//! the whole `can_id` and the 8 data bytes in BCM mode; both parse to [`Message::ErrorFrame`],
//! which is emitted with the class alone (as raw mode writes it) and the data bytes, if any.
//!
//! Parsing takes words separated by any whitespace; emitting writes the spacing socketcand
//! writes. A message this codec does not know (`< stat … >`, `< subscribe … >`) is kept as
//! [`Message::Other`]; only bytes that are not a message, or a known message with malformed
//! words, are errors.

use super::frame::{check_id, check_len, CanFrame, MAX_LEN};
use super::socketcan::{ErrorClass, EFF_MASK};
use crate::wire::Error;

/// The longest message [`Message::parse`] waits for before calling the stream garbage
/// (socketcand's own buffer is about 8 KiB, for ISO-TP PDUs this codec does not carry).
pub const MAX_MESSAGE_LEN: usize = 512;

/// The words of a message [`Message::parse`] splits without allocating.
const WORDS: usize = 16;

/// A socketcand timestamp: seconds and microseconds (`%lld.%06lld`) of the host's clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Timestamp {
    /// Seconds.
    pub secs: u64,
    /// Microseconds, 0..=999999.
    pub usecs: u32,
}

/// One socketcand message.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Message {
    /// `< hi >`: the server's greeting.
    Hi,
    /// `< open CHANNEL >`: select the bus `channel` (e.g. `can0`).
    Open {
        /// The bus name, one word.
        channel: String,
    },
    /// `< ok >`.
    Ok,
    /// `< rawmode >`: switch to RAW mode (every frame on the bus is forwarded).
    RawMode,
    /// `< bcmmode >`: switch back to BCM mode.
    BcmMode,
    /// `< echo >`.
    Echo,
    /// `< error TEXT >`: the server refuses (`could not open bus`, `unknown command`).
    Error {
        /// The words after `error`, joined by single spaces.
        text: String,
    },
    /// `< error CLASS SECS.USECS [BYTES] >`: an error frame on the bus.
    ErrorFrame {
        /// The class bits (`CAN_ERR_FLAG` removed).
        class: ErrorClass,
        /// When it was received.
        time: Timestamp,
        /// The data bytes BCM mode adds (empty in raw mode).
        data: Vec<u8>,
    },
    /// `< frame ID SECS.USECS DATA >`: a frame received from the bus.
    Frame {
        /// The frame.
        frame: CanFrame,
        /// When it was received.
        time: Timestamp,
    },
    /// `< send ID LEN B0 B1 … >`: a frame to send.
    Send {
        /// The frame.
        frame: CanFrame,
    },
    /// Any other message, its words joined by single spaces.
    Other {
        /// The words between `<` and `>`.
        text: String,
    },
}

/// The result of reading a byte stream: a whole message, or the need for more bytes.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Framed {
    /// A message and the bytes it took, including the whitespace before it.
    Complete {
        /// The message.
        message: Message,
        /// Bytes consumed from the start of the buffer.
        consumed: usize,
    },
    /// The buffer holds (whitespace and) the start of a message only.
    Incomplete,
}

impl Message {
    /// Reads the first message of `buf`: whitespace, `<`, words, `>`. Bytes other than
    /// whitespace before the `<`, a second `<` before the `>`, non-ASCII bytes, or no `>`
    /// within [`MAX_MESSAGE_LEN`] bytes are errors.
    pub fn parse(buf: &[u8]) -> Result<Framed, Error> {
        let start = buf
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(buf.len());
        let rest = &buf[start..];
        let Some(&first) = rest.first() else {
            return Ok(Framed::Incomplete);
        };
        if first != b'<' {
            return Err(Error::syntax(
                "message",
                &String::from_utf8_lossy(rest),
                "does not start with '<'",
            ));
        }
        let Some(end) = rest.iter().position(|&b| b == b'>') else {
            return if rest.len() > MAX_MESSAGE_LEN {
                Err(Error::SocketcandUnterminated {
                    max: MAX_MESSAGE_LEN,
                })
            } else {
                Ok(Framed::Incomplete)
            };
        };
        if end > MAX_MESSAGE_LEN {
            return Err(Error::SocketcandUnterminated {
                max: MAX_MESSAGE_LEN,
            });
        }
        let inner = &rest[1..end];
        let text = std::str::from_utf8(inner)
            .ok()
            .filter(|t| t.is_ascii() && !t.contains('<'))
            .ok_or_else(|| {
                Error::syntax(
                    "message",
                    &String::from_utf8_lossy(inner),
                    "holds a non-ASCII byte or a second '<'",
                )
            })?;
        // The words on the stack: a frame or a send has at most 11 (a BCM frame 11 too); a
        // longer message (some `Other`) takes a vector.
        let mut words = [""; WORDS];
        let mut n = 0;
        let mut split = text.split_ascii_whitespace();
        for (slot, word) in words.iter_mut().zip(split.by_ref()) {
            *slot = word;
            n += 1;
        }
        let message = match split.next() {
            None => Message::from_words(&words[..n])?,
            Some(more) => {
                let mut all = words.to_vec();
                all.push(more);
                all.extend(split);
                Message::from_words(&all)?
            }
        };
        Ok(Framed::Complete {
            message,
            consumed: start + end + 1,
        })
    }

    fn from_words(words: &[&str]) -> Result<Message, Error> {
        let none = |m: Message| {
            if words.len() == 1 {
                Ok(m)
            } else {
                Err(Error::syntax("message", &words.join(" "), "takes no words"))
            }
        };
        match words {
            [] => Err(Error::syntax("message", "", "is empty")),
            ["hi", ..] => none(Message::Hi),
            ["ok", ..] => none(Message::Ok),
            ["rawmode", ..] => none(Message::RawMode),
            ["bcmmode", ..] => none(Message::BcmMode),
            ["echo", ..] => none(Message::Echo),
            ["open", channel] => Ok(Message::Open {
                channel: (*channel).to_owned(),
            }),
            ["open", ..] => Err(Error::syntax(
                "open",
                &words.join(" "),
                "takes one bus name",
            )),
            ["error", rest @ ..] => Ok(error_frame(rest)?.unwrap_or_else(|| Message::Error {
                text: rest.join(" "),
            })),
            ["frame", id, time, data @ ..] => Ok(Message::Frame {
                frame: {
                    let (bytes, len) = hex_data(data)?;
                    CanFrame::new(identifier(id)?, &bytes[..len])?
                },
                time: timestamp(time)?,
            }),
            ["frame", ..] => Err(Error::syntax(
                "frame",
                &words.join(" "),
                "needs an identifier and a timestamp",
            )),
            ["send", id, len, bytes @ ..] => Ok(Message::Send {
                frame: send_frame(id, len, bytes)?,
            }),
            ["send", ..] => Err(Error::syntax(
                "send",
                &words.join(" "),
                "needs an identifier and a length",
            )),
            _ => Ok(Message::Other {
                text: words.join(" "),
            }),
        }
    }

    /// The message as socketcand writes it. A remote frame is [`Error::SocketcandRemote`]; a
    /// bus name or text that is empty where a word is needed, or holds whitespace, `<` or `>`,
    /// is [`Error::SocketcandSyntax`]; error-frame data longer than 8 bytes is
    /// [`Error::CanDataLength`].
    pub fn emit(&self) -> Result<String, Error> {
        let text = match self {
            Message::Hi => "< hi >".to_owned(),
            Message::Ok => "< ok >".to_owned(),
            Message::RawMode => "< rawmode >".to_owned(),
            Message::BcmMode => "< bcmmode >".to_owned(),
            Message::Echo => "< echo >".to_owned(),
            Message::Open { channel } => {
                if channel.is_empty() || channel.contains(|c: char| c.is_whitespace()) {
                    return Err(Error::syntax("open", channel, "is not one word"));
                }
                format!("< open {} >", plain("open", channel)?)
            }
            Message::Error { text } => format!("< error {} >", plain("error", text)?),
            Message::ErrorFrame { class, time, data } => {
                check_len(data.len())?;
                let mut s = format!(
                    "< error {:03X} {}.{:06} ",
                    class.0 & EFF_MASK,
                    time.secs,
                    time.usecs
                );
                data.iter().for_each(|b| s.push_str(&format!("{b:02X} ")));
                if data.is_empty() {
                    s.push('>');
                } else {
                    s.push_str(" >");
                }
                s
            }
            Message::Frame { .. } | Message::Send { .. } => {
                let mut s = String::with_capacity(48);
                self.emit_into(&mut s)?;
                s
            }
            Message::Other { text } => format!("< {} >", plain("message", text)?),
        };
        // A reader takes a message whose `>` comes within MAX_MESSAGE_LEN bytes of its `<`
        // ([`Message::parse`]); words read from a longer run of whitespace than the one space
        // written between them can come back too long to be read.
        if text.len() > MAX_MESSAGE_LEN + 1 {
            return Err(Error::syntax(
                "message",
                text.get(..32).unwrap_or(&text),
                "is longer than the 512 bytes a socketcand reader takes",
            ));
        }
        Ok(text)
    }

    /// [`Message::emit`] appended to `out`: the same text, written without allocating for a
    /// frame and a send (what a server and a client write for every frame); `out` is left as
    /// it was when the message cannot be written.
    pub fn emit_into(&self, out: &mut String) -> Result<(), Error> {
        match self {
            Message::Frame { frame, time } => {
                no_remote(frame)?;
                out.push_str("< frame ");
                push_id(out, frame.id());
                out.push(' ');
                push_decimal(out, time.secs, 1);
                out.push('.');
                push_decimal(out, time.usecs.into(), 6);
                out.push(' ');
                for b in frame.data() {
                    out.push(char::from(HEX_UPPER[usize::from(b >> 4)]));
                    out.push(char::from(HEX_UPPER[usize::from(b & 0x0F)]));
                }
                out.push_str(" >");
            }
            Message::Send { frame } => {
                no_remote(frame)?;
                out.push_str("< send ");
                push_id(out, frame.id());
                out.push(' ');
                push_decimal(out, frame.dlc().into(), 1);
                for b in frame.data() {
                    out.push(' ');
                    if *b > 0x0F {
                        out.push(char::from(HEX_LOWER[usize::from(b >> 4)]));
                    }
                    out.push(char::from(HEX_LOWER[usize::from(b & 0x0F)]));
                }
                out.push_str(" >");
            }
            other => out.push_str(&other.emit()?),
        }
        Ok(())
    }
}

const HEX_UPPER: &[u8; 16] = b"0123456789ABCDEF";
const HEX_LOWER: &[u8; 16] = b"0123456789abcdef";

/// An identifier as `%03X`: upper-case hex, at least 3 digits.
fn push_id(out: &mut String, id: u16) {
    let digits = (1..=4)
        .rev()
        .find(|&n| id >> (4 * (n - 1)) != 0)
        .unwrap_or(1)
        .max(3);
    for n in (0..digits).rev() {
        out.push(char::from(HEX_UPPER[usize::from((id >> (4 * n)) & 0x0F)]));
    }
}

/// `value` in decimal, zero-padded to `width` digits at least.
fn push_decimal(out: &mut String, mut value: u64, width: usize) {
    let mut digits = [b'0'; 20];
    let mut n = 0;
    while value > 0 || n < width.max(1) {
        digits[n] = b'0' + (value % 10) as u8;
        value /= 10;
        n += 1;
    }
    for d in digits[..n].iter().rev() {
        out.push(char::from(*d));
    }
}

/// `text` if it can stand between `<` and `>`.
fn plain<'a>(field: &'static str, text: &'a str) -> Result<&'a str, Error> {
    if text.trim().is_empty() || !text.is_ascii() || text.contains(['<', '>']) {
        return Err(Error::syntax(field, text, "cannot stand inside '< … >'"));
    }
    Ok(text)
}

fn no_remote(frame: &CanFrame) -> Result<(), Error> {
    if frame.is_remote() {
        Err(Error::SocketcandRemote)
    } else {
        Ok(())
    }
}

/// `< error CLASS SECS.USECS [BYTES] >`, or `None` when the words are a refusal's text.
fn error_frame(words: &[&str]) -> Result<Option<Message>, Error> {
    let [class, time, data @ ..] = words else {
        return Ok(None);
    };
    let (Some(class), Ok(time)) = (hex_u32(class), timestamp(time)) else {
        return Ok(None);
    };
    let (bytes, len) = hex_data(data)?;
    check_len(len)?;
    Ok(Some(Message::ErrorFrame {
        class: ErrorClass(class & EFF_MASK),
        time,
        data: bytes[..len].to_vec(),
    }))
}

/// A hex word of 1..8 digits.
fn hex_u32(word: &str) -> Option<u32> {
    if (1..=8).contains(&word.len()) && word.bytes().all(|b| b.is_ascii_hexdigit()) {
        u32::from_str_radix(word, 16).ok()
    } else {
        None
    }
}

/// An identifier word: 8 digits is an extended frame (socketcand's rule), fewer a base one.
fn identifier(word: &str) -> Result<u16, Error> {
    let id = hex_u32(word)
        .ok_or_else(|| Error::syntax("identifier", word, "is not 1 to 8 hex digits"))?;
    if word.len() == 8 {
        return Err(Error::CanExtended { id: id & EFF_MASK });
    }
    check_id(id)
}

/// `SECS.USECS` with exactly 6 digits of microseconds.
fn timestamp(word: &str) -> Result<Timestamp, Error> {
    let bad = || Error::syntax("timestamp", word, "is not SECS.USECS (6 digits of µs)");
    let (s, us) = word.split_once('.').ok_or_else(bad)?;
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    if !digits(s) || !digits(us) || us.len() != 6 {
        return Err(bad());
    }
    Ok(Timestamp {
        secs: s.parse().map_err(|_| bad())?,
        usecs: us.parse().map_err(|_| bad())?,
    })
}

/// Data words: pairs of hex digits, in one word (raw mode) or several (BCM mode), a pair
/// possibly across two words; the bytes and how many.
fn hex_data(words: &[&str]) -> Result<([u8; MAX_LEN], usize), Error> {
    let digits: usize = words.iter().map(|w| w.len()).sum();
    let bad = || Error::syntax("data", &words.concat(), "is not pairs of hex digits");
    let mut all = words.iter().flat_map(|w| w.bytes());
    if digits & 1 != 0 || !all.clone().all(|b| b.is_ascii_hexdigit()) {
        return Err(bad());
    }
    if digits > 2 * MAX_LEN {
        return Err(Error::CanDataLength { len: digits / 2 });
    }
    let mut bytes = [0u8; MAX_LEN];
    for byte in bytes.iter_mut().take(digits / 2) {
        let (Some(hi), Some(lo)) = (all.next(), all.next()) else {
            return Err(bad());
        };
        *byte = (hex_digit(hi) << 4) | hex_digit(lo);
    }
    Ok((bytes, digits / 2))
}

/// The value of a hex digit (checked before).
fn hex_digit(b: u8) -> u8 {
    match b {
        b'0'..=b'9' => b - b'0',
        b'a'..=b'f' => b - b'a' + 10,
        b'A'..=b'F' => b - b'A' + 10,
        _ => 0,
    }
}

/// `send ID LEN B0 …`: a decimal length 0..8 and exactly that many 1- or 2-digit hex words.
fn send_frame(id: &str, len: &str, bytes: &[&str]) -> Result<CanFrame, Error> {
    let id = identifier(id)?;
    if len.is_empty() || len.len() > 2 || !len.bytes().all(|b| b.is_ascii_digit()) {
        return Err(Error::syntax("send length", len, "is not a decimal number"));
    }
    let n: usize = len
        .parse()
        .map_err(|_| Error::syntax("send length", len, "is not a decimal number"))?;
    check_len(n)?;
    if bytes.len() != n {
        return Err(Error::syntax(
            "send data",
            &bytes.join(" "),
            "does not have as many bytes as the length says",
        ));
    }
    let mut data = [0u8; MAX_LEN];
    for (byte, w) in data.iter_mut().zip(bytes) {
        if !(1..=2).contains(&w.len()) || !w.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(Error::syntax("send data", w, "is not a hex byte"));
        }
        *byte = w.bytes().fold(0, |v, b| (v << 4) | hex_digit(b));
    }
    CanFrame::new(id, &data[..n])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(s: &str) -> Message {
        match Message::parse(s.as_bytes()).unwrap() {
            Framed::Complete { message, consumed } => {
                assert_eq!(consumed, s.len(), "{s}");
                message
            }
            Framed::Incomplete => panic!("{s}: incomplete"),
        }
    }

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(id, data).unwrap()
    }

    #[test]
    fn session_messages() {
        // doc/protocol.md "Mode NO_BUS", "Mode RAW", "Echo command".
        for (text, m) in [
            ("< hi >", Message::Hi),
            ("< ok >", Message::Ok),
            ("< rawmode >", Message::RawMode),
            ("< bcmmode >", Message::BcmMode),
            ("< echo >", Message::Echo),
            (
                "< open can0 >",
                Message::Open {
                    channel: "can0".into(),
                },
            ),
            (
                "< error could not open bus >",
                Message::Error {
                    text: "could not open bus".into(),
                },
            ),
            (
                "< subscribe 0 0 123 >",
                Message::Other {
                    text: "subscribe 0 0 123".into(),
                },
            ),
        ] {
            assert_eq!(one(text), m, "{text}");
            assert_eq!(m.emit().unwrap(), text);
        }
        // Any whitespace between the words.
        assert_eq!(one("<open\tcan0>"), one("< open can0 >"));
    }

    #[test]
    fn raw_mode_frames() {
        // The document's example: 123h, 4 bytes, received at 23.424242 s.
        let m = Message::Frame {
            frame: frame(0x123, &[0x1A, 0x22, 0x03, 0x44]),
            time: Timestamp {
                secs: 23,
                usecs: 424_242,
            },
        };
        assert_eq!(one("< frame 123 23.424242 1A220344 >"), m);
        assert_eq!(m.emit().unwrap(), "< frame 123 23.424242 1A220344 >");
        // No data: socketcand writes nothing between the two spaces.
        let m = Message::Frame {
            frame: frame(0x080, &[]),
            time: Timestamp { secs: 5, usecs: 7 },
        };
        assert_eq!(m.emit().unwrap(), "< frame 080 5.000007  >");
        assert_eq!(one("< frame 080 5.000007  >"), m);
        // BCM mode writes a word per byte; lower case is read too.
        assert_eq!(
            one("< frame 705 1.000000 7f  >"),
            Message::Frame {
                frame: frame(0x705, &[0x7F]),
                time: Timestamp { secs: 1, usecs: 0 }
            }
        );
    }

    #[test]
    fn send() {
        // The document's example "< send 123 0 >", and an SDO upload request to node 5.
        let m = Message::Send {
            frame: frame(0x123, &[]),
        };
        assert_eq!(one("< send 123 0 >"), m);
        assert_eq!(m.emit().unwrap(), "< send 123 0 >");
        let m = Message::Send {
            frame: frame(0x605, &[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0xF1]),
        };
        assert_eq!(m.emit().unwrap(), "< send 605 8 40 0 10 0 0 0 0 f1 >");
        assert_eq!(one("< send 605 8 40 0 10 0 0 0 0 f1 >"), m);
        // Any width and case of the identifier below 8 digits (sscanf %x).
        assert_eq!(
            one("< send 07ff 1 AA >"),
            Message::Send {
                frame: frame(0x7FF, &[0xAA])
            }
        );
        // The document's extended example: 8 digits.
        assert_eq!(
            Message::parse(b"< send 1AAAAAAA 2 1 f1 >"),
            Err(Error::CanExtended { id: 0x1AAA_AAAA })
        );
        assert_eq!(
            Message::parse(b"< send 00000123 0 >"),
            Err(Error::CanExtended { id: 0x123 })
        );
        assert_eq!(
            Message::parse(b"< send 800 0 >"),
            Err(Error::CanIdentifier { id: 0x800 })
        );
        assert_eq!(
            Message::parse(b"< send 123 9 1 2 3 4 5 6 7 8 9 >"),
            Err(Error::CanDataLength { len: 9 })
        );
        for bad in [
            "< send 123 2 1 >",
            "< send 123 1 1 2 >",
            "< send 123 1 100 >",
            "< send 123 x >",
            "< send 12g 0 >",
            "< send 123 >",
        ] {
            assert!(
                matches!(
                    Message::parse(bad.as_bytes()),
                    Err(Error::SocketcandSyntax { .. })
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn remote_frames_cannot_be_carried() {
        let r = CanFrame::remote(0x705, 1).unwrap();
        assert_eq!(
            Message::Send { frame: r }.emit(),
            Err(Error::SocketcandRemote)
        );
        assert_eq!(
            Message::Frame {
                frame: r,
                time: Timestamp::default()
            }
            .emit(),
            Err(Error::SocketcandRemote)
        );
    }

    #[test]
    fn error_frames() {
        // Raw mode: class only (bus off).
        let m = Message::ErrorFrame {
            class: ErrorClass::BUSOFF,
            time: Timestamp {
                secs: 12,
                usecs: 500_000,
            },
            data: vec![],
        };
        assert_eq!(one("< error 040 12.500000 >"), m);
        assert_eq!(m.emit().unwrap(), "< error 040 12.500000 >");
        // BCM mode: the whole can_id (CAN_ERR_FLAG set) and the 8 data bytes.
        let m = Message::ErrorFrame {
            class: ErrorClass::CRTL,
            time: Timestamp { secs: 1, usecs: 2 },
            data: vec![0, 0x20, 0, 0, 0, 0, 0, 0],
        };
        assert_eq!(
            one("< error 20000004 1.000002 00 20 00 00 00 00 00 00  >"),
            m
        );
        assert_eq!(
            m.emit().unwrap(),
            "< error 004 1.000002 00 20 00 00 00 00 00 00  >"
        );
        // Raw mode: a bus error (CAN_ERR_PROT | CAN_ERR_BUSERROR), as a listener reports
        // another node's destroyed frame; the details stay behind in raw mode.
        let bus = ErrorClass(ErrorClass::PROT.0 | ErrorClass::BUSERROR.0);
        let m = one("< error 088 3.000250 >");
        assert_eq!(
            m,
            Message::ErrorFrame {
                class: bus,
                time: Timestamp {
                    secs: 3,
                    usecs: 250
                },
                data: vec![],
            }
        );
        assert_eq!(m.emit().unwrap(), "< error 088 3.000250 >");
        // A refusal whose first word happens to be hex is still text.
        assert_eq!(
            one("< error add failed >"),
            Message::Error {
                text: "add failed".into()
            }
        );
    }

    #[test]
    fn frames_and_sends_are_written_as_format_writes_them() {
        // What `emit` wrote with `format!` before it wrote by hand.
        let by_format = |m: &Message| match m {
            Message::Frame { frame, time } => {
                let data: String = frame.data().iter().map(|b| format!("{b:02X}")).collect();
                format!(
                    "< frame {:03X} {}.{:06} {data} >",
                    frame.id(),
                    time.secs,
                    time.usecs
                )
            }
            Message::Send { frame } => {
                let mut s = format!("< send {:03X} {}", frame.id(), frame.dlc());
                frame
                    .data()
                    .iter()
                    .for_each(|b| s.push_str(&format!(" {b:x}")));
                s + " >"
            }
            _ => unreachable!(),
        };
        let data = [0x00, 0x0F, 0x10, 0xF1, 0xAB, 0x7F, 0x80, 0xFF];
        for id in [0, 1, 0xF, 0x10, 0xFF, 0x100, 0x5A4, 0x7FF] {
            for len in 0..=MAX_LEN {
                let frame = CanFrame::new(id, &data[..len]).unwrap();
                for (secs, usecs) in [
                    (0, 0),
                    (7, 5),
                    (23, 424_242),
                    (u64::MAX, 999_999),
                    (1, 1_234_567),
                ] {
                    let m = Message::Frame {
                        frame,
                        time: Timestamp { secs, usecs },
                    };
                    assert_eq!(m.emit().unwrap(), by_format(&m));
                }
                let m = Message::Send { frame };
                assert_eq!(m.emit().unwrap(), by_format(&m));
                assert_eq!(one(&m.emit().unwrap()), m);
                // Appended to what is there.
                let mut out = String::from("x");
                m.emit_into(&mut out).unwrap();
                assert_eq!(out, format!("x{}", by_format(&m)));
            }
        }
        // A remote frame leaves `out` as it was.
        let mut out = String::from("x");
        let r = CanFrame::remote(0x705, 1).unwrap();
        assert!(Message::Send { frame: r }.emit_into(&mut out).is_err());
        assert_eq!(out, "x");
    }

    /// Found by the `can` fuzz target (fuzz/regressions/can/): words read across tabs and
    /// vertical tabs (no whitespace to `split_ascii_whitespace`, so part of a word) came back
    /// from `emit` with one space each side of them, two bytes past what a reader takes.
    #[test]
    fn a_message_read_near_the_limit_is_not_written_past_it() {
        let mut read = b"<".to_vec();
        read.push(b'\t');
        read.resize(MAX_MESSAGE_LEN, b'w');
        read.push(b'>');
        let Ok(Framed::Complete { message, .. }) = Message::parse(&read) else {
            panic!("a message whose `>` is at the limit is read");
        };
        let err = message.emit().unwrap_err().to_string();
        assert!(err.contains("longer than the 512 bytes"), "{err}");
        // One byte fewer, and what is written is read back the same.
        let mut short = read[..read.len() - 3].to_vec();
        short.push(b'>');
        let Ok(Framed::Complete { message, .. }) = Message::parse(&short) else {
            panic!("read");
        };
        let text = message.emit().unwrap();
        assert_eq!(
            Message::parse(text.as_bytes()),
            Ok(Framed::Complete {
                message,
                consumed: text.len()
            })
        );
    }

    #[test]
    fn long_messages_and_data_across_words() {
        // More words than are split on the stack.
        let words: Vec<String> = (0..40).map(|n| format!("w{n}")).collect();
        let text = format!("< stat {} >", words.join(" "));
        assert_eq!(
            one(&text),
            Message::Other {
                text: format!("stat {}", words.join(" "))
            }
        );
        // Pairs of digits across words, as the words are joined before pairing.
        assert_eq!(
            one("< frame 123 1.000000 1 23 4 >"),
            Message::Frame {
                frame: frame(0x123, &[0x12, 0x34]),
                time: Timestamp { secs: 1, usecs: 0 }
            }
        );
        assert!(Message::parse(b"< frame 123 1.000000 1 23 >").is_err());
    }

    #[test]
    fn stream_framing() {
        let stream = b" < hi >< ok >\r\n< frame 181 0.000001 0102 >";
        let mut at = 0;
        let mut got = vec![];
        while let Framed::Complete { message, consumed } = Message::parse(&stream[at..]).unwrap() {
            got.push(message);
            at += consumed;
        }
        assert_eq!(at, stream.len());
        assert_eq!(got.len(), 3);
        assert_eq!(got[1], Message::Ok);
        // Every split point of a message: incomplete until the '>'.
        let m = b"< send 605 8 40 0 10 0 0 0 0 0 >";
        for n in 0..m.len() {
            assert_eq!(Message::parse(&m[..n]), Ok(Framed::Incomplete), "{n}");
        }
        assert_eq!(Message::parse(b"   \n"), Ok(Framed::Incomplete));
    }

    #[test]
    fn garbage_is_an_error() {
        for bad in [
            &b"hi >"[..],
            b"< hi < ok >",
            b"< \xFF >",
            b"< >",
            b"< hi there >",
            b"< open >",
            b"< open a b >",
            b"< frame 123 >",
            b"< frame 123 1.5 01 >",
            b"< frame 123 1.000000 012 >",
            b"< frame 123 1.000000 010203040506070809 >",
            b"< frame 123 -1.000000 >",
            b"< frame 1AAAAAAA 1.000000 >",
        ] {
            assert!(
                Message::parse(bad).is_err(),
                "{:?}",
                String::from_utf8_lossy(bad)
            );
        }
        let mut long = b"< ".to_vec();
        long.resize(MAX_MESSAGE_LEN + 2, b'a');
        assert_eq!(
            Message::parse(&long),
            Err(Error::SocketcandUnterminated {
                max: MAX_MESSAGE_LEN
            })
        );
        assert_eq!(
            Message::parse(b"x"),
            Err(Error::SocketcandSyntax {
                field: "message",
                token: "x".into(),
                why: "does not start with '<'"
            })
        );
        // Text that cannot be emitted.
        for m in [
            Message::Open {
                channel: "can 0".into(),
            },
            Message::Open { channel: "".into() },
            Message::Error { text: "a>b".into() },
            Message::Other { text: " ".into() },
        ] {
            assert!(
                matches!(m.emit(), Err(Error::SocketcandSyntax { .. })),
                "{m:?}"
            );
        }
    }

    mod properties {
        use super::*;
        use crate::can::frame::MAX_ID;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Data frames: socketcand carries no remote frame.
        fn can_frame() -> impl Strategy<Value = CanFrame> {
            (0..=MAX_ID, vec(any::<u8>(), 0..=MAX_LEN))
                .prop_map(|(id, data)| CanFrame::new(id, &data).unwrap())
        }

        fn timestamp() -> impl Strategy<Value = Timestamp> {
            (any::<u64>(), 0u32..=999_999).prop_map(|(secs, usecs)| Timestamp { secs, usecs })
        }

        /// Every message but `Other`: the fixed ones, a one-word bus name, a refusal whose
        /// words cannot read as an error frame (no hex digit), error frames, frames and sends.
        fn message() -> impl Strategy<Value = Message> {
            prop_oneof![
                Just(Message::Hi),
                Just(Message::Ok),
                Just(Message::RawMode),
                Just(Message::BcmMode),
                Just(Message::Echo),
                "[a-z][a-z0-9_.-]{0,12}".prop_map(|channel| Message::Open { channel }),
                vec("[g-z]{1,8}", 1..4).prop_map(|w| Message::Error { text: w.join(" ") }),
                (0..=EFF_MASK, timestamp(), vec(any::<u8>(), 0..=MAX_LEN)).prop_map(
                    |(class, time, data)| Message::ErrorFrame {
                        class: ErrorClass(class),
                        time,
                        data
                    }
                ),
                (can_frame(), timestamp()).prop_map(|(frame, time)| Message::Frame { frame, time }),
                can_frame().prop_map(|frame| Message::Send { frame }),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(m in message(), lead in "[ \\t\\n]{0,3}") {
                let s = format!("{lead}{}", m.emit().unwrap());
                prop_assert_eq!(
                    Message::parse(s.as_bytes()),
                    Ok(Framed::Complete { message: m, consumed: s.len() })
                );
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..64)) {
                let _ = Message::parse(&bytes);
            }

            #[test]
            fn parsing_arbitrary_words_never_panics(words in vec("[a-z0-9.]{0,10}", 0..12)) {
                let s = format!("< {} >", words.join(" "));
                let _ = Message::parse(s.as_bytes());
            }
        }
    }
}
