//! The ASnd services other than SDO (EPSG DS 301 §7.3.3.2 IdentResponse, §7.3.3.3
//! StatusResponse, §7.3.1 NMTCommand, §7.3.6 NMTRequest): their payload after the ServiceID.
//!
//! IdentResponse (158 bytes): 0 flags EN 10h, EC 08h; 1 PR/RS; 2 NMTStatus; 3 reserved;
//! 4 EPLVersion; 5 reserved; 6–9 FeatureFlags; 10–11 MTU; 12–13 PollInSize; 14–15 PollOutSize;
//! 16–19 ResponseTime; 20–21 reserved; 22–25 DeviceType; 26–29 VendorId; 30–33 ProductCode;
//! 34–37 RevisionNumber; 38–41 SerialNumber; 42–49 VendorSpecificExtension1; 50–65
//! VerifyConfiguration date/time and ApplicationSw date/time; 66–69 IPAddress; 70–73
//! SubnetMask; 74–77 DefaultGateway (the three in network order); 78–109 HostName; 110–157
//! VendorSpecificExtension2.
//!
//! StatusResponse: 0 flags; 1 PR/RS; 2 NMTStatus; 3–5 reserved; 6–13 StaticErrorBitField
//! (6 ERR_ErrorRegister_U8, 7 reserved, 8–13 device specific); 14.. ErrorCodeList, 20 bytes an
//! entry: EntryType (u16), ErrorCode (u16), TimeStamp (u64), AdditionalInformation (u64) — the
//! ERR_History_ADOM (1003h) entry format. BU 0620 §5.4.1.2 prints a 14-byte entry (entry type
//! in byte 0, error code in bytes 1–2, time stamp in bytes 3–4, FI id in byte 5, the FI error
//! code as ASCII in bytes 6–13): an erratum against DS 301's 20 bytes; the FI id and the FI
//! error code fit the 8 bytes of AdditionalInformation, where this crate's users put them.

use std::net::Ipv4Addr;

use super::nmt::{NmtCommand, NmtState};
use crate::wire::{Error, Reader};

/// Length of an IdentResponse payload.
pub const IDENT_RESPONSE_LEN: usize = 158;
/// Length of the fixed part of a StatusResponse payload.
pub const STATUS_RESPONSE_HEADER: usize = 14;
/// Length of one error entry.
pub const ERROR_ENTRY_LEN: usize = 20;
/// Length of the HostName field.
pub const HOSTNAME_LEN: usize = 32;

/// The exception and request flags every response of a CN carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Flags {
    /// EN: exception new.
    pub en: bool,
    /// EC: exception clear.
    pub ec: bool,
    /// PR: priority of pending requests (0..7).
    pub pr: u8,
    /// RS: pending requests (0..7).
    pub rs: u8,
}

