//! SocketCAN: a CAN interface of this host as the system bus (`can0` on a PEAK, Kvaser or
//! gs_usb/CANable adapter; `vcan0` for tests), through the `socketcan` crate. The harness's
//! `--dut can://IFACE` and `harness serve can --iface IFACE` use it. Frames with a 29-bit
//! identifier are not the system bus's (CAN 2.0A, CiA 301) and are passed over; the
//! controller's error frames (the socket asks the kernel for every class) are reported apart
//! ([`CanLink::take_error_frames`]), as the socketcand link reports them.

use std::time::{Duration, Instant};

use proto::can::socketcan::{ErrorClass, ErrorFrame};
use proto::can::CanFrame;
use socketcan::{CanSocket, EmbeddedFrame, Id, Socket, SocketOptions, StandardId};

use super::link::{keep_error_frame, CanLink, CanLinkError};

/// One CAN interface, opened raw.
pub(crate) struct SocketCan {
    socket: CanSocket,
    /// `CAN interface IFACE`, for errors.
    iface: String,
    since: Instant,
    /// The error frames read since [`CanLink::take_error_frames`].
    errors: Vec<ErrorFrame>,
}

impl SocketCan {
    /// Opens `iface` (it must exist and be up: `ip link set can0 up type can bitrate 250000`).
    pub(crate) fn open(iface: &str) -> Result<SocketCan, CanLinkError> {
        let peer = format!("CAN interface {iface}");
        let socket = CanSocket::open(iface).map_err(|source| CanLinkError::Io {
            peer: peer.clone(),
            source,
        })?;
        // The kernel passes error frames to a raw socket only when asked (CAN_RAW_ERR_FILTER).
        socket
            .set_error_filter_accept_all()
            .map_err(|source| CanLinkError::Io {
                peer: peer.clone(),
                source,
            })?;
        Ok(SocketCan {
            socket,
            iface: peer,
            since: Instant::now(),
            errors: Vec::new(),
        })
    }

    fn io(&self, source: std::io::Error) -> CanLinkError {
        CanLinkError::Io {
            peer: self.iface.clone(),
            source,
        }
    }
}

/// The kernel's frame of `f`.
pub(crate) fn to_socketcan(f: &CanFrame) -> Option<socketcan::CanFrame> {
    let id = StandardId::new(f.id())?;
    match f.is_remote() {
        true => socketcan::CanFrame::new_remote(id, usize::from(f.dlc())),
        false => socketcan::CanFrame::new(id, f.data()),
    }
}

/// The error frame of a kernel frame, if it is one: its class bits and 8 data bytes.
pub(crate) fn error_of(f: &socketcan::CanFrame) -> Option<ErrorFrame> {
    let socketcan::CanFrame::Error(e) = f else {
        return None;
    };
    let mut data = [0; 8];
    data.iter_mut()
        .zip(e.data())
        .for_each(|(to, from)| *to = *from);
    Some(ErrorFrame {
        class: ErrorClass(e.error_bits()),
        data,
    })
}

/// The system-bus frame of a kernel frame; `None` for an extended or error frame.
pub(crate) fn from_socketcan(f: &socketcan::CanFrame) -> Option<CanFrame> {
    if matches!(f, socketcan::CanFrame::Error(_)) {
        return None;
    }
    let Id::Standard(id) = f.id() else {
        return None;
    };
    match f.is_remote_frame() {
        true => CanFrame::remote(id.as_raw(), f.dlc() as u8).ok(),
        false => CanFrame::new(id.as_raw(), f.data()).ok(),
    }
}

impl CanLink for SocketCan {
    fn now(&self) -> Duration {
        self.since.elapsed()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), CanLinkError> {
        let f = to_socketcan(frame).ok_or_else(|| CanLinkError::Protocol {
            peer: self.iface.clone(),
            what: format!("{frame:?} is no CAN 2.0A frame"),
        })?;
        self.socket.write_frame(&f).map_err(|e| self.io(e))
    }

    fn recv(&mut self, limit: Duration) -> Result<Option<CanFrame>, CanLinkError> {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            match self.socket.read_frame_timeout(left) {
                Ok(f) => {
                    if let Some(frame) = from_socketcan(&f) {
                        return Ok(Some(frame));
                    }
                    if let Some(e) = error_of(&f) {
                        keep_error_frame(&mut self.errors, e);
                    }
                }
                Err(e) if crate::net::timed_out(&e) => return Ok(None),
                Err(e) => return Err(self.io(e)),
            }
        }
    }

    fn take_error_frames(&mut self) -> Vec<ErrorFrame> {
        std::mem::take(&mut self.errors)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_cross_to_the_kernels_and_back() {
        for f in [
            CanFrame::new(0x624, &[0x40, 0x66, 0x20, 0x01, 0, 0, 0, 0]).unwrap(),
            CanFrame::new(0x080, &[]).unwrap(),
            CanFrame::remote(0x724, 1).unwrap(),
        ] {
            let k = to_socketcan(&f).unwrap();
            assert_eq!(from_socketcan(&k), Some(f));
        }
        // A 29-bit frame is not the system bus's.
        let ext =
            socketcan::CanFrame::new(socketcan::ExtendedId::new(0x1234_5678).unwrap(), &[1, 2])
                .unwrap();
        assert_eq!(from_socketcan(&ext), None);
    }

    #[test]
    fn an_error_frame_is_no_frame_and_is_read_as_one() {
        // A controller gone error passive after a protocol violation: class CRTL | PROT (00Ch),
        // data[1] 10h CAN_ERR_CRTL_RX_PASSIVE.
        let k = socketcan::CanFrame::Error(
            socketcan::CanErrorFrame::new_error(0x0C, &[0, 0x10, 0, 0, 0, 0, 0, 0]).unwrap(),
        );
        assert_eq!(from_socketcan(&k), None);
        let e = error_of(&k).unwrap();
        assert_eq!(e.class, ErrorClass(0x0C));
        assert_eq!(e.controller(), Some(0x10));
        assert_eq!(
            error_of(&to_socketcan(&CanFrame::new(0x080, &[]).unwrap()).unwrap()),
            None
        );
    }
}
