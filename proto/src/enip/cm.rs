//! Connection Manager services: Forward_Open, Large_Forward_Open, Forward_Close and
//! Unconnected_Send, with the extended status codes of connection failures.

use super::cip::MrRequest;
use super::epath::EPath;
use super::wire::Put;
use crate::wire::{Error, Reader};

/// Extended status codes of the Connection Manager (general status 01h).
pub mod ext {
    /// Connection in use or duplicate Forward_Open.
    pub const CONNECTION_IN_USE: u16 = 0x0100;
    /// Transport class and trigger combination not supported.
    pub const TRANSPORT_NOT_SUPPORTED: u16 = 0x0103;
    /// Ownership conflict (a second exclusive owner).
    pub const OWNERSHIP_CONFLICT: u16 = 0x0106;
    /// Target connection not found (Forward_Close).
    pub const CONNECTION_NOT_FOUND: u16 = 0x0107;
    /// Invalid network connection parameter.
    pub const INVALID_NETWORK_PARAMETER: u16 = 0x0108;
    /// RPI not supported.
    pub const RPI_NOT_SUPPORTED: u16 = 0x0111;
    /// RPI values not acceptable.
    pub const RPI_NOT_ACCEPTABLE: u16 = 0x0112;
    /// Out of connections.
    pub const OUT_OF_CONNECTIONS: u16 = 0x0113;
    /// Vendor id or product code mismatch (electronic key).
    pub const VENDOR_OR_PRODUCT_MISMATCH: u16 = 0x0114;
    /// Device type mismatch (electronic key).
    pub const DEVICE_TYPE_MISMATCH: u16 = 0x0115;
    /// Revision mismatch (electronic key).
    pub const REVISION_MISMATCH: u16 = 0x0116;
    /// A listen-only connection without an owner connection to listen to.
    pub const NON_LISTEN_ONLY_NOT_OPENED: u16 = 0x0119;
    /// The target object's connections are used up.
    pub const TARGET_OUT_OF_CONNECTIONS: u16 = 0x011A;
    /// Transport class not supported.
    pub const TRANSPORT_CLASS_NOT_SUPPORTED: u16 = 0x011C;
    /// Production trigger not supported.
    pub const TRIGGER_NOT_SUPPORTED: u16 = 0x011D;
    /// Invalid O→T connection type.
    pub const INVALID_O_T_TYPE: u16 = 0x0123;
    /// Invalid T→O connection type.
    pub const INVALID_T_O_TYPE: u16 = 0x0124;
    /// Invalid O→T connection size (a second word gives the right size).
    pub const INVALID_O_T_SIZE: u16 = 0x0127;
    /// Invalid T→O connection size (a second word gives the right size).
    pub const INVALID_T_O_SIZE: u16 = 0x0128;
    /// Invalid configuration application path.
    pub const INVALID_CONFIG_PATH: u16 = 0x0129;
    /// Invalid consuming application path.
    pub const INVALID_CONSUMING_PATH: u16 = 0x012A;
    /// Invalid producing application path.
    pub const INVALID_PRODUCING_PATH: u16 = 0x012B;
    /// Connection timeout multiplier not acceptable.
    pub const TIMEOUT_MULTIPLIER_NOT_ACCEPTABLE: u16 = 0x0133;
    /// Parameter error in Unconnected_Send.
    pub const UNCONNECTED_SEND_PARAMETER: u16 = 0x0205;
    /// Port not available (routing).
    pub const PORT_NOT_AVAILABLE: u16 = 0x0311;
    /// Invalid segment in the connection path.
    pub const INVALID_SEGMENT: u16 = 0x0315;
}

/// Network connection parameters (16-bit in Forward_Open, 32-bit in Large_Forward_Open).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NetParams {
    /// Connection size in bytes.
    pub size: u16,
    /// Variable (true) or fixed size.
    pub variable: bool,
    /// Priority (0 low, 1 high, 2 scheduled, 3 urgent).
    pub priority: u8,
    /// Connection type: 0 null, 1 multicast, 2 point-to-point.
    pub kind: u8,
    /// Redundant owner.
    pub redundant_owner: bool,
}

