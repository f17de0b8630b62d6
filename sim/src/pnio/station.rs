//! The station: name of station and IP suite, and the DCP services on them (IEC 61158-6-10
//! DCP; BU 0620 §3.8.1, §4.2.4, §4.4.3; BU 0590 §5.1.2).
//!
//! - Identify (all, or by name) is answered with the device's blocks: type of station,
//!   name, vendor/device id, role, options, IP suite.
//! - Get answers the blocks asked for; an unknown option gets a Control/Response block with
//!   "option not supported".
//! - Set checks each block as PROFINET does: a name by the NameOfStation rules
//!   ([`def::check_station_name`]), an IP suite by the IP rules ([`def::check_ip_suite`],
//!   block error 03h "suboption not set"), neither while an application relation runs (06h
//!   "in operation"); Signal flashes the LED; Reset to Factory clears name and address.
//!   A permanent IP suite goes into the IP parameters (SK 550P P850/P851/P852; SK TU3-PNT
//!   P160/P161); the SK 550P shows the suite in use in P875–P877 (§4.4.3).

use std::net::Ipv4Addr;
use std::time::Duration;

use proto::eth::MacAddr;
use proto::nord::pnio::{self as def, IpSuite};
use proto::nord::Product;
use proto::pnio::dcp::{
    BlockError, BlockInfo, BlockValue, DcpBlock, DcpData, DcpOption, DcpRepr, IpParameter,
    ServiceId, ServiceType,
};

use super::{IoDevice, Out};
use crate::device::Device;
use crate::link::Unit;

/// How long a DCP Signal makes the LED flash (3 s at 1 Hz, as PROFINET devices do).
const SIGNAL_TIME: Duration = Duration::from_secs(3);

/// The options the device answers (DeviceOptions).
const OPTIONS: [DcpOption; 9] = [
    DcpOption::IP_MAC,
    DcpOption::IP_PARAMETER,
    DcpOption::DEVICE_VENDOR,
    DcpOption::NAME_OF_STATION,
    DcpOption::DEVICE_ID,
    DcpOption::DEVICE_ROLE,
    DcpOption::DEVICE_OPTIONS,
    DcpOption::CONTROL_SIGNAL,
    DcpOption::CONTROL_RESET_TO_FACTORY,
];

/// Name of station and IP suite.
#[derive(Debug, Clone)]
pub(super) struct Station {
    pub(super) name: String,
    pub(super) ip: IpSuite,
}

impl Station {
    pub(super) fn new(name: String, ip: IpSuite) -> Station {
        Station { name, ip }
    }

    /// Shows the suite in use where the product has display parameters (SK 550P P875–P877).
    pub(super) fn show(&self, device: &mut Device, product: Product) {
        let Some(p) = def::ip_parameters(product) else {
            return;
        };
        let Ok(store) = device.store(Unit::Interface) else {
            return;
        };
        if let Some(present) = p.present {
            for (number, addr) in
                present
                    .into_iter()
                    .zip([self.ip.ip, self.ip.mask, self.ip.gateway])
            {
                for (e, b) in (1u8..).zip(addr.octets()) {
                    store.set_info(number, e, i32::from(b));
                }
            }
        }
    }

    /// Keeps the suite in the IP parameters (a permanent Set): SK 550P P850/P851/P852, SK
    /// TU3-PNT P160/P161.
    pub(super) fn keep(&self, device: &mut Device, product: Product) {
        self.write_params(device, product, self.ip);
    }

    /// Writes `suite` into the IP parameters.
    fn write_params(&self, device: &mut Device, product: Product, suite: IpSuite) {
        let Some(p) = def::ip_parameters(product) else {
            return;
        };
        let Ok(store) = device.store(Unit::Interface) else {
            return;
        };
        let mut params = vec![(p.ip, suite.ip), (p.mask, suite.mask)];
        params.extend(p.gateway.map(|g| (g, suite.gateway)));
        for (number, addr) in params {
            for (e, b) in (1u8..).zip(addr.octets()) {
                store.set_info(number, e, i32::from(b));
            }
        }
    }

