//! The harness as SDO client (CiA 301 §7.2.4.3): expedited and segmented upload and download
//! to one node over a [`CanLink`], every frame kept for the transcript.

use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::{
    Abort, Cob, Emergency, Expedited, Function, InitiateData, Message, SdoAbortCode, SdoRequest,
    SdoResponse, SegmentData,
};

use super::link::{CanLink, CanLinkError};
use crate::hex::can_frame;
use crate::outcome::Exchange;

/// Why a transfer did not complete.
#[derive(Debug, thiserror::Error)]
pub(crate) enum SdoError {
    /// The node refused with an abort code.
    #[error("SDO abort {0}")]
    Abort(SdoAbortCode),
    /// The node did not answer within the limit.
    #[error("no SDO answer from node {node} to {what} within {limit:?}")]
    Silent {
        /// The node.
        node: u8,
        /// The request.
        what: String,
        /// The limit.
        limit: Duration,
    },
    /// The node answered what CiA 301 does not allow here.
    #[error("node {node}: {what}")]
    Protocol {
        /// The node.
        node: u8,
        /// What was wrong.
        what: String,
    },
    /// The link failed.
    #[error(transparent)]
    Link(#[from] CanLinkError),
}

/// An SDO client of one link, recording each request and its answer.
pub(crate) struct Client<L> {
    pub(crate) link: L,
    /// How long a node may take to answer one request.
    pub(crate) limit: Duration,
    exchanges: Vec<Exchange>,
    /// The EMCYs heard while waiting for something else (node, message), for the binding to
    /// judge (`crate::binding::emergency`); the latest [`KEPT_EMERGENCIES`].
    emergencies: Vec<(u8, Emergency)>,
}

/// EMCYs set aside at most between two looks (a babbling node cannot grow them unbounded).
const KEPT_EMERGENCIES: usize = 64;

/// A frame decoded as CANopen, for the transcript.
pub(crate) fn describe(f: &CanFrame) -> String {
    match Message::parse(f) {
        Ok(m) => format!("{m:?}"),
        Err(e) => format!("not CANopen: {e}"),
    }
}

impl<L: CanLink> Client<L> {
    pub(crate) fn new(link: L, limit: Duration) -> Client<L> {
        Client {
            link,
            limit,
            exchanges: Vec::new(),
            emergencies: Vec::new(),
        }
    }

    /// Keeps an exchange the binding made on the link itself.
    pub(crate) fn record(&mut self, e: Exchange) {
        self.exchanges.push(e);
    }

    /// The exchanges since the last call.
    pub(crate) fn take_exchanges(&mut self) -> Vec<Exchange> {
        std::mem::take(&mut self.exchanges)
    }

    /// A frame heard while waiting for another: an EMCY is set aside.
    pub(crate) fn overheard(&mut self, f: &CanFrame) {
        let Some(Cob {
            function: Function::Emcy,
            node,
        }) = Cob::classify(f.id())
        else {
            return;
        };
        if f.is_remote() {
            return;
        }
        let Ok(e) = Emergency::parse(f.data()) else {
            return;
        };
        if self.emergencies.len() == KEPT_EMERGENCIES {
            self.emergencies.remove(0);
        }
        self.emergencies.push((node, e));
    }

    /// The EMCYs set aside since the last look.
    pub(crate) fn take_emergencies(&mut self) -> Vec<(u8, Emergency)> {
        std::mem::take(&mut self.emergencies)
    }

    /// Sends `request` to `node` and waits for its SDO answer; other frames on the bus pass.
    fn ask(&mut self, node: u8, request: SdoRequest) -> Result<SdoResponse, SdoError> {
        let protocol = |what: String| SdoError::Protocol { node, what };
        let frame = request
            .to_can(node)
            .map_err(|e| protocol(format!("cannot address it: {e}")))?;
        self.link.send(&frame)?;
        let answer_id = Function::SdoTx
            .cob_id(node)
            .map_err(|e| protocol(e.to_string()))?;
        let mut waited = Duration::ZERO;
        let answer = loop {
            // The link's clock passes only while it waits; bound the frames of others.
            match self.link.recv(self.limit.saturating_sub(waited))? {
                Some(f) if f.id() == answer_id => break Some(f),
                Some(f) => {
                    self.overheard(&f);
                    waited += Duration::from_micros(500);
                }
                None => break None,
            }
            if waited >= self.limit {
                break None;
            }
        };
        self.exchanges.push(Exchange {
            sent_hex: can_frame(&frame),
            sent: describe(&frame),
            received_hex: answer.as_ref().map(can_frame).unwrap_or_default(),
            received: answer
                .as_ref()
                .map_or_else(|| "(nothing received)".into(), describe),
        });
        let Some(answer) = answer else {
            return Err(SdoError::Silent {
                node,
                what: format!("{request:?}"),
                limit: self.limit,
            });
        };
        let response = SdoResponse::parse(answer.data())
            .map_err(|e| protocol(format!("malformed SDO answer: {e}")))?;
        match response {
            SdoResponse::Abort(a) => Err(SdoError::Abort(a.code)),
            r => Ok(r),
        }
    }

