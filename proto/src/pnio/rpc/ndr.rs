//! The NDR layer of the PNIO calls (IEC 61158-6-10 "IPNIO_Connect" … "IPNIO_ReadImplicit";
//! C706 §14 conformant varying array): see the table of [`super`].

use super::{u32d, Drep};
use crate::pnio::PnioStatus;
use crate::wire::{Error, Reader};

/// Length of the NDR header of a request (ArgsMaximum .. ActualCount).
pub const NDR_REQUEST_LEN: usize = 20;
/// Length of the NDR header of a response (PNIOStatus .. ActualCount).
pub const NDR_RESPONSE_LEN: usize = 20;

/// ArgsLength, MaximumCount, Offset, ActualCount and the ActualCount bytes, which must fill
/// the rest.
fn ndr_array(
    r: &mut Reader<'_>,
    drep: Drep,
    what: &'static str,
) -> Result<(u32, u32, u32, u32, Vec<u8>), Error> {
    let args_length = u32d(r, drep, "NDR ArgsLength")?;
    let maximum_count = u32d(r, drep, "NDR MaximumCount")?;
    let offset = u32d(r, drep, "NDR Offset")?;
    let actual_count = u32d(r, drep, "NDR ActualCount")?;
    let n = actual_count as usize;
    if n > r.remaining() {
        return Err(Error::Length {
            field: "NDR ActualCount",
            value: n,
            available: r.remaining(),
        });
    }
    let data = r.bytes(n, what)?.to_vec();
    r.finish(what)?;
    Ok((args_length, maximum_count, offset, actual_count, data))
}

fn len_u32(n: usize, what: &'static str) -> Result<u32, Error> {
    u32::try_from(n).map_err(|_| Error::TooLong {
        what,
        len: n,
        max: u32::MAX as usize,
    })
}

/// The NDR body of a PNIO request (Connect, Release, Read, Write, Control, ReadImplicit):
/// the counts as they travel and the bytes of PNIO blocks ([`super::block::Block::parse_all`]).
/// The counts are kept as read so a device can refuse inconsistent ones and a tester can send
/// them; [`NdrRequest::new`] fills them consistently.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct NdrRequest {
    /// ArgsMaximum: the largest response body (after the NDR header) the caller accepts.
    pub args_maximum: u32,
    /// ArgsLength: the length of the blocks.
    pub args_length: u32,
    /// MaximumCount of the conformant array (= ArgsMaximum).
    pub maximum_count: u32,
    /// Offset of the varying array (0).
    pub offset: u32,
    /// ActualCount: the bytes that follow.
    pub actual_count: u32,
    /// The PNIO blocks.
    pub data: Vec<u8>,
}

impl NdrRequest {
    /// A request carrying `data`: ArgsLength = ActualCount = its length, MaximumCount =
    /// ArgsMaximum, Offset 0. Data longer than u32 is [`Error::TooLong`].
    pub fn new(args_maximum: u32, data: Vec<u8>) -> Result<NdrRequest, Error> {
        let n = len_u32(data.len(), "NDR data")?;
        Ok(NdrRequest {
            args_maximum,
            args_length: n,
            maximum_count: args_maximum,
            offset: 0,
            actual_count: n,
            data,
        })
    }

    /// Parses a request body: ActualCount bytes must follow the header and fill the body.
    pub fn parse(body: &[u8], drep: Drep) -> Result<NdrRequest, Error> {
        let mut r = Reader::new(body);
        let args_maximum = u32d(&mut r, drep, "NDR ArgsMaximum")?;
        let (args_length, maximum_count, offset, actual_count, data) =
            ndr_array(&mut r, drep, "NDR request data")?;
        Ok(NdrRequest {
            args_maximum,
            args_length,
            maximum_count,
            offset,
            actual_count,
            data,
        })
    }

    /// The header and the data.
    pub fn buffer_len(&self) -> usize {
        NDR_REQUEST_LEN + self.data.len()
    }

    /// The body bytes in `drep` order, the counts as they are.
    pub fn emit(&self, drep: Drep) -> Vec<u8> {
        let mut b = Vec::with_capacity(self.buffer_len());
        for v in [
            self.args_maximum,
            self.args_length,
            self.maximum_count,
            self.offset,
            self.actual_count,
        ] {
            b.extend(drep.u32(v));
        }
        b.extend(&self.data);
        b
    }
}

/// The NDR body of a PNIO response: the PNIO status of the call, the counts as they travel
/// and the bytes of PNIO blocks.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct NdrResponse {
    /// The call's PNIO status (a refused Connect: ErrorCode 81h, ErrorDecode 81h "PNIO").
    pub status: PnioStatus,
    /// ArgsLength: the length of the blocks.
    pub args_length: u32,
    /// MaximumCount: the request's.
    pub maximum_count: u32,
    /// Offset (0).
    pub offset: u32,
    /// ActualCount: the bytes that follow.
    pub actual_count: u32,
    /// The PNIO blocks.
    pub data: Vec<u8>,
}

impl NdrResponse {
    /// The response to `request` carrying `data`: MaximumCount the request's, ArgsLength =
    /// ActualCount = the data's length, Offset 0. Data longer than u32 is [`Error::TooLong`].
    pub fn answering(
        request: &NdrRequest,
        status: PnioStatus,
        data: Vec<u8>,
    ) -> Result<NdrResponse, Error> {
        let n = len_u32(data.len(), "NDR data")?;
        Ok(NdrResponse {
            status,
            args_length: n,
            maximum_count: request.maximum_count,
            offset: 0,
            actual_count: n,
            data,
        })
    }