/// Connection type in [`NetParams::kind`].
pub mod kind {
    /// Null: no data in this direction.
    pub const NULL: u8 = 0;
    /// Multicast.
    pub const MULTICAST: u8 = 1;
    /// Point to point.
    pub const POINT_TO_POINT: u8 = 2;
}

impl NetParams {
    /// A fixed-size connection of `kind` (point to point, multicast), low priority, no
    /// redundant owner: what a scanner asks for unless told otherwise.
    pub fn fixed(size: u16, kind: u8) -> NetParams {
        NetParams {
            size,
            variable: false,
            priority: 0,
            kind,
            redundant_owner: false,
        }
    }

    /// From the 16-bit field.
    pub fn from_u16(v: u16) -> NetParams {
        NetParams {
            size: v & 0x01FF,
            variable: v & 0x0200 != 0,
            priority: ((v >> 10) & 3) as u8,
            kind: ((v >> 13) & 3) as u8,
            redundant_owner: v & 0x8000 != 0,
        }
    }

    /// The 16-bit field (sizes above 511 do not fit: use Large_Forward_Open).
    pub fn to_u16(self) -> u16 {
        (self.size & 0x01FF)
            | u16::from(self.variable) << 9
            | u16::from(self.priority & 3) << 10
            | u16::from(self.kind & 3) << 13
            | u16::from(self.redundant_owner) << 15
    }

    /// From the 32-bit field.
    pub fn from_u32(v: u32) -> NetParams {
        NetParams {
            size: (v & 0xFFFF) as u16,
            variable: v & (1 << 25) != 0,
            priority: ((v >> 26) & 3) as u8,
            kind: ((v >> 29) & 3) as u8,
            redundant_owner: v & (1 << 31) != 0,
        }
    }

    /// The 32-bit field.
    pub fn to_u32(self) -> u32 {
        u32::from(self.size)
            | u32::from(self.variable) << 25
            | u32::from(self.priority & 3) << 26
            | u32::from(self.kind & 3) << 29
            | u32::from(self.redundant_owner) << 31
    }
}

/// The transport type/trigger byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transport(pub u8);

impl Transport {
    /// Class 1, cyclic, client (an I/O connection as scanners open it).
    pub const CLASS1_CYCLIC: Transport = Transport(0x01);
    /// Class 3, application triggered, server (connected explicit messaging).
    pub const CLASS3: Transport = Transport(0xA3);

    /// Transport class 0..3.
    pub fn class(self) -> u8 {
        self.0 & 0x0F
    }
    /// Production trigger: 0 cyclic, 1 change of state, 2 application.
    pub fn trigger(self) -> u8 {
        (self.0 >> 4) & 0x07
    }
}

/// A Forward_Open or Large_Forward_Open request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ForwardOpen {
    /// Large_Forward_Open (32-bit network parameters).
    pub large: bool,
    /// Priority/time tick.
    pub priority_tick: u8,
    /// Timeout ticks.
    pub timeout_ticks: u8,
    /// O→T connection id (chosen by the target for point-to-point).
    pub o_t_id: u32,
    /// T→O connection id (chosen by the originator).
    pub t_o_id: u32,
    /// Connection serial number.
    pub serial: u16,
    /// Originator vendor id.
    pub vendor: u16,
    /// Originator serial number.
    pub originator_serial: u32,
    /// Connection timeout multiplier (timeout = RPI · 4 << multiplier).
    pub timeout_multiplier: u8,
    /// O→T requested packet interval, µs.
    pub o_t_rpi: u32,
    /// O→T network parameters.
    pub o_t: NetParams,
    /// T→O requested packet interval, µs.
    pub t_o_rpi: u32,
    /// T→O network parameters.
    pub t_o: NetParams,
    /// Transport type/trigger.
    pub transport: Transport,
    /// Connection path.
    pub path: EPath,
}