impl Flags {
    fn parse(r: &mut Reader<'_>) -> Result<Flags, Error> {
        let f = r.u8("EN/EC flags")?;
        let prrs = r.u8("PR/RS")?;
        Ok(Flags {
            en: f & 0x10 != 0,
            ec: f & 0x08 != 0,
            pr: (prrs >> 3) & 0x07,
            rs: prrs & 0x07,
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        b.push(if self.en { 0x10 } else { 0 } | if self.ec { 0x08 } else { 0 });
        b.push(((self.pr & 7) << 3) | (self.rs & 7));
    }
}

/// An IdentResponse (answer to a SoA IdentRequest).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IdentResponse {
    /// EN/EC, PR/RS.
    pub flags: Flags,
    /// The node's NMT state.
    pub state: NmtState,
    /// EPLVersion (20h = V2.0).
    pub epl_version: u8,
    /// NMT_FeatureFlags_U32 (1F82h).
    pub feature_flags: u32,
    /// NMT_CycleTiming_REC.AsyncMTU_U16.
    pub mtu: u16,
    /// PReq payload size the node expects.
    pub poll_in_size: u16,
    /// PRes payload size the node sends.
    pub poll_out_size: u16,
    /// PRes response time (ns).
    pub response_time: u32,
    /// NMT_DeviceType_U32 (1000h).
    pub device_type: u32,
    /// 1018h/1 vendor id.
    pub vendor_id: u32,
    /// 1018h/2 product code.
    pub product_code: u32,
    /// 1018h/3 revision number.
    pub revision: u32,
    /// 1018h/4 serial number.
    pub serial: u32,
    /// VendorSpecificExtension1.
    pub vendor_ext1: u64,
    /// VerifyConfiguration date and time, ApplicationSw date and time.
    pub dates: [u32; 4],
    /// IP address.
    pub ip: Ipv4Addr,
    /// Subnet mask.
    pub subnet: Ipv4Addr,
    /// Default gateway.
    pub gateway: Ipv4Addr,
    /// Host name (NUL-padded on the wire).
    pub hostname: String,
    /// VendorSpecificExtension2.
    pub vendor_ext2: [u8; 48],
}

fn ipv4(r: &mut Reader<'_>, what: &'static str) -> Result<Ipv4Addr, Error> {
    let b = r.bytes(4, what)?;
    Ok(Ipv4Addr::new(b[0], b[1], b[2], b[3]))
}

fn u64le(r: &mut Reader<'_>, what: &'static str) -> Result<u64, Error> {
    let b = r.bytes(8, what)?;
    let mut a = [0u8; 8];
    a.copy_from_slice(b);
    Ok(u64::from_le_bytes(a))
}

impl IdentResponse {
    /// Parses an IdentResponse payload (bytes after the ServiceID; padding may follow).
    pub fn parse(payload: &[u8]) -> Result<IdentResponse, Error> {
        let mut r = Reader::new(payload);
        let flags = Flags::parse(&mut r)?;
        let state = NmtState(r.u8("IdentResponse NMTStatus")?);
        r.u8("IdentResponse reserved")?;
        let epl_version = r.u8("IdentResponse EPLVersion")?;
        r.u8("IdentResponse reserved")?;
        let feature_flags = r.u32("IdentResponse FeatureFlags")?;
        let mtu = r.u16("IdentResponse MTU")?;
        let poll_in_size = r.u16("IdentResponse PollInSize")?;
        let poll_out_size = r.u16("IdentResponse PollOutSize")?;
        let response_time = r.u32("IdentResponse ResponseTime")?;
        r.u16("IdentResponse reserved")?;
        let device_type = r.u32("IdentResponse DeviceType")?;
        let vendor_id = r.u32("IdentResponse VendorId")?;
        let product_code = r.u32("IdentResponse ProductCode")?;
        let revision = r.u32("IdentResponse RevisionNumber")?;
        let serial = r.u32("IdentResponse SerialNumber")?;
        let vendor_ext1 = u64le(&mut r, "IdentResponse VendorSpecificExtension1")?;
        let mut dates = [0u32; 4];
        for d in &mut dates {
            *d = r.u32("IdentResponse configuration/application dates")?;
        }
        let ip = ipv4(&mut r, "IdentResponse IPAddress")?;
        let subnet = ipv4(&mut r, "IdentResponse SubnetMask")?;
        let gateway = ipv4(&mut r, "IdentResponse DefaultGateway")?;
        let name = r.bytes(HOSTNAME_LEN, "IdentResponse HostName")?;
        let end = name.iter().position(|&c| c == 0).unwrap_or(HOSTNAME_LEN);
        let hostname = String::from_utf8_lossy(&name[..end]).into_owned();
        let mut vendor_ext2 = [0u8; 48];
        vendor_ext2.copy_from_slice(r.bytes(48, "IdentResponse VendorSpecificExtension2")?);
        Ok(IdentResponse {
            flags,
            state,
            epl_version,
            feature_flags,
            mtu,
            poll_in_size,
            poll_out_size,
            response_time,
            device_type,
            vendor_id,
            product_code,
            revision,
            serial,
            vendor_ext1,
            dates,
            ip,
            subnet,
            gateway,
            hostname,
            vendor_ext2,
        })
    }

