//! The NORD system bus as a virtual CAN segment: the inverters of a product as CANopen nodes
//! (CiA 301) at their system-bus addresses (P515: FI n at 32 + 2·(n − 1), BU 0620 §2.6,
//! `proto::nord::can`), fed CAN frames and the time, answering frames.
//!
//! What the manuals do not state, and where this simulator follows CiA 301 instead (each
//! choice "not stated by the manuals"):
//! - COB-IDs: the pre-defined connection set (SDO 600h/580h + node, heartbeat 700h + node,
//!   EMCY 80h + node, NMT 000h).
//! - SDO access to parameters: NORD's object layout as the project maps it for EtherCAT, one
//!   node per inverter: parameter P at object 2000h + P, its sets or elements as sub-indices
//!   (`proto::nord::ecat::parameter_subindex`).
//! - The communication objects: 1000h device type 0 (no standard device profile), 1001h error
//!   register (bit 0 while the inverter has an error), 1008h the product's name, 1017h the
//!   producer heartbeat time (ms, 0 = off, the factory value), 1018h identity (NORD's vendor id
//!   538h, as its EtherCAT interface reports it).
//! - EMCY: one when an inverter error appears (P700 [-01] from 0), the code as the SK 550P's
//!   EtherCAT interface sends it (BU 0620 §5.3's DS402 code for a communication error, else
//!   FF00h).
//!
//! Process data (PDOs) and SYNC are not simulated yet.

mod node;
mod sdo;
#[cfg(test)]
mod tests;

use std::time::Duration;

use proto::can::CanFrame;
use proto::nord::can::SystemBusAddress;
use proto::nord::Inverter;

use crate::device::{Device, DeviceConfig};
use node::Node;

/// Why a segment cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum SegmentError {
    /// An inverter has no system-bus address.
    #[error("FI {0} has no system-bus address")]
    NoAddress(u8),
}

/// One CAN segment: the device's inverters as nodes.
#[derive(Debug)]
pub struct Segment {
    device: Device,
    nodes: Vec<Node>,
    /// P700 [-01] of each inverter as last seen, for EMCY.
    faults: [i32; 8],
}

impl Segment {
    /// The segment of `config`'s inverters, each about to boot.
    pub fn new(config: DeviceConfig) -> Result<Segment, SegmentError> {
        let nodes = (1..=config.inverters)
            .map(|n| {
                let fi = Inverter::new(i64::from(n)).map_err(|_| SegmentError::NoAddress(n))?;
                Ok(Node::new(
                    fi,
                    SystemBusAddress::inverter(fi).get(),
                    config.product,
                ))
            })
            .collect::<Result<Vec<_>, SegmentError>>()?;
        Ok(Segment {
            device: Device::new(config),
            nodes,
            faults: [0; 8],
        })
    }

    /// The node ids on the segment.
    pub fn nodes(&self) -> Vec<u8> {
        self.nodes.iter().map(Node::id).collect()
    }

    /// The device behind the nodes (its inverters' parameters and drives).
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// A frame on the bus at `now`: what the nodes answer to it, in node order.
    pub fn receive(&mut self, frame: &CanFrame, now: Duration) -> Vec<CanFrame> {
        let mut out = self.poll(now);
        for node in &mut self.nodes {
            out.extend(node.receive(frame, &mut self.device, now));
        }
        out
    }

    /// What the nodes send on their own at `now`: boot-up messages, heartbeats, EMCY.
    pub fn poll(&mut self, now: Duration) -> Vec<CanFrame> {
        self.device.tick(now);
        let mut out = Vec::new();
        for node in &mut self.nodes {
            out.extend(node.poll(now));
        }
        for (fi, value) in self.device.fault_changes(&mut self.faults) {
            if let Some(node) = self.nodes.iter_mut().find(|n| n.inverter() == fi) {
                out.extend(node.emergency(value));
            }
        }
        out
    }

    /// When a node next sends on its own (`None`: nothing scheduled).
    pub fn next_due(&self) -> Option<Duration> {
        self.nodes.iter().filter_map(Node::next_due).min()
    }
}
