//! The harness's end of a CAN segment: frames out, frames in within a limit.
//!
//! Two links carry the same `proto::can` frames: the simulated segment in-process, on a
//! virtual clock ([`Embedded`]), and a socketcand server over TCP ([`Socketcand`]), which
//! reaches a real CAN bus on another machine (or `harness serve can --socketcand`).

use std::collections::VecDeque;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use proto::can::socketcan::{ErrorFrame, SocketCanRepr};
use proto::can::socketcand::{Framed, Message, MAX_MESSAGE_LEN};
use proto::can::CanFrame;
use sim::can::Segment;

use crate::pcap::{SharedTap, Stamper};

/// The most error frames a link keeps for [`CanLink::take_error_frames`].
const MAX_ERROR_FRAMES: usize = 1024;

/// Keeps `e` among a link's error frames, dropping the oldest beyond [`MAX_ERROR_FRAMES`].
pub(super) fn keep_error_frame(errors: &mut Vec<ErrorFrame>, e: ErrorFrame) {
    if errors.len() == MAX_ERROR_FRAMES {
        errors.remove(0);
    }
    errors.push(e);
}

/// Why a link failed.
#[derive(Debug, thiserror::Error)]
pub(crate) enum CanLinkError {
    /// The socket failed.
    #[error("{peer}: {source}")]
    Io {
        /// The server (`socketcand ADDR`) or interface (`CAN interface IFACE`).
        peer: String,
        /// What the system said.
        source: std::io::Error,
    },
    /// The server said something socketcand does not, or refused; a frame the link cannot carry.
    #[error("{peer}: {what}")]
    Protocol {
        /// As for `Io`.
        peer: String,
        /// What went wrong.
        what: String,
    },
}

/// A CAN segment as the harness reaches it.
pub(crate) trait CanLink {
    /// Puts `frame` on the bus.
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanLinkError>;
    /// The next frame another node put on the bus, waiting up to `limit` on the link's clock;
    /// `None` when none came.
    fn recv(&mut self, limit: Duration) -> Result<Option<CanFrame>, CanLinkError>;
    /// The time on the link's clock (virtual in-process, since the connection on a network).
    fn now(&self) -> Duration;
    /// [`CanLink::recv`] with the time the frame was on the bus: the link's clock when it came,
    /// unless the link carries the sender's time (socketcand's timestamps).
    fn recv_stamped(
        &mut self,
        limit: Duration,
    ) -> Result<Option<(Duration, CanFrame)>, CanLinkError> {
        Ok(self.recv(limit)?.map(|f| (self.now(), f)))
    }
    /// The simulated segment behind the link, if it is one (`inject`, `observe`), and the time
    /// on its clock.
    fn segment(&mut self) -> Option<(&mut Segment, Duration)> {
        None
    }
    /// The error frames the link reported since the last call (SocketCAN's `CAN_ERR_FLAG`
    /// frames: a controller's report of a bus error, no node's frame; socketcand forwards them
    /// as `< error CLASS TIME >`, the simulated segment keeps them apart). [`CanLink::recv`]
    /// never returns one: they are reported here and otherwise ignored. At most the last 1024.
    fn take_error_frames(&mut self) -> Vec<ErrorFrame> {
        Vec::new()
    }
}

/// The simulated segment in-process: what the nodes answer is queued at once; waiting
/// advances the virtual clock to the next frame a node sends on its own.
pub(crate) struct Embedded {
    segment: Segment,
    now: Duration,
    queue: VecDeque<CanFrame>,
    /// Frames sent at `now` and not yet on the segment: they go together when the link is
    /// next read (the same instant on the virtual clock).
    inbox: Vec<CanFrame>,
}

impl Embedded {
    /// The segment at power-on, its boot-up messages waiting.
    pub(crate) fn new(mut segment: Segment) -> Embedded {
        let queue = segment.poll(Duration::ZERO).into();
        Embedded {
            segment,
            now: Duration::ZERO,
            queue,
            inbox: Vec::new(),
        }
    }

    /// The frames sent so far onto the segment.
    fn deliver(&mut self) {
        if !self.inbox.is_empty() {
            let answers = self.segment.receive_all(&self.inbox, self.now);
            self.queue.extend(answers);
            self.inbox.clear();
        }
    }
}

impl CanLink for Embedded {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanLinkError> {
        self.inbox.push(*frame);
        Ok(())
    }

