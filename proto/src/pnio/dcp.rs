//! DCP, the Discovery and basic Configuration Protocol (IEC 61158-6-10 §4.3; IEC 61158-5-10
//! "DCP" services): how a controller or an engineering tool finds devices by name (Identify),
//! reads and writes their name and IP suite (Get, Set) and how a device announces itself
//! (Hello). BU 0620 §2.5.2 / §3.8 and BU 0590 §3 describe the device names and addresses a
//! NORD device takes over DCP.
//!
//! A DCP telegram follows the frame id ([`FrameId::DCP_HELLO`] .. [`FrameId::DCP_IDENTIFY_RES`]);
//! [`DcpRepr`] and [`DcpPacket`] start at the frame id. All fields are big-endian.
//!
//! | bytes (from the frame id) | field |
//! |---|---|
//! | 0–1 | FrameID FEFCh Hello, FEFDh Get/Set, FEFEh Identify request, FEFFh Identify response |
//! | 2 | ServiceID: 3 Get, 4 Set, 5 Identify, 6 Hello |
//! | 3 | ServiceType: 0 request, 1 response success, 5 response "request not supported" |
//! | 4–7 | Xid (the response repeats the request's) |
//! | 8–9 | ResponseDelay in an Identify request (spread of the answers, in 10 ms units of a MAC-derived slot); reserved 0 elsewhere |
//! | 10–11 | DCPDataLength: the bytes of blocks (padding included) that follow |
//! | 12.. | Get request: a list of (Option, Suboption) pairs; otherwise blocks |
//!
//! A block is Option, Suboption, DCPBlockLength (u16), the block data and, if the length is
//! odd, one padding byte (not counted in DCPBlockLength, counted in DCPDataLength). The data
//! opens with a 2-byte prefix that depends on the telegram:
//!
//! - BlockInfo in Identify responses, Get responses and Hello requests (for the IP blocks:
//!   bit 0 IP set, bit 1 set by DHCP, bit 7 address conflict; 0 elsewhere);
//! - BlockQualifier in Set requests (0 temporary, 1 permanent; Reset to Factory: the mode);
//!   the Control blocks of a Set (Start, Stop, Signal, Factory Reset, Reset to Factory) carry
//!   one too;
//! - no prefix in Identify request filters and in the Control / Response block (option 5,
//!   suboption 4: the option and suboption answered and a BlockError), which is the whole
//!   answer to a Set and the negative answer to a Get.
//!
//! This is how Wireshark's packet-dcp.c and p-net's pf_dcp.c read and write them.
//!
//! A block of an option or suboption not typed here parses into [`BlockValue::Raw`] (prefix
//! included in its data) so that a device can answer "option not supported"; an unknown
//! ServiceID leaves the data opaque ([`DcpData::Opaque`]) so that it can answer "request not
//! supported". Errors are for what cannot be framed: a header or block header cut short, a
//! DCPBlockLength past the DCPDataLength, a DCPDataLength past the frame, and a typed block
//! whose length does not fit its type. [`DcpPacket::blocks`] frames the blocks without typing
//! them, so that a device can answer a telegram block by block.

use std::fmt;
use std::net::Ipv4Addr;

use super::frame::{read_frame_id, FrameId};
use crate::eth::MacAddr;
use crate::wire::{Error, Reader};

/// The DCP header after the frame id: ServiceID, ServiceType, Xid, ResponseDelay,
/// DCPDataLength.
pub const HEADER_LEN: usize = 10;

/// ServiceID.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ServiceId(pub u8);

impl ServiceId {
    /// Get (read blocks).
    pub const GET: ServiceId = ServiceId(3);
    /// Set (write blocks).
    pub const SET: ServiceId = ServiceId(4);
    /// Identify (multicast request, filter blocks; the matching devices answer).
    pub const IDENTIFY: ServiceId = ServiceId(5);
    /// Hello (a device announces itself).
    pub const HELLO: ServiceId = ServiceId(6);

    /// The service's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            ServiceId::GET => "Get",
            ServiceId::SET => "Set",
            ServiceId::IDENTIFY => "Identify",
            ServiceId::HELLO => "Hello",
            _ => return None,
        })
    }
}

impl fmt::Debug for ServiceId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => f.write_str(n),
            None => write!(f, "ServiceId({:02X}h)", self.0),
        }
    }
}

/// ServiceType.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ServiceType(pub u8);

impl ServiceType {
    /// Request.
    pub const REQUEST: ServiceType = ServiceType(0);
    /// Response, success.
    pub const SUCCESS: ServiceType = ServiceType(1);
    /// Response, "request not supported".
    pub const NOT_SUPPORTED: ServiceType = ServiceType(5);

    /// A response (bit 0 set).
    pub fn is_response(self) -> bool {
        self.0 & 0x01 != 0
    }
}

impl fmt::Debug for ServiceType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ServiceType::REQUEST => f.write_str("Request"),
            ServiceType::SUCCESS => f.write_str("Success"),
            ServiceType::NOT_SUPPORTED => f.write_str("NotSupported"),
            ServiceType(v) => write!(f, "ServiceType({v:02X}h)"),
        }
    }
}

/// An Option and Suboption pair: what a block, a Get selector or a DeviceOptions entry names.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord)]
pub struct DcpOption {
    /// Option (1 IP, 2 device properties, 3 DHCP, 5 control, 6 device initiative, 80h–FEh
    /// manufacturer specific, FFh all).
    pub option: u8,
    /// Suboption.
    pub suboption: u8,
}

impl DcpOption {
    /// Option IP.
    pub const OPT_IP: u8 = 1;
    /// Option device properties.
    pub const OPT_DEVICE: u8 = 2;
    /// Option DHCP.
    pub const OPT_DHCP: u8 = 3;
    /// Option control.
    pub const OPT_CONTROL: u8 = 5;
    /// Option device initiative.
    pub const OPT_DEVICE_INITIATIVE: u8 = 6;
    /// Option "all selector".
    pub const OPT_ALL: u8 = 0xFF;

    /// IP / MAC address.
    pub const IP_MAC: DcpOption = DcpOption::new(1, 1);
    /// IP / IP parameter (address, mask, gateway).
    pub const IP_PARAMETER: DcpOption = DcpOption::new(1, 2);
    /// IP / full IP suite (parameter and four DNS servers).
    pub const IP_FULL_SUITE: DcpOption = DcpOption::new(1, 3);
    /// Device / manufacturer specific: DeviceVendorValue ("type of station").
    pub const DEVICE_VENDOR: DcpOption = DcpOption::new(2, 1);
    /// Device / NameOfStation.
    pub const NAME_OF_STATION: DcpOption = DcpOption::new(2, 2);
    /// Device / DeviceID (vendor id, device id).
    pub const DEVICE_ID: DcpOption = DcpOption::new(2, 3);
    /// Device / DeviceRole.
    pub const DEVICE_ROLE: DcpOption = DcpOption::new(2, 4);
    /// Device / DeviceOptions (the options the device supports).
    pub const DEVICE_OPTIONS: DcpOption = DcpOption::new(2, 5);
    /// Device / AliasName.
    pub const ALIAS_NAME: DcpOption = DcpOption::new(2, 6);
    /// Device / DeviceInstance.
    pub const DEVICE_INSTANCE: DcpOption = DcpOption::new(2, 7);
    /// Device / OEM DeviceID.
    pub const OEM_DEVICE_ID: DcpOption = DcpOption::new(2, 8);
    /// Control / Start transaction.
    pub const CONTROL_START: DcpOption = DcpOption::new(5, 1);
    /// Control / Stop transaction.
    pub const CONTROL_STOP: DcpOption = DcpOption::new(5, 2);
    /// Control / Signal (flash the LED).
    pub const CONTROL_SIGNAL: DcpOption = DcpOption::new(5, 3);
    /// Control / Response.
    pub const CONTROL_RESPONSE: DcpOption = DcpOption::new(5, 4);
    /// Control / Factory Reset.
    pub const CONTROL_FACTORY_RESET: DcpOption = DcpOption::new(5, 5);
    /// Control / Reset to Factory.
    pub const CONTROL_RESET_TO_FACTORY: DcpOption = DcpOption::new(5, 6);
    /// DeviceInitiative.
    pub const DEVICE_INITIATIVE: DcpOption = DcpOption::new(6, 1);
    /// All selector.
    pub const ALL: DcpOption = DcpOption::new(0xFF, 0xFF);

    /// The pair.
    pub const fn new(option: u8, suboption: u8) -> DcpOption {
        DcpOption { option, suboption }
    }

