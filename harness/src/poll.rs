//! Low-latency reads from a TCP stream: poll briefly, then sleep.
//!
//! A request–reply exchange over loopback costs a few microseconds of work and, when each
//! side sleeps in `read` until the other answers, about as much again in waking threads up.
//! Polling a non-blocking socket for a short while before sleeping takes the wake-up out of
//! the common case (a reply that comes within the poll window), as low-latency network code
//! does; a slow peer still gets the full timeout, in a blocking read that costs no CPU. The
//! poll yields the processor on every turn, so a peer on the same core is not starved.

use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// How long a client polls for a reply before it sleeps: a device that answers within it (the
/// simulator over loopback does, in tens of µs) is seen without a thread wake-up.
pub const REPLY_POLL: Duration = Duration::from_micros(100);

/// A TCP stream read by polling for up to `spin` before blocking.
#[derive(Debug)]
pub struct PollingStream {
    tcp: TcpStream,
    spin: Duration,
    /// The socket's mode as last set: a wait in blocking mode that could not switch back
    /// leaves it `false`, and the next call switches back before it polls.
    nonblocking: bool,
}

impl PollingStream {
    /// Wraps `tcp`, which is made non-blocking.
    pub fn new(tcp: TcpStream, spin: Duration) -> std::io::Result<PollingStream> {
        let mut s = PollingStream {
            tcp,
            spin,
            nonblocking: false,
        };
        s.set_nonblocking(true)?;
        Ok(s)
    }

    fn set_nonblocking(&mut self, on: bool) -> std::io::Result<()> {
        if self.nonblocking != on {
            self.tcp.set_nonblocking(on)?;
            self.nonblocking = on;
        }
        Ok(())
    }

    /// The stream, to write to or ask for addresses.
    pub fn get(&self) -> &TcpStream {
        &self.tcp
    }

    /// Reads what has arrived into `buf`, waiting up to `timeout` for something: `Ok(0)` is
    /// the peer's close, `ErrorKind::TimedOut` that nothing came in time.
    pub fn read(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        self.set_nonblocking(true)?;
        let start = Instant::now();
        loop {
            match (&self.tcp).read(buf) {
                Err(e) if e.kind() == ErrorKind::WouldBlock => {}
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                other => return other,
            }
            let spent = start.elapsed();
            if spent >= self.spin.min(timeout) {
                let left = timeout.saturating_sub(spent);
                if left.is_zero() {
                    return Err(ErrorKind::TimedOut.into());
                }
                return self.read_blocking(buf, left);
            }
            std::thread::yield_now();
        }
    }

    /// Writes all of `bytes`; a full send buffer is waited on for up to `timeout`.
    pub fn write_all(&mut self, bytes: &[u8], timeout: Duration) -> std::io::Result<()> {
        self.set_nonblocking(true)?;
        let mut rest = bytes;
        while !rest.is_empty() {
            match (&self.tcp).write(rest) {
                Ok(0) => return Err(ErrorKind::WriteZero.into()),
                Ok(n) => rest = &rest[n..],
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    self.set_nonblocking(false)?;
                    self.tcp
                        .set_write_timeout(Some(timeout.max(Duration::from_millis(1))))?;
                    let r = (&self.tcp).write_all(rest);
                    // The write's own outcome counts; a failed switch back is retried by
                    // the next call.
                    let _ = self.set_nonblocking(true);
                    return r;
                }
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// A blocking read of at most `timeout`; the stream is non-blocking again afterwards.
    fn read_blocking(&mut self, buf: &mut [u8], timeout: Duration) -> std::io::Result<usize> {
        self.set_nonblocking(false)?;
        self.tcp.set_read_timeout(Some(timeout))?;
        let r = loop {
            match (&self.tcp).read(buf) {
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    break Err(ErrorKind::TimedOut.into())
                }
                other => break other,
            }
        };
        // Bytes read are returned whatever the switch back gives; a failed one is retried by
        // the next call.
        let _ = self.set_nonblocking(true);
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::TcpListener;

    fn pair(spin: Duration) -> (PollingStream, TcpStream) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let client = TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (server, _) = listener.accept().unwrap();
        (PollingStream::new(client, spin).unwrap(), server)
    }

    #[test]
    fn reads_what_arrived_and_sees_the_close() {
        let (mut s, mut peer) = pair(Duration::from_micros(50));
        peer.write_all(b"abc").unwrap();
        let mut buf = [0u8; 8];
        let n = s.read(&mut buf, Duration::from_secs(2)).unwrap();
        assert_eq!(&buf[..n], b"abc");
        drop(peer);
        assert_eq!(s.read(&mut buf, Duration::from_secs(2)).unwrap(), 0);
    }

    #[test]
    fn a_late_reply_is_read_blocking_and_silence_times_out() {
        let (mut s, mut peer) = pair(Duration::from_micros(10));
        let writer = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(30));
            peer.write_all(b"late").unwrap();
            peer
        });
        let mut buf = [0u8; 8];
        let n = s.read(&mut buf, Duration::from_secs(2)).unwrap();
        assert_eq!(&buf[..n], b"late");
        let _peer = writer.join().unwrap();
        let e = s.read(&mut buf, Duration::from_millis(20)).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::TimedOut);
        // Non-blocking again after the blocking read: writes and polls go on.
        assert!(s.get().set_nodelay(true).is_ok());
        let e = s.read(&mut buf, Duration::ZERO).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::TimedOut);
    }
}