    /// The payload bytes; a host name longer than 32 bytes is [`Error::TooLong`].
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        if self.hostname.len() > HOSTNAME_LEN {
            return Err(Error::TooLong {
                what: "IdentResponse HostName",
                len: self.hostname.len(),
                max: HOSTNAME_LEN,
            });
        }
        let mut b = Vec::with_capacity(IDENT_RESPONSE_LEN);
        self.flags.emit(&mut b);
        b.extend([self.state.0, 0, self.epl_version, 0]);
        b.extend(self.feature_flags.to_le_bytes());
        for v in [self.mtu, self.poll_in_size, self.poll_out_size] {
            b.extend(v.to_le_bytes());
        }
        b.extend(self.response_time.to_le_bytes());
        b.extend([0, 0]);
        for v in [
            self.device_type,
            self.vendor_id,
            self.product_code,
            self.revision,
            self.serial,
        ] {
            b.extend(v.to_le_bytes());
        }
        b.extend(self.vendor_ext1.to_le_bytes());
        for d in self.dates {
            b.extend(d.to_le_bytes());
        }
        for a in [self.ip, self.subnet, self.gateway] {
            b.extend(a.octets());
        }
        let mut name = [0u8; HOSTNAME_LEN];
        name[..self.hostname.len()].copy_from_slice(self.hostname.as_bytes());
        b.extend(name);
        b.extend(self.vendor_ext2);
        debug_assert_eq!(b.len(), IDENT_RESPONSE_LEN);
        Ok(b)
    }
}

/// One entry of the error history (ERR_History_ADOM 1003h) and of a StatusResponse's
/// ErrorCodeList.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ErrorEntry {
    /// EntryType: bits 0–11 profile, 12–13 mode (1 status active, 2 status cleared, 3 history
    /// event), 14 reserved, 15 "warning/error" per profile.
    pub entry_type: u16,
    /// The error code (BU 0620 §5.4.1.2 table: 8100h bus timeout, …).
    pub code: u16,
    /// Time stamp (NetTime of the event).
    pub time: u64,
    /// AdditionalInformation: the NORD interface puts the FI id in byte 0 and the FI error
    /// code (P700, ASCII) in bytes 1–7.
    pub info: u64,
}

impl ErrorEntry {
    /// EntryType mode "history entry" (event occurred) with the device profile: the entries
    /// of 1003h.
    pub const MODE_HISTORY: u16 = 3 << 12;

    /// The entry type's mode bits (12–13).
    pub fn mode(&self) -> u8 {
        ((self.entry_type >> 12) & 0x03) as u8
    }

    /// Parses one 20-byte entry.
    pub fn parse(bytes: &[u8]) -> Result<ErrorEntry, Error> {
        let mut r = Reader::new(bytes);
        let e = ErrorEntry {
            entry_type: r.u16("error entry EntryType")?,
            code: r.u16("error entry ErrorCode")?,
            time: u64le(&mut r, "error entry TimeStamp")?,
            info: u64le(&mut r, "error entry AdditionalInformation")?,
        };
        r.finish("error entry")?;
        Ok(e)
    }

    /// The 20 bytes.
    pub fn emit(&self) -> [u8; ERROR_ENTRY_LEN] {
        let mut b = [0u8; ERROR_ENTRY_LEN];
        b[..2].copy_from_slice(&self.entry_type.to_le_bytes());
        b[2..4].copy_from_slice(&self.code.to_le_bytes());
        b[4..12].copy_from_slice(&self.time.to_le_bytes());
        b[12..].copy_from_slice(&self.info.to_le_bytes());
        b
    }
}

/// A StatusResponse (answer to a SoA StatusRequest).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct StatusResponse {
    /// EN/EC, PR/RS.
    pub flags: Flags,
    /// The node's NMT state.
    pub state: NmtState,
    /// ERR_ErrorRegister_U8 (1001h).
    pub error_register: u8,
    /// The 6 device-specific bytes of the static error bit field.
    pub specific: [u8; 6],
    /// The error entries.
    pub entries: Vec<ErrorEntry>,
}