    /// The pair's name, if typed here.
    pub fn name(self) -> Option<&'static str> {
        Some(match (self.option, self.suboption) {
            (1, 1) => "IP/MAC",
            (1, 2) => "IP/IPParameter",
            (1, 3) => "IP/FullIPSuite",
            (2, 1) => "Device/Vendor",
            (2, 2) => "Device/NameOfStation",
            (2, 3) => "Device/DeviceID",
            (2, 4) => "Device/DeviceRole",
            (2, 5) => "Device/DeviceOptions",
            (2, 6) => "Device/AliasName",
            (2, 7) => "Device/DeviceInstance",
            (2, 8) => "Device/OEMDeviceID",
            (3, _) => "DHCP",
            (5, 1) => "Control/Start",
            (5, 2) => "Control/Stop",
            (5, 3) => "Control/Signal",
            (5, 4) => "Control/Response",
            (5, 5) => "Control/FactoryReset",
            (5, 6) => "Control/ResetToFactory",
            (6, 1) => "DeviceInitiative",
            (0xFF, 0xFF) => "All",
            _ => return None,
        })
    }
}

impl fmt::Debug for DcpOption {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{n}({:02X}h/{:02X}h)", self.option, self.suboption),
            None => write!(f, "DcpOption({:02X}h/{:02X}h)", self.option, self.suboption),
        }
    }
}

/// BlockError of a Control / Response block.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BlockError(pub u8);

impl BlockError {
    /// No error.
    pub const OK: BlockError = BlockError(0);
    /// Option not supported.
    pub const OPTION_NOT_SUPPORTED: BlockError = BlockError(1);
    /// Suboption not supported, or no data set available.
    pub const SUBOPTION_NOT_SUPPORTED: BlockError = BlockError(2);
    /// Suboption not set.
    pub const SUBOPTION_NOT_SET: BlockError = BlockError(3);
    /// Resource error.
    pub const RESOURCE_ERROR: BlockError = BlockError(4);
    /// Set not possible by local reasons.
    pub const SET_NOT_POSSIBLE: BlockError = BlockError(5);
    /// In operation, set not possible.
    pub const IN_OPERATION: BlockError = BlockError(6);

    /// The code's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self.0 {
            0 => "ok",
            1 => "option not supported",
            2 => "suboption not supported or no data set",
            3 => "suboption not set",
            4 => "resource error",
            5 => "set not possible by local reasons",
            6 => "in operation, set not possible",
            _ => return None,
        })
    }
}

impl fmt::Debug for BlockError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "BlockError({} {n})", self.0),
            None => write!(f, "BlockError({:02X}h)", self.0),
        }
    }
}

/// BlockInfo: the prefix of a block in an Identify or Get response and in a Hello request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BlockInfo(pub u16);

impl BlockInfo {
    /// Nothing to report (and, for the IP blocks: no IP set).
    pub const NONE: BlockInfo = BlockInfo(0);
    /// IP blocks, bit 0: an IP suite is set.
    pub const IP_SET: BlockInfo = BlockInfo(0x0001);
    /// IP blocks, bit 1: the IP suite was set by DHCP.
    pub const IP_BY_DHCP: BlockInfo = BlockInfo(0x0002);
    /// IP blocks, bit 7: an address conflict was detected.
    pub const IP_CONFLICT: BlockInfo = BlockInfo(0x0080);

    /// IP set (bit 0).
    pub fn ip_set(self) -> bool {
        self.0 & 0x0001 != 0
    }
    /// IP set by DHCP (bit 1).
    pub fn by_dhcp(self) -> bool {
        self.0 & 0x0002 != 0
    }
    /// Address conflict (bit 7).
    pub fn conflict(self) -> bool {
        self.0 & 0x0080 != 0
    }
}

/// BlockQualifier: the prefix of every block of a Set request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BlockQualifier(pub u16);

impl BlockQualifier {
    /// Use the value temporarily (lost at power-off).
    pub const TEMPORARY: BlockQualifier = BlockQualifier(0);
    /// Save the value permanently.
    pub const PERMANENT: BlockQualifier = BlockQualifier(1);
    /// Reset to Factory: reset application data.
    pub const RESET_APPLICATION_DATA: BlockQualifier = BlockQualifier(2);
    /// Reset to Factory: reset communication parameters.
    pub const RESET_COMMUNICATION: BlockQualifier = BlockQualifier(4);
    /// Reset to Factory: reset engineering parameters.
    pub const RESET_ENGINEERING: BlockQualifier = BlockQualifier(6);
    /// Reset to Factory: reset all stored data.
    pub const RESET_ALL_DATA: BlockQualifier = BlockQualifier(8);
    /// Reset to Factory: all stored data to factory values.
    pub const RESET_DEVICE: BlockQualifier = BlockQualifier(0x10);
    /// Reset to Factory: reset and restore data.
    pub const RESET_AND_RESTORE: BlockQualifier = BlockQualifier(0x12);

    /// Bit 0: save permanently.
    pub fn permanent(self) -> bool {
        self.0 & 0x0001 != 0
    }
}

/// The 2-byte prefix of a block, as the telegram that carries it says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum BlockHead {
    /// No prefix (Identify filters, Control / Response, Set responses, [`BlockValue::Raw`]).
    #[default]
    None,
    /// BlockInfo (Identify and Get responses, Hello).
    Info(BlockInfo),
    /// BlockQualifier (Set requests).
    Qualifier(BlockQualifier),
}

/// Which prefix the blocks of a telegram carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HeadKind {
    /// None.
    None,
    /// BlockInfo.
    Info,
    /// BlockQualifier.
    Qualifier,
}

impl HeadKind {
    /// The prefix a block of `option` carries in a telegram of `service` and `service_type`.
    pub fn of(service: ServiceId, service_type: ServiceType, option: DcpOption) -> HeadKind {
        if option == DcpOption::CONTROL_RESPONSE {
            return HeadKind::None;
        }
        match (service, service_type.is_response()) {
            (ServiceId::SET, false) => HeadKind::Qualifier,
            (ServiceId::IDENTIFY, true) | (ServiceId::GET, true) | (ServiceId::HELLO, false) => {
                HeadKind::Info
            }
            _ => HeadKind::None,
        }
    }
}

/// IP address, subnet mask, standard gateway (IPParameter; 0.0.0.0 ×3: none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct IpParameter {
    /// IPAddress.
    pub ip: Ipv4Addr,
    /// Subnetmask.
    pub mask: Ipv4Addr,
    /// StandardGateway (0.0.0.0: none).
    pub gateway: Ipv4Addr,
}

impl Default for IpParameter {
    fn default() -> Self {
        IpParameter {
            ip: Ipv4Addr::UNSPECIFIED,
            mask: Ipv4Addr::UNSPECIFIED,
            gateway: Ipv4Addr::UNSPECIFIED,
        }
    }
}

/// DeviceRole bits.
pub mod role {
    /// IO device.
    pub const IO_DEVICE: u8 = 0x01;
    /// IO controller.
    pub const IO_CONTROLLER: u8 = 0x02;
    /// IO multidevice.
    pub const IO_MULTIDEVICE: u8 = 0x04;
    /// PN supervisor.
    pub const SUPERVISOR: u8 = 0x08;
}

/// SignalValue "flash once" (0100h): the device flashes its signal LED (3 s at 1 Hz in p-net).
pub const SIGNAL_FLASH_ONCE: u16 = 0x0100;

/// The data of a block after its prefix, typed by Option and Suboption.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BlockValue {
    /// IP / MAC: the device's MAC address.
    Mac(MacAddr),
    /// IP / IP parameter.
    IpParameter(IpParameter),
    /// IP / full IP suite.
    FullIpSuite {
        /// Address, mask, gateway.
        ip: IpParameter,
        /// Four DNS server addresses.
        dns: [Ipv4Addr; 4],
    },
    /// Device / DeviceVendorValue: the type of station, a visible string (bytes that are not
    /// UTF-8 are replaced, as every string of this enum).
    DeviceVendor(String),
    /// Device / NameOfStation (see [`station_name_valid`]; empty in a Set: delete the name).
    NameOfStation(String),
    /// Device / DeviceID.
    DeviceId {
        /// VendorID (assigned by PROFIBUS & PROFINET International).
        vendor_id: u16,
        /// DeviceID.
        device_id: u16,
    },
    /// Device / DeviceRole ([`role`] bits; a reserved byte follows on the wire).
    DeviceRole(u8),
    /// Device / DeviceOptions: the option pairs the device supports.
    DeviceOptions(Vec<DcpOption>),
    /// Device / AliasName ("port-xyz.name-of-neighbour").
    AliasName(String),
    /// Device / DeviceInstance.
    DeviceInstance {
        /// DeviceInstanceHigh.
        high: u8,
        /// DeviceInstanceLow.
        low: u8,
    },
    /// Device / OEM DeviceID.
    OemDeviceId {
        /// OEM VendorID.
        vendor_id: u16,
        /// OEM DeviceID.
        device_id: u16,
    },
    /// DHCP (option 3), any suboption, data as is.
    Dhcp {
        /// The suboption (the DHCP option code).
        suboption: u8,
        /// The data.
        data: Vec<u8>,
    },
    /// Control / Start transaction.
    Start,
    /// Control / Stop transaction.
    Stop,
    /// Control / Signal with its SignalValue ([`SIGNAL_FLASH_ONCE`]).
    Signal(u16),
    /// Control / Response: the answer to one block of a Set (or a failed Get).
    Response {
        /// The option answered.
        option: DcpOption,
        /// Its error.
        error: BlockError,
    },
    /// Control / Factory Reset (the qualifier says what).
    FactoryReset,
    /// Control / Reset to Factory (the qualifier says what).
    ResetToFactory,
    /// DeviceInitiative: 1 the device sends Hello after power-on, 0 not.
    DeviceInitiative(u16),
    /// All selector (Identify All).
    All,
    /// An option or suboption not typed here: the whole block data, prefix included.
    Raw {
        /// Option and suboption.
        option: DcpOption,
        /// The bytes after DCPBlockLength, without padding.
        data: Vec<u8>,
    },
}