    fn recv(&mut self, limit: Duration) -> Result<Option<CanFrame>, CanLinkError> {
        self.deliver();
        let deadline = self.now + limit;
        loop {
            if let Some(f) = self.queue.pop_front() {
                return Ok(Some(f));
            }
            match self.segment.next_due() {
                Some(due) if due <= deadline => {
                    // A node due now that sends nothing must not stall the clock.
                    self.now = due.max(self.now + Duration::from_micros(1));
                    let frames = self.segment.poll(self.now);
                    self.queue.extend(frames);
                }
                _ => {
                    self.now = deadline;
                    return Ok(None);
                }
            }
        }
    }

    fn now(&self) -> Duration {
        self.now
    }

    fn segment(&mut self) -> Option<(&mut Segment, Duration)> {
        self.deliver();
        Some((&mut self.segment, self.now))
    }

    fn take_error_frames(&mut self) -> Vec<ErrorFrame> {
        self.deliver();
        let errors = self.segment.take_error_frames();
        errors.into_iter().map(|(_, e)| e).collect()
    }
}

/// A link whose frames also go to the run's capture (`--pcap`), both ways, on its CAN
/// interface, stamped on the run's time line.
pub(crate) struct Tapped<L> {
    inner: L,
    stamper: Stamper,
}

impl<L: CanLink> Tapped<L> {
    /// `inner`, recorded into `tap` from now on.
    pub(crate) fn new(inner: L, tap: SharedTap) -> Tapped<L> {
        let stamper = Stamper::on(tap, inner.now());
        Tapped { inner, stamper }
    }

    fn record(&self, frame: SocketCanRepr) {
        self.stamper
            .record(self.inner.now(), |c, at| c.can(&frame, at));
    }
}

impl<L: CanLink> CanLink for Tapped<L> {
    fn send(&mut self, frame: &CanFrame) -> Result<(), CanLinkError> {
        self.inner.send(frame)?;
        self.record(SocketCanRepr::Frame(*frame));
        Ok(())
    }

    fn recv(&mut self, limit: Duration) -> Result<Option<CanFrame>, CanLinkError> {
        let frame = self.inner.recv(limit)?;
        if let Some(f) = frame {
            self.record(SocketCanRepr::Frame(f));
        }
        Ok(frame)
    }

    fn now(&self) -> Duration {
        self.inner.now()
    }

    fn segment(&mut self) -> Option<(&mut Segment, Duration)> {
        self.inner.segment()
    }

    /// The error frames, recorded in the capture too when they are taken (a step's end): the
    /// link reports them apart and keeps no time of their own.
    fn take_error_frames(&mut self) -> Vec<ErrorFrame> {
        let errors = self.inner.take_error_frames();
        for e in &errors {
            self.record(SocketCanRepr::Error(*e));
        }
        errors
    }
}

/// A socketcand server's channel in raw mode: every frame on that bus comes to the harness.
pub(crate) struct Socketcand {
    peer: String,
    stream: TcpStream,
    buf: Vec<u8>,
    /// The message being written (kept between writes: a frame costs no allocation).
    out: String,
    /// The read time-out the socket has (`None`: none set yet).
    timeout: Option<Duration>,
    since: Instant,
    /// The error frames the server forwarded since [`CanLink::take_error_frames`].
    errors: Vec<ErrorFrame>,
}

/// How far the socket's read time-out may be from the time left before a read sets it anew
/// (a system call per read otherwise). The kernel counts the time-out in ticks, rounded up
/// (1–10 ms), so a read may already wait that much longer than asked; one that times out
/// before the deadline reads again with the time left.
const TIMEOUT_SLACK: Duration = Duration::from_micros(500);

impl Socketcand {
    /// Connects to `host:port`, opens `channel` and switches to raw mode, each answer
    /// awaited for `limit`.
    pub(crate) fn connect(
        addr: std::net::SocketAddr,
        channel: &str,
        limit: Duration,
    ) -> Result<Socketcand, CanLinkError> {
        let peer = format!("socketcand {addr}");
        let io = |source| CanLinkError::Io {
            peer: peer.clone(),
            source,
        };
        let stream = TcpStream::connect_timeout(&addr, limit).map_err(io)?;
        stream.set_nodelay(true).map_err(io)?;
        let mut link = Socketcand {
            peer: peer.clone(),
            stream,
            buf: Vec::new(),
            out: String::new(),
            timeout: None,
            since: Instant::now(),
            errors: Vec::new(),
        };
        link.expect(Message::Hi, limit, "the greeting `< hi >`")?;
        link.write(&Message::Open {
            channel: channel.to_string(),
        })?;
        link.expect(
            Message::Ok,
            limit,
            &format!("`< ok >` to `< open {channel} >`"),
        )?;
        link.write(&Message::RawMode)?;
        link.expect(Message::Ok, limit, "`< ok >` to `< rawmode >`")?;
        Ok(link)
    }

