//! CIP message-router requests and responses, services and general status codes.
//!
//! Request: service, path size (words), padded EPATH, service data.
//! Response: service | 80h, reserved, general status, extended status size (words), extended
//! status words, service data.

use std::fmt;

use super::epath::EPath;
use super::wire::Put;
use crate::wire::{Error, Reader};

/// CIP object class ids.
pub mod class {
    /// Identity.
    pub const IDENTITY: u16 = 0x01;
    /// Message Router.
    pub const MESSAGE_ROUTER: u16 = 0x02;
    /// Assembly.
    pub const ASSEMBLY: u16 = 0x04;
    /// Connection Manager.
    pub const CONNECTION_MANAGER: u16 = 0x06;
    /// TCP/IP Interface.
    pub const TCP_IP: u16 = 0xF5;
    /// Ethernet Link.
    pub const ETHERNET_LINK: u16 = 0xF6;
    /// Device Level Ring (DLR, CIP Vol 2 chapter 5).
    pub const DLR: u16 = 0x47;
}

/// A CIP service code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Service(pub u8);

impl Service {
    /// Get_Attributes_All.
    pub const GET_ATTRIBUTES_ALL: Service = Service(0x01);
    /// Set_Attributes_All.
    pub const SET_ATTRIBUTES_ALL: Service = Service(0x02);
    /// Reset.
    pub const RESET: Service = Service(0x05);
    /// Multiple_Service_Packet.
    pub const MULTIPLE_SERVICE: Service = Service(0x0A);
    /// Get_Attribute_Single.
    pub const GET_ATTRIBUTE_SINGLE: Service = Service(0x0E);
    /// Set_Attribute_Single.
    pub const SET_ATTRIBUTE_SINGLE: Service = Service(0x10);
    /// Forward_Close (Connection Manager).
    pub const FORWARD_CLOSE: Service = Service(0x4E);
    /// Unconnected_Send (Connection Manager).
    pub const UNCONNECTED_SEND: Service = Service(0x52);
    /// Forward_Open (Connection Manager).
    pub const FORWARD_OPEN: Service = Service(0x54);
    /// Large_Forward_Open (Connection Manager).
    pub const LARGE_FORWARD_OPEN: Service = Service(0x5B);

    /// The service's name, if it is one this stack knows.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            Service::GET_ATTRIBUTES_ALL => "Get_Attributes_All",
            Service::SET_ATTRIBUTES_ALL => "Set_Attributes_All",
            Service::RESET => "Reset",
            Service::MULTIPLE_SERVICE => "Multiple_Service_Packet",
            Service::GET_ATTRIBUTE_SINGLE => "Get_Attribute_Single",
            Service::SET_ATTRIBUTE_SINGLE => "Set_Attribute_Single",
            Service::FORWARD_CLOSE => "Forward_Close",
            Service::UNCONNECTED_SEND => "Unconnected_Send",
            Service::FORWARD_OPEN => "Forward_Open",
            Service::LARGE_FORWARD_OPEN => "Large_Forward_Open",
            _ => return None,
        })
    }
}

impl fmt::Display for Service {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{n}"),
            None => write!(f, "service {:02X}h", self.0),
        }
    }
}

/// A CIP general status code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GeneralStatus(pub u8);