/// Checks a typed block's data length.
fn exact(data: &[u8], n: usize, field: &'static str) -> Result<(), Error> {
    if data.len() == n {
        Ok(())
    } else {
        Err(Error::Invalid {
            field,
            value: data.len() as u32,
            why: "not the length of the option's value",
        })
    }
}

fn ipv4(b: &[u8]) -> Ipv4Addr {
    Ipv4Addr::new(b[0], b[1], b[2], b[3])
}

fn string(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

impl BlockValue {
    /// The option and suboption of the block.
    pub fn option(&self) -> DcpOption {
        match self {
            BlockValue::Mac(_) => DcpOption::IP_MAC,
            BlockValue::IpParameter(_) => DcpOption::IP_PARAMETER,
            BlockValue::FullIpSuite { .. } => DcpOption::IP_FULL_SUITE,
            BlockValue::DeviceVendor(_) => DcpOption::DEVICE_VENDOR,
            BlockValue::NameOfStation(_) => DcpOption::NAME_OF_STATION,
            BlockValue::DeviceId { .. } => DcpOption::DEVICE_ID,
            BlockValue::DeviceRole(_) => DcpOption::DEVICE_ROLE,
            BlockValue::DeviceOptions(_) => DcpOption::DEVICE_OPTIONS,
            BlockValue::AliasName(_) => DcpOption::ALIAS_NAME,
            BlockValue::DeviceInstance { .. } => DcpOption::DEVICE_INSTANCE,
            BlockValue::OemDeviceId { .. } => DcpOption::OEM_DEVICE_ID,
            BlockValue::Dhcp { suboption, .. } => DcpOption::new(DcpOption::OPT_DHCP, *suboption),
            BlockValue::Start => DcpOption::CONTROL_START,
            BlockValue::Stop => DcpOption::CONTROL_STOP,
            BlockValue::Signal(_) => DcpOption::CONTROL_SIGNAL,
            BlockValue::Response { .. } => DcpOption::CONTROL_RESPONSE,
            BlockValue::FactoryReset => DcpOption::CONTROL_FACTORY_RESET,
            BlockValue::ResetToFactory => DcpOption::CONTROL_RESET_TO_FACTORY,
            BlockValue::DeviceInitiative(_) => DcpOption::DEVICE_INITIATIVE,
            BlockValue::All => DcpOption::ALL,
            BlockValue::Raw { option, .. } => *option,
        }
    }

    /// Whether `option` is typed here (else it parses into [`BlockValue::Raw`]).
    pub fn is_typed(option: DcpOption) -> bool {
        option.name().is_some()
    }

    /// Parses the data after the prefix of a block of a typed `option`.
    fn parse(option: DcpOption, d: &[u8]) -> Result<BlockValue, Error> {
        Ok(match (option.option, option.suboption) {
            (1, 1) => {
                exact(d, 6, "IP/MAC block length")?;
                let mut m = [0u8; 6];
                m.copy_from_slice(d);
                BlockValue::Mac(MacAddr(m))
            }
            (1, 2) => {
                exact(d, 12, "IP/IPParameter block length")?;
                BlockValue::IpParameter(IpParameter {
                    ip: ipv4(&d[0..4]),
                    mask: ipv4(&d[4..8]),
                    gateway: ipv4(&d[8..12]),
                })
            }
            (1, 3) => {
                exact(d, 28, "IP/FullIPSuite block length")?;
                BlockValue::FullIpSuite {
                    ip: IpParameter {
                        ip: ipv4(&d[0..4]),
                        mask: ipv4(&d[4..8]),
                        gateway: ipv4(&d[8..12]),
                    },
                    dns: [
                        ipv4(&d[12..16]),
                        ipv4(&d[16..20]),
                        ipv4(&d[20..24]),
                        ipv4(&d[24..28]),
                    ],
                }
            }
            (2, 1) => BlockValue::DeviceVendor(string(d)),
            (2, 2) => BlockValue::NameOfStation(string(d)),
            (2, 3) => {
                exact(d, 4, "Device/DeviceID block length")?;
                BlockValue::DeviceId {
                    vendor_id: u16::from_be_bytes([d[0], d[1]]),
                    device_id: u16::from_be_bytes([d[2], d[3]]),
                }
            }
            (2, 4) => {
                exact(d, 2, "Device/DeviceRole block length")?;
                BlockValue::DeviceRole(d[0])
            }
            (2, 5) => {
                if d.len() % 2 == 1 {
                    return Err(Error::Invalid {
                        field: "Device/DeviceOptions block length",
                        value: d.len() as u32,
                        why: "odd: each option is 2 bytes",
                    });
                }
                BlockValue::DeviceOptions(
                    d.chunks_exact(2)
                        .map(|p| DcpOption::new(p[0], p[1]))
                        .collect(),
                )
            }
            (2, 6) => BlockValue::AliasName(string(d)),
            (2, 7) => {
                exact(d, 2, "Device/DeviceInstance block length")?;
                BlockValue::DeviceInstance {
                    high: d[0],
                    low: d[1],
                }
            }
            (2, 8) => {
                exact(d, 4, "Device/OEMDeviceID block length")?;
                BlockValue::OemDeviceId {
                    vendor_id: u16::from_be_bytes([d[0], d[1]]),
                    device_id: u16::from_be_bytes([d[2], d[3]]),
                }
            }
            (3, suboption) => BlockValue::Dhcp {
                suboption,
                data: d.to_vec(),
            },
            (5, 1) => {
                exact(d, 0, "Control/Start block length")?;
                BlockValue::Start
            }
            (5, 2) => {
                exact(d, 0, "Control/Stop block length")?;
                BlockValue::Stop
            }
            (5, 3) => {
                exact(d, 2, "Control/Signal block length")?;
                BlockValue::Signal(u16::from_be_bytes([d[0], d[1]]))
            }
            (5, 4) => {
                exact(d, 3, "Control/Response block length")?;
                BlockValue::Response {
                    option: DcpOption::new(d[0], d[1]),
                    error: BlockError(d[2]),
                }
            }
            (5, 5) => {
                exact(d, 0, "Control/FactoryReset block length")?;
                BlockValue::FactoryReset
            }
            (5, 6) => {
                exact(d, 0, "Control/ResetToFactory block length")?;
                BlockValue::ResetToFactory
            }
            (6, 1) => {
                exact(d, 2, "DeviceInitiative block length")?;
                BlockValue::DeviceInitiative(u16::from_be_bytes([d[0], d[1]]))
            }
            (0xFF, 0xFF) => {
                exact(d, 0, "All selector block length")?;
                BlockValue::All
            }
            _ => BlockValue::Raw {
                option,
                data: d.to_vec(),
            },
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        let ip = |b: &mut Vec<u8>, p: &IpParameter| {
            b.extend(p.ip.octets());
            b.extend(p.mask.octets());
            b.extend(p.gateway.octets());
        };
        match self {
            BlockValue::Mac(m) => b.extend(m.0),
            BlockValue::IpParameter(p) => ip(b, p),
            BlockValue::FullIpSuite { ip: p, dns } => {
                ip(b, p);
                for d in dns {
                    b.extend(d.octets());
                }
            }
            BlockValue::DeviceVendor(s)
            | BlockValue::NameOfStation(s)
            | BlockValue::AliasName(s) => b.extend(s.as_bytes()),
            BlockValue::DeviceId {
                vendor_id,
                device_id,
            }
            | BlockValue::OemDeviceId {
                vendor_id,
                device_id,
            } => {
                b.extend(vendor_id.to_be_bytes());
                b.extend(device_id.to_be_bytes());
            }
            BlockValue::DeviceRole(r) => b.extend([*r, 0]),
            BlockValue::DeviceOptions(o) => {
                for p in o {
                    b.extend([p.option, p.suboption]);
                }
            }
            BlockValue::DeviceInstance { high, low } => b.extend([*high, *low]),
            BlockValue::Dhcp { data, .. } | BlockValue::Raw { data, .. } => b.extend(data),
            BlockValue::Start
            | BlockValue::Stop
            | BlockValue::FactoryReset
            | BlockValue::ResetToFactory
            | BlockValue::All => {}
            BlockValue::Signal(v) | BlockValue::DeviceInitiative(v) => b.extend(v.to_be_bytes()),
            BlockValue::Response { option, error } => {
                b.extend([option.option, option.suboption, error.0])
            }
        }
    }
}

/// One block: its prefix and its value (which names the option).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DcpBlock {
    /// The prefix (what the telegram's [`HeadKind`] says).
    pub head: BlockHead,
    /// The value.
    pub value: BlockValue,
}

/// A framed but untyped block: its option and data (prefix included, padding not).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawBlock<'a> {
    /// Option and suboption.
    pub option: DcpOption,
    /// The DCPBlockLength bytes after the block header.
    pub data: &'a [u8],
}

impl DcpBlock {
    /// A block without prefix (an Identify filter).
    pub fn filter(value: BlockValue) -> DcpBlock {
        DcpBlock {
            head: BlockHead::None,
            value,
        }
    }

    /// A block of a response or Hello, with its BlockInfo.
    pub fn info(info: BlockInfo, value: BlockValue) -> DcpBlock {
        DcpBlock {
            head: BlockHead::Info(info),
            value,
        }
    }

    /// A block of a Set request, with its BlockQualifier.
    pub fn set(qualifier: BlockQualifier, value: BlockValue) -> DcpBlock {
        DcpBlock {
            head: BlockHead::Qualifier(qualifier),
            value,
        }
    }

    /// A Control / Response block answering `option` with `error`.
    pub fn response(option: DcpOption, error: BlockError) -> DcpBlock {
        DcpBlock::filter(BlockValue::Response { option, error })
    }

    /// The block's option and suboption.
    pub fn option(&self) -> DcpOption {
        self.value.option()
    }

    /// Types a framed block: splits the prefix `kind` asks for (not for a
    /// [`BlockValue::Raw`]) and parses the rest by option.
    pub fn parse(kind: HeadKind, raw: RawBlock<'_>) -> Result<DcpBlock, Error> {
        if !BlockValue::is_typed(raw.option) {
            return Ok(DcpBlock::filter(BlockValue::Raw {
                option: raw.option,
                data: raw.data.to_vec(),
            }));
        }
        let mut r = Reader::new(raw.data);
        let head = match kind {
            HeadKind::None => BlockHead::None,
            HeadKind::Info => BlockHead::Info(BlockInfo(r.u16_be("BlockInfo")?)),
            HeadKind::Qualifier => {
                BlockHead::Qualifier(BlockQualifier(r.u16_be("BlockQualifier")?))
            }
        };
        let value = BlockValue::parse(raw.option, r.rest())?;
        Ok(DcpBlock { head, value })
    }

    /// Appends the block with its padding; data over 65535 bytes is [`Error::TooLong`].
    fn emit(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        let mut d = Vec::new();
        match self.head {
            BlockHead::None => {}
            BlockHead::Info(BlockInfo(v)) | BlockHead::Qualifier(BlockQualifier(v)) => {
                d.extend(v.to_be_bytes())
            }
        }
        self.value.emit(&mut d);
        let len = u16::try_from(d.len()).map_err(|_| Error::TooLong {
            what: "DCPBlockLength",
            len: d.len(),
            max: usize::from(u16::MAX),
        })?;
        let o = self.option();
        out.extend([o.option, o.suboption]);
        out.extend(len.to_be_bytes());
        out.extend(&d);
        if d.len() % 2 == 1 {
            out.push(0);
        }
        Ok(())
    }
}

/// A checked view of a DCP telegram from its frame id on: the header is there and
/// DCPDataLength fits the buffer (bytes after it are Ethernet padding). The blocks are framed
/// by [`DcpPacket::blocks`].
#[derive(Debug, Clone)]
pub struct DcpPacket<T: AsRef<[u8]>> {
    buffer: T,
}

mod field {
    pub(super) const SERVICE_ID: usize = 2;
    pub(super) const SERVICE_TYPE: usize = 3;
    pub(super) const XID: usize = 4;
    pub(super) const RESPONSE_DELAY: usize = 8;
    pub(super) const DATA_LENGTH: usize = 10;
    pub(super) const DATA: usize = 12;
}

impl<T: AsRef<[u8]>> DcpPacket<T> {
    /// Checks the frame id, the header and DCPDataLength.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let b = buffer.as_ref();
        let id = read_frame_id(b)?;
        if !(FrameId::DCP_HELLO.0..=FrameId::DCP_IDENTIFY_RES.0).contains(&id.0) {
            return Err(Error::Unknown {
                field: "DCP FrameID",
                value: u32::from(id.0),
            });
        }
        if b.len() < field::DATA {
            return Err(Error::Truncated {
                what: "DCP header",
                need: field::DATA,
                got: b.len(),
            });
        }
        let p = DcpPacket { buffer };
        let len = usize::from(p.data_length());
        let available = p.buffer.as_ref().len() - field::DATA;
        if len > available {
            return Err(Error::Length {
                field: "DCPDataLength",
                value: len,
                available,
            });
        }
        Ok(p)
    }

    fn u16_at(&self, at: usize) -> u16 {
        let b = self.buffer.as_ref();
        u16::from_be_bytes([b[at], b[at + 1]])
    }

    /// FrameID.
    pub fn frame_id(&self) -> FrameId {
        FrameId(self.u16_at(0))
    }
    /// ServiceID.
    pub fn service(&self) -> ServiceId {
        ServiceId(self.buffer.as_ref()[field::SERVICE_ID])
    }
    /// ServiceType.
    pub fn service_type(&self) -> ServiceType {
        ServiceType(self.buffer.as_ref()[field::SERVICE_TYPE])
    }
    /// Xid.
    pub fn xid(&self) -> u32 {
        let b = &self.buffer.as_ref()[field::XID..field::XID + 4];
        u32::from_be_bytes([b[0], b[1], b[2], b[3]])
    }
    /// ResponseDelay (Identify request) or the reserved field.
    pub fn response_delay(&self) -> u16 {
        self.u16_at(field::RESPONSE_DELAY)
    }
    /// DCPDataLength.
    pub fn data_length(&self) -> u16 {
        self.u16_at(field::DATA_LENGTH)
    }
    /// The DCPDataLength bytes after the header (cut at the buffer's end if a setter made
    /// DCPDataLength too long).
    pub fn data(&self) -> &[u8] {
        let b = self.buffer.as_ref();
        let end = (field::DATA + usize::from(self.data_length())).min(b.len());
        &b[field::DATA..end]
    }

    /// The blocks, framed: each item is a block or the error that ends the framing.
    pub fn blocks(&self) -> Blocks<'_> {
        Blocks {
            r: Reader::new(self.data()),
            done: false,
        }
    }

    /// The selectors of a Get request: (option, suboption) pairs; an odd DCPDataLength is
    /// [`Error::Trailing`].
    pub fn selectors(&self) -> Result<Vec<DcpOption>, Error> {
        let d = self.data();
        if d.len() % 2 == 1 {
            return Err(Error::Trailing {
                what: "Get selectors",
                extra: 1,
            });
        }
        Ok(d.chunks_exact(2)
            .map(|p| DcpOption::new(p[0], p[1]))
            .collect())
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> DcpPacket<T> {
    /// Sets ServiceID (for negative tests).
    pub fn set_service(&mut self, s: ServiceId) {
        self.buffer.as_mut()[field::SERVICE_ID] = s.0;
    }
    /// Sets ServiceType.
    pub fn set_service_type(&mut self, t: ServiceType) {
        self.buffer.as_mut()[field::SERVICE_TYPE] = t.0;
    }
    /// Sets Xid.
    pub fn set_xid(&mut self, xid: u32) {
        self.buffer.as_mut()[field::XID..field::XID + 4].copy_from_slice(&xid.to_be_bytes());
    }
    /// Sets DCPDataLength (not checked against the buffer: [`DcpPacket::data`] then stops at
    /// the buffer's end; `new_checked` on the bytes reports the bad length).
    pub fn set_data_length(&mut self, len: u16) {
        self.buffer.as_mut()[field::DATA_LENGTH..field::DATA_LENGTH + 2]
            .copy_from_slice(&len.to_be_bytes());
    }

    /// The buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }
}

/// The framing iterator of [`DcpPacket::blocks`].
#[derive(Debug, Clone)]
pub struct Blocks<'a> {
    r: Reader<'a>,
    done: bool,
}