impl StatusResponse {
    /// Parses a StatusResponse payload. Its list has no count: every whole 20-byte entry up
    /// to the end counts, and a trailing run of zero bytes (Ethernet padding) is not an entry.
    pub fn parse(payload: &[u8]) -> Result<StatusResponse, Error> {
        let mut r = Reader::new(payload);
        let flags = Flags::parse(&mut r)?;
        let state = NmtState(r.u8("StatusResponse NMTStatus")?);
        r.bytes(3, "StatusResponse reserved")?;
        let error_register = r.u8("StatusResponse ErrorRegister")?;
        r.u8("StatusResponse reserved")?;
        let mut specific = [0u8; 6];
        specific.copy_from_slice(r.bytes(6, "StatusResponse StaticErrorBitField")?);
        let mut entries = Vec::new();
        while r.remaining() >= ERROR_ENTRY_LEN {
            let e = ErrorEntry::parse(r.bytes(ERROR_ENTRY_LEN, "error entry")?)?;
            if e == ErrorEntry::default() {
                break;
            }
            entries.push(e);
        }
        Ok(StatusResponse {
            flags,
            state,
            error_register,
            specific,
            entries,
        })
    }

    /// The payload bytes.
    pub fn emit(&self) -> Vec<u8> {
        let mut b =
            Vec::with_capacity(STATUS_RESPONSE_HEADER + ERROR_ENTRY_LEN * self.entries.len());
        self.flags.emit(&mut b);
        b.extend([self.state.0, 0, 0, 0, self.error_register, 0]);
        b.extend(self.specific);
        for e in &self.entries {
            b.extend(e.emit());
        }
        b
    }
}

/// An NMT command from the MN (ASnd service 4): 0 NMTCommandID, 1 reserved, 2.. data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NmtCommandFrame {
    /// The command.
    pub command: NmtCommand,
    /// NMTCommandData (node lists of the extended commands, a host name…).
    pub data: Vec<u8>,
}

impl NmtCommandFrame {
    /// Parses the payload.
    pub fn parse(payload: &[u8]) -> Result<NmtCommandFrame, Error> {
        let mut r = Reader::new(payload);
        let command = NmtCommand(r.u8("NMTCommandID")?);
        r.u8("NMTCommand reserved")?;
        Ok(NmtCommandFrame {
            command,
            data: r.rest().to_vec(),
        })
    }

    /// The payload bytes.
    pub fn emit(&self) -> Vec<u8> {
        let mut b = vec![self.command.0, 0];
        b.extend(&self.data);
        b
    }
}

/// An NMT request from a CN (ASnd service 3): 0 NMTRequestedCommandID, 1 target, 2.. data.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NmtRequestFrame {
    /// The command asked for.
    pub command: NmtCommand,
    /// The node it is for.
    pub target: u8,
    /// NMTRequestedCommandData.
    pub data: Vec<u8>,
}

impl NmtRequestFrame {
    /// Parses the payload.
    pub fn parse(payload: &[u8]) -> Result<NmtRequestFrame, Error> {
        let mut r = Reader::new(payload);
        Ok(NmtRequestFrame {
            command: NmtCommand(r.u8("NMTRequestedCommandID")?),
            target: r.u8("NMTRequestedCommandTarget")?,
            data: r.rest().to_vec(),
        })
    }

