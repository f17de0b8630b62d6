//! The SDO server of CoE (ETG.1000.6 §5.6.2, CiA 301 §7.2.4.3): expedited, normal and
//! segmented upload and download, complete access, abort transfer (BU 0620 §2.2.7: "a single
//! SDO channel").
//!
//! One transfer at a time: a new initiate request ends an unfinished one. Segments carry a
//! toggle bit that starts at 0 and alternates; a segment with the wrong toggle aborts the
//! transfer with 05030000h, a segment without a transfer or an unknown command specifier with
//! 05040001h. A download's data is checked against the object only when it is complete.

use proto::ecat::coe::{SdoAbortCode, SdoData, SdoRequest, SdoResponse};
use proto::nord::errors::SdoAbort;

use super::od::{Context, Dictionary};
use crate::objects::abort;

/// Largest normal/segmented download the server takes (bytes): more is "out of memory"
/// (05040005h). The largest object, a complete access to an array of 64 words per set, is
/// 514 bytes.
pub(crate) const MAX_DOWNLOAD: u32 = 1024;

#[derive(Debug, Clone, PartialEq, Eq)]
enum Transfer {
    Idle,
    Download {
        index: u16,
        sub: u8,
        complete: bool,
        size: u32,
        data: Vec<u8>,
        toggle: bool,
    },
    Upload {
        index: u16,
        sub: u8,
        data: Vec<u8>,
        sent: usize,
        toggle: bool,
    },
}

/// The SDO server's transfer state.
#[derive(Debug, Clone)]
pub(crate) struct SdoServer {
    transfer: Transfer,
}

impl Default for SdoServer {
    fn default() -> Self {
        SdoServer {
            transfer: Transfer::Idle,
        }
    }
}

/// Bytes of object data in a normal upload response (mailbox header 6, CoE 2, SDO 8).
pub(crate) fn normal_room(mailbox: usize) -> usize {
    mailbox.saturating_sub(16)
}

/// Bytes of data in a segment (mailbox header 6, CoE 2, command 1).
pub(crate) fn segment_room(mailbox: usize) -> usize {
    mailbox.saturating_sub(9)
}