impl GeneralStatus {
    /// Success.
    pub const SUCCESS: GeneralStatus = GeneralStatus(0x00);
    /// Connection failure (extended status names the reason).
    pub const CONNECTION_FAILURE: GeneralStatus = GeneralStatus(0x01);
    /// Resource unavailable.
    pub const RESOURCE_UNAVAILABLE: GeneralStatus = GeneralStatus(0x02);
    /// Invalid parameter value.
    pub const INVALID_PARAMETER_VALUE: GeneralStatus = GeneralStatus(0x03);
    /// Path segment error: the path could not be parsed.
    pub const PATH_SEGMENT_ERROR: GeneralStatus = GeneralStatus(0x04);
    /// Path destination unknown: class or instance does not exist.
    pub const PATH_DESTINATION_UNKNOWN: GeneralStatus = GeneralStatus(0x05);
    /// Service not supported.
    pub const SERVICE_NOT_SUPPORTED: GeneralStatus = GeneralStatus(0x08);
    /// Invalid attribute value.
    pub const INVALID_ATTRIBUTE_VALUE: GeneralStatus = GeneralStatus(0x09);
    /// Object state conflict.
    pub const OBJECT_STATE_CONFLICT: GeneralStatus = GeneralStatus(0x0C);
    /// Attribute not settable.
    pub const ATTRIBUTE_NOT_SETTABLE: GeneralStatus = GeneralStatus(0x0E);
    /// Privilege violation.
    pub const PRIVILEGE_VIOLATION: GeneralStatus = GeneralStatus(0x0F);
    /// Device state conflict.
    pub const DEVICE_STATE_CONFLICT: GeneralStatus = GeneralStatus(0x10);
    /// Reply data too large.
    pub const REPLY_DATA_TOO_LARGE: GeneralStatus = GeneralStatus(0x11);
    /// Not enough data.
    pub const NOT_ENOUGH_DATA: GeneralStatus = GeneralStatus(0x13);
    /// Attribute not supported.
    pub const ATTRIBUTE_NOT_SUPPORTED: GeneralStatus = GeneralStatus(0x14);
    /// Too much data.
    pub const TOO_MUCH_DATA: GeneralStatus = GeneralStatus(0x15);
    /// Object does not exist.
    pub const OBJECT_DOES_NOT_EXIST: GeneralStatus = GeneralStatus(0x16);
    /// Vendor specific error.
    pub const VENDOR_SPECIFIC: GeneralStatus = GeneralStatus(0x1F);
    /// Invalid parameter.
    pub const INVALID_PARAMETER: GeneralStatus = GeneralStatus(0x20);
    /// Path size invalid.
    pub const PATH_SIZE_INVALID: GeneralStatus = GeneralStatus(0x26);

    /// The status's name.
    pub fn name(self) -> &'static str {
        match self.0 {
            0x00 => "success",
            0x01 => "connection failure",
            0x02 => "resource unavailable",
            0x03 => "invalid parameter value",
            0x04 => "path segment error",
            0x05 => "path destination unknown",
            0x06 => "partial transfer",
            0x08 => "service not supported",
            0x09 => "invalid attribute value",
            0x0C => "object state conflict",
            0x0E => "attribute not settable",
            0x0F => "privilege violation",
            0x10 => "device state conflict",
            0x11 => "reply data too large",
            0x13 => "not enough data",
            0x14 => "attribute not supported",
            0x15 => "too much data",
            0x16 => "object does not exist",
            0x1F => "vendor specific error",
            0x20 => "invalid parameter",
            0x26 => "path size invalid",
            _ => "other status",
        }
    }
}

impl fmt::Display for GeneralStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:02X}h ({})", self.0, self.name())
    }
}

/// A message-router request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MrRequest {
    /// Service code.
    pub service: u8,
    /// Request path.
    pub path: EPath,
    /// Service data.
    pub data: Vec<u8>,
}

/// The first bytes of a request, before its path is understood: a malformed path still has a
/// service to answer to.
pub fn request_service(bytes: &[u8]) -> Option<u8> {
    bytes.first().copied()
}

impl MrRequest {
    /// Parses a request filling `bytes`.
    pub fn parse(bytes: &[u8]) -> Result<MrRequest, Error> {
        let mut r = Reader::new(bytes);
        let service = r.u8("request service")?;
        if service & 0x80 != 0 {
            return Err(Error::Invalid {
                field: "request service",
                value: u32::from(service),
                why: "the reply bit (80h) is set",
            });
        }
        let words = usize::from(r.u8("request path size")?);
        let path = r.sized(words * 2, "request path size")?;
        let path = EPath::parse(path)?;
        Ok(MrRequest {
            service,
            path,
            data: r.rest().to_vec(),
        })
    }

    /// The bytes.
    pub fn emit(&self) -> Vec<u8> {
        let path = self.path.emit();
        let mut out = Vec::with_capacity(2 + path.len() + self.data.len());
        out.put_u8(self.service);
        out.put_u8((path.len() / 2) as u8);
        out.extend(path);
        out.extend_from_slice(&self.data);
        out
    }
}

/// A message-router response.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MrResponse {
    /// The request's service (without the reply bit).
    pub service: u8,
    /// General status.
    pub general: u8,
    /// Extended status words.
    pub extended: Vec<u16>,
    /// Reply data.
    pub data: Vec<u8>,
}

impl MrResponse {
    /// A success reply with data.
    pub fn ok(service: u8, data: Vec<u8>) -> MrResponse {
        MrResponse {
            service,
            general: 0,
            extended: Vec::new(),
            data,
        }
    }