    fn ip_block(&self) -> DcpBlock {
        let info = if self.ip.ip.is_unspecified() {
            BlockInfo::NONE
        } else {
            BlockInfo::IP_SET
        };
        DcpBlock::info(
            info,
            BlockValue::IpParameter(IpParameter {
                ip: self.ip.ip,
                mask: self.ip.mask,
                gateway: self.ip.gateway,
            }),
        )
    }
}

impl IoDevice {
    /// A DCP telegram from `src` to `dst` (the device or a multicast address).
    pub(super) fn dcp(
        &mut self,
        src: MacAddr,
        dst: MacAddr,
        payload: &[u8],
        now: Duration,
    ) -> Vec<Out> {
        let Ok(req) = DcpRepr::parse(payload) else {
            self.dropped += 1;
            return Vec::new();
        };
        if req.service_type != ServiceType::REQUEST {
            return Vec::new();
        }
        let answer = match req.service {
            ServiceId::IDENTIFY => {
                if !self.identified_by(&req) {
                    return Vec::new();
                }
                req.response(self.blocks_of(&[DcpOption::ALL]))
            }
            // Get and Set go to the device's own address only.
            _ if dst != self.mac => return Vec::new(),
            ServiceId::GET => match &req.data {
                DcpData::Selectors(s) => req.response(self.blocks_of(s)),
                _ => req.not_supported(),
            },
            ServiceId::SET => match &req.data {
                DcpData::Blocks(b) => {
                    let answers = b.iter().map(|b| self.set(b, now)).collect();
                    req.response(answers)
                }
                _ => req.not_supported(),
            },
            _ => req.not_supported(),
        };
        match answer.emit() {
            Ok(bytes) => vec![self.ethernet(src, bytes)],
            Err(_) => Vec::new(),
        }
    }

    /// Whether an Identify's filter blocks select this device: All, or every filter given
    /// matches (name of station, vendor/device id, role).
    fn identified_by(&self, req: &DcpRepr) -> bool {
        let blocks = req.blocks();
        blocks.iter().all(|b| match &b.value {
            BlockValue::All => true,
            BlockValue::NameOfStation(n) => *n == self.station.name,
            BlockValue::DeviceId {
                vendor_id,
                device_id,
            } => *vendor_id == def::VENDOR_ID && Some(*device_id) == def::device_id(self.product),
            BlockValue::DeviceRole(r) => r & def::DEVICE_ROLE_IO_DEVICE != 0,
            BlockValue::DeviceVendor(v) => Some(v.as_str()) == def::station_type(self.product),
            _ => false,
        }) && !blocks.is_empty()
    }

    /// The blocks answering `selectors` (All: every block of an Identify response).
    fn blocks_of(&self, selectors: &[DcpOption]) -> Vec<DcpBlock> {
        let all = selectors.contains(&DcpOption::ALL);
        let wanted: Vec<DcpOption> = if all {
            vec![
                DcpOption::DEVICE_VENDOR,
                DcpOption::NAME_OF_STATION,
                DcpOption::DEVICE_ID,
                DcpOption::DEVICE_ROLE,
                DcpOption::DEVICE_OPTIONS,
                DcpOption::IP_PARAMETER,
            ]
        } else {
            selectors.to_vec()
        };
        wanted.into_iter().map(|o| self.block(o)).collect()
    }

