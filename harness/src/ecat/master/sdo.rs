//! The CoE SDO client (ETG.1000.6 §5.6.2; CiA 301 §7.2.4.3): upload and download, expedited
//! (up to 4 bytes in the initiate message), normal (the data in the initiate message after the
//! size) and segmented (the rest in segments with an alternating toggle bit), with complete
//! access (every sub-index at once) if asked. The messages are `proto::ecat::coe`'s.
//!
//! The NORD parameters are objects 2000h + 800h·(FI − 1) + parameter number, sub-index 1 first
//! (BU 0620 §2.2.7: P102 of FI 3 is 3066h). An abort transfer from the slave is its refusal,
//! [`Refusal::SdoAbort`] with the abort code (BU 0620 §2.2.7.2); a response that does not
//! answer the request breaks the protocol ([`ProtocolError`]).

use proto::ecat::coe::{self, SdoData, SdoRequest, SdoResponse};
use proto::ecat::mailbox::MailboxType;

use super::engine::Master;
use super::error::{MasterError, ProtocolError, Refusal, Result, UsageError};
use super::segment::Segment;

/// A response that is not the one the request needs.
fn unexpected(expected: &'static str, got: &SdoResponse) -> MasterError {
    ProtocolError::Unexpected {
        expected,
        got: format!("{got:?}"),
    }
    .into()
}

impl<S: Segment> Master<S> {
    /// One SDO request of the transfer of `index`:`sub` and its response; an abort is
    /// [`Refusal::SdoAbort`].
    fn sdo_exchange(
        &mut self,
        station: u16,
        index: u16,
        sub: u8,
        request: &SdoRequest,
    ) -> Result<SdoResponse> {
        let data = request.emit_coe().map_err(UsageError::Mailbox)?;
        let m = self.mailbox_request(station, MailboxType::COE, data)?;
        if m.kind != MailboxType::COE {
            return Err(ProtocolError::Unexpected {
                expected: "a CoE reply",
                got: format!("mailbox type {}", m.kind),
            }
            .into());
        }
        match SdoResponse::parse_coe(&m.data).map_err(ProtocolError::Coe)? {
            SdoResponse::Abort { code, .. } => Err(Refusal::SdoAbort { index, sub, code }.into()),
            r => Ok(r),
        }
    }

    /// SDO upload of `index`:`sub` from `station` (complete access: every sub-index from
    /// `sub`, 0 or 1, on).
    pub(crate) fn sdo_upload(
        &mut self,
        station: u16,
        index: u16,
        sub: u8,
        complete: bool,
    ) -> Result<Vec<u8>> {
        let request = SdoRequest::Upload {
            index,
            sub,
            complete_access: complete,
        };
        let r = self.sdo_exchange(station, index, sub, &request)?;
        let (size, mut data) = match r {
            SdoResponse::Upload {
                index: i,
                sub: s,
                data,
                ..
            } if (i, s) == (index, sub) => match data {
                SdoData::Expedited { data, .. } => return Ok(data),
                SdoData::Normal { size, data } => (size, data),
            },
            other => return Err(unexpected("the upload response of the object", &other)),
        };
        let want = size as usize;
        // Segmented: the rest in upload segments, toggle 0 first.
        let mut toggle = false;
        while data.len() < want {
            let r =
                self.sdo_exchange(station, index, sub, &SdoRequest::UploadSegment { toggle })?;
            let SdoResponse::UploadSegment {
                toggle: t,
                last,
                data: seg,
            } = r
            else {
                return Err(unexpected("an upload segment", &r));
            };
            if t != toggle {
                return Err(ProtocolError::Toggle {
                    expected: toggle,
                    got: t,
                }
                .into());
            }
            data.extend(seg);
            if last {
                break;
            }
            toggle = !toggle;
        }
        if data.len() != want {
            return Err(ProtocolError::SdoSize {
                announced: size,
                got: data.len(),
            }
            .into());
        }
        Ok(data)
    }

    /// SDO download of `data` to `index`:`sub` of `station` (expedited for 1 to 4 bytes
    /// without complete access, else normal and, if the mailbox is too small, segmented).
    pub(crate) fn sdo_download(
        &mut self,
        station: u16,
        index: u16,
        sub: u8,
        data: &[u8],
        complete: bool,
    ) -> Result<()> {
        let room = self.mailbox_room(station)?;
        let (first, rest) = if !complete && (1..=4).contains(&data.len()) {
            (
                SdoData::Expedited {
                    sized: true,
                    data: data.to_vec(),
                },
                &[][..],
            )
        } else {
            let n = data.len().min(coe::normal_capacity(room));
            (
                SdoData::Normal {
                    size: data.len() as u32,
                    data: data[..n].to_vec(),
                },
                &data[n..],
            )
        };
        let request = SdoRequest::Download {
            index,
            sub,
            complete_access: complete,
            data: first,
        };
        match self.sdo_exchange(station, index, sub, &request)? {
            SdoResponse::Download {
                index: i, sub: s, ..
            } if (i, s) == (index, sub) => {}
            other => return Err(unexpected("the download response of the object", &other)),
        }
        let capacity = coe::segment_capacity(room).max(1);
        let mut toggle = false;
        for (k, chunk) in rest.chunks(capacity).enumerate() {
            let last = (k + 1) * capacity >= rest.len();
            let segment = SdoRequest::DownloadSegment {
                toggle,
                last,
                data: chunk.to_vec(),
            };
            match self.sdo_exchange(station, index, sub, &segment)? {
                SdoResponse::DownloadSegment { toggle: t } if t == toggle => {}
                SdoResponse::DownloadSegment { toggle: t } => {
                    return Err(ProtocolError::Toggle {
                        expected: toggle,
                        got: t,
                    }
                    .into())
                }
                other => return Err(unexpected("a download segment response", &other)),
            }
            toggle = !toggle;
        }
        Ok(())
    }

    /// The length of `station`'s receive mailbox.
    fn mailbox_room(&self, station: u16) -> Result<usize> {
        let out = self
            .slave(station)
            .and_then(|s| s.mailbox)
            .ok_or(UsageError::NoMailbox { station })?
            .0;
        Ok(usize::from(out.len))
    }
}
