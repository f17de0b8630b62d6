//! The cyclic real-time frame of RT_CLASS_1 (and 2/3, which share its layout): IEC 61158-6-10
//! §4.2.2 "C_SDU" / "APDU_Status"; BU 0620 §2.5.3 (frame id, data, status).
//!
//! | bytes (from the frame id) | field |
//! |---|---|
//! | 0–1 | FrameID (big-endian) |
//! | 2..2+n | C_SDU: the IO data objects with their IOPS and the IOCS of the other side, n = 40..1440 |
//! | n+2..n+3 | CycleCounter (big-endian, 1/32 ms units of the send clock) |
//! | n+4 | DataStatus |
//! | n+5 | TransferStatus |
//!
//! A sender pads a C_SDU shorter than 40 bytes with zeros to 40 so the frame reaches the
//! Ethernet minimum (46 payload bytes) by itself; the APDU status is then the last four bytes
//! of the frame. A receiver that knows the IOCR's data length (from Connect) passes it to
//! [`RtRepr::parse`], which then also refuses frames of another length; without it the last
//! four bytes are taken as the status, which is right for every sender that pads as the
//! standard says (never for one that leaves the padding to the Ethernet layer).
//!
//! The C_SDU's inner layout (which data object, IOPS and IOCS sits where) is the AR's, set by
//! the IOCR blocks of Connect; this module gives the IOxS byte ([`Iox`]) and leaves the layout
//! to the caller.

use std::fmt;

use super::frame::{read_frame_id, FrameId};
use crate::wire::Error;

/// The shortest C_SDU (IEC 61158-6-10 "C_SDU length 40..1440"; shorter data is padded).
pub const MIN_C_SDU: usize = 40;
/// The longest C_SDU.
pub const MAX_C_SDU: usize = 1440;
/// Frame id, CycleCounter, DataStatus and TransferStatus around the C_SDU.
pub const OVERHEAD: usize = 6;

/// The DataStatus byte of the APDU status (IEC 61158-6-10 "DataStatus"):
///
/// | bit | name | 1 | 0 |
/// |---|---|---|---|
/// | 0 | State | primary | backup |
/// | 1 | Redundancy | no primary AR of the AR set (input CR of a redundant AR) | default |
/// | 2 | DataValid | valid | invalid |
/// | 3 | reserved | | |
/// | 4 | ProviderState | run | stop |
/// | 5 | StationProblemIndicator | normal (no problem) | problem detected (diagnosis present) |
/// | 6 | reserved | | |
/// | 7 | Ignore | evaluate not the frame | evaluate the frame |
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct DataStatus(pub u8);

impl DataStatus {
    /// Bit 0: State primary.
    pub const PRIMARY: u8 = 0x01;
    /// Bit 1: Redundancy.
    pub const REDUNDANCY: u8 = 0x02;
    /// Bit 2: DataValid.
    pub const DATA_VALID: u8 = 0x04;
    /// Bit 4: ProviderState run.
    pub const RUN: u8 = 0x10;
    /// Bit 5: StationProblemIndicator "normal" (no problem).
    pub const STATION_OK: u8 = 0x20;
    /// Bit 7: Ignore.
    pub const IGNORE: u8 = 0x80;
    /// 35h: primary, valid, run, no problem — the usual status of a running AR.
    pub const GOOD: DataStatus = DataStatus(0x35);

    /// State: primary (else backup).
    pub fn primary(self) -> bool {
        self.0 & Self::PRIMARY != 0
    }
    /// Redundancy bit.
    pub fn redundancy(self) -> bool {
        self.0 & Self::REDUNDANCY != 0
    }
    /// DataValid.
    pub fn data_valid(self) -> bool {
        self.0 & Self::DATA_VALID != 0
    }
    /// ProviderState run (else stop).
    pub fn run(self) -> bool {
        self.0 & Self::RUN != 0
    }
    /// StationProblemIndicator normal (else a problem is reported).
    pub fn station_ok(self) -> bool {
        self.0 & Self::STATION_OK != 0
    }
    /// Ignore: the receiver shall not evaluate the frame.
    pub fn ignore(self) -> bool {
        self.0 & Self::IGNORE != 0
    }

    /// The byte with `bit` (one of the constants) set or cleared.
    pub fn with(self, bit: u8, on: bool) -> DataStatus {
        DataStatus(if on { self.0 | bit } else { self.0 & !bit })
    }
}