impl SdoServer {
    /// Serves one request; `mailbox` is the send mailbox's size. `None` answers an abort
    /// request (no response).
    pub(crate) fn serve(
        &mut self,
        od: &Dictionary,
        cx: &mut Context<'_>,
        req: SdoRequest,
        mailbox: usize,
    ) -> Option<SdoResponse> {
        let current = std::mem::replace(&mut self.transfer, Transfer::Idle);
        let (index, sub) = match &current {
            Transfer::Download { index, sub, .. } | Transfer::Upload { index, sub, .. } => {
                (*index, *sub)
            }
            Transfer::Idle => (0, 0),
        };
        let fail = |index, sub, code: SdoAbort| {
            Some(SdoResponse::Abort {
                index,
                sub,
                code: SdoAbortCode(code.0),
            })
        };
        match req {
            SdoRequest::Abort { .. } => None,
            SdoRequest::Upload {
                index,
                sub,
                complete_access: complete,
            } => match od.upload(cx, index, sub, complete) {
                Err(code) => fail(index, sub, code),
                Ok(data) if data.len() <= 4 && !data.is_empty() => Some(SdoResponse::Upload {
                    index,
                    sub,
                    complete_access: complete,
                    data: SdoData::Expedited { sized: true, data },
                }),
                Ok(data) => {
                    let first = data.len().min(normal_room(mailbox));
                    let size = data.len() as u32;
                    let part = data[..first].to_vec();
                    if first < data.len() {
                        self.transfer = Transfer::Upload {
                            index,
                            sub,
                            data,
                            sent: first,
                            toggle: false,
                        };
                    }
                    Some(SdoResponse::Upload {
                        index,
                        sub,
                        complete_access: complete,
                        data: SdoData::Normal { size, data: part },
                    })
                }
            },
            SdoRequest::UploadSegment { toggle } => {
                let Transfer::Upload {
                    index,
                    sub,
                    data,
                    sent,
                    toggle: expected,
                } = current
                else {
                    return fail(index, sub, abort::COMMAND);
                };
                if toggle != expected {
                    return fail(index, sub, abort::TOGGLE);
                }
                let n = (data.len() - sent).min(segment_room(mailbox));
                let part = data[sent..sent + n].to_vec();
                let last = sent + n >= data.len();
                if !last {
                    self.transfer = Transfer::Upload {
                        index,
                        sub,
                        data,
                        sent: sent + n,
                        toggle: !toggle,
                    };
                }
                Some(SdoResponse::UploadSegment {
                    toggle,
                    last,
                    data: part,
                })
            }
            SdoRequest::Download {
                index,
                sub,
                complete_access: complete,
                data,
            } => {
                let (expedited, size, data) = match data {
                    SdoData::Expedited { sized, data } => {
                        (true, sized.then_some(data.len() as u32), data)
                    }
                    SdoData::Normal { size, data } => (false, Some(size), data),
                };
                if expedited {
                    let data = match size {
                        Some(n) => data.get(..n as usize).unwrap_or(&data).to_vec(),
                        None => self.unspecified(od, cx, index, sub, complete, data),
                    };
                    return match od.download(cx, index, sub, complete, &data) {
                        Ok(()) => Some(SdoResponse::Download {
                            index,
                            sub,
                            complete_access: complete,
                        }),
                        Err(code) => fail(index, sub, code),
                    };
                }
                let size = size.unwrap_or(data.len() as u32);
                if size > MAX_DOWNLOAD {
                    return fail(index, sub, abort::NO_MEMORY);
                }
                let mut data = data;
                data.truncate(size as usize);
                if data.len() as u32 == size {
                    return match od.download(cx, index, sub, complete, &data) {
                        Ok(()) => Some(SdoResponse::Download {
                            index,
                            sub,
                            complete_access: complete,
                        }),
                        Err(code) => fail(index, sub, code),
                    };
                }
                self.transfer = Transfer::Download {
                    index,
                    sub,
                    complete,
                    size,
                    data,
                    toggle: false,
                };
                Some(SdoResponse::Download {
                    index,
                    sub,
                    complete_access: complete,
                })
            }
            SdoRequest::DownloadSegment { toggle, last, data } => {
                let Transfer::Download {
                    index,
                    sub,
                    complete,
                    size,
                    data: mut buf,
                    toggle: expected,
                } = current
                else {
                    return fail(index, sub, abort::COMMAND);
                };
                if toggle != expected {
                    return fail(index, sub, abort::TOGGLE);
                }
                buf.extend(data);
                if buf.len() as u32 > size {
                    return fail(index, sub, abort::TOO_LONG);
                }
                if !last {
                    self.transfer = Transfer::Download {
                        index,
                        sub,
                        complete,
                        size,
                        data: buf,
                        toggle: !toggle,
                    };
                    return Some(SdoResponse::DownloadSegment { toggle });
                }
                if (buf.len() as u32) < size {
                    return fail(index, sub, abort::TOO_SHORT);
                }
                match od.download(cx, index, sub, complete, &buf) {
                    Ok(()) => Some(SdoResponse::DownloadSegment { toggle }),
                    Err(code) => fail(index, sub, code),
                }
            }
        }
    }

    /// An expedited download without size: the object's own size of the four bytes (CiA 301
    /// §7.2.4.3.3 "size not indicated"), found by reading it; all four when unreadable.
    /// A request with a command specifier the server does not know (5, 6, 7): ends any
    /// transfer and aborts with 05040001h.
    pub(crate) fn unknown(&mut self, index: u16, sub: u8) -> SdoResponse {
        self.transfer = Transfer::Idle;
        SdoResponse::Abort {
            index,
            sub,
            code: SdoAbortCode(abort::COMMAND.0),
        }
    }

    fn unspecified(
        &self,
        od: &Dictionary,
        cx: &mut Context<'_>,
        index: u16,
        sub: u8,
        complete: bool,
        data: Vec<u8>,
    ) -> Vec<u8> {
        match od.upload(cx, index, sub, complete) {
            Ok(current) if current.len() <= data.len() => data[..current.len()].to_vec(),
            _ => data,
        }
    }
}