    fn protocol(&self, what: String) -> CanLinkError {
        CanLinkError::Protocol {
            peer: self.peer.clone(),
            what,
        }
    }

    fn write(&mut self, m: &Message) -> Result<(), CanLinkError> {
        self.out.clear();
        m.emit_into(&mut self.out)
            .map_err(|e| self.protocol(e.to_string()))?;
        self.stream
            .write_all(self.out.as_bytes())
            .map_err(|source| CanLinkError::Io {
                peer: self.peer.clone(),
                source,
            })
    }

    /// The next message within `limit`.
    fn message(&mut self, limit: Duration) -> Result<Option<Message>, CanLinkError> {
        let deadline = Instant::now() + limit;
        let mut chunk = [0u8; 1024];
        loop {
            match Message::parse(&self.buf) {
                Ok(Framed::Complete { message, consumed }) => {
                    self.buf.drain(..consumed);
                    return Ok(Some(message));
                }
                Ok(Framed::Incomplete) if self.buf.len() <= MAX_MESSAGE_LEN => {}
                Ok(Framed::Incomplete) => {
                    return Err(self.protocol(format!("no `>` within {MAX_MESSAGE_LEN} bytes")))
                }
                Err(e) => return Err(self.protocol(e.to_string())),
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            let io = |source| CanLinkError::Io {
                peer: self.peer.clone(),
                source,
            };
            if self
                .timeout
                .is_none_or(|t| t.abs_diff(left) > TIMEOUT_SLACK)
            {
                self.stream.set_read_timeout(Some(left)).map_err(io)?;
                self.timeout = Some(left);
            }
            match self.stream.read(&mut chunk) {
                Ok(0) => return Err(self.protocol("the server closed the connection".into())),
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                // Before the deadline, a time-out set a little short: the time left, again.
                Err(e) if crate::net::timed_out(&e) && Instant::now() < deadline => {
                    self.timeout = None;
                }
                Err(e) if crate::net::timed_out(&e) => return Ok(None),
                Err(e) => return Err(io(e)),
            }
        }
    }

    fn expect(&mut self, want: Message, limit: Duration, what: &str) -> Result<(), CanLinkError> {
        match self.message(limit)? {
            Some(m) if m == want => Ok(()),
            Some(Message::Error { text }) => Err(self.protocol(format!("refused: {text}"))),
            Some(other) => Err(self.protocol(format!("expected {what}, got {other:?}"))),
            None => Err(self.protocol(format!("no {what} within {limit:?}"))),
        }
    }
}

impl CanLink for Socketcand {
    fn now(&self) -> Duration {
        self.since.elapsed()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), CanLinkError> {
        self.write(&Message::Send { frame: *frame })
    }

    fn recv(&mut self, limit: Duration) -> Result<Option<CanFrame>, CanLinkError> {
        Ok(self.recv_stamped(limit)?.map(|(_, f)| f))
    }

    fn take_error_frames(&mut self) -> Vec<ErrorFrame> {
        std::mem::take(&mut self.errors)
    }