impl fmt::Debug for DataStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "DataStatus({:02X}h {} {} {} {}{})",
            self.0,
            if self.primary() { "primary" } else { "backup" },
            if self.data_valid() {
                "valid"
            } else {
                "invalid"
            },
            if self.run() { "run" } else { "stop" },
            if self.station_ok() { "ok" } else { "problem" },
            if self.ignore() { " ignore" } else { "" },
        )
    }
}

/// An IOPS or IOCS byte (IEC 61158-6-10 "IOxS"): bit 7 DataState (1 good, 0 bad), bits 6–5
/// Instance (who detected "bad": 0 subslot, 1 slot, 2 IO device, 3 IO controller), bits 4–1
/// reserved, bit 0 Extension (1: another IOxS byte follows; 0 in every single-byte IOxS).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Iox(pub u8);

impl Iox {
    /// Good (80h).
    pub const GOOD: Iox = Iox(0x80);
    /// Bad, detected by the subslot (00h).
    pub const BAD: Iox = Iox(0x00);
    /// Bad, detected by the slot (20h).
    pub const BAD_BY_SLOT: Iox = Iox(0x20);
    /// Bad, detected by the IO device (40h).
    pub const BAD_BY_DEVICE: Iox = Iox(0x40);
    /// Bad, detected by the IO controller (60h).
    pub const BAD_BY_CONTROLLER: Iox = Iox(0x60);

    /// DataState good.
    pub fn is_good(self) -> bool {
        self.0 & 0x80 != 0
    }
    /// Instance (bits 6–5): 0 subslot, 1 slot, 2 IO device, 3 IO controller.
    pub fn instance(self) -> u8 {
        (self.0 >> 5) & 0x03
    }
    /// Extension: another IOxS byte follows.
    pub fn extension(self) -> bool {
        self.0 & 0x01 != 0
    }
}

impl fmt::Debug for Iox {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let by = ["subslot", "slot", "device", "controller"][usize::from(self.instance())];
        if self.is_good() {
            write!(f, "Iox({:02X}h good)", self.0)
        } else {
            write!(f, "Iox({:02X}h bad by {by})", self.0)
        }
    }
}

/// A cyclic frame from its frame id on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RtRepr {
    /// The frame id of the IOCR.
    pub frame_id: FrameId,
    /// The C_SDU (as received, or as the sender gives it: [`RtRepr::emit`] pads to 40).
    pub data: Vec<u8>,
    /// CycleCounter.
    pub cycle_counter: u16,
    /// DataStatus.
    pub data_status: DataStatus,
    /// TransferStatus (0 on RT_CLASS_1; RT_CLASS_3 reports receive errors in it).
    pub transfer_status: u8,
}

impl RtRepr {
    /// Parses a frame from its frame id on.
    ///
    /// With `c_sdu_len = Some(n)` (the IOCR's DataLength) the frame must hold exactly
    /// `2 + n + 4` bytes, except that bytes after them up to the 46-byte Ethernet minimum are
    /// padding: a shorter frame is [`Error::Truncated`], a longer one [`Error::Trailing`].
    /// With `None` the status is the last four bytes and the C_SDU is what lies between; its
    /// length must be 40..=1440 ([`Error::Invalid`] "C_SDU length" otherwise).
    pub fn parse(buf: &[u8], c_sdu_len: Option<usize>) -> Result<RtRepr, Error> {
        let frame_id = read_frame_id(buf)?;
        let n = match c_sdu_len {
            Some(n) => {
                let need = n.saturating_add(OVERHEAD);
                if buf.len() < need {
                    return Err(Error::Truncated {
                        what: "RT frame",
                        need,
                        got: buf.len(),
                    });
                }
                // 46: the Ethernet payload minimum, which a short frame is padded to.
                if buf.len() > need.max(46) {
                    return Err(Error::Trailing {
                        what: "RT frame",
                        extra: buf.len() - need,
                    });
                }
                n
            }
            None => {
                if buf.len() < OVERHEAD {
                    return Err(Error::Truncated {
                        what: "RT frame",
                        need: OVERHEAD,
                        got: buf.len(),
                    });
                }
                let n = buf.len() - OVERHEAD;
                if !(MIN_C_SDU..=MAX_C_SDU).contains(&n) {
                    return Err(Error::Invalid {
                        field: "C_SDU length",
                        value: n as u32,
                        why: "outside 40..1440 bytes",
                    });
                }
                n
            }
        };
        let data = buf[2..2 + n].to_vec();
        let s = &buf[2 + n..2 + n + 4];
        Ok(RtRepr {
            frame_id,
            data,
            cycle_counter: u16::from_be_bytes([s[0], s[1]]),
            data_status: DataStatus(s[2]),
            transfer_status: s[3],
        })
    }