/// The triple that names a connection: serial, vendor, originator serial.
pub type ConnectionKey = (u16, u16, u32);

impl ForwardOpen {
    /// The connection's identity triple.
    pub fn key(&self) -> ConnectionKey {
        (self.serial, self.vendor, self.originator_serial)
    }

    /// Parses the service data of Forward_Open (`large` false) or Large_Forward_Open.
    pub fn parse(data: &[u8], large: bool) -> Result<ForwardOpen, Error> {
        let mut r = Reader::new(data);
        let priority_tick = r.u8("priority/time tick")?;
        let timeout_ticks = r.u8("timeout ticks")?;
        let o_t_id = r.u32("O→T connection id")?;
        let t_o_id = r.u32("T→O connection id")?;
        let serial = r.u16("connection serial number")?;
        let vendor = r.u16("originator vendor id")?;
        let originator_serial = r.u32("originator serial number")?;
        let timeout_multiplier = r.u8("connection timeout multiplier")?;
        r.bytes(3, "reserved")?;
        let o_t_rpi = r.u32("O→T RPI")?;
        let o_t = if large {
            NetParams::from_u32(r.u32("O→T network connection parameters")?)
        } else {
            NetParams::from_u16(r.u16("O→T network connection parameters")?)
        };
        let t_o_rpi = r.u32("T→O RPI")?;
        let t_o = if large {
            NetParams::from_u32(r.u32("T→O network connection parameters")?)
        } else {
            NetParams::from_u16(r.u16("T→O network connection parameters")?)
        };
        let transport = Transport(r.u8("transport type/trigger")?);
        let words = usize::from(r.u8("connection path size")?);
        let path = r.sized(words * 2, "connection path size")?;
        let path = EPath::parse(path)?;
        r.finish("Forward_Open request")?;
        Ok(ForwardOpen {
            large,
            priority_tick,
            timeout_ticks,
            o_t_id,
            t_o_id,
            serial,
            vendor,
            originator_serial,
            timeout_multiplier,
            o_t_rpi,
            o_t,
            t_o_rpi,
            t_o,
            transport,
            path,
        })
    }

    /// The service data.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(48);
        out.put_u8(self.priority_tick);
        out.put_u8(self.timeout_ticks);
        out.put_u32(self.o_t_id);
        out.put_u32(self.t_o_id);
        out.put_u16(self.serial);
        out.put_u16(self.vendor);
        out.put_u32(self.originator_serial);
        out.put_u8(self.timeout_multiplier);
        out.extend_from_slice(&[0; 3]);
        out.put_u32(self.o_t_rpi);
        if self.large {
            out.put_u32(self.o_t.to_u32());
        } else {
            out.put_u16(self.o_t.to_u16());
        }
        out.put_u32(self.t_o_rpi);
        if self.large {
            out.put_u32(self.t_o.to_u32());
        } else {
            out.put_u16(self.t_o.to_u16());
        }
        out.put_u8(self.transport.0);
        let path = self.path.emit();
        out.put_u8((path.len() / 2) as u8);
        out.extend(path);
        out
    }

    /// The connection timeout: RPI · 4 << multiplier (O→T side, as the consumer watches it).
    pub fn timeout_us(&self) -> u64 {
        u64::from(self.o_t_rpi) * (4u64 << self.timeout_multiplier.min(7))
    }
}

/// A successful Forward_Open reply.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ForwardOpenReply {
    /// O→T connection id.
    pub o_t_id: u32,
    /// T→O connection id.
    pub t_o_id: u32,
    /// Connection serial number.
    pub serial: u16,
    /// Originator vendor id.
    pub vendor: u16,
    /// Originator serial number.
    pub originator_serial: u32,
    /// O→T actual packet interval, µs.
    pub o_t_api: u32,
    /// T→O actual packet interval, µs.
    pub t_o_api: u32,
}