impl<'a> Iterator for Blocks<'a> {
    type Item = Result<RawBlock<'a>, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done || self.r.remaining() == 0 {
            return None;
        }
        let item = (|| {
            let h = self.r.bytes(4, "DCP block header")?;
            let option = DcpOption::new(h[0], h[1]);
            let len = usize::from(u16::from_be_bytes([h[2], h[3]]));
            if len > self.r.remaining() {
                return Err(Error::Length {
                    field: "DCPBlockLength",
                    value: len,
                    available: self.r.remaining(),
                });
            }
            let data = self.r.bytes(len, "DCP block")?;
            if len % 2 == 1 && self.r.remaining() > 0 {
                self.r.u8("DCP block padding")?;
            }
            Ok(RawBlock { option, data })
        })();
        self.done = item.is_err();
        Some(item)
    }
}

/// What follows the DCP header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DcpData {
    /// A Get request's selectors.
    Selectors(Vec<DcpOption>),
    /// Blocks (every other telegram of a known service).
    Blocks(Vec<DcpBlock>),
    /// The data of a telegram whose ServiceID is not Get, Set, Identify or Hello.
    Opaque(Vec<u8>),
}

/// A DCP telegram from its frame id on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DcpRepr {
    /// FrameID (FEFCh–FEFFh).
    pub frame_id: FrameId,
    /// ServiceID.
    pub service: ServiceId,
    /// ServiceType.
    pub service_type: ServiceType,
    /// Xid.
    pub xid: u32,
    /// ResponseDelay (Identify requests; 0 elsewhere).
    pub response_delay: u16,
    /// Selectors, blocks or opaque data.
    pub data: DcpData,
}