    /// The length [`RtRepr::emit`] writes: the C_SDU padded to 40, plus 6.
    pub fn buffer_len(&self) -> usize {
        self.data.len().max(MIN_C_SDU) + OVERHEAD
    }

    /// The frame bytes: a C_SDU shorter than 40 bytes is padded with zeros to 40; a longer one
    /// than 1440 is written as given (for negative tests; [`RtRepr::parse`] refuses it).
    pub fn emit(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(self.buffer_len());
        b.extend(self.frame_id.0.to_be_bytes());
        b.extend(&self.data);
        b.resize(2 + self.data.len().max(MIN_C_SDU), 0);
        b.extend(self.cycle_counter.to_be_bytes());
        b.push(self.data_status.0);
        b.push(self.transfer_status);
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An output frame of a PPO type 1 exchange padded to 40 bytes: frame id C001h; IOCS 80h of
    /// the DAP, then PKW 8 bytes + IOPS 80h, PZD 4 bytes + IOPS 80h, the rest zero; cycle
    /// counter 1F40h, data status 35h (primary, valid, run, ok), transfer status 00.
    fn frame() -> Vec<u8> {
        let mut b = vec![0xC0, 0x01];
        let mut c_sdu = vec![0x80];
        c_sdu.extend([0x11, 0x2C, 0, 0, 0, 0, 0, 0, 0x80]);
        c_sdu.extend([0x04, 0x7E, 0x20, 0x00, 0x80]);
        c_sdu.resize(40, 0);
        b.extend(c_sdu);
        b.extend([0x1F, 0x40, 0x35, 0x00]);
        b
    }

    #[test]
    fn fields_and_round_trip() {
        let b = frame();
        let r = RtRepr::parse(&b, None).unwrap();
        assert_eq!(r.frame_id, FrameId(0xC001));
        assert_eq!(r.data.len(), 40);
        assert_eq!(Iox(r.data[0]), Iox::GOOD);
        assert_eq!(r.cycle_counter, 0x1F40);
        assert_eq!(r.data_status, DataStatus::GOOD);
        assert!(r.data_status.primary() && r.data_status.data_valid() && r.data_status.run());
        assert!(r.data_status.station_ok() && !r.data_status.ignore());
        assert_eq!(r.transfer_status, 0);
        assert_eq!(r.emit(), b);
        assert_eq!(r.buffer_len(), b.len());
        assert_eq!(RtRepr::parse(&b, Some(40)), Ok(r));
    }

    #[test]
    fn short_data_is_padded_to_forty() {
        // Frame id 8000h, 3 data bytes, counter 0, data status 15h (run 10h, valid 04h,
        // primary 01h, bit 5 clear: station problem), transfer status 0.
        let r = RtRepr {
            frame_id: FrameId(0x8000),
            data: vec![1, 2, 3],
            cycle_counter: 0,
            data_status: DataStatus(0x15),
            transfer_status: 0,
        };
        let b = r.emit();
        assert_eq!(b.len(), 46);
        assert_eq!(&b[2..5], [1, 2, 3]);
        assert!(b[5..42].iter().all(|&x| x == 0));
        assert_eq!(&b[42..], [0, 0, 0x15, 0]);
        assert!(!DataStatus(0x15).station_ok());
        // With the IOCR's length of 3 the padding counts as Ethernet padding.
        let p = RtRepr::parse(&b, Some(3)).unwrap();
        assert_eq!(p.data, [1, 2, 3]);
        assert_eq!(p.data_status, DataStatus(0)); // the status sits after 40 bytes, not 3
    }

    #[test]
    fn lengths_are_checked() {
        let b = frame();
        for cut in 0..b.len() {
            assert!(RtRepr::parse(&b[..cut], None).is_err(), "cut {cut}");
            assert!(RtRepr::parse(&b[..cut], Some(40)).is_err(), "cut {cut}");
        }
        assert_eq!(
            RtRepr::parse(&b[..45], Some(40)),
            Err(Error::Truncated {
                what: "RT frame",
                need: 46,
                got: 45
            })
        );
        // Two bytes more than the IOCR's 40: a frame of another length.
        let mut x = b.clone();
        x.extend([0, 0]);
        assert_eq!(
            RtRepr::parse(&x, Some(40)),
            Err(Error::Trailing {
                what: "RT frame",
                extra: 2
            })
        );
        // An IOCR of 38 bytes: its frame is padded to 46 by the sender's Ethernet layer.
        assert!(RtRepr::parse(&b, Some(38)).is_ok());
        assert!(RtRepr::parse(&x, Some(38)).is_err());
        assert_eq!(
            RtRepr::parse(&b[..40], None),
            Err(Error::Invalid {
                field: "C_SDU length",
                value: 34,
                why: "outside 40..1440 bytes",
            })
        );
        let mut long = vec![0xC0, 0x01];
        long.resize(2 + MAX_C_SDU + 1 + 4, 0);
        assert!(matches!(
            RtRepr::parse(&long, None),
            Err(Error::Invalid { .. })
        ));
        assert!(RtRepr::parse(&long, Some(MAX_C_SDU + 1)).is_ok());
        assert!(RtRepr::parse(&long, Some(usize::MAX)).is_err());
    }

    #[test]
    fn iox_and_data_status_bits() {
        assert!(Iox::GOOD.is_good() && !Iox::GOOD.extension());
        assert_eq!(Iox::BAD_BY_CONTROLLER.instance(), 3);
        assert!(!Iox::BAD_BY_DEVICE.is_good());
        assert_eq!(format!("{:?}", Iox(0x40)), "Iox(40h bad by device)");
        let s = DataStatus::GOOD.with(DataStatus::RUN, false);
        assert_eq!(s, DataStatus(0x25));
        assert_eq!(
            format!("{:?}", s.with(DataStatus::IGNORE, true)),
            "DataStatus(A5h primary valid stop ok ignore)"
        );
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn rt(data: impl Strategy<Value = Vec<u8>>) -> impl Strategy<Value = RtRepr> {
            (any::<u16>(), data, any::<u16>(), any::<u8>(), any::<u8>()).prop_map(
                |(frame_id, data, cycle_counter, status, transfer_status)| RtRepr {
                    frame_id: FrameId(frame_id),
                    data,
                    cycle_counter,
                    data_status: DataStatus(status),
                    transfer_status,
                },
            )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            /// Without a known DataLength: C_SDUs of 40..=1440 bytes.
            #[test]
            fn emit_then_parse_round_trips(r in rt(vec(any::<u8>(), MIN_C_SDU..=MAX_C_SDU))) {
                let b = r.emit();
                prop_assert_eq!(b.len(), r.buffer_len());
                prop_assert_eq!(RtRepr::parse(&b, None), Ok(r.clone()));
                prop_assert_eq!(RtRepr::parse(&b, Some(r.data.len())), Ok(r));
            }

            /// A short C_SDU is sent padded to 40 (the standard's minimum) and read back so: the
            /// padding belongs to the C_SDU, the status follows it. (`parse` with `Some(n)`,
            /// n < 40, models a sender that leaves the padding to the Ethernet layer instead,
            /// `short_data_is_padded_to_forty`, so it is no inverse of `emit` there.)
            #[test]
            fn short_c_sdu_is_read_back_padded(r in rt(vec(any::<u8>(), 0..MIN_C_SDU))) {
                let b = r.emit();
                prop_assert_eq!(b.len(), r.buffer_len());
                let mut padded = r.clone();
                padded.data.resize(MIN_C_SDU, 0);
                prop_assert_eq!(RtRepr::parse(&b, None), Ok(padded.clone()));
                prop_assert_eq!(RtRepr::parse(&b, Some(MIN_C_SDU)), Ok(padded));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(
                bytes in vec(any::<u8>(), 0..64),
                n in proptest::option::of(prop_oneof![0usize..64, Just(usize::MAX)]),
            ) {
                let _ = RtRepr::parse(&bytes, n);
            }
        }
    }
}