impl ForwardOpenReply {
    /// Parses the reply data.
    pub fn parse(data: &[u8]) -> Result<ForwardOpenReply, Error> {
        let mut r = Reader::new(data);
        let reply = ForwardOpenReply {
            o_t_id: r.u32("O→T connection id")?,
            t_o_id: r.u32("T→O connection id")?,
            serial: r.u16("connection serial number")?,
            vendor: r.u16("originator vendor id")?,
            originator_serial: r.u32("originator serial number")?,
            o_t_api: r.u32("O→T API")?,
            t_o_api: r.u32("T→O API")?,
        };
        let words = usize::from(r.u8("application reply size")?);
        r.u8("reserved")?;
        r.bytes(words * 2, "application reply")?;
        r.finish("Forward_Open reply")?;
        Ok(reply)
    }

    /// The reply data (no application reply).
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(26);
        out.put_u32(self.o_t_id);
        out.put_u32(self.t_o_id);
        out.put_u16(self.serial);
        out.put_u16(self.vendor);
        out.put_u32(self.originator_serial);
        out.put_u32(self.o_t_api);
        out.put_u32(self.t_o_api);
        out.put_u8(0);
        out.put_u8(0);
        out
    }
}

/// The data of a failed Forward_Open or Forward_Close reply: the connection triple, remaining
/// path size, reserved.
pub fn failure_data(key: ConnectionKey) -> Vec<u8> {
    let mut out = Vec::with_capacity(10);
    out.put_u16(key.0);
    out.put_u16(key.1);
    out.put_u32(key.2);
    out.put_u8(0);
    out.put_u8(0);
    out
}

/// A Forward_Close request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ForwardClose {
    /// Priority/time tick.
    pub priority_tick: u8,
    /// Timeout ticks.
    pub timeout_ticks: u8,
    /// Connection serial number.
    pub serial: u16,
    /// Originator vendor id.
    pub vendor: u16,
    /// Originator serial number.
    pub originator_serial: u32,
    /// Connection path.
    pub path: EPath,
}

impl ForwardClose {
    /// The connection's identity triple.
    pub fn key(&self) -> ConnectionKey {
        (self.serial, self.vendor, self.originator_serial)
    }

    /// Parses the service data.
    pub fn parse(data: &[u8]) -> Result<ForwardClose, Error> {
        let mut r = Reader::new(data);
        let priority_tick = r.u8("priority/time tick")?;
        let timeout_ticks = r.u8("timeout ticks")?;
        let serial = r.u16("connection serial number")?;
        let vendor = r.u16("originator vendor id")?;
        let originator_serial = r.u32("originator serial number")?;
        let words = usize::from(r.u8("connection path size")?);
        r.u8("reserved")?;
        let path = r.sized(words * 2, "connection path size")?;
        let path = EPath::parse(path)?;
        r.finish("Forward_Close request")?;
        Ok(ForwardClose {
            priority_tick,
            timeout_ticks,
            serial,
            vendor,
            originator_serial,
            path,
        })
    }

    /// The service data.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.put_u8(self.priority_tick);
        out.put_u8(self.timeout_ticks);
        out.put_u16(self.serial);
        out.put_u16(self.vendor);
        out.put_u32(self.originator_serial);
        let path = self.path.emit();
        out.put_u8((path.len() / 2) as u8);
        out.put_u8(0);
        out.extend(path);
        out
    }
}

/// The data of a successful Forward_Close reply.
pub fn forward_close_reply(key: ConnectionKey) -> Vec<u8> {
    failure_data(key)
}

/// An Unconnected_Send request: an embedded request and the route to its target.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnconnectedSend {
    /// Priority/time tick.
    pub priority_tick: u8,
    /// Timeout ticks.
    pub timeout_ticks: u8,
    /// The embedded message-router request (bytes).
    pub request: Vec<u8>,
    /// Route path (port segments).
    pub route: EPath,
}