impl DcpRepr {
    /// Parses a telegram from its frame id on; bytes after DCPDataLength are padding.
    pub fn parse(buf: &[u8]) -> Result<DcpRepr, Error> {
        let p = DcpPacket::new_checked(buf)?;
        let (service, service_type) = (p.service(), p.service_type());
        let data = match service {
            ServiceId::GET if !service_type.is_response() => DcpData::Selectors(p.selectors()?),
            ServiceId::GET | ServiceId::SET | ServiceId::IDENTIFY | ServiceId::HELLO => {
                let mut blocks = Vec::new();
                for raw in p.blocks() {
                    let raw = raw?;
                    let kind = HeadKind::of(service, service_type, raw.option);
                    blocks.push(DcpBlock::parse(kind, raw)?);
                }
                DcpData::Blocks(blocks)
            }
            _ => DcpData::Opaque(p.data().to_vec()),
        };
        Ok(DcpRepr {
            frame_id: p.frame_id(),
            service,
            service_type,
            xid: p.xid(),
            response_delay: p.response_delay(),
            data,
        })
    }

    /// The telegram bytes from the frame id on (blocks padded to even lengths, the padding
    /// counted in DCPDataLength; the Ethernet layer pads the frame). Data over 65535 bytes is
    /// [`Error::TooLong`].
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut d = Vec::new();
        match &self.data {
            DcpData::Selectors(s) => {
                for o in s {
                    d.extend([o.option, o.suboption]);
                }
            }
            DcpData::Blocks(blocks) => {
                for b in blocks {
                    b.emit(&mut d)?;
                }
            }
            DcpData::Opaque(o) => d.extend(o),
        }
        let len = u16::try_from(d.len()).map_err(|_| Error::TooLong {
            what: "DCPDataLength",
            len: d.len(),
            max: usize::from(u16::MAX),
        })?;
        let mut b = Vec::with_capacity(field::DATA + d.len());
        b.extend(self.frame_id.0.to_be_bytes());
        b.extend([self.service.0, self.service_type.0]);
        b.extend(self.xid.to_be_bytes());
        b.extend(self.response_delay.to_be_bytes());
        b.extend(len.to_be_bytes());
        b.extend(d);
        Ok(b)
    }

    /// The length [`DcpRepr::emit`] writes (0 if it fails).
    pub fn buffer_len(&self) -> usize {
        self.emit().map_or(0, |b| b.len())
    }

    fn request(frame_id: FrameId, service: ServiceId, xid: u32, data: DcpData) -> DcpRepr {
        DcpRepr {
            frame_id,
            service,
            service_type: ServiceType::REQUEST,
            xid,
            response_delay: 0,
            data,
        }
    }

    /// Identify All: the All selector as the only filter, to [`super::MULTICAST_DCP_IDENTIFY`].
    pub fn identify_all(xid: u32, response_delay: u16) -> DcpRepr {
        DcpRepr {
            response_delay,
            ..DcpRepr::request(
                FrameId::DCP_IDENTIFY_REQ,
                ServiceId::IDENTIFY,
                xid,
                DcpData::Blocks(vec![DcpBlock::filter(BlockValue::All)]),
            )
        }
    }

    /// Identify by NameOfStation.
    pub fn identify_name(xid: u32, response_delay: u16, name: &str) -> DcpRepr {
        DcpRepr {
            response_delay,
            ..DcpRepr::request(
                FrameId::DCP_IDENTIFY_REQ,
                ServiceId::IDENTIFY,
                xid,
                DcpData::Blocks(vec![DcpBlock::filter(BlockValue::NameOfStation(
                    name.to_owned(),
                ))]),
            )
        }
    }

    /// A Get request for `selectors`.
    pub fn get(xid: u32, selectors: Vec<DcpOption>) -> DcpRepr {
        DcpRepr::request(
            FrameId::DCP_GET_SET,
            ServiceId::GET,
            xid,
            DcpData::Selectors(selectors),
        )
    }

    /// A Set request of `blocks` (each with its BlockQualifier: [`DcpBlock::set`]).
    pub fn set(xid: u32, blocks: Vec<DcpBlock>) -> DcpRepr {
        DcpRepr::request(
            FrameId::DCP_GET_SET,
            ServiceId::SET,
            xid,
            DcpData::Blocks(blocks),
        )
    }

    /// A Hello request of `blocks` (each with its BlockInfo), to
    /// [`super::MULTICAST_DCP_HELLO`].
    pub fn hello(xid: u32, blocks: Vec<DcpBlock>) -> DcpRepr {
        DcpRepr::request(
            FrameId::DCP_HELLO,
            ServiceId::HELLO,
            xid,
            DcpData::Blocks(blocks),
        )
    }

    /// The success response to this request with `blocks`: same service and Xid, reserved
    /// field 0, on FEFFh for an Identify and this request's frame id otherwise.
    pub fn response(&self, blocks: Vec<DcpBlock>) -> DcpRepr {
        DcpRepr {
            frame_id: if self.service == ServiceId::IDENTIFY {
                FrameId::DCP_IDENTIFY_RES
            } else {
                self.frame_id
            },
            service: self.service,
            service_type: ServiceType::SUCCESS,
            xid: self.xid,
            response_delay: 0,
            data: DcpData::Blocks(blocks),
        }
    }

    /// The "request not supported" response to this request (no blocks).
    pub fn not_supported(&self) -> DcpRepr {
        DcpRepr {
            service_type: ServiceType::NOT_SUPPORTED,
            ..self.response(Vec::new())
        }
    }

    /// The blocks (none for selectors or opaque data).
    pub fn blocks(&self) -> &[DcpBlock] {
        match &self.data {
            DcpData::Blocks(b) => b,
            _ => &[],
        }
    }

    /// The first block of `option`.
    pub fn find(&self, option: DcpOption) -> Option<&DcpBlock> {
        self.blocks().iter().find(|b| b.option() == option)
    }
}

/// The longest NameOfStation (IEC 61158-6-10 §4.3.1.4.15: "OctetString with 1 to 240
/// octets"). BU 0620 §3.8.1 prints 127 for the SK 550P's P854 (the §4.2.4 parameter table
/// prints 240): which applies is the NORD layer's call, through [`station_name_valid_max`].
pub const NAME_OF_STATION_MAX: usize = 240;
/// The longest label of a NameOfStation.
pub const LABEL_MAX: usize = 63;

/// Why a NameOfStation breaks the rules of [`station_name_valid`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    /// No characters (in a Set: "delete the name", not a name).
    #[error("the name is empty")]
    Empty,
    /// Longer than the maximum.
    #[error("the name has {len} characters, at most {max} are allowed")]
    TooLong {
        /// Its length.
        len: usize,
        /// The maximum.
        max: usize,
    },
    /// A character other than a–z, 0–9, '-' and '.'.
    #[error("character {ch:?} at {at} is not one of a-z 0-9 - .")]
    BadChar {
        /// The character.
        ch: char,
        /// Its byte offset.
        at: usize,
    },
    /// An empty label (leading, trailing or doubled '.').
    #[error("empty label at {at}")]
    EmptyLabel {
        /// Byte offset of the label.
        at: usize,
    },
    /// A label over 63 characters.
    #[error("the label at {at} has {len} characters, at most 63 are allowed")]
    LabelTooLong {
        /// Byte offset of the label.
        at: usize,
        /// Its length.
        len: usize,
    },
    /// A label that starts or ends with '-'.
    #[error("the label at {at} starts or ends with '-'")]
    Hyphen {
        /// Byte offset of the label.
        at: usize,
    },
    /// The form n.n.n.n (n = 0..999) of an IP address.
    #[error("the name has the form n.n.n.n of an IP address")]
    IpAddressForm,
    /// The first label has the form "port-xyz" or "port-xyz-abcde" (x..e digits) of a port
    /// name.
    #[error("the first label has the form port-xyz or port-xyz-abcde")]
    PortName,
}

