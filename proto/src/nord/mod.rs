//! Everything the five NORD manuals state that does not depend on a wire protocol.
//!
//! The manuals (see `shared/manuals/README.md`):
//! - BU 0620 (2020-03, English; Chinese translation): SK 550P with integrated Industrial Ethernet.
//! - BU 2100: EtherNet/IP modules SK TU3-EIP, SK TU4-EIP, SK CU4-EIP.
//! - BU 0590 (2012): PROFINET module SK TU3-PNT.
//! - BU 2200 (2019, German): POWERLINK modules SK TU3-POL, SK TU4-POL, SK CU4-POL.
//!
//! The product is always an explicit input ([`Product`]): the SK 550P and the plug-in modules
//! differ in parameter numbers (P85x vs P15x), address tables and supported order labels.

pub mod addr;
pub mod can;
pub mod control;
pub mod ecat;
pub mod eip;
pub mod epl;
pub mod errors;
pub mod led;
pub mod mutant;
pub mod nmt;
pub mod no_panic;
pub mod params;
pub mod pkw;
pub mod pnio;
pub mod ppo;
pub mod product;
pub mod rules;
pub mod scaling;
pub mod state_machine;
pub mod status;
pub mod types;

pub use product::{Family, Product, Protocol};
pub use types::{ArrayElement, Inverter, ParamAddress, ParamNumber, ParamSet, RangeError};