    /// One block of the device, or the Control/Response block saying it has none.
    fn block(&self, option: DcpOption) -> DcpBlock {
        let info = |v| DcpBlock::info(BlockInfo::NONE, v);
        match option {
            DcpOption::IP_MAC => info(BlockValue::Mac(self.mac)),
            DcpOption::IP_PARAMETER => self.station.ip_block(),
            DcpOption::DEVICE_VENDOR => info(BlockValue::DeviceVendor(
                def::station_type(self.product).unwrap_or("").to_string(),
            )),
            DcpOption::NAME_OF_STATION => {
                info(BlockValue::NameOfStation(self.station.name.clone()))
            }
            DcpOption::DEVICE_ID => info(BlockValue::DeviceId {
                vendor_id: def::VENDOR_ID,
                device_id: def::device_id(self.product).unwrap_or(0),
            }),
            DcpOption::DEVICE_ROLE => info(BlockValue::DeviceRole(def::DEVICE_ROLE_IO_DEVICE)),
            DcpOption::DEVICE_OPTIONS => info(BlockValue::DeviceOptions(OPTIONS.to_vec())),
            other => DcpBlock::response(other, unsupported(other)),
        }
    }

    /// One block of a Set, answered with its Control/Response block.
    fn set(&mut self, block: &DcpBlock, now: Duration) -> DcpBlock {
        let option = block.option();
        let permanent = match block.head {
            proto::pnio::dcp::BlockHead::Qualifier(q) => q.permanent(),
            _ => false,
        };
        let in_operation = self.ar.is_some();
        let error = match &block.value {
            BlockValue::NameOfStation(_) | BlockValue::IpParameter(_) if in_operation => {
                BlockError::IN_OPERATION
            }
            BlockValue::NameOfStation(n) => self.set_name(n),
            BlockValue::IpParameter(p) => self.set_ip(
                IpSuite {
                    ip: p.ip,
                    mask: p.mask,
                    gateway: p.gateway,
                },
                permanent,
            ),
            BlockValue::Signal(_) => {
                self.signal_until = Some(now + SIGNAL_TIME);
                BlockError::OK
            }
            BlockValue::ResetToFactory | BlockValue::FactoryReset if in_operation => {
                BlockError::IN_OPERATION
            }
            BlockValue::ResetToFactory | BlockValue::FactoryReset => {
                self.station.name.clear();
                let factory = def::factory_ip(self.product).unwrap_or(IpSuite {
                    ip: Ipv4Addr::UNSPECIFIED,
                    mask: Ipv4Addr::UNSPECIFIED,
                    gateway: Ipv4Addr::UNSPECIFIED,
                });
                self.set_ip(factory, true)
            }
            BlockValue::Start | BlockValue::Stop => BlockError::OK,
            _ => unsupported(option),
        };
        DcpBlock::response(option, error)
    }

    /// A new name of station (empty: the name is deleted).
    fn set_name(&mut self, name: &str) -> BlockError {
        if !name.is_empty() && def::check_station_name(name).is_err() {
            return BlockError::SET_NOT_POSSIBLE;
        }
        self.station.name = name.to_string();
        BlockError::OK
    }

    /// A new IP suite, kept in the parameters if `permanent`.
    fn set_ip(&mut self, suite: IpSuite, permanent: bool) -> BlockError {
        if def::check_ip_suite(&suite).is_err() {
            return BlockError::SUBOPTION_NOT_SET;
        }
        self.station.ip = suite;
        if permanent {
            self.station.keep(&mut self.device, self.product);
        } else if def::controller_ip_zeroes_parameters(self.product) {
            // "If the IP address is assigned by the IO controller, this parameter is then set
            // to 0" (BU 0620 §4.2.4); P875–P877 show the suite in use.
            let zero = IpSuite {
                ip: Ipv4Addr::UNSPECIFIED,
                mask: Ipv4Addr::UNSPECIFIED,
                gateway: Ipv4Addr::UNSPECIFIED,
            };
            self.station
                .write_params(&mut self.device, self.product, zero);
        }
        self.station.show(&mut self.device, self.product);
        BlockError::OK
    }
}

/// "Option not supported" for an option the device does not know at all, "suboption not
/// supported" for an unknown suboption of a known one.
fn unsupported(option: DcpOption) -> BlockError {
    match option.option {
        DcpOption::OPT_IP | DcpOption::OPT_DEVICE | DcpOption::OPT_CONTROL => {
            BlockError::SUBOPTION_NOT_SUPPORTED
        }
        _ => BlockError::OPTION_NOT_SUPPORTED,
    }
}