    /// Reads `index`:`sub` of `node`: expedited, or segment by segment.
    pub(crate) fn upload(&mut self, node: u8, index: u16, sub: u8) -> Result<Vec<u8>, SdoError> {
        let protocol = |what: String| SdoError::Protocol { node, what };
        let size = match self.ask(node, SdoRequest::InitiateUpload { index, sub })? {
            SdoResponse::InitiateUpload {
                index: i,
                sub: s,
                data,
            } if (i, s) == (index, sub) => match data {
                InitiateData::Expedited(e) => return Ok(e.data().to_vec()),
                InitiateData::Segmented { size } => size,
            },
            other => {
                return Err(protocol(format!(
                    "{other:?} to an upload of {index:04X}h:{sub:02X}h"
                )))
            }
        };
        let mut data = Vec::new();
        let mut toggle = false;
        loop {
            match self.ask(node, SdoRequest::UploadSegment { toggle })? {
                SdoResponse::UploadSegment {
                    toggle: t,
                    last,
                    data: d,
                } if t == toggle => {
                    data.extend_from_slice(d.data());
                    if last {
                        break;
                    }
                }
                // CiA 301 §7.2.4.3.5: the client aborts a transfer whose toggle bit did not
                // alternate.
                SdoResponse::UploadSegment { .. } => {
                    let code = SdoAbortCode::TOGGLE_BIT;
                    self.abort(node, index, sub, code)?;
                    return Err(protocol(format!(
                        "upload segment of {index:04X}h:{sub:02X}h with toggle bit {}, expected {}: aborted with {code}",
                        u8::from(!toggle),
                        u8::from(toggle)
                    )));
                }
                other => return Err(protocol(format!("{other:?} to an upload segment"))),
            }
            toggle = !toggle;
            if data.len() > 0xFFFF {
                return Err(protocol("an upload beyond 64 KiB".into()));
            }
        }
        match size {
            Some(n) if n as usize != data.len() => Err(protocol(format!(
                "{} bytes of {index:04X}h:{sub:02X}h uploaded, {n} announced",
                data.len()
            ))),
            _ => Ok(data),
        }
    }

    /// Aborts the transfer of `index`:`sub` with `code` (no answer comes to an abort).
    fn abort(&mut self, node: u8, index: u16, sub: u8, code: SdoAbortCode) -> Result<(), SdoError> {
        let request = SdoRequest::Abort(Abort { index, sub, code });
        let frame = request.to_can(node).map_err(|e| SdoError::Protocol {
            node,
            what: format!("cannot address it: {e}"),
        })?;
        self.link.send(&frame)?;
        self.exchanges.push(Exchange {
            sent_hex: can_frame(&frame),
            sent: describe(&frame),
            received_hex: String::new(),
            received: "(an abort is not answered)".into(),
        });
        Ok(())
    }

    /// Writes `data` to `index`:`sub` of `node`: expedited up to 4 bytes, else segmented.
    pub(crate) fn download(
        &mut self,
        node: u8,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoError> {
        let protocol = |what: String| SdoError::Protocol { node, what };
        let initiate = match Expedited::new(data) {
            Ok(e) => InitiateData::Expedited(e),
            Err(_) => InitiateData::Segmented {
                size: Some(data.len() as u32),
            },
        };
        match self.ask(
            node,
            SdoRequest::InitiateDownload {
                index,
                sub,
                data: initiate,
            },
        )? {
            SdoResponse::InitiateDownload { index: i, sub: s } if (i, s) == (index, sub) => {}
            other => {
                return Err(protocol(format!(
                    "{other:?} to a download of {index:04X}h:{sub:02X}h"
                )))
            }
        }
        if matches!(initiate, InitiateData::Expedited(_)) {
            return Ok(());
        }
        let mut toggle = false;
        let chunks: Vec<&[u8]> = data.chunks(7).collect();
        for (n, chunk) in chunks.iter().enumerate() {
            let segment = SegmentData::new(chunk).map_err(|e| protocol(e.to_string()))?;
            let last = n + 1 == chunks.len();
            match self.ask(
                node,
                SdoRequest::DownloadSegment {
                    toggle,
                    last,
                    data: segment,
                },
            )? {
                SdoResponse::DownloadSegment { toggle: t } if t == toggle => {}
                other => return Err(protocol(format!("{other:?} to a download segment"))),
            }
            toggle = !toggle;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::link::Embedded;
    use super::*;
    use proto::nord::Product;
    use sim::can::Segment;
    use sim::device::DeviceConfig;

    fn client() -> Client<Embedded> {
        let segment = Segment::new(DeviceConfig::new(Product::Sk550p)).unwrap();
        Client::new(Embedded::new(segment), Duration::from_millis(100))
    }

    #[test]
    fn reads_and_writes_a_parameter_and_a_string() {
        let mut c = client();
        // FI 3 is node 36; P102 at 2066h (2000h + 102), set 1 at sub-index 1 (0: 4 sets).
        assert_eq!(c.upload(36, 0x2066, 0).unwrap(), [4]);
        assert_eq!(c.upload(36, 0x2066, 1).unwrap(), 200u16.to_le_bytes());
        c.download(36, 0x2066, 1, &250u16.to_le_bytes()).unwrap();
        assert_eq!(c.upload(36, 0x2066, 1).unwrap(), 250u16.to_le_bytes());
        // 1008h (the product's name) is longer than 4 bytes: segmented.
        let name = c.upload(32, 0x1008, 0).unwrap();
        assert!(name.len() > 4, "{name:?}");
        assert_eq!(c.take_exchanges().len(), 5 + name.len().div_ceil(7));
    }

    #[test]
    fn a_refusal_is_the_abort_code_and_silence_is_named() {
        let mut c = client();
        assert!(matches!(
            c.upload(36, 0x2000 + 999, 0),
            Err(SdoError::Abort(SdoAbortCode::NO_OBJECT))
        ));
        // Node 100 is on no segment of the SK 550P.
        let e = c.upload(100, 0x1000, 0).unwrap_err();
        assert!(matches!(e, SdoError::Silent { node: 100, .. }), "{e}");
    }
}