impl UnconnectedSend {
    /// Parses the service data.
    pub fn parse(data: &[u8]) -> Result<UnconnectedSend, Error> {
        let mut r = Reader::new(data);
        let priority_tick = r.u8("priority/time tick")?;
        let timeout_ticks = r.u8("timeout ticks")?;
        let size = usize::from(r.u16("embedded message size")?);
        let request = r.sized(size, "embedded message size")?.to_vec();
        if size % 2 == 1 {
            r.u8("embedded message pad")?;
        }
        let words = usize::from(r.u8("route path size")?);
        r.u8("reserved")?;
        let route = EPath::parse(r.bytes(words * 2, "route path")?)?;
        r.finish("Unconnected_Send request")?;
        Ok(UnconnectedSend {
            priority_tick,
            timeout_ticks,
            request,
            route,
        })
    }

    /// The service data.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.put_u8(self.priority_tick);
        out.put_u8(self.timeout_ticks);
        out.put_u16(self.request.len() as u16);
        out.extend_from_slice(&self.request);
        if self.request.len() % 2 == 1 {
            out.put_u8(0);
        }
        let route = self.route.emit();
        out.put_u8((route.len() / 2) as u8);
        out.put_u8(0);
        out.extend(route);
        out
    }

    /// The embedded request, parsed.
    pub fn embedded(&self) -> Result<MrRequest, Error> {
        MrRequest::parse(&self.request)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enip::epath::Segment;

    fn sample(large: bool) -> ForwardOpen {
        ForwardOpen {
            large,
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            o_t_id: 0,
            t_o_id: 0x1234_5678,
            serial: 7,
            vendor: 0x004D,
            originator_serial: 0xCAFE,
            timeout_multiplier: 2,
            o_t_rpi: 10_000,
            o_t: NetParams {
                size: 2 + 4 + 96,
                variable: false,
                priority: 0,
                kind: kind::POINT_TO_POINT,
                redundant_owner: false,
            },
            t_o_rpi: 10_000,
            t_o: NetParams {
                size: 2 + 96,
                variable: false,
                priority: 0,
                kind: kind::POINT_TO_POINT,
                redundant_owner: false,
            },
            transport: Transport::CLASS1_CYCLIC,
            path: EPath::io_connection(100, 101),
        }
    }

    #[test]
    fn forward_open_round_trips_in_both_sizes() {
        for large in [false, true] {
            let fo = sample(large);
            let b = fo.emit();
            assert_eq!(b.len(), if large { 36 + 4 + 8 } else { 36 + 8 });
            assert_eq!(ForwardOpen::parse(&b, large).unwrap(), fo);
        }
        // O→T: 102 bytes, fixed, low priority, point to point.
        assert_eq!(sample(false).o_t.to_u16(), 0x4066);
        assert_eq!(sample(true).o_t.to_u32(), 0x4000_0066);
        assert_eq!(sample(false).timeout_us(), 160_000);
    }

    #[test]
    fn forward_open_with_a_short_path_is_an_error() {
        let mut b = sample(false).emit();
        b.truncate(b.len() - 2);
        assert!(matches!(
            ForwardOpen::parse(&b, false),
            Err(Error::Length { .. })
        ));
        assert!(ForwardOpen::parse(&b[..10], false).is_err());
    }

    #[test]
    fn unconnected_send_pads_odd_messages() {
        let us = UnconnectedSend {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            request: vec![0x0E, 0x03, 0x20, 0x01, 0x24, 0x01, 0x30, 0x07, 0xAA],
            route: EPath {
                segments: vec![Segment::Port {
                    port: 1,
                    link: vec![0],
                }],
            },
        };
        let b = us.emit();
        assert_eq!(b[4 + 9], 0, "pad byte");
        assert_eq!(UnconnectedSend::parse(&b).unwrap(), us);
    }

    #[test]
    fn forward_close_round_trips() {
        let fc = ForwardClose {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            serial: 7,
            vendor: 0x4D,
            originator_serial: 0xCAFE,
            path: EPath::object(4, 1),
        };
        assert_eq!(ForwardClose::parse(&fc.emit()).unwrap(), fc);
    }

    mod properties {
        use super::*;
        use crate::enip::epath::Segment;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Network parameters that fit the field: sizes up to 511 in the 16-bit form.
        fn net(large: bool) -> impl Strategy<Value = NetParams> {
            let max = if large { u16::MAX } else { 0x01FF };
            (0..=max, any::<bool>(), 0u8..=3, 0u8..=3, any::<bool>()).prop_map(
                |(size, variable, priority, kind, redundant_owner)| NetParams {
                    size,
                    variable,
                    priority,
                    kind,
                    redundant_owner,
                },
            )
        }

        fn connection_path() -> impl Strategy<Value = EPath> {
            any::<(u16, u16, u16)>().prop_map(|(c, o, t)| EPath::io_connection_configured(c, o, t))
        }

        fn forward_open() -> impl Strategy<Value = ForwardOpen> {
            any::<bool>().prop_flat_map(|large| {
                (
                    any::<(u8, u8, u32, u32, u16, u16, u32, u8)>(),
                    (any::<u32>(), net(large), any::<u32>(), net(large)),
                    any::<u8>(),
                    connection_path(),
                )
                    .prop_map(
                        move |(
                            (
                                priority_tick,
                                timeout_ticks,
                                o_t_id,
                                t_o_id,
                                serial,
                                vendor,
                                originator_serial,
                                timeout_multiplier,
                            ),
                            (o_t_rpi, o_t, t_o_rpi, t_o),
                            transport,
                            path,
                        )| ForwardOpen {
                            large,
                            priority_tick,
                            timeout_ticks,
                            o_t_id,
                            t_o_id,
                            serial,
                            vendor,
                            originator_serial,
                            timeout_multiplier,
                            o_t_rpi,
                            o_t,
                            t_o_rpi,
                            t_o,
                            transport: Transport(transport),
                            path,
                        },
                    )
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn forward_open_round_trips(f in forward_open()) {
                prop_assert_eq!(ForwardOpen::parse(&f.emit(), f.large), Ok(f));
            }

            #[test]
            fn forward_open_reply_round_trips(v in any::<(u32, u32, u16, u16, u32, u32, u32)>()) {
                let r = ForwardOpenReply {
                    o_t_id: v.0,
                    t_o_id: v.1,
                    serial: v.2,
                    vendor: v.3,
                    originator_serial: v.4,
                    o_t_api: v.5,
                    t_o_api: v.6,
                };
                prop_assert_eq!(ForwardOpenReply::parse(&r.emit()), Ok(r));
            }

            #[test]
            fn forward_close_round_trips(v in any::<(u8, u8, u16, u16, u32)>(), path in connection_path()) {
                let c = ForwardClose {
                    priority_tick: v.0,
                    timeout_ticks: v.1,
                    serial: v.2,
                    vendor: v.3,
                    originator_serial: v.4,
                    path,
                };
                prop_assert_eq!(ForwardClose::parse(&c.emit()), Ok(c));
            }

            /// Any embedded bytes (odd lengths padded), a route of port segments.
            #[test]
            fn unconnected_send_round_trips(
                ticks in any::<(u8, u8)>(),
                request in vec(any::<u8>(), 0..24),
                route in vec((1u16..=20, vec(any::<u8>(), 0..4)), 0..3),
            ) {
                let u = UnconnectedSend {
                    priority_tick: ticks.0,
                    timeout_ticks: ticks.1,
                    request,
                    route: EPath {
                        segments: route
                            .into_iter()
                            .map(|(port, link)| Segment::Port { port, link })
                            .collect(),
                    },
                };
                prop_assert_eq!(UnconnectedSend::parse(&u.emit()), Ok(u));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..64), large in any::<bool>()) {
                let _ = ForwardOpen::parse(&bytes, large);
                let _ = ForwardOpenReply::parse(&bytes);
                let _ = ForwardClose::parse(&bytes);
                if let Ok(u) = UnconnectedSend::parse(&bytes) {
                    let _ = u.embedded();
                }
            }
        }
    }
}