    /// Parses a response body.
    pub fn parse(body: &[u8], drep: Drep) -> Result<NdrResponse, Error> {
        let mut r = Reader::new(body);
        let status = u32d(&mut r, drep, "NDR PNIOStatus")?;
        let (args_length, maximum_count, offset, actual_count, data) =
            ndr_array(&mut r, drep, "NDR response data")?;
        Ok(NdrResponse {
            status: PnioStatus::from_bytes(status.to_be_bytes()),
            args_length,
            maximum_count,
            offset,
            actual_count,
            data,
        })
    }

    /// The header and the data.
    pub fn buffer_len(&self) -> usize {
        NDR_RESPONSE_LEN + self.data.len()
    }

    /// The body bytes in `drep` order (the PNIO status as a u32 of that order).
    pub fn emit(&self, drep: Drep) -> Vec<u8> {
        let mut b = Vec::with_capacity(self.buffer_len());
        for v in [
            u32::from_be_bytes(self.status.to_bytes()),
            self.args_length,
            self.maximum_count,
            self.offset,
            self.actual_count,
        ] {
            b.extend(drep.u32(v));
        }
        b.extend(&self.data);
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ndr_request_and_response() {
        // Request, little-endian: ArgsMaximum 16696 (4138h), ArgsLength 2, MaximumCount
        // 16696, Offset 0, ActualCount 2, then 2 bytes.
        let bytes = [
            0x38, 0x41, 0, 0, 2, 0, 0, 0, 0x38, 0x41, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 0x01, 0x02,
        ];
        let req = NdrRequest::parse(&bytes, Drep::LITTLE_ENDIAN).unwrap();
        assert_eq!(req, NdrRequest::new(16696, vec![1, 2]).unwrap());
        assert_eq!(req.emit(Drep::LITTLE_ENDIAN), bytes);
        let be = req.emit(Drep::BIG_ENDIAN);
        assert_eq!(be[..4], [0, 0, 0x41, 0x38]);
        assert_eq!(NdrRequest::parse(&be, Drep::BIG_ENDIAN), Ok(req.clone()));

        // Response, little-endian: PNIOStatus 81813D06h (ErrorCode 81h, ErrorDecode 81h,
        // ErrorCode1 3Dh, ErrorCode2 06h) travels as 06 3D 81 81; ArgsLength 0, MaximumCount
        // 16696, Offset 0, ActualCount 0.
        let res = NdrResponse::answering(&req, PnioStatus::cm(0x81, 0x3D, 6), vec![]).unwrap();
        let b = res.emit(Drep::LITTLE_ENDIAN);
        assert_eq!(
            b,
            [0x06, 0x3D, 0x81, 0x81, 0, 0, 0, 0, 0x38, 0x41, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]
        );
        assert_eq!(NdrResponse::parse(&b, Drep::LITTLE_ENDIAN), Ok(res.clone()));
        // Big-endian: the status in its natural order 81 81 3D 06.
        let b = res.emit(Drep::BIG_ENDIAN);
        assert_eq!(b[..4], [0x81, 0x81, 0x3D, 0x06]);
        assert_eq!(NdrResponse::parse(&b, Drep::BIG_ENDIAN), Ok(res));
    }

    #[test]
    fn ndr_counts_that_do_not_fit() {
        // ActualCount 5 with 2 bytes.
        let bytes = [
            0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 5, 0, 0, 0, 1, 2,
        ];
        assert_eq!(
            NdrRequest::parse(&bytes, Drep::LITTLE_ENDIAN),
            Err(Error::Length {
                field: "NDR ActualCount",
                value: 5,
                available: 2
            })
        );
        // ActualCount 1 with 2 bytes.
        let mut b = bytes;
        b[16] = 1;
        assert_eq!(
            NdrRequest::parse(&b, Drep::LITTLE_ENDIAN),
            Err(Error::Trailing {
                what: "NDR request data",
                extra: 1
            })
        );
        assert!(matches!(
            NdrResponse::parse(&b[..10], Drep::LITTLE_ENDIAN),
            Err(Error::Truncated { .. })
        ));
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn drep() -> impl Strategy<Value = Drep> {
            prop_oneof![Just(Drep::LITTLE_ENDIAN), Just(Drep::BIG_ENDIAN)]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            /// The counts travel as they are, ActualCount saying how many bytes follow.
            #[test]
            fn request_round_trips(
                counts in any::<(u32, u32, u32, u32)>(),
                data in vec(any::<u8>(), 0..32),
                drep in drep(),
            ) {
                let r = NdrRequest {
                    args_maximum: counts.0,
                    args_length: counts.1,
                    maximum_count: counts.2,
                    offset: counts.3,
                    actual_count: data.len() as u32,
                    data,
                };
                let b = r.emit(drep);
                prop_assert_eq!(b.len(), r.buffer_len());
                prop_assert_eq!(NdrRequest::parse(&b, drep), Ok(r));
            }

            #[test]
            fn response_round_trips(
                status in any::<[u8; 4]>(),
                counts in any::<(u32, u32, u32)>(),
                data in vec(any::<u8>(), 0..32),
                drep in drep(),
            ) {
                let r = NdrResponse {
                    status: PnioStatus::from_bytes(status),
                    args_length: counts.0,
                    maximum_count: counts.1,
                    offset: counts.2,
                    actual_count: data.len() as u32,
                    data,
                };
                let b = r.emit(drep);
                prop_assert_eq!(b.len(), r.buffer_len());
                prop_assert_eq!(NdrResponse::parse(&b, drep), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..48), drep in drep()) {
                let _ = NdrRequest::parse(&bytes, drep);
                let _ = NdrResponse::parse(&bytes, drep);
            }
        }
    }
}