    /// An error reply.
    pub fn error(service: u8, status: GeneralStatus) -> MrResponse {
        MrResponse {
            service,
            general: status.0,
            extended: Vec::new(),
            data: Vec::new(),
        }
    }

    /// Parses a response filling `bytes`.
    pub fn parse(bytes: &[u8]) -> Result<MrResponse, Error> {
        let mut r = Reader::new(bytes);
        let service = r.u8("reply service")?;
        if service & 0x80 == 0 {
            return Err(Error::Invalid {
                field: "reply service",
                value: u32::from(service),
                why: "the reply bit (80h) is clear",
            });
        }
        r.u8("reply reserved byte")?;
        let general = r.u8("general status")?;
        let words = usize::from(r.u8("extended status size")?);
        let mut extended = Vec::with_capacity(words);
        for _ in 0..words {
            extended.push(r.u16("extended status")?);
        }
        Ok(MrResponse {
            service: service & 0x7F,
            general,
            extended,
            data: r.rest().to_vec(),
        })
    }

    /// The bytes.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(4 + 2 * self.extended.len() + self.data.len());
        out.put_u8(self.service | 0x80);
        out.put_u8(0);
        out.put_u8(self.general);
        out.put_u8(self.extended.len() as u8);
        for e in &self.extended {
            out.put_u16(*e);
        }
        out.extend_from_slice(&self.data);
        out
    }

    /// General status as a typed value.
    pub fn status(&self) -> GeneralStatus {
        GeneralStatus(self.general)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn get_attribute_single_p102_of_fi5_set3() {
        // BU 0620 §2.3.5: FI 5 → class 105; set 3 → instance 2; attribute = 102.
        let req = MrRequest {
            service: Service::GET_ATTRIBUTE_SINGLE.0,
            path: EPath::attribute(105, 2, 102),
            data: vec![],
        };
        let b = req.emit();
        assert_eq!(b, [0x0E, 0x03, 0x20, 105, 0x24, 0x02, 0x30, 102]);
        assert_eq!(MrRequest::parse(&b).unwrap(), req);
    }

    #[test]
    fn responses_round_trip_with_extended_status() {
        let resp = MrResponse {
            service: 0x54,
            general: 0x01,
            extended: vec![0x0127],
            data: vec![],
        };
        let b = resp.emit();
        assert_eq!(b, [0xD4, 0, 0x01, 0x01, 0x27, 0x01]);
        assert_eq!(MrResponse::parse(&b).unwrap(), resp);
    }

    #[test]
    fn a_path_size_beyond_the_message_is_an_error() {
        assert!(matches!(
            MrRequest::parse(&[0x0E, 0x05, 0x20, 0x01]),
            Err(Error::Length {
                value: 10,
                available: 2,
                ..
            })
        ));
        assert!(MrRequest::parse(&[0x8E, 0x00]).is_err());
        assert!(MrResponse::parse(&[0x0E, 0, 0, 0]).is_err());
        assert!(MrResponse::parse(&[0x8E, 0, 0, 2, 1]).is_err());
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Request paths as clients send them (the path codec has its own properties in
        /// `epath`): class/instance/attribute or class/instance, 8- to 32-bit instances.
        fn path() -> impl Strategy<Value = EPath> {
            (
                any::<u16>(),
                any::<u32>(),
                proptest::option::of(any::<u16>()),
            )
                .prop_map(|(class, instance, attribute)| match attribute {
                    Some(a) => EPath::attribute(class, instance, a),
                    None => EPath::object(class, instance),
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            /// A request: a service without the reply bit.
            #[test]
            fn request_round_trips(service in 0u8..=0x7F, path in path(), data in vec(any::<u8>(), 0..24)) {
                let r = MrRequest { service, path, data };
                prop_assert_eq!(request_service(&r.emit()), Some(service));
                prop_assert_eq!(MrRequest::parse(&r.emit()), Ok(r));
            }

            /// A response: the service without the reply bit, at most 255 extended status
            /// words (the size is one byte).
            #[test]
            fn response_round_trips(
                service in 0u8..=0x7F,
                general in any::<u8>(),
                extended in vec(any::<u16>(), 0..4),
                data in vec(any::<u8>(), 0..24),
            ) {
                let r = MrResponse { service, general, extended, data };
                prop_assert_eq!(MrResponse::parse(&r.emit()), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..32)) {
                let _ = MrRequest::parse(&bytes);
                let _ = MrResponse::parse(&bytes);
                let _ = request_service(&bytes);
            }
        }
    }
}
