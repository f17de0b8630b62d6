//! The bus interface's side of the NORD system bus (CANopen on CAN between the interface and
//! its inverters, `proto::nord::can`): the gateway that reaches the inverters' parameters
//! through their nodes' SDO servers ([`Gateway`]; PKW orders through it, [`serve_order`]) and
//! their drives through their nodes' PDOs ([`ProcessData`]: RPDOs, a SYNC, TPDOs per
//! system-bus cycle, at the system bus's pace), and the recorder of the frames on the bus
//! ([`Tap`]). Both are real CAN frames, in process: what the field bus gets back is read from
//! the nodes' answer frames. Behind the SK 550P, FI 1 is the device itself and no system-bus
//! traffic (BU 0620 §2.1).
//!
//! A field-bus refusal after the system bus: the node answers a CiA 301 abort code, which the
//! field bus turns back into its own error. For CoE and POWERLINK SDO that is the code itself;
//! for CIP the general status the parameter store's reason gives (`sim::enip`'s
//! `access_status`; one status per abort code, so the code alone would do); for PKW the error
//! number the store's reason gives (`pkw::error_of`). Where a field bus is
//! finer than the code (the parameter channel's error numbers tell "no array" from "faulty
//! sub-index", one abort 06090011h for both), the store's own reason travels beside the code
//! ([`crate::objects::Refused`]): a real gateway would have the code only, but the simulated
//! device keeps what it knows rather than report a coarser error than the field bus could.

mod gateway;
mod pkw;
mod process;
mod tap;

pub(crate) use gateway::Gateway;
pub(crate) use pkw::{carries, serve_order};
pub(crate) use process::ProcessData;
pub(crate) use tap::{Access, Tap};

/// The frame of `function` of node `node` with `data`; none for a COB-ID or length CAN 2.0A
/// has not.
fn frame(
    function: proto::canopen::cob_id::Function,
    node: u8,
    data: &[u8],
) -> Option<proto::can::CanFrame> {
    proto::can::CanFrame::new(function.cob_id(node).ok()?, data).ok()
}

/// Frames as the tests compare them: `ID DATA` in hex.
#[cfg(test)]
fn hex(frames: &[proto::can::CanFrame]) -> Vec<String> {
    frames
        .iter()
        .map(|f| {
            let data: Vec<String> = f.data().iter().map(|b| format!("{b:02X}")).collect();
            format!("{:03X} {}", f.id(), data.join(" "))
                .trim()
                .to_string()
        })
        .collect()
}