    /// The payload bytes.
    pub fn emit(&self) -> Vec<u8> {
        let mut b = vec![self.command.0, self.target];
        b.extend(&self.data);
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ident() -> IdentResponse {
        IdentResponse {
            flags: Flags::default(),
            state: NmtState::PRE_OPERATIONAL_2,
            epl_version: 0x20,
            feature_flags: 0x0000_0045,
            mtu: 300,
            poll_in_size: 96,
            poll_out_size: 96,
            response_time: 20_000,
            device_type: 0,
            vendor_id: 0xED,
            product_code: 0x550,
            revision: 0x0001_0000,
            serial: 7,
            vendor_ext1: 0,
            dates: [0; 4],
            ip: Ipv4Addr::new(192, 168, 100, 1),
            subnet: Ipv4Addr::new(255, 255, 255, 0),
            gateway: Ipv4Addr::new(192, 168, 100, 254),
            hostname: "1-000000ED".into(),
            vendor_ext2: [0; 48],
        }
    }

    #[test]
    fn ident_response_offsets() {
        let b = ident().emit().unwrap();
        assert_eq!(b.len(), IDENT_RESPONSE_LEN);
        assert_eq!(b[2], 0x5D); // NMTStatus
        assert_eq!(b[4], 0x20); // EPLVersion
        assert_eq!(&b[26..30], &[0xED, 0, 0, 0]); // VendorId
        assert_eq!(&b[66..70], &[192, 168, 100, 1]); // IPAddress, network order
        assert_eq!(&b[78..88], b"1-000000ED");
        assert_eq!(IdentResponse::parse(&b).unwrap(), ident());
        assert!(matches!(
            IdentResponse::parse(&b[..100]),
            Err(Error::Truncated {
                what: "IdentResponse HostName",
                ..
            })
        ));
        let mut long = ident();
        long.hostname = "x".repeat(33);
        assert!(matches!(long.emit(), Err(Error::TooLong { .. })));
    }

    #[test]
    fn status_response_entries_and_padding() {
        let s = StatusResponse {
            flags: Flags {
                en: true,
                ..Flags::default()
            },
            state: NmtState::OPERATIONAL,
            error_register: 0x11,
            specific: [0; 6],
            entries: vec![ErrorEntry {
                entry_type: ErrorEntry::MODE_HISTORY | 0x0002,
                code: 0x8100,
                time: 5,
                info: 0x3130_3031,
            }],
        };
        let mut b = s.emit();
        assert_eq!(&b[..3], &[0x10, 0x00, 0xFD]);
        assert_eq!(b[6], 0x11);
        assert_eq!(&b[14..18], &[0x02, 0x30, 0x00, 0x81]);
        b.extend([0u8; 26]); // Ethernet padding: not entries
        assert_eq!(StatusResponse::parse(&b).unwrap(), s);
        assert_eq!(s.entries[0].mode(), 3);
        assert!(StatusResponse::parse(&b[..10]).is_err());
    }

    #[test]
    fn nmt_command_and_request() {
        let c = NmtCommandFrame {
            command: NmtCommand::START_NODE,
            data: vec![],
        };
        assert_eq!(c.emit(), [0x21, 0]);
        assert_eq!(NmtCommandFrame::parse(&[0x21, 0, 9]).unwrap().data, [9]);
        assert!(NmtCommandFrame::parse(&[0x21]).is_err());
        let q = NmtRequestFrame::parse(&[0x24, 1]).unwrap();
        assert_eq!(
            (q.command, q.target),
            (NmtCommand::ENABLE_READY_TO_OPERATE, 1)
        );
        assert_eq!(q.emit(), [0x24, 1]);
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn flags() -> impl Strategy<Value = Flags> {
            (any::<bool>(), any::<bool>(), 0u8..=7, 0u8..=7).prop_map(|(en, ec, pr, rs)| Flags {
                en,
                ec,
                pr,
                rs,
            })
        }

        fn ip() -> impl Strategy<Value = Ipv4Addr> {
            any::<[u8; 4]>().prop_map(Ipv4Addr::from)
        }

        /// A host name the field carries: no NUL (the padding), at most 32 bytes of UTF-8.
        fn hostname() -> impl Strategy<Value = String> {
            vec(
                any::<char>().prop_filter("NUL pads the field", |c| *c != '\0'),
                0..=32,
            )
            .prop_map(|cs| {
                let mut s = String::new();
                for c in cs {
                    if s.len() + c.len_utf8() > HOSTNAME_LEN {
                        break;
                    }
                    s.push(c);
                }
                s
            })
        }

        fn ident() -> impl Strategy<Value = IdentResponse> {
            (
                (
                    flags(),
                    any::<u8>(),
                    any::<u8>(),
                    any::<u32>(),
                    any::<u16>(),
                    any::<u16>(),
                    any::<u16>(),
                ),
                (
                    any::<u32>(),
                    any::<u32>(),
                    any::<u32>(),
                    any::<u32>(),
                    any::<u32>(),
                    any::<u32>(),
                ),
                (
                    any::<u64>(),
                    any::<[u32; 4]>(),
                    ip(),
                    ip(),
                    ip(),
                    hostname(),
                    vec(any::<u8>(), 48),
                ),
            )
                .prop_map(
                    |(
                        (
                            flags,
                            state,
                            epl_version,
                            feature_flags,
                            mtu,
                            poll_in_size,
                            poll_out_size,
                        ),
                        (response_time, device_type, vendor_id, product_code, revision, serial),
                        (vendor_ext1, dates, ip, subnet, gateway, hostname, ext2),
                    )| {
                        let mut vendor_ext2 = [0u8; 48];
                        vendor_ext2.copy_from_slice(&ext2);
                        IdentResponse {
                            flags,
                            state: NmtState(state),
                            epl_version,
                            feature_flags,
                            mtu,
                            poll_in_size,
                            poll_out_size,
                            response_time,
                            device_type,
                            vendor_id,
                            product_code,
                            revision,
                            serial,
                            vendor_ext1,
                            dates,
                            ip,
                            subnet,
                            gateway,
                            hostname,
                            vendor_ext2,
                        }
                    },
                )
        }

        fn entry() -> impl Strategy<Value = ErrorEntry> {
            (any::<u16>(), any::<u16>(), any::<u64>(), any::<u64>()).prop_map(
                |(entry_type, code, time, info)| ErrorEntry {
                    entry_type,
                    code,
                    time,
                    info,
                },
            )
        }

        /// A StatusResponse; an all-zero entry ends the list (it is Ethernet padding), so the
        /// entries carried are not all zero.
        fn status() -> impl Strategy<Value = StatusResponse> {
            (
                flags(),
                any::<u8>(),
                any::<u8>(),
                any::<[u8; 6]>(),
                vec(
                    entry().prop_filter("zero entry is padding", |e| *e != ErrorEntry::default()),
                    0..4,
                ),
            )
                .prop_map(|(flags, state, error_register, specific, entries)| {
                    StatusResponse {
                        flags,
                        state: NmtState(state),
                        error_register,
                        specific,
                        entries,
                    }
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn ident_response_round_trips(i in ident()) {
                let b = i.emit().unwrap();
                prop_assert_eq!(b.len(), IDENT_RESPONSE_LEN);
                prop_assert_eq!(IdentResponse::parse(&b), Ok(i));
            }

            #[test]
            fn error_entry_round_trips(e in entry()) {
                prop_assert_eq!(ErrorEntry::parse(&e.emit()), Ok(e));
            }

            #[test]
            fn status_response_round_trips(s in status(), padding in 0usize..24) {
                let mut b = s.emit();
                prop_assert_eq!(b.len(), STATUS_RESPONSE_HEADER + ERROR_ENTRY_LEN * s.entries.len());
                prop_assert_eq!(StatusResponse::parse(&b), Ok(s.clone()));
                b.resize(b.len() + padding, 0);
                prop_assert_eq!(StatusResponse::parse(&b), Ok(s));
            }

            #[test]
            fn nmt_frames_round_trip(command in any::<u8>(), target in any::<u8>(), data in vec(any::<u8>(), 0..16)) {
                let c = NmtCommandFrame { command: NmtCommand(command), data: data.clone() };
                prop_assert_eq!(NmtCommandFrame::parse(&c.emit()), Ok(c));
                let r = NmtRequestFrame { command: NmtCommand(command), target, data };
                prop_assert_eq!(NmtRequestFrame::parse(&r.emit()), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..200)) {
                let _ = IdentResponse::parse(&bytes);
                let _ = ErrorEntry::parse(&bytes);
                let _ = StatusResponse::parse(&bytes);
                let _ = NmtCommandFrame::parse(&bytes);
                let _ = NmtRequestFrame::parse(&bytes);
            }
        }
    }
}