    fn recv_stamped(
        &mut self,
        limit: Duration,
    ) -> Result<Option<(Duration, CanFrame)>, CanLinkError> {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.message(left)? {
                Some(Message::Frame { frame, time }) => {
                    let at =
                        Duration::from_secs(time.secs) + Duration::from_micros(time.usecs.into());
                    return Ok(Some((at, frame)));
                }
                // An error frame is reported, not taken for a frame (raw mode gives its class
                // alone; BCM mode adds the data).
                Some(Message::ErrorFrame { class, data, .. }) => {
                    let mut bytes = [0; 8];
                    bytes
                        .iter_mut()
                        .zip(&data)
                        .for_each(|(to, from)| *to = *from);
                    keep_error_frame(&mut self.errors, ErrorFrame { class, data: bytes });
                }
                // Replies to nothing the harness asked are not frames.
                Some(_) => continue,
                None => return Ok(None),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::can::socketcan::ErrorClass;
    use sim::device::DeviceConfig;

    /// Reads `stream` up to the end of the next message.
    fn read_message(stream: &mut TcpStream) -> String {
        let mut text = Vec::new();
        let mut byte = [0u8; 1];
        while !text.ends_with(b">") {
            assert_eq!(stream.read(&mut byte).unwrap(), 1, "the client went");
            text.push(byte[0]);
        }
        String::from_utf8(text).unwrap()
    }

    /// A socketcand server on a port of its own: the greeting, `< ok >` to `open` and
    /// `rawmode`, then for the first `send` the harness writes, `answer`.
    fn server(answer: &'static str) -> std::net::SocketAddr {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            s.write_all(b"< hi >").unwrap();
            for _ in 0..2 {
                read_message(&mut s);
                s.write_all(b"< ok >").unwrap();
            }
            assert!(read_message(&mut s).contains("send"));
            s.write_all(answer.as_bytes()).unwrap();
            // Held open until the client goes.
            let _ = s.read(&mut [0u8; 16]);
        });
        addr
    }

    #[test]
    fn an_error_frame_is_reported_apart_and_the_sdo_client_reads_on() {
        // A bus error (class 088h) before the node's answer, and one in BCM form after it.
        let addr = server(
            "< error 088 1.000000 >< frame 5A0 1.000100 4300100000000000 >\
             < error 20000004 1.000200 00 20 00 00 00 00 00 00 >",
        );
        let limit = Duration::from_secs(5);
        let link = Socketcand::connect(addr, "can0", limit).unwrap();
        let mut client = super::super::sdo::Client::new(link, limit);
        assert_eq!(client.upload(32, 0x1000, 0).unwrap(), [0, 0, 0, 0]);
        // Nothing more comes as a frame; both error frames are reported.
        assert_eq!(client.link.recv(Duration::from_millis(200)).unwrap(), None);
        let errors = client.link.take_error_frames();
        assert_eq!(errors.len(), 2, "{errors:?}");
        assert_eq!(errors[0].class, ErrorClass(0x088));
        assert_eq!(errors[0].data, [0; 8], "raw mode gives the class alone");
        assert_eq!(errors[1].controller(), Some(0x20));
        assert!(client.link.take_error_frames().is_empty());
    }

    #[test]
    fn the_embedded_segment_reports_its_error_frames_apart() {
        let segment = Segment::new(DeviceConfig::new(proto::nord::Product::Sk550p)).unwrap();
        let mut link = Embedded::new(segment);
        while link.recv(Duration::ZERO).unwrap().is_some() {}
        let fi2 = proto::nord::Inverter::new(2).unwrap();
        let (segment, now) = link.segment().unwrap();
        segment
            .inject_fault_at(fi2, sim::can::ERROR_FRAMES, now)
            .unwrap();
        let req = CanFrame::new(0x600 + 34, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap();
        link.send(&req).unwrap();
        let answer = link.recv(Duration::ZERO).unwrap().unwrap();
        assert_eq!(answer.id(), 0x580 + 34);
        let errors = link.take_error_frames();
        assert_eq!(errors.len(), usize::from(sim::can::BURST));
        assert!(errors.iter().all(|e| *e == sim::can::bus_error()));
        assert_eq!(
            super::super::binding::error_frame_hex(&errors[0]),
            "error 088 00 00 04 0A 00 00 00 00"
        );
    }

    #[test]
    fn the_embedded_segment_boots_and_answers_on_its_clock() {
        let segment = Segment::new(DeviceConfig::new(proto::nord::Product::Sk550p)).unwrap();
        let mut link = Embedded::new(segment);
        // Boot-up messages (700h + node, one byte 00h) of FI 1 (node 32) first.
        let first = link.recv(Duration::ZERO).unwrap().unwrap();
        assert_eq!((first.id(), first.data()), (0x700 + 32, &[0u8][..]));
        while link.recv(Duration::ZERO).unwrap().is_some() {}
        // Nothing scheduled at factory settings (1017h = 0): a wait passes the clock.
        assert_eq!(link.recv(Duration::from_millis(50)).unwrap(), None);
        assert_eq!(link.now, Duration::from_millis(50));
        // An SDO upload of 1000h from node 32 is answered at once.
        let req = CanFrame::new(0x600 + 32, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap();
        link.send(&req).unwrap();
        let answer = link.recv(Duration::ZERO).unwrap().unwrap();
        assert_eq!(answer.id(), 0x580 + 32);
    }
}