/// Checks a NameOfStation against IEC 61158-6-10 §4.3.1.4.15 ("Coding of the field
/// NameOfStationValue", IETF RFC 5890 host-name syntax) with at most
/// [`NAME_OF_STATION_MAX`] (240) characters:
///
/// - 1 to 240 characters in one or more labels separated by '.';
/// - a label has 1 to 63 characters;
/// - the characters are a–z, 0–9 and '-' (lower case only);
/// - no label starts or ends with '-';
/// - the name does not have the form n.n.n.n with n = 0..999 (an IP address);
/// - the first label does not have the form "port-xyz" or "port-xyz-abcde" with a..e, x..z
///   digits (the NameOfPort of an alias name).
///
/// Not checked: "labels start with 'xn-' only if RFC 3490 (IDNA) is applied".
///
/// BU 0620 §3.8.1 words the same rules for P854 and adds "must not begin or end with a
/// number", a rule of older PROFINET editions that the standard no longer has (p-net accepts
/// "a1.2.3.4" and "device-1"): the NORD layer applies it if it wants it.
pub fn station_name_valid(name: &str) -> Result<(), NameError> {
    station_name_valid_max(name, NAME_OF_STATION_MAX)
}

/// [`station_name_valid`] with another maximum length (BU 0620 §3.8.1 prints 127).
pub fn station_name_valid_max(name: &str, max_len: usize) -> Result<(), NameError> {
    if name.is_empty() {
        return Err(NameError::Empty);
    }
    if let Some((at, ch)) = name
        .char_indices()
        .find(|&(_, c)| !(c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '.'))
    {
        return Err(NameError::BadChar { ch, at });
    }
    if name.len() > max_len {
        return Err(NameError::TooLong {
            len: name.len(),
            max: max_len,
        });
    }
    let mut at = 0;
    let mut labels = Vec::new();
    for label in name.split('.') {
        if label.is_empty() {
            return Err(NameError::EmptyLabel { at });
        }
        if label.len() > LABEL_MAX {
            return Err(NameError::LabelTooLong {
                at,
                len: label.len(),
            });
        }
        if label.starts_with('-') || label.ends_with('-') {
            return Err(NameError::Hyphen { at });
        }
        labels.push(label);
        at += label.len() + 1;
    }
    let digits = |s: &str, n: usize| s.len() == n && s.bytes().all(|c| c.is_ascii_digit());
    if labels.len() == 4
        && labels
            .iter()
            .all(|l| l.len() <= 3 && l.bytes().all(|c| c.is_ascii_digit()))
    {
        return Err(NameError::IpAddressForm);
    }
    if let Some(rest) = labels[0].strip_prefix("port-") {
        let port = match rest.split_once('-') {
            None => digits(rest, 3),
            Some((xyz, abcde)) => digits(xyz, 3) && digits(abcde, 5),
        };
        if port {
            return Err(NameError::PortName);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Identify All as a controller sends it (layout as Wireshark shows it).
    const IDENTIFY_ALL: [u8; 16] = [
        0xFE, 0xFE, // FrameID: Identify request
        0x05, // ServiceID Identify
        0x00, // ServiceType request
        0x01, 0x00, 0x00, 0x2A, // Xid 0100002Ah
        0x00, 0x80, // ResponseDelay 128
        0x00, 0x04, // DCPDataLength 4
        0xFF, 0xFF, 0x00, 0x00, // All selector, DCPBlockLength 0
    ];

    /// An Identify response of a device named "sk550p-1" (8 characters), IP 192.168.100.10/24
    /// no gateway, vendor 0001h device 0002h, role IO device.
    fn identify_response() -> Vec<u8> {
        vec![
            0xFE, 0xFF, // FrameID: Identify response
            0x05, 0x01, // Identify, response success
            0x01, 0x00, 0x00, 0x2A, // Xid
            0x00, 0x00, // reserved
            0x00, 0x3C, // DCPDataLength 60
            0x02, 0x02, 0x00, 0x0A, // Device/NameOfStation, length 10
            0x00, 0x00, // BlockInfo 0
            b's', b'k', b'5', b'5', b'0', b'p', b'-', b'1', // "sk550p-1"
            0x01, 0x02, 0x00, 0x0E, // IP/IPParameter, length 14
            0x00, 0x01, // BlockInfo: IP set
            192, 168, 100, 10, // IPAddress
            255, 255, 255, 0, // Subnetmask
            0, 0, 0, 0, // StandardGateway
            0x02, 0x03, 0x00, 0x06, // Device/DeviceID, length 6
            0x00, 0x00, // BlockInfo
            0x00, 0x01, 0x00, 0x02, // VendorID 1, DeviceID 2
            0x02, 0x04, 0x00, 0x04, // Device/DeviceRole, length 4
            0x00, 0x00, // BlockInfo
            0x01, 0x00, // IO device, reserved
            0x02, 0x01, 0x00, 0x05, // Device/Vendor, length 5
            0x00, 0x00, // BlockInfo
            b'S', b'K', b'5', // "SK5"
            0x00, // padding
        ]
    }

    #[test]
    fn identify_all_round_trip() {
        let r = DcpRepr::parse(&IDENTIFY_ALL).unwrap();
        assert_eq!(r, DcpRepr::identify_all(0x0100_002A, 128));
        assert_eq!(r.emit().unwrap(), IDENTIFY_ALL);
        assert_eq!(r.buffer_len(), IDENTIFY_ALL.len());
        // Ethernet padding after DCPDataLength is ignored.
        let mut padded = IDENTIFY_ALL.to_vec();
        padded.resize(46, 0);
        assert_eq!(DcpRepr::parse(&padded).unwrap(), r);
    }

    #[test]
    fn identify_response_blocks_carry_block_info() {
        let b = identify_response();
        let r = DcpRepr::parse(&b).unwrap();
        let want = DcpRepr::identify_all(0x0100_002A, 128).response(vec![
            DcpBlock::info(
                BlockInfo::NONE,
                BlockValue::NameOfStation("sk550p-1".into()),
            ),
            DcpBlock::info(
                BlockInfo::IP_SET,
                BlockValue::IpParameter(IpParameter {
                    ip: Ipv4Addr::new(192, 168, 100, 10),
                    mask: Ipv4Addr::new(255, 255, 255, 0),
                    gateway: Ipv4Addr::UNSPECIFIED,
                }),
            ),
            DcpBlock::info(
                BlockInfo::NONE,
                BlockValue::DeviceId {
                    vendor_id: 1,
                    device_id: 2,
                },
            ),
            DcpBlock::info(BlockInfo::NONE, BlockValue::DeviceRole(role::IO_DEVICE)),
            DcpBlock::info(BlockInfo::NONE, BlockValue::DeviceVendor("SK5".into())),
        ]);
        assert_eq!(r, want);
        assert_eq!(r.emit().unwrap(), b);
        assert_eq!(
            r.find(DcpOption::NAME_OF_STATION).map(|b| &b.value),
            Some(&BlockValue::NameOfStation("sk550p-1".into()))
        );
        // The last block's padding may be missing when nothing follows.
        let mut short = b.clone();
        short.pop();
        short[11] = 0x3B;
        assert_eq!(DcpRepr::parse(&short).unwrap(), r);
    }

    #[test]
    fn set_request_and_response() {
        // Set NameOfStation "drive-7" permanently, then IP 10.0.0.2/8 gateway 10.0.0.1
        // temporarily.
        let b = [
            0xFE, 0xFD, // FrameID Get/Set
            0x04, 0x00, // Set request
            0x00, 0x00, 0x00, 0x07, // Xid 7
            0x00, 0x00, // reserved
            0x00, 0x20, // DCPDataLength 32
            0x02, 0x02, 0x00, 0x09, // NameOfStation, length 9
            0x00, 0x01, // BlockQualifier permanent
            b'd', b'r', b'i', b'v', b'e', b'-', b'7', // "drive-7"
            0x00, // padding
            0x01, 0x02, 0x00, 0x0E, // IP parameter, length 14
            0x00, 0x00, // BlockQualifier temporary
            10, 0, 0, 2, 255, 0, 0, 0, 10, 0, 0, 1, // address, mask, gateway
        ];
        let r = DcpRepr::parse(&b).unwrap();
        let want = DcpRepr::set(
            7,
            vec![
                DcpBlock::set(
                    BlockQualifier::PERMANENT,
                    BlockValue::NameOfStation("drive-7".into()),
                ),
                DcpBlock::set(
                    BlockQualifier::TEMPORARY,
                    BlockValue::IpParameter(IpParameter {
                        ip: Ipv4Addr::new(10, 0, 0, 2),
                        mask: Ipv4Addr::new(255, 0, 0, 0),
                        gateway: Ipv4Addr::new(10, 0, 0, 1),
                    }),
                ),
            ],
        );
        assert_eq!(r, want);
        assert_eq!(r.emit().unwrap(), b);

        // The response: one Control/Response block per Set block, 3 bytes + padding each.
        let res = r.response(vec![
            DcpBlock::response(DcpOption::NAME_OF_STATION, BlockError::OK),
            DcpBlock::response(DcpOption::IP_PARAMETER, BlockError::SET_NOT_POSSIBLE),
        ]);
        let rb = res.emit().unwrap();
        assert_eq!(
            rb,
            [
                0xFE, 0xFD, 0x04, 0x01, 0, 0, 0, 7, 0, 0, 0x00, 0x10, // header, 16 bytes
                0x05, 0x04, 0x00, 0x03, 0x02, 0x02, 0x00, 0x00, // Response: 2/2 ok, pad
                0x05, 0x04, 0x00, 0x03, 0x01, 0x02, 0x05, 0x00, // Response: 1/2 error 5, pad
            ]
        );
        assert_eq!(DcpRepr::parse(&rb).unwrap(), res);
    }

    #[test]
    fn get_selectors_and_negative_get_response() {
        // Get request for IP parameter and NameOfStation.
        let b = [
            0xFE, 0xFD, 0x03, 0x00, 0, 0, 0, 9, 0, 0, 0x00, 0x04, // Get request, 4 bytes
            0x01, 0x02, 0x02, 0x02, // selectors 1/2, 2/2
        ];
        let r = DcpRepr::parse(&b).unwrap();
        assert_eq!(
            r,
            DcpRepr::get(9, vec![DcpOption::IP_PARAMETER, DcpOption::NAME_OF_STATION])
        );
        assert_eq!(r.emit().unwrap(), b);
        // Get response: the IP block with BlockInfo, and an unsupported one as
        // Control/Response without prefix.
        let res = r.response(vec![
            DcpBlock::info(
                BlockInfo::IP_SET,
                BlockValue::IpParameter(IpParameter::default()),
            ),
            DcpBlock::response(DcpOption::new(0x80, 1), BlockError::OPTION_NOT_SUPPORTED),
        ]);
        let rb = res.emit().unwrap();
        assert_eq!(
            &rb[rb.len() - 8..],
            [0x05, 0x04, 0x00, 0x03, 0x80, 0x01, 0x01, 0x00]
        );
        assert_eq!(DcpRepr::parse(&rb).unwrap(), res);
        // An odd selector list.
        let mut odd = b[..15].to_vec();
        odd[11] = 3;
        assert_eq!(
            DcpRepr::parse(&odd),
            Err(Error::Trailing {
                what: "Get selectors",
                extra: 1
            })
        );
    }

    #[test]
    fn control_device_options_hello_round_trip() {
        let set = DcpRepr::set(
            1,
            vec![
                DcpBlock::set(BlockQualifier::TEMPORARY, BlockValue::Start),
                DcpBlock::set(
                    BlockQualifier::TEMPORARY,
                    BlockValue::Signal(SIGNAL_FLASH_ONCE),
                ),
                DcpBlock::set(
                    BlockQualifier::RESET_COMMUNICATION,
                    BlockValue::ResetToFactory,
                ),
                DcpBlock::set(BlockQualifier::PERMANENT, BlockValue::FactoryReset),
                DcpBlock::set(BlockQualifier::TEMPORARY, BlockValue::Stop),
                DcpBlock::set(
                    BlockQualifier::TEMPORARY,
                    BlockValue::Dhcp {
                        suboption: 61,
                        data: vec![61, 1, 1],
                    },
                ),
            ],
        );
        let b = set.emit().unwrap();
        // Signal: 05 03, length 4, qualifier 0000, value 0100h.
        assert_eq!(&b[18..26], [0x05, 0x03, 0x00, 0x04, 0x00, 0x00, 0x01, 0x00]);
        assert_eq!(DcpRepr::parse(&b).unwrap(), set);

        let hello = DcpRepr::hello(
            3,
            vec![
                DcpBlock::info(
                    BlockInfo::NONE,
                    BlockValue::Mac(MacAddr([0, 1, 2, 3, 4, 5])),
                ),
                DcpBlock::info(
                    BlockInfo::NONE,
                    BlockValue::DeviceOptions(vec![DcpOption::IP_MAC, DcpOption::ALL]),
                ),
                DcpBlock::info(BlockInfo::NONE, BlockValue::AliasName("port-001.x".into())),
                DcpBlock::info(
                    BlockInfo::NONE,
                    BlockValue::DeviceInstance { high: 0, low: 1 },
                ),
                DcpBlock::info(
                    BlockInfo::NONE,
                    BlockValue::OemDeviceId {
                        vendor_id: 5,
                        device_id: 6,
                    },
                ),
                DcpBlock::info(BlockInfo::NONE, BlockValue::DeviceInitiative(1)),
                DcpBlock::info(
                    BlockInfo(0x81),
                    BlockValue::FullIpSuite {
                        ip: IpParameter::default(),
                        dns: [Ipv4Addr::new(1, 1, 1, 1); 4],
                    },
                ),
            ],
        );
        assert_eq!(hello.frame_id, FrameId::DCP_HELLO);
        let b = hello.emit().unwrap();
        assert_eq!(DcpRepr::parse(&b).unwrap(), hello);
        assert!(BlockInfo(0x81).ip_set() && BlockInfo(0x81).conflict());
        assert!(!BlockInfo(0x81).by_dhcp());
    }

    #[test]
    fn unknown_options_and_services_are_kept() {
        // Set of option 80h/01h (manufacturer specific) with 3 data bytes, then option 02h/0Ah
        // (RSI properties, not typed here).
        let b = [
            0xFE, 0xFD, 0x04, 0x00, 0, 0, 0, 1, 0, 0, 0x00, 0x0E, // Set request, 14 bytes
            0x80, 0x01, 0x00, 0x03, 0x00, 0x01, 0xAA, 0x00, // 80h/01h, 3 bytes, pad
            0x02, 0x0A, 0x00, 0x02, 0x00, 0x01, // 02h/0Ah, 2 bytes
        ];
        let r = DcpRepr::parse(&b).unwrap();
        assert_eq!(
            r.blocks()[0],
            DcpBlock::filter(BlockValue::Raw {
                option: DcpOption::new(0x80, 1),
                data: vec![0, 1, 0xAA]
            })
        );
        assert_eq!(r.blocks()[1].option(), DcpOption::new(2, 0x0A));
        assert_eq!(r.emit().unwrap(), b);
        // ServiceID 07h: opaque data, to be answered "not supported".
        let mut x = b;
        x[2] = 7;
        let r = DcpRepr::parse(&x).unwrap();
        assert_eq!(r.data, DcpData::Opaque(b[12..].to_vec()));
        assert_eq!(r.emit().unwrap(), x);
        let ns = r.not_supported();
        assert_eq!(ns.service_type, ServiceType::NOT_SUPPORTED);
        assert_eq!(ns.emit().unwrap()[2..4], [7, 5]);
    }

    #[test]
    fn framing_errors_name_the_field() {
        let b = identify_response();
        for cut in 0..b.len() - 1 {
            assert!(DcpRepr::parse(&b[..cut]).is_err(), "cut {cut}");
        }
        // DCPDataLength past the frame.
        let mut x = b.clone();
        x[11] = 0x3E;
        assert_eq!(
            DcpRepr::parse(&x),
            Err(Error::Length {
                field: "DCPDataLength",
                value: 62,
                available: 60
            })
        );
        // The first block claims 100 bytes.
        let mut x = b.clone();
        x[15] = 100;
        assert_eq!(
            DcpRepr::parse(&x),
            Err(Error::Length {
                field: "DCPBlockLength",
                value: 100,
                available: 56
            })
        );
        // IP parameter of 10 bytes (block length 12).
        let mut x = b.clone();
        x[29] = 12;
        assert!(matches!(
            DcpRepr::parse(&x),
            Err(Error::Invalid {
                field: "IP/IPParameter block length",
                value: 10,
                why: "not the length of the option's value",
            })
        ));
        // A block header cut by DCPDataLength.
        let mut x = IDENTIFY_ALL;
        x[11] = 2;
        assert_eq!(
            DcpRepr::parse(&x),
            Err(Error::Truncated {
                what: "DCP block header",
                need: 4,
                got: 2
            })
        );
        // A Set block too short for its qualifier.
        let x = [
            0xFE, 0xFD, 0x04, 0x00, 0, 0, 0, 1, 0, 0, 0, 4, 0x02, 0x02, 0x00, 0x00,
        ];
        assert_eq!(
            DcpRepr::parse(&x),
            Err(Error::Truncated {
                what: "BlockQualifier",
                need: 2,
                got: 0
            })
        );
        // Not a DCP frame id.
        assert_eq!(
            DcpRepr::parse(&[0xFE, 0x01, 5, 0, 0, 0, 0, 0, 0, 0, 0, 0]),
            Err(Error::Unknown {
                field: "DCP FrameID",
                value: 0xFE01
            })
        );
        // The view frames blocks until the first error, block by block.
        let mut x = b.clone();
        x[29] = 100;
        let p = DcpPacket::new_checked(&x[..]).unwrap();
        let items: Vec<_> = p.blocks().collect();
        assert_eq!(items.len(), 2);
        assert!(items[0].is_ok() && items[1].is_err());
    }

    #[test]
    fn view_setters_break_a_valid_telegram() {
        let mut p = DcpPacket::new_checked(IDENTIFY_ALL).unwrap();
        p.set_service(ServiceId(9));
        p.set_service_type(ServiceType::SUCCESS);
        p.set_xid(0xDEAD_BEEF);
        p.set_data_length(2);
        let b = p.into_inner();
        assert_eq!(&b[2..12], [9, 1, 0xDE, 0xAD, 0xBE, 0xEF, 0, 0x80, 0, 2]);
        p = DcpPacket::new_checked(b).unwrap();
        assert_eq!(p.data(), [0xFF, 0xFF]);
        assert_eq!(format!("{:?}", p.service()), "ServiceId(09h)");
        p.set_data_length(500);
        assert_eq!(p.data().len(), 4);
        assert!(DcpPacket::new_checked(p.into_inner()).is_err());
    }

    #[test]
    fn station_names_follow_the_standard() {
        for ok in [
            "abc",
            "a1.2.3.4",
            "device-1.machine-1.plant-1.vendor",
            "xn--mhle1-kva.xn--lmhle1-vxa4c.plant.com",
            "port-xyz",
            "port-xyz-abcde",
            "port-12",
            "port-1234",
            "sk550p",
            "1.2.3",
            "1.2.3.4.5",
            "1234.2.3.4",
        ] {
            assert_eq!(station_name_valid(ok), Ok(()), "{ok}");
        }
        let label63 = "a".repeat(63);
        assert_eq!(station_name_valid(&label63), Ok(()));
        let name240 = format!("{0}.{0}.{0}.{1}", label63, "d".repeat(48));
        assert_eq!(name240.len(), 240);
        assert_eq!(station_name_valid(&name240), Ok(()));
        assert_eq!(
            station_name_valid(&format!("{name240}d")),
            Err(NameError::TooLong { len: 241, max: 240 })
        );
        assert_eq!(
            station_name_valid_max(&"a".repeat(128), 127),
            Err(NameError::TooLong { len: 128, max: 127 })
        );
        let cases: [(&str, NameError); 12] = [
            ("", NameError::Empty),
            ("name_1", NameError::BadChar { ch: '_', at: 4 }),
            ("name/1", NameError::BadChar { ch: '/', at: 4 }),
            ("Name", NameError::BadChar { ch: 'N', at: 0 }),
            ("a b", NameError::BadChar { ch: ' ', at: 1 }),
            ("-name", NameError::Hyphen { at: 0 }),
            ("name-", NameError::Hyphen { at: 0 }),
            ("name.-name", NameError::Hyphen { at: 5 }),
            ("name..x", NameError::EmptyLabel { at: 5 }),
            ("1.2.3.4", NameError::IpAddressForm),
            ("port-123", NameError::PortName),
            ("port-123-98765.x", NameError::PortName),
        ];
        for (name, err) in cases {
            assert_eq!(station_name_valid(name), Err(err), "{name:?}");
        }
        assert_eq!(
            station_name_valid(&"l".repeat(64)),
            Err(NameError::LabelTooLong { at: 0, len: 64 })
        );
        assert_eq!(
            station_name_valid("x.ü"),
            Err(NameError::BadChar { ch: 'ü', at: 2 })
        );
        assert_eq!(
            station_name_valid("."),
            Err(NameError::EmptyLabel { at: 0 })
        );
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn ip4() -> impl Strategy<Value = Ipv4Addr> {
            any::<[u8; 4]>().prop_map(Ipv4Addr::from)
        }

        fn ip_parameter() -> impl Strategy<Value = IpParameter> {
            (ip4(), ip4(), ip4()).prop_map(|(ip, mask, gateway)| IpParameter { ip, mask, gateway })
        }

        fn option() -> impl Strategy<Value = DcpOption> {
            any::<(u8, u8)>().prop_map(|(o, s)| DcpOption::new(o, s))
        }

        /// A value of every typed option, or a raw block of an option not typed here.
        fn value() -> impl Strategy<Value = BlockValue> {
            let text = || "\\PC{0,16}";
            prop_oneof![
                any::<[u8; 6]>().prop_map(|m| BlockValue::Mac(MacAddr(m))),
                ip_parameter().prop_map(BlockValue::IpParameter),
                (ip_parameter(), [ip4(), ip4(), ip4(), ip4()])
                    .prop_map(|(ip, dns)| BlockValue::FullIpSuite { ip, dns }),
                text().prop_map(BlockValue::DeviceVendor),
                text().prop_map(BlockValue::NameOfStation),
                any::<(u16, u16)>().prop_map(|(vendor_id, device_id)| BlockValue::DeviceId {
                    vendor_id,
                    device_id
                }),
                any::<u8>().prop_map(BlockValue::DeviceRole),
                vec(option(), 0..6).prop_map(BlockValue::DeviceOptions),
                text().prop_map(BlockValue::AliasName),
                any::<(u8, u8)>().prop_map(|(high, low)| BlockValue::DeviceInstance { high, low }),
                any::<(u16, u16)>().prop_map(|(vendor_id, device_id)| BlockValue::OemDeviceId {
                    vendor_id,
                    device_id
                }),
                (any::<u8>(), vec(any::<u8>(), 0..12))
                    .prop_map(|(suboption, data)| BlockValue::Dhcp { suboption, data }),
                Just(BlockValue::Start),
                Just(BlockValue::Stop),
                any::<u16>().prop_map(BlockValue::Signal),
                (option(), any::<u8>()).prop_map(|(option, e)| BlockValue::Response {
                    option,
                    error: BlockError(e)
                }),
                Just(BlockValue::FactoryReset),
                Just(BlockValue::ResetToFactory),
                any::<u16>().prop_map(BlockValue::DeviceInitiative),
                Just(BlockValue::All),
                (
                    option().prop_filter("typed option", |o| !BlockValue::is_typed(*o)),
                    vec(any::<u8>(), 0..12)
                )
                    .prop_map(|(option, data)| BlockValue::Raw { option, data }),
            ]
        }

        /// The block with the prefix its telegram gives it (none for a raw block).
        fn block(
            service: ServiceId,
            service_type: ServiceType,
            value: BlockValue,
            v: u16,
        ) -> DcpBlock {
            let head = if matches!(value, BlockValue::Raw { .. }) {
                BlockHead::None
            } else {
                match HeadKind::of(service, service_type, value.option()) {
                    HeadKind::None => BlockHead::None,
                    HeadKind::Info => BlockHead::Info(BlockInfo(v)),
                    HeadKind::Qualifier => BlockHead::Qualifier(BlockQualifier(v)),
                }
            };
            DcpBlock { head, value }
        }

        fn repr() -> impl Strategy<Value = DcpRepr> {
            (
                FrameId::DCP_HELLO.0..=FrameId::DCP_IDENTIFY_RES.0,
                prop_oneof![3 => 3u8..=6, 1 => any::<u8>()],
                prop_oneof![Just(0u8), Just(1), Just(5), any::<u8>()],
                any::<u32>(),
                any::<u16>(),
            )
                .prop_flat_map(
                    |(frame_id, service, service_type, xid, response_delay)| {
                        let (service, service_type) =
                            (ServiceId(service), ServiceType(service_type));
                        let data = match service {
                            ServiceId::GET if !service_type.is_response() => {
                                vec(option(), 0..6).prop_map(DcpData::Selectors).boxed()
                            }
                            ServiceId::GET
                            | ServiceId::SET
                            | ServiceId::IDENTIFY
                            | ServiceId::HELLO => vec((value(), any::<u16>()), 0..5)
                                .prop_map(move |vs| {
                                    DcpData::Blocks(
                                        vs.into_iter()
                                            .map(|(value, v)| {
                                                block(service, service_type, value, v)
                                            })
                                            .collect(),
                                    )
                                })
                                .boxed(),
                            _ => vec(any::<u8>(), 0..24).prop_map(DcpData::Opaque).boxed(),
                        };
                        data.prop_map(move |data| DcpRepr {
                            frame_id: FrameId(frame_id),
                            service,
                            service_type,
                            xid,
                            response_delay,
                            data,
                        })
                    },
                )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in repr(), padding in 0usize..8) {
                let mut b = r.emit().unwrap();
                prop_assert_eq!(b.len(), r.buffer_len());
                prop_assert_eq!(DcpRepr::parse(&b), Ok(r.clone()));
                // Ethernet padding after DCPDataLength is ignored.
                b.resize(b.len() + padding, 0);
                prop_assert_eq!(DcpRepr::parse(&b), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(
                head in (0xFEFCu16..=0xFEFF, 0u8..=8, any::<u8>(), any::<u32>(), any::<u16>()),
                data in vec(any::<u8>(), 0..48),
                len_delta in -2i32..=2,
            ) {
                // A plausible header (so the blocks get parsed) over arbitrary data, and the
                // arbitrary bytes on their own.
                let (id, service, service_type, xid, delay) = head;
                let len = (data.len() as i32 + len_delta).clamp(0, 0xFFFF) as u16;
                let mut b = id.to_be_bytes().to_vec();
                b.extend([service, service_type]);
                b.extend(xid.to_be_bytes());
                b.extend(delay.to_be_bytes());
                b.extend(len.to_be_bytes());
                b.extend(&data);
                let _ = DcpRepr::parse(&b);
                let _ = DcpRepr::parse(&data);
            }
        }
    }
}
